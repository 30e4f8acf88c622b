"""SortingEnv: reset to a seeded or saved scene, step push / grasp+place actions, observe RGB-D.

    env = SortingEnv()
    obs = env.reset(seed=0)
    obs, outcome = env.step(Action(Primitive.GRASP, (0.3, 0.0, 0.0), 0.0, place_bin="knife"))

The env also exposes `privileged_state()` (true poses and classes) for scripted policies.
"""

from __future__ import annotations

import copy
import time
from dataclasses import dataclass

import mujoco
import numpy as np

from sortbot.config import EnvConfig
from sortbot.sim import outcome as measure
from sortbot.sim import ur3_kinematics as kin
from sortbot.sim.camera import RGBDCamera
from sortbot.sim.motion import ArmController
from sortbot.sim.objects import ObjectSpec
from sortbot.sim.primitives import Primitives
from sortbot.sim.scene_file import SceneSpec, load_scene, sample_scene
from sortbot.sim.world import BlowUp, World
from sortbot.types import Action, Observation, Outcome, Primitive


@dataclass
class ObjectState:
    """What a scripted policy may know about one object (never shown to learned policies)."""

    instance_id: int
    cls: str
    spec: ObjectSpec
    position: np.ndarray
    quaternion: np.ndarray
    status: str  # pick_area | table | bin:<name>
    grasp_point: np.ndarray  # world position of the handle's middle
    long_axis_yaw: float

    @property
    def remaining(self) -> bool:
        return not self.status.startswith("bin:")


@dataclass
class EpisodeStats:
    steps: int = 0
    consecutive_failures: int = 0
    blowups: int = 0
    done: bool = False
    end_reason: str | None = None


