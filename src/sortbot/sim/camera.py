"""The RGB-D camera: RGB, metric depth and segmentation from `mujoco.Renderer`, turned into
exact per-object labels (instance id, class, box, mask, 6-D pose).

One `update_scene` feeds all three renders; nothing renders while the arm moves.
"""

from __future__ import annotations

import mujoco
import numpy as np

from sortbot.config import CameraConfig
from sortbot.sim.scene_mjcf import CAMERA_NAME, camera_axes
from sortbot.sim.world import World
from sortbot.types import CameraIntrinsics, CameraPose, ObjectLabel

_GEOM = int(mujoco.mjtObj.mjOBJ_GEOM)  # a plain int: comparing an array to the enum object is elementwise Python
MIN_VISIBLE_PIXELS = 15  # fewer segmentation pixels than this and the object is not labelled


def camera_from_config(cfg: CameraConfig) -> tuple[CameraIntrinsics, CameraPose]:
    """Intrinsics and pose of a camera of this config (square pixels, principal point at the
    centre, looking from `position` at `lookat`); usable without a renderer."""
    intrinsics = CameraIntrinsics(fx=cfg.focal_length, fy=cfg.focal_length, cx=cfg.width / 2, cy=cfg.height / 2,
                                  width=cfg.width, height=cfg.height)
    right, up, forward = camera_axes(np.array(cfg.position, float), np.array(cfg.lookat, float))
    # OpenCV optical frame: x right, y down, z forward
    return intrinsics, CameraPose(position=np.array(cfg.position, float), rotation=np.stack([right, -up, forward], axis=1))


class RGBDCamera:
    def __init__(self, world: World, cfg: CameraConfig):
        self.world = world
        self.cfg = cfg
        self.renderer = mujoco.Renderer(world.model, height=cfg.height, width=cfg.width)
        self.intrinsics, self.pose = camera_from_config(cfg)

    def render(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """RGB (H, W, 3) uint8, depth (H, W) float32 metres, instance map (H, W) int32 (0 = none)."""
        r = self.renderer
        r.update_scene(self.world.data, camera=CAMERA_NAME)
        rgb = r.render().copy()
        r.enable_depth_rendering()
        depth = r.render().astype(np.float32)
        r.disable_depth_rendering()
        r.enable_segmentation_rendering()
        seg = r.render()
        r.disable_segmentation_rendering()
        geom_ids = seg[..., 0]
        is_geom = (seg[..., 1] == _GEOM) & (geom_ids >= 0)
        instances = np.where(is_geom, self.world.geom_instance[np.clip(geom_ids, 0, None)], 0).astype(np.int32)
        return rgb, depth, instances

    def labels(self, instances: np.ndarray) -> list[ObjectLabel]:
        """A label for every object with enough visible pixels; boxes are the masks' extents."""
        poses = self.world.object_poses()
        counts = np.bincount(instances.ravel(), minlength=len(self.world.specs) + 1)
        out = []
        for inst in range(1, len(self.world.specs) + 1):
            if counts[inst] < MIN_VISIBLE_PIXELS:
                continue
            mask = instances == inst
            rows = np.flatnonzero(mask.any(axis=1))
            cols = np.flatnonzero(mask.any(axis=0))
            out.append(
                ObjectLabel(
                    instance_id=inst,
                    cls=self.world.specs[inst - 1].cls,
                    box=(int(cols[0]), int(rows[0]), int(cols[-1]) + 1, int(rows[-1]) + 1),
                    mask=mask,
                    position=poses.positions[inst - 1],
                    quaternion=poses.quaternions[inst - 1],
                )
            )
        return out

    def close(self) -> None:
        self.renderer.close()
