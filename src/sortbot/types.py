"""Data contracts shared by every layer (DESIGN section 4): Observation, Action, Outcome, labels."""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import IntEnum

import numpy as np

CLASS_NAMES: tuple[str, ...] = ("fork", "knife", "spoon", "block")
CUTLERY_CLASSES: tuple[str, ...] = ("fork", "knife", "spoon")


def class_index(name: str) -> int:
    """Index of a class name in CLASS_NAMES (the integer stored in datasets)."""
    try:
        return CLASS_NAMES.index(name)
    except ValueError:
        raise ValueError(f"unknown class {name!r}: expected one of {', '.join(CLASS_NAMES)}") from None


class Primitive(IntEnum):
    PUSH = 0
    GRASP = 1


@dataclass(frozen=True)
class CameraIntrinsics:
    """Pinhole intrinsics in pixels (OpenCV convention)."""

    fx: float
    fy: float
    cx: float
    cy: float
    width: int
    height: int

    def matrix(self) -> np.ndarray:
        return np.array([[self.fx, 0.0, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])

    def project(self, cam: np.ndarray) -> np.ndarray:
        """Camera-frame points (N, 3), z forward, to pixel coordinates (N, 2)."""
        cam = np.asarray(cam, float)
        return np.stack([cam[:, 0] / cam[:, 2] * self.fx + self.cx, cam[:, 1] / cam[:, 2] * self.fy + self.cy], axis=1)


@dataclass(frozen=True)
class CameraPose:
    """Camera-to-base transform in the OpenCV optical convention (x right, y down, z forward)."""

    position: np.ndarray  # (3,)
    rotation: np.ndarray  # (3, 3), columns are the camera axes in the base frame

    def matrix(self) -> np.ndarray:
        out = np.eye(4)
        out[:3, :3] = self.rotation
        out[:3, 3] = self.position
        return out


@dataclass
class ObjectLabel:
    """Exact label of one visible object, from the renderer's segmentation."""

    instance_id: int
    cls: str
    box: tuple[int, int, int, int]  # x1, y1, x2, y2 in pixels, inclusive-exclusive
    mask: np.ndarray  # (H, W) bool
    position: np.ndarray  # (3,) base frame, metres
    quaternion: np.ndarray  # (4,) w, x, y, z

    @property
    def yaw(self) -> float:
        w, x, y, z = self.quaternion
        return float(np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z)))


@dataclass
class Observation:
    """One decision's view of the world: RGB-D, calibration, exact labels, robot state."""

    rgb: np.ndarray  # (H, W, 3) uint8
    depth: np.ndarray  # (H, W) float32 metres along the optical axis
    intrinsics: CameraIntrinsics
    camera_pose: CameraPose
    labels: list[ObjectLabel]
    joint_positions: np.ndarray  # (6,) radians
    gripper_opening: float  # metres between the finger pads
    step: int = 0


@dataclass
class Action:
    """A primitive at a base-frame position; `angle` is the push direction or the gripper's
    closing-axis yaw. A grasp also names the bin the policy believes the object belongs in."""

    primitive: Primitive
    position: tuple[float, float, float]
    angle: float
    place_bin: str | None = None
    heightmap_index: tuple[int, int, int] | None = None  # (rotation, row, col) for learned policies

    def as_array(self) -> np.ndarray:
        """[primitive, x, y, z, angle]: the dataset's `action` feature."""
        return np.array([int(self.primitive), *self.position, self.angle], dtype=np.float32)


@dataclass
class Outcome:
    """What an action achieved, measured in the simulator (DESIGN section 4)."""

    primitive: Primitive
    executed: bool = True  # False when the target was unreachable and the arm did not move
    grasp_success: bool = False
    held_object_id: int | None = None
    held_object_class: str | None = None
    placed_bin: str | None = None
    well_placed: bool = False
    push_moved: bool = False
    change_detected: bool = False
    reward: float = 0.0
    done: bool = False
    end_reason: str | None = None  # cleared | step_budget | consecutive_failures | blowup
    failure_reason: str | None = None  # unreachable | blowup | ...
    sim_time_s: float = 0.0
    moved_object_ids: list[int] = field(default_factory=list)
