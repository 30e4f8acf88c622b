"""Nothing lost: a killed collection keeps its finished episodes and --resume carries on."""

import json
import os
import signal
import subprocess
import sys
import time

import pytest

from sortbot.datasets.lerobot_store import BACKUP_DIR, EPISODES_FILE, EpisodeStore

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
    episodes_file = out / "lerobot" / EPISODES_FILE
    deadline = time.time() + 240
    while time.time() < deadline and proc.poll() is None:
        if episodes_file.is_file() and episodes_file.read_text().count("\n") >= 1:
            break
        time.sleep(0.1)
    assert proc.poll() is None, "collection ended before it could be killed"
    time.sleep(1.0)  # into the next episode
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()

    finished = _load(out / "lerobot").meta.total_episodes  # loads before any repair
    assert finished >= 1
    again = _sortbot("collect", "--episodes", "3", "--out", str(out), *ARGS)
    assert again.returncode == 2 and "--resume" in again.stderr  # never overwritten silently
    resumed = _sortbot("collect", "--episodes", "3", "--out", str(out), "--resume", *ARGS)
    assert resumed.returncode == 0, resumed.stderr
    ds = _load(out / "lerobot")
    assert ds.meta.total_episodes == 3
    assert sorted(set(int(e) for e in ds.hf_dataset.with_format("numpy")["episode_index"])) == [0, 1, 2]
    lines = [json.loads(x) for x in episodes_file.read_text().splitlines()]
    assert [r["episode_index"] for r in lines] == [0, 1, 2]
    assert sorted(p.name for p in (out / "mcap").glob("*.mcap")) == [f"episode_00000{k}.mcap" for k in range(3)]
    clash = _sortbot("collect", "--episodes", "3", "--out", str(out), "--resume", "--objects", "6", "--seed", "3")
    assert clash.returncode == 2 and "different settings" in clash.stderr


def test_crash_inside_a_commit_is_rolled_back(collected, tmp_path, monkeypatch):
    """A process dying between lerobot's save_episode and our commit point leaves a backup of
    meta/; reopening restores it and drops the half-written episode's files."""
    import shutil

    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    src, _ = collected
    root = tmp_path / "lerobot"
    shutil.copytree(src / "lerobot", root)
    frames_before = len(_load(root))
    store = EpisodeStore.open(root)
    frame = {k: v for k, v in _load(root).hf_dataset.with_format("numpy")[0].items()}
    assert frame is not None

    class Died(Exception):
        pass

    def die(self):
        raise Died

    monkeypatch.setattr(LeRobotDataset, "finalize", die)
    from conftest import small_env_config  # noqa: F401  (same camera size as the collected set)
    from sortbot.collect.episode import EpisodeCollector
    from sortbot.config import DatasetConfig

    cfg = small_env_config()
    cfg.scene.num_objects = 3
    collector = EpisodeCollector(cfg, "oracle", DatasetConfig(), tmp_path / "mcap", 7, {})
    record = collector.collect(5)
    collector.close()
    with pytest.raises(Died):
        store.append(record.frames, record.task, record.meta)
    monkeypatch.undo()
    assert (root / BACKUP_DIR).is_dir()
    reopened = EpisodeStore.open(root)
    assert not (root / BACKUP_DIR).exists()
    assert reopened.committed_episodes == 2
    assert len(_load(root)) == frames_before
    assert len(list((root / "data").rglob("*.parquet"))) == 2  # the half-written episode's data is gone


def test_commits_leave_no_hf_cache_behind(tmp_path, monkeypatch):
    """lerobot's resume() writes an arrow cache of all episode metadata per call; per-episode
    commits must not pile those up in ~/.cache/huggingface."""
    import datasets
    from conftest import small_request

    from sortbot.collect.runner import collect

    monkeypatch.setattr(datasets.config, "HF_DATASETS_CACHE", tmp_path / "hf_cache")
    collect(small_request(tmp_path / "run", episodes=3))
    assert not list((tmp_path / "hf_cache").rglob("*.arrow"))
