"""Workers and Ray actors give the same dataset, in the same order, as one process."""

import numpy as np
import pytest
from conftest import small_request

from sortbot.collect.runner import collect


def _columns(root):
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    table = LeRobotDataset("local/sortbot", root=root).hf_dataset.with_format("numpy")
    return {k: np.asarray(table[k]) for k in ("episode_index", "action", "observation.labels", "next.reward",
                                             "outcome.grasp_success", "outcome.push_moved")}


@pytest.mark.parametrize("engine", ["local", "ray"])
def test_two_workers_match_one(collected, tmp_path, engine):
    out, _ = collected
    result = collect(small_request(tmp_path / engine, workers=2, engine=engine))
    assert result.episodes == 2
    one, two = _columns(out / "lerobot"), _columns(tmp_path / engine / "lerobot")
    for key in one:
        np.testing.assert_array_equal(one[key], two[key], err_msg=f"{key} differs with {engine} x2")
