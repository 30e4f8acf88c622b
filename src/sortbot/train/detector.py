"""Train the YOLO detector (ultralytics) on a YOLO detection set, fully offline.

From scratch (an architecture yaml such as `yolo11n.yaml`, shipped inside ultralytics) or from a
local checkpoint; never from weights that would have to be downloaded. Everything lands in
`out_dir`: ultralytics' run in `out_dir/yolo/`, the best weights as `out_dir/best.pt`, the checked
data.yaml and `metrics.json` (the held-out figures of the best weights plus the settings). A set
cut to the pick area (its data.yaml records a `crop`) leaves that crop beside the weights
(`best.crop.json`, and in metrics.json) so that `YoloDetector` cuts its input the same way.
"""

from __future__ import annotations

import json
import os
import shutil
import time
from dataclasses import asdict, dataclass
from pathlib import Path

from sortbot.perception.detector import require_weights
from sortbot.perception.yolo_data import (CROP_KEY, CropBox, crop_sidecar, read_crop, split_image_sizes,
                                         summarize_metrics, write_crop_sidecar, write_resolved)
from sortbot.perception.yolo_offline import import_yolo, torch_threads_kept, ultralytics_device

RUN_NAME = "yolo"
OUTPUTS = (RUN_NAME, "best.pt", crop_sidecar("best.pt").name, "data.yaml", "metrics.json")  # what train_detector writes in out_dir


@dataclass
class DetectorTrainConfig:
    """Defaults measured on 6-cutlery drops, yolo11n from scratch on 2 CPU cores: more steps beat
    bigger batches (6-epoch probes: batch 4 > 8 > 16) and 640 px learned little more per epoch at
    3.4x the time. What limits mAP50 is training steps (train and val losses level, the curve still
    rising at 73 epochs); the runs and their figures are in the README."""

    model: str = "yolo11n.yaml"  # architecture yaml (from scratch) or a local .pt
    init: str | None = None  # local checkpoint to start from (its weights, our classes)
    epochs: int = 30
    imgsz: int = 320  # the 640 x 480 frames, long side scaled to this
    batch: int = 4
    device: str = "auto"  # cpu | cuda | cuda:N | auto
    workers: int = 2  # dataloader processes
    seed: int = 0
    deterministic: bool = True
    patience: int = 20  # epochs without improvement before stopping early
    optimizer: str = "AdamW"
    lr0: float = 0.002
    nbs: int | None = None  # images per optimizer step; None: every batch (ultralytics' 64 is too few steps on a CPU)
    warmup_epochs: float = 1.0
    mosaic: float = 0.0  # the camera never moves: mosaic's zoomed-out tiles teach scales never seen
    close_mosaic: int = 0  # last epochs trained without mosaic
    scale: float = 0.2  # random zoom +-: objects are always seen at about the same size
    translate: float = 0.1
    fliplr: float = 0.5  # cutlery classes do not change under flips
    flipud: float = 0.5
    # Rectangular batches: the pick-area crop (442 x 287) trains as 416 x 288 instead of a padded
    # 416 x 416 square, 1.4x faster a step, same augmentation. ultralytics keeps shuffling only when
    # every batch has the same shape, so None (auto) uses them only when all training images share one size.
    rect: bool | None = None
    cache: bool = False  # decoded images in RAM: faster, but ultralytics warns it is not deterministic
    val_every_epoch: bool = True  # needed for best.pt and early stopping; the last epoch is always validated
    plots: bool = True  # ultralytics' label/result/PR plots in the run folder
    # torch threads on a CPU; None: every core (ultralytics keeps one idle, half of a 2-core machine).
    # The same seed gives the same weights only at the same count.
    cpu_threads: int | None = None


@dataclass
class DetectorTrainResult:
    weights: Path  # out_dir/best.pt
    metrics: dict  # map50, map50_95, precision, recall, per_class (held-out split `val`)
    train_seconds: float
    epochs: int  # asked for
    epochs_run: int  # fewer when early stopping triggered
    imgsz: int
    device: str
    out_dir: Path
    crop: CropBox | None = None  # the part of the full frames the detector sees (None: all of it)
    rect: bool = False  # trained on rectangular batches
    resumed_after: int | None = None  # epochs already trained when this invocation continued an interrupted run


