"""datasets info / merge / push --dry-run / export-yolo on a collected set, through the CLI."""

import json

import numpy as np
import yaml

from sortbot.cli import main
from sortbot.datasets.features import label_rows
from sortbot.datasets.summary import load_table


def test_info_counts_equal_a_hand_count(collected, capsys):
    out, result = collected
    assert main(["datasets", "info", str(out), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    table = load_table(out / "lerobot")
    grasp = table["action"][:, 0] == 1
    assert info["episodes"] == 2 and info["frames"] == result.frames == len(grasp)
    assert info["outcomes"]["grasps"] == int(grasp.sum())
    assert info["outcomes"]["grasp_success"] == int(table["outcome.grasp_success"].reshape(-1)[grasp].sum())
    assert sum(info["class_balance_scenes"].values()) == 6  # 2 scenes x 3 objects
    assert info["size_bytes"] > 0


def test_merge_concatenates_episodes(collected, tmp_path, capsys):
    out, result = collected
    merged = tmp_path / "merged"
    assert main(["datasets", "merge", str(out), str(out / "lerobot"), "--out", str(merged)]) == 0
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    ds = LeRobotDataset("local/sortbot", root=merged / "lerobot")
    assert ds.meta.total_episodes == 4 and len(ds) == 2 * result.frames
    assert sorted(p.name for p in (merged / "mcap").glob("*.mcap")) == [f"episode_00000{k}.mcap" for k in range(4)]
    assert main(["datasets", "merge", str(out), str(out), "--out", str(merged)]) == 2  # not over an existing one


def test_merge_keeps_what_sources_agree_on_so_a_mix_of_step_budgets_still_exports_cropped(collected, tmp_path, capsys):
    """A long-episode collection merged with a short-episode one differs only in the step budget:
    the merged record keeps their common workspace, so the pick-area crop is still known."""
    from sortbot.collect.runner import collect
    from sortbot.datasets.merge import MIXED, agreed
    from sortbot.perception.yolo_data import read_crop
    from conftest import small_env_config, small_request

    assert agreed([{"a": 1, "b": {"c": 2, "d": 3}}, {"a": 1, "b": {"c": 2, "d": 4}}]) == {"a": 1, "b": {"c": 2, "d": MIXED}}
    assert agreed([[1, 2], [1, 3]]) == MIXED and agreed([5, 5]) == 5
    out, _ = collected
    cfg = small_env_config()
    cfg.outcome.max_steps = 1
    short = tmp_path / "short"
    collect(small_request(short, episodes=1, seed=11, env_config=cfg))
    merged = tmp_path / "merged"
    assert main(["datasets", "merge", str(out), str(short), "--out", str(merged)]) == 0
    record = json.loads((merged / "lerobot" / "meta" / "sortbot.json").read_text())
    assert record["env_config"]["outcome"]["max_steps"] == MIXED
    assert record["env_config"]["workspace"] == json.loads((out / "lerobot" / "meta" / "sortbot.json").read_text())["env_config"]["workspace"]
    assert main(["datasets", "export-yolo", str(merged), "--out", str(tmp_path / "y"), "--val-fraction", "0.5"]) == 0
    assert main(["datasets", "export-yolo", str(out), "--out", str(tmp_path / "y1"), "--val-fraction", "0.5"]) == 0
    assert read_crop(tmp_path / "y" / "data.yaml") == read_crop(tmp_path / "y1" / "data.yaml")

    record["env_config"]["workspace"]["pick_min"] = MIXED  # sources with different pick areas: no one crop
    (merged / "lerobot" / "meta" / "sortbot.json").write_text(json.dumps(record))
    capsys.readouterr()
    assert main(["datasets", "export-yolo", str(merged), "--out", str(tmp_path / "y2")]) == 2
    assert "different pick areas" in capsys.readouterr().err


def test_push_dry_run_and_offline_error(collected, capsys, monkeypatch):
    out, _ = collected
    assert main(["datasets", "push", str(out), "--repo-id", "me/sortbot-test", "--dry-run"]) == 0
    listed = capsys.readouterr().out
    assert "meta/info.json" in listed and "would upload" in listed
    monkeypatch.setenv("HF_HUB_OFFLINE", "1")
    assert main(["datasets", "push", str(out), "--repo-id", "me/sortbot-test"]) == 2
    assert "--dry-run" in capsys.readouterr().err


def test_export_yolo_splits_by_episode(collected, tmp_path):
    out, _ = collected
    yolo = tmp_path / "yolo"
    assert main(["datasets", "export-yolo", str(out), "--out", str(yolo), "--val-fraction", "0.5", "--no-crop"]) == 0
    data = yaml.safe_load((yolo / "data.yaml").read_text())
    assert data["names"] == {0: "fork", 1: "knife", 2: "spoon", 3: "block"} and "crop" not in data
    train = sorted((yolo / "images" / "train").glob("*.jpg"))
    val = sorted((yolo / "images" / "val").glob("*.jpg"))
    assert train and val
    assert {p.name[:8] for p in train}.isdisjoint({p.name[:8] for p in val})  # no episode in both
    table = load_table(out / "lerobot")
    first = (yolo / "labels" / "train" / (train[0].stem + ".txt")).read_text().split("\n")
    rows = [list(map(float, line.split())) for line in first if line]
    labels = label_rows(table["observation.labels"][0])
    present = labels[labels[:, 0] > 0.5]
    assert len(rows) == len(present)
    cls, cx = rows[0][0], rows[0][1]
    x1, x2 = present[0][2], present[0][4]
    assert cls == present[0][1] and np.isclose(cx, (x1 + x2) / 2 / 320, atol=1e-5)


def test_export_yolo_crops_to_the_pick_area_and_clips_labels(collected, tmp_path):
    """The default export: frames cut to the pick area of the dataset's own camera, labels clipped
    to it and kept when 4 px remain; the crop is recorded for training, the detector and eval."""
    from PIL import Image

    from sortbot.datasets.yolo_export import YoloExportConfig
    from sortbot.perception.yolo_data import CropBox, read_crop

    out, _ = collected
    yolo = tmp_path / "yolo"
    assert main(["datasets", "export-yolo", str(out), "--out", str(yolo), "--val-fraction", "0.5"]) == 0
    crop = read_crop(yolo / "data.yaml")
    assert crop is not None and (crop.image_width, crop.image_height) == (320, 240)
    assert 0 < crop.width < 320 and 0 < crop.height < 240
    assert CropBox.from_record(json.loads((yolo / "split.json").read_text())) == crop
    table = load_table(out / "lerobot")
    frame0 = sorted((yolo / "images" / "train").glob("*.jpg"))[0]
    assert frame0.stem.endswith("f0000") and Image.open(frame0).size == (crop.width, crop.height)
    rows = [list(map(float, line.split())) for line in (yolo / "labels" / "train" / (frame0.stem + ".txt")).read_text().splitlines()]
    labels = label_rows(table["observation.labels"][0])
    keep = (YoloExportConfig.min_box_side, YoloExportConfig.min_inside_fraction)
    expected = [(row[1], crop.box_to_crop(row[2:6], *keep)) for row in labels if row[0] > 0.5]
    expected = [(k, b) for k, b in expected if b is not None]
    assert expected and len(rows) == len(expected)
    for (k, b), row in zip(expected, rows):
        x1, y1, x2, y2 = b
        assert row[0] == k and np.allclose(row[1:], [(x1 + x2) / 2 / crop.width, (y1 + y2) / 2 / crop.height,
                                                     (x2 - x1) / crop.width, (y2 - y1) / crop.height], atol=1e-5)
    whole = [row[2:6] for row in labels if row[0] > 0.5 and crop.x0 <= row[2] and row[4] <= crop.x1
             and crop.y0 <= row[3] and row[5] <= crop.y1]
    assert whole and all(np.allclose(crop.box_to_full(crop.box_to_crop(b)), b) for b in whole)  # the detector's shift back


def test_export_leaves_cutlery_lying_in_a_bin_unlabelled():
    """Sorted cutlery is no target: a fork whose centre lies in the fork bin gets no label, while a
    spoon in the pick area keeps its own; `--label-sorted` (label_sorted) labels both. The bins are
    the ones the dataset recorded."""
    from sortbot.config import WorkspaceConfig
    from sortbot.datasets.features import LABEL_COLUMNS
    from sortbot.datasets.yolo_export import BIN_FIELDS, dataset_workspace, yolo_lines
    from sortbot.types import CLASS_NAMES

    bins = {"fork": [0.0, 0.35, 0.0], "knife": [-0.35, 0.0, 1.5707963], "spoon": [0.0, -0.35, 0.0]}
    recorded = dataset_workspace({"env_config": {"workspace": {"bins": bins, "bin_inner_size": [0.2, 0.1]}}},
                                 BIN_FIELDS)
    assert recorded.bins["fork"] == (0.0, 0.35, 0.0) and recorded.bin_inner_size == (0.2, 0.1)
    rows = np.zeros((3, len(LABEL_COLUMNS)), np.float32)  # the third row: no object
    rows[0] = [1, CLASS_NAMES.index("spoon"), 100, 100, 160, 120, 0.30, 0.0, 0.005, 0.0]
    rows[1] = [1, CLASS_NAMES.index("fork"), 10, 10, 60, 30, 0.02, 0.38, 0.005, 0.0]  # in the recorded fork bin
    sorted_out = yolo_lines(rows.ravel(), 320, 240, 4, bins=recorded)
    assert [line.split()[0] for line in sorted_out] == [str(CLASS_NAMES.index("spoon"))]
    assert len(yolo_lines(rows.ravel(), 320, 240, 4)) == 2
    # with the default bins (y = 0.29 +- 0.055) that fork lies outside every bin: labelled
    assert len(yolo_lines(rows.ravel(), 320, 240, 4, bins=WorkspaceConfig())) == 2


def test_export_refuses_a_merge_whose_collections_have_different_bins():
    import pytest

    from sortbot.datasets.merge import MIXED
    from sortbot.datasets.yolo_export import BIN_FIELDS, dataset_workspace

    with pytest.raises(ValueError, match="different bins"):
        dataset_workspace({"env_config": {"workspace": {"bins": MIXED}}}, BIN_FIELDS)
