"""Shared fixtures. Importing sortbot.sim first selects the headless GL backend before mujoco loads."""

import numpy as np
import pytest

import sortbot.sim  # noqa: F401  (GL backend selection)
from sortbot.config import EnvConfig
from sortbot.sim.env import SortingEnv
from sortbot.sim.objects import ObjectSpec
from sortbot.sim.scene_file import SceneSpec


def yaw_quat(yaw: float):
    return (float(np.cos(yaw / 2)), 0.0, 0.0, float(np.sin(yaw / 2)))


def single_object_scene(spec: ObjectSpec, x: float, y: float, yaw: float) -> SceneSpec:
    spec.position = (x, y, 0.001)
    spec.quaternion = yaw_quat(yaw)
    return SceneSpec(objects=[spec], settle_time=0.3)


@pytest.fixture
def env():
    e = SortingEnv(EnvConfig())
    yield e
    e.close()
