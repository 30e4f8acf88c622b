"""One detected object: the paper's six numbers (box x1 y1 x2 y2, confidence, class).

Kept apart from the YOLO wrapper so target selection and tests work without ultralytics, e.g. on
ground-truth labels turned into detections.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Iterable, Sequence

import numpy as np

from sortbot.types import CLASS_NAMES, ObjectLabel, class_index


@dataclass(frozen=True)
class Detection:
    box: tuple[float, float, float, float]  # x1, y1, x2, y2 in pixels (x2, y2 exclusive)
    confidence: float
    cls: str  # one of CLASS_NAMES

    def __post_init__(self) -> None:
        class_index(self.cls)  # a clear error for a class we do not sort

    @property
    def class_id(self) -> int:
        return class_index(self.cls)

    def as_array(self) -> np.ndarray:
        """[x1, y1, x2, y2, confidence, class index]: the paper's label row."""
        return np.array([*self.box, self.confidence, self.class_id], dtype=np.float32)

    @classmethod
    def from_array(cls, row: Sequence[float]) -> "Detection":
        x1, y1, x2, y2, conf, k = (float(v) for v in row[:6])
        return cls(box=(x1, y1, x2, y2), confidence=conf, cls=CLASS_NAMES[int(k)])


def by_confidence(detections: Iterable[Detection]) -> list[Detection]:
    """Most confident first (stable for ties): never trust the order a detector returned."""
    return sorted(detections, key=lambda d: -d.confidence)


def detections_from_labels(labels: Iterable[ObjectLabel], confidence: float = 1.0) -> list[Detection]:
    """Ground-truth labels as detections: the oracle detector, for ablations and tests."""
    return [Detection(box=tuple(float(v) for v in l.box), confidence=confidence, cls=l.cls) for l in labels]
