import json

import numpy as np
from PIL import Image

from sortbot.cli import main


def test_snapshot_writes_images_and_refuses_to_overwrite(tmp_path, capsys):
    out = tmp_path / "snap"
    assert main(["sim", "snapshot", "--seed", "2", "--objects", "3", "--out", str(out)]) == 0
    rgb = np.array(Image.open(out / "rgb.png"))
    depth = np.array(Image.open(out / "depth.png"))
    assert rgb.shape == (480, 640, 3) and depth.dtype == np.uint16 and depth.max() > 0
    labels = json.loads((out / "labels.json").read_text())["labels"]
    assert len(labels) == 3
    before = (out / "rgb.png").read_bytes()
    assert main(["sim", "snapshot", "--seed", "3", "--out", str(out)]) == 2
    assert "--overwrite" in capsys.readouterr().err
    assert (out / "rgb.png").read_bytes() == before  # nothing written was lost


def test_bad_scene_file_is_a_clear_error(tmp_path, capsys):
    bad = tmp_path / "bad.json"
    bad.write_text('{"no_objects": 1}')
    assert main(["sim", "snapshot", "--scene", str(bad), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "not a valid scene" in err and err.count("\n") == 1
    assert main(["sim", "snapshot", "--scene", str(tmp_path / "missing.json"), "--out", str(tmp_path / "o")]) == 2


def test_run_prints_sorting_summary(capsys):
    assert main(["sim", "run", "--policy", "oracle", "--episodes", "1", "--objects", "3", "--seed", "1", "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["episodes"] == 1 and result["objects"] == 3 and 0 <= result["sorted_fraction"] <= 1


def test_bench_sim_json_has_actions_per_s(capsys):
    assert main(["bench", "sim", "--episodes", "1", "--objects", "3", "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["actions_per_s"] > 0 and result["render_ms_per_observation"] > 0


def test_zero_episodes_is_rejected(capsys):
    assert main(["sim", "run", "--episodes", "0"]) == 2
