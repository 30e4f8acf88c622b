"""`sortbot datasets export-yolo`: the dataset's RGB frames and exact labels as an ultralytics
YOLO detection set (images, txt labels, data.yaml), split by episode so that no scene is seen
in both training and validation."""

from __future__ import annotations

import json
import math
import shutil
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sortbot.datasets.features import LABELS_KEY, RGB_KEY, label_rows
from sortbot.datasets.lerobot_store import read_collection
from sortbot.datasets.summary import resolve_root
from sortbot.types import CLASS_NAMES


@dataclass
class YoloExportConfig:
    val_fraction: float = 0.2  # of episodes (the last ones) held out for validation
    min_box_side: int = 4  # px: slivers of almost hidden objects are not useful boxes
    jpeg_quality: int = 95


def split_episodes(episodes: list[int], val_fraction: float) -> tuple[list[int], list[int]]:
    """Train/val by episode: the last ceil(fraction * n) episodes (at least one) validate;
    a fraction of 1 puts every episode in val."""
    episodes = sorted(episodes)
    if val_fraction >= 1.0:  # everything held out: a dataset kept for evaluation only
        return [], episodes
    if len(episodes) < 2:
        raise ValueError(f"need at least 2 episodes to split by episode, the dataset has {len(episodes)}")
    n_val = min(max(1, math.ceil(val_fraction * len(episodes))), len(episodes) - 1)
    return episodes[:-n_val], episodes[-n_val:]


def yolo_lines(labels: np.ndarray, width: int, height: int, min_box_side: int) -> list[str]:
    """`cls cx cy w h` (normalised) for each present label row."""
    lines = []
    for row in label_rows(labels):
        if row[0] < 0.5:
            continue
        x1, y1, x2, y2 = (float(v) for v in row[2:6])
        if x2 - x1 < min_box_side or y2 - y1 < min_box_side:
            continue
        cx, cy = (x1 + x2) / 2 / width, (y1 + y2) / 2 / height
        lines.append(f"{int(round(row[1]))} {cx:.6f} {cy:.6f} {(x2 - x1) / width:.6f} {(y2 - y1) / height:.6f}")
    return lines


def export_yolo(path: Path, out: Path, config: YoloExportConfig | None = None, overwrite: bool = False,
                progress=None) -> Path:
    """Write `out`/images/{train,val}, `out`/labels/{train,val}, `out`/data.yaml; returns data.yaml."""
    import yaml
    from lerobot.datasets.lerobot_dataset import LeRobotDataset
    from PIL import Image

    config = config or YoloExportConfig()
    root = resolve_root(path)
    collection = read_collection(root)
    out = Path(out)
    if out.exists() and any(out.iterdir()):
        if not overwrite:
            raise FileExistsError(f"{out} is not empty: choose another --out or pass --overwrite")
        shutil.rmtree(out)
    ds = LeRobotDataset(collection["repo_id"], root=root)
    episode_index = np.asarray(ds.hf_dataset.with_format("numpy")["episode_index"])
    train, val = split_episodes(sorted(set(int(e) for e in episode_index)), config.val_fraction)
    split_of = {**{e: "train" for e in train}, **{e: "val" for e in val}}
    for split in ("train", "val"):
        (out / "images" / split).mkdir(parents=True, exist_ok=True)
        (out / "labels" / split).mkdir(parents=True, exist_ok=True)
    for i in range(len(ds)):
        item = ds[i]
        ep, frame = int(item["episode_index"]), int(item["frame_index"])
        rgb = (item[RGB_KEY].permute(1, 2, 0).numpy() * 255).round().clip(0, 255).astype(np.uint8)
        h, w = rgb.shape[:2]
        name = f"ep{ep:06d}_f{frame:04d}"
        split = split_of[ep]
        Image.fromarray(rgb).save(out / "images" / split / f"{name}.jpg", quality=config.jpeg_quality)
        lines = yolo_lines(item[LABELS_KEY].numpy(), w, h, config.min_box_side)
        (out / "labels" / split / f"{name}.txt").write_text("".join(line + "\n" for line in lines))
        if progress:
            progress(i + 1, len(ds))
    data_yaml = out / "data.yaml"
    data_yaml.write_text(yaml.safe_dump({
        "path": str(out.resolve()), "train": "images/train", "val": "images/val",
        "names": dict(enumerate(CLASS_NAMES)),
    }, sort_keys=False))
    (out / "split.json").write_text(json.dumps({"source": str(root), "train_episodes": train, "val_episodes": val}))
    return data_yaml
