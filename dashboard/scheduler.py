"""Run scheduling for the served dashboard, free of Panel so that it can be tested on its own.

* One process-wide thread pool (:data:`EXECUTOR`) with as many workers as cores: runs from
  different sessions compute in parallel (the Numba kernels release the GIL).
* One :class:`LatestRun` per session: at most one run of the session computes at a time and
  at most one waits; a newer request replaces the waiting one, so dragging a slider or pressing
  an arrow key repeatedly never queues stale runs. A computing run may hand on parts of its
  outcome (:meth:`LatestRun.post`), shown before it ends.
* :func:`warm_up`: one cheap run when the server starts, so the kernels are compiled (or loaded
  from Numba's cache) before the first visitor asks for a result.
"""

from __future__ import annotations

import asyncio
import os
import threading
from collections.abc import Callable
from concurrent.futures import Executor, Future, ThreadPoolExecutor
from typing import Generic, TypeVar

from model.params import Scenario
from model.pipeline import run

Job = TypeVar("Job")
Outcome = TypeVar("Outcome")

EXECUTOR = ThreadPoolExecutor(max_workers=os.cpu_count() or 1, thread_name_prefix="pipeline")
"""Worker threads shared by every session of the server process."""


class RunCancelled(Exception):
    """Raised inside a computing run whose session has closed: the run stops there."""


_warm_up_lock = threading.Lock()
_warm_up_future: Future | None = None


def warm_up(task: Callable[[], object], executor: Executor = EXECUTOR) -> Future:
    """Start ``task`` once per process in ``executor``; every call returns the same future."""
    global _warm_up_future
    with _warm_up_lock:
        if _warm_up_future is None:
            _warm_up_future = executor.submit(task)
        return _warm_up_future


WARM_UP_PRESET = "single_bogie"


def warm_up_run() -> None:
    """One cheap run per tunnel–soil model: compiles (or loads from Numba's cache) every
    kernel of the pipeline.

    It lives here, in an imported module, not in the served app script: ``panel serve --warm``
    runs the script once in a session that is then destroyed, which clears that script's
    globals while this task may still be running.
    """
    scenario = Scenario.preset(WARM_UP_PRESET)
    scenario.numerics.n_depths = 11
    for model in ("2d", "2.5d"):
        scenario.tunnel.model = model
        run(scenario, cache=None)


def outcome_of(compute: Callable[[Job], Outcome], job: Job) -> Outcome | BaseException:
    """``compute(job)``, with an exception returned instead of raised (to be shown, not
    raised, by the caller)."""
    try:
        return compute(job)
    except Exception as error:  # noqa: BLE001
        return error


