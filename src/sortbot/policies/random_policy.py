"""Uniformly random push or grasp in the pick area, random angle, random bin: the floor any
learned policy must beat, and a source of failed actions for datasets."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from sortbot.config import WorkspaceConfig
from sortbot.types import Action, Observation, Primitive


@dataclass
class RandomPolicyConfig:
    grasp_probability: float = 0.5
    grasp_height: float = 0.0  # m above the table (the env lifts it to the fingertip clearance)


class RandomPolicy:
    name = "random"

    def __init__(self, workspace: WorkspaceConfig | None = None, config: RandomPolicyConfig | None = None):
        self.workspace = workspace or WorkspaceConfig()
        self.config = config or RandomPolicyConfig()
        self.rng = np.random.default_rng(0)

    def reset(self, seed: int | None = None) -> None:
        self.rng = np.random.default_rng(seed)

    def act(self, obs: Observation, state: Sequence | None = None) -> Action:
        ws, r = self.workspace, self.rng
        x = float(r.uniform(ws.pick_min[0], ws.pick_max[0]))
        y = float(r.uniform(ws.pick_min[1], ws.pick_max[1]))
        angle = float(r.uniform(-np.pi, np.pi))
        if r.random() < self.config.grasp_probability:
            bins = sorted(ws.bins)
            return Action(Primitive.GRASP, (x, y, ws.table_height + self.config.grasp_height), angle,
                          place_bin=bins[int(r.integers(len(bins)))])
        return Action(Primitive.PUSH, (x, y, ws.table_height), angle)
