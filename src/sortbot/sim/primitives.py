"""The three primitives, executed by the arm through physics: push, grasp, place.

Each plans its whole path first (so an unreachable target is reported before the arm moves),
then runs it with acceleration limits and ends back at the home pose, out of the camera's view.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import mujoco
import numpy as np

from sortbot.config import EnvConfig
from sortbot.sim import outcome as measure
from sortbot.sim import ur3_kinematics as kin
from sortbot.sim.motion import ArmController


@dataclass
class GraspResult:
    held_ids: list[int] = field(default_factory=list)  # instance ids lifted with the gripper
    held_id: int | None = None  # the one nearest the TCP


def _yaw_of_flange(world) -> float:
    xmat = world.data.site_xmat[world.tcp_site].reshape(3, 3)
    return float(np.arctan2(xmat[1, 0], xmat[0, 0]))


class Primitives:
    def __init__(self, arm: ArmController, cfg: EnvConfig):
        self.arm = arm
        self.world = arm.world
        self.cfg = cfg
        m = cfg.motion
        self.home_q = arm.ik(np.array(m.home_tcp), m.home_yaw, seed=np.array([0.0, -np.pi / 2, np.pi / 2, -np.pi / 2, -np.pi / 2, 0.0]))

    # ---------------------------------------------------------------- helpers
    def _z(self, height: float) -> float:
        return self.cfg.workspace.table_height + height

    def go_home(self) -> None:
        self.arm.execute(self.arm.plan_joint(self.home_q))

    # ---------------------------------------------------------------- push
    def plan_push(self, x: float, y: float, angle: float) -> list[np.ndarray]:
        m = self.cfg.motion
        direction = np.array([np.cos(angle), np.sin(angle), 0.0])
        start = np.array([x, y, self._z(m.push_height)])
        end = start + m.push_length * direction
        up = np.array([0.0, 0.0, m.approach_height])
        q_above = self.arm.ik(start + up, angle)
        down = self.arm.plan_line(start + up, start, m.cartesian_speed, q_start=q_above)
        sweep = self.arm.plan_line(start, end, m.cartesian_speed, q_start=down[-1])
        lift = self.arm.plan_line(end, end + up, m.cartesian_speed, q_start=sweep[-1])
        return [self.arm.plan_joint(q_above), down, sweep, lift]

    def push(self, x: float, y: float, angle: float) -> None:
        """Closed fingers, `push_length` along `angle` starting at (x, y). Raises UnreachableError."""
        paths = self.plan_push(x, y, angle)
        self.arm.move_fingers(self.cfg.gripper.stroke / 2, speed=0.5)
        for path in paths:
            self.arm.execute(path)
        self.go_home()
        self.world.hold(self.cfg.motion.settle_time)

    # ---------------------------------------------------------------- grasp
    def grasp(self, x: float, y: float, z: float, angle: float) -> GraspResult:
        """Open, descend, close at a limited speed, lift gradually; report what came up."""
        m, g = self.cfg.motion, self.cfg.gripper
        z = max(z, self._z(g.fingertip_clearance))
        target = np.array([x, y, z])
        above = target + (0.0, 0.0, m.approach_height)
        lifted = np.array([x, y, self._z(m.lift_height)])
        q_above = self.arm.ik(above, angle)
        to_above = self.arm.plan_joint(q_above)
        down = self.arm.plan_line(above, target, m.cartesian_speed, q_start=q_above)
        up = self.arm.plan_line(target, lifted, m.lift_speed, q_start=down[-1])
        before = self.world.object_poses().positions
        self.arm.move_fingers(self.arm.opening_to_travel(g.grasp_opening), speed=0.5)
        self.arm.execute(to_above)
        self.arm.execute(down)
        self.world.set_noslip(True)
        self.arm.move_fingers(g.stroke / 2)  # squeeze: the force limit stops the pads on the object
        self.world.hold(0.05)
        self.arm.execute(up)
        after = self.world.object_poses().positions
        tcp = self.world.tcp_position()
        rose = after[:, 2] - before[:, 2] >= self.cfg.outcome.held_lift
        near = np.linalg.norm(after - tcp, axis=1) <= self.cfg.outcome.held_radius
        held = [int(i) + 1 for i in np.flatnonzero(rose & near)]
        result = GraspResult(held_ids=held)
        if held:
            result.held_id = min(held, key=lambda k: float(np.linalg.norm(after[k - 1] - tcp)))
        return result

    def release_empty(self) -> None:
        """After a failed grasp: open and go home."""
        self.arm.move_fingers(0.0, speed=0.5)
        self.world.set_noslip(False)
        self.go_home()

    # ---------------------------------------------------------------- place
    def place(self, bin_name: str, held_id: int) -> None:
        """Carry the held object over `bin_name` with its long axis along the bin, and drop it.

        The gripper yaw and TCP are chosen from where the object actually sits in the fingers, so
        an object held near one end still lands inside the bin.
        """
        m, ws = self.cfg.motion, self.cfg.workspace
        bx, by, byaw = ws.bins[bin_name]
        poses = self.world.object_poses()
        obj_pos = poses.positions[held_id - 1]
        rot = np.zeros(9)
        mujoco.mju_quat2Mat(rot, poses.quaternions[held_id - 1])
        obj_yaw = float(np.arctan2(rot[3], rot[0]))  # yaw of the object's long (x) axis
        tcp = self.world.tcp_position()
        flange_yaw = _yaw_of_flange(self.world)
        c, s = np.cos(-flange_yaw), np.sin(-flange_yaw)
        rel = obj_pos[:2] - tcp[:2]
        offset_local = np.array([c * rel[0] - s * rel[1], s * rel[0] + c * rel[1]])
        relative_yaw = obj_yaw - flange_yaw
        best = None
        for flip in (0.0, np.pi):
            new_yaw = byaw - relative_yaw + flip
            cy, sy = np.cos(new_yaw), np.sin(new_yaw)
            offset = np.array([cy * offset_local[0] - sy * offset_local[1], sy * offset_local[0] + cy * offset_local[1]])
            goal = np.array([bx - offset[0], by - offset[1], self._z(m.place_height)])
            try:
                q = kin.solve_top_down(goal, new_yaw, self.cfg.gripper.tool_length, self.arm.target, self.arm.limits, symmetric=False)
            except kin.UnreachableError:
                continue
            cost = float(np.sum(np.abs(q - self.arm.target)))
            if best is None or cost < best[0]:
                best = (cost, q)
        if best is None:
            raise kin.UnreachableError(f"cannot reach over the {bin_name} bin with the object held")
        self.arm.execute(self.arm.plan_joint(best[1], slow=True))
        self.arm.move_fingers(0.0, speed=0.5)
        self.world.set_noslip(False)
        self.world.hold(m.settle_time)
        self.go_home()

    def bins_of_objects(self, ids: list[int]) -> dict[int, str | None]:
        pos = self.world.object_poses().positions
        return {i: measure.bin_of(pos[i - 1], self.cfg.workspace) for i in ids}
