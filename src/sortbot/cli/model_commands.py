"""`sortbot train detector` and `sortbot eval detector`: YOLO from collected data, fully offline."""

from __future__ import annotations

import json
import sys
from pathlib import Path


def _yolo_data(data: Path, out: Path, val_fraction: float, overwrite: bool, crop: bool = True, crop_box=None) -> Path:
    """A data.yaml for `data`: a YOLO set (folder with data.yaml, or the yaml itself) is used as is;
    a collected dataset is exported first (split by episode) into `out`, cut to the pick area unless
    `crop` is False, or to exactly `crop_box` when given."""
    from sortbot.datasets.lerobot_store import is_dataset
    from sortbot.datasets.summary import resolve_root
    from sortbot.datasets.yolo_export import YoloExportConfig, export_yolo

    data = Path(data)
    if data.is_file() and data.suffix in (".yaml", ".yml"):
        return data
    if (data / "data.yaml").is_file():
        return data / "data.yaml"
    root = resolve_root(data)
    if not is_dataset(root):
        raise ValueError(f"{data} is neither a collected dataset nor a YOLO set (no data.yaml): "
                         "give `sortbot collect`'s --out or `datasets export-yolo`'s --out")
    print(f"exporting {root} to a YOLO set in {out} (split by episode)", file=sys.stderr)
    config = YoloExportConfig(val_fraction=val_fraction)
    if not crop:
        config.crop = None
    return export_yolo(root, out, config, overwrite=overwrite, crop_box=crop_box)


def cmd_train_detector(args) -> int:
    from sortbot.train.detector import DetectorTrainConfig, resume_detector, train_detector

    out = Path(args.out)
    if args.resume:
        fixed = [f"--{n.replace('_', '-')}" for n in ("data", "model", "init", "epochs", "imgsz", "batch", "seed")
                 if getattr(args, n) is not None]
        if fixed:
            raise ValueError(f"--resume continues with the run's own data and settings: drop {' '.join(fixed)}")
        result = resume_detector(out / "model", device=args.device)
        return _report_training(result)
    if not args.data:
        raise ValueError("train detector needs --data (a collected dataset or a YOLO set), or --resume")
    if out.exists() and any(out.iterdir()) and not args.overwrite:
        raise FileExistsError(f"{out} is not empty: choose another --out or pass --overwrite")
    data_yaml = _yolo_data(Path(args.data), out / "yolo_data", args.val_fraction, overwrite=True, crop=not args.no_crop)
    cfg = DetectorTrainConfig()
    for name in ("model", "epochs", "imgsz", "device", "init", "batch", "seed"):
        if getattr(args, name) is not None:
            setattr(cfg, name, getattr(args, name))
    return _report_training(train_detector(data_yaml, out / "model", cfg, overwrite=True))


def _report_training(result) -> int:
    m = result.metrics
    print(f"best weights -> {result.weights}")
    seen = f"the crop {result.crop.as_list()}" if result.crop else "whole frames"
    resumed = f" (resumed after {result.resumed_after})" if result.resumed_after is not None else ""
    print(f"trained {result.epochs_run}/{result.epochs} epochs{resumed} at imgsz {result.imgsz} on {seen}, {result.device}, in "
          f"{result.train_seconds / 60:.1f} min; held-out mAP50 {m['map50']:.3f}, mAP50-95 {m['map50_95']:.3f}")
    return 0


class _ultralytics_quiet:
    """Raise ultralytics' logger to WARNING for the duration (its handler holds the real stdout)."""

    def __enter__(self):
        import logging

        from sortbot.perception.yolo_offline import import_yolo

        import_yolo()  # offline settings before ultralytics is first imported
        from ultralytics.utils import LOGGER

        self.logger, self.level = LOGGER, LOGGER.level
        LOGGER.setLevel(logging.WARNING)
        return self

    def __exit__(self, *exc):
        self.logger.setLevel(self.level)


def cmd_eval_detector(args) -> int:
    import tempfile

    from sortbot.eval.detector_eval import evaluate_detector
    from sortbot.perception.detector import require_weights
    from sortbot.perception.yolo_data import read_crop_sidecar

    with tempfile.TemporaryDirectory(prefix="sortbot-eval-") as tmp:
        data = Path(args.data)
        crop = read_crop_sidecar(require_weights(args.weights))  # a collected dataset is cut as the weights were trained
        # a collected dataset given here is held out as a whole, unless --val-fraction says otherwise
        data_yaml = _yolo_data(data, Path(tmp) / "yolo", args.val_fraction if args.val_fraction else 1.0, overwrite=True,
                               crop=crop is not None, crop_box=crop)
        if args.json:  # keep stdout pure JSON: ultralytics logs its banner and table to stdout
            import contextlib

            with contextlib.redirect_stdout(sys.stderr), _ultralytics_quiet():
                result = evaluate_detector(args.weights, data_yaml, split=args.split, imgsz=args.imgsz, device=args.device)
        else:
            result = evaluate_detector(args.weights, data_yaml, split=args.split, imgsz=args.imgsz, device=args.device)
        if args.errors:
            from sortbot.eval.detector_errors import ErrorConfig, detector_errors

            with _ultralytics_quiet():
                result["errors"] = detector_errors(args.weights, data_yaml, split=args.split, device=args.device,
                                                   config=ErrorConfig(confidence=args.conf))
    if args.json:
        print(json.dumps(result, indent=1, default=str))
        return 0
    if result.get("crop"):
        print(f"on the crop {result['crop']} of each frame (the pick area the weights were trained on)")
    print(f"mAP50 {result['map50']:.3f}   mAP50-95 {result['map50_95']:.3f}   precision {result['precision']:.3f}   recall {result['recall']:.3f}")
    for name, row in result.get("per_class", {}).items():
        print(f"  {name:6s} precision {row['precision']:.3f}  recall {row['recall']:.3f}  mAP50 {row['map50']:.3f}  "
              f"mAP50-95 {row['map50_95']:.3f}")
    if "errors" in result:
        e = result["errors"]
        print(f"at confidence {e['confidence']}: {e['objects']} objects in {e['frames']} frames: {e['correct']} found "
              f"({e['correct_fraction']:.1%}), {e['wrong_class']} wrong class, {e['poor_box']} poor box, "
              f"{e['missed']} missed; {e['false_positive']} false positives, {e['duplicate']} duplicates")
        if e["confusions"]:
            print("  confusions (true->detected): " + ", ".join(f"{k} {v}" for k, v in e["confusions"].items()))
        for n, row in e["by_objects_in_frame"].items():
            print(f"  {n} objects in frame: {row['frames']} frames, {row['correct_fraction']:.1%} found, "
                  f"{row['wrong_class']} wrong class, {row['poor_box']} poor box, {row['missed']} missed")
    return 0


