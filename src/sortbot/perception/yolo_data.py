"""The YOLO detection-set contract as the detector's training and evaluation read it, and the
figures ultralytics measures on it.

A set is a `data.yaml` with `path`, `train`, `val` (optionally `test`) image folders and
`names: {0: fork, 1: knife, 2: spoon, 3: block}` (CLASS_NAMES order), images beside YOLO txt labels.
Ultralytics resolves a relative `path` against its own datasets folder, not the yaml's, and tries to
download a set it cannot find; so the yaml is checked here and handed over with absolute paths.
"""

from __future__ import annotations

from pathlib import Path

import yaml

from sortbot.types import CLASS_NAMES

SPLITS = ("train", "val", "test")


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
