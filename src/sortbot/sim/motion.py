"""Arm and gripper motion through physics: acceleration-limited joint and Cartesian moves.

Every move is planned whole before the arm starts (IK on every waypoint), so an unreachable
target is reported before anything moves. Targets follow trapezoidal velocity profiles: a jump
in the position target jerks a held knife out of the fingers (DESIGN section 5).
"""

from __future__ import annotations

import numpy as np

from sortbot.config import EnvConfig
from sortbot.sim import ur3_kinematics as kin
from sortbot.sim.world import World

CARTESIAN_WAYPOINT_SPACING = 0.005  # m between IK solutions along a straight line


def trapezoid(distance: float, speed: float, accel: float, dt: float) -> np.ndarray:
    """Samples of travelled distance at `dt` for a rest-to-rest trapezoidal (or triangular) profile.
    The last sample is exactly `distance`."""
    if distance <= 1e-12:
        return np.array([0.0])
    t_acc = speed / accel
    if accel * t_acc * t_acc >= distance:  # never reaches full speed
        t_acc = np.sqrt(distance / accel)
        speed = accel * t_acc
        t_total = 2 * t_acc
    else:
        t_total = 2 * t_acc + (distance - accel * t_acc * t_acc) / speed
    t = np.append(np.arange(dt, t_total, dt), t_total)
    s = np.where(
        t < t_acc,
        0.5 * accel * t * t,
        np.where(
            t <= t_total - t_acc,
            0.5 * accel * t_acc * t_acc + speed * (t - t_acc),
            distance - 0.5 * accel * (t_total - t) ** 2,
        ),
    )
    return np.clip(s, 0.0, distance)


class ArmController:
    """Plans and executes moves of the UR3 and its gripper in a World."""

    def __init__(self, world: World, cfg: EnvConfig):
        self.world = world
        self.cfg = cfg
        self.limits = kin.ArmLimits()
        self.target = world.arm_q()  # last commanded joint target
        self.finger_target = world.finger_q().mean()

    # ---------------------------------------------------------------- planning
    def ik(self, position: np.ndarray, yaw: float, seed: np.ndarray | None = None) -> np.ndarray:
        seed = self.target if seed is None else seed
        return kin.solve_top_down(np.asarray(position, float), yaw, self.cfg.gripper.tool_length, seed, self.limits)

    def plan_joint(self, q_goal: np.ndarray, q_start: np.ndarray | None = None, slow: bool = False) -> np.ndarray:
        q_start = self.target if q_start is None else q_start
        m = self.cfg.motion
        speed = m.joint_speed * (0.5 if slow else 1.0)
        accel = m.joint_accel * (0.35 if slow else 1.0)
        delta = q_goal - q_start
        span = float(np.max(np.abs(delta)))
        s = trapezoid(span, speed, accel, self.world.control_dt)
        frac = s / span if span > 0 else np.ones_like(s)
        return q_start[None, :] + frac[:, None] * delta[None, :]

    def plan_line(self, p_start: np.ndarray, p_goal: np.ndarray, speed: float,
                  q_start: np.ndarray | None = None) -> np.ndarray:
        """Joint targets moving the TCP on a straight line, keeping the gripper yaw that `q_start`
        has (raises UnreachableError)."""
        q = self.target if q_start is None else q_start
        yaw = kin.flange_yaw(q)
        p_start, p_goal = np.asarray(p_start, float), np.asarray(p_goal, float)
        length = float(np.linalg.norm(p_goal - p_start))
        n = max(2, int(np.ceil(length / CARTESIAN_WAYPOINT_SPACING)) + 1)
        along = np.linspace(0.0, length, n)
        waypoints = []
        for s in along:
            p = p_start + (p_goal - p_start) * (s / length if length > 0 else 1.0)
            q = kin.solve_top_down(p, yaw, self.cfg.gripper.tool_length, q, self.limits, symmetric=False)
            waypoints.append(q)
        waypoints = np.array(waypoints)
        if np.any(np.abs(np.diff(waypoints, axis=0)) > 0.5):
            raise kin.UnreachableError("straight line passes a wrist singularity")
        s_t = trapezoid(length, speed, self.cfg.motion.cartesian_accel, self.world.control_dt)
        return np.stack([np.interp(s_t, along, waypoints[:, j]) for j in range(6)], axis=1)

    def plan_fingers(self, goal: float, speed: float) -> np.ndarray:
        s = trapezoid(abs(goal - self.finger_target), speed, speed * 20, self.world.control_dt)
        return self.finger_target + np.sign(goal - self.finger_target) * s

    # ---------------------------------------------------------------- execution
    def execute(self, arm_path: np.ndarray) -> None:
        """Follow joint targets, then wait (bounded) for the servos to converge."""
        self.world.run(arm_path, None)
        self.target = arm_path[-1].copy()
        m = self.cfg.motion
        waited = 0.0
        while np.max(np.abs(self.world.arm_q() - self.target)) > m.servo_tolerance and waited < m.servo_timeout:
            self.world.hold(self.world.control_dt)
            waited += self.world.control_dt

    def move_fingers(self, goal: float, speed: float | None = None) -> None:
        """Ramp both finger targets to `goal` (inward travel per finger) at a limited speed."""
        path = self.plan_fingers(goal, speed or self.cfg.gripper.close_speed)
        self.world.run(None, np.repeat(path[:, None], 2, axis=1))
        self.finger_target = float(goal)

    def opening_to_travel(self, opening: float) -> float:
        """Finger travel giving a pad-to-pad `opening` (clipped to the stroke)."""
        stroke = self.cfg.gripper.stroke
        return float(np.clip((stroke - opening) / 2, 0.0, stroke / 2))
