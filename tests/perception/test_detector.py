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


def test_pick_area_crop_follows_the_camera_and_round_trips_boxes():
    import numpy as np

    from sortbot.config import CameraConfig, WorkspaceConfig
    from sortbot.perception.heightmap import camera_points, to_base
    from sortbot.perception.yolo_data import CropBox, CropConfig, pick_area_crop, project_points
    from sortbot.sim.camera import camera_from_config

    intrinsics, pose = camera_from_config(CameraConfig())
    # projecting is the inverse of the heightmap's back-projection
    depth = np.zeros((480, 640), np.float32)
    depth[[50, 300, 470], [20, 320, 600]] = [0.9, 0.7, 0.5]
    pts, idx = camera_points(depth, intrinsics)
    v, u = np.divmod(idx, 640)
    assert np.allclose(project_points(to_base(pts, pose), intrinsics, pose), np.stack([u, v], 1), atol=1e-6)

    ws = WorkspaceConfig()
    crop = pick_area_crop(intrinsics, pose, ws, CropConfig(margin=0.0, object_height=0.0))
    corners = project_points(np.array([(x, y, 0.0) for x in (ws.pick_min[0], ws.pick_max[0])
                                       for y in (ws.pick_min[1], ws.pick_max[1])]), intrinsics, pose)
    assert np.allclose(corners.min(0), [crop.x0, crop.y0], atol=1) and np.allclose(corners.max(0), [crop.x1, crop.y1], atol=1)
    wide = pick_area_crop(intrinsics, pose, ws, CropConfig())  # the margin grows it, yet it stays well inside the frame
    assert wide.x0 < crop.x0 and wide.y0 < crop.y0 and wide.x1 > crop.x1 and wide.y1 > crop.y1
    assert 0 < wide.width * wide.height < 0.5 * 640 * 480

    box = CropBox(100, 50, 300, 250, 640, 480)
    full = (120.0, 60.0, 180.0, 90.0)
    inside = box.box_to_crop(full)
    assert inside == (20.0, 10.0, 80.0, 40.0) and box.box_to_full(inside) == full
    assert box.box_to_crop((90, 40, 110, 260)) == (0.0, 0.0, 10.0, 200.0)  # clipped to the crop
    assert box.box_to_crop((90, 40, 102, 260), min_side=4) is None  # 2 px left inside
    assert box.box_to_crop((80, 40, 110, 260), min_inside_fraction=0.25) is not None  # 10 of 30 px wide inside: 1/3
    assert box.box_to_crop((60, 40, 110, 260), min_inside_fraction=0.25) is None  # 10 of 50 px wide inside: 1/5
    assert box.box_to_crop((400, 300, 420, 320)) is None  # wholly outside
    assert CropBox.from_record(box.record()) == box and CropBox.from_record({"crop": None}) is None
    frame = np.random.default_rng(0).integers(0, 255, (480, 640, 3), dtype=np.uint8)
    pasted = box.paste(box.apply(frame))  # the crop back where it was cut, black around it
    assert pasted.shape == frame.shape and np.array_equal(box.apply(pasted), box.apply(frame))
    assert pasted.sum() == box.apply(frame).sum()
    with pytest.raises(ValueError, match="made for 640 x 480"):
        box.apply(np.zeros((240, 320, 3), np.uint8))
    with pytest.raises(ValueError, match="200 x 200 crop"):
        box.paste(np.zeros((10, 10, 3), np.uint8))
    with pytest.raises(ValueError, match="inside"):
        CropBox(0, 0, 700, 10, 640, 480)


def test_detector_predicts_on_the_crop_and_returns_full_image_boxes(tmp_path):
    """The wrapper with ultralytics' model replaced: it must hand over the cropped pixels and shift
    the boxes it gets back by the crop's corner."""
    import json
    from types import SimpleNamespace

    import numpy as np
    import torch

    from sortbot.perception.yolo_data import CropBox, read_crop_sidecar, write_crop_sidecar

    crop = CropBox(100, 50, 300, 250, 640, 480)
    weights = tmp_path / "best.pt"
    assert read_crop_sidecar(weights) is None  # no sidecar: whole frames
    write_crop_sidecar(weights, crop)
    assert json.loads((tmp_path / "best.crop.json").read_text())["crop"] == [100, 50, 300, 250]
    assert read_crop_sidecar(weights) == crop

    rgb = np.zeros((480, 640, 3), np.uint8)
    rgb[50:250, 100:300, 0] = 255  # the crop is red, the rest black
    seen = []

    class FakeModel:
        def predict(self, source, **kwargs):
            seen.append(source)
            boxes = SimpleNamespace(xyxy=torch.tensor([[20.0, 10.0, 80.0, 40.0]]), conf=torch.tensor([0.9]),
                                    cls=torch.tensor([1.0]))
            return [SimpleNamespace(boxes=boxes)]

    det = object.__new__(YoloDetector)
    det.config, det.model, det.names, det.imgsz, det.device = DetectorConfig(), FakeModel(), {1: "knife"}, 64, "cpu"
    det.crop = read_crop_sidecar(weights)
    (d,) = det.predict_rgb(rgb)
    assert seen[0].shape == (200, 200, 3) and (seen[0][..., 2] == 255).all()  # BGR: red is channel 2
    assert d.box == (120.0, 60.0, 180.0, 90.0) and d.cls == "knife"
    det.crop = None
    (d,) = det.predict_rgb(rgb)
    assert seen[1].shape == (480, 640, 3) and d.box == (20.0, 10.0, 80.0, 40.0)
