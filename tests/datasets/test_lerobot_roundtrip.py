"""What `collect` writes reopens in stock lerobot and equals what the env returned."""

import numpy as np
from conftest import COLLECT_SEED, small_env_config

from sortbot.collect.episode import episode_seed
from sortbot.datasets.features import DEPTH_KEY, LABELS_KEY, RGB_KEY, encode_labels
from sortbot.datasets.lerobot_store import read_collection, read_episode_records
from sortbot.policies import make_policy
from sortbot.sim.env import SortingEnv


def _rerun_episode(index: int):
    """The same episode, run directly in a fresh env: observations, actions, outcomes."""
    cfg = small_env_config()
    cfg.scene.num_objects = 3
    seed = episode_seed(COLLECT_SEED, index)
    policy = make_policy("oracle", cfg.gripper, cfg.workspace)
    steps = []
    with SortingEnv(cfg) as env:
        obs = env.reset(seed=seed)
        policy.reset(seed)
        while not env.stats.done:
            action = policy.act(obs, env.privileged_state())
            nxt, out = env.step(action)
            steps.append((obs, action, out))
            obs = nxt
    return steps


def test_dataset_reopens_in_stock_lerobot_and_matches_the_env(collected):
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    out, result = collected
    root = out / "lerobot"
    ds = LeRobotDataset("local/sortbot", root=root)  # stock lerobot, nothing of ours
    assert ds.meta.total_episodes == 2 == result.episodes
    assert len(ds) == result.frames
    assert ds.meta.info.features[DEPTH_KEY]["info"]["is_depth_map"] is True
    assert ds.meta.info.features[RGB_KEY]["info"]["camera.fx"] == 618.62 / 2
    assert read_collection(root)["seed"] == COLLECT_SEED
    assert [r["episode_index"] for r in read_episode_records(root)] == [0, 1]

    steps = _rerun_episode(0)
    ep0 = [i for i in range(len(ds)) if int(ds.hf_dataset[i]["episode_index"]) == 0]
    assert len(ep0) == len(steps)
    quantum_mm = (1.5 - 0.1) / 4095 * 1000
    for i, (obs, action, outcome) in zip(ep0, steps):
        item = ds[i]
        np.testing.assert_allclose(item["action"].numpy(), action.as_array(), atol=1e-6)
        np.testing.assert_allclose(item[LABELS_KEY].numpy(), encode_labels(obs, 10).reshape(-1), atol=1e-5)
        assert bool(item["outcome.grasp_success"]) == outcome.grasp_success
        assert bool(item["outcome.push_moved"]) == outcome.push_moved
        assert bool(item["outcome.well_placed"]) == outcome.well_placed
        assert bool(item["next.done"]) == outcome.done
        assert float(item["next.reward"]) == np.float32(outcome.reward)
        depth_mm = item[DEPTH_KEY].numpy()[0]  # lerobot returns depth in millimetres
        err = np.abs(depth_mm - obs.depth * 1000)
        # the 12-bit depth video decodes within 1.5 quanta (0.5 mm), unbiased
        assert err.max() <= 2 * quantum_mm and err.mean() <= quantum_mm
        rgb = (item[RGB_KEY].permute(1, 2, 0).numpy() * 255)
        assert np.abs(rgb - obs.rgb).mean() < 6, "RGB video is lossy but close"
