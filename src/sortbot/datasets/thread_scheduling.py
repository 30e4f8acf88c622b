"""Keep video encoding from leaving the process on real-time scheduling.

SVT-AV1 (LeRobot's RGB encoder, inside PyAV) puts the thread that opens it on SCHED_FIFO at
priority 99 whenever it may, i.e. when run as root, and never puts it back: the recorder's main
thread, and every thread it starts afterwards (torch's OpenMP pool, Arrow's, Ray's), then runs
real-time. On a 2-core machine a few spinning real-time threads starve each other for minutes;
this is what hung CI in the detector tests after a collection. `scheduling_kept()` puts every
thread that turned real-time inside it back on the policy the calling thread had on entry.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

REAL_TIME_POLICIES = frozenset(getattr(os, name) for name in ("SCHED_FIFO", "SCHED_RR") if hasattr(os, name))
_TASKS = Path("/proc/self/task")


def _threads() -> list[int]:
    try:
        return [int(p.name) for p in _TASKS.iterdir()]
    except OSError:  # no /proc: not Linux, nothing to restore
        return []


def _policy(tid: int) -> int | None:
    try:
        return os.sched_getscheduler(tid)
    except OSError:  # the thread ended meanwhile
        return None


def real_time_threads() -> list[int]:
    """Ids of this process's threads that run on a real-time policy."""
    return [tid for tid in _threads() if _policy(tid) in REAL_TIME_POLICIES]


@contextmanager
def scheduling_kept() -> Iterator[None]:
    """Undo, on exit, any switch to real-time scheduling made inside by this thread or by
    threads it started; threads that were real-time already on entry are left as they were."""
    if not hasattr(os, "sched_getscheduler"):
        yield
        return
    policy, param = os.sched_getscheduler(0), os.sched_getparam(0)
    already = set(real_time_threads())
    try:
        yield
    finally:
        for tid in real_time_threads():
            if tid in already:
                continue
            try:
                os.sched_setscheduler(tid, policy, param)
            except OSError:  # ended meanwhile
                pass
