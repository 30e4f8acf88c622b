"""`sortbot bench sim`: primitive actions per second with one RGB-D observation per action.

The oracle runs seeded 6-cutlery episodes; wall time is split into physics (primitives, through
the arm) and rendering (RGB + depth + segmentation + labels). Ratios printed side by side come
from the same run: against the 5 actions/s goal and the seed paper's 16 s per action.
"""

from __future__ import annotations

import time

from sortbot.config import EnvConfig
from sortbot.eval.rollout import run_episode
from sortbot.policies import make_policy
from sortbot.sim.env import SortingEnv

GOAL_ACTIONS_PER_S = 5.0
SEED_PAPER_S_PER_ACTION = 16.0


def bench_sim(episodes: int = 3, objects: int = 6, seed: int = 0, progress=None) -> dict:
    cfg = EnvConfig()
    cfg.scene.num_objects = objects
    policy = make_policy("oracle", cfg.gripper, cfg.workspace)
    actions, episode_wall, reset_wall = 0, 0.0, 0.0
    with SortingEnv(cfg) as env:
        for k in range(episodes):
            tally = run_episode(env, policy, seed + k)
            actions += tally.actions
            episode_wall += tally.wall_s
            if progress:
                progress(k + 1, episodes)
        # an episode's wall time includes its reset (scene build + settling); take it out
        for k in range(episodes):
            t0 = time.perf_counter()
            env.reset(seed=seed + k)
            reset_wall += time.perf_counter() - t0
        render_ms = env.render_seconds / env.observations * 1e3
        physics_ms = env.physics_seconds / max(1, actions) * 1e3
    wall = max(1e-9, episode_wall - reset_wall)
    per_s = actions / wall
    return {
        "episodes": episodes,
        "objects": objects,
        "actions": actions,
        "actions_per_s": per_s,
        "s_per_action": 1.0 / per_s,
        "render_ms_per_observation": render_ms,
        "physics_ms_per_action": physics_ms,
        "reset_s_per_episode": reset_wall / episodes,
        "ratio_to_goal_5_per_s": per_s / GOAL_ACTIONS_PER_S,
        "speedup_vs_seed_paper_16s_per_action": SEED_PAPER_S_PER_ACTION * per_s,
    }
