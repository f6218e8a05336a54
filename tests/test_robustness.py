"""Issue 29, the model side: bounded work, no data loss, bad input refused in one line.

Each test reproduces one finding of the issue (what went wrong before is in its docstring) and
checks the fix; none needs a Dask cluster or OpenSeesPy.
"""

from __future__ import annotations

import json
import socket
import threading
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import model.cli as run_cli
import model.study.cli as study_cli
from model.fe.analysis import run_fe
from model.fe.mesh import MAX_FE_ELEMENTS, FEMesh, section_mesh
from model.fe.store import FEResult, save_fe_result, scenario_key, stored_fe_result
from model.outputs import replacing_folder, write_atomic, write_text_atomic
from model.params import Scenario
from model.study import definition as definition_module
from model.study import execution as study_module
from model.study.definition import MAX_RUNS, define_study
from model.study.execution import check_scheduler, study_table
from model.study.tables import load_study, read_study, save_study

BASE_SEED = Scenario.preset("single_bogie").irregularity.seed
"""The seed of the studies on the command line (one seed: the base scenario's)."""
MARKER = "SECRET-CONTENT-7f3a"
"""Text put in files that errors must not quote."""


def _leftovers(folder: Path) -> list[str]:
    """Temporary files or folders left beside or inside ``folder``."""
    return sorted(p.name for p in folder.parent.iterdir() if p.name.startswith("."))


# ---- atomic writes -------------------------------------------------------------------------
def test_write_atomic_leaves_the_old_file_when_the_writer_fails(tmp_path):
    """Before, files were written in place: a writer stopped half-way left half a file. Now
    the old file is untouched and no temporary file stays behind."""
    path = tmp_path / "summary.json"
    write_text_atomic(path, "old\n")

    def half_then_interrupt(temporary: Path) -> None:
        temporary.write_text("ne", encoding="utf-8")
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        write_atomic(path, half_then_interrupt)
    assert path.read_text(encoding="utf-8") == "old\n"
    assert [p.name for p in tmp_path.iterdir()] == ["summary.json"]


def test_replacing_folder_keeps_the_old_folder_until_the_new_one_is_complete(tmp_path):
    """An error inside the block leaves the old folder as it was; leaving it normally puts
    the new folder in its place (and removes the old files)."""
    out = tmp_path / "results"
    out.mkdir()
    (out / "a.csv").write_text("old a\n", encoding="utf-8")
    (out / "stale.csv").write_text("from another run\n", encoding="utf-8")
    with pytest.raises(KeyboardInterrupt), replacing_folder(out) as folder:
        (folder / "a.csv").write_text("new a\n", encoding="utf-8")
        raise KeyboardInterrupt
    assert sorted(p.name for p in out.iterdir()) == ["a.csv", "stale.csv"]
    assert (out / "a.csv").read_text(encoding="utf-8") == "old a\n"
    with replacing_folder(out) as folder:
        (folder / "a.csv").write_text("new a\n", encoding="utf-8")
    assert [p.name for p in out.iterdir()] == ["a.csv"]
    assert (out / "a.csv").read_text(encoding="utf-8") == "new a\n"
    assert _leftovers(out) == []


# ---- python -m model (a single run) ----------------------------------------------------------
@pytest.fixture
def fake_run(monkeypatch, base_results):
    """The single run's pipeline replaced by the cheap scenario's cached results."""
    monkeypatch.setattr(run_cli, "run", lambda *args, **kwargs: base_results)


def test_run_force_interrupted_mid_write_keeps_the_previous_folder(tmp_path, fake_run, monkeypatch):
    """Before, ``--force`` wrote file by file into the old folder: interrupted, it left a
    folder mixing two runs that parsed cleanly. Now the old folder stays whole."""
    out = tmp_path / "out"
    argv = ["--preset", "single_bogie", "--out", str(out), "--quiet"]
    assert run_cli.main(argv) == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    real = run_cli.write_csv_table
    calls = []

    def interrupted(path, columns):
        calls.append(path.name)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return real(path, columns)

    monkeypatch.setattr(run_cli, "write_csv_table", interrupted)
    with pytest.raises(KeyboardInterrupt):
        run_cli.main([*argv, "--force"])
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    assert _leftovers(out) == []


def test_run_refuses_a_file_as_out_before_computing(tmp_path, monkeypatch, capsys):
    """``--out`` naming a file is refused before the run (one line, exit code 2)."""
    monkeypatch.setattr(run_cli, "run", lambda *a, **k: pytest.fail("a run was computed"))
    target = tmp_path / "taken"
    target.write_text(MARKER, encoding="utf-8")
    with pytest.raises(SystemExit) as exited:
        run_cli.main(["--preset", "single_bogie", "--out", str(target)])
    err = capsys.readouterr().err
    assert exited.value.code == 2 and err.count("\n") == 1 and "is a file" in err
    assert target.read_text(encoding="utf-8") == MARKER


