"""Seeing: VPG heightmaps, detections, point-cloud target selection, the offline YOLO detector.

The YOLO wrapper lives in `sortbot.perception.detector`; importing this package does not import
ultralytics (slow, and its offline set-up must run first, see `yolo_offline`).
"""

from sortbot.perception.detection import Detection, by_confidence, detections_from_labels
from sortbot.perception.heightmap import Heightmap, HeightmapConfig, make_heightmap, observation_heightmap
from sortbot.perception.pointcloud import (
    ObjectCloud, Target, TargetConfig, candidate_targets, detection_target, object_cloud, select_target,
)

__all__ = [
    "Detection", "by_confidence", "detections_from_labels",
    "Heightmap", "HeightmapConfig", "make_heightmap", "observation_heightmap",
    "ObjectCloud", "Target", "TargetConfig", "candidate_targets", "detection_target", "object_cloud", "select_target",
]
