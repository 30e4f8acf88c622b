"""`sortbot datasets info`: what a collected dataset holds, read through lerobot (no video decoding)."""

from __future__ import annotations

from collections import Counter
from pathlib import Path

import numpy as np

from sortbot.datasets.features import ACTION_KEY, LABELS_KEY, label_rows
from sortbot.datasets.lerobot_store import (is_dataset, read_collection, read_episode_records, staged_episodes,
                                            staging_dir, total_episodes)
from sortbot.types import CLASS_NAMES, Primitive


def resolve_root(path: Path) -> Path:
    """Accept either a collect folder (holding lerobot/) or the LeRobot dataset folder itself."""
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"{path} does not exist: give a folder written by `sortbot collect`")
    root = path / "lerobot" if is_dataset(path / "lerobot") else path
    if is_dataset(root) and total_episodes(root) == 0:  # lerobot would try to download an empty one
        staged = len(staged_episodes(root))
        raise ValueError(f"{root} holds no episodes yet" + (
            f"; {staged} finished episodes wait in {staging_dir(root)}: `sortbot collect ... --resume` folds them in"
            if staged else ": collect some with `sortbot collect`"))
    return root


def load_table(root: Path) -> dict[str, np.ndarray]:
    """The non-video columns of every frame, as numpy arrays (lerobot's own parquet reader)."""
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    collection = read_collection(root)
    ds = LeRobotDataset(collection["repo_id"], root=root)
    table = ds.hf_dataset.with_format("numpy")
    return {key: np.asarray(table[key]) for key in table.column_names}


def dataset_summary(path: Path) -> dict:
    root = resolve_root(path)
    collection = read_collection(root)
    table = load_table(root)
    episodes = read_episode_records(root)
    actions = table[ACTION_KEY]
    grasp = actions[:, 0] == int(Primitive.GRASP)
    push = ~grasp

    def count(key: str, mask=None) -> int:
        values = table[key].reshape(-1).astype(bool)
        return int(values[mask].sum() if mask is not None else values.sum())

    labels = label_rows(table[LABELS_KEY])
    present = labels[..., 0] > 0.5
    frame_classes = Counter(CLASS_NAMES[int(c)] for c in labels[..., 1][present])
    scene_classes = Counter(o["cls"] for ep in episodes for o in ep.get("scene", {}).get("objects", []))
    size = sum(f.stat().st_size for f in root.rglob("*") if f.is_file())
    return {
        "root": str(root),
        "repo_id": collection["repo_id"],
        "policy": collection.get("policy"),
        "object_set": collection.get("object_set"),
        "objects_per_scene": collection.get("objects"),
        "episodes": int(len(np.unique(table["episode_index"]))),
        "frames": int(len(actions)),
        "outcomes": {
            "grasps": int(grasp.sum()),
            "grasp_success": count("outcome.grasp_success", grasp),
            "well_placed": count("outcome.well_placed", grasp),
            "pushes": int(push.sum()),
            "push_moved": count("outcome.push_moved", push),
            "change_detected": count("outcome.change_detected", push),
            "unreachable": int((~table["outcome.executed"].reshape(-1).astype(bool)).sum()),
            "reward": float(table["next.reward"].sum()),
        },
        "end_reasons": dict(Counter(str(ep.get("end_reason")) for ep in episodes)),
        "sorted_correctly": sum(int(ep.get("sorted_correctly", 0)) for ep in episodes),
        "objects": sum(int(ep.get("objects", 0)) for ep in episodes),
        "class_balance_scenes": dict(sorted(scene_classes.items())),
        "class_balance_labels": dict(sorted(frame_classes.items())),
        "size_bytes": size,
        # committed by a run that was killed before folding them in; `collect --resume` folds them
        "staged_episodes": len(staged_episodes(root)),
        "staging_dir": str(staging_dir(root)),
        "bytes_per_frame": size / max(len(actions), 1),
    }
