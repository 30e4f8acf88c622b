"""Ultralytics without a network, set up in one place (DESIGN section 2).

Ultralytics decides at import time whether it is online, where its settings live and which font
file it uses; a missing `Arial.ttf` makes it download one even when offline. So before the first
import: `YOLO_OFFLINE=1`, `YOLO_AUTOINSTALL=false`, `YOLO_CONFIG_DIR` pointing to a folder of ours
holding a TTF that is already on disk (matplotlib's DejaVuSans, shipped with ultralytics' own
dependency) as `Ultralytics/Arial.ttf` and `Arial.Unicode.ttf`; after it, settings with `sync`
and every logging integration off. Everything in sortbot imports ultralytics through `import_yolo`.
"""

from __future__ import annotations

import logging
import os
import shutil
import sys
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

log = logging.getLogger(__name__)

DEFAULT_CONFIG_DIR = Path("~/.cache/sortbot/ultralytics")
FONT_NAMES = ("Arial.ttf", "Arial.Unicode.ttf")
_OFF_SETTINGS = ("sync", "hub", "clearml", "comet", "dvc", "mlflow", "neptune", "raytune", "tensorboard", "wandb")
_state: dict[str, Path] = {}


def _local_font() -> Path:
    """A TTF already on disk: matplotlib's bundled DejaVuSans."""
    import matplotlib

    font = Path(matplotlib.get_data_path()) / "fonts" / "ttf" / "DejaVuSans.ttf"
    if not font.is_file():
        raise FileNotFoundError(f"no local TTF for ultralytics at {font}: reinstall matplotlib")
    return font


def _writable_dir(wanted: Path) -> Path:
    try:
        wanted.mkdir(parents=True, exist_ok=True)
        return wanted
    except OSError:
        alt = Path(tempfile.gettempdir()) / f"sortbot-ultralytics-{os.getuid()}"
        alt.mkdir(parents=True, exist_ok=True)
        log.warning("%s is not writable; using %s for ultralytics settings", wanted, alt)
        return alt


def _install_fonts(user_dir: Path) -> None:
    user_dir.mkdir(parents=True, exist_ok=True)
    font = _local_font()
    for name in FONT_NAMES:
        target = user_dir / name
        if not target.is_file():
            shutil.copyfile(font, target)


def setup_offline(config_dir: str | Path | None = None) -> Path:
    """Make ultralytics work with no network; returns its settings folder. Idempotent.

    `config_dir` defaults to `$YOLO_CONFIG_DIR` if the user set one, else ~/.cache/sortbot/ultralytics.
    """
    if "dir" in _state:
        return _state["dir"]
    base = Path(config_dir or os.environ.get("YOLO_CONFIG_DIR") or DEFAULT_CONFIG_DIR).expanduser()
    base = _writable_dir(base)
    os.environ["YOLO_OFFLINE"] = "1"
    os.environ["YOLO_AUTOINSTALL"] = "false"
    already = "ultralytics" in sys.modules
    if not already:
        os.environ["YOLO_CONFIG_DIR"] = str(base)
        _install_fonts(base / "Ultralytics")  # ultralytics' USER_CONFIG_DIR is $YOLO_CONFIG_DIR/Ultralytics
    from ultralytics import utils

    if already:  # someone imported it first: its constants are fixed, patch what still matters
        log.warning("ultralytics was imported before sortbot's offline set-up; patching its settings in %s",
                     utils.USER_CONFIG_DIR)
        utils.ONLINE = False
        _install_fonts(Path(utils.USER_CONFIG_DIR))
    settings = {k: False for k in _OFF_SETTINGS if k in utils.SETTINGS}
    for key in ("runs_dir", "weights_dir"):  # never ./runs or ./weights, even by accident
        settings[key] = str(Path(utils.USER_CONFIG_DIR) / key.removesuffix("_dir"))
    if any(utils.SETTINGS.get(k) != v for k, v in settings.items()):
        utils.SETTINGS.update(settings)
    _state["dir"] = Path(utils.USER_CONFIG_DIR)
    return _state["dir"]


def import_yolo(config_dir: str | Path | None = None):
    """The `ultralytics.YOLO` class, imported after `setup_offline`."""
    setup_offline(config_dir)
    from ultralytics import YOLO

    return YOLO


def ultralytics_device(device: str) -> str:
    """Our device names (cpu | cuda | cuda:N | auto) as ultralytics wants them ('cpu', '0')."""
    import torch

    name = str(device).strip().lower()
    if name == "auto":
        return "0" if torch.cuda.is_available() else "cpu"
    if name == "cpu":
        return "cpu"
    if name == "cuda" or name.startswith("cuda:") or name.isdigit():
        if not torch.cuda.is_available():
            raise ValueError(f"device {device!r} asked for CUDA but torch sees no GPU: use 'cpu' or 'auto'")
        return name.split(":", 1)[1] if ":" in name else ("0" if name == "cuda" else name)
    raise ValueError(f"unknown device {device!r}: use cpu, cuda, cuda:N or auto")


@contextmanager
def torch_threads_kept() -> Iterator[None]:
    """Give back the process's torch thread count after an ultralytics call: its device selection
    sets it to cores - 1 (one on a 2-core machine) for the whole process, which would slow every
    later torch job in it, e.g. the Q-network beside the detector."""
    import torch

    count = torch.get_num_threads()
    try:
        yield
    finally:
        torch.set_num_threads(count)