# ---- python -m model study -----------------------------------------------------------------
@pytest.fixture
def no_runs(monkeypatch):
    """Fail the test if any study run is submitted."""
    monkeypatch.setattr(
        study_module, "_collect", lambda *a, **k: pytest.fail("a run was submitted")
    )


def _study_argv(out: Path, *extra: str) -> list[str]:
    return ["--preset", "single_bogie", "--vary", "train.speed_kmh=90,100", "--out", str(out),
            "--quiet", *extra]  # fmt: skip


def test_study_out_onto_a_file_is_refused_before_the_study(tmp_path, capsys, no_runs):
    """Before, the whole study ran and then failed to write onto a file."""
    target = tmp_path / "study.csv"
    target.write_text(MARKER, encoding="utf-8")
    with pytest.raises(SystemExit) as exited:
        study_cli.main(_study_argv(target))
    err = capsys.readouterr().err
    assert exited.value.code == 2 and "is a file" in err and MARKER not in err


def test_study_out_onto_a_study_folder_needs_force(tmp_path, capsys, no_runs, cheap_scenario):
    """Before, an existing study folder was overwritten without ``--force``."""
    study = define_study(cheap_scenario(), {"train.speed_kmh": [90.0]}, seeds=[7])
    save_study(study_table(study, {0: {"train.speed_kmh": 90.0, "seed": 7}}, False), tmp_path)
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    with pytest.raises(SystemExit) as exited:
        study_cli.main(_study_argv(tmp_path))
    err = capsys.readouterr().err
    assert exited.value.code == 2 and "already holds files" in err and "--force" in err
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before


def _fake_execute(rows_then, interrupt: bool):
    """An execute_study that records the given rows (as finished runs) and then raises
    KeyboardInterrupt (a second Ctrl-C) or returns their table."""

    def execute(study, scheduler=None, *, progress=None, record=None, **kwargs):
        for run, row in rows_then.items():
            record(run, row)
        if interrupt:
            raise KeyboardInterrupt
        return study_table(study, rows_then, cancelled=False)

    return execute


def test_second_ctrl_c_keeps_the_finished_runs_and_records_the_cancel(tmp_path, monkeypatch):
    """Before, a second Ctrl-C (while the cancelled runs stopped) lost every finished run.
    Now they are saved as a cancelled study, and study.json says it was cancelled."""
    point = {"train.speed_kmh": 90.0, "seed": BASE_SEED}
    rows = {
        0: {**point, "soil.youngs_modulus": 4e6, "peak_disp_invert_m": 1e-3},
        3: {**point, "soil.youngs_modulus": 5e6, "peak_disp_invert_m": 2e-3},
    }
    rows[3]["train.speed_kmh"] = 100.0
    monkeypatch.setattr(study_cli, "execute_study", _fake_execute(rows, interrupt=True))
    out = tmp_path / "study"
    argv = _study_argv(out, "--vary", "soil.youngs_modulus=4e6,5e6")
    assert study_cli.main(argv) == 130
    saved = json.loads((out / "study.json").read_text(encoding="utf-8"))["saved"]
    assert saved["cancelled"] is True and saved["n_rows"] == 2
    table = read_study(out)
    assert table.attrs["cancelled"] is True and table.attrs["n_runs"] == 4
    assert list(table["peak_disp_invert_m"]) == [1e-3, 2e-3]
    assert sorted(p.name for p in out.iterdir()) == ["bands.csv", "runs.csv", "study.json"]


def test_study_rows_are_journalled_as_they_arrive(tmp_path, monkeypatch):
    """Each finished run is on disk (one JSON line, in the folder being assembled) before the
    next one is collected."""
    seen = []

    def execute(study, scheduler=None, *, progress=None, record=None, **kwargs):
        record(0, {"train.speed_kmh": 90.0, "seed": 1, "peak_disp_invert_m": 1e-3})
        journals = list(tmp_path.glob(f".out.new-*/{study_cli.JOURNAL_FILE}"))
        seen.extend(json.loads(line) for line in journals[0].read_text().splitlines())
        return study_table(study, {}, cancelled=True)

    monkeypatch.setattr(study_cli, "execute_study", execute)
    study_cli.main(_study_argv(tmp_path / "out"))
    assert seen == [{"run": 0, "train.speed_kmh": 90.0, "seed": 1, "peak_disp_invert_m": 1e-3}]


