"""Shared fixtures. Importing sortbot.sim first selects the headless GL backend before mujoco loads."""

import socket
from collections import Counter

import numpy as np
import pytest
import yaml
from PIL import Image

import sortbot.sim  # noqa: F401  (GL backend selection)
from sortbot.config import EnvConfig
from sortbot.perception.yolo_offline import setup_offline
from sortbot.sim.env import SortingEnv
from sortbot.sim.objects import ObjectSpec
from sortbot.sim.scene_file import SceneSpec
from sortbot.types import CLASS_NAMES, class_index


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


# Detector training: a tiny YOLO set from SortingEnv drops, tiny settings, an unreachable network.
TRAIN_SEEDS, VAL_SEEDS = range(0, 6), range(100, 102)
TINY = dict(epochs=1, imgsz=64, batch=4, device="cpu", workers=0, cache=False, plots=False)


@pytest.fixture(scope="session")
def yolo_set(tmp_path_factory):
    """A YOLO detection set written straight from SortingEnv observations (3-object drops); held-out
    seeds for val. `path` is left out so the yaml's own folder must be used."""
    setup_offline(tmp_path_factory.getbasetemp() / "ultralytics")
    root = tmp_path_factory.mktemp("yolo_set")
    cfg = EnvConfig()
    cfg.scene.num_objects, cfg.scene.settle_time = 3, 0.5
    val_counts = Counter()
    with SortingEnv(cfg) as env:
        for split, seeds in (("train", TRAIN_SEEDS), ("val", VAL_SEEDS)):
            (root / "images" / split).mkdir(parents=True)
            (root / "labels" / split).mkdir(parents=True)
            for seed in seeds:
                obs = env.reset(seed=seed)
                h, w = obs.depth.shape
                Image.fromarray(obs.rgb).save(root / "images" / split / f"{seed}.png")
                rows = [f"{class_index(l.cls)} {(l.box[0] + l.box[2]) / 2 / w} {(l.box[1] + l.box[3]) / 2 / h} "
                        f"{(l.box[2] - l.box[0]) / w} {(l.box[3] - l.box[1]) / h}" for l in obs.labels]
                (root / "labels" / split / f"{seed}.txt").write_text("\n".join(rows) + "\n")
                if split == "val":
                    val_counts.update(l.cls for l in obs.labels)
            last_obs = obs
    (root / "data.yaml").write_text(yaml.safe_dump(
        {"train": "images/train", "val": "images/val", "names": dict(enumerate(CLASS_NAMES))}))
    return root / "data.yaml", val_counts, last_obs


@pytest.fixture
def no_network(monkeypatch):
    """Any attempt to reach the internet is recorded and refused."""
    attempts = []

    def refuse_connect(self, address, *args):
        if self.family in (socket.AF_INET, socket.AF_INET6):
            attempts.append(address)
            raise OSError("network disabled in this test")
        return real_connect(self, address, *args)

    def refuse_lookup(host, *args, **kwargs):
        attempts.append(host)
        raise socket.gaierror("network disabled in this test")

    real_connect = socket.socket.connect
    monkeypatch.setattr(socket.socket, "connect", refuse_connect)
    monkeypatch.setattr(socket, "getaddrinfo", refuse_lookup)
    return attempts
