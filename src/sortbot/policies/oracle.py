"""The scripted oracle: reads true poses, grasps across the handle where both fingers land free,
pushes apart objects that are too close, and places by true class.

It never touches MuJoCo: it sees the env's privileged object list (`ObjectState`-like records with
instance_id, cls, spec, position, long_axis_yaw, grasp_point, status).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from sortbot.config import GripperConfig, WorkspaceConfig
from sortbot.types import Action, Observation, Primitive


@dataclass
class OracleConfig:
    clearance: float = 0.004  # m kept between a finger and any other object
    handle_offsets: tuple[float, ...] = (0.0, -0.25, 0.25, -0.4)  # along the handle, in handle lengths
    push_back_off: float = 0.035  # m behind the object where a push starts
    stack_height: float = 0.004  # m: an object this much higher over the grasp point is on top
    max_grasp_tries: int = 3  # failed grasps on one object before pushing it instead


def _footprint(state) -> tuple[np.ndarray, float, float, float]:
    """Centre (xy), yaw, half length, half width of an object's outline on the table."""
    p = state.spec.params
    if "length" in p:
        half_w = max(p["handle_width"], p["head_width"]) / 2
        return state.position[:2], state.long_axis_yaw, p["length"] / 2, half_w
    size = p.get("size", 0.03)
    half_l = size if state.spec.shape == "bar" else size / 2
    return state.position[:2], state.long_axis_yaw, half_l, size / 2


def _inside(points: np.ndarray, centre: np.ndarray, yaw: float, half_l: float, half_w: float, margin: float) -> np.ndarray:
    c, s = np.cos(yaw), np.sin(yaw)
    d = points - centre
    lx = c * d[:, 0] + s * d[:, 1]
    ly = -s * d[:, 0] + c * d[:, 1]
    return (np.abs(lx) <= half_l + margin) & (np.abs(ly) <= half_w + margin)


