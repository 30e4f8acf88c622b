"""One tiny YOLO epoch from scratch, with the network unreachable: train, predict, evaluate."""

import json
import os
from pathlib import Path

import numpy as np
import pytest
import torch
import yaml
from PIL import Image

from sortbot.config import EnvConfig
from sortbot.eval.detector_eval import evaluate_detector
from sortbot.perception import Detection
from sortbot.perception.detector import DetectorConfig, YoloDetector
from sortbot.train import DetectorTrainConfig, train_detector
from sortbot.types import CLASS_NAMES

from conftest import TINY, VAL_SEEDS


def _state(weights):
    return {k: v.float() for k, v in torch.load(weights, map_location="cpu", weights_only=False)["model"].state_dict().items()}


@pytest.fixture
def process_threads():
    """A torch thread count that is neither ultralytics' (cores - 1) nor the trainer's (2), put back afterwards."""
    before = torch.get_num_threads()
    yield max(3, (os.cpu_count() or 1) + 1)
    torch.set_num_threads(before)


def test_tiny_training_predicts_and_evaluates_offline(yolo_set, tmp_path, no_network, monkeypatch, process_threads):
    data_yaml, val_counts, obs = yolo_set
    monkeypatch.chdir(tmp_path)  # nothing may land in the working directory
    out = tmp_path / "detector"
    torch.set_num_threads(process_threads)
    result = train_detector(data_yaml, out, DetectorTrainConfig(**TINY, cpu_threads=2))
    assert torch.get_num_threads() == process_threads  # ultralytics' count (cores - 1) and the trainer's stay inside training

    assert result.weights == out / "best.pt" and result.weights.is_file()
    assert result.epochs_run == 1 and result.imgsz == 64 and result.device == "cpu"
    record = json.loads((out / "metrics.json").read_text())
    for key in ("map50", "map50_95", "precision", "recall"):
        assert 0.0 <= record[key] <= 1.0 and record[key] == pytest.approx(result.metrics[key])
    assert record["train_seconds"] > 0 and record["config"]["imgsz"] == 64
    assert sorted(p.name for p in tmp_path.iterdir()) == ["detector"]  # no ./runs, no downloaded weights

    thread_counts = []  # ultralytics sets cores - 1 threads; the trainer must get the count asked for
    real_set_threads = torch.set_num_threads
    monkeypatch.setattr(torch, "set_num_threads", lambda n: (thread_counts.append(n), real_set_threads(n)))
    again = train_detector(data_yaml, tmp_path / "again", DetectorTrainConfig(**TINY, cpu_threads=2))  # the same seed...
    monkeypatch.setattr(torch, "set_num_threads", real_set_threads)
    assert 2 in thread_counts
    first, second = _state(result.weights), _state(again.weights)
    assert first.keys() == second.keys() and all(torch.equal(first[k], second[k]) for k in first)  # ...same weights (the thread count is part of the seed: float sums change with it)
    assert again.metrics == result.metrics

    detector = YoloDetector(result.weights, DetectorConfig(confidence=0.0, max_detections=20, device="cpu"))
    assert detector.imgsz == 64  # the size it was trained at
    dets = detector.predict(obs)
    assert torch.get_num_threads() == process_threads  # predicting leaves the process's thread count alone
    assert 0 < len(dets) <= 20 and all(isinstance(d, Detection) for d in dets)
    conf = [d.confidence for d in dets]
    assert conf == sorted(conf, reverse=True)
    h, w = obs.depth.shape
    for d in dets:
        x1, y1, x2, y2 = d.box
        assert d.cls in CLASS_NAMES and -1 <= x1 < x2 <= w + 1 and -1 <= y1 < y2 <= h + 1

    figures = evaluate_detector(result.weights, data_yaml, split="val", device="cpu")
    assert torch.get_num_threads() == process_threads
    assert figures["split"] == "val" and figures["imgsz"] == 64 and 0.0 <= figures["map50"] <= 1.0
    # ultralytics counted exactly the held-out objects we labelled, class by class
    assert {c: v["instances"] for c, v in figures["per_class"].items()} == dict(val_counts)
    assert no_network == []


def test_refusals_happen_before_any_training(yolo_set, tmp_path):
    data_yaml, _, _ = yolo_set
    busy = tmp_path / "busy"
    busy.mkdir()
    (busy / "notes.txt").write_text("mine")
    with pytest.raises(FileExistsError, match="overwrite=True"):
        train_detector(data_yaml, busy, DetectorTrainConfig(**TINY))
    with pytest.raises(FileNotFoundError, match="never downloaded"):
        train_detector(data_yaml, tmp_path / "a", DetectorTrainConfig(**{**TINY, "model": "yolo11n.pt"}))
    with pytest.raises(FileNotFoundError, match="nothing is downloaded"):
        train_detector(data_yaml, tmp_path / "b", DetectorTrainConfig(**{**TINY, "init": str(tmp_path / "x.pt")}))
    bad = tmp_path / "bad.yaml"
    bad.write_text(yaml.safe_dump({**yaml.safe_load(data_yaml.read_text()), "names": ["spoon", "fork"]}))
    with pytest.raises(ValueError, match="CLASS_NAMES"):
        train_detector(bad, tmp_path / "c", DetectorTrainConfig(**TINY))
    with pytest.raises(FileNotFoundError, match="export a detection set"):
        train_detector(tmp_path / "none.yaml", tmp_path / "d", DetectorTrainConfig(**TINY))
    with pytest.raises(FileNotFoundError, match="nothing is downloaded"):
        evaluate_detector(tmp_path / "nothing.pt", data_yaml)
    assert (busy / "notes.txt").read_text() == "mine" and not Path("yolo11n.pt").exists()


