"""Where episodes run: in this process, in K local processes, or in K Ray actors.

Every engine yields finished episodes in index order, whatever order the workers finish in, so
the dataset's episode order does not depend on the number of workers or the engine. At most
`2 * workers` episodes are in flight, which bounds the memory held by finished-but-unwritten ones.
"""

from __future__ import annotations

import itertools
import multiprocessing
import os
from collections import deque
from collections.abc import Iterable, Iterator
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass

from sortbot.collect.episode import EpisodeCollector, EpisodeRecord

ENGINES = ("local", "ray")
IN_FLIGHT_PER_WORKER = 2


@dataclass
class CollectorSpec:
    """Everything a worker needs to build its own EpisodeCollector (picklable)."""

    env_config: object
    policy: str
    dataset_config: object
    mcap_dir: str
    base_seed: int
    run_metadata: dict

    def build(self) -> EpisodeCollector:
        return EpisodeCollector(self.env_config, self.policy, self.dataset_config, self.mcap_dir,
                                self.base_seed, self.run_metadata)


def _in_order(submit, indices: Iterable[int], limit: int) -> Iterator[EpisodeRecord]:
    """Submit episodes in index order, at most `limit` ahead; yield their records in the same
    order. `submit(i)` starts episode i and returns a callable that waits for its record."""
    pending: deque = deque()
    for index in indices:
        pending.append(submit(index))
        if len(pending) >= limit:
            yield pending.popleft()()
    while pending:
        yield pending.popleft()()


# -- local processes ----------------------------------------------------------------------------
_WORKER: EpisodeCollector | None = None


def _init_worker(spec: CollectorSpec) -> None:
    import sortbot.sim  # noqa: F401  (GL backend before mujoco)

    global _WORKER
    _WORKER = spec.build()


def _collect_in_worker(index: int) -> EpisodeRecord:
    assert _WORKER is not None, "worker not initialised"
    return _WORKER.collect(index)


def run_local(spec: CollectorSpec, indices: Iterable[int], workers: int) -> Iterator[EpisodeRecord]:
    if workers <= 1:
        collector = spec.build()
        try:
            for index in indices:
                yield collector.collect(index)
        finally:
            collector.close()
        return
    # spawn, not fork: a forked MuJoCo/EGL context is not safe to reuse
    ctx = multiprocessing.get_context("spawn")
    pool = ProcessPoolExecutor(max_workers=workers, mp_context=ctx, initializer=_init_worker, initargs=(spec,))
    try:
        yield from _in_order(lambda index: pool.submit(_collect_in_worker, index).result, indices,
                             workers * IN_FLIGHT_PER_WORKER)
    finally:
        pool.shutdown(wait=True, cancel_futures=True)  # a stopped run does not wait for queued episodes


# -- Ray actors ---------------------------------------------------------------------------------
def run_ray(spec: CollectorSpec, indices: Iterable[int], workers: int, address: str | None = None) -> Iterator[EpisodeRecord]:
    """K Ray actors, each with its own env. `address=None` starts a local Ray instance; pass the
    address printed by `ray start --head` (or set RAY_ADDRESS) to use a cluster."""
    os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")  # no phoning home
    import ray

    started_here = not ray.is_initialized()
    if started_here:
        address = address or os.environ.get("RAY_ADDRESS")
        if address:
            ray.init(address=address, log_to_driver=False)
        else:
            ray.init(num_cpus=max(workers, 1), include_dashboard=False, log_to_driver=False)

    @ray.remote(num_cpus=1)
    class CollectorActor:
        def __init__(self, spec: CollectorSpec):
            _init_worker(spec)

        def collect(self, index: int) -> EpisodeRecord:
            return _collect_in_worker(index)

    actors = [CollectorActor.remote(spec) for _ in range(max(workers, 1))]
    turn = itertools.cycle(actors)
    try:
        def submit(index: int):
            ref = next(turn).collect.remote(index)
            return lambda: ray.get(ref)

        yield from _in_order(submit, indices, len(actors) * IN_FLIGHT_PER_WORKER)
    finally:
        for actor in actors:
            ray.kill(actor)
        if started_here:
            ray.shutdown()
