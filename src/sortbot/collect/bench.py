"""`sortbot bench collect`: frames/s written (LeRobot + MCAP), bytes per frame, and the speed-up of
2 workers over 1 measured side by side in one run; `--soak` runs N actions and samples memory."""

from __future__ import annotations

import os
import tempfile
import time
from pathlib import Path

from sortbot.collect.runner import LEROBOT_DIR, MCAP_DIR, CollectRequest, collect


def _folder_bytes(path: Path) -> int:
    return sum(f.stat().st_size for f in Path(path).rglob("*") if f.is_file())


def _rss_mb() -> dict:
    """Resident memory of this process and of its worker processes (MB)."""
    import psutil

    me = psutil.Process(os.getpid())
    children = me.children(recursive=True)
    return {"main_mb": me.memory_info().rss / 2**20,
            "workers_mb": sum(c.memory_info().rss for c in children if c.is_running()) / 2**20}


def bench_collect(episodes: int = 2, objects: int = 6, seed: int = 0, policy: str = "oracle",
                  worker_counts: tuple[int, ...] = (1, 2), progress=None) -> dict:
    """Collect the same `episodes` with each worker count; report rates and their ratio."""
    result: dict = {"episodes": episodes, "objects": objects, "policy": policy, "cpu_count": os.cpu_count()}
    with tempfile.TemporaryDirectory(prefix="sortbot-bench-") as tmp:
        for workers in worker_counts:
            out = Path(tmp) / f"workers{workers}"
            res = collect(CollectRequest(out=out, episodes=episodes, objects=objects, seed=seed, policy=policy,
                                         workers=workers), progress=progress)
            lerobot_b, mcap_b = _folder_bytes(out / LEROBOT_DIR), _folder_bytes(out / MCAP_DIR)
            result[f"workers{workers}"] = {
                "frames": res.frames, "wall_s": res.wall_s, "frames_per_s": res.frames / res.wall_s,
                "lerobot_bytes_per_frame": lerobot_b / res.frames, "mcap_bytes_per_frame": mcap_b / res.frames,
                "lerobot_write_s_per_frame": res.write_s / res.frames,
            }
    if len(worker_counts) >= 2:
        a, b = worker_counts[0], worker_counts[1]
        result[f"speedup_{b}_over_{a}_workers"] = result[f"workers{b}"]["frames_per_s"] / result[f"workers{a}"]["frames_per_s"]
    return result


def soak(actions: int = 10_000, objects: int = 6, seed: int = 0, policy: str = "oracle", workers: int = 1,
         out: Path | None = None, sample_every_s: float = 30.0, progress=None, on_sample=None) -> dict:
    """Collect until `actions` frames are written, sampling RSS; memory should stay flat."""
    samples: list[dict] = []
    t0 = time.perf_counter()
    last = [-1e9]

    def on_episode(done: int, total: int, info: dict) -> None:
        now = time.perf_counter()
        if now - last[0] >= sample_every_s:
            samples.append({"t_s": now - t0, "frames": info["frames"], **_rss_mb()})
            last[0] = now
            if on_sample:
                on_sample(samples[-1])
        if progress:
            progress(info["frames"], actions, info)

    with tempfile.TemporaryDirectory(prefix="sortbot-soak-") as tmp:
        target = Path(out) if out else Path(tmp) / "soak"
        samples.append({"t_s": 0.0, "frames": 0, **_rss_mb()})
        res = collect(CollectRequest(out=target, episodes=10**9, objects=objects, seed=seed, policy=policy,
                                     workers=workers, max_frames=actions, overwrite=True), progress=on_episode)
        samples.append({"t_s": time.perf_counter() - t0, "frames": res.frames, **_rss_mb()})
        size = _folder_bytes(target)
    warm = samples[min(2, len(samples) - 1)]  # after the first episodes: imports, GL, encoders loaded
    return {
        "actions": res.frames, "episodes": res.episodes, "wall_s": res.wall_s, "frames_per_s": res.frames / res.wall_s,
        "workers": workers, "policy": policy, "bytes_per_frame": size / max(res.frames, 1),
        "rss_start_mb": samples[0]["main_mb"], "rss_warm_mb": warm["main_mb"], "rss_end_mb": samples[-1]["main_mb"],
        "worker_rss_warm_mb": warm["workers_mb"], "worker_rss_end_mb": samples[-1]["workers_mb"],
        "samples": samples,
    }
