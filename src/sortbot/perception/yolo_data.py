"""The YOLO detection-set contract as the detector's training and evaluation read it, and the
figures ultralytics measures on it.

A set is a `data.yaml` with `path`, `train`, `val` (optionally `test`) image folders and
`names: {0: fork, 1: knife, 2: spoon, 3: block}` (CLASS_NAMES order), images beside YOLO txt labels.
An optional `crop: [x0, y0, x1, y1]` with `image_size: [width, height]` says the images are that
part of the full camera frames (see `pick_area_crop`); the detector then crops the same way.
Ultralytics resolves a relative `path` against its own datasets folder, not the yaml's, and tries to
download a set it cannot find; so the yaml is checked here and handed over with absolute paths.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml

from sortbot.config import WorkspaceConfig
from sortbot.types import CLASS_NAMES, CameraIntrinsics, CameraPose

SPLITS = ("train", "val", "test")
IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".webp")


def _names(raw) -> dict[int, str]:
    if isinstance(raw, list):
        return dict(enumerate(str(n) for n in raw))
    if isinstance(raw, dict):
        return {int(k): str(v) for k, v in raw.items()}
    raise ValueError(f"data.yaml `names` must be a list or a mapping, got {type(raw).__name__}")


def read_data_yaml(data_yaml: str | Path, splits: tuple[str, ...] = ("train", "val")) -> dict:
    """The yaml as a dict with an absolute `path` and absolute split entries; a clear error when the
    file, a needed split or its folder is missing, or the classes are not sortbot's."""
    file = Path(data_yaml).expanduser()
    if not file.is_file():
        raise FileNotFoundError(f"YOLO data file {file} not found: export a detection set first")
    data = yaml.safe_load(file.read_text())
    if not isinstance(data, dict):
        raise ValueError(f"{file} is not a YOLO data.yaml (expected a mapping with path, train, val, names)")
    expected = dict(enumerate(CLASS_NAMES))
    if _names(data.get("names", [])) != expected:
        raise ValueError(f"{file}: names must be {expected} (sortbot's CLASS_NAMES order), got {data.get('names')}")
    root = Path(data.get("path") or file.parent).expanduser()
    root = (root if root.is_absolute() else file.parent / root).resolve()
    data["path"] = str(root)
    for split in SPLITS:
        if split not in data or data[split] is None:
            if split in splits:
                raise ValueError(f"{file} has no `{split}` split")
            continue
        entries = data[split] if isinstance(data[split], list) else [data[split]]
        resolved = []
        for entry in entries:
            p = Path(entry).expanduser()
            p = p if p.is_absolute() else root / p
            if split in splits and not p.exists():
                raise FileNotFoundError(f"{file}: the {split} split {p} does not exist")
            resolved.append(str(p))
        data[split] = resolved if isinstance(data[split], list) else resolved[0]
    data["names"] = expected
    data.pop("download", None)  # never fetch a missing set
    return data


def write_resolved(data_yaml: str | Path, out_dir: str | Path, splits: tuple[str, ...] = ("train", "val")) -> Path:
    """A checked copy of the data.yaml, all paths absolute, written to `out_dir/data.yaml`."""
    data = read_data_yaml(data_yaml, splits)
    out = Path(out_dir) / "data.yaml"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(yaml.safe_dump(data, sort_keys=False))
    return out


def split_images(data_yaml: str | Path, split: str = "train") -> list[Path]:
    """A split's image files, sorted. A split may be a folder, a list of folders, or a txt file
    listing images, as ultralytics allows."""
    entries = read_data_yaml(data_yaml, splits=(split,))[split]
    files: list[Path] = []
    for entry in entries if isinstance(entries, list) else [entries]:
        p = Path(entry)
        if p.is_dir():
            files += [f for f in p.rglob("*") if f.suffix.lower() in IMAGE_SUFFIXES]
        elif p.suffix == ".txt":
            files += [p.parent / line.strip() for line in p.read_text().splitlines() if line.strip()]
        else:
            files.append(p)
    return sorted(files)


def label_path(image: Path) -> Path:
    """The YOLO label file of an image: .../images/<split>/x.jpg -> .../labels/<split>/x.txt."""
    return image.parent.parent.parent / "labels" / image.parent.name / (image.stem + ".txt")


def split_image_sizes(data_yaml: str | Path, split: str = "train") -> set[tuple[int, int]]:
    """The distinct (width, height) of a split's images (headers only, nothing decoded)."""
    from PIL import Image

    sizes = set()
    for f in split_images(data_yaml, split):
        with Image.open(f) as im:
            sizes.add(im.size)
    return sizes


