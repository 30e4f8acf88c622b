"""Run a policy in SortingEnv over seeded episodes and tally outcomes (the counts behind the
paper's metrics; the metrics module of the evaluation issue builds on these)."""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass, field

from sortbot.sim.env import SortingEnv
from sortbot.types import Primitive


@dataclass
class EpisodeTally:
    seed: int
    objects: int = 0
    sorted_correctly: int = 0
    actions: int = 0
    grasps: int = 0
    grasp_successes: int = 0
    well_placed: int = 0
    pushes: int = 0
    pushes_moved: int = 0
    changes_detected: int = 0
    unreachable: int = 0
    end_reason: str | None = None
    wall_s: float = 0.0


@dataclass
class RolloutSummary:
    episodes: list[EpisodeTally] = field(default_factory=list)

    def total(self, key: str) -> int:
        return sum(getattr(e, key) for e in self.episodes)

    def ratio(self, num: str, den: str) -> float:
        d = self.total(den)
        return self.total(num) / d if d else 0.0

    def as_dict(self) -> dict:
        return {
            "episodes": len(self.episodes),
            "objects": self.total("objects"),
            "sorted_correctly": self.total("sorted_correctly"),
            "sorted_fraction": self.ratio("sorted_correctly", "objects"),
            "actions": self.total("actions"),
            "grasp_success": self.ratio("grasp_successes", "grasps"),
            "well_placed_of_successful": self.ratio("well_placed", "grasp_successes"),
            "well_placed_of_grasps": self.ratio("well_placed", "grasps"),
            "push_moved": self.ratio("pushes_moved", "pushes"),
            "push_change_detected": self.ratio("changes_detected", "pushes"),
            "cleared": sum(e.end_reason == "cleared" for e in self.episodes),
            "per_episode": [asdict(e) for e in self.episodes],
        }


def run_episode(env: SortingEnv, policy, seed: int, privileged: bool = True) -> EpisodeTally:
    """One episode from `seed` (scene and policy randomness both seeded)."""
    t0 = time.perf_counter()
    obs = env.reset(seed=seed)
    policy.reset(seed)
    tally = EpisodeTally(seed=seed, objects=len(env.world.specs))
    done = env.stats.done
    while not done:
        action = policy.act(obs, env.privileged_state() if privileged else None)
        obs, out = env.step(action)
        done = out.done
        tally.actions += 1
        tally.unreachable += not out.executed
        if out.primitive == Primitive.GRASP:
            tally.grasps += 1
            tally.grasp_successes += out.grasp_success
            tally.well_placed += out.well_placed
        else:
            tally.pushes += 1
            tally.pushes_moved += out.push_moved
            tally.changes_detected += out.change_detected
    tally.end_reason = env.stats.end_reason
    tally.sorted_correctly = sum(s.status == f"bin:{s.cls}" for s in env.privileged_state())
    tally.wall_s = time.perf_counter() - t0
    return tally
