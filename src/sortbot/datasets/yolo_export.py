"""`sortbot datasets export-yolo`: the dataset's RGB frames and exact labels as an ultralytics
YOLO detection set (images, txt labels, data.yaml), split by episode so that no scene is seen
in both training and validation.

By default the frames are cut to the pick area (`perception.yolo_data.pick_area_crop`, from the
dataset's recorded camera and workspace) and the labels clipped to it; the crop is recorded in
data.yaml and split.json so that training, the detector and evaluation cut the same way."""

from __future__ import annotations

import json
import math
import shutil
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from sortbot.config import WorkspaceConfig
from sortbot.datasets.features import LABELS_KEY, RGB_KEY, camera_from_info, label_rows
from sortbot.datasets.lerobot_store import read_collection
from sortbot.datasets.merge import MIXED
from sortbot.datasets.summary import resolve_root
from sortbot.perception.yolo_data import CropBox, CropConfig, label_path, pick_area_crop, read_data_yaml
from sortbot.sim.outcome import bin_of
from sortbot.types import CLASS_NAMES


@dataclass
class YoloExportConfig:
    val_fraction: float = 0.2  # of episodes (the last ones) held out for validation
    min_box_side: int = 4  # px: slivers of almost hidden objects are not useful boxes
    # with a crop: an object with less than this share of its box inside is not labelled. Mostly
    # sorted cutlery in a bin showing a 5-px strip at the crop's edge: nothing to pick, and nothing a
    # detector can tell (48 of 65 misses on 30 held-out episodes before this rule).
    min_inside_fraction: float = 0.25
    # cutlery lying in a bin is sorted: no target, so not labelled even where a corner of it shows
    # in the crop (19 of the 58 objects R416ft2 missed on 30 held-out episodes: spoons in their bin,
    # a few pixels of each at the crop's top corner). False: label what the camera sees.
    label_sorted: bool = False
    jpeg_quality: int = 95
    crop: CropConfig | None = field(default_factory=CropConfig)  # None: whole frames


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


def box_lines(boxes, width: int, height: int, min_box_side: float, crop: CropBox | None = None,
              min_inside_fraction: float = YoloExportConfig.min_inside_fraction) -> list[str]:
    """`cls cx cy w h` (normalised to the written image) for each (class id, (x1, y1, x2, y2)) in
    full-image pixels; with a crop, boxes are clipped to it and kept if `min_box_side` px and
    `min_inside_fraction` of their area remain."""
    if crop is not None:
        crop.check_image(width, height)
        width, height = crop.width, crop.height
    lines = []
    for cls, box in boxes:
        box = crop.box_to_crop(box, min_box_side, min_inside_fraction) if crop is not None else box
        if box is None:
            continue
        x1, y1, x2, y2 = (float(v) for v in box)
        if x2 - x1 < min_box_side or y2 - y1 < min_box_side:
            continue
        cx, cy = (x1 + x2) / 2 / width, (y1 + y2) / 2 / height
        lines.append(f"{int(cls)} {cx:.6f} {cy:.6f} {(x2 - x1) / width:.6f} {(y2 - y1) / height:.6f}")
    return lines


def yolo_lines(labels: np.ndarray, width: int, height: int, min_box_side: int, crop: CropBox | None = None,
               min_inside_fraction: float = YoloExportConfig.min_inside_fraction,
               bins: WorkspaceConfig | None = None) -> list[str]:
    """`cls cx cy w h` (normalised) for each present label row (boxes in full-image pixels); with
    `bins` (a workspace), not for objects whose centre lies in one of its bins."""
    rows = [row for row in label_rows(labels)
            if row[0] >= 0.5 and (bins is None or bin_of(row[6:9], bins) is None)]
    return box_lines([(int(round(row[1])), row[2:6]) for row in rows], width, height, min_box_side, crop,
                     min_inside_fraction)


PICK_AREA_FIELDS = ("pick_min", "pick_max", "table_height")
BIN_FIELDS = ("bins", "bin_inner_size", "bin_wall_height")


def dataset_workspace(collection: dict, fields: tuple[str, ...], refusal: str | None = None) -> WorkspaceConfig:
    """The workspace recorded in a dataset's collection metadata: `fields` as recorded (defaults
    where one is missing). A merge of collections that differ in one of them is refused, with
    `refusal` or else a message naming the fields."""
    env = collection.get("env_config") or {}
    ws = (env.get("workspace") if isinstance(env, dict) else None) or {}
    mixed = [k for k in fields if not isinstance(ws, dict) or ws.get(k) == MIXED]
    if mixed:
        raise ValueError(refusal or f"the dataset merges collections with different {', '.join(mixed)}: "
                         "export each collection on its own")

    def recorded(value):
        if isinstance(value, dict):
            return {k: recorded(v) for k, v in value.items()}
        return tuple(value) if isinstance(value, list) else value

    return WorkspaceConfig(**{k: recorded(ws[k]) for k in fields if k in ws})


