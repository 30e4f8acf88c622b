"""Where a detector goes wrong, at the confidence it runs at: every labelled object of a YOLO set
counted as found, found with the wrong class, boxed badly, or missed, plus the detections that
match nothing, overall and by how many objects the frame holds (piles vs. strays).

mAP integrates over every score; this is what target selection actually receives. Detections come
from `YoloDetector` on the full camera frame (a cropped set's image pasted back where it was cut),
so the crop, letterbox and NMS are the ones the sorting pipeline uses.
"""

from __future__ import annotations

from collections import Counter, defaultdict
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sortbot.perception.detection import Detection
from sortbot.perception.yolo_data import CropBox, label_path, read_crop, split_images
from sortbot.types import CLASS_NAMES


@dataclass(frozen=True)
class ErrorConfig:
    confidence: float = 0.25  # the detector's own threshold (DetectorConfig.confidence)
    match_iou: float = 0.5  # a detection this close to a labelled box found it (mAP50's rule)
    touch_iou: float = 0.1  # below match_iou but above this: the object was seen, its box is poor


def label_boxes(label_file: Path, width: int, height: int, crop: CropBox | None) -> list[tuple[int, tuple]]:
    """(class id, full-frame box) for each line of a YOLO label file of a (width x height) image."""
    boxes = []
    for line in label_file.read_text().splitlines() if label_file.is_file() else []:
        if not line.strip():
            continue
        k, cx, cy, w, h = (float(v) for v in line.split()[:5])
        box = ((cx - w / 2) * width, (cy - h / 2) * height, (cx + w / 2) * width, (cy + h / 2) * height)
        boxes.append((int(k), crop.box_to_full(box) if crop is not None else box))
    return boxes


def match_frame(truth: list[tuple[int, tuple]], detections: list[Detection], config: ErrorConfig) -> dict:
    """Greedy one-to-one matching, most confident detection first (as mAP's matcher), class-agnostic
    so that a wrong class is counted as such and not as a miss plus a false positive."""
    import torch
    from torchvision.ops import box_iou

    outcome = {"correct": 0, "wrong_class": [], "poor_box": 0, "missed": 0, "false_positive": 0, "duplicate": 0}
    if not truth:
        outcome["false_positive"] = len(detections)
        return outcome
    t_boxes = torch.tensor([b for _, b in truth], dtype=torch.float64)
    d_boxes = torch.tensor([d.box for d in detections], dtype=torch.float64).reshape(-1, 4)
    iou = box_iou(d_boxes, t_boxes).numpy() if len(detections) else np.zeros((0, len(truth)))
    found = np.zeros(len(truth), bool)
    touched = np.zeros(len(truth), bool)
    for i in np.argsort([-d.confidence for d in detections], kind="stable"):
        free = np.where(found, -1.0, iou[i])
        j = int(np.argmax(free))
        if free[j] >= config.match_iou:
            found[j] = True
            k_true, k_pred = truth[j][0], detections[i].class_id
            if k_true == k_pred:
                outcome["correct"] += 1
            else:
                outcome["wrong_class"].append((CLASS_NAMES[k_true], CLASS_NAMES[k_pred]))
        elif iou[i].max(initial=0.0) >= config.match_iou:
            outcome["duplicate"] += 1  # a second box on an object already found
        elif free[j] >= config.touch_iou:
            touched[j] = True
        else:
            outcome["false_positive"] += 1
    outcome["poor_box"] = int((touched & ~found).sum())
    outcome["missed"] = int((~touched & ~found).sum())
    return outcome


def detector_errors(weights: str | Path, data_yaml: str | Path, split: str = "val", device: str = "auto",
                    config: ErrorConfig | None = None, progress=None) -> dict:
    """Counts over every image of `split`: objects correct / wrong class (with the confusions) /
    poor box / missed, detections that are duplicates or false positives; the same by objects per frame."""
    from PIL import Image

    from sortbot.perception.detector import DetectorConfig, YoloDetector

    cfg = config or ErrorConfig()
    detector = YoloDetector(weights, DetectorConfig(confidence=cfg.confidence, device=device))
    crop = read_crop(data_yaml)
    images = split_images(data_yaml, split)
    if not images:
        raise ValueError(f"{data_yaml} has no images in its {split} split")
    totals: Counter = Counter()
    confusions: Counter = Counter()
    by_count: dict[int, Counter] = defaultdict(Counter)
    for n, path in enumerate(images):
        rgb = np.asarray(Image.open(path).convert("RGB"))
        h, w = rgb.shape[:2]
        truth = label_boxes(label_path(path), w, h, crop)
        result = match_frame(truth, detector.predict_rgb(crop.paste(rgb) if crop is not None else rgb), cfg)
        confusions.update(result["wrong_class"])
        row = {**result, "wrong_class": len(result["wrong_class"]), "objects": len(truth), "frames": 1}
        totals.update(row)
        by_count[len(truth)].update(row)
        if progress:
            progress(n + 1, len(images))
    return {
        **{k: int(v) for k, v in totals.items()},
        "correct_fraction": totals["correct"] / max(totals["objects"], 1),
        "confusions": {f"{t}->{p}": int(c) for (t, p), c in confusions.most_common()},
        "by_objects_in_frame": {str(k): {**{key: int(v) for key, v in c.items()},
                                         "correct_fraction": c["correct"] / max(c["objects"], 1)}
                                for k, c in sorted(by_count.items())},
        "confidence": cfg.confidence, "match_iou": cfg.match_iou, "split": split,
    }