def cmd_bench_detector(args) -> int:
    import contextlib
    import tempfile

    from sortbot.train.detector_bench import bench_detector

    with tempfile.TemporaryDirectory(prefix="sortbot-bench-data-") as tmp:
        data_yaml = _yolo_data(Path(args.data), Path(tmp) / "yolo", 0.2, overwrite=True)
        say = (lambda mode, s: print(f"  {mode:6s} epoch {s:.1f} s", file=sys.stderr)) if not args.json else None
        quiet = contextlib.redirect_stdout(sys.stderr) if args.json else contextlib.nullcontext()
        with quiet, _ultralytics_quiet():
            result = bench_detector(data_yaml, frames=args.frames, imgsz=args.imgsz, batch=args.batch, device=args.device,
                                    rounds=args.rounds, weights=args.weights, progress=say)
    if args.json:
        print(json.dumps(result, indent=1))
        return 0
    sq, rc = result["train_square"]["images_per_s"], result["train_rect"]["images_per_s"]
    print(f"training, {result['frames']} frames at imgsz {result['imgsz']}, batch {result['batch']}, {result['device']}: "
          f"square {sq:.2f} img/s, rectangular {rc:.2f} img/s -> {result['rect_speedup']:.2f}x")
    if "predict" in result:
        p = result["predict"]
        print(f"prediction on full frames ({p['device']}): {p['ms_per_frame_median']:.1f} ms/frame median, "
              f"{p['ms_per_frame_p90']:.1f} ms p90 ({p['frames_per_s']:.1f} frames/s)")
    return 0


def add_bench_parser(bench) -> None:
    sp = bench.add_parser("detector", help="YOLO training images/s, square vs rectangular batches; prediction ms/frame")
    sp.add_argument("--data", required=True, help="a YOLO set (data.yaml or its folder) or a collected dataset")
    sp.add_argument("--frames", type=int, default=120, help="training frames timed per epoch")
    sp.add_argument("--imgsz", type=int, default=416)
    sp.add_argument("--batch", type=int, default=4)
    sp.add_argument("--rounds", type=int, default=2, help="alternating square/rect epochs; the median counts")
    sp.add_argument("--weights", help="local .pt to time prediction with (optional)")
    sp.add_argument("--device", default="auto", help="cpu, cuda, cuda:N or auto")
    sp.add_argument("--json", action="store_true")
    sp.set_defaults(func=cmd_bench_detector)


def add_parsers(sub) -> None:
    train = sub.add_parser("train", help="train models from collected datasets").add_subparsers(dest="train_command", required=True)
    sp = train.add_parser("detector", help="YOLO detector from a collected dataset or a YOLO set, offline")
    sp.add_argument("--data", help="collect --out folder, LeRobot root, or YOLO set (data.yaml)")
    sp.add_argument("--out", required=True)
    sp.add_argument("--resume", action="store_true",
                    help="continue the interrupted training in --out from its last epoch (same data and settings)")
    sp.add_argument("--model", help="architecture yaml (from scratch, default yolo11n.yaml) or a local .pt")
    sp.add_argument("--init", help="local checkpoint to start from (never downloaded)")
    sp.add_argument("--epochs", type=int)
    sp.add_argument("--imgsz", type=int)
    sp.add_argument("--batch", type=int)
    sp.add_argument("--device", help="cpu, cuda, cuda:N or auto")
    sp.add_argument("--seed", type=int)
    sp.add_argument("--val-fraction", type=float, default=0.2, help="episodes held out when exporting a dataset")
    sp.add_argument("--no-crop", action="store_true", help="when exporting a dataset: whole frames, not the pick area")
    sp.add_argument("--overwrite", action="store_true")
    sp.set_defaults(func=cmd_train_detector)

    ev = sub.add_parser("eval", help="evaluate models").add_subparsers(dest="eval_command", required=True)
    sp = ev.add_parser("detector", help="mAP50, mAP50-95, per-class precision/recall on held-out episodes")
    sp.add_argument("--weights", required=True)
    sp.add_argument("--data", required=True, help="a YOLO set (its --split), or a collected dataset (all held out)")
    sp.add_argument("--split", default="val")
    sp.add_argument("--val-fraction", type=float, help="with a collected dataset: hold out only its last episodes")
    sp.add_argument("--imgsz", type=int)
    sp.add_argument("--device", default="auto")
    sp.add_argument("--errors", action="store_true",
                    help="also count objects found / wrong class / poor box / missed at --conf, by objects per frame")
    sp.add_argument("--conf", type=float, default=0.25, help="confidence for --errors (the detector's own threshold)")
    sp.add_argument("--json", action="store_true")
    sp.set_defaults(func=cmd_eval_detector)
