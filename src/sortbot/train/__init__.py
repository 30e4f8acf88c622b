"""Training workflows: the YOLO detector on exported detection sets (the Q-network comes later)."""

from sortbot.train.detector import DetectorTrainConfig, DetectorTrainResult, resume_detector, train_detector

__all__ = ["DetectorTrainConfig", "DetectorTrainResult", "resume_detector", "train_detector"]
