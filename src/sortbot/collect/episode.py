"""Run one seeded episode, logging it to MCAP as it runs, and return its LeRobot frames.

The episode's seed fixes the scene and the policy's randomness, so an episode collected twice
(or by another worker, or after `--resume`) is the same episode.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from sortbot.config import DatasetConfig, EnvConfig
from sortbot.datasets.features import camera_info, step_frame
from sortbot.datasets.mcap_writer import McapEpisodeLog
from sortbot.policies import make_policy
from sortbot.sim.env import SortingEnv


def episode_seed(base_seed: int, index: int) -> int:
    """Seed of episode `index` of a run started with `base_seed` (independent of workers)."""
    return int(np.random.SeedSequence([int(base_seed), int(index)]).generate_state(1)[0])


@dataclass
class EpisodeRecord:
    """A finished episode, ready to be committed to the LeRobot dataset."""

    index: int
    seed: int
    task: str
    frames: list[dict]
    meta: dict  # seed, scene, end reason, counts: one line of meta/sortbot_episodes.jsonl
    camera: dict  # intrinsics and pose for the dataset's metadata
    timings: dict = field(default_factory=dict)


def task_string(config: EnvConfig) -> str:
    return f"sort {config.scene.num_objects} {config.scene.object_set} objects into their bins"


def _scene_objects(states) -> list[dict]:
    """True object poses for the MCAP /scene topic: box markers centred on each object."""
    from scipy.spatial.transform import Rotation

    objects = []
    for s in states:
        size = s.spec.extent()
        up = Rotation.from_quat(s.quaternion, scalar_first=True).apply((0.0, 0.0, 1.0))  # body z axis
        objects.append({"instance_id": s.instance_id, "cls": s.cls, "status": s.status, "size": size,
                        "position": (s.position + up * size[2] / 2).tolist(), "quaternion": list(map(float, s.quaternion))})
    return objects


class EpisodeCollector:
    """Owns one env and one policy; collects episodes by index (one per call)."""

    def __init__(self, env_config: EnvConfig, policy: str, dataset_config: DatasetConfig, mcap_dir: Path,
                 base_seed: int, run_metadata: dict):
        self.env = SortingEnv(env_config)
        self.policy = make_policy(policy, env_config.gripper, env_config.workspace)
        self.dataset_config = dataset_config
        self.mcap_dir = Path(mcap_dir)
        self.base_seed = base_seed
        self.run_metadata = run_metadata

    def close(self) -> None:
        self.env.close()

    def collect(self, index: int) -> EpisodeRecord:
        seed = episode_seed(self.base_seed, index)
        t_start = time.perf_counter()
        env, cfg = self.env, self.dataset_config
        obs = env.reset(seed=seed)
        self.policy.reset(seed)
        scene = env.current_scene().to_dict()
        meta = {"seed": seed, "index": index, "scene": scene, "camera_pose": obs.camera_pose.matrix().tolist(), **self.run_metadata}
        path = self.mcap_dir / f"episode_{index:06d}.mcap"
        frames: list[dict] = []
        t_ns = int(round(scene.get("settle_time", 0.0) * 1e9))
        sorted_ok = 0
        with McapEpisodeLog(path, meta, cfg, overwrite=True) as log:  # an unfinished file from a killed run is redone
            states = env.privileged_state()  # one query per observation: logged, then shown to the policy
            log.log_observation(obs, _scene_objects(states), t_ns)
            while not env.stats.done:
                t0 = time.perf_counter()
                action = self.policy.act(obs, states)
                log.log_action(obs.step, action, t_ns)
                next_obs, outcome = env.step(action)
                frames.append(step_frame(obs, action, outcome, cfg))
                t_ns += int(round(outcome.sim_time_s * 1e9)) or 1
                states = env.privileged_state()
                log.log_observation(next_obs, _scene_objects(states), t_ns)
                log.log_outcome(obs.step, outcome, t_ns, time.perf_counter() - t0)
                obs = next_obs
            sorted_ok = sum(s.status == f"bin:{s.cls}" for s in states)
        record_meta = {"seed": seed, "actions": len(frames), "end_reason": env.stats.end_reason,
                       "objects": len(scene["objects"]), "sorted_correctly": sorted_ok, "mcap": path.name,
                       "scene": scene}
        return EpisodeRecord(index=index, seed=seed, task=task_string(env.config), frames=frames, meta=record_meta,
                             camera=camera_info(obs), timings={"collect_s": time.perf_counter() - t_start})
