"""Nothing lost: a killed collection keeps its finished episodes and --resume carries on."""

import json
import os
import signal
import subprocess
import sys
import time

import pytest

from sortbot.datasets.lerobot_store import (EPISODES_FILE, STAGED_RECORD, EpisodeStore, read_episode_records,
                                            staged_episodes, staging_dir)

ARGS = ["--objects", "3", "--seed", "3", "--max-steps", "3"]


def _sortbot(*args, **kw):
    return subprocess.run([sys.executable, "-m", "sortbot.cli", *args], capture_output=True, text=True, **kw)


def _load(root):
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    return LeRobotDataset("local/sortbot", root=root)


def test_kill_mid_episode_then_resume(tmp_path):
    out = tmp_path / "run"
    proc = subprocess.Popen([sys.executable, "-m", "sortbot.cli", "collect", "--episodes", "3", "--out", str(out), *ARGS],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    first_commit = staging_dir(out / "lerobot") / "episode_000000" / STAGED_RECORD
    deadline = time.time() + 240
    while time.time() < deadline and proc.poll() is None and not first_commit.is_file():
        time.sleep(0.1)
    assert proc.poll() is None, "collection ended before it could be killed"
    time.sleep(1.0)  # into the next episode
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()

    finished = staged_episodes(out / "lerobot")  # every committed episode loads, before any repair
    assert len(finished) >= 1
    for folder in finished:
        assert _load(folder).meta.total_episodes == 1
    info = _sortbot("datasets", "info", str(out))  # none folded in yet: says how to get them
    assert info.returncode == 2 and "--resume" in info.stderr
    again = _sortbot("collect", "--episodes", "3", "--out", str(out), *ARGS)
    assert again.returncode == 2 and "--resume" in again.stderr  # never overwritten silently
    resumed = _sortbot("collect", "--episodes", "3", "--out", str(out), "--resume", *ARGS)
    assert resumed.returncode == 0, resumed.stderr
    ds = _load(out / "lerobot")
    assert ds.meta.total_episodes == 3
    assert sorted(set(int(e) for e in ds.hf_dataset.with_format("numpy")["episode_index"])) == [0, 1, 2]
    lines = [json.loads(x) for x in (out / "lerobot" / EPISODES_FILE).read_text().splitlines()]
    assert [r["episode_index"] for r in lines] == [0, 1, 2]
    assert not staging_dir(out / "lerobot").exists()
    assert sorted(p.name for p in (out / "mcap").glob("*.mcap")) == [f"episode_00000{k}.mcap" for k in range(3)]
    clash = _sortbot("collect", "--episodes", "3", "--out", str(out), "--resume", "--objects", "6", "--seed", "3")
    assert clash.returncode == 2 and "different settings" in clash.stderr


class Died(Exception):
    pass


def _die(*args, **kwargs):
    raise Died


@pytest.fixture(scope="module")
def third_episode(tmp_path_factory):
    """A third episode for the 2-episode `collected` dataset (same camera size)."""
    from conftest import small_env_config

    from sortbot.collect.episode import EpisodeCollector
    from sortbot.config import DatasetConfig

    cfg = small_env_config()
    cfg.scene.num_objects = 3
    collector = EpisodeCollector(cfg, "oracle", DatasetConfig(), tmp_path_factory.mktemp("mcap"), 7, {})
    try:
        return collector.collect(5)
    finally:
        collector.close()


def _copy_collected(collected, tmp_path):
    import shutil

    root = tmp_path / "lerobot"
    shutil.copytree(collected[0] / "lerobot", root)
    return root


def test_episode_killed_while_staged_is_dropped(collected, third_episode, tmp_path, monkeypatch):
    """Dying inside lerobot's writing leaves a staged folder without its commit record: reopening
    drops it and the dataset is as before."""
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    root = _copy_collected(collected, tmp_path)
    frames_before = len(_load(root))
    store = EpisodeStore.open(root)
    monkeypatch.setattr(LeRobotDataset, "finalize", _die)
    with pytest.raises(Died):
        store.append(third_episode.frames, third_episode.task, third_episode.meta)
    monkeypatch.undo()
    assert (staging_dir(root) / "episode_000002").is_dir() and not staged_episodes(root)
    reopened = EpisodeStore.open(root)
    assert not (staging_dir(root) / "episode_000002").exists()
    assert reopened.committed_episodes == 2
    assert len(_load(root)) == frames_before


@pytest.mark.parametrize("where", ["aggregate", "swap"])
def test_fold_killed_midway_keeps_every_episode(collected, third_episode, tmp_path, monkeypatch, where):
    """A fold dying inside lerobot's aggregation, or between the two renames of the swap, loses
    nothing: reopening undoes or finishes it and the dataset ends with all 3 episodes in order."""
    import lerobot.datasets.aggregate as aggregate
    from pathlib import Path

    root = _copy_collected(collected, tmp_path)
    store = EpisodeStore.open(root)
    assert store.append(third_episode.frames, third_episode.task, third_episode.meta) == 2
    assert len(staged_episodes(root)) == 1 and store.committed_episodes == 3
    if where == "aggregate":
        real = aggregate.aggregate_datasets

        def half_then_die(*args, **kwargs):
            real(*args, **kwargs)
            raise Died
        monkeypatch.setattr(aggregate, "aggregate_datasets", half_then_die)
    else:
        real_rename, calls = Path.rename, []

        def rename_once(self, target):
            calls.append(self)
            if len(calls) == 2:  # root -> .old done, .folding -> root not yet
                raise Died
            return real_rename(self, target)
        monkeypatch.setattr(Path, "rename", rename_once)
    with pytest.raises(Died):
        store.close()
    monkeypatch.undo()
    reopened = EpisodeStore.open(root)
    assert reopened.committed_episodes == 3
    reopened.close()
    ds = _load(root)
    assert ds.meta.total_episodes == 3 and not staging_dir(root).exists()
    assert [r["episode_index"] for r in read_episode_records(root)] == [0, 1, 2]
    assert sorted(set(int(e) for e in ds.hf_dataset.with_format("numpy")["episode_index"])) == [0, 1, 2]
    assert len(ds) == len(_load(collected[0] / "lerobot")) + len(third_episode.frames)


def test_commits_leave_no_hf_cache_behind(tmp_path, monkeypatch):
    """lerobot's resume() writes an arrow cache of all episode metadata per call; per-episode
    commits must not pile those up in ~/.cache/huggingface."""
    import datasets
    from conftest import small_request

    from sortbot.collect.runner import collect

    monkeypatch.setattr(datasets.config, "HF_DATASETS_CACHE", tmp_path / "hf_cache")
    collect(small_request(tmp_path / "run", episodes=3))
    assert not list((tmp_path / "hf_cache").rglob("*.arrow"))


def test_append_folds_every_k_episodes(collected, third_episode, tmp_path):
    """With fold_every=1 the committed episode is in the dataset itself right after append; a
    1-frame episode folds in too (lerobot's stats of a single frame keep the bool dtype)."""
    root = _copy_collected(collected, tmp_path)
    store = EpisodeStore.open(root)
    store.config.fold_every = 1
    assert store.append(third_episode.frames, third_episode.task, third_episode.meta) == 2
    assert not staged_episodes(root)
    assert store.append(third_episode.frames[:1], third_episode.task, third_episode.meta) == 3
    ds = _load(root)
    assert ds.meta.total_episodes == 4
    assert len(ds) == len(_load(collected[0] / "lerobot")) + len(third_episode.frames) + 1
    assert [r["episode_index"] for r in read_episode_records(root)] == [0, 1, 2, 3]
