"""Studies: parameter sweeps and Monte-Carlo bands on Dask distributed (docs/model.md §11).

A study is a base scenario, some of its parameters varied (a grid, or random / Latin-hypercube
samples within ranges) and a list of irregularity seeds: one run per (point, seed). Every run is
the task :func:`run_summary`, a pure function of the scenario's JSON, so a worker anywhere
computes exactly what :func:`model.pipeline.run` computes in-process. Runs go to Dask
distributed: a ``LocalCluster`` sized to this machine by default, or an existing scheduler
(``tcp://host:port``, argument or ``TUNNELSETTLE_SCHEDULER``).

Examples::

    from model.params import Scenario
    from model.study import aggregate, run_study
    table = run_study(Scenario.paper(), vary={"train.speed_kmh": [60, 80]}, seeds=range(20))
    bands = aggregate(table)     # mean and 5–95 % band per speed across the 20 seeds

    python -m model study --preset paper --vary train.speed_kmh=40:80:5 \\
        --vary soil.youngs_modulus=4e6,6e6,10e6 --seeds 20 --out study
"""

from __future__ import annotations

import argparse
import contextlib
import itertools
import json
import logging
import math
import os
import re
import sys
import threading
import time
import uuid
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numba
import numpy as np
import pandas as pd
import param

from model.params import SECTIONS, Scenario
from model.pipeline import StageCache, run
from model.track.vehicle_track import check_inputs

SCHEDULER_ENV = "TUNNELSETTLE_SCHEDULER"
"""Environment variable with the address of an existing Dask scheduler to use by default."""
MAX_RUNS_UNCONFIRMED = 500
"""Largest study run without ``confirm=True`` / ``--yes`` (about 5 min of the paper case on two
cores at ~1.2 s per run)."""
SAMPLINGS = ("grid", "random", "lhs")
STUDY_FORMAT = "tunnelsettle-study/1"
BAND = (0.05, 0.95)
"""Quantiles of the band across seeds (numpy's linear interpolation between order statistics)."""
CONNECT_TIMEOUT_S = 5.0
CANCEL_WAIT_S = 300.0  # a cancelled task already executing is waited for, at most this long
POLL_S = 0.05  # how often the collecting loop looks at the cancel flag when nothing finished
PROFILE_COLUMN = "profile_peak_disp_{depth:g}m_m"
_PROFILE_RE = re.compile(r"^profile_peak_disp_(.+)m_m$")
_ADDRESS_RE = re.compile(r"^(tcp|tls|ucx|ws|wss)://[^\s:/]+:\d+$")

Progress = Callable[[int, int, dict[str, Any]], None]
"""Called with (runs done, runs in all, the finished run's row) as each run comes back."""

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
    # Parallelism comes from running many tasks at once, one per worker thread: Numba's prange
    # kernels use one thread per task so they do not oversubscribe the cores (Dask's nanny
    # already sets OMP/MKL/OpenBLAS to one thread per worker process). Setting it here, rather
    # than NUMBA_NUM_THREADS in the worker's environment, also holds on workers started by hand.
    numba.set_num_threads(1)
    results = run(Scenario.from_json(scenario_json), cache=_TASK_CACHE)
    row = results.summary()
    if depth_profile:
        soil = results.soil
        for depth, peak in zip(soil.depth_m, soil.peak_disp_m, strict=True):
            row[PROFILE_COLUMN.format(depth=float(depth))] = float(peak)
    return row


