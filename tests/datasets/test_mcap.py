"""The per-episode MCAP reads back with the `mcap` reader: every topic, Foxglove schema names,
exact depth, and a damaged file gives what could be read plus a clear error."""

import numpy as np
import pytest

from sortbot.datasets.mcap_reader import McapReadError, read_episode
from sortbot.datasets.mcap_writer import ALL_TOPICS

SCHEMAS = {
    "/camera/rgb": "foxglove.CompressedImage", "/camera/depth": "foxglove.RawImage",
    "/camera/calibration": "foxglove.CameraCalibration", "/tf": "foxglove.FrameTransforms",
    "/scene": "foxglove.SceneUpdate", "/labels": "sortbot.Labels", "/action": "sortbot.Action",
    "/outcome": "sortbot.Outcome",
}


def test_mcap_reads_back_with_every_topic(collected):
    out, _ = collected
    log = read_episode(out / "mcap" / "episode_000000.mcap")
    assert log.error is None and log.complete
    assert log.schemas == SCHEMAS
    assert set(log.counts) == set(ALL_TOPICS)
    n = len(log.actions)
    assert n == len(log.outcomes) >= 1
    assert len(log.observations) == n + 1  # the first observation and one after every action
    assert log.metadata["seed"] > 0 and log.metadata["policy"] == "oracle"
    assert len(log.metadata["scene"]["objects"]) == 3
    obs = log.observations[0]
    assert obs.rgb().shape == (240, 320, 3)
    depth = obs.depth()
    assert depth.dtype == np.float32 and 0.4 < float(np.median(depth)) < 1.2  # metres
    assert list(log.calibration.K)[0] == pytest.approx(618.62 / 2)
    assert {o["instance_id"] for o in obs.labels["objects"]} <= {1, 2, 3}
    assert log.outcomes[-1]["done"] is True


def test_truncated_mcap_keeps_what_came_before(collected, tmp_path):
    out, _ = collected
    data = (out / "mcap" / "episode_000000.mcap").read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: len(data) // 2])
    log = read_episode(cut)
    assert log.error is not None and "cut short" in log.error
    assert not log.complete
    assert len(log.observations) >= 1 and log.observations[0].rgb().shape == (240, 320, 3)


def test_garbage_is_not_an_mcap(tmp_path):
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(b"not an mcap at all")
    with pytest.raises(McapReadError, match="not a readable MCAP"):
        read_episode(bad)


def test_closed_logs_do_not_pile_up_in_foxglove(tmp_path):
    """foxglove-sdk keeps every Channel in a module dict; a long collection must not grow it."""
    from foxglove import channel as fox_channel

    from sortbot.datasets.mcap_writer import McapEpisodeLog

    before = len(fox_channel._channels_by_id)
    for k in range(5):
        with McapEpisodeLog(tmp_path / f"{k}.mcap", {"seed": k}):
            pass
    assert len(fox_channel._channels_by_id) == before
