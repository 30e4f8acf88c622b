"""The YOLO wrapper's offline guarantees; training and predicting are in tests/train."""

import os

import pytest

from sortbot.perception.detector import DetectorConfig, YoloDetector
from sortbot.perception.yolo_offline import FONT_NAMES, setup_offline, ultralytics_device


@pytest.fixture(scope="module")
def yolo_dir(tmp_path_factory):
    return setup_offline(tmp_path_factory.getbasetemp() / "ultralytics")


def test_missing_weights_is_a_one_line_error_not_a_download(tmp_path):
    with pytest.raises(FileNotFoundError, match="nothing is downloaded") as err:
        YoloDetector(tmp_path / "best.pt")
    assert "\n" not in str(err.value)
    with pytest.raises(FileNotFoundError):
        YoloDetector("yolo11n.pt")  # a name ultralytics would fetch
    assert not (tmp_path / "best.pt").exists() and not os.path.exists("yolo11n.pt")


def test_offline_setup_has_fonts_and_no_sync(yolo_dir):
    from ultralytics import utils

    assert os.environ["YOLO_OFFLINE"] == "1" and os.environ["YOLO_AUTOINSTALL"] == "false"
    assert utils.ONLINE is False
    for name in FONT_NAMES:  # without these ultralytics downloads Arial even offline
        assert (yolo_dir / name).stat().st_size > 100_000
    assert utils.SETTINGS["sync"] is False and utils.SETTINGS["mlflow"] is False
    from ultralytics.utils.checks import check_font

    assert check_font("Arial.ttf") == yolo_dir / "Arial.ttf"  # found locally, no download attempted
    assert setup_offline() == yolo_dir  # idempotent


def test_device_names():
    assert ultralytics_device("cpu") == "cpu"
    assert ultralytics_device("auto") in ("cpu", "0")
    with pytest.raises(ValueError, match="unknown device"):
        ultralytics_device("tpu")
    assert DetectorConfig().device == "auto"