def test_study_force_interrupted_while_saving_keeps_the_old_study(tmp_path, monkeypatch):
    """An interrupt while the new study is written leaves the old folder whole."""
    rows = {0: {"train.speed_kmh": 90.0, "soil.youngs_modulus": 4e6, "seed": BASE_SEED, "x_m": 1}}
    monkeypatch.setattr(study_cli, "execute_study", _fake_execute(rows, interrupt=False))
    out = tmp_path / "study"
    study_cli.main(_study_argv(out, "--vary", "soil.youngs_modulus=4e6"))
    before = {p.name: p.read_bytes() for p in out.iterdir()}

    def interrupted(table, folder):
        (Path(folder) / "runs.csv").write_text("half", encoding="utf-8")
        raise KeyboardInterrupt

    monkeypatch.setattr(study_cli, "save_study", interrupted)
    with pytest.raises(KeyboardInterrupt):
        study_cli.main(_study_argv(out, "--vary", "soil.youngs_modulus=5e6", "--force"))
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    assert _leftovers(out) == []


def test_grid_size_is_checked_before_the_grid_is_built(tmp_path, capsys, monkeypatch, no_runs):
    """Before, 40:80:0.00001 × 2 values (8 million runs) built every value and point (2.2 GB
    of memory) before being refused; now the count comes from the value counts first."""
    monkeypatch.setattr(study_cli, "parse_values", lambda spec: pytest.fail("values built"))
    cases = (("0.001", [], "80002 runs, more than 500 without confirmation"),
             ("0.00001", ["--yes"], f"8000002 runs, more than the {MAX_RUNS} allowed"))  # fmt: skip
    for step, extra, message in cases:
        with pytest.raises(SystemExit) as exited:
            study_cli.main(
                ["--preset", "single_bogie", "--vary", f"train.speed_kmh=40:80:{step}",
                 "--vary", "soil.youngs_modulus=1e6,2e6", *extra, "--out", str(tmp_path / "o")]
            )  # fmt: skip
        err = capsys.readouterr().err
        assert exited.value.code == 2 and message in err
    assert not (tmp_path / "o").exists()


def test_define_study_counts_runs_before_checking_values(cheap_scenario, monkeypatch):
    """The API too: no value is converted or point built for a study too large to run."""
    calls = []
    real = definition_module._set
    monkeypatch.setattr(definition_module, "_set", lambda *a: calls.append(a) or real(*a))
    speeds = list(np.linspace(60.0, 80.0, 1001))
    with pytest.raises(ValueError, match="more than 500 without confirmation"):
        define_study(cheap_scenario(), {"train.speed_kmh": speeds, "train.n_cars": [1]})
    assert [path for _, path, _ in calls] == ["irregularity.seed"]  # the seed only


# ---- a study folder read back ----------------------------------------------------------------
@pytest.fixture
def saved_study(tmp_path, cheap_scenario):
    """A two-run study folder written by save_study."""
    study = define_study(cheap_scenario(), {"train.speed_kmh": [90.0, 100.0]}, seeds=[7])
    rows = {i: {"train.speed_kmh": v, "seed": 7, "peak_disp_invert_m": (i + 1) * 1e-3}
            for i, v in enumerate([90.0, 100.0])}  # fmt: skip
    save_study(study_table(study, rows, cancelled=False), tmp_path)
    return tmp_path


def test_a_tampered_runs_table_is_refused(saved_study):
    """Before, a changed runs.csv was reported without complaint; now its checksum (saved in
    study.json) is checked."""
    runs = saved_study / "runs.csv"
    runs.write_text(runs.read_text().replace("0.002", "0.009"), encoding="utf-8")
    with pytest.raises(ValueError, match="SHA-256 differs") as refused:
        read_study(saved_study)
    assert "\n" not in str(refused.value)


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda text: text.replace("\n1,100.0,7", "\n5,100.0,7"), "allowed range [0, 1]"),
        (lambda text: text.replace(",100.0,7,", ",110.0,7,"), "train.speed_kmh are not"),
        (lambda text: text.replace("seed", "seeds"), "the column seed"),
    ],
)
def test_a_runs_table_that_is_not_the_studys_is_refused(saved_study, edit, message):
    """Without a checksum (a folder written before it was recorded), the run numbers and the
    input columns are checked against study.json."""
    definition = saved_study / "study.json"
    data = json.loads(definition.read_text(encoding="utf-8"))
    del data["saved"]
    definition.write_text(json.dumps(data), encoding="utf-8")
    assert read_study(saved_study).attrs["cancelled"] is False  # intact: read as before
    runs = saved_study / "runs.csv"
    runs.write_text(edit(runs.read_text(encoding="utf-8")), encoding="utf-8")
    with pytest.raises(ValueError, match=message.replace("[", r"\[")):
        read_study(saved_study)


