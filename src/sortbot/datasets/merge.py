"""`sortbot datasets merge A B --out C`: lerobot's own aggregation, plus sortbot's metadata and the
MCAP logs carried over with their episodes renumbered in the merged order."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

from sortbot.datasets.lerobot_store import COLLECTION_FILE, EPISODES_FILE, read_collection, read_episode_records
from sortbot.datasets.summary import resolve_root

SHARED_KEYS = ("policy", "object_set", "objects", "env_config", "dataset_config")
MIXED = "mixed"  # a setting the merged sources disagree on


def agreed(values: list):
    """What a list of settings agree on: the value when all are equal; for mappings, key by key
    (so sources collected with different step budgets still share their workspace and camera);
    otherwise MIXED."""
    first = values[0]
    if all(v == first for v in values):
        return first
    if all(isinstance(v, dict) for v in values) and all(v.keys() == first.keys() for v in values):
        return {k: agreed([v[k] for v in values]) for k in first}
    return MIXED


def merge_datasets(sources: list[Path], out: Path, overwrite: bool = False, repo_id: str | None = None) -> Path:
    """Merge collected datasets (collect folders or LeRobot roots) into `out`/lerobot (+ `out`/mcap).
    Returns the merged LeRobot root."""
    from lerobot.datasets.aggregate import aggregate_datasets

    if len(sources) < 2:
        raise ValueError("merge needs at least two datasets")
    roots = [resolve_root(s) for s in sources]
    collections = [read_collection(r) for r in roots]
    out = Path(out)
    target = out / "lerobot"
    if out.exists() and any(out.iterdir()):
        if not overwrite:
            raise FileExistsError(f"{out} is not empty: choose another --out or pass --overwrite")
        if any(out.resolve() in (r.resolve(), *r.resolve().parents) for r in roots):
            raise ValueError(f"--out {out} holds one of the sources: choose another folder")
        shutil.rmtree(out)
    aggregate_datasets(
        repo_ids=[f"local/merge_source_{k}" for k in range(len(roots))],
        aggr_repo_id=repo_id or collections[0]["repo_id"], roots=roots, aggr_root=target,
        concatenate_videos=False,  # lerobot's remux of clips into one file fails on some (non-monotonic dts)
    )
    merged = {k: agreed([c.get(k) for c in collections]) for k in SHARED_KEYS}
    merged.update(repo_id=repo_id or collections[0]["repo_id"], seed=[c.get("seed") for c in collections],
                  versions=collections[0].get("versions"), merged_from=[str(r) for r in roots])
    (target / COLLECTION_FILE).write_text(json.dumps(merged, indent=1, default=str))
    lines, index = [], 0
    for root in roots:
        for record in read_episode_records(root):
            mcap = root.parent / "mcap" / str(record.get("mcap", ""))
            record = {**record, "episode_index": index, "source": str(root), "source_episode": record["episode_index"]}
            if record.get("mcap") and mcap.is_file():
                record["mcap"] = f"episode_{index:06d}.mcap"
                (out / "mcap").mkdir(parents=True, exist_ok=True)
                shutil.copy2(mcap, out / "mcap" / record["mcap"])
            lines.append(json.dumps(record, default=str) + "\n")
            index += 1
    (target / EPISODES_FILE).write_text("".join(lines))
    return target
