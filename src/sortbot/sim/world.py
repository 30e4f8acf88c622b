"""The compiled MuJoCo world and cheap queries on it: joints, gripper, objects, blow-up checks.

Everything that knows MuJoCo ids lives here, so primitives and the env speak in names and arrays.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from sortbot.config import EnvConfig
from sortbot.sim import robot_mjcf
from sortbot.sim.objects import ObjectSpec
from sortbot.sim.scene_mjcf import object_body_name, world_xml


class BlowUp(RuntimeError):
    """The physics left the realm of the plausible (NaN, objects thrown off the table, ...)."""

    def __init__(self, reason: str):
        super().__init__(reason)
        self.reason = reason


@dataclass
class ObjectPoses:
    positions: np.ndarray  # (N, 3)
    quaternions: np.ndarray  # (N, 4) w x y z


class World:
    """MjModel + MjData for one scene, with the index bookkeeping done once."""

    CONTROL_SUBSTEPS = 5  # physics steps per control update (10 ms at the default 2 ms step)

    def __init__(self, cfg: EnvConfig, specs: list[ObjectSpec]):
        self.cfg = cfg
        self.specs = specs
        self.model = mujoco.MjModel.from_xml_string(world_xml(cfg, specs))
        self.data = mujoco.MjData(self.model)
        m = self.model
        self.arm_qpos = np.array([m.jnt_qposadr[m.joint(j).id] for j in robot_mjcf.ARM_JOINTS])
        self.arm_dof = np.array([m.jnt_dofadr[m.joint(j).id] for j in robot_mjcf.ARM_JOINTS])
        self.finger_qpos = np.array([m.jnt_qposadr[m.joint(j).id] for j in robot_mjcf.FINGER_JOINTS])
        self.arm_act = np.array([m.actuator(j).id for j in robot_mjcf.ARM_JOINTS])
        self.finger_act = np.array([m.actuator(j).id for j in robot_mjcf.FINGER_JOINTS])
        self.tcp_site = m.site(robot_mjcf.TCP_SITE).id
        self.pad_geoms = np.array([m.geom(g).id for g in robot_mjcf.FINGER_PAD_GEOMS])
        self.object_bodies = np.array([m.body(object_body_name(i + 1)).id for i in range(len(specs))], dtype=int)
        self.object_qpos = np.array([m.jnt_qposadr[m.body_jntadr[b]] for b in self.object_bodies], dtype=int)
        self.object_dof = np.array([m.jnt_dofadr[m.body_jntadr[b]] for b in self.object_bodies], dtype=int)
        # geom id -> object instance id (1-based), 0 for anything that is not an object
        self.geom_instance = np.zeros(m.ngeom, dtype=np.int32)
        for k, body in enumerate(self.object_bodies):
            self.geom_instance[m.geom_bodyid == body] = k + 1
        self._max_speed = cfg.physics.max_object_speed
        self.set_noslip(False)

    # ---------------------------------------------------------------- robot
    def arm_q(self) -> np.ndarray:
        return self.data.qpos[self.arm_qpos].copy()

    def set_arm(self, q: np.ndarray) -> None:
        """Teleport the arm (reset only) and hold it there."""
        self.data.qpos[self.arm_qpos] = q
        self.data.qvel[self.arm_dof] = 0.0
        self.data.ctrl[self.arm_act] = q
        mujoco.mj_forward(self.model, self.data)

    def finger_q(self) -> np.ndarray:
        return self.data.qpos[self.finger_qpos].copy()

    def gripper_opening(self) -> float:
        return float(self.cfg.gripper.stroke - self.finger_q().sum())

    def tcp_position(self) -> np.ndarray:
        return self.data.site_xpos[self.tcp_site].copy()

    # ---------------------------------------------------------------- objects
    def object_poses(self) -> ObjectPoses:
        q = self.data.qpos
        idx = self.object_qpos[:, None] + np.arange(7)[None, :]
        block = q[idx] if len(self.object_qpos) else np.zeros((0, 7))
        return ObjectPoses(positions=block[:, :3].copy(), quaternions=block[:, 3:7].copy())

    def set_object_pose(self, index: int, position: np.ndarray, quaternion: np.ndarray) -> None:
        adr = self.object_qpos[index]
        self.data.qpos[adr : adr + 3] = position
        self.data.qpos[adr + 3 : adr + 7] = quaternion
        self.data.qvel[self.object_dof[index] : self.object_dof[index] + 6] = 0.0

    def objects_touching_pads(self) -> set[int]:
        """Instance ids of objects in contact with both finger pads."""
        touching: list[set[int]] = [set(), set()]
        d = self.data
        for i in range(d.ncon):
            g1, g2 = d.contact.geom1[i], d.contact.geom2[i]
            for side, pad in enumerate(self.pad_geoms):
                other = g2 if g1 == pad else g1 if g2 == pad else -1
                if other >= 0 and self.geom_instance[other]:
                    touching[side].add(int(self.geom_instance[other]))
        return touching[0] & touching[1]

    # ---------------------------------------------------------------- physics
    def set_noslip(self, on: bool) -> None:
        """Noslip passes keep a squeezed knife from creeping; they cost half the step rate, so they
        run only while the fingers hold something."""
        self.model.opt.noslip_iterations = self.cfg.physics.noslip_iterations if on else 0

    def check(self) -> None:
        """Raise BlowUp if the state is not physical any more."""
        d = self.data
        if not (np.all(np.isfinite(d.qpos)) and np.all(np.isfinite(d.qvel))):
            raise BlowUp("nan_state")
        if d.warning[mujoco.mjtWarning.mjWARN_BADQACC].number > 0:
            raise BlowUp("bad_acceleration")
        if len(self.object_qpos):
            pos = d.qpos[self.object_qpos[:, None] + np.arange(3)[None, :]]
            if np.any(np.abs(pos[:, :2]) > 0.6) or np.any(pos[:, 2] < self.cfg.workspace.table_height - 0.05):
                raise BlowUp("object_off_table")
            vel = d.qvel[self.object_dof[:, None] + np.arange(3)[None, :]]
            if np.any(np.linalg.norm(vel, axis=1) > self._max_speed):
                raise BlowUp("object_too_fast")

    def run(self, arm_targets: np.ndarray | None, finger_targets: np.ndarray | None) -> None:
        """Apply one control target per row (arm (T, 6), fingers (T,) ) for CONTROL_SUBSTEPS each."""
        rows = len(arm_targets) if arm_targets is not None else len(finger_targets)
        for t in range(rows):
            if arm_targets is not None:
                self.data.ctrl[self.arm_act] = arm_targets[t]
            if finger_targets is not None:
                self.data.ctrl[self.finger_act] = finger_targets[t]
            mujoco.mj_step(self.model, self.data, nstep=self.CONTROL_SUBSTEPS)
            self.check()

    def hold(self, seconds: float) -> None:
        """Keep current targets for `seconds` of physics."""
        steps = max(1, int(round(seconds / (self.model.opt.timestep * self.CONTROL_SUBSTEPS))))
        for _ in range(steps):
            mujoco.mj_step(self.model, self.data, nstep=self.CONTROL_SUBSTEPS)
            self.check()

    @property
    def control_dt(self) -> float:
        return self.model.opt.timestep * self.CONTROL_SUBSTEPS

    @property
    def time(self) -> float:
        return float(self.data.time)