def _prepare_out_dir(out_dir: Path, overwrite: bool) -> None:
    if out_dir.exists() and not out_dir.is_dir():
        raise NotADirectoryError(f"output {out_dir} exists and is not a folder")
    if out_dir.exists() and any(out_dir.iterdir()):
        if not overwrite:
            raise FileExistsError(f"output folder {out_dir} is not empty: choose another or pass overwrite=True")
        for name in OUTPUTS:  # only what a previous run wrote; anything else of the user's stays
            p = out_dir / name
            if p.is_dir():
                shutil.rmtree(p)
            elif p.exists():
                p.unlink()
    out_dir.mkdir(parents=True, exist_ok=True)


def _load_model(config: DetectorTrainConfig):
    yolo = import_yolo()
    if config.init:
        return yolo(str(require_weights(config.init)), task="detect")
    if config.model.endswith((".yaml", ".yml")):
        return yolo(config.model, task="detect")  # a shipped architecture name or a local yaml
    if Path(config.model).expanduser().is_file():
        return yolo(str(Path(config.model).expanduser()), task="detect")
    raise FileNotFoundError(f"model {config.model} is neither an architecture yaml nor a local weights file; "
                            "pretrained weights are never downloaded (use e.g. yolo11n.yaml or init=<local .pt>)")


def _use_cpu_threads(model, threads: int | None) -> None:
    """ultralytics' device selection sets torch to cores - 1 threads, one thread on a 2-core machine;
    training with both was 1.42x faster (one epoch, 300 frames: 40.5 s -> 28.5 s). The trainer selects
    its device before any callback, so the count is set again when its set-up starts."""
    count = threads or os.cpu_count() or 1

    def set_threads(trainer) -> None:
        if trainer.device.type == "cpu":
            import torch

            torch.set_num_threads(count)

    model.add_callback("on_pretrain_routine_start", set_threads)


def use_rect(setting: bool | None, data_yaml: str | Path) -> bool:
    """Whether to train on rectangular batches: as set, or (None) when every training image has the
    same size, the only case where ultralytics still shuffles them."""
    return setting if setting is not None else len(split_image_sizes(data_yaml, "train")) == 1


def train_detector(data_yaml: str | Path, out_dir: str | Path, config: DetectorTrainConfig | None = None,
                   *, overwrite: bool = False, callbacks: dict | None = None) -> DetectorTrainResult:
    """Train on `data_yaml`'s train split, keep the best epoch on its val split, write metrics.json.
    `callbacks`: ultralytics event name -> function(trainer), e.g. to time epochs or report progress."""
    cfg = config or DetectorTrainConfig()
    out_dir = Path(out_dir).expanduser().resolve()
    _prepare_out_dir(out_dir, overwrite)
    data = write_resolved(data_yaml, out_dir)
    crop = read_crop(data)
    device = ultralytics_device(cfg.device)
    rect = use_rect(cfg.rect, data)
    model = _load_model(cfg)
    metrics, seconds = _run(
        model, cfg, callbacks,
        data=str(data), epochs=cfg.epochs, imgsz=cfg.imgsz, batch=cfg.batch, device=device, workers=cfg.workers,
        seed=cfg.seed, deterministic=cfg.deterministic, patience=cfg.patience, optimizer=cfg.optimizer,
        lr0=cfg.lr0, nbs=cfg.nbs or cfg.batch, warmup_epochs=cfg.warmup_epochs, mosaic=cfg.mosaic,
        close_mosaic=cfg.close_mosaic, scale=cfg.scale, translate=cfg.translate, fliplr=cfg.fliplr,
        flipud=cfg.flipud, rect=rect, cache=cfg.cache, val=cfg.val_every_epoch, plots=cfg.plots,
        amp=False,  # AMP's self-check downloads weights
        project=str(out_dir), name=RUN_NAME, exist_ok=True, pretrained=bool(cfg.init), verbose=False)
    return _finish(model, metrics, seconds, cfg, out_dir, data, crop, rect, device)


def _run(model, cfg: DetectorTrainConfig, callbacks: dict | None, **train_args) -> tuple:
    """model.train(**train_args) on the configured CPU threads with the caller's callbacks; (metrics, seconds)."""
    _use_cpu_threads(model, cfg.cpu_threads)
    for event, fn in (callbacks or {}).items():
        model.add_callback(event, fn)
    t0 = time.perf_counter()
    with torch_threads_kept():  # the trainer's count is for training only, not the rest of the process
        metrics = model.train(**train_args)
    return metrics, time.perf_counter() - t0


