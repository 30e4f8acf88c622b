"""Held-out detector figures: mAP50, mAP50-95, precision and recall, overall and per class, from
ultralytics' own validator (the numbers its training reports), run offline on local weights.

Weights trained on the pick-area crop are only evaluated on a set cut with the same crop (and
whole-frame weights on whole frames): anything else would measure a different image scale."""

from __future__ import annotations

import tempfile
from pathlib import Path

from sortbot.perception.detector import DEFAULT_IMGSZ, require_weights, trained_imgsz
from sortbot.perception.yolo_data import read_crop, read_crop_sidecar, summarize_metrics, write_resolved
from sortbot.perception.yolo_offline import import_yolo, torch_threads_kept, ultralytics_device

VAL_CONFIDENCE = 0.001  # ultralytics' validation threshold: mAP integrates over all scores
VAL_IOU = 0.7  # NMS IoU during validation


def evaluate_detector(weights: str | Path, data_yaml: str | Path, split: str = "val", imgsz: int | None = None,
                      device: str = "auto", batch: int = 16, out_dir: str | Path | None = None) -> dict:
    """Evaluate `weights` on one split of a YOLO data.yaml, at the size they were trained at unless
    `imgsz` says otherwise. Plots and the checked data.yaml go to `out_dir` when given, else to a
    temporary folder that is removed."""
    weights = require_weights(weights)
    if split not in ("train", "val", "test"):
        raise ValueError(f"unknown split {split!r}: use train, val or test")
    crop = read_crop_sidecar(weights)
    data_crop = read_crop(data_yaml) if Path(data_yaml).expanduser().is_file() else crop  # missing: write_resolved says so
    if crop != data_crop:
        def say(c):
            return f"the crop {c.as_list()} of {c.image_width} x {c.image_height} frames" if c else "whole frames"
        raise ValueError(f"{weights} was trained on {say(crop)} but {data_yaml} holds {say(data_crop)}: "
                         "evaluate on a set exported with the same crop")
    yolo = import_yolo()
    dev = ultralytics_device(device)
    with tempfile.TemporaryDirectory(prefix="sortbot-val-") as tmp, torch_threads_kept():
        folder = Path(out_dir).expanduser().resolve() if out_dir else Path(tmp)
        data = write_resolved(data_yaml, folder, splits=(split,))
        model = yolo(str(weights), task="detect")
        imgsz = int(imgsz or trained_imgsz(model) or DEFAULT_IMGSZ)
        metrics = model.val(data=str(data), split=split, imgsz=imgsz, device=dev, batch=batch, conf=VAL_CONFIDENCE,
                            iou=VAL_IOU, plots=out_dir is not None, project=str(folder), name="val",
                            exist_ok=True, workers=0, verbose=False)
        summary = summarize_metrics(metrics)
    return {**summary, "weights": str(weights), "split": split, "imgsz": imgsz, "device": dev,
            "crop": crop.as_list() if crop else None}
