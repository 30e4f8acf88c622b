"""Writing a dataset leaves no thread of the process on real-time scheduling (SVT-AV1 switches
the encoding thread to SCHED_FIFO 99 when run as root, which starved the detector tests in CI)."""

import os
import threading

import pytest

from sortbot.datasets.thread_scheduling import real_time_threads, scheduling_kept


def test_a_real_time_switch_inside_is_undone_for_the_thread_and_what_it_started():
    before = os.sched_getscheduler(0)
    started, release = threading.Event(), threading.Event()
    worker = threading.Thread(target=lambda: (started.set(), release.wait(10)))
    with scheduling_kept():
        try:
            os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(1))  # what SVT-AV1 does as root
        except PermissionError:
            pytest.skip("this user may not switch to real-time scheduling, so no encoder can either")
        worker.start()  # inherits SCHED_FIFO, like the encoder's and any pool's threads
        started.wait(10)
        assert len(real_time_threads()) == 2
    try:
        assert os.sched_getscheduler(0) == before
        assert os.sched_getscheduler(worker.native_id) == before  # a thread started inside, still alive
        assert real_time_threads() == []
    finally:
        release.set()
        worker.join()


def test_collecting_a_dataset_leaves_no_real_time_threads(collected):
    out, result = collected
    assert result.episodes == 2 and (out / "lerobot" / "meta" / "info.json").is_file()
    assert real_time_threads() == []  # the fixture ran lerobot's AV1 encoder in this process