@pytest.mark.parametrize(
    "text",
    [
        "{" + MARKER,
        "[" * 100_000 + "]" * 100_000,
        json.dumps({"format": "tunnelsettle-study/1", "base": MARKER, "vary": {}, "seeds": [1]}),
        json.dumps({"format": "tunnelsettle-study/1", "base": {}, "vary": [], "seeds": [1]}),
        json.dumps(
            {"format": "tunnelsettle-study/1", "base": {"train": 3}, "vary": {}, "seeds": [1]}
        ),  # fmt: skip
    ],
    ids=["not-json", "nested", "base-text", "vary-list", "section-number"],
)
def test_malformed_study_json_is_one_line_naming_the_file(saved_study, text):
    """Before, ``export --study`` on a malformed study.json gave a KeyError or TypeError
    traceback; now one line naming the file, never its contents."""
    (saved_study / "study.json").write_text(text, encoding="utf-8")
    for read in (read_study, lambda folder: load_study(folder / "study.json")):
        with pytest.raises(ValueError) as refused:
            read(saved_study)
        message = str(refused.value)
        assert "\n" not in message and MARKER not in message and "study.json" in message


# ---- the scheduler address -------------------------------------------------------------------
@pytest.mark.parametrize("reply", [None, b"HTTP/1.0 200 OK\r\n\r\n" + b"x" * 64])
def test_a_server_that_is_not_a_dask_scheduler_fails_within_the_timeout(reply):
    """Before, an address where something else listens (silent, or another protocol) hung
    past the connect timeout (or raised MemoryError). Now a one-line ValueError. The call
    runs in a thread joined after 30 s, 30 times the timeout: a hang detector, not a timing."""
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(4)
    accepted = []

    def serve():
        connection, _ = server.accept()
        accepted.append(connection)
        if reply is not None:
            connection.recv(64)
            connection.sendall(reply)

    threading.Thread(target=serve, daemon=True).start()
    outcome = []

    def connect():
        try:
            check_scheduler(f"tcp://127.0.0.1:{server.getsockname()[1]}", 1.0)
        except ValueError as error:
            outcome.append(str(error))

    caller = threading.Thread(target=connect, daemon=True)
    caller.start()
    caller.join(30.0)
    server.close()
    for connection in accepted:
        connection.close()
    assert not caller.is_alive(), "check_scheduler hung"
    assert len(outcome) == 1 and "cannot reach the Dask scheduler" in outcome[0]
    assert "\n" not in outcome[0]


# ---- the FE section: mesh size, stored results -----------------------------------------------
@pytest.mark.parametrize(
    ("outer_radius", "element_size"), [(30.0, 1e-9), (30.0, 0.01), (1e308, 1.0)]
)
def test_a_mesh_too_large_is_refused_naming_its_parameters(outer_radius, element_size):
    """Before: bad_alloc in OpenSees, MemoryError or OverflowError; now a ValueError naming
    mesh.element_size and mesh.outer_radius, before any array is built."""
    with pytest.raises(ValueError) as refused:
        section_mesh(2.85, outer_radius, element_size, 3.0)
    message = str(refused.value)
    assert "mesh.element_size" in message and "mesh.outer_radius" in message
    assert f"more than the {MAX_FE_ELEMENTS} allowed" in message


def test_run_fe_refuses_a_large_mesh_before_the_pipeline_runs(monkeypatch):
    """A given element size is checked before the (long) pipeline run of the load."""
    import model.pipeline

    monkeypatch.setattr(model.pipeline, "run", lambda *a, **k: pytest.fail("pipeline ran"))
    with pytest.raises(ValueError, match="mesh.element_size = 0.001 m"):
        run_fe(Scenario.paper(), mesh=FEMesh(element_size=0.001))


def test_the_default_mesh_sizes_are_allowed():
    """The guard is far from the meshes in use: 0.15 m to R = 30 m (137 122 elements)."""
    grid = section_mesh(2.85, 30.0, 0.15, 3.0)
    assert grid.n_rings * grid.n_theta < MAX_FE_ELEMENTS


