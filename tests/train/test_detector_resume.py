"""An interrupted detector training goes on from its last epoch, from the API and the CLI."""

import json

import pytest
import torch
from conftest import TINY

from sortbot.cli import main
from sortbot.train import DetectorTrainConfig, resume_detector, train_detector


class Interrupted(Exception):
    """Stands for a killed process: raised once the first epoch has been saved."""


def _stop_after_first_epoch(trainer) -> None:
    if trainer.epoch == 0:
        raise Interrupted


def _epoch_of(weights) -> int:
    return int(torch.load(weights, map_location="cpu", weights_only=False)["epoch"])


def test_resume_finishes_an_interrupted_run_where_it_stopped(yolo_set, tmp_path, no_network):
    data_yaml, _, _ = yolo_set
    out = tmp_path / "det"
    cfg = DetectorTrainConfig(**{**TINY, "epochs": 2})
    with pytest.raises(Interrupted):
        train_detector(data_yaml, out, cfg, callbacks={"on_fit_epoch_end": _stop_after_first_epoch})
    last = out / "yolo" / "weights" / "last.pt"
    assert _epoch_of(last) == 0 and not (out / "metrics.json").exists()

    seen = []
    result = resume_detector(out, callbacks={"on_train_epoch_start": lambda t: seen.append(t.epoch)})
    assert seen == [1]  # only the missing epoch was trained
    assert result.resumed_after == 1 and result.epochs_run == 2 and result.epochs == 2
    assert result.weights == out / "best.pt" and result.weights.is_file()
    record = json.loads((out / "metrics.json").read_text())
    assert record["resumed_after_epochs"] == 1 and record["epochs_run"] == 2
    assert record["config"]["imgsz"] == TINY["imgsz"] and record["config"]["batch"] == TINY["batch"]
    assert 0.0 <= record["map50"] <= 1.0 and no_network == []

    with pytest.raises(ValueError, match="already finished"):  # a finished run is not trained again
        resume_detector(out)
    with pytest.raises(FileNotFoundError, match="no interrupted detector training"):
        resume_detector(tmp_path / "elsewhere")


def test_cli_resume_refuses_changed_settings_and_missing_runs(tmp_path, capsys):
    assert main(["train", "detector", "--out", str(tmp_path / "run"), "--resume", "--epochs", "5"]) != 0
    assert "drop --epochs" in capsys.readouterr().err
    assert main(["train", "detector", "--out", str(tmp_path / "run"), "--resume"]) != 0
    assert "no interrupted detector training" in capsys.readouterr().err
    assert main(["train", "detector", "--out", str(tmp_path / "run")]) != 0
    assert "needs --data" in capsys.readouterr().err
    assert not (tmp_path / "run").exists()