def summarize_metrics(metrics) -> dict:
    """Ultralytics' DetMetrics as plain numbers: overall mAP50, mAP50-95, precision, recall, and the
    same per class (only classes with instances in the split; ultralytics measures no others)."""
    box = metrics.box
    precision, recall, map50, map50_95 = (float(v) for v in box.mean_results())
    per_class = {}
    nt = getattr(metrics, "nt_per_class", None)
    for i, c in enumerate(box.ap_class_index):
        p, r, ap50, ap = (float(v) for v in box.class_result(i))
        per_class[str(metrics.names[int(c)])] = {
            "precision": p, "recall": r, "map50": ap50, "map50_95": ap,
            "instances": int(nt[int(c)]) if nt is not None else None,
        }
    return {"map50": map50, "map50_95": map50_95, "precision": precision, "recall": recall, "per_class": per_class}


# --- the pick-area crop ---------------------------------------------------------------------------
# The camera never moves and objects are only picked in the pick area, which fills about 40 % of a
# frame (the rest is bins and the robot). Training and predicting on that part only gives the same
# network input size ~1.5x more pixels per object: a knife is 3-5 px wide in a whole 640 x 480
# frame scaled to 320, and most detector errors were fork/knife/spoon confusions.

CROP_KEY = "crop"  # data.yaml / split.json / sidecar key: [x0, y0, x1, y1] in full-image pixels
IMAGE_SIZE_KEY = "image_size"  # [width, height] of the full images the crop was cut from
CROP_SIDECAR_SUFFIX = ".crop.json"  # best.pt -> best.crop.json


@dataclass(frozen=True)
class CropConfig:
    """How far beyond the pick area the detector looks. `margin` (metres, on the table) covers
    objects lying across the pick area's edge: drops land `drop_margin` (5 cm) inside it and the
    longest knife reaches ~10 cm from its centre, so 6 cm keeps almost all of every object (on the
    6-cutlery set 98 % of boxes whole, the rest clipped; only objects already in a bin fall outside).
    `object_height` (metres) is the top of anything lying on the table, seen higher in the image."""

    margin: float = 0.06
    object_height: float = 0.03

    def __post_init__(self) -> None:
        if self.margin < 0 or self.object_height < 0:
            raise ValueError(f"crop margin and object height must be >= 0, got {self.margin}, {self.object_height}")


@dataclass(frozen=True)
class CropBox:
    """A fixed rectangle of the full image, [x0, x1) x [y0, y1) in pixels, and the full image's size."""

    x0: int
    y0: int
    x1: int
    y1: int
    image_width: int
    image_height: int

    def __post_init__(self) -> None:
        if not (0 <= self.x0 < self.x1 <= self.image_width and 0 <= self.y0 < self.y1 <= self.image_height):
            raise ValueError(f"crop {self.as_list()} does not lie inside a {self.image_width} x {self.image_height} image")

    @property
    def width(self) -> int:
        return self.x1 - self.x0

    @property
    def height(self) -> int:
        return self.y1 - self.y0

    def as_list(self) -> list[int]:
        return [self.x0, self.y0, self.x1, self.y1]

    def record(self) -> dict:
        """What data.yaml, split.json and the weights' sidecar store."""
        return {CROP_KEY: self.as_list(), IMAGE_SIZE_KEY: [self.image_width, self.image_height]}

    @classmethod
    def from_record(cls, record: dict) -> "CropBox | None":
        """The crop a data.yaml / sidecar dict records, or None when it records none (full images)."""
        box = record.get(CROP_KEY)
        if box is None:
            return None
        size = record.get(IMAGE_SIZE_KEY)
        if size is None or len(box) != 4 or len(size) != 2:
            raise ValueError(f"a crop needs {CROP_KEY}: [x0, y0, x1, y1] and {IMAGE_SIZE_KEY}: [width, height], got {record}")
        return cls(*(int(v) for v in box), int(size[0]), int(size[1]))

    def check_image(self, width: int, height: int) -> None:
        if (width, height) != (self.image_width, self.image_height):
            raise ValueError(f"the crop {self.as_list()} was made for {self.image_width} x {self.image_height} "
                             f"images, got {width} x {height}")

    def apply(self, image: np.ndarray) -> np.ndarray:
        """The crop of a full (H, W, ...) image."""
        self.check_image(image.shape[1], image.shape[0])
        return image[self.y0:self.y1, self.x0:self.x1]

    def box_to_crop(self, box, min_side: float = 0.0, min_inside_fraction: float = 0.0,
                    ) -> tuple[float, float, float, float] | None:
        """A full-image box clipped to the crop, in crop pixels; None when less than `min_side`
        pixels of it (in either direction), or less than `min_inside_fraction` of its area, remain inside."""
        bx1, by1, bx2, by2 = (float(v) for v in box)
        x1, x2 = max(bx1, self.x0) - self.x0, min(bx2, self.x1) - self.x0
        y1, y2 = max(by1, self.y0) - self.y0, min(by2, self.y1) - self.y0
        if x2 - x1 < max(min_side, 1e-9) or y2 - y1 < max(min_side, 1e-9):
            return None
        if (x2 - x1) * (y2 - y1) < min_inside_fraction * (bx2 - bx1) * (by2 - by1):
            return None
        return x1, y1, x2, y2

    def paste(self, image: np.ndarray) -> np.ndarray:
        """A full frame (black outside the crop) holding a cropped (H, W, 3) image where it was cut."""
        if image.shape[:2] != (self.height, self.width):
            raise ValueError(f"expected a {self.width} x {self.height} crop, got {image.shape[1]} x {image.shape[0]}")
        frame = np.zeros((self.image_height, self.image_width, *image.shape[2:]), image.dtype)
        frame[self.y0:self.y1, self.x0:self.x1] = image
        return frame

    def box_to_full(self, box) -> tuple[float, float, float, float]:
        """A box in crop pixels back in full-image pixels."""
        x1, y1, x2, y2 = (float(v) for v in box)
        return x1 + self.x0, y1 + self.y0, x2 + self.x0, y2 + self.y0


