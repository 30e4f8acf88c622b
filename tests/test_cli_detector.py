"""`sortbot train detector` / `eval detector` from a collected dataset, through the CLI, offline."""

import json
import socket

import yaml

from sortbot.cli import main


def test_train_then_eval_detector_from_a_collected_dataset(collected, tmp_path, capsys, monkeypatch):
    def no_network(*args, **kwargs):
        raise OSError("network disabled in this test")

    monkeypatch.setattr(socket.socket, "connect", no_network)
    out, _ = collected
    model = tmp_path / "det"
    assert main(["train", "detector", "--data", str(out), "--out", str(model), "--epochs", "1", "--imgsz", "64",
                 "--batch", "4", "--device", "cpu", "--val-fraction", "0.5"]) == 0
    weights = model / "model" / "best.pt"
    assert weights.is_file() and (model / "yolo_data" / "data.yaml").is_file()
    assert "held-out mAP50" in capsys.readouterr().out
    crop = json.loads((model / "model" / "best.crop.json").read_text())["crop"]  # trained on the pick area...
    assert crop == yaml.safe_load((model / "yolo_data" / "data.yaml").read_text())["crop"]
    assert main(["eval", "detector", "--weights", str(weights), "--data", str(out), "--device", "cpu", "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert 0.0 <= result["map50"] <= 1.0 and "per_class" in result
    assert result["crop"] == crop  # ...and evaluated on the same crop
    assert main(["eval", "detector", "--weights", str(weights), "--data", str(out), "--device", "cpu", "--json",
                 "--errors", "--conf", "0.0"]) == 0
    errors = json.loads(capsys.readouterr().out)["errors"]
    labelled = sum(int(n) * row["frames"] for n, row in errors["by_objects_in_frame"].items())
    assert errors["objects"] == labelled == sum(errors[k] for k in ("correct", "wrong_class", "poor_box", "missed"))
    assert errors["frames"] == sum(row["frames"] for row in errors["by_objects_in_frame"].values()) > 0
    # refuses to train over a previous run, and rejects a folder that holds no data
    assert main(["train", "detector", "--data", str(out), "--out", str(model), "--epochs", "1"]) == 2
    assert main(["train", "detector", "--data", str(tmp_path / "empty_dir_missing"), "--out", str(tmp_path / "x")]) == 2
    assert capsys.readouterr().err.count("sortbot: error:") == 2
