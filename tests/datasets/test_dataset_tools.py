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
    assert main(["datasets", "export-yolo", str(out), "--out", str(yolo), "--val-fraction", "0.5"]) == 0
    data = yaml.safe_load((yolo / "data.yaml").read_text())
    assert data["names"] == {0: "fork", 1: "knife", 2: "spoon", 3: "block"}
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
