"""Studies on Dask (docs/model.md §11): exact rows, worker loss, cancellation, external cluster.

Every study here uses the cheap single-bogie scenario (about 0.1 s a run once a worker has
loaded the compiled kernels). Numbers are compared with ``==``: a task is the same pure
function of the scenario JSON as an in-process ``run()``, so no tolerance is needed.
"""

from __future__ import annotations

import contextlib
import os
import signal
import socket
import subprocess
import sys
import threading
from pathlib import Path

import dask
import numpy as np
import pandas as pd
import pytest
from distributed import Client
from distributed.nanny import WorkerProcess

from model.params import Scenario
from model.pipeline import TRANSFER, StageCache, run
from model.study import execution as study_module
from model.study.cli import main, parse_values
from model.study.definition import MAX_RUNS_UNCONFIRMED, Study, define_study
from model.study.execution import SCHEDULER_ENV, execute_study, run_study, study_client
from model.study.tables import aggregate, load_study, profile_depths, read_study, save_study

ROOT = Path(__file__).resolve().parent.parent
CLUSTER_START_S = 120.0  # cold imports in fresh processes on a busy 2-core machine


@contextlib.contextmanager
def _dask_cluster_processes(port: int):
    """``dask scheduler`` and one ``dask worker`` on 127.0.0.1:port, always torn down."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    dask_cli = [str(Path(sys.executable).with_name("dask"))]  # the console script of the venv
    address = f"tcp://127.0.0.1:{port}"
    processes = []
    try:
        processes.append(
            subprocess.Popen(
                [*dask_cli, "scheduler", "--host", "127.0.0.1", "--port", str(port)]
                + ["--no-dashboard", "--no-show"],
                env=env,
                stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL,
            )
        )
        processes.append(
            subprocess.Popen(
                [*dask_cli, "worker", address, "--nthreads", "1", "--nworkers", "2"]
                + ["--no-dashboard", "--host", "127.0.0.1"],
                env=env,
                stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL,
            )
        )
        with Client(address, timeout=CLUSTER_START_S, set_as_default=False) as waiting:
            waiting.wait_for_workers(2, timeout=CLUSTER_START_S)
        yield address
    finally:
        for process in reversed(processes):
            process.terminate()
        for process in reversed(processes):
            try:
                process.wait(timeout=30)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait()


@pytest.fixture(scope="module")
def cluster_address():
    """``dask scheduler`` and ``dask worker`` (2 single-threaded processes under a nanny) started
    as separate commands on 127.0.0.1, as a user starts a cluster; torn down after the module."""
    with _dask_cluster_processes(_free_port()) as address:
        yield address


@pytest.fixture
def client(cluster_address):
    """A client of that cluster."""
    with study_client(cluster_address) as dask_client:
        yield dask_client


def _in_process_row(base, point, seed):
    """Summary and depth profile of the same scenario run in this process."""
    scenario = base.copy()
    for path, value in point.items():
        scenario.set_value(path, value)
    scenario.irregularity.seed = seed
    results = run(scenario, cache=None)
    return results.summary(), results.soil.peak_disp_m


def _free_port() -> int:
    """A TCP port on 127.0.0.1 that nothing listens on right now."""
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def _our_tasks(client) -> list[str]:
    """Study tasks the scheduler still processes or any worker still executes."""
    processing = [key for keys in client.processing().values() for key in keys]
    executing = [key for keys in client.run(study_module._executing_keys).values() for key in keys]
    return [str(key) for key in processing + executing if "tunnelsettle-run" in str(key)]


# ---- exact rows ----------------------------------------------------------------------------
def test_rows_equal_in_process_runs_bit_for_bit(cheap_scenario, tmp_path):
    """Each row of a study on a LocalCluster started by run_study (scheduler=None) equals run()
    of the same scenario in this process, every summary number and the depth profile exactly
    (tolerance 0: the same deterministic code on the same inputs); CSV keeps every bit. The
    cluster leaves this process's environment as it was (Dask's nannies wrote their workers'
    thread counts into it)."""
    base = cheap_scenario()
    environment = dict(os.environ)
    seen = []
    table = run_study(
        base,
        vary={"train.speed_kmh": [90, 100]},
        seeds=[7, 8],
        depth_profile=True,
        n_workers=2,
        progress=lambda done, total, row: seen.append((done, total)),
    )
    assert list(table.index) == [0, 1, 2, 3]
    assert list(table.columns[:2]) == ["train.speed_kmh", "seed"]
    assert "error" not in table
    assert sorted(seen) == [(1, 4), (2, 4), (3, 4), (4, 4)]
    assert table.attrs["cancelled"] is False
    assert dict(os.environ) == environment
    # the transfer functions computed here for the forked workers are not kept here
    assert not study_module._TASK_CACHE._entries[TRANSFER]
    depths = [column for _, column in profile_depths(table)]
    for speed, seed in [(90.0, 7), (90.0, 8), (100.0, 7), (100.0, 8)]:
        summary, profile = _in_process_row(base, {"train.speed_kmh": speed}, seed)
        values = table.loc[(table["train.speed_kmh"] == speed) & (table["seed"] == seed)]
        assert len(values) == 1
        for key, expected in summary.items():
            assert values[key].item() == expected, key
        np.testing.assert_array_equal(values[depths].to_numpy()[0], profile)
    save_study(table, tmp_path)
    back = read_study(tmp_path)
    pd.testing.assert_frame_equal(back, table, check_exact=True)
    assert back.attrs == table.attrs


def test_local_cluster_runs_without_the_diagnostics_of_a_dashboard_it_does_not_start():
    """A study's own LocalCluster: its workers run with LOCAL_CLUSTER_CONFIG (no profiler), its
    nannies looked for their new workers at the short interval (not Dask's 50 ms); this
    process's configuration is as it was afterwards."""
    profile = "distributed.worker.profile.enabled"
    before = dask.config.get(profile)
    with study_client(None, n_workers=1) as client:
        assert list(client.run(dask.config.get, profile).values()) == [False]
        assert WorkerProcess._init_msg_interval == study_module.NANNY_POLL_S
    assert dask.config.get(profile) == before


def test_transfer_functions_computed_before_the_fork_are_the_first_runs(
    cheap_scenario, monkeypatch
):
    """What a new LocalCluster's workers inherit from this process is what their first runs
    ask the task cache for; inputs a run refuses are left to the runs (their rows say why)."""
    cache = StageCache(size=1, transfer_size=1)
    monkeypatch.setattr(study_module, "_TASK_CACHE", cache)
    study = define_study(cheap_scenario(), {"train.speed_kmh": [90, 100]}, seeds=[7, 8])
    assert study_module._prefetch_before_fork(study)
    assert (cache.hits[TRANSFER], cache.misses[TRANSFER]) == (0, 1)
    _, first = next(study.runs())
    run(Scenario.from_json(first), cache=cache)  # as a forked worker's first task runs it
    assert (cache.hits[TRANSFER], cache.misses[TRANSFER]) == (1, 1)

    def refuse(scenario, cache):
        raise ValueError("a run refuses these inputs")

    monkeypatch.setattr(study_module, "prefetch_transfer", refuse)
    assert not study_module._prefetch_before_fork(study)  # the study goes on: its rows say why


def test_rerun_from_saved_definition_gives_the_same_table(client, cheap_scenario, tmp_path):
    """study.json re-runs the study: same points, seeds and numbers (exact), on any cluster."""
    table = run_study(
        cheap_scenario(),
        vary={"soil.youngs_modulus": [4e6, 10e6]},
        seeds=[1, 2],
        scheduler=client,
    )
    save_study(table, tmp_path)
    again = execute_study(load_study(tmp_path / "study.json"), client)
    pd.testing.assert_frame_equal(again, table, check_exact=True)
    bands = pd.read_csv(tmp_path / "bands.csv")
    assert list(bands["soil.youngs_modulus"]) == [4e6, 10e6]
    assert list(bands["n_runs"]) == [2, 2]


# ---- cancellation, an existing cluster, worker loss ----------------------------------------
def test_cancelled_study_returns_finished_rows_and_leaves_no_task(client, cheap_scenario):
    """Cancel after the second row of 60: the table holds only complete finished rows, marked
    cancelled, and no study task is left on the scheduler or executing on a worker."""
    cancel = threading.Event()

    def cancel_after_two(done, total, row):
        if done >= 2:
            cancel.set()

    table = run_study(
        cheap_scenario(),
        vary={"train.speed_kmh": list(np.arange(90.0, 100.0, 0.5))},
        seeds=[1, 2, 3],
        scheduler=client,
        progress=cancel_after_two,
        cancel=cancel,
    )
    assert table.attrs["cancelled"] is True
    assert 2 <= len(table) < 60
    assert table.notna().all().all()
    assert _our_tasks(client) == []


def test_command_line_on_separately_started_cluster(
    cluster_address, cheap_scenario, tmp_path, monkeypatch
):
    """The command line, pointed at the hand-started cluster through $TUNNELSETTLE_SCHEDULER,
    writes runs.csv whose rows equal the in-process runs exactly."""
    monkeypatch.setenv(SCHEDULER_ENV, cluster_address)
    code = main(
        ["--preset", "single_bogie", "--set", "numerics.n_depths=11"]
        + ["--vary", "train.speed_kmh=90:100:10", "--seeds", "3,4", "--out", str(tmp_path)]
        + ["--quiet"]
    )
    assert code == 0
    table = pd.read_csv(tmp_path / "runs.csv", index_col="run")
    assert list(zip(table["train.speed_kmh"], table["seed"], strict=True)) == [
        (90.0, 3),
        (90.0, 4),
        (100.0, 3),
        (100.0, 4),
    ]
    base = cheap_scenario()
    summary, _ = _in_process_row(base, {"train.speed_kmh": 90.0}, 4)
    for key, expected in summary.items():
        assert table.loc[1, key] == expected, key


def test_killed_worker_loses_and_doubles_no_row(client, cheap_scenario):
    """SIGKILL of a worker that is processing study tasks, right after the first row: the
    scheduler re-runs its tasks elsewhere; every (speed, seed) comes back exactly once and
    equals the in-process run."""
    pids = client.run(os.getpid)
    killed = []

    def kill_busy_worker(done, total, row):
        if killed:
            return
        busy = [address for address, keys in client.processing().items() if keys]
        address = busy[0] if busy else next(iter(pids))
        os.kill(pids[address], signal.SIGKILL)
        killed.append(address)

    speeds = [90.0, 95.0, 100.0, 105.0]
    seeds = [1, 2, 3, 4]
    base = cheap_scenario()
    table = run_study(
        base,
        vary={"train.speed_kmh": speeds},
        seeds=seeds,
        scheduler=client,
        progress=kill_busy_worker,
    )
    assert killed
    assert "error" not in table
    assert list(table.index) == list(range(16))
    pairs = list(zip(table["train.speed_kmh"], table["seed"], strict=True))
    assert sorted(pairs) == [(v, s) for v in speeds for s in seeds]
    summary, _ = _in_process_row(base, {"train.speed_kmh": 105.0}, 4)
    assert table.iloc[-1]["peak_disp_invert_m"] == summary["peak_disp_invert_m"]
    client.wait_for_workers(2, timeout=CLUSTER_START_S)  # the nanny restarts the worker
    assert set(client.run(os.getpid).values()) != set(pids.values())


# ---- definitions, sampling, aggregation (no cluster) ---------------------------------------
def test_grid_text_is_inclusive_and_exact():
    """40:80:5 gives the 9 speeds 40…80 (stop included); 0.1 steps are not 0.30000000000000004."""
    assert parse_values("40:80:5") == [str(v) for v in range(40, 85, 5)]
    assert parse_values("0.1:0.3:0.1") == ["0.1", "0.2", "0.3"]
    assert parse_values("4e6,6e6,10e6") == ["4e6", "6e6", "10e6"]
    assert parse_values("1:2") == ("1", "2")
    assert parse_values("") is None


def test_latin_hypercube_has_one_sample_per_stratum(cheap_scenario):
    """LHS with n points: each parameter's range cut into n equal strata holds exactly one
    sample; with no range given, the range is the parameter's softbounds."""
    n = 16
    study = define_study(
        cheap_scenario(),
        {"train.speed_kmh": (60.0, 120.0), "soil.youngs_modulus": None},
        sampling="lhs",
        n_samples=n,
        sampling_seed=3,
    )
    low, high = type(cheap_scenario().soil).param["youngs_modulus"].get_soft_bounds()
    assert study.vary["soil.youngs_modulus"] == [low, high]
    for path, (lo, hi) in study.vary.items():
        values = np.array([point[path] for point in study.points])
        strata = np.floor((values - lo) / (hi - lo) * n).astype(int)
        assert sorted(strata) == list(range(n)), path
    random = define_study(
        cheap_scenario(), {"train.speed_kmh": (60.0, 120.0)}, sampling="random", n_samples=n
    )
    speeds = [point["train.speed_kmh"] for point in random.points]
    assert len(set(speeds)) == n and 60.0 <= min(speeds) and max(speeds) <= 120.0


def test_definition_json_round_trip(cheap_scenario):
    """Study.from_json(to_json()) gives the same base, points and seeds."""
    study = define_study(
        cheap_scenario(), {"train.speed_kmh": None}, [1, 5], sampling="lhs", n_samples=4
    )
    again = Study.from_json(study.to_json())
    assert again.points == study.points
    assert again.seeds == [1, 5]
    assert again.base_json == study.base_json
    assert [inputs for inputs, _ in again.runs()] == [inputs for inputs, _ in study.runs()]


def test_read_study_gives_back_failed_and_cancelled_runs(cheap_scenario, tmp_path):
    """A cancelled study with a failed run: read_study gives back its rows exactly (the error
    message, empty for the runs that succeeded) and the attrs run_study set."""
    study = define_study(cheap_scenario(), {"train.speed_kmh": [90.0, 100.0]}, seeds=[7, 8])
    rows = {
        0: {"train.speed_kmh": 90.0, "seed": 7, "peak_disp_invert_m": 0.1 + 0.2},
        1: {"train.speed_kmh": 90.0, "seed": 8, "error": "SimulationError: unstable, at 3 s"},
        3: {"train.speed_kmh": 100.0, "seed": 8, "peak_disp_invert_m": 1 / 3 * 1e-3},
    }
    table = study_module.study_table(study, rows, cancelled=True)
    save_study(table, tmp_path)
    back = read_study(tmp_path)
    pd.testing.assert_frame_equal(back, table, check_exact=True)
    assert back.attrs == table.attrs == {"study": study.to_json(), "n_runs": 4, "cancelled": True}


@pytest.mark.parametrize("missing", ["runs.csv", "study.json"])
def test_read_study_refuses_a_folder_without_its_files(cheap_scenario, tmp_path, missing):
    study = define_study(cheap_scenario(), {"train.speed_kmh": [90.0]}, seeds=[7])
    table = study_module.study_table(
        study, {0: {"train.speed_kmh": 90.0, "seed": 7}}, cancelled=False
    )
    save_study(table, tmp_path)
    (tmp_path / missing).unlink()
    with pytest.raises(ValueError) as refused:
        read_study(tmp_path)
    message = str(refused.value)
    assert "\n" not in message and str(tmp_path / missing) in message and "not found" in message


def test_aggregate_mean_and_band():
    """Per point: the mean and numpy's linearly interpolated 5 % and 95 % quantiles of the
    seeds' values (exact arithmetic on small integers); failed runs (NaN) left out."""
    values = np.arange(21.0)
    table = pd.DataFrame(
        {
            "train.speed_kmh": [60.0] * 21 + [80.0] * 2,
            "seed": list(range(21)) + [0, 1],
            "peak_disp_invert_m": list(values) + [1.0, np.nan],
        }
    )
    bands = aggregate(table)
    first, second = bands.iloc[0], bands.iloc[1]
    assert first["n_runs"] == 21
    assert first["peak_disp_invert_m_mean"] == 10.0
    assert first["peak_disp_invert_m_p05"] == 1.0  # 0.05 × 20 = 1st order statistic
    assert first["peak_disp_invert_m_p95"] == 19.0
    assert second["n_runs"] == 1 and second["peak_disp_invert_m_mean"] == 1.0


# ---- bad input: one line, before anything is computed --------------------------------------
@pytest.fixture
def nothing_computed(monkeypatch):
    """Fail the test if any run is submitted."""

    def refuse(*args, **kwargs):
        raise AssertionError("a run was submitted")

    monkeypatch.setattr(study_module, "_collect", refuse)


@pytest.mark.parametrize(
    ("vary", "kwargs", "message"),
    [
        ({"train.speedkmh": [60]}, {}, "unknown parameter 'train.speedkmh'"),
        ({"trian.speed_kmh": [60]}, {}, "a parameter is section.parameter"),
        ({"train.speed_kmh": [60, 500]}, {}, "outside the allowed range [1, 400]"),
        ({"soil.youngs_modulus": (-1.0, 1e7)}, {"sampling": "lhs", "n_samples": 4}, "-1 Pa"),
        ({"train.speed_kmh": []}, {}, "the grid is empty"),
        ({"train.speed_kmh": [60]}, {"seeds": []}, "seeds is empty"),
        ({"irregularity.seed": [1, 2]}, {}, "varied through seeds"),
        ({"train.single_bogie": None}, {"sampling": "random", "n_samples": 3}, "not a number"),
        ({"train.speed_kmh": None}, {"sampling": "lhs"}, "n_samples = None"),
        (
            {"numerics.dt": [1e-4, 9e-4]},
            {},
            "at numerics.dt = 0.0009: numerics.dt = 0.0009 s is above",
        ),
    ],
)
def test_bad_study_is_one_line_error(cheap_scenario, nothing_computed, vary, kwargs, message):
    """Each bad input is a one-line ValueError naming the parameter (and its range)."""
    with pytest.raises(ValueError) as raised:
        run_study(cheap_scenario(), vary, **kwargs)
    text = str(raised.value)
    assert message in text
    assert "\n" not in text


def test_too_many_runs_need_confirmation(cheap_scenario, nothing_computed):
    """More than MAX_RUNS_UNCONFIRMED runs without confirm is refused before any cluster."""
    speeds = np.linspace(60.0, 80.0, MAX_RUNS_UNCONFIRMED // 2 + 1)
    with pytest.raises(ValueError, match=f"more than {MAX_RUNS_UNCONFIRMED} without confirm"):
        run_study(cheap_scenario(), {"train.speed_kmh": speeds}, seeds=[1, 2])


def test_unreachable_scheduler_is_one_line_error(cheap_scenario, nothing_computed, monkeypatch):
    """An address where no scheduler listens, given or from the environment variable."""
    address = f"tcp://127.0.0.1:{_free_port()}"
    with pytest.raises(ValueError, match="cannot reach the Dask scheduler") as raised:
        run_study(cheap_scenario(), {}, scheduler=address, connect_timeout_s=1.0)
    assert "\n" not in str(raised.value)
    monkeypatch.setenv(SCHEDULER_ENV, "localhost:8786")
    with pytest.raises(ValueError, match="not of the form tcp://host:port"):
        run_study(cheap_scenario(), {})


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--vary", "train.speed_kmh=80:40:5"], "stop is below start, the grid is empty"),
        (["--vary", "train.speed_kmh=40:80:0"], "the step must be > 0"),
        (["--vary", "train.nope=1,2"], "unknown parameter 'train.nope'"),
        (["--vary", "train.speed_kmh=1:x:3"], "start:stop:step must be numbers"),
        (["--vary", "train.speed_kmh=40:800:20"], "outside the allowed range"),
        (["--vary", "train.speed_kmh=60:80:0.01", "--seeds", "2"], "--yes"),
        (["--scheduler", "tcp://127.0.0.1:1", "--seeds", "2"], "cannot reach"),
        (["--seeds", "0"], "--seeds 0 must be at least 1"),
    ],
)
def test_command_line_bad_input(argv, message, tmp_path, capsys, nothing_computed, monkeypatch):
    """Exit code 2 and a one-line ``error: ...`` on stderr, nothing written."""
    monkeypatch.setattr(study_module, "CONNECT_TIMEOUT_S", 1.0)
    monkeypatch.delenv(SCHEDULER_ENV, raising=False)
    with pytest.raises(SystemExit) as exited:
        main(["--preset", "single_bogie", "--out", str(tmp_path / "out"), *argv])
    assert exited.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: ") and message in err[0], err
    assert not (tmp_path / "out").exists()
