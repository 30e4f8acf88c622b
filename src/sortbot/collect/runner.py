"""`sortbot collect`: run a policy over seeded episodes and write DIR/lerobot and DIR/mcap.

Episodes are committed to the LeRobot dataset one by one in index order, so a killed run keeps
every finished episode and `resume=True` continues after the last one. An existing dataset is
only replaced with `overwrite=True`.
"""

from __future__ import annotations

import json
import shutil
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path

from sortbot.collect.engines import ENGINES, CollectorSpec, run_local, run_ray
from sortbot.config import DatasetConfig, EnvConfig
from sortbot.datasets.lerobot_store import DEFAULT_REPO_ID, EpisodeStore, is_dataset, read_collection
from sortbot.policies import POLICIES

LEROBOT_DIR, MCAP_DIR = "lerobot", "mcap"
# what must match for --resume to continue a dataset
RESUME_KEYS = ("policy", "object_set", "objects", "seed")


@dataclass
class CollectRequest:
    out: Path
    episodes: int
    policy: str = "oracle"
    object_set: str = "cutlery"
    objects: int = 6
    seed: int = 0
    workers: int = 1
    engine: str = "local"
    ray_address: str | None = None
    resume: bool = False
    overwrite: bool = False
    repo_id: str = DEFAULT_REPO_ID
    max_frames: int | None = None  # stop after the episode that reaches this many frames (soak runs)
    env_config: EnvConfig | None = None
    dataset_config: DatasetConfig = field(default_factory=DatasetConfig)

    def resolved_env_config(self) -> EnvConfig:
        cfg = self.env_config or EnvConfig()
        cfg.scene.object_set = self.object_set
        cfg.scene.num_objects = self.objects
        return cfg


@dataclass
class CollectResult:
    out: Path
    first_episode: int  # first index collected by this run (> 0 after --resume)
    episodes: int  # total committed episodes in the dataset
    frames: int  # frames written by this run
    wall_s: float
    sorted_correctly: int = 0
    objects: int = 0
    collect_s: float = 0.0  # summed per-episode sim+policy+MCAP time (over all workers)
    write_s: float = 0.0  # LeRobot writing time in the main process


def _validate(req: CollectRequest) -> None:
    if req.policy not in POLICIES:
        raise ValueError(f"unknown policy {req.policy!r}: use one of {', '.join(POLICIES)}")
    if req.engine not in ENGINES:
        raise ValueError(f"unknown engine {req.engine!r}: use one of {', '.join(ENGINES)}")
    if req.episodes < 1 or req.workers < 1 or req.objects < 1:
        raise ValueError("--episodes, --workers and --objects must be at least 1")
    if req.resume and req.overwrite:
        raise ValueError("--resume and --overwrite contradict each other: pick one")
    if req.objects > req.dataset_config.max_objects:
        raise ValueError(f"--objects {req.objects} exceeds the dataset's max_objects={req.dataset_config.max_objects}")


def _prepare(req: CollectRequest) -> EpisodeStore | None:
    """Check what is already in `out`; return the store to continue (resume) or None (fresh)."""
    root, mcap = req.out / LEROBOT_DIR, req.out / MCAP_DIR
    existing = is_dataset(root) or (mcap.is_dir() and any(mcap.glob("*.mcap")))
    if req.resume:
        if not is_dataset(root):
            if existing:
                raise ValueError(f"{req.out} has MCAP logs but no dataset to resume: use --overwrite to start again")
            return None  # nothing committed yet: a fresh start is the resume
        done = read_collection(root)
        clash = [f"{k}={done.get(k)!r} (asked {getattr(req, k)!r})" for k in RESUME_KEYS if done.get(k) != getattr(req, k)]
        env_now = json.loads(json.dumps(asdict(req.resolved_env_config()), default=str))
        if done.get("env_config") != env_now:
            clash.append("the env config (e.g. --max-steps)")
        if clash:
            raise ValueError(f"--resume with different settings than {root}: {', '.join(clash)}")
        return EpisodeStore.open(root)
    if existing or (root.exists() and any(root.iterdir())):
        if not req.overwrite:
            raise FileExistsError(f"{req.out} already holds collected data: pass --resume to continue it or --overwrite to replace it")
        shutil.rmtree(root, ignore_errors=True)
        shutil.rmtree(mcap, ignore_errors=True)
    return None


def collect(req: CollectRequest, progress: Callable[[int, int, dict], None] | None = None) -> CollectResult:
    """Collect `req.episodes` episodes in total into `req.out` (see module docstring).
    `progress(done, total, info)` is called after each committed episode."""
    _validate(req)
    t0 = time.perf_counter()
    store = _prepare(req)
    start = store.committed_episodes if store else 0
    env_cfg = req.resolved_env_config()
    versions = _versions()
    collection = {"policy": req.policy, "object_set": req.object_set, "objects": req.objects, "seed": req.seed,
                  "env_config": asdict(env_cfg), "versions": versions}
    spec = CollectorSpec(env_config=env_cfg, policy=req.policy, dataset_config=req.dataset_config,
                         mcap_dir=str(req.out / MCAP_DIR), base_seed=req.seed,
                         run_metadata={"policy": req.policy, "object_set": req.object_set, "objects": req.objects,
                                       "base_seed": req.seed, "versions": versions, "env_config": collection["env_config"]})
    indices = range(start, req.episodes)
    if req.engine == "ray":
        records = run_ray(spec, indices, req.workers, req.ray_address)
    else:
        records = run_local(spec, indices, req.workers)
    result = CollectResult(out=req.out, first_episode=start, episodes=start, frames=0, wall_s=0.0)
    try:
        for record in records:
            if store is None:
                store = EpisodeStore.create(req.out / LEROBOT_DIR, req.dataset_config, collection, record.camera, req.repo_id)
            t_write = time.perf_counter()
            store.append(record.frames, record.task, record.meta)
            result.write_s += time.perf_counter() - t_write
            result.collect_s += record.timings.get("collect_s", 0.0)
            result.episodes += 1
            result.frames += len(record.frames)
            result.sorted_correctly += record.meta["sorted_correctly"]
            result.objects += record.meta["objects"]
            if progress:
                progress(result.episodes, req.episodes, {"frames": result.frames, "end": record.meta["end_reason"]})
            if req.max_frames is not None and result.frames >= req.max_frames:
                break
    finally:
        if hasattr(records, "close"):
            records.close()
        if store is not None:
            store.close()
    result.wall_s = time.perf_counter() - t0
    return result


def _versions() -> dict:
    from importlib.metadata import PackageNotFoundError, version

    out = {}
    for name in ("sortbot", "mujoco", "lerobot", "foxglove-sdk", "numpy"):
        try:
            out[name] = version(name)
        except PackageNotFoundError:
            out[name] = "unknown"
    return out