# ---- the study definition ------------------------------------------------------------------
@dataclass
class Study:
    """Everything that defines a study; its JSON re-runs it exactly.

    ``vary`` maps a dotted parameter path to its grid values (``sampling="grid"``) or to its
    ``[low, high]`` range (``"random"``, ``"lhs"``; ``None`` takes the parameter's softbounds).
    """

    base_json: str
    vary: dict[str, Any]
    seeds: list[int]
    sampling: str = "grid"
    n_samples: int | None = None
    sampling_seed: int = 0
    depth_profile: bool = False
    _points: list[dict[str, Any]] = field(default_factory=list, init=False, repr=False)

    @property
    def base(self) -> Scenario:
        """A fresh copy of the base scenario."""
        return Scenario.from_json(self.base_json)

    @property
    def points(self) -> list[dict[str, Any]]:
        """Values of the varied parameters at each point (seeds not included)."""
        if not self._points:
            self._points = _sample_points(self)
        return self._points

    @property
    def n_runs(self) -> int:
        """Points times seeds."""
        return len(self.points) * len(self.seeds)

    def runs(self) -> Iterator[tuple[dict[str, Any], str]]:
        """(inputs row, scenario JSON) of every run, seeds innermost."""
        for point in self.points:
            scenario = self.base
            for path, value in point.items():
                scenario.set_value(path, value)
            for seed in self.seeds:
                scenario.irregularity.seed = seed
                yield {**point, "seed": seed}, scenario.to_json(indent=None)

    def to_json(self) -> str:
        """JSON of the definition (with the base scenario inline)."""
        data = {key: value for key, value in asdict(self).items() if not key.startswith("_")}
        data["base"] = json.loads(data.pop("base_json"))
        return json.dumps({"format": STUDY_FORMAT, **data}, indent=2, allow_nan=False)

    @classmethod
    def from_json(cls, text: str) -> Study:
        """Validated study from :meth:`to_json` output."""
        try:
            data = json.loads(text)
        except json.JSONDecodeError as error:
            raise ValueError(f"study definition is not valid JSON: {error}") from None
        if not isinstance(data, dict) or data.get("format") != STUDY_FORMAT:
            raise ValueError(f"not a study definition (expected format {STUDY_FORMAT!r})")
        base = Scenario.from_dict(data["base"])
        return define_study(
            base,
            vary=data["vary"],
            seeds=data["seeds"],
            sampling=data.get("sampling", "grid"),
            n_samples=data.get("n_samples"),
            sampling_seed=data.get("sampling_seed", 0),
            depth_profile=data.get("depth_profile", False),
            confirm=True,  # the count is checked when the study is run
        )


