"""VPG-style colour and depth heightmaps: the RGB-D image reprojected onto a top-down grid over the
pick area, one cell per `resolution` metres, keeping the highest point that falls in each cell.

Grid convention (as VPG): row index runs along +y, column index along +x, both from the
workspace's minimum corner. Index (row, col) covers [x_min + col * res, x_min + (col + 1) * res)
and likewise in y; `pixel_to_base` returns the cell's centre (VPG used the corner, 1 mm off).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sortbot.config import WorkspaceConfig
from sortbot.types import CameraIntrinsics, CameraPose, Observation

_WS = WorkspaceConfig()


@dataclass(frozen=True)
class HeightmapConfig:
    """The grid: x/y limits of the pick area, the table height heights are measured from, and the
    cell size. `max_height` drops points above the table higher than anything that can lie on it
    (the arm, if it ever enters the view)."""

    x_min: float = _WS.pick_min[0]
    x_max: float = _WS.pick_max[0]
    y_min: float = _WS.pick_min[1]
    y_max: float = _WS.pick_max[1]
    table_height: float = _WS.table_height
    resolution: float = 0.002  # m per cell, VPG's
    max_height: float = 0.30  # m above the table; higher points are not on the table
    below_table_tolerance: float = 0.005  # m: points this far below the table are kept (depth noise), deeper ones dropped
    min_depth: float = 1e-4  # m along the optical axis: smaller depths are "no return"

    @classmethod
    def from_workspace(cls, workspace: WorkspaceConfig, resolution: float = 0.002, **overrides) -> "HeightmapConfig":
        """Limits from the pick area and table of a WorkspaceConfig."""
        return cls(
            x_min=workspace.pick_min[0], x_max=workspace.pick_max[0],
            y_min=workspace.pick_min[1], y_max=workspace.pick_max[1],
            table_height=workspace.table_height, resolution=resolution, **overrides,
        )

    def __post_init__(self) -> None:
        if self.resolution <= 0:
            raise ValueError(f"heightmap resolution must be positive, got {self.resolution}")
        if self.x_max <= self.x_min or self.y_max <= self.y_min:
            raise ValueError(f"heightmap limits are empty: x [{self.x_min}, {self.x_max}], y [{self.y_min}, {self.y_max}]")

    @property
    def shape(self) -> tuple[int, int]:
        """(rows, cols) = (cells along y, cells along x)."""
        return (int(round((self.y_max - self.y_min) / self.resolution)),
                int(round((self.x_max - self.x_min) / self.resolution)))

    def pixel_to_base(self, row, col) -> tuple[np.ndarray, np.ndarray]:
        """Base-frame (x, y) of the centre of heightmap cell (row, col); scalars or arrays."""
        row = np.asarray(row, dtype=float)
        col = np.asarray(col, dtype=float)
        return self.x_min + (col + 0.5) * self.resolution, self.y_min + (row + 0.5) * self.resolution

    def base_to_pixel(self, x, y) -> tuple[np.ndarray, np.ndarray]:
        """Heightmap (row, col) of the cell holding base-frame (x, y); may lie outside the grid
        (check with `contains`)."""
        col = np.floor((np.asarray(x, dtype=float) - self.x_min) / self.resolution).astype(int)
        row = np.floor((np.asarray(y, dtype=float) - self.y_min) / self.resolution).astype(int)
        return row, col

    def contains(self, row, col) -> np.ndarray:
        rows, cols = self.shape
        row, col = np.asarray(row), np.asarray(col)
        return (row >= 0) & (row < rows) & (col >= 0) & (col < cols)


@dataclass
class Heightmap:
    """`color` (rows, cols, 3) uint8 and `depth` (rows, cols) float32 heights above the table in
    metres; cells no point fell into are 0 in both and False in `valid`."""

    color: np.ndarray
    depth: np.ndarray
    valid: np.ndarray
    config: HeightmapConfig


def camera_points(depth: np.ndarray, intrinsics: CameraIntrinsics, min_depth: float = 1e-4) -> tuple[np.ndarray, np.ndarray]:
    """Back-project a depth image (metres along the optical axis) to camera-frame points.
    Returns (N, 3) points and the flat pixel indices they came from (pixels with depth > min_depth)."""
    h, w = depth.shape
    flat = depth.reshape(-1)
    idx = np.flatnonzero(np.isfinite(flat) & (flat > min_depth))
    z = flat[idx].astype(np.float64)
    v, u = np.divmod(idx, w)
    x = (u - intrinsics.cx) * z / intrinsics.fx
    y = (v - intrinsics.cy) * z / intrinsics.fy
    return np.stack([x, y, z], axis=1), idx


def to_base(points: np.ndarray, pose: CameraPose) -> np.ndarray:
    """Camera-frame (OpenCV) points to the robot base frame."""
    return points @ np.asarray(pose.rotation, float).T + np.asarray(pose.position, float)


def make_heightmap(rgb: np.ndarray, depth: np.ndarray, intrinsics: CameraIntrinsics, pose: CameraPose,
                   config: HeightmapConfig | None = None) -> Heightmap:
    """Reproject every valid depth pixel into the base frame and keep, per grid cell, the highest
    point (VPG sorts by z and lets the last write win; here the winner is chosen explicitly)."""
    cfg = config or HeightmapConfig()
    rows, cols = cfg.shape
    pts_cam, idx = camera_points(depth, intrinsics, cfg.min_depth)
    pts = to_base(pts_cam, pose)
    height = pts[:, 2] - cfg.table_height
    r, c = cfg.base_to_pixel(pts[:, 0], pts[:, 1])
    keep = cfg.contains(r, c) & (height >= -cfg.below_table_tolerance) & (height <= cfg.max_height)
    r, c, height, idx = r[keep], c[keep], height[keep], idx[keep]
    cell = r * cols + c
    order = np.lexsort((height, cell))  # by cell, then by height: the last of each cell is its highest
    cell, height, idx = cell[order], height[order], idx[order]
    last = np.ones(cell.size, dtype=bool)
    last[:-1] = cell[1:] != cell[:-1]
    cell, height, idx = cell[last], height[last], idx[last]

    depth_map = np.zeros(rows * cols, dtype=np.float32)
    depth_map[cell] = np.maximum(height, 0.0)  # the table itself is height 0
    color_map = np.zeros((rows * cols, 3), dtype=np.uint8)
    color_map[cell] = rgb.reshape(-1, 3)[idx]
    valid = np.zeros(rows * cols, dtype=bool)
    valid[cell] = True
    return Heightmap(color=color_map.reshape(rows, cols, 3), depth=depth_map.reshape(rows, cols),
                     valid=valid.reshape(rows, cols), config=cfg)


def observation_heightmap(obs: Observation, config: HeightmapConfig | None = None) -> Heightmap:
    """The heightmap of one Observation."""
    return make_heightmap(obs.rgb, obs.depth, obs.intrinsics, obs.camera_pose, config)
