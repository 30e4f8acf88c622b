"""Target selection from point clouds (the paper's section III, steps 5-10).

For each detection: crop the depth image to its box, build the object's point cloud with Open3D,
move it to the robot base frame, clip it to the camera's near/far range, drop the table, sort it
by height, cluster it with k-means and return a target point on the object.

Which points are the object's: a box around a piece of cutlery in a pile also holds parts of its
neighbours (about half the points above the table, measured on 40 six-object drops). The paper's
rule, the cluster holding the highest point, landed on the detected object only 62 % of the time
there (the top of a pile is usually another object). An object spans its own box along one of the
two diagonals, so here the points near the better-supported diagonal are kept, split in two with
k-means, and the cluster nearest the box centre wins: 91 % on the same scenes. Its mean, snapped to
the nearest real point, is the target.

Then the object to act on is the one NEAREST the robot base (the paper's intent: "the points that
are further away from the camera are closer to the robot"; its code took the farthest). Detections
are ranked by confidence for real (the code took the first box): a detection whose target lands
where a more confident detection's already did is a duplicate of that object and is dropped, so the
class believed for an object is its most confident one. `selection="confidence"` is the paper's
literal step 5: act on the most confident detection.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
import open3d as o3d
from scipy.cluster.vq import ClusterError, kmeans2

from sortbot.config import WorkspaceConfig
from sortbot.perception.detection import Detection, by_confidence
from sortbot.types import CameraIntrinsics, CameraPose, Observation

SELECTIONS = ("nearest", "confidence")


@dataclass(frozen=True)
class TargetConfig:
    min_confidence: float = 0.25  # detections below this are ignored
    selection: str = "nearest"  # nearest (the robot base) | confidence (the paper's literal step 5)
    depth_scale: float = 1.0  # depth units per metre: ours are metres (the paper's sim: 10000)
    z_near: float = 0.01  # m along the optical axis, the paper's zNear
    z_far: float = 10.0  # m, the paper's zFar (also Open3D's depth_trunc)
    box_margin: int = 2  # px grown around a box before cropping
    table_height: float = WorkspaceConfig().table_height
    min_height: float = 0.001  # m above the table: lower points are the table, not the object
    max_height: float = 0.15  # m above the table: higher points are not lying on it (the arm)
    diagonal_band_px: float = 5.0  # px: points this near the box diagonal may be the object's...
    diagonal_band_fraction: float = 0.1  # ...or this fraction of the box's short side, if wider
    clusters: int = 2  # k for k-means over the diagonal's points
    kmeans_iterations: int = 20
    min_points: int = 10  # fewer object points than this and the detection gets no target
    duplicate_radius: float = 0.01  # m: a target this close to a more confident one is the same object
    seed: int = 0  # k-means initialisation

    def __post_init__(self) -> None:
        if self.selection not in SELECTIONS:
            raise ValueError(f"unknown selection {self.selection!r}: use one of {', '.join(SELECTIONS)}")
        if self.clusters < 1:
            raise ValueError(f"k-means needs at least one cluster, got {self.clusters}")


@dataclass
class ObjectCloud:
    """Points above the table inside a box, highest first: base-frame xyz and their image pixels."""

    points: np.ndarray  # (N, 3) metres, base frame
    pixels: np.ndarray  # (N, 2) u, v (column, row) in the full image


@dataclass
class Target:
    """Where to act: a base-frame point on the object, the detection it came from, its distance
    from the robot base in the table plane, and how many cloud points the box held."""

    point: np.ndarray  # (3,) metres, base frame
    detection: Detection
    distance: float
    num_points: int


def crop_box(box: Sequence[float], width: int, height: int, margin: int = 0) -> tuple[int, int, int, int]:
    """Integer pixel window (x1, y1, x2, y2), exclusive ends, covering a float box, inside the image."""
    x1 = max(0, int(np.floor(box[0])) - margin)
    y1 = max(0, int(np.floor(box[1])) - margin)
    x2 = min(width, int(np.ceil(box[2])) + margin)
    y2 = min(height, int(np.ceil(box[3])) + margin)
    return x1, y1, x2, y2


def object_cloud(depth: np.ndarray, intrinsics: CameraIntrinsics, pose: CameraPose, box: Sequence[float],
                 config: TargetConfig | None = None) -> ObjectCloud:
    """What lies above the table inside a box of the depth image, as a base-frame cloud."""
    cfg = config or TargetConfig()
    h, w = depth.shape
    x1, y1, x2, y2 = crop_box(box, w, h, cfg.box_margin)
    if x2 <= x1 or y2 <= y1:
        return ObjectCloud(np.zeros((0, 3)), np.zeros((0, 2)))
    crop = np.ascontiguousarray(depth[y1:y2, x1:x2], dtype=np.float32)
    # the crop's own camera: same focal length, principal point shifted by the crop's corner
    intr = o3d.camera.PinholeCameraIntrinsic(x2 - x1, y2 - y1, intrinsics.fx, intrinsics.fy,
                                             intrinsics.cx - x1, intrinsics.cy - y1)
    pcd = o3d.geometry.PointCloud.create_from_depth_image(
        o3d.geometry.Image(crop), intr, np.eye(4), depth_scale=cfg.depth_scale, depth_trunc=cfg.z_far)
    cam = np.asarray(pcd.points)
    pcd = pcd.select_by_index(np.flatnonzero(cam[:, 2] >= cfg.z_near))
    cam = np.asarray(pcd.points).copy()
    pixels = intrinsics.project(cam)
    pcd.transform(pose.matrix())
    pts = np.asarray(pcd.points)
    height = pts[:, 2] - cfg.table_height
    keep = (height >= cfg.min_height) & (height <= cfg.max_height)
    pts, pixels = pts[keep], pixels[keep]
    order = np.argsort(-pts[:, 2], kind="stable")  # the paper's sort by height, highest first
    return ObjectCloud(points=pts[order], pixels=pixels[order])


def _diagonal_points(cloud: ObjectCloud, box: Sequence[float], cfg: TargetConfig) -> np.ndarray:
    """Indices of the points near whichever box diagonal more points lie along."""
    x1, y1, x2, y2 = (float(v) for v in box)
    band = max(cfg.diagonal_band_px, cfg.diagonal_band_fraction * min(x2 - x1, y2 - y1))
    u, v = cloud.pixels[:, 0], cloud.pixels[:, 1]
    best = np.zeros(0, dtype=int)
    for (ax, ay), (bx, by) in (((x1, y1), (x2, y2)), ((x1, y2), (x2, y1))):
        dx, dy = bx - ax, by - ay
        dist = np.abs((u - ax) * dy - (v - ay) * dx) / max(np.hypot(dx, dy), 1e-9)
        near = np.flatnonzero(dist <= band)
        if len(near) > len(best):
            best = near
    return best


def _snap(points: np.ndarray) -> np.ndarray:
    """The real point nearest (in the table plane) to the points' mean; the highest on ties."""
    mean = points.mean(axis=0)
    return points[int(np.argmin(np.linalg.norm(points[:, :2] - mean[:2], axis=1)))].copy()