def test_training_on_the_pick_area_crop_carries_it_to_the_detector_and_eval(yolo_set, tmp_path, no_network):
    from sortbot.datasets.yolo_export import crop_yolo_set
    from sortbot.perception.yolo_data import pick_area_crop, read_crop
    from sortbot.sim.camera import camera_from_config

    data_yaml, _, obs = yolo_set
    intrinsics, pose = camera_from_config(EnvConfig().camera)  # what the renderer's camera reports, without one
    assert intrinsics == obs.intrinsics and np.allclose(pose.rotation, obs.camera_pose.rotation)
    assert np.allclose(pose.position, obs.camera_pose.position)
    crop = pick_area_crop(intrinsics, pose, EnvConfig().workspace)
    cropped = crop_yolo_set(data_yaml, tmp_path / "cropped", crop)
    assert read_crop(cropped) == crop
    image = next((tmp_path / "cropped" / "images" / "val").iterdir())
    assert Image.open(image).size == (crop.width, crop.height)
    val_rows = [line.split() for p in (tmp_path / "cropped" / "labels" / "val").iterdir() for line in p.read_text().splitlines()]

    result = train_detector(cropped, tmp_path / "det", DetectorTrainConfig(**TINY))
    assert result.rect  # all crops share one size: rectangular batches, still shuffled
    assert result.crop == crop and json.loads((tmp_path / "det" / "best.crop.json").read_text())["crop"] == crop.as_list()
    assert json.loads((tmp_path / "det" / "metrics.json").read_text())["crop"] == crop.as_list()
    detector = YoloDetector(result.weights, DetectorConfig(confidence=0.0, max_detections=20, device="cpu"))
    assert detector.crop == crop
    dets = detector.predict(obs)
    assert dets and all(crop.x0 - 1 <= d.box[0] < d.box[2] <= crop.x1 + 1 and crop.y0 - 1 <= d.box[1] < d.box[3] <= crop.y1 + 1
                        for d in dets)  # full-image pixels, inside the crop it saw

    figures = evaluate_detector(result.weights, cropped, split="val", device="cpu")
    assert figures["crop"] == crop.as_list()
    assert sum(v["instances"] for v in figures["per_class"].values()) == len(val_rows)
    with pytest.raises(ValueError, match="same crop"):  # crop weights on whole frames measure nothing useful
        evaluate_detector(result.weights, data_yaml, split="val", device="cpu")
    assert no_network == []


def test_rectangular_batches_only_when_every_training_image_has_one_size(yolo_set, tmp_path):
    from sortbot.perception.yolo_data import split_image_sizes
    from sortbot.train.detector import use_rect

    data_yaml, _, _ = yolo_set
    assert split_image_sizes(data_yaml) == {(640, 480)} and use_rect(None, data_yaml)
    mixed = tmp_path / "mixed"
    for sub in ("images/train", "labels/train", "images/val", "labels/val"):
        (mixed / sub).mkdir(parents=True)
    for i, size in enumerate(((640, 480), (320, 320))):
        Image.new("RGB", size).save(mixed / "images" / "train" / f"{i}.png")
        (mixed / "labels" / "train" / f"{i}.txt").write_text("0 0.5 0.5 0.2 0.2\n")
    (mixed / "data.yaml").write_text(yaml.safe_dump(
        {"train": "images/train", "val": "images/val", "names": dict(enumerate(CLASS_NAMES))}))
    assert split_image_sizes(mixed / "data.yaml") == {(640, 480), (320, 320)}
    assert not use_rect(None, mixed / "data.yaml")  # ultralytics would stop shuffling: square batches
    assert use_rect(True, mixed / "data.yaml") and not use_rect(False, data_yaml)  # as asked when asked


def test_bench_detector_times_square_and_rectangular_epochs_and_prediction(yolo_set, tmp_path, capsys, no_network):
    from sortbot.cli import main

    data_yaml, _, _ = yolo_set
    weights = train_detector(data_yaml, tmp_path / "det", DetectorTrainConfig(**TINY)).weights
    capsys.readouterr()  # the training's own log
    argv = ["bench", "detector", "--data", str(data_yaml), "--frames", "4", "--imgsz", "64", "--rounds", "1",
            "--device", "cpu", "--weights", str(weights), "--json"]
    assert main(argv) == 0
    result = json.loads(capsys.readouterr().out)  # stdout is the JSON alone
    for mode in ("square", "rect"):
        (seconds,) = result[f"train_{mode}"]["epoch_s"]
        assert seconds > 0 and result[f"train_{mode}"]["images_per_s"] == pytest.approx(4 / seconds)
    assert result["rect_speedup"] == pytest.approx(result["train_rect"]["images_per_s"] / result["train_square"]["images_per_s"])
    assert result["device"] == "cpu" and result["predict"]["frames"] == len(VAL_SEEDS)
    assert 0 < result["predict"]["ms_per_frame_median"] <= result["predict"]["ms_per_frame_p90"]
    assert main(["bench", "detector", "--data", str(data_yaml), "--frames", "0"]) == 2
    assert main(["bench", "detector", "--data", str(data_yaml), "--frames", "2", "--batch", "4"]) == 2
    assert "at least the batch size" in capsys.readouterr().err
    assert no_network == []
