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


# -- a small collected dataset, shared by the collect / datasets / eval tests ----------------------
COLLECT_SEED = 7


def small_env_config() -> EnvConfig:
    """3 cutlery, a 4-decision budget and a half-size camera (same field of view): fast to collect."""
    cfg = EnvConfig()
    cfg.outcome.max_steps = 4
    cfg.camera.width, cfg.camera.height, cfg.camera.focal_length = 320, 240, 618.62 / 2
    return cfg


def small_request(out, **kw):
    from sortbot.collect.runner import CollectRequest

    args = dict(out=out, episodes=2, objects=3, seed=COLLECT_SEED, env_config=small_env_config())
    args.update(kw)
    return CollectRequest(**args)


@pytest.fixture(scope="session")
def collected(tmp_path_factory):
    """(out folder, CollectResult) of 2 small oracle episodes, collected once per test session."""
    from sortbot.collect.runner import collect

    out = tmp_path_factory.mktemp("collect") / "run"
    return out, collect(small_request(out))
