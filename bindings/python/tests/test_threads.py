# SPDX-License-Identifier: MIT
"""Threads: thread pools give the serial results; the GIL is released; one Matcher is safe to share."""

from __future__ import annotations

import threading
import time
from concurrent.futures import ThreadPoolExecutor

import pytest

import kissm

import testdata
from helpers import assert_same_result

VOXEL = testdata.VOXEL_SIZE


@pytest.fixture(scope="module")
def serial(pairs) -> list[kissm.Result]:
    with kissm.Matcher(voxel_size=VOXEL, num_threads=1) as matcher:
        return [matcher.register(p.source, p.target) for p in pairs]


def test_serial_results_are_valid(serial) -> None:
    assert all(r.valid for r in serial)


def test_thread_pool_sharing_one_matcher_equals_serial(pairs, serial) -> None:
    jobs = list(range(len(pairs))) * 2
    with kissm.Matcher(voxel_size=VOXEL, num_threads=1) as matcher, ThreadPoolExecutor(4) as pool:
        results = list(pool.map(lambda i: matcher.register(pairs[i].source, pairs[i].target), jobs))
    for i, result in zip(jobs, results, strict=True):
        assert_same_result(result, serial[i])


def test_thread_pool_with_a_matcher_per_task_equals_serial(pairs, serial) -> None:
    def run(i: int) -> kissm.Result:
        return kissm.register(pairs[i].source, pairs[i].target, voxel_size=VOXEL, num_threads=2)

    with ThreadPoolExecutor(4) as pool:
        results = list(pool.map(run, range(len(pairs))))
    for result, expected in zip(results, serial, strict=True):
        assert_same_result(result, expected)


def test_features_shared_between_threads_and_matchers(pairs, serial) -> None:
    with kissm.Matcher(voxel_size=VOXEL) as describer:
        features = [(describer.compute_features(p.source), describer.compute_features(p.target)) for p in pairs]
    local = threading.local()

    def run(i: int) -> kissm.Result:
        if not hasattr(local, "matcher"):
            local.matcher = kissm.Matcher(voxel_size=VOXEL, num_threads=1)
        return local.matcher.register_features(*features[i])

    with ThreadPoolExecutor(3) as pool:
        results = list(pool.map(run, list(range(len(pairs))) * 3))
    for k, result in enumerate(results):
        assert_same_result(result, serial[k % len(pairs)])


@pytest.mark.parametrize("call", ["register", "refine"])
def test_the_gil_is_released_during_registration(pair, call: str) -> None:
    """While one thread registers (or refines), another keeps running Python code."""
    args = (pair.source, pair.target) + ((pair.transform,) if call == "refine" else ())
    with kissm.Matcher(voxel_size=VOXEL, num_threads=1) as matcher:
        run = getattr(matcher, call)
        measured = []
        # A busy machine may deschedule this thread for a while; a held GIL stalls every attempt.
        for _ in range(3):
            start = time.perf_counter()
            run(*args)
            duration = time.perf_counter() - start

            worker = threading.Thread(target=run, args=args)
            worker.start()
            last, longest_pause, ticks = time.perf_counter(), 0.0, 0
            while worker.is_alive():
                now = time.perf_counter()
                longest_pause, last, ticks = max(longest_pause, now - last), now, ticks + 1
            worker.join()
            measured.append((longest_pause, duration, ticks))
            # Holding the GIL for the whole call would stall this loop for about `duration`.
            if longest_pause < 0.6 * duration:
                return
    pytest.fail(f"the main thread stalled while {call} ran in another: (longest pause, duration, ticks) {measured}")


def test_one_matcher_runs_one_call_at_a_time(pair) -> None:
    """The per-matcher lock: close() waits for a running call instead of freeing the matcher under it."""
    matcher = kissm.Matcher(voxel_size=VOXEL, num_threads=1)
    outcome: list[kissm.Result] = []
    worker = threading.Thread(target=lambda: outcome.append(matcher.register(pair.source, pair.target)))
    worker.start()
    while not matcher._call_lock.locked() and worker.is_alive():
        time.sleep(0.0005)
    matcher.close()
    worker.join()
    assert matcher.closed and len(outcome) == 1 and outcome[0].valid
