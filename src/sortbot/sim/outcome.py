"""Measurements that turn two world states into an outcome: did a push move anything, did the
depth image change (VPG's rule), which bin holds an object, is it still in the pick area."""

from __future__ import annotations

import numpy as np

from sortbot.config import OutcomeConfig, WorkspaceConfig


def quaternion_angle(q1: np.ndarray, q2: np.ndarray) -> np.ndarray:
    """Rotation angle between unit quaternions (rows), in radians."""
    dot = np.abs(np.sum(np.asarray(q1) * np.asarray(q2), axis=-1))
    return 2 * np.arccos(np.clip(dot, -1.0, 1.0))


def moved_objects(pos_before: np.ndarray, quat_before: np.ndarray, pos_after: np.ndarray,
                  quat_after: np.ndarray, cfg: OutcomeConfig) -> list[int]:
    """Instance ids (1-based) of objects that moved >= push_moved_distance or turned >= push_moved_angle:
    the honest push success."""
    dist = np.linalg.norm(pos_after - pos_before, axis=1)
    turn = quaternion_angle(quat_before, quat_after)
    return [int(i) + 1 for i in np.flatnonzero((dist >= cfg.push_moved_distance) | (turn >= cfg.push_moved_angle))]


def depth_change_area(depth_before: np.ndarray, depth_after: np.ndarray, focal_length: float,
                      cfg: OutcomeConfig) -> float:
    """Area (m^2) of surface whose depth changed by between change_depth_min and change_depth_max:
    VPG's heightmap-difference rule, measured in the image with each pixel's footprint (z/f)^2."""
    diff = np.abs(depth_after.astype(np.float64) - depth_before.astype(np.float64))
    changed = np.isfinite(diff) & (diff > cfg.change_depth_min) & (diff < cfg.change_depth_max)
    footprint = (depth_before[changed].astype(np.float64) / focal_length) ** 2
    return float(footprint.sum())


def change_detected(depth_before: np.ndarray, depth_after: np.ndarray, focal_length: float,
                    cfg: OutcomeConfig) -> bool:
    return depth_change_area(depth_before, depth_after, focal_length, cfg) > cfg.change_area


def bin_of(position: np.ndarray, ws: WorkspaceConfig) -> str | None:
    """Name of the bin whose inside holds `position`, or None."""
    x, y, z = position
    for name, (bx, by, byaw) in ws.bins.items():
        c, s = np.cos(byaw), np.sin(byaw)
        lx = c * (x - bx) + s * (y - by)
        ly = -s * (x - bx) + c * (y - by)
        if abs(lx) <= ws.bin_inner_size[0] / 2 and abs(ly) <= ws.bin_inner_size[1] / 2 and z < ws.bin_wall_height + 0.05:
            return name
    return None


def in_pick_area(position: np.ndarray, ws: WorkspaceConfig) -> bool:
    (x0, y0), (x1, y1) = ws.pick_min, ws.pick_max
    return bool(x0 <= position[0] <= x1 and y0 <= position[1] <= y1)
