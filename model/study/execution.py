"""Running a study on Dask distributed: the task, the client, progress and cancelling.

Every run is the task :func:`run_summary`, a pure function of the scenario's JSON, so a worker
anywhere computes exactly what :func:`model.pipeline.run` computes in-process. Runs go to a
``LocalCluster`` sized to this machine by default, or an existing scheduler
(``tcp://host:port``, argument or ``TUNNELSETTLE_SCHEDULER``).
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import contextlib
import logging
import multiprocessing
import os
import queue
import re
import threading
import time
import uuid
from collections.abc import Callable, Iterable
from typing import Any

import dask
import numba
import pandas as pd

# Imported with the module, not when the first study starts: the import takes ~0.25 s, which
# is the process's once, not a study's.
from distributed import Client, LocalCluster
from distributed.comm import connect
from distributed.nanny import WorkerProcess
from distributed.versions import get_versions

from model.params import Scenario
from model.pipeline import StageCache, prefetch_transfer, run
from model.study.definition import Study, check_run_count, define_study
from model.study.tables import PROFILE_COLUMN

SCHEDULER_ENV = "TUNNELSETTLE_SCHEDULER"
"""Environment variable with the address of an existing Dask scheduler to use by default."""
CONNECT_TIMEOUT_S = 5.0
CANCEL_WAIT_S = 300.0  # a cancelled task already executing is waited for, at most this long
POLL_S = 0.05  # how often the collecting loop looks at the cancel flag when nothing finished
NANNY_POLL_S = 0.005
"""How often a LocalCluster's nanny looks whether its new worker has connected (s). Dask's 50 ms
(``WorkerProcess._init_msg_interval``) held a forked worker, ready ~30 ms after the fork, until
the next look: a new cluster of two came up in 0.08 s, 0.05 s at this interval."""
LOCAL_CLUSTER_CONFIG = {
    # Diagnostics read only by Dask's dashboard, which a study's LocalCluster does not start:
    # the workers' statistical profiler (a stack sample every 10 ms), the event-loop tick
    # (every 20 ms in each server) and the system monitor (every 0.5 s).
    "distributed.worker.profile.enabled": False,
    "distributed.admin.tick.interval": "200ms",
    "distributed.admin.system-monitor.interval": "2s",
    # The nannies look at their workers' memory every 0.5 s, not 0.1 s: a run's memory is
    # bounded before it starts (model.run_cost.estimate_run).
    "distributed.worker.memory.monitor-interval": "500ms",
}
"""Dask settings of a study's own LocalCluster (an existing scheduler keeps its own). Idle, the
calling process spent 19–28 ms of CPU per second and each worker 17–20 with Dask's, 12 and 5
with these; a cold 10-run study of the paper case took 1.94 s against 2.06 s (medians of 12
alternated studies in one process)."""
_ADDRESS_RE = re.compile(r"^(tcp|tls|ucx|ws|wss)://[^\s:/]+:\d+$")
# The package versions each new worker reports when it registers, and the scheduler its own:
# Dask looks them up once per process (~10 ms). Looked up here, once, the forked workers
# inherit them: a process's first LocalCluster came up 0.01–0.015 s sooner.
get_versions()

Progress = Callable[[int, int, dict[str, Any]], None]
"""Called with (runs done, runs in all, the finished run's row) as each run comes back."""
Record = Callable[[int, dict[str, Any]], None]
"""Called with (the run's place in the study, its row) as each run comes back: to save it."""

# The process's last run, stages and tunnel–soil transfer functions: a study's runs that differ
# only in the load (seeds, vehicle, track) reuse the soil kernel, the costliest part after the
# vehicle–track integration. The values are those of a fresh run (the cache serves exactly what
# it would compute), so each row still equals run(scenario) bit for bit.
_TASK_CACHE = StageCache(size=1, transfer_size=1)


# ---- the task ------------------------------------------------------------------------------
def run_summary(scenario_json: str, depth_profile: bool = False) -> dict[str, float]:
    """Run one scenario and return its summary numbers (the task of a study).

    Parameters
    ----------
    scenario_json : str
        :meth:`Scenario.to_json` text; the run depends on nothing else.
    depth_profile : bool
        Also return the peak displacement at every output depth, as columns
        ``profile_peak_disp_<depth>m_m`` (m).

    Returns
    -------
    dict
        :meth:`Results.summary` (SI units), plus the depth profile if asked.
    """
    scenario = Scenario.from_json(scenario_json)
    results = run_in_worker(scenario)
    row = results.summary(scenario)  # the scenario parsed once (milliseconds per run)
    if depth_profile:
        soil = results.soil
        for depth, peak in zip(soil.depth_m, soil.peak_disp_m, strict=True):
            row[PROFILE_COLUMN.format(depth=float(depth))] = float(peak)
    return row


def run_in_worker(scenario: Scenario):
    """:func:`model.pipeline.run` as a task runs it: one Numba thread, the worker's stage cache.

    Parameters
    ----------
    scenario : Scenario
        The run's inputs.

    Returns
    -------
    Results
        Equal to ``run(scenario)`` in-process, bit for bit (the cache serves what a fresh run
        computes); runs that differ from the worker's last one only downstream of a stage
        reuse that stage.
    """
    # Parallelism comes from running many tasks at once, one per worker thread: Numba's prange
    # kernels use one thread per task so they do not oversubscribe the cores (Dask's nanny
    # already sets OMP/MKL/OpenBLAS to one thread per worker process). Setting it here, rather
    # than NUMBA_NUM_THREADS in the worker's environment, also holds on workers started by hand.
    numba.set_num_threads(1)
    return run(scenario, cache=_TASK_CACHE)


# ---- running -------------------------------------------------------------------------------
def machine_workers() -> int:
    """Cores this process may use: the LocalCluster's number of single-threaded workers."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


@contextlib.contextmanager
def study_client(
    scheduler=None, n_workers: int | None = None, connect_timeout_s: float | None = None
):
    """A Dask client: the given one, one on an existing scheduler, or one on a new LocalCluster.

    ``scheduler`` is a ``distributed.Client`` (used as is, not closed), a scheduler address
    ``"tcp://host:port"``, or ``None``: then ``$TUNNELSETTLE_SCHEDULER`` if set, else a
    ``LocalCluster`` of ``n_workers`` (default: the machine's cores) single-threaded worker
    processes (forked, :func:`worker_start_method`; no diagnostics dashboard, nor the
    diagnostics only it reads: :data:`LOCAL_CLUSTER_CONFIG`), closed on exit.
    An unreachable address is a one-line ``ValueError``.
    """
    if isinstance(scheduler, Client):
        yield scheduler
        return
    address = _scheduler_address(scheduler)
    connect_timeout_s = CONNECT_TIMEOUT_S if connect_timeout_s is None else connect_timeout_s
    if address:
        if not isinstance(address, str) or not _ADDRESS_RE.match(address):
            raise ValueError(f"scheduler address {address!r} is not of the form tcp://host:port")
        check_scheduler(address, connect_timeout_s)
        try:
            client = Client(address, timeout=connect_timeout_s, set_as_default=False)
        except (OSError, TimeoutError) as error:
            message = " ".join(str(error).split()) or type(error).__name__
            raise ValueError(
                f"cannot reach the Dask scheduler at {address} within {connect_timeout_s:g} s "
                f"({message})"
            ) from None
        with client:
            yield client
        return
    with (
        dask.config.set(
            {
                **LOCAL_CLUSTER_CONFIG,
                "distributed.worker.multiprocessing-method": worker_start_method(),
            }
        ),
        _local_cluster(n_workers or machine_workers()) as cluster,
        Client(cluster, set_as_default=False) as client,
    ):
        yield client


def _scheduler_address(scheduler: str | None) -> str | None:
    """The address :func:`study_client` connects to, or None for a new LocalCluster."""
    return scheduler or os.environ.get(SCHEDULER_ENV) or None


_ENVIRONMENT_LOCK = threading.Lock()


def _local_cluster(n_workers: int) -> LocalCluster:
    """A started LocalCluster of ``n_workers`` single-threaded worker processes, this process's
    environment left as it was.

    Each of Dask's nannies writes its worker's variables into this process's ``os.environ``
    before it starts the worker (one thread for OpenMP, MKL and OpenBLAS, a malloc trim
    threshold, a hash seed), and leaves them there: every process this one started afterwards
    (a script's own subprocesses, a later cluster's spawned workers) inherited them. They are
    put back once the workers run; a nanny that restarts a crashed worker writes them again.
    Clusters start one at a time, so each sees the environment as it was. The nannies look for
    their new workers every :data:`NANNY_POLL_S`.
    """
    with _ENVIRONMENT_LOCK:
        environment = dict(os.environ)
        if hasattr(WorkerProcess, "_init_msg_interval"):  # a private attribute: only if there
            WorkerProcess._init_msg_interval = NANNY_POLL_S
        try:
            return LocalCluster(
                n_workers=n_workers,
                threads_per_worker=1,
                processes=True,
                dashboard_address=None,  # its Bokeh server would add ~0.6 s to every start
                silence_logs=logging.ERROR,
            )
        finally:
            for name in set(os.environ) - set(environment):
                del os.environ[name]
            os.environ.update(environment)


def worker_start_method() -> str:
    """How the LocalCluster starts its worker processes: ``"fork"`` where the platform has it.

    A forked worker starts with this process's imported modules and loaded Numba kernels, in
    a few milliseconds, where a spawned one imports Python, Dask and the model afresh and loads
    every kernel from the disk cache (seconds, on every worker, before its first run). A forked
    process runs the serial compilation of the one parallel kernel
    (:mod:`model.soil.section_2d`), so it never enters the OpenMP threads this process may
    have started. ``"spawn"`` elsewhere (macOS, Windows: Python's default there).
    """
    return "fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn"


def check_scheduler(address: str, timeout_s: float) -> None:
    """Refuse, within ``timeout_s``, an address where no Dask scheduler answers.

    Dask's client waits past its timeout for a server that accepts the connection but never
    speaks Dask's protocol (and may try to allocate a frame length read from other bytes), so
    the scheduler's ``identity`` is asked first, in a thread of its own, bounded in time.

    Raises
    ------
    ValueError
        Nothing listens, nothing answers in time, or what answers is not a Dask scheduler.
    """
    pool = concurrent.futures.ThreadPoolExecutor(1)
    asked = pool.submit(asyncio.run, _scheduler_identity(address, timeout_s))
    try:
        identity = asked.result(timeout=timeout_s + 1.0)
    except (concurrent.futures.TimeoutError, TimeoutError):
        identity = "the server there accepted the connection but gave no Dask answer"
    except OSError as error:  # nothing listens, or the connection failed
        identity = " ".join(str(error).split()) or type(error).__name__
    except Exception as error:  # noqa: BLE001 — whatever a server of another protocol provokes
        identity = f"the server there does not speak Dask's protocol: {type(error).__name__}"
    finally:
        pool.shutdown(wait=False)
    if isinstance(identity, dict) and identity.get("type") == "Scheduler":
        return
    if not isinstance(identity, str):
        identity = "the server there is not a Dask scheduler"
    raise ValueError(
        f"cannot reach the Dask scheduler at {address} within {timeout_s:g} s ({identity})"
    )


async def _scheduler_identity(address: str, timeout_s: float):
    """The ``identity`` reply of the server at ``address`` (Dask's comm protocol)."""
    comm = await asyncio.wait_for(connect(address, timeout=timeout_s), timeout_s)
    try:
        await asyncio.wait_for(comm.write({"op": "identity", "reply": True}), timeout_s)
        return await asyncio.wait_for(comm.read(), timeout_s)
    finally:
        comm.abort()


def run_study(
    base: Scenario,
    vary: dict[str, Any],
    seeds: Iterable[int] | None = None,
    scheduler=None,
    *,
    sampling: str = "grid",
    n_samples: int | None = None,
    sampling_seed: int = 0,
    depth_profile: bool = False,
    progress: Progress | None = None,
    cancel: threading.Event | None = None,
    confirm: bool = False,
    n_workers: int | None = None,
    connect_timeout_s: float | None = None,
) -> pd.DataFrame:
    """Run a study on Dask and return one row per run.

    Parameters
    ----------
    base, vary, seeds, sampling, n_samples, sampling_seed, depth_profile
        The study, see :func:`define_study`.
    scheduler : None, str or distributed.Client
        See :func:`study_client`.
    progress : callable(done, total, row), optional
        Called in this thread as each run comes back (in completion order).
    cancel : threading.Event, optional
        Set it (from any thread) to stop: unfinished runs are cancelled and the finished ones
        returned, with ``table.attrs["cancelled"] = True``.
    confirm : bool
        Required for more than :data:`MAX_RUNS_UNCONFIRMED` runs.
    n_workers : int, optional
        Workers of the LocalCluster (default: the machine's cores).
    connect_timeout_s : float, optional
        How long to try an existing scheduler's address (s), default :data:`CONNECT_TIMEOUT_S`.

    Returns
    -------
    pandas.DataFrame
        Index ``run`` (the run's place in the study); columns: each varied parameter by its
        dotted path, ``seed``, every key of :meth:`Results.summary` (SI units), the depth
        profile if asked, and ``error`` (the message, empty when the run succeeded) only if a
        run failed. ``attrs``: ``study`` (definition JSON), ``n_runs``, ``cancelled``.

    Raises
    ------
    ValueError
        Bad study (see :func:`define_study`), too many runs without ``confirm``, unreachable
        scheduler: before any run is submitted.
    """
    study = define_study(
        base, vary, seeds, sampling, n_samples, sampling_seed, depth_profile, confirm
    )
    return execute_study(
        study,
        scheduler,
        progress=progress,
        cancel=cancel,
        confirm=confirm,
        n_workers=n_workers,
        connect_timeout_s=connect_timeout_s,
    )


def execute_study(
    study: Study,
    scheduler=None,
    *,
    progress: Progress | None = None,
    cancel: threading.Event | None = None,
    confirm: bool = False,
    n_workers: int | None = None,
    connect_timeout_s: float | None = None,
    record: Record | None = None,
) -> pd.DataFrame:
    """Run a checked :class:`Study` (e.g. from :meth:`Study.from_json`); see :func:`run_study`.

    ``record(run, row)`` is called as each run comes back (after ``progress``), so a caller can
    save finished runs at once: a second Ctrl-C (KeyboardInterrupt while the cancelled runs
    stop) raises out of this function, and the rows recorded are then all there is.
    """
    check_run_count(study.n_runs, confirm)
    new_cluster = not isinstance(scheduler, Client) and _scheduler_address(scheduler) is None
    prefetched = new_cluster and _prefetch_before_fork(study)
    with study_client(scheduler, n_workers, connect_timeout_s) as client:
        if prefetched:  # the forked workers have their copy: this process keeps none (tens of MB)
            _TASK_CACHE.clear()
        rows, cancelled = _collect(client, study, progress, cancel, record)
    return study_table(study, rows, cancelled)


def _prefetch_before_fork(study: Study) -> bool:
    """Compute the tunnel–soil transfer functions of the study's first run into this process's
    task cache before a new LocalCluster forks its workers (nothing where workers spawn);
    True when they are there.

    The workers inherit them, so the runs at that point (all the runs of a seeds-only study)
    reuse them from the first on; otherwise every worker's first run computed them, the same
    work on every core at once, one thread each. On the paper case with two workers: 0.055 s
    here against ~0.1 s more in each worker's first run; a cold 10-run study 0.04 s faster
    (median of 8 alternated pairs, 7 faster). Inputs that a run refuses are left to its row.
    """
    if worker_start_method() != "fork":
        return False
    _, scenario_json = next(study.runs())
    try:
        prefetch_transfer(Scenario.from_json(scenario_json), _TASK_CACHE)
    except ValueError:
        return False
    return True


SEED_ROUNDS = 3
"""The runs are submitted in this many rounds, each a share of the seeds at every point: a
study cancelled after its first round has results across its whole range, not only at its
first points. More rounds would cover the range sooner, but each round computes the soil
kernel of every point again (a worker reuses it only between runs of the same point)."""


def submission_order(n_points: int, n_seeds: int, rounds: int = SEED_ROUNDS) -> list[int]:
    """Run indices (study order: point-major, seeds innermost) in the order they are
    submitted: ``rounds`` rounds, each taking the next block of seeds at every point.

    Parameters
    ----------
    n_points, n_seeds : int
        Points of the study and seeds per point.
    rounds : int
        Rounds (at most ``n_seeds``).

    Returns
    -------
    list of int
        A permutation of ``range(n_points * n_seeds)``.
    """
    block = -(-n_seeds // max(1, min(rounds, n_seeds)))  # ceil
    return [
        point * n_seeds + seed
        for first in range(0, n_seeds, block)
        for point in range(n_points)
        for seed in range(first, min(first + block, n_seeds))
    ]


def _collect(client, study: Study, progress, cancel, record=None) -> tuple[dict[int, dict], bool]:
    """Submit every run of the study (:func:`submission_order`), gather rows as they finish
    (see :func:`collect_tasks`)."""
    tasks = [
        (row, run_summary, (scenario_json, study.depth_profile))
        for row, scenario_json in study.runs()
    ]
    order = submission_order(len(study.points), len(study.seeds))
    return collect_tasks(client, tasks, progress, cancel, order=order, record=record)


def collect_tasks(
    client, tasks, progress, cancel, order=None, record=None
) -> tuple[dict[int, dict], bool]:
    """Submit tasks, gather their rows as they finish; on cancel, stop the rest and wait.

    Parameters
    ----------
    client : distributed.Client
        Where the tasks run.
    tasks : list of (dict, callable, tuple)
        Per task: its input columns, and a function returning a dict of results called with
        the arguments; its row is the inputs and the results (or ``error``, its message).
    progress, cancel
        As in :func:`run_study`.
    order : list of int, optional
        The order the tasks are submitted in (a permutation of their places); default as given.
    record : callable(place, row), optional
        Told every row as it is gathered (see :func:`execute_study`).

    Returns
    -------
    (rows, cancelled)
        Rows by the task's place in ``tasks``; True when stopped by ``cancel`` or Ctrl-C.
    """
    token = uuid.uuid4().hex[:12]
    inputs = [row for row, _, _ in tasks]
    futures = [None] * len(tasks)
    for index in range(len(tasks)) if order is None else order:
        _, function, arguments = tasks[index]
        futures[index] = client.submit(
            function, *arguments, key=f"tunnelsettle-run-{token}-{index}", pure=False
        )
    index_of = {future.key: index for index, future in enumerate(futures)}
    rows: dict[int, dict] = {}
    cancelled = False
    # each future puts itself here as it finishes: a row is gathered the moment its run ends,
    # and the cancel flag is looked at between rows or every POLL_S
    finished: queue.SimpleQueue = queue.SimpleQueue()
    for future in futures:
        future.add_done_callback(finished.put)
    try:
        while len(rows) < len(futures):
            if cancel is not None and cancel.is_set():
                cancelled = True
                break
            try:
                future = finished.get(timeout=POLL_S)
            except queue.Empty:
                continue
            index = index_of[future.key]
            rows[index] = {**inputs[index], **_outcome(future)}
            if progress is not None:
                progress(len(rows), len(futures), rows[index])
            if record is not None:
                record(index, rows[index])
    except KeyboardInterrupt:
        cancelled = True
    finally:
        pending = [future for future in futures if not future.done()]
        if pending:
            client.cancel(pending, force=True)
            _wait_idle(client, {future.key for future in pending})
        for index, future in enumerate(futures):  # finished while the loop was stopping
            if index not in rows and future.status in ("finished", "error"):
                rows[index] = {**inputs[index], **_outcome(future)}
                if record is not None:
                    record(index, rows[index])
    return rows, cancelled


def _outcome(future) -> dict[str, Any]:
    """Summary of a finished run, or its error message."""
    if future.status == "finished":
        return future.result()
    error = future.exception()
    return {"error": f"{type(error).__name__}: {' '.join(str(error).split())}"}


def _executing_keys(dask_worker) -> list[str]:
    """Keys of the tasks a worker is executing right now (run on each worker)."""
    return [str(task.key) for task in dask_worker.state.executing]


def _wait_idle(client, keys: set[str]) -> None:
    """Wait until no worker still executes one of ``keys`` (a cancelled task ends its run)."""
    deadline = time.monotonic() + CANCEL_WAIT_S
    while time.monotonic() < deadline:
        try:
            executing = client.run(_executing_keys)
        except OSError:  # a worker went away: it executes nothing any more
            return
        if not any(key in keys for running in executing.values() for key in running):
            return
        time.sleep(POLL_S)


def study_table(study: Study, rows: dict[int, dict], cancelled: bool) -> pd.DataFrame:
    """A study's table from its rows by run (study order; ``error`` column only if a run
    failed), with the ``attrs`` of :func:`run_study`."""
    table = pd.DataFrame.from_dict(rows, orient="index").sort_index()
    table.index.name = "run"
    if "error" in table:
        table["error"] = table["error"].fillna("")
        table = table[[c for c in table.columns if c != "error"] + ["error"]]
    table.attrs.update(study=study.to_json(), n_runs=study.n_runs, cancelled=cancelled)
    return table