class OraclePolicy:
    name = "oracle"

    def __init__(self, gripper: GripperConfig | None = None, workspace: WorkspaceConfig | None = None,
                 config: OracleConfig | None = None):
        self.gripper = gripper or GripperConfig()
        self.workspace = workspace or WorkspaceConfig()
        self.config = config or OracleConfig()
        self.rng = np.random.default_rng(0)
        self._failures: dict[int, int] = {}
        self._last: tuple[int, Primitive, np.ndarray] | None = None

    def reset(self, seed: int | None = None) -> None:
        self.rng = np.random.default_rng(seed)
        self._failures = {}
        self._last = None

    def _learn_from_last(self, state: Sequence) -> None:
        """Count a failure when the last target is still where it was (grasp) or did not move
        (push), so the next attempt tries another grasp point or push."""
        if self._last is None:
            return
        target_id, primitive, position = self._last
        now = {s.instance_id: s for s in state}.get(target_id)
        if now is None or not now.remaining:
            return
        moved = float(np.linalg.norm(now.position[:2] - position[:2])) > 0.01
        if primitive == Primitive.GRASP or not moved:
            self._failures[target_id] = self._failures.get(target_id, 0) + 1

    # ---------------------------------------------------------------- geometry
    def _finger_points(self, point: np.ndarray, yaw: float) -> np.ndarray:
        """Sample points covering both finger footprints and the gap they close over: another
        object anywhere there would be squeezed too (a double grasp) or block a finger."""
        g = self.gripper
        axis = np.array([np.cos(yaw), np.sin(yaw)])
        across = np.array([-axis[1], axis[0]])
        reach = g.grasp_opening / 2 + g.pad_thickness
        t = np.linspace(-reach, reach, 13)
        u = np.linspace(-g.finger_width / 2, g.finger_width / 2, 5)
        tt, uu = np.meshgrid(t, u)
        return point + tt.reshape(-1, 1) * axis + uu.reshape(-1, 1) * across

    def _blocked(self, target, point: np.ndarray, yaw: float, others: list) -> bool:
        pts = self._finger_points(point[:2], yaw)
        for o in others:
            centre, oyaw, hl, hw = _footprint(o)
            if np.any(_inside(pts, centre, oyaw, hl, hw, self.config.clearance)):
                return True
            # something lying over the grasp point itself
            if _inside(point[None, :2], centre, oyaw, hl, hw, 0.0)[0] and o.position[2] > target.position[2] + self.config.stack_height:
                return True
        return False

    def _covered(self, target, others: list) -> bool:
        """Another object rests on the target somewhere along it: lifting the target would carry
        it along, so the top one goes first."""
        centre, yaw, half_l, _ = _footprint(target)
        axis = np.array([np.cos(yaw), np.sin(yaw)])
        line = centre + np.linspace(-half_l, half_l, 15)[:, None] * axis
        for o in others:
            oc, oyaw, ohl, ohw = _footprint(o)
            if o.position[2] > target.position[2] + self.config.stack_height and np.any(_inside(line, oc, oyaw, ohl, ohw, 0.002)):
                return True
        return False

    def _grasp_candidates(self, target):
        yaw = target.long_axis_yaw + np.pi / 2
        handle_len = target.spec.params.get("handle_length", 0.0)
        axis = np.array([np.cos(target.long_axis_yaw), np.sin(target.long_axis_yaw), 0.0])
        for off in self.config.handle_offsets:
            yield target.grasp_point + off * handle_len * axis, yaw

    # ---------------------------------------------------------------- acting
    def act(self, obs: Observation, state: Sequence | None = None) -> Action:
        if state is None:
            raise ValueError("the oracle needs the env's privileged state: pass env.privileged_state()")
        self._learn_from_last(state)
        remaining = [s for s in state if s.status == "pick_area"] or [s for s in state if s.remaining]
        if not remaining:
            raise ValueError("no object left to act on")
        # nearest the robot first, as the paper's target selection
        remaining.sort(key=lambda s: float(np.linalg.norm(s.position[:2])))
        for target in remaining:
            others = [o for o in remaining if o.instance_id != target.instance_id]
            if self._covered(target, others):
                continue
            free = [c for c in self._grasp_candidates(target) if not self._blocked(target, c[0], c[1], others)]
            tries = self._failures.get(target.instance_id, 0)
            if tries < min(len(free), self.config.max_grasp_tries):
                point, yaw = free[tries]  # after a failure, the next free grasp point
                self._last = (target.instance_id, Primitive.GRASP, target.position.copy())
                return Action(Primitive.GRASP, (float(point[0]), float(point[1]), float(point[2])), float(yaw), place_bin=target.cls)
        return self._push_apart(remaining)

    def _push_apart(self, remaining: list) -> Action:
        """Push the object nearest the robot away from its closest neighbour, across its long axis.
        Repeated failures on it rotate the push by a quarter turn each time."""
        target = remaining[0]
        others = remaining[1:]
        if not others:
            others = [target]
        nearest = min(others, key=lambda o: float(np.linalg.norm(o.position[:2] - target.position[:2])))
        away = target.position[:2] - nearest.position[:2]
        across = np.array([-np.sin(target.long_axis_yaw), np.cos(target.long_axis_yaw)])
        direction = across if across @ away >= 0 else -across
        # steer the push back toward the pick area's centre if it would leave it
        centre = (np.array(self.workspace.pick_min) + np.array(self.workspace.pick_max)) / 2
        if direction @ (centre - target.position[:2]) < 0 and np.linalg.norm(centre - target.position[:2]) > 0.06:
            direction = -direction
        turns = self._failures.get(target.instance_id, 0) % 4
        c, s = np.cos(turns * np.pi / 2), np.sin(turns * np.pi / 2)
        direction = np.array([c * direction[0] - s * direction[1], s * direction[0] + c * direction[1]])
        start = target.grasp_point[:2] - self.config.push_back_off * direction
        angle = float(np.arctan2(direction[1], direction[0]))
        self._last = (target.instance_id, Primitive.PUSH, target.position.copy())
        return Action(Primitive.PUSH, (float(start[0]), float(start[1]), 0.0), angle)