def define_study(
    base: Scenario,
    vary: dict[str, Any],
    seeds: Iterable[int] | None = None,
    sampling: str = "grid",
    n_samples: int | None = None,
    sampling_seed: int = 0,
    depth_profile: bool = False,
    confirm: bool = False,
) -> Study:
    """Check a study's inputs and every one of its scenarios, before anything is computed.

    Parameters
    ----------
    base : Scenario
        Scenario that every run starts from.
    vary : dict
        Dotted parameter path (``"train.speed_kmh"``, SI units except km/h) → grid values for
        ``sampling="grid"``; → ``(low, high)`` or ``None`` (the parameter's softbounds, its
        realistic slider range) for ``"random"`` and ``"lhs"``.
    seeds : iterable of int, optional
        Irregularity seeds, one run per seed at each point; default the base scenario's seed.
    sampling : {"grid", "random", "lhs"}
        Full grid, independent uniform samples, or a Latin hypercube (each range cut into
        ``n_samples`` equal strata, one sample per stratum and parameter).
    n_samples : int, optional
        Number of points for ``"random"`` and ``"lhs"``.
    sampling_seed : int
        Seed of the random / Latin-hypercube points (not of the irregularity).
    depth_profile : bool
        Also return the peak displacement at every depth (see :func:`run_summary`).
    confirm : bool
        Required for more than :data:`MAX_RUNS_UNCONFIRMED` runs.

    Raises
    ------
    ValueError
        Unknown parameter, value or range outside the parameter's bounds, empty grid, no
        seeds, too many runs without ``confirm``, inconsistent scenario: one line naming the
        parameter and the allowed range.
    """
    if sampling not in SAMPLINGS:
        raise ValueError(f"sampling = {sampling!r} is not one of {', '.join(SAMPLINGS)}")
    if not isinstance(vary, dict):
        raise ValueError("vary must map parameter paths to values")
    seeds = [base.irregularity.seed] if seeds is None else list(seeds)
    if not seeds:
        raise ValueError("seeds is empty: give at least one irregularity seed")
    probe = base.copy()
    for seed in seeds:
        _set(probe, "irregularity.seed", seed)
    seeds = [int(seed) for seed in seeds]
    if len(set(seeds)) != len(seeds):
        raise ValueError(f"seeds {seeds} repeat a seed: each run would be computed twice")
    checked: dict[str, Any] = {}
    for path, spec in vary.items():
        if path == "irregularity.seed":
            raise ValueError("irregularity.seed is varied through seeds, not vary")
        parameter = _parameter(path)
        if sampling == "grid":
            values = [spec] if isinstance(spec, str) or not isinstance(spec, Iterable) else spec
            values = [_set(probe, path, value) for value in values]
            if not values:
                raise ValueError(f"{path}: no values given, the grid is empty")
            checked[path] = values
        else:
            checked[path] = _sampling_range(probe, path, parameter, spec)
    if sampling == "grid":
        if n_samples is not None:
            raise ValueError("n_samples is for random or lhs sampling, not for a grid")
    else:
        if not vary:
            raise ValueError(f"{sampling} sampling needs at least one parameter to vary")
        if n_samples is None or int(n_samples) != n_samples or n_samples < 1:
            raise ValueError(f"n_samples = {n_samples!r} must be a whole number ≥ 1")
        n_samples = int(n_samples)
    study = Study(
        base_json=base.to_json(),
        vary=checked,
        seeds=seeds,
        sampling=sampling,
        n_samples=n_samples,
        sampling_seed=int(sampling_seed),
        depth_profile=bool(depth_profile),
    )
    check_run_count(study.n_runs, confirm)
    for point in study.points:  # the seed changes no constraint, so one check per point
        scenario = study.base
        for path, value in point.items():
            scenario.set_value(path, value)
        try:
            check_inputs(scenario)
        except ValueError as error:
            where = ", ".join(f"{path} = {value!r}" for path, value in point.items())
            message = " ".join(str(error).split())
            raise ValueError(f"at {where or 'the base scenario'}: {message}") from None
    return study


def _parameter(path: str) -> param.Parameter:
    """The parameter at a dotted path, or a one-line error listing what exists."""
    section, _, name = path.partition(".")
    if section not in SECTIONS or not name:
        raise ValueError(f"{path!r} is not of the form section.parameter, section in {SECTIONS}")
    obj = Scenario.param[section].class_
    if name not in obj.param or name == "name":
        names = ", ".join(n for n in obj.param if n != "name")
        raise ValueError(f"unknown parameter {path!r}; {section} has: {names}")
    return obj.param[name]


def _set(scenario: Scenario, path: str, value: Any) -> Any:
    """Set ``value`` (text, number, numpy scalar) at ``path``; return it as the parameter's type."""
    parameter = _parameter(path)
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(parameter, param.Integer) and isinstance(value, float) and value.is_integer():
        value = int(value)
    elif _is_quantity(parameter) and isinstance(value, int) and not isinstance(value, bool):
        value = float(value)  # 60 and 60.0 must give the same scenario JSON
    try:
        scenario.set_value(path, value)
    except KeyError as error:
        raise ValueError(error.args[0]) from None
    section, _, name = path.partition(".")
    return getattr(getattr(scenario, section), name)


def _is_quantity(parameter: param.Parameter) -> bool:
    """A real-valued number parameter (not an integer or a flag)."""
    return isinstance(parameter, param.Number) and not isinstance(
        parameter, param.Integer | param.Boolean
    )


