"""The YOLO detector (ultralytics): local weights only, one RGB image in, the paper's six numbers
per object out (box, confidence, class), most confident first.

Weights trained on frames cut to the pick area (`best.crop.json` beside them, see
`yolo_data.pick_area_crop`) get the same cut: the image is cropped before predicting and the boxes
shifted back, so callers always see full-image pixels.

Never downloads: a weights path that is not a file is an error before ultralytics sees it (it
would otherwise fetch any name it knows, e.g. `yolo11n.pt`).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sortbot.perception.detection import Detection, by_confidence
from sortbot.perception.yolo_data import CropBox, read_crop_sidecar
from sortbot.perception.yolo_offline import import_yolo, torch_threads_kept, ultralytics_device
from sortbot.types import CLASS_NAMES, Observation

DEFAULT_IMGSZ = 640  # ultralytics' own default, used when the checkpoint does not record its training size


@dataclass(frozen=True)
class DetectorConfig:
    confidence: float = 0.25  # ultralytics' default score threshold
    iou: float = 0.7  # non-maximum suppression IoU
    imgsz: int | None = None  # None: the size the weights were trained at
    device: str = "auto"  # cpu | cuda | cuda:N | auto
    max_detections: int = 50
    agnostic_nms: bool = False  # per-class NMS keeps a second class guess; target selection resolves it
    crop: CropBox | None = None  # None: the crop recorded beside the weights (none recorded: whole frames)


def trained_imgsz(model) -> int | None:
    """The image size a loaded ultralytics model was trained at, if its checkpoint says."""
    ckpt = getattr(model, "ckpt", None)
    size = (ckpt.get("train_args") or {}).get("imgsz") if isinstance(ckpt, dict) else None
    return int(size) if isinstance(size, (int, float)) else None


def require_weights(weights: str | Path) -> Path:
    """A local weights file, or a one-line error that says what to do (nothing is downloaded)."""
    path = Path(weights).expanduser()
    if not path.is_file():
        raise FileNotFoundError(
            f"detector weights {path} not found: give a local .pt file (e.g. best.pt from `train_detector`); "
            "nothing is downloaded")
    return path


class YoloDetector:
    def __init__(self, weights: str | Path, config: DetectorConfig | None = None):
        self.weights = require_weights(weights)
        self.config = config or DetectorConfig()
        yolo = import_yolo()
        self.model = yolo(str(self.weights), task="detect")
        names = dict(self.model.names)
        unknown = sorted(set(names.values()) - set(CLASS_NAMES))
        if unknown:
            raise ValueError(f"weights {self.weights} detect classes {unknown} that sortbot does not know "
                             f"(expected a subset of {', '.join(CLASS_NAMES)})")
        self.names = names
        self.imgsz = int(self.config.imgsz or trained_imgsz(self.model) or DEFAULT_IMGSZ)
        self.device = ultralytics_device(self.config.device)
        self.crop = self.config.crop or read_crop_sidecar(self.weights)

    def predict_rgb(self, rgb: np.ndarray) -> list[Detection]:
        """Detections on a full RGB uint8 (H, W, 3) frame, most confident first, boxes in its pixels
        (cut to the weights' crop first, when they have one)."""
        if rgb.ndim != 3 or rgb.shape[2] != 3 or rgb.dtype != np.uint8:
            raise ValueError(f"expected an RGB uint8 image (H, W, 3), got {rgb.dtype} {rgb.shape}")
        seen = self.crop.apply(rgb) if self.crop is not None else rgb
        bgr = np.ascontiguousarray(seen[..., ::-1])  # ultralytics reads numpy images as OpenCV BGR
        cfg = self.config
        with torch_threads_kept():
            result = self.model.predict(
                source=bgr, imgsz=self.imgsz, conf=cfg.confidence, iou=cfg.iou, device=self.device,
                max_det=cfg.max_detections, agnostic_nms=cfg.agnostic_nms, verbose=False)[0]
        boxes = result.boxes
        xyxy = boxes.xyxy.cpu().numpy().astype(float)
        conf = boxes.conf.cpu().numpy().astype(float)
        cls = boxes.cls.cpu().numpy().astype(int)
        to_full = self.crop.box_to_full if self.crop is not None else (lambda b: tuple(float(v) for v in b))
        return by_confidence(
            Detection(box=to_full(b), confidence=float(c), cls=self.names[int(k)])
            for b, c, k in zip(xyxy, conf, cls))

    def predict(self, observation: Observation) -> list[Detection]:
        """Detections on an Observation's RGB image, most confident first."""
        return self.predict_rgb(observation.rgb)
