"""`sortbot bench detector`: how fast the YOLO detector trains and predicts on this machine.

Training: the same frames, one epoch each, with square (padded) and rectangular batches, measured
side by side in one run (alternating, so that a busy machine hurts both alike); images/s of the
epoch's training loop alone (no set-up, no validation) and their ratio. Prediction: with weights
given, ms per full camera frame through `YoloDetector` (crop, letterbox, network, NMS, boxes back).
"""

from __future__ import annotations

import os
import statistics
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import yaml

from sortbot.perception.yolo_data import label_path, read_data_yaml, split_images
from sortbot.train.detector import DetectorTrainConfig, train_detector


def subset_yolo_set(data_yaml: str | Path, out: Path, frames: int) -> Path:
    """A YOLO set of the first `frames` training images (links, not copies) that validates on the
    same images; its data.yaml keeps the source's crop."""
    data = read_data_yaml(data_yaml)
    images = split_images(data_yaml, "train")[:frames]
    if not images:
        raise ValueError(f"{data_yaml} has no training images to benchmark on")
    for sub in ("images", "labels"):
        (out / sub / "train").mkdir(parents=True, exist_ok=True)
    for image in images:
        (out / "images" / "train" / image.name).symlink_to(image.resolve())
        label = label_path(image)
        if label.is_file():
            (out / "labels" / "train" / label.name).symlink_to(label.resolve())
    record = {k: v for k, v in yaml.safe_load(Path(data_yaml).expanduser().read_text()).items()
              if k not in ("path", "train", "val", "test")}
    record.update(path=str(out), train="images/train", val="images/train", names=data["names"])
    (out / "data.yaml").write_text(yaml.safe_dump(record, sort_keys=False))
    return out / "data.yaml"


def _epoch_seconds(data_yaml: Path, out_dir: Path, config: DetectorTrainConfig) -> float:
    """Wall time of the training loop of one epoch (the trainer's own epoch start/end callbacks)."""
    marks: dict[str, float] = {}

    def mark(name):
        return lambda trainer: marks.__setitem__(name, time.perf_counter())

    train_detector(data_yaml, out_dir, config, overwrite=True,
                   callbacks={"on_train_epoch_start": mark("start"), "on_train_epoch_end": mark("end")})
    return marks["end"] - marks["start"]


def bench_detector(data_yaml: str | Path, frames: int = 120, imgsz: int = 416, batch: int = 4, device: str = "auto",
                   rounds: int = 2, weights: str | Path | None = None, predict_frames: int = 30,
                   progress=None) -> dict:
    """Training images/s with square vs rectangular batches (median of `rounds` alternating epochs,
    after an untimed warm-up epoch) and, with `weights`, prediction latency on full frames."""
    if frames < batch:
        raise ValueError(f"--frames must be at least the batch size ({batch})")
    base = DetectorTrainConfig(epochs=1, imgsz=imgsz, batch=batch, device=device, val_every_epoch=False, plots=False)
    result: dict = {"frames": frames, "imgsz": imgsz, "batch": batch, "cpu_count": os.cpu_count()}
    with tempfile.TemporaryDirectory(prefix="sortbot-bench-detector-") as tmp:
        subset = subset_yolo_set(data_yaml, Path(tmp) / "set", frames)
        warm = subset_yolo_set(data_yaml, Path(tmp) / "warm", batch)
        _epoch_seconds(warm, Path(tmp) / "warm_run", base)  # one-time costs (kernels, allocator) land in neither mode
        times: dict[str, list[float]] = {"square": [], "rect": []}
        for r in range(rounds):
            for mode in ("square", "rect"):
                seconds = _epoch_seconds(subset, Path(tmp) / f"{mode}{r}", replace(base, rect=mode == "rect"))
                times[mode].append(seconds)
                if progress:
                    progress(mode, seconds)
        for mode, values in times.items():
            result[f"train_{mode}"] = {"epoch_s": values, "images_per_s": frames / statistics.median(values)}
        result["device"] = _device_used(Path(tmp) / "rect0")
        result["rect_speedup"] = result["train_rect"]["images_per_s"] / result["train_square"]["images_per_s"]
    if weights is not None:
        result["predict"] = bench_predict(weights, data_yaml, predict_frames, device)
    return result


def _device_used(out_dir: Path) -> str:
    import json

    return json.loads((out_dir / "metrics.json").read_text())["device"]


def bench_predict(weights: str | Path, data_yaml: str | Path, frames: int = 30, device: str = "auto") -> dict:
    """ms per frame of `YoloDetector.predict_rgb` on full camera-size frames rebuilt from the set
    (a cropped set's images are pasted back into a frame of the recorded size)."""
    import numpy as np
    from PIL import Image

    from sortbot.perception.detector import DetectorConfig, YoloDetector
    from sortbot.perception.yolo_data import read_crop

    detector = YoloDetector(weights, DetectorConfig(device=device))
    crop = read_crop(data_yaml)
    images = split_images(data_yaml, "val")[:frames]
    if not images:
        raise ValueError(f"{data_yaml} has no validation images to time prediction on")
    full = []
    for path in images:
        rgb = np.asarray(Image.open(path).convert("RGB"))
        full.append(crop.paste(rgb) if crop is not None else rgb)
    detector.predict_rgb(full[0])  # first call builds the model's fused graph
    ms = []
    for rgb in full:
        t = time.perf_counter()
        detector.predict_rgb(rgb)
        ms.append((time.perf_counter() - t) * 1000)
    return {"frames": len(full), "ms_per_frame_median": statistics.median(ms), "ms_per_frame_p90": float(np.percentile(ms, 90)),
            "frames_per_s": 1000 / statistics.median(ms), "device": detector.device}
