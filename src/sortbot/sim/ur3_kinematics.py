"""UR3 forward and closed-form inverse kinematics from its DH parameters (CB3 series).

The MuJoCo model is built from the same table (`sim/robot_mjcf.py`), so a joint vector here is
the same vector in the simulator. IK returns every analytic solution; `solve_top_down` picks the
one nearest the current joints and reports an unreachable target instead of clipping it.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

# DH table (Universal Robots, UR3 CB3): d, a, alpha per joint.
D = np.array([0.1519, 0.0, 0.0, 0.11235, 0.08535, 0.0819])
A = np.array([0.0, -0.24365, -0.21325, 0.0, 0.0, 0.0])
ALPHA = np.array([np.pi / 2, 0.0, 0.0, np.pi / 2, -np.pi / 2, 0.0])

JOINT_NAMES = ("shoulder_pan", "shoulder_lift", "elbow", "wrist_1", "wrist_2", "wrist_3")
# The UR3 manual: every joint +-360 deg; we keep the elbow within +-180 deg so the arm cannot fold
# through itself (the sim has no self-collision for the arm).
JOINT_LOWER = np.array([-2 * np.pi, -2 * np.pi, -np.pi, -2 * np.pi, -2 * np.pi, -2 * np.pi])
JOINT_UPPER = -JOINT_LOWER
# UR3 manual: 180 deg/s base/shoulder/elbow, 360 deg/s wrists; torques 56/56/28/12/12/12 Nm.
JOINT_MAX_SPEED = np.deg2rad([180.0, 180.0, 180.0, 360.0, 360.0, 360.0])
JOINT_MAX_TORQUE = np.array([56.0, 56.0, 28.0, 12.0, 12.0, 12.0])


class UnreachableError(ValueError):
    """The requested pose has no IK solution within the joint limits."""


def dh_transform(theta: float, d: float, a: float, alpha: float) -> np.ndarray:
    """Rz(theta) Tz(d) Tx(a) Rx(alpha)."""
    ct, st, ca, sa = np.cos(theta), np.sin(theta), np.cos(alpha), np.sin(alpha)
    return np.array(
        [
            [ct, -st * ca, st * sa, a * ct],
            [st, ct * ca, -ct * sa, a * st],
            [0.0, sa, ca, d],
            [0.0, 0.0, 0.0, 1.0],
        ]
    )


def forward(q: np.ndarray) -> np.ndarray:
    """Flange pose (4x4) in the base frame."""
    out = np.eye(4)
    for i in range(6):
        out = out @ dh_transform(q[i], D[i], A[i], ALPHA[i])
    return out


def inverse(target: np.ndarray) -> list[np.ndarray]:
    """All closed-form solutions (up to 8) placing the flange at `target` (4x4).

    Derivation: the wrist centre p5 lies d4 off the arm plane (theta1); the tool axis' component
    along joint 2's axis is cos(theta5); theta6 from the same axis seen in the flange frame;
    joints 2-4 form a planar two-link chain.
    """
    rot, p6 = target[:3, :3], target[:3, 3]
    p5 = p6 - D[5] * rot[:, 2]
    r = np.hypot(p5[0], p5[1])
    if r < abs(D[3]) + 1e-9:
        return []
    psi = np.arctan2(p5[1], p5[0])
    offset = np.arcsin(np.clip(D[3] / r, -1.0, 1.0))
    solutions = []
    for theta1 in (psi + offset, psi + np.pi - offset):
        z1 = np.array([np.sin(theta1), -np.cos(theta1), 0.0])
        c5 = (p6 @ z1 - D[3]) / D[5]
        if abs(c5) > 1.0 + 1e-9:
            continue
        for theta5 in (np.arccos(np.clip(c5, -1, 1)), -np.arccos(np.clip(c5, -1, 1))):
            s5 = np.sin(theta5)
            if abs(s5) < 1e-9:
                theta6 = 0.0  # wrist singularity: any theta6 works, keep it zero
            else:
                theta6 = np.arctan2(-(rot[:, 1] @ z1) / s5, (rot[:, 0] @ z1) / s5)
            t01 = dh_transform(theta1, D[0], A[0], ALPHA[0])
            t46 = dh_transform(theta5, D[4], A[4], ALPHA[4]) @ dh_transform(theta6, D[5], A[5], ALPHA[5])
            t14 = np.linalg.inv(t01) @ target @ np.linalg.inv(t46)
            px, py = t14[0, 3], t14[1, 3]
            c3 = (px * px + py * py - A[1] ** 2 - A[2] ** 2) / (2 * A[1] * A[2])
            if abs(c3) > 1.0 + 1e-9:
                continue
            for theta3 in (np.arccos(np.clip(c3, -1, 1)), -np.arccos(np.clip(c3, -1, 1))):
                theta2 = np.arctan2(py, px) - np.arctan2(A[2] * np.sin(theta3), A[1] + A[2] * np.cos(theta3))
                theta234 = np.arctan2(t14[1, 0], t14[0, 0])
                theta4 = theta234 - theta2 - theta3
                q = _wrap(np.array([theta1, theta2, theta3, theta4, theta5, theta6]))
                if np.allclose(forward(q), target, atol=1e-6):
                    solutions.append(q)
    return solutions


def _wrap(q: np.ndarray) -> np.ndarray:
    return (q + np.pi) % (2 * np.pi) - np.pi


def flange_yaw(q: np.ndarray) -> float:
    """Yaw of the flange x axis (the closing axis) about the base z axis."""
    rot = forward(q)[:3, :3]
    return float(np.arctan2(rot[1, 0], rot[0, 0]))


def top_down_pose(position: np.ndarray, yaw: float, tool_length: float) -> np.ndarray:
    """Flange pose that puts the TCP at `position` with the tool pointing down and the closing
    axis (flange x) at `yaw` about the base z axis."""
    c, s = np.cos(yaw), np.sin(yaw)
    out = np.eye(4)
    out[:3, 0] = (c, s, 0.0)
    out[:3, 1] = (s, -c, 0.0)
    out[:3, 2] = (0.0, 0.0, -1.0)
    out[:3, 3] = np.asarray(position, dtype=float) + (0.0, 0.0, tool_length)
    return out


@dataclass(frozen=True)
class ArmLimits:
    """Where a solution may lie; the elbow must stay above `min_elbow_height` (the table)."""

    lower: np.ndarray = field(default_factory=JOINT_LOWER.copy)
    upper: np.ndarray = field(default_factory=JOINT_UPPER.copy)
    min_elbow_height: float = 0.03


def _elbow_height(q: np.ndarray) -> float:
    t = dh_transform(q[0], D[0], A[0], ALPHA[0]) @ dh_transform(q[1], D[1], A[1], ALPHA[1])
    return float(t[2, 3])


def is_preferred(q: np.ndarray) -> bool:
    """The posture family every move stays in, so a path never flips configuration: shoulder
    facing the target (theta1 = psi + asin(d4 / r)), elbow up (theta3 < 0) and theta5 > 0
    (of the 8 analytic families, the one that covers the whole pick area and every bin at every
    yaw with the tool down; checked in tests/sim/test_kinematics.py). Leaving it needs a stretched arm or a wrist singularity, so paths inside it are
    continuous; it covers the pick area and all three bins with the tool down."""
    flange = forward(q)
    p5 = flange[:3, 3] - D[5] * flange[:3, 2]
    r = np.hypot(p5[0], p5[1])
    if r < abs(D[3]):
        return False
    facing = np.arctan2(p5[1], p5[0]) + np.arcsin(D[3] / r)
    if abs(_wrap(np.array([q[0] - facing]))[0]) > 1e-6:
        return False
    wrapped = _wrap(q)
    return bool(wrapped[2] < 0 and wrapped[4] > 0)


def nearest_solution(solutions: list[np.ndarray], current: np.ndarray, limits: ArmLimits) -> np.ndarray | None:
    """The solution (with each joint shifted by multiples of 2 pi inside the limits) closest to
    `current`, so that a Cartesian path never flips configuration."""
    valid = []
    for q in solutions:
        if _elbow_height(q) < limits.min_elbow_height:
            continue
        # choose per joint the 2*pi shift nearest the current angle, then check limits
        shifted = q + 2 * np.pi * np.round((current - q) / (2 * np.pi))
        for j in range(6):  # a shift that leaves the range is undone by one turn the other way
            if shifted[j] > limits.upper[j]:
                shifted[j] -= 2 * np.pi
            elif shifted[j] < limits.lower[j]:
                shifted[j] += 2 * np.pi
        if np.any(shifted < limits.lower - 1e-9) or np.any(shifted > limits.upper + 1e-9):
            continue
        valid.append((q, shifted))
    valid = [v for v in valid if is_preferred(v[0])] or valid
    best, best_cost = None, np.inf
    for q, shifted in valid:
        cost = float(np.sum(np.abs(shifted - current) * (2.0, 2.0, 1.5, 1.0, 1.0, 0.5)))
        if cost < best_cost:
            best, best_cost = shifted, cost
    return best


def solve_top_down(
    position: np.ndarray,
    yaw: float,
    tool_length: float,
    current: np.ndarray,
    limits: ArmLimits | None = None,
    symmetric: bool = True,
) -> np.ndarray:
    """Joints putting the TCP at `position`, tool down, closing axis at `yaw`.

    A parallel gripper is symmetric under a half turn, so with `symmetric` the yaw + pi variant is
    also considered and the one needing the least wrist motion wins. Raises UnreachableError.
    """
    limits = limits or ArmLimits()
    candidates = []
    for y in (yaw, yaw + np.pi) if symmetric else (yaw,):
        q = nearest_solution(inverse(top_down_pose(position, y, tool_length)), current, limits)
        if q is not None:
            candidates.append(q)
    if not candidates:
        x, y_, z = np.asarray(position, dtype=float)
        raise UnreachableError(f"no IK solution for TCP ({x:.3f}, {y_:.3f}, {z:.3f}) yaw {np.rad2deg(yaw):.0f} deg")
    return min(candidates, key=lambda q: float(np.sum(np.abs(q - current))))