def _sampling_range(probe: Scenario, path: str, parameter, spec) -> list[float]:
    """[low, high] of a sampled parameter: the given range, or its softbounds."""
    if not isinstance(parameter, param.Number):
        raise ValueError(f"{path} is not a number and can only be varied on a grid")
    if spec is None:
        low, high = parameter.get_soft_bounds()
        if low is None or high is None:
            raise ValueError(f"{path} has no finite softbounds: give its range as low:high")
    else:
        try:
            low, high = spec
        except (TypeError, ValueError):
            raise ValueError(f"{path}: a sampling range is (low, high), not {spec!r}") from None
    low, high = _set(probe, path, low), _set(probe, path, high)
    if not low < high:
        raise ValueError(f"{path}: the range [{low:g}, {high:g}] is empty (low must be < high)")
    return [low, high]


def _sample_points(study: Study) -> list[dict[str, Any]]:
    """The points of a study: the grid's product, or the random / Latin-hypercube draws."""
    paths = list(study.vary)
    if study.sampling == "grid":
        return [
            dict(zip(paths, values, strict=True))
            for values in itertools.product(*study.vary.values())
        ]
    rng = np.random.default_rng(study.sampling_seed)
    n, d = study.n_samples, len(paths)
    if study.sampling == "random":
        unit = rng.random((n, d))
    else:  # one sample in each of n equal strata per parameter, strata paired at random
        unit = (np.argsort(rng.random((d, n)), axis=1).T + rng.random((n, d))) / n
    points = []
    for row in unit:
        point = {}
        for path, fraction in zip(paths, row, strict=True):
            low, high = study.vary[path]
            value = low + fraction * (high - low)
            point[path] = round(value) if isinstance(_parameter(path), param.Integer) else value
        points.append(point)
    return points


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
    processes, closed on exit. An unreachable address is a one-line ``ValueError``.
    """
    from distributed import Client, LocalCluster

    if isinstance(scheduler, Client):
        yield scheduler
        return
    address = scheduler or os.environ.get(SCHEDULER_ENV) or None
    connect_timeout_s = CONNECT_TIMEOUT_S if connect_timeout_s is None else connect_timeout_s
    if address:
        if not isinstance(address, str) or not _ADDRESS_RE.match(address):
            raise ValueError(f"scheduler address {address!r} is not of the form tcp://host:port")
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
        LocalCluster(
            n_workers=n_workers or machine_workers(),
            threads_per_worker=1,
            processes=True,
            dashboard_address=":0",
            silence_logs=logging.ERROR,
        ) as cluster,
        Client(cluster, set_as_default=False) as client,
    ):
        yield client


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
) -> pd.DataFrame:
    """Run a checked :class:`Study` (e.g. from :meth:`Study.from_json`); see :func:`run_study`."""
    check_run_count(study.n_runs, confirm)
    with study_client(scheduler, n_workers, connect_timeout_s) as client:
        rows, cancelled = _collect(client, study, progress, cancel)
    return _table(study, rows, cancelled)


def check_run_count(n_runs: int, confirm: bool) -> None:
    """Refuse more than :data:`MAX_RUNS_UNCONFIRMED` runs unless confirmed."""
    if n_runs > MAX_RUNS_UNCONFIRMED and not confirm:
        raise ValueError(
            f"the study has {n_runs} runs, more than {MAX_RUNS_UNCONFIRMED} without "
            "confirmation: confirm it (--yes on the command line)"
        )


def _collect(client, study: Study, progress, cancel) -> tuple[dict[int, dict], bool]:
    """Submit every run, gather rows as they finish; on cancel, stop the rest and wait."""
    from distributed import as_completed

    token = uuid.uuid4().hex[:12]
    inputs, futures = [], []
    for index, (row, scenario_json) in enumerate(study.runs()):
        inputs.append(row)
        futures.append(
            client.submit(
                run_summary,
                scenario_json,
                study.depth_profile,
                key=f"tunnelsettle-run-{token}-{index}",
                pure=False,
            )
        )
    index_of = {future.key: index for index, future in enumerate(futures)}
    rows: dict[int, dict] = {}
    cancelled = False
    finished = as_completed(futures, loop=client.loop)
    try:
        while not finished.is_empty():
            if cancel is not None and cancel.is_set():
                cancelled = True
                break
            batch = finished.next_batch(block=False)
            if not batch:
                time.sleep(POLL_S)
                continue
            for future in batch:
                index = index_of[future.key]
                rows[index] = {**inputs[index], **_outcome(future)}
                if progress is not None:
                    progress(len(rows), len(futures), rows[index])
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


def _table(study: Study, rows: dict[int, dict], cancelled: bool) -> pd.DataFrame:
    """Rows in study order; ``error`` column only if a run failed."""
    table = pd.DataFrame.from_dict(rows, orient="index").sort_index()
    table.index.name = "run"
    if "error" in table:
        table["error"] = table["error"].fillna("")
        table = table[[c for c in table.columns if c != "error"] + ["error"]]
    table.attrs.update(study=study.to_json(), n_runs=study.n_runs, cancelled=cancelled)
    return table


# ---- results -------------------------------------------------------------------------------
def input_columns(table: pd.DataFrame) -> list[str]:
    """The varied parameters: columns named by a dotted path ``section.parameter``."""
    return [c for c in table.columns if "." in c and c.partition(".")[0] in SECTIONS]


def output_columns(table: pd.DataFrame) -> list[str]:
    """Numeric result columns (summary numbers and depth profile)."""
    inputs = set(input_columns(table)) | {"seed"}
    return [c for c in table.columns if c not in inputs and pd.api.types.is_numeric_dtype(table[c])]


def profile_depths(table: pd.DataFrame) -> list[tuple[float, str]]:
    """(depth in m, column) of the depth-profile columns, shallowest first."""
    found = [(m, c) for c in table.columns if (m := _PROFILE_RE.match(c))]
    return sorted((float(m.group(1)), c) for m, c in found)


def aggregate(table: pd.DataFrame, band: tuple[float, float] = BAND) -> pd.DataFrame:
    """Mean and band across seeds at each point of a study.

    Parameters
    ----------
    table : pandas.DataFrame
        :func:`run_study` output (failed runs, with NaN results, are left out).
    band : (float, float)
        Lower and upper quantile, default 5 % and 95 %.

    Returns
    -------
    pandas.DataFrame
        One row per point (the varied columns, in study order), ``n_runs`` and for each result
        column ``<column>_mean``, ``<column>_p05``, ``<column>_p95`` (same units).
    """
    inputs, outputs = input_columns(table), output_columns(table)
    low, high = band
    names = {"mean": "mean", "low": f"p{round(100 * low):02d}", "high": f"p{round(100 * high):02d}"}
    groups = table.groupby(inputs, sort=False) if inputs else [((), table)]
    rows = []
    for key, group in groups:
        key = key if isinstance(key, tuple) else (key,)
        values = group[outputs]
        ok = values.notna().all(axis=1)
        row = {**dict(zip(inputs, key, strict=True)), "n_runs": int(ok.sum())}
        stats = {
            "mean": values[ok].mean(),
            "low": values[ok].quantile(low),
            "high": values[ok].quantile(high),
        }
        for column in outputs:
            for stat, series in stats.items():
                row[f"{column}_{names[stat]}"] = float(series[column])
        rows.append(row)
    return pd.DataFrame(rows)


def save_study(table: pd.DataFrame, folder: Path) -> list[Path]:
    """Write ``runs.csv`` (one row per run), ``bands.csv`` (:func:`aggregate`) and ``study.json``.

    Floats are written in their shortest exact form, so ``pandas.read_csv`` gives back the
    same numbers bit for bit.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    paths = [folder / "runs.csv", folder / "bands.csv", folder / "study.json"]
    table.to_csv(paths[0])
    aggregate(table).to_csv(paths[1], index=False)
    paths[2].write_text(table.attrs["study"] + "\n", encoding="utf-8")
    return paths


