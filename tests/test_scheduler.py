"""Run scheduling of the served dashboard (dashboard/scheduler.py), without Panel or a browser.

Jobs are plain values and ``compute`` functions are controlled with threading events, so every
test is deterministic: nothing depends on how long a computation takes.
"""

import asyncio
import threading
from concurrent.futures import ThreadPoolExecutor

import pytest

from dashboard import scheduler
from dashboard.scheduler import LatestRun


@pytest.fixture
def pool():
    with ThreadPoolExecutor(max_workers=2) as executor:
        yield executor


def _record(started, finished):
    return (lambda job: started.append(job)), (lambda job, out: finished.append((job, out)))


def test_a_request_while_idle_runs_at_once(pool):
    """A request while idle starts computing before anything drains the queue (the page's
    other work on a change does not delay the run)."""
    computing = threading.Event()

    def compute(job):
        computing.set()
        return job * 10

    runs = LatestRun(compute, pool)
    started, finished = [], []
    assert runs.request(1) is True
    assert computing.wait(timeout=60)
    asyncio.run(runs.drain(*_record(started, finished)))
    assert started == [1] and finished == [(1, 10)] and not runs.busy


def _drain_while_job_1_computes(runs, computed, release, meanwhile):
    """Request job 1, call ``meanwhile()`` once it computes and the drain has started it (it
    computes from its request on), then let it finish and drain the queue; returns the
    (started, finished) records."""
    started, finished = [], []

    async def scenario():
        assert runs.request(1)
        draining = asyncio.create_task(runs.drain(*_record(started, finished), poll_s=0.01))
        while not (computed and started):
            await asyncio.sleep(0.01)
        meanwhile()
        release.set()
        await draining

    asyncio.run(scenario())
    return started, finished


def test_newest_request_supersedes_a_waiting_one(pool):
    """While job 1 computes, jobs 2, 3, 4 are requested: only 4 runs after 1."""
    release = threading.Event()
    computed = []

    def compute(job):
        computed.append(job)
        if job == 1:
            assert release.wait(timeout=60)
        return job

    runs = LatestRun(compute, pool)

    def request_three_more():
        assert [runs.request(job) for job in (2, 3, 4)] == [False, False, False]

    _, finished = _drain_while_job_1_computes(runs, computed, release, request_three_more)
    assert computed == [1, 4] and [job for job, _ in finished] == [1, 4]
    assert not runs.busy


def test_an_exception_is_delivered_as_the_outcome(pool):
    def compute(job):
        raise ValueError(f"bad job {job}")

    runs = LatestRun(compute, pool)
    finished = []
    runs.request(7)
    asyncio.run(runs.drain(lambda job: None, lambda job, out: finished.append(out)))
    assert isinstance(finished[0], ValueError) and str(finished[0]) == "bad job 7"
    assert runs.request(8) is True  # the queue is usable again


def test_a_cancelled_queue_drops_its_waiting_job_and_the_computing_ones_outcome(pool):
    """A closed session (issue 29): while job 1 computes, job 2 waits; after cancel, job 2 is
    never computed, job 1's outcome is not handed on, and later requests are dropped."""
    release = threading.Event()
    computed = []

    def compute(job):
        computed.append(job)
        assert release.wait(timeout=60)
        return job

    runs = LatestRun(compute, pool)

    def request_then_cancel():
        assert runs.request(2) is False
        runs.cancel()

    started, finished = _drain_while_job_1_computes(runs, computed, release, request_then_cancel)
    assert computed == [1] and started == [1] and finished == [] and not runs.busy
    assert runs.request(3) is False and not runs.busy


def test_a_job_cancelled_before_the_drain_is_not_shown(pool):
    """A session closed between a request (its job computing at once) and the drain: the
    drain waits for the job but neither starts nor finishes it on the page."""
    runs = LatestRun(lambda job: job, pool)
    started, finished = [], []
    assert runs.request(1) is True
    runs.cancel()
    asyncio.run(runs.drain(*_record(started, finished)))
    assert started == [] and finished == [] and not runs.busy


def test_parts_of_an_outcome_are_handed_on_while_the_job_computes(pool):
    """``post`` from the computing job reaches ``posted`` at once, before the job ends (the
    page draws the first stages' plots meanwhile), in order, and never a progress tick."""
    seen, release = [], threading.Event()

    def compute(job):
        runs.post(("first part", job))
        runs.post(("second part", job))
        assert release.wait(timeout=60)  # ends only once both parts were handed on
        runs.post(("last part", job))  # posted as it ends: still before its outcome
        return job * 10

    def posted(job, part):
        seen.append(part)
        if len(seen) == 2:
            release.set()

    runs = LatestRun(compute, pool)
    ticks, finished = [], []
    assert runs.request(1)
    asyncio.run(
        runs.drain(
            lambda job: None,
            lambda job, outcome: finished.append((list(seen), outcome)),
            tick=lambda: ticks.append(1),
            poll_s=30.0,
            posted=posted,
        )
    )
    parts = [("first part", 1), ("second part", 1), ("last part", 1)]
    assert finished == [(parts, 10)] and ticks == []


def test_a_cancelled_jobs_parts_are_not_handed_on(pool):
    """A session closed while its job computes: what the job posts after that is dropped."""
    computed, release, seen = [], threading.Event(), []

    def compute(job):
        computed.append(job)
        assert release.wait(timeout=60)
        runs.post("after the close")
        return job

    runs = LatestRun(compute, pool)
    started, finished = [], []

    async def scenario():
        assert runs.request(1)
        draining = asyncio.create_task(
            runs.drain(
                *_record(started, finished),
                poll_s=0.01,
                posted=lambda job, part: seen.append(part),
            )
        )
        while not computed:
            await asyncio.sleep(0.01)
        runs.cancel()
        release.set()
        await draining

    asyncio.run(scenario())
    assert seen == [] and finished == []


def test_sessions_compute_in_parallel(pool):
    """Two sessions' runs overlap in time: each waits until the other has started (a barrier
    that a one-worker pool could never pass)."""
    barrier = threading.Barrier(2, timeout=60)

    def compute(job):
        barrier.wait()
        return job

    first, second = LatestRun(compute, pool), LatestRun(compute, pool)
    results = []

    async def both():
        first.request("a")
        second.request("b")
        record = lambda job, out: results.append(out)  # noqa: E731
        ignore = lambda job: None  # noqa: E731
        await asyncio.gather(first.drain(ignore, record), second.drain(ignore, record))

    asyncio.run(both())
    assert sorted(results) == ["a", "b"]


def test_the_shared_pool_has_a_worker_per_core():
    assert scheduler.EXECUTOR._max_workers == (scheduler.os.cpu_count() or 1)


def test_warm_up_runs_once_per_process(monkeypatch, pool):
    monkeypatch.setattr(scheduler, "_warm_up_future", None)
    calls = []
    first = scheduler.warm_up(lambda: calls.append(1), pool)
    second = scheduler.warm_up(lambda: calls.append(2), pool)
    first.result(timeout=60)
    assert first is second and calls == [1]