class SortingEnv:
    def __init__(self, config: EnvConfig | None = None):
        self.config = config or EnvConfig()
        self.world: World | None = None
        self.camera: RGBDCamera | None = None
        self.scene: SceneSpec | None = None
        self.stats = EpisodeStats()
        self.total_blowups = 0
        self._last_obs: Observation | None = None
        # cumulative timings for benchmarks: rendering per observation, physics per step
        self.render_seconds = 0.0
        self.observations = 0
        self.physics_seconds = 0.0

    # ---------------------------------------------------------------- lifecycle
    def reset(self, seed: int | None = None, scene: SceneSpec | str | None = None) -> Observation:
        """A new episode: a random drop from `seed`, or a scene (SceneSpec, file path or shipped name)."""
        if scene is None:
            spec = sample_scene(self.config, 0 if seed is None else int(seed))
        elif isinstance(scene, SceneSpec):
            spec = copy.deepcopy(scene)
        else:
            spec = load_scene(scene)
        self.close()
        self.scene = spec
        cfg = self.config
        if spec.source_container is not None and spec.source_container != cfg.workspace.source_container:
            cfg = copy.deepcopy(cfg)
            cfg.workspace.source_container = spec.source_container
        self.world = World(cfg, spec.objects)
        self.arm = ArmController(self.world, cfg)
        self.primitives = Primitives(self.arm, cfg)
        self.world.set_arm(self.primitives.home_q)
        self.arm.target = self.primitives.home_q.copy()
        self.arm.move_fingers(0.0, speed=1.0)
        self.camera = RGBDCamera(self.world, self.config.camera)
        self.stats = EpisodeStats()
        try:
            if spec.settle_time > 0:
                self.world.hold(spec.settle_time)
        except BlowUp as err:
            self._end(f"blowup:{err.reason}")
            self.stats.blowups += 1
            self.total_blowups += 1
        self._last_obs = self.observe()
        return self._last_obs

    def close(self) -> None:
        if self.camera is not None:
            self.camera.close()
            self.camera = None

    def __enter__(self) -> "SortingEnv":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # ---------------------------------------------------------------- observing
    def observe(self) -> Observation:
        t0 = time.perf_counter()
        rgb, depth, instances = self.camera.render()
        labels = self.camera.labels(instances)
        self.render_seconds += time.perf_counter() - t0
        self.observations += 1
        self._last_instances = instances
        return Observation(
            rgb=rgb, depth=depth, intrinsics=self.camera.intrinsics, camera_pose=self.camera.pose, labels=labels,
            joint_positions=self.world.arm_q(), gripper_opening=self.world.gripper_opening(), step=self.stats.steps,
        )

    def instance_map(self) -> np.ndarray:
        """Per-pixel instance ids of the last observation (0 = not an object)."""
        return self._last_instances

    def privileged_state(self) -> list[ObjectState]:
        poses = self.world.object_poses()
        out = []
        ws = self.config.workspace
        for k, spec in enumerate(self.world.specs):
            pos, quat = poses.positions[k], poses.quaternions[k]
            rot = _quat_to_matrix(quat)
            placed = measure.bin_of(pos, ws)
            status = f"bin:{placed}" if placed else ("pick_area" if measure.in_pick_area(pos, ws) else "table")
            out.append(ObjectState(
                instance_id=k + 1, cls=spec.cls, spec=spec, position=pos, quaternion=quat, status=status,
                grasp_point=pos + rot @ spec.grasp_point_local(),
                long_axis_yaw=float(np.arctan2(rot[1, 0], rot[0, 0])),
            ))
        return out

    def current_scene(self) -> SceneSpec:
        """The scene as it is now (poses included), with no settling: saving it reproduces this state."""
        poses = self.world.object_poses()
        objects = []
        for k, spec in enumerate(self.world.specs):
            o = copy.deepcopy(spec)
            o.position = tuple(float(v) for v in poses.positions[k])
            o.quaternion = tuple(float(v) for v in poses.quaternions[k])
            objects.append(o)
        return SceneSpec(objects=objects, settle_time=0.0, name=self.scene.name, description=self.scene.description,
                         seed=self.scene.seed, source_container=self.scene.source_container)

    # ---------------------------------------------------------------- acting
    def step(self, action: Action) -> tuple[Observation, Outcome]:
        if self.stats.done:
            raise RuntimeError("episode is over: call reset() first")
        _validate(action, self.config)
        out = Outcome(primitive=Primitive(action.primitive))
        poses_before = self.world.object_poses()
        t_sim, t0 = self.world.time, time.perf_counter()
        x, y, z = (float(v) for v in action.position)
        try:
            if action.primitive == Primitive.PUSH:
                self.primitives.push(x, y, float(action.angle))
                after = self.world.object_poses()
                out.moved_object_ids = measure.moved_objects(
                    poses_before.positions, poses_before.quaternions, after.positions, after.quaternions, self.config.outcome)
                out.push_moved = bool(out.moved_object_ids)
            else:
                self._grasp_and_place(action, out)
        except kin.UnreachableError:
            out.executed = False
            out.failure_reason = "unreachable"
        except BlowUp as err:
            out.failure_reason = f"blowup:{err.reason}"
            self.stats.blowups += 1
            self.total_blowups += 1
            self._end(out.failure_reason)
        self.physics_seconds += time.perf_counter() - t0
        out.sim_time_s = self.world.time - t_sim
        obs = self.observe()
        f = self.config.camera.focal_length
        out.change_detected = out.grasp_success or measure.change_detected(self._last_obs.depth, obs.depth, f, self.config.outcome)
        out.reward = _reward(out, self.config)
        self._bookkeep(out)
        self._last_obs = obs
        return obs, out

    def _grasp_and_place(self, action: Action, out: Outcome) -> None:
        x, y, z = (float(v) for v in action.position)
        result = self.primitives.grasp(x, y, z, float(action.angle))
        if result.held_id is None:
            self.primitives.release_empty()
            return
        out.grasp_success = True
        out.held_object_id = result.held_id
        out.held_object_class = self.world.specs[result.held_id - 1].cls
        try:
            self.primitives.place(action.place_bin, result.held_id)
        except kin.UnreachableError:  # decided after the grasp: an IK failure mid-motion
            raise BlowUp("ik_failure_mid_motion") from None
        out.placed_bin = self.primitives.bins_of_objects([result.held_id])[result.held_id]
        out.well_placed = out.placed_bin == out.held_object_class

    def _bookkeep(self, out: Outcome) -> None:
        s, oc = self.stats, self.config.outcome
        s.steps += 1
        success = out.grasp_success if out.primitive == Primitive.GRASP else out.push_moved
        s.consecutive_failures = 0 if success else s.consecutive_failures + 1
        if not s.done:
            if not any(o.remaining for o in self.privileged_state()):
                self._end("cleared")
            elif s.consecutive_failures >= oc.max_consecutive_failures:
                self._end("consecutive_failures")
            elif s.steps >= oc.max_steps:
                self._end("step_budget")
        out.done = s.done
        out.end_reason = s.end_reason

    def _end(self, reason: str) -> None:
        self.stats.done = True
        self.stats.end_reason = reason


def _validate(action: Action, cfg: EnvConfig) -> None:
    if int(action.primitive) not in (Primitive.PUSH, Primitive.GRASP):
        raise ValueError(f"unknown primitive {action.primitive!r}: use Primitive.PUSH or Primitive.GRASP")
    if len(action.position) != 3 or not np.all(np.isfinite(action.position)) or not np.isfinite(action.angle):
        raise ValueError(f"action position/angle must be 3 finite numbers and a finite angle, got {action.position}, {action.angle}")
    if action.primitive == Primitive.GRASP and action.place_bin not in cfg.workspace.bins:
        raise ValueError(f"a grasp must name the bin to place in: one of {', '.join(cfg.workspace.bins)}, got {action.place_bin!r}")


def _reward(out: Outcome, cfg: EnvConfig) -> float:
    oc = cfg.outcome
    if out.primitive == Primitive.GRASP:
        return oc.reward_grasp * out.grasp_success + oc.reward_well_placed * out.well_placed
    return oc.reward_push * out.push_moved


def _quat_to_matrix(q: np.ndarray) -> np.ndarray:
    out = np.zeros(9)
    mujoco.mju_quat2Mat(out, np.asarray(q, dtype=float))
    return out.reshape(3, 3)