def load_study(path: Path) -> Study:
    """The :class:`Study` of a ``study.json`` written by :func:`save_study`."""
    return Study.from_json(Path(path).read_text(encoding="utf-8"))


def read_study(folder: Path) -> pd.DataFrame:
    """The table of a study folder written by :func:`save_study`, as :func:`run_study` gave it.

    Parameters
    ----------
    folder : path
        Holds ``runs.csv`` and ``study.json``.

    Returns
    -------
    pandas.DataFrame
        The rows of ``runs.csv`` (the same numbers bit for bit), ``attrs`` ``study``,
        ``n_runs`` and ``cancelled`` (True when the folder holds fewer rows than the study has
        runs).

    Raises
    ------
    ValueError
        A file is missing, or ``study.json`` is not a study definition (one line).
    """
    folder = Path(folder)
    runs, definition = folder / "runs.csv", folder / "study.json"
    for path in (runs, definition):
        if not path.is_file():
            raise ValueError(
                f"{path} not found: {folder} is not a folder written by save_study or "
                "python -m model study --out"
            )
    study = load_study(definition)
    table = pd.read_csv(runs, index_col="run")
    if "error" in table:
        table["error"] = table["error"].fillna("")
    table.attrs.update(
        study=study.to_json(), n_runs=study.n_runs, cancelled=len(table) < study.n_runs
    )
    return table