def target_point(cloud: ObjectCloud, box: Sequence[float], config: TargetConfig | None = None) -> np.ndarray | None:
    """A point on the boxed object: k-means over the points along its diagonal, the cluster whose
    snapped mean is nearest the box centre in the image. None when too few points."""
    cfg = config or TargetConfig()
    idx = _diagonal_points(cloud, box, cfg)
    if len(idx) < cfg.min_points:
        return None
    pts, pix = cloud.points[idx], cloud.pixels[idx]
    centre = np.array([(box[0] + box[2]) / 2, (box[1] + box[3]) / 2])
    k = min(cfg.clusters, len(pts))
    labels = np.zeros(len(pts), dtype=int)
    if k > 1:
        try:
            _, labels = kmeans2(pts, k, iter=cfg.kmeans_iterations, minit="++", missing="raise",
                                rng=np.random.default_rng(cfg.seed))
        except ClusterError:  # an empty cluster: the points are one blob
            labels = np.zeros(len(pts), dtype=int)
    best, best_dist = None, np.inf
    for j in np.unique(labels):
        members = np.flatnonzero(labels == j)
        point = _snap(pts[members])
        at = members[int(np.argmin(np.linalg.norm(pts[members] - point, axis=1)))]
        d = float(np.linalg.norm(pix[at] - centre))
        if d < best_dist:
            best, best_dist = point, d
    return best


def detection_target(obs: Observation, detection: Detection, config: TargetConfig | None = None) -> Target | None:
    """The target point on one detected object, or None when its box holds too few object points."""
    cfg = config or TargetConfig()
    cloud = object_cloud(obs.depth, obs.intrinsics, obs.camera_pose, detection.box, cfg)
    point = target_point(cloud, detection.box, cfg)
    if point is None:
        return None
    return Target(point=point, detection=detection, distance=float(np.linalg.norm(point[:2])),
                  num_points=len(cloud.points))


def candidate_targets(obs: Observation, detections: Sequence[Detection], config: TargetConfig | None = None) -> list[Target]:
    """One target per object, most confident detection first: detections under `min_confidence`,
    without enough points, or landing within `duplicate_radius` of a more confident detection's
    target (the same object seen twice, e.g. as fork and as spoon) are dropped."""
    cfg = config or TargetConfig()
    kept: list[Target] = []
    for det in by_confidence(detections):
        if det.confidence < cfg.min_confidence:
            break
        t = detection_target(obs, det, cfg)
        if t is None or any(np.linalg.norm(t.point - k.point) < cfg.duplicate_radius for k in kept):
            continue
        kept.append(t)
    return kept


def select_target(obs: Observation, detections: Sequence[Detection], config: TargetConfig | None = None) -> Target | None:
    """The object to act on: nearest the robot base (ties: the more confident), or with
    `selection="confidence"` the most confident detection that has a target. None if nothing qualifies."""
    cfg = config or TargetConfig()
    targets = candidate_targets(obs, detections, cfg)
    if not targets:
        return None
    if cfg.selection == "confidence":
        return targets[0]
    return min(targets, key=lambda t: (t.distance, -t.detection.confidence))