class LatestRun(Generic[Job, Outcome]):
    """One session's runs: one computing at a time, and only the newest request waiting.

    Parameters
    ----------
    compute : callable
        ``compute(job) -> outcome``, called in ``executor``; an exception it raises is passed
        on as the outcome (to be shown, not raised).
    executor : Executor
        Where runs compute (default: the shared :data:`EXECUTOR`).
    """

    def __init__(self, compute: Callable[[Job], Outcome], executor: Executor = EXECUTOR) -> None:
        self._compute = compute
        self._executor = executor
        self._lock = threading.Lock()
        self._waiting: Job | None = None
        self._has_waiting = False
        self._computing: tuple[Job, Future] | None = None
        """The job submitted by :meth:`request`, not yet taken by :meth:`drain`."""
        self._busy = False
        self._cancelled = False
        self._parts: list[object] = []
        """Parts of the computing job's outcome posted and not yet handed on."""
        self._wake: Callable[[], None] | None = None
        """Wakes the awaiting :meth:`drain` when a part is posted, while one runs."""

    @property
    def busy(self) -> bool:
        """True while a run computes or waits."""
        return self._busy

    def request(self, job: Job) -> bool:
        """Ask for ``job`` to run, replacing any job still waiting.

        Returns True when nothing was running: ``job`` then starts computing at once (before
        the caller's further work and the page's messages, which would otherwise delay it),
        and the caller must await :meth:`drain` for its outcome; False also after
        :meth:`cancel`, when the job is dropped.
        """
        with self._lock:
            if self._cancelled:
                return False
            if self._busy:
                self._waiting, self._has_waiting = job, True
                return False
            self._busy, self._parts = True, []
            self._computing = (job, self._submit(job))
            return True

    @property
    def cancelled(self) -> bool:
        """True once :meth:`cancel` was called."""
        return self._cancelled

    def stop_if_cancelled(self, where: str) -> None:
        """Stop the computing job here once :meth:`cancel` was called: its ``compute`` calls
        this where it can stop (e.g. at a progress report).

        Raises
        ------
        RunCancelled
            After :meth:`cancel`, naming ``where`` the job stopped.
        """
        if self._cancelled:
            raise RunCancelled(f"the session closed during {where}")

    def post(self, part: object) -> None:
        """Hand ``part`` of the computing job's outcome to :meth:`drain`, which passes it on
        as soon as it can (called by the job's ``compute``, in its worker thread). Dropped
        after :meth:`cancel`."""
        with self._lock:
            if self._cancelled:
                return
            self._parts.append(part)
            wake = self._wake
        if wake is not None:
            wake()

    def _take_parts(self) -> list[object]:
        """The parts posted since the last call."""
        with self._lock:
            parts, self._parts = self._parts, []
        return parts

    def cancel(self) -> None:
        """Drop the waiting job and every later request; the outcome of the job computing is
        not handed on (a closed session). The job itself stops where its ``compute`` calls
        :meth:`stop_if_cancelled`, else it finishes."""
        with self._lock:
            self._cancelled = True
            self._waiting, self._has_waiting = None, False

    def _submit(self, job: Job) -> Future:
        """Start computing ``job`` in the executor."""
        return self._executor.submit(outcome_of, self._compute, job)

    def _next(self) -> tuple[Job, Future] | None:
        """The job computing since its request, else the waiting job (started now), else None
        (the queue is marked idle)."""
        with self._lock:
            computing, self._computing = self._computing, None
            if computing is not None:
                return computing
            if not self._has_waiting:
                self._busy = False
                return None
            job, self._waiting, self._has_waiting = self._waiting, None, False
            self._parts = []
        return job, self._submit(job)

    async def drain(
        self,
        started: Callable[[Job], None],
        finished: Callable[[Job, Outcome | BaseException], None],
        tick: Callable[[], None] | None = None,
        poll_s: float = 0.1,
        posted: Callable[[Job, object], None] | None = None,
    ) -> None:
        """Compute jobs until none waits: ``started(job)`` (the job may be computing already,
        since its request), then ``finished(job, outcome)``.

        ``tick()`` is called every ``poll_s`` seconds while a job computes (progress display),
        not once it has finished. ``posted(job, part)`` is called for each part of its outcome
        the job hands on (:meth:`post`), as soon as it does, and before ``finished``.
        The callbacks run in the awaiting event loop, never in a worker thread.
        """
        loop, woken = asyncio.get_running_loop(), asyncio.Event()
        with self._lock:
            self._wake = lambda: loop.call_soon_threadsafe(woken.set)
        try:
            while (computing := self._next()) is not None:
                job, submitted = computing
                if not self._cancelled:
                    started(job)
                future = asyncio.wrap_future(submitted)
                while True:
                    for part in self._take_parts():  # posted before its outcome is ready
                        if posted is not None and not self._cancelled:
                            posted(job, part)
                    if future.done():
                        break
                    wake = asyncio.ensure_future(woken.wait())
                    done, _ = await asyncio.wait(
                        [future, wake], timeout=poll_s, return_when=asyncio.FIRST_COMPLETED
                    )
                    wake.cancel()
                    woken.clear()
                    # no progress shown once it is done: its results follow at once
                    if not done and tick is not None and not self._cancelled:
                        tick()
                if not self._cancelled:
                    finished(job, future.result())
        except BaseException:
            with self._lock:
                self._busy, self._waiting, self._has_waiting = False, None, False
                self._computing = None
            raise
        finally:
            with self._lock:
                self._wake = None
