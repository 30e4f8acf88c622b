"""The LeRobot feature set of a sortbot dataset (DESIGN section 4) and the conversion of one
decision (observation, action, outcome) into one LeRobot frame, and back for labels.

One frame per decision: the observation the policy saw, the action it took, and what happened
(`next.reward`, `next.done`, `outcome.*`).
"""

from __future__ import annotations

import numpy as np

from sortbot.config import DatasetConfig
from sortbot.types import CLASS_NAMES, Action, CameraIntrinsics, CameraPose, Observation, Outcome

RGB_KEY = "observation.images.rgb"
DEPTH_KEY = "observation.images.depth"
STATE_KEY = "observation.state"
LABELS_KEY = "observation.labels"
ACTION_KEY = "action"

STATE_NAMES = [f"joint_{i}" for i in range(6)] + ["gripper_opening"]
LABEL_COLUMNS = ["present", "class", "x1", "y1", "x2", "y2", "x", "y", "z", "yaw"]
ACTION_NAMES = ["primitive", "x", "y", "z", "angle"]
NO_ID = -1  # integer outcome fields with no value (no held object, no bin)

# outcome feature -> dtype; ints hold indices into CLASS_NAMES (classes, bins) or NO_ID
OUTCOME_FIELDS: dict[str, str] = {
    "outcome.executed": "bool",
    "outcome.grasp_success": "bool",
    "outcome.held_object_id": "int64",
    "outcome.held_object_class": "int64",
    "outcome.placed_bin": "int64",
    "outcome.well_placed": "bool",
    "outcome.push_moved": "bool",
    "outcome.change_detected": "bool",
    "outcome.sim_time_s": "float32",
}


def dataset_features(height: int, width: int, config: DatasetConfig) -> dict[str, dict]:
    """The `features` argument of `LeRobotDataset.create` for a camera of height x width."""
    image_names = ["height", "width", "channels"]
    feats: dict[str, dict] = {
        RGB_KEY: {"dtype": "video", "shape": (height, width, 3), "names": image_names},
        DEPTH_KEY: {"dtype": "video", "shape": (height, width, 1), "names": image_names, "info": {"is_depth_map": True}},
        STATE_KEY: {"dtype": "float32", "shape": (len(STATE_NAMES),), "names": STATE_NAMES},
        # flat (max_objects * 10,): lerobot's aggregation and stats handle 1-D vectors only
        LABELS_KEY: {
            "dtype": "float32",
            "shape": (config.max_objects * len(LABEL_COLUMNS),),
            "names": [f"object{k}.{col}" for k in range(config.max_objects) for col in LABEL_COLUMNS],
        },
        ACTION_KEY: {"dtype": "float32", "shape": (len(ACTION_NAMES),), "names": ACTION_NAMES},
        "action.place_bin": {"dtype": "int64", "shape": (1,), "names": None},
        "next.reward": {"dtype": "float32", "shape": (1,), "names": None},
        "next.done": {"dtype": "bool", "shape": (1,), "names": None},
    }
    for key, dtype in OUTCOME_FIELDS.items():
        feats[key] = {"dtype": dtype, "shape": (1,), "names": None}
    return feats


def _class_or_none(name: str | None) -> int:
    return CLASS_NAMES.index(name) if name is not None else NO_ID


def encode_labels(obs: Observation, max_objects: int) -> np.ndarray:
    """(max_objects, 10) rows [present, class, x1, y1, x2, y2, x, y, z, yaw], by instance id."""
    labels = sorted(obs.labels, key=lambda lab: lab.instance_id)
    if len(labels) > max_objects:
        raise ValueError(f"{len(labels)} labelled objects exceed DatasetConfig.max_objects={max_objects}")
    out = np.zeros((max_objects, len(LABEL_COLUMNS)), dtype=np.float32)
    for row, lab in zip(out, labels):
        row[:] = [1.0, CLASS_NAMES.index(lab.cls), *lab.box, *lab.position, lab.yaw]
    return out


def label_rows(array: np.ndarray) -> np.ndarray:
    """An `observation.labels` value (flat or not, one frame or many) as (..., objects, 10) rows."""
    array = np.asarray(array)
    return array.reshape(*array.shape[:-1], -1, len(LABEL_COLUMNS)) if array.shape[-1] != len(LABEL_COLUMNS) else array


def step_frame(obs: Observation, action: Action, outcome: Outcome, config: DatasetConfig) -> dict:
    """One LeRobot frame (without `task`): what was seen, what was done, what came of it."""
    frame = {
        RGB_KEY: obs.rgb,
        DEPTH_KEY: obs.depth[..., None].astype(np.float32),
        STATE_KEY: np.array([*obs.joint_positions, obs.gripper_opening], dtype=np.float32),
        LABELS_KEY: encode_labels(obs, config.max_objects).reshape(-1),
        ACTION_KEY: action.as_array(),
        "action.place_bin": np.array([_class_or_none(action.place_bin)], dtype=np.int64),
        "next.reward": np.array([outcome.reward], dtype=np.float32),
        "next.done": np.array([outcome.done], dtype=bool),
        "outcome.executed": np.array([outcome.executed], dtype=bool),
        "outcome.grasp_success": np.array([outcome.grasp_success], dtype=bool),
        "outcome.held_object_id": np.array([NO_ID if outcome.held_object_id is None else outcome.held_object_id], dtype=np.int64),
        "outcome.held_object_class": np.array([_class_or_none(outcome.held_object_class)], dtype=np.int64),
        "outcome.placed_bin": np.array([_class_or_none(outcome.placed_bin)], dtype=np.int64),
        "outcome.well_placed": np.array([outcome.well_placed], dtype=bool),
        "outcome.push_moved": np.array([outcome.push_moved], dtype=bool),
        "outcome.change_detected": np.array([outcome.change_detected], dtype=bool),
        "outcome.sim_time_s": np.array([outcome.sim_time_s], dtype=np.float32),
    }
    return frame


def camera_info(obs: Observation) -> dict:
    """Intrinsics and pose stored in the camera features' `info` (they survive lerobot's probing)."""
    k = obs.intrinsics
    return {
        "camera.fx": k.fx, "camera.fy": k.fy, "camera.cx": k.cx, "camera.cy": k.cy,
        "camera.width": k.width, "camera.height": k.height,
        "camera.pose": obs.camera_pose.matrix().round(9).tolist(),  # camera -> base, OpenCV optical axes
    }


def camera_from_info(info: dict) -> tuple[CameraIntrinsics, CameraPose]:
    """The inverse of `camera_info`: intrinsics and pose from a camera feature's `info`."""
    intrinsics = CameraIntrinsics(fx=float(info["camera.fx"]), fy=float(info["camera.fy"]), cx=float(info["camera.cx"]),
                                  cy=float(info["camera.cy"]), width=int(info["camera.width"]), height=int(info["camera.height"]))
    pose = np.asarray(info["camera.pose"], float)
    return intrinsics, CameraPose(position=pose[:3, 3], rotation=pose[:3, :3])