def project_points(points: np.ndarray, intrinsics: CameraIntrinsics, pose: CameraPose) -> np.ndarray:
    """Base-frame points (N, 3) to pixel coordinates (N, 2): the inverse of heightmap's
    `camera_points` + `to_base`."""
    cam = (np.asarray(points, float) - np.asarray(pose.position, float)) @ np.asarray(pose.rotation, float)
    if np.any(cam[:, 2] <= 0):
        raise ValueError("a point to project lies behind the camera")
    return intrinsics.project(cam)


def pick_area_crop(intrinsics: CameraIntrinsics, pose: CameraPose, workspace: WorkspaceConfig | None = None,
                   config: CropConfig | None = None) -> CropBox:
    """The image rectangle holding the pick area grown by `config.margin`, from the table up to
    `config.object_height` (the bounding box of those 8 corners projected), clipped to the image."""
    ws, cfg = workspace or WorkspaceConfig(), config or CropConfig()
    (xa, ya), (xb, yb) = ws.pick_min, ws.pick_max
    m, z0 = cfg.margin, ws.table_height
    corners = np.array([(x, y, z) for x in (xa - m, xb + m) for y in (ya - m, yb + m) for z in (z0, z0 + cfg.object_height)])
    uv = project_points(corners, intrinsics, pose)
    w, h = int(intrinsics.width), int(intrinsics.height)
    x0, y0 = (int(np.clip(np.floor(v), 0, s)) for v, s in zip(uv.min(axis=0), (w, h)))
    x1, y1 = (int(np.clip(np.ceil(v), 0, s)) for v, s in zip(uv.max(axis=0), (w, h)))
    if x1 <= x0 or y1 <= y0:
        raise ValueError("the pick area is not in the camera's view: no crop")
    return CropBox(x0, y0, x1, y1, w, h)


def read_crop(data_yaml: str | Path) -> CropBox | None:
    """The crop a YOLO set was cut with (its data.yaml's `crop`), or None for full images."""
    data = yaml.safe_load(Path(data_yaml).expanduser().read_text())
    return CropBox.from_record(data) if isinstance(data, dict) else None


def crop_sidecar(weights: str | Path) -> Path:
    """Where the crop a detector was trained with is written beside its weights."""
    weights = Path(weights)
    return weights.with_name(weights.stem + CROP_SIDECAR_SUFFIX)


def write_crop_sidecar(weights: str | Path, crop: CropBox | None) -> Path:
    """`best.crop.json` beside `best.pt`: the crop (or `crop: null` for full images)."""
    path = crop_sidecar(weights)
    path.write_text(json.dumps(crop.record() if crop else {CROP_KEY: None}))
    return path


def read_crop_sidecar(weights: str | Path) -> CropBox | None:
    """The crop recorded beside `weights`; None when none is recorded (weights trained on full images)."""
    path = crop_sidecar(weights)
    return CropBox.from_record(json.loads(path.read_text())) if path.is_file() else None