def _finish(model, metrics, seconds: float, cfg: DetectorTrainConfig, out_dir: Path, data: Path,
            crop: CropBox | None, rect: bool, device: str, resumed_after: int | None = None) -> DetectorTrainResult:
    """Copy the best epoch's weights (and their crop) out of ultralytics' run, write metrics.json."""
    trainer = model.trainer
    best = trainer.best if Path(trainer.best).exists() else trainer.last
    weights = out_dir / "best.pt"
    shutil.copyfile(best, weights)
    write_crop_sidecar(weights, crop)
    summary = summarize_metrics(metrics)
    epochs_run = int(trainer.epoch) + 1
    record = {
        **summary, "weights": str(weights), "train_seconds": seconds, "epochs": cfg.epochs,
        "epochs_run": epochs_run, "imgsz": cfg.imgsz, "rect": rect, "device": device, "data": str(data), "config": asdict(cfg),
        **(crop.record() if crop else {CROP_KEY: None}),
    }
    if resumed_after is not None:
        record["resumed_after_epochs"] = resumed_after  # train_seconds counts from there
    (out_dir / "metrics.json").write_text(json.dumps(record, indent=1))
    return DetectorTrainResult(weights=weights, metrics=summary, train_seconds=seconds, epochs=cfg.epochs,
                               epochs_run=epochs_run, imgsz=cfg.imgsz, device=device, out_dir=out_dir, crop=crop,
                               rect=rect, resumed_after=resumed_after)


def last_checkpoint(out_dir: str | Path) -> Path:
    """The interrupted run's last.pt under `out_dir`, or a one-line error saying why it cannot go on."""
    out_dir = Path(out_dir).expanduser().resolve()
    last = out_dir / RUN_NAME / "weights" / "last.pt"
    if not last.is_file():
        raise FileNotFoundError(f"no interrupted detector training in {out_dir} (no {last.relative_to(out_dir)}): "
                                "give the folder a `train detector` run wrote")
    return last


def _run_config(args: dict) -> DetectorTrainConfig:
    """The settings of a run, rebuilt from the arguments ultralytics saved in its checkpoint."""
    cfg = DetectorTrainConfig()
    for name in asdict(cfg):
        if name in args:
            setattr(cfg, name, args[name])
    cfg.val_every_epoch = bool(args.get("val", True))
    cfg.init = args.get("model") if args.get("pretrained") else None
    if cfg.init:
        cfg.model = DetectorTrainConfig.model
    return cfg


def resume_detector(out_dir: str | Path, *, device: str | None = None, cpu_threads: int | None = None,
                    callbacks: dict | None = None) -> DetectorTrainResult:
    """Continue an interrupted `train_detector` run in `out_dir` from its last epoch, with the same data,
    settings, optimizer state and schedule (ultralytics' resume), then write best.pt and metrics.json as
    a finished run does. `device` may change; nothing else can."""
    last = last_checkpoint(out_dir)
    out_dir = last.parents[2]
    model = import_yolo()(str(last), task="detect")  # its .ckpt is the checkpoint, read once
    args, epoch = dict(model.ckpt.get("train_args") or {}), int(model.ckpt.get("epoch", -1))
    if model.ckpt.get("optimizer") is None or epoch < 0 or epoch + 1 >= int(args.get("epochs", 0)):
        raise ValueError(f"the training in {out_dir} already finished ({args.get('epochs', '?')} epochs): "
                         "nothing to resume; start a new one with more --epochs or --init its best.pt")
    data = Path(args.get("data", ""))
    if not data.is_file():
        raise FileNotFoundError(f"the run in {out_dir} trained on {data}, which is gone: it cannot be resumed")
    cfg = _run_config(args)
    cfg.device, cfg.cpu_threads = device or cfg.device, cpu_threads
    device = ultralytics_device(cfg.device)
    metrics, seconds = _run(model, cfg, callbacks, resume=True, device=device)
    return _finish(model, metrics, seconds, cfg, out_dir, data, read_crop(data), bool(cfg.rect), device,
                   resumed_after=epoch + 1)