def dataset_crop(ds, collection: dict, config: CropConfig) -> CropBox:
    """The pick-area crop of a collected dataset, from the camera recorded in its RGB feature's info
    and the workspace recorded in its collection metadata (defaults where a field is missing)."""
    try:
        intrinsics, pose = camera_from_info(ds.meta.features[RGB_KEY].get("info") or {})
    except KeyError as err:
        raise ValueError(f"the dataset records no camera {err}: export whole frames (--no-crop)") from None
    workspace = dataset_workspace(collection, PICK_AREA_FIELDS, "the dataset merges collections with different pick "
                                  "areas, so no one crop fits all of it: export each collection on its own, or export "
                                  "whole frames (--no-crop)")
    return pick_area_crop(intrinsics, pose, workspace, config)


def export_yolo(path: Path, out: Path, config: YoloExportConfig | None = None, overwrite: bool = False,
                progress=None, crop_box: CropBox | None = None) -> Path:
    """Write `out`/images/{train,val}, `out`/labels/{train,val}, `out`/data.yaml; returns data.yaml.
    `crop_box` overrides the crop computed from `config.crop` (e.g. to evaluate weights on exactly
    the crop they were trained on)."""
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
    crop = crop_box or (dataset_crop(ds, collection, config.crop) if config.crop is not None else None)
    bins = None if config.label_sorted else dataset_workspace(collection, BIN_FIELDS)
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
        image = crop.apply(rgb) if crop is not None else rgb
        Image.fromarray(np.ascontiguousarray(image)).save(out / "images" / split / f"{name}.jpg", quality=config.jpeg_quality)
        lines = yolo_lines(item[LABELS_KEY].numpy(), w, h, config.min_box_side, crop, config.min_inside_fraction, bins)
        (out / "labels" / split / f"{name}.txt").write_text("".join(line + "\n" for line in lines))
        if progress:
            progress(i + 1, len(ds))
    data_yaml = out / "data.yaml"
    data_yaml.write_text(yaml.safe_dump({
        "path": str(out.resolve()), "train": "images/train", "val": "images/val",
        "names": dict(enumerate(CLASS_NAMES)), **(crop.record() if crop else {}),
    }, sort_keys=False))
    (out / "split.json").write_text(json.dumps({"source": str(root), "train_episodes": train, "val_episodes": val,
                                                **(crop.record() if crop else {})}))
    return data_yaml


def crop_yolo_set(data_yaml: str | Path, out: Path, crop: CropBox, min_box_side: float = YoloExportConfig.min_box_side,
                  overwrite: bool = False, min_inside_fraction: float = YoloExportConfig.min_inside_fraction) -> Path:
    """A whole-frame YOLO set (e.g. written straight from SortingEnv) cut to `crop` the way
    `export_yolo` cuts: images cropped (same format), labels clipped; returns the new data.yaml."""
    import yaml
    from PIL import Image

    data = read_data_yaml(data_yaml, splits=())
    if data.get("crop") is not None:
        raise ValueError(f"{data_yaml} is already cropped")
    out = Path(out)
    if out.exists() and any(out.iterdir()):
        if not overwrite:
            raise FileExistsError(f"{out} is not empty: choose another folder or pass overwrite=True")
        shutil.rmtree(out)
    record = {"path": str(out.resolve()), "names": dict(enumerate(CLASS_NAMES))}
    for split in ("train", "val", "test"):
        if not data.get(split):
            continue
        src = Path(data[split])
        (out / "images" / split).mkdir(parents=True, exist_ok=True)
        (out / "labels" / split).mkdir(parents=True, exist_ok=True)
        for image_path in sorted(p for p in src.iterdir() if p.suffix.lower() in (".png", ".jpg", ".jpeg")):
            image = np.asarray(Image.open(image_path).convert("RGB"))
            h, w = image.shape[:2]
            Image.fromarray(np.ascontiguousarray(crop.apply(image))).save(out / "images" / split / image_path.name)
            label_file = label_path(image_path)
            boxes = []
            for line in (label_file.read_text().splitlines() if label_file.is_file() else []):
                if line.strip():
                    k, cx, cy, bw, bh = (float(v) for v in line.split()[:5])
                    boxes.append((int(k), ((cx - bw / 2) * w, (cy - bh / 2) * h, (cx + bw / 2) * w, (cy + bh / 2) * h)))
            lines = box_lines(boxes, w, h, min_box_side, crop, min_inside_fraction)
            (out / "labels" / split / (image_path.stem + ".txt")).write_text("".join(line + "\n" for line in lines))
        record[split] = f"images/{split}"
    out_yaml = out / "data.yaml"
    out_yaml.write_text(yaml.safe_dump({**record, **crop.record()}, sort_keys=False))
    return out_yaml