# ---- command line --------------------------------------------------------------------------
def parse_values(spec: str) -> list[str] | tuple[str, str] | None:
    """Grid text of ``--vary``: ``a,b,c`` → values; ``start:stop:step`` → the inclusive range;
    ``low:high`` → a sampling range; empty → None (softbounds)."""
    if not spec.strip():
        return None
    if ":" not in spec:
        return [part.strip() for part in spec.split(",")]
    parts = [part.strip() for part in spec.split(":")]
    if len(parts) == 2:
        return parts[0], parts[1]
    if len(parts) != 3:
        raise ValueError(f"{spec!r} is not start:stop:step, low:high or a,b,c")
    try:
        start, stop, step = (float(part) for part in parts)
    except ValueError:
        raise ValueError(f"{spec!r}: start:stop:step must be numbers") from None
    if not step > 0:
        raise ValueError(f"{spec!r}: the step must be > 0")
    count = math.floor((stop - start) / step * (1 + 1e-12) + 1e-9) + 1
    if count < 1:
        raise ValueError(f"{spec!r}: stop is below start, the grid is empty")
    # rounded to 12 significant digits so 0.1-type steps give 0.3, not 0.30000000000000004
    return [f"{start + i * step:.12g}" for i in range(count)]


def build_parser() -> argparse.ArgumentParser:
    """Argument parser of ``python -m model study``."""
    from model.__main__ import add_scenario_arguments

    parser = argparse.ArgumentParser(
        prog="python -m model study",
        description="Parameter sweeps and Monte-Carlo bands on Dask distributed.",
    )
    add_scenario_arguments(parser)
    parser.add_argument(
        "--vary",
        action="append",
        default=[],
        metavar="SECTION.PARAM=SPEC",
        help="grid: start:stop:step (inclusive) or a,b,c; random/lhs: low:high or nothing "
        "(the parameter's softbounds). Repeatable.",
    )
    parser.add_argument("--sampling", choices=SAMPLINGS, default="grid")
    parser.add_argument("--samples", type=int, help="number of random / lhs points")
    parser.add_argument("--sampling-seed", type=int, default=0, help="seed of the random points")
    parser.add_argument(
        "--seeds",
        default="1",
        help="irregularity seeds: a count N (the base seed and the N-1 after it) or a,b,c",
    )
    parser.add_argument("--depth-profile", action="store_true", help="keep every depth's peak")
    parser.add_argument("--study", type=Path, help="re-run a study.json (ignores the above)")
    parser.add_argument("--out", type=Path, required=True, help="output folder (created)")
    parser.add_argument(
        "--scheduler",
        help=f"existing Dask scheduler tcp://host:port (default ${SCHEDULER_ENV}, else a "
        "LocalCluster with one single-threaded worker per core)",
    )
    parser.add_argument("--workers", type=int, help="LocalCluster workers (default: cores)")
    parser.add_argument(
        "--yes", action="store_true", help=f"allow more than {MAX_RUNS_UNCONFIRMED} runs"
    )
    parser.add_argument("--quiet", action="store_true", help="no progress bar or summary")
    return parser


