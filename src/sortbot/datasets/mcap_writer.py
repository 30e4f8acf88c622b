"""One MCAP log per episode, written with foxglove-sdk while the episode runs (DESIGN section 4).

Foxglove well-known schemas where one exists (images, calibration, transforms, scene), named JSON
schemas for sortbot's own messages. Each decision is flushed to disk as soon as it is logged, so a
crash loses only the decision in flight and Foxglove opens the file as it is.
"""

from __future__ import annotations

import io
import json
from pathlib import Path

import numpy as np

from sortbot.config import DatasetConfig
from sortbot.types import Action, Observation, Outcome

TOPIC_RGB = "/camera/rgb"
TOPIC_DEPTH = "/camera/depth"
TOPIC_CALIBRATION = "/camera/calibration"
TOPIC_TF = "/tf"
TOPIC_SCENE = "/scene"
TOPIC_LABELS = "/labels"
TOPIC_ACTION = "/action"
TOPIC_OUTCOME = "/outcome"
ALL_TOPICS = (TOPIC_RGB, TOPIC_DEPTH, TOPIC_CALIBRATION, TOPIC_TF, TOPIC_SCENE, TOPIC_LABELS, TOPIC_ACTION, TOPIC_OUTCOME)
EPISODE_METADATA = "sortbot.episode"  # name of the MCAP metadata record
BASE_FRAME, CAMERA_FRAME = "base", "camera"

_NUMBER_LIST = {"type": "array", "items": {"type": "number"}}
LABELS_SCHEMA = {
    "title": "sortbot.Labels", "type": "object",
    "properties": {
        "step": {"type": "integer"},
        "objects": {"type": "array", "items": {"type": "object", "properties": {
            "instance_id": {"type": "integer"}, "cls": {"type": "string"}, "box": _NUMBER_LIST,
            "position": _NUMBER_LIST, "quaternion": _NUMBER_LIST, "yaw": {"type": "number"}}}},
    },
}
ACTION_SCHEMA = {
    "title": "sortbot.Action", "type": "object",
    "properties": {
        "step": {"type": "integer"}, "primitive": {"type": "string", "enum": ["push", "grasp"]},
        "position": _NUMBER_LIST, "angle": {"type": "number"}, "place_bin": {"type": ["string", "null"]},
        "heightmap_index": {"type": ["array", "null"], "items": {"type": "integer"}},
    },
}
OUTCOME_SCHEMA = {
    "title": "sortbot.Outcome", "type": "object",
    "properties": {
        "step": {"type": "integer"}, "primitive": {"type": "string"}, "executed": {"type": "boolean"},
        "grasp_success": {"type": "boolean"}, "held_object_id": {"type": ["integer", "null"]},
        "held_object_class": {"type": ["string", "null"]}, "placed_bin": {"type": ["string", "null"]},
        "well_placed": {"type": "boolean"}, "push_moved": {"type": "boolean"},
        "change_detected": {"type": "boolean"}, "reward": {"type": "number"}, "done": {"type": "boolean"},
        "end_reason": {"type": ["string", "null"]}, "failure_reason": {"type": ["string", "null"]},
        "sim_time_s": {"type": "number"}, "moved_object_ids": {"type": "array", "items": {"type": "integer"}},
        "wall_time_s": {"type": "number"},
    },
}
_CLASS_COLOURS = {"fork": (0.9, 0.3, 0.2), "knife": (0.2, 0.6, 0.9), "spoon": (0.3, 0.8, 0.3), "block": (0.8, 0.7, 0.2)}