def _tiny_result(scenario: Scenario) -> FEResult:
    """An FEResult of three depths and two time steps (no FE run)."""
    depth = np.array([0.0, 1.0, 2.0])
    return FEResult(
        soil_law="elastic",
        passages=1,
        depth_m=depth,
        peak_disp_m=depth * 1e-3,
        residual_disp_m=depth * 0.0,
        peak_per_passage_m=depth[None, :] * 1e-3,
        residual_per_passage_m=depth[None, :] * 0.0,
        t_s=np.array([0.0, 0.1]),
        disp_m=np.zeros((3, 2)),
        load_N_per_m=np.zeros(2),
        scenario_json=scenario.to_json(),
    )


def test_a_corrupt_stored_fe_result_is_passed_over_with_a_warning(tmp_path):
    """Before, a stored file cut short raised in every run of its scenario; now a warning
    naming the file and None (the result is computed again)."""
    scenario = Scenario.paper()
    path = save_fe_result(_tiny_result(scenario), tmp_path)
    assert stored_fe_result(scenario, tmp_path) is not None
    path.write_bytes(path.read_bytes()[:40])
    with pytest.warns(UserWarning, match="cannot be read") as caught:
        assert stored_fe_result(scenario, tmp_path) is None
    assert str(path) in str(caught[0].message)


def test_the_fe_key_follows_the_profile_content_not_unused_numerics(tmp_path):
    """The key of a stored FE result changes with the measured profile's content (it ignored
    the file's contents) and not with the 2.5D wavenumber numerics of a 2D run."""
    profile = tmp_path / "profile.csv"
    profile.write_text("x_m,eta_mm\n0,0\n1,0.5\n2,0\n", encoding="utf-8")
    scenario = Scenario.preset("single_bogie")
    scenario.irregularity.profile_csv = str(profile)
    key = scenario_key(scenario)
    profile.write_text("x_m,eta_mm\n0,0\n1,0.7\n2,0\n", encoding="utf-8")
    assert scenario_key(scenario) != key
    assert scenario.tunnel.model == "2d"
    unused = scenario.copy()
    unused.numerics.n_wavenumbers *= 2
    unused.numerics.max_wavenumber *= 2
    assert scenario_key(unused) == scenario_key(scenario)
    changed = scenario.copy()
    changed.soil.youngs_modulus *= 1.1
    assert scenario_key(changed) != scenario_key(scenario)


def test_fe_result_files_are_written_whole(tmp_path, monkeypatch):
    """An interrupted save leaves the stored result as it was."""
    scenario = Scenario.paper()
    path = save_fe_result(_tiny_result(scenario), tmp_path)
    before = path.read_bytes()
    monkeypatch.setattr(np, "savez_compressed", lambda *a, **k: (_ for _ in ()).throw(OSError))
    with pytest.raises(OSError):
        save_fe_result(_tiny_result(scenario), tmp_path)
    assert path.read_bytes() == before and [p.name for p in tmp_path.iterdir()] == [path.name]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert stored_fe_result(scenario, tmp_path) is not None


def test_pandas_reads_a_saved_study_bit_for_bit(saved_study):
    """The checksummed text is the file pandas reads (shortest exact floats)."""
    table = pd.read_csv(saved_study / "runs.csv", index_col="run")
    assert list(table["peak_disp_invert_m"]) == [1e-3, 2e-3]


# ---- the run's memory estimate -------------------------------------------------------------
@pytest.mark.parametrize("tunnel_model", ["2d", "2.5d"])
def test_the_memory_estimate_is_not_below_the_measured_peak(cheap_scenario, tunnel_model):
    """Before, the estimate was the largest stage's arrays, 1.5–1.9× below the peak (each
    stage keeps its results while the next computes; the 2.5D stress field is larger). Now
    the tracemalloc peak of a whole run is at most the estimate (an upper count of sizes)."""
    import tracemalloc

    from model.pipeline import run
    from model.run_cost import estimate_run

    scenario = cheap_scenario()
    scenario.tunnel.model = tunnel_model
    scenario.numerics.n_depths = 71
    run(scenario)  # Numba caches loaded outside the measurement
    tracemalloc.start()
    try:
        run(scenario)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert estimate_run(scenario).peak_memory_bytes >= peak


def test_a_measured_profile_is_counted_in_the_memory_estimate():
    """Before, a measured profile's size did not enter the estimate."""
    from model.run_cost import PROFILE_BYTES_PER_LINE, estimate_run

    scenario = Scenario.preset("single_bogie")
    base = estimate_run(scenario).memory_bytes["vehicle_track"]
    lines = "\n".join(f"{x * 0.01:.2f},0.1" for x in range(20_000))
    scenario.irregularity.profile_data = "x_m,eta_mm\n" + lines + "\n"
    grown = estimate_run(scenario).memory_bytes["vehicle_track"] - base
    assert grown == PROFILE_BYTES_PER_LINE * 20_002