def _parse_seeds(text: str, base_seed: int) -> list[int]:
    """``N`` → N seeds from the base scenario's; ``a,b,c`` → those seeds."""
    try:
        if "," in text:
            return [int(part) for part in text.split(",")]
        count = int(text)
    except ValueError:
        raise ValueError(f"--seeds {text!r} is not a count or a list of whole numbers") from None
    if count < 1:
        raise ValueError(f"--seeds {count} must be at least 1")
    return list(range(base_seed, base_seed + count))


def study_from_args(args: argparse.Namespace) -> Study:
    """The :class:`Study` described by the command line."""
    from model.__main__ import load_scenario

    if args.study:
        return load_study(args.study)
    base = load_scenario(args)
    vary: dict[str, Any] = {}
    for item in args.vary:
        path, sep, spec = item.partition("=")
        path = path.strip()
        if not sep and args.sampling == "grid":
            raise ValueError(f"--vary {item!r} must be of the form section.parameter=values")
        if path in vary:
            raise ValueError(f"--vary {path} is given twice")
        values = parse_values(spec)
        if args.sampling == "grid" and not isinstance(values, list):
            raise ValueError(f"--vary {item!r}: a grid needs a,b,c or start:stop:step")
        if args.sampling != "grid" and isinstance(values, list):
            raise ValueError(f"--vary {item!r}: {args.sampling} sampling needs low:high or nothing")
        vary[path] = values
    return define_study(
        base,
        vary,
        seeds=_parse_seeds(args.seeds, base.irregularity.seed),
        sampling=args.sampling,
        n_samples=args.samples,
        sampling_seed=args.sampling_seed,
        depth_profile=args.depth_profile,
        confirm=args.yes,
    )


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m model study``: returns the exit code (2 bad input, 130 cancelled)."""
    from model.__main__ import TerminalProgress

    class StudyProgress(TerminalProgress):
        """Runs done out of all, on the command line's progress bar."""

        failed = 0

        def __call__(self, done: int, total: int, row: dict) -> None:
            self.failed += bool(row.get("error"))
            filled = round(done / total * self.width)
            bar = "#" * filled + "-" * (self.width - filled)
            failed = f", {self.failed} failed" if self.failed else ""
            self.stream.write(f"\r[{bar}] {done}/{total} runs{failed}")
            self.stream.flush()
            self.shown = True

    parser = build_parser()
    args = parser.parse_args(None if argv is None else list(argv))
    progress = None if args.quiet else StudyProgress()
    try:
        study = study_from_args(args)
        table = execute_study(
            study, args.scheduler, progress=progress, confirm=args.yes, n_workers=args.workers
        )
    except (ValueError, KeyError, OSError) as error:
        message = error.args[0] if isinstance(error, KeyError) and error.args else error
        parser.exit(2, f"error: {message}\n")
    finally:
        if progress is not None:
            progress.close()
    paths = save_study(table, args.out)
    cancelled = table.attrs["cancelled"]
    if not args.quiet:
        failed = int((table["error"] != "").sum()) if "error" in table else 0
        state = "cancelled after" if cancelled else "done:"
        print(
            f"study {state} {len(table)} of {study.n_runs} runs ({failed} failed); "
            f"{', '.join(str(p) for p in paths)}",
            file=sys.stderr if cancelled else sys.stdout,
        )
    return 130 if cancelled else 0