def _stamp(t_ns: int):
    from foxglove.messages import Timestamp

    return Timestamp(int(t_ns // 1_000_000_000), int(t_ns % 1_000_000_000))


def _encode_rgb(rgb: np.ndarray, config: DatasetConfig) -> tuple[bytes, str]:
    from PIL import Image

    buf = io.BytesIO()
    if config.mcap_image_format == "jpeg":
        Image.fromarray(rgb).save(buf, format="JPEG", quality=config.mcap_jpeg_quality)
    elif config.mcap_image_format == "png":
        Image.fromarray(rgb).save(buf, format="PNG", compress_level=1)
    else:
        raise ValueError(f"DatasetConfig.mcap_image_format must be png or jpeg, not {config.mcap_image_format!r}")
    return buf.getvalue(), config.mcap_image_format


class McapEpisodeLog:
    """Writes one episode's MCAP file; use as a context manager."""

    def __init__(self, path: Path, metadata: dict, config: DatasetConfig | None = None, overwrite: bool = False):
        import foxglove
        from foxglove import channels as ch

        self.path = Path(path)
        self.config = config or DatasetConfig()
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._context = foxglove.Context()
        self._writer = foxglove.open_mcap(self.path, allow_overwrite=overwrite, context=self._context)
        ctx = self._context
        self._rgb = ch.CompressedImageChannel(TOPIC_RGB, context=ctx)
        self._depth = ch.RawImageChannel(TOPIC_DEPTH, context=ctx)
        self._calibration = ch.CameraCalibrationChannel(TOPIC_CALIBRATION, context=ctx)
        self._tf = ch.FrameTransformsChannel(TOPIC_TF, context=ctx)
        self._scene = ch.SceneUpdateChannel(TOPIC_SCENE, context=ctx)
        self._labels = foxglove.Channel(TOPIC_LABELS, schema=LABELS_SCHEMA, context=ctx)
        self._action = foxglove.Channel(TOPIC_ACTION, schema=ACTION_SCHEMA, context=ctx)
        self._outcome = foxglove.Channel(TOPIC_OUTCOME, schema=OUTCOME_SCHEMA, context=ctx)
        self._writer.write_metadata(EPISODE_METADATA, {k: v if isinstance(v, str) else json.dumps(v, default=str)
                                                       for k, v in metadata.items()})
        self._writer.flush()

    def __enter__(self) -> "McapEpisodeLog":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        if self._writer is None:
            return
        from foxglove import channel as fox_channel

        self._writer.close()
        self._writer = None
        for chan in (self._rgb, self._depth, self._calibration, self._tf, self._scene, self._labels, self._action, self._outcome):
            chan.close()
            # foxglove-sdk 0.25 keeps every foxglove.Channel in a module-level dict forever: one
            # episode log per file would leak three channels (and their context) per episode
            fox_channel._channels_by_id.pop(chan.id(), None)
        self._context = None

    # -- per decision ------------------------------------------------------------------------
    def log_observation(self, obs: Observation, objects: list[dict], t_ns: int) -> None:
        """Camera images, calibration, transforms, scene (true object poses) and labels."""
        from foxglove import messages as m

        stamp = _stamp(t_ns)
        data, fmt = _encode_rgb(obs.rgb, self.config)
        self._rgb.log(m.CompressedImage(timestamp=stamp, frame_id=CAMERA_FRAME, data=data, format=fmt), log_time=t_ns)
        depth = np.ascontiguousarray(obs.depth, dtype="<f4")
        h, w = depth.shape
        self._depth.log(m.RawImage(timestamp=stamp, frame_id=CAMERA_FRAME, width=w, height=h, encoding="32FC1",
                                   step=4 * w, data=depth.tobytes()), log_time=t_ns)
        k = obs.intrinsics
        self._calibration.log(m.CameraCalibration(
            timestamp=stamp, frame_id=CAMERA_FRAME, width=k.width, height=k.height, distortion_model="plumb_bob",
            D=[0.0] * 5, K=[float(v) for v in k.matrix().ravel()], R=[1.0, 0, 0, 0, 1.0, 0, 0, 0, 1.0],
            P=[k.fx, 0.0, k.cx, 0.0, 0.0, k.fy, k.cy, 0.0, 0.0, 0.0, 1.0, 0.0]), log_time=t_ns)
        self._tf.log(m.FrameTransforms(transforms=[_camera_transform(obs, stamp)]), log_time=t_ns)
        self._scene.log(m.SceneUpdate(entities=[_entity(o, stamp) for o in objects]), log_time=t_ns)
        self._labels.log({"step": obs.step, "objects": [
            {"instance_id": lab.instance_id, "cls": lab.cls, "box": [int(v) for v in lab.box],
             "position": [float(v) for v in lab.position], "quaternion": [float(v) for v in lab.quaternion],
             "yaw": lab.yaw} for lab in obs.labels]}, log_time=t_ns)

    def log_action(self, step: int, action: Action, t_ns: int) -> None:
        self._action.log({
            "step": step, "primitive": action.primitive.name.lower(),
            "position": [float(v) for v in action.position], "angle": float(action.angle),
            "place_bin": action.place_bin,
            "heightmap_index": None if action.heightmap_index is None else [int(v) for v in action.heightmap_index],
        }, log_time=t_ns)

    def log_outcome(self, step: int, outcome: Outcome, t_ns: int, wall_time_s: float) -> None:
        self._outcome.log({
            "step": step, "primitive": outcome.primitive.name.lower(), "executed": outcome.executed,
            "grasp_success": outcome.grasp_success, "held_object_id": outcome.held_object_id,
            "held_object_class": outcome.held_object_class, "placed_bin": outcome.placed_bin,
            "well_placed": outcome.well_placed, "push_moved": outcome.push_moved,
            "change_detected": outcome.change_detected, "reward": float(outcome.reward), "done": outcome.done,
            "end_reason": outcome.end_reason, "failure_reason": outcome.failure_reason,
            "sim_time_s": float(outcome.sim_time_s), "moved_object_ids": [int(i) for i in outcome.moved_object_ids],
            "wall_time_s": float(wall_time_s),
        }, log_time=t_ns)
        self._writer.flush()  # one decision is durable once its outcome is on disk


def _camera_transform(obs: Observation, stamp):
    from foxglove import messages as m
    from scipy.spatial.transform import Rotation

    x, y, z, w = Rotation.from_matrix(obs.camera_pose.rotation).as_quat()
    p = obs.camera_pose.position
    return m.FrameTransform(timestamp=stamp, parent_frame_id=BASE_FRAME, child_frame_id=CAMERA_FRAME,
                            translation=m.Vector3(x=float(p[0]), y=float(p[1]), z=float(p[2])),
                            rotation=m.Quaternion(x=float(x), y=float(y), z=float(z), w=float(w)))


def _entity(obj: dict, stamp):
    """A box marker per object: pose from the simulator, size from its footprint."""
    from foxglove import messages as m

    px, py, pz = (float(v) for v in obj["position"])
    qw, qx, qy, qz = (float(v) for v in obj["quaternion"])
    pose = m.Pose(position=m.Vector3(x=px, y=py, z=pz), orientation=m.Quaternion(x=qx, y=qy, z=qz, w=qw))
    r, g, b = _CLASS_COLOURS.get(obj["cls"], (0.7, 0.7, 0.7))
    sx, sy, sz = (float(v) for v in obj["size"])
    return m.SceneEntity(
        timestamp=stamp, frame_id=BASE_FRAME, id=f"object_{obj['instance_id']}",
        metadata=[m.KeyValuePair(key="class", value=obj["cls"]), m.KeyValuePair(key="status", value=obj["status"])],
        cubes=[m.CubePrimitive(pose=pose, size=m.Vector3(x=sx, y=sy, z=sz), color=m.Color(r=r, g=g, b=b, a=0.6))],
        texts=[m.TextPrimitive(pose=pose, billboard=True, font_size=12.0, scale_invariant=True,
                               color=m.Color(r=1.0, g=1.0, b=1.0, a=1.0), text=obj["cls"])],
    )
