"""Regression tests of issue 10: no silently wrong number, no raw traceback, no runaway run.

One test (or parametrised group) per defect of the issue, numbered as there; each failed on the
code before the fix. The input rules they protect are tabulated in docs/validity.md.
"""

import dataclasses
import inspect
import json
import os
import shutil

import numpy as np
import pytest

from model import pipeline, run_cost
from model.cli import main
from model.params import DATA_DIR, Scenario, ScenarioError
from model.pipeline import StageCache, run, stage_keys
from model.run_checks import invariant_warnings
from model.run_cost import SlowRunWarning, estimate_run
from model.soil.response import SoilResponse
from model.soil.section_2d import invert_receptance

CHEAP_SET = [
    "--preset",
    "single_bogie",
    "--set",
    "train.speed_kmh=100",
    "--set",
    "numerics.n_depths=11",
    "--quiet",
]


def result_arrays(results):
    """Every ndarray held by the stage results of a run, with its dotted name."""
    for stage in ("vehicle_track", "load", "soil"):
        value = getattr(results, stage)
        for item in dataclasses.fields(value):
            array = getattr(value, item.name)
            if isinstance(array, np.ndarray):
                yield f"{stage}.{item.name}", array


# ---- 1. results handed out read-only, no hidden default cache -------------------------------
def test_1_a_caller_cannot_change_what_the_cache_serves(cheap_scenario):
    """r.soil.peak_disp_m *= 1e3 used to turn the cached metres into millimetres."""
    scenario, cache = cheap_scenario(), StageCache()
    first = run(scenario, cache=cache)
    expected = first.soil.peak_disp_m.copy()
    with pytest.raises(ValueError, match="read-only"):
        first.soil.peak_disp_m *= 1e3
    again = run(scenario, cache=cache)
    assert again.cached_stages == pipeline.STAGES
    np.testing.assert_array_equal(again.soil.peak_disp_m, expected)
    for results in (first, again):
        writable = [name for name, array in result_arrays(results) if array.flags.writeable]
        assert writable == []


def test_1_results_cannot_be_changed_behind_the_cache(cheap_scenario):
    """Arrays are read-only and stage results frozen: converting a field to kN in place, or
    rebinding it, raises instead of changing what the cache serves to the next run; warnings
    are tuples."""
    scenario, cache = cheap_scenario(), StageCache()
    first = run(scenario, cache=cache)
    expected = first.vehicle_track.block_force_N.copy()
    with pytest.raises(ValueError, match="read-only"):
        first.soil.peak_disp_m *= 1e3
    with pytest.raises(dataclasses.FrozenInstanceError):
        first.vehicle_track.block_force_N = first.vehicle_track.block_force_N / 1e3
    with pytest.raises(dataclasses.FrozenInstanceError):
        first.load.line_load_N_per_m = first.load.line_load_N_per_m / 1e3
    assert isinstance(first.vehicle_track.warnings, tuple)
    assert isinstance(first.longterm.warnings, tuple)
    again = run(scenario, cache=cache)
    assert again.cached_stages == pipeline.STAGES
    np.testing.assert_array_equal(again.vehicle_track.block_force_N, expected)
    assert again.load.line_load_N_per_m.max() > 1e3  # N/m, not kN/m


def test_1_run_caches_only_when_given_a_cache(cheap_scenario):
    assert inspect.signature(run).parameters["cache"].default is None
    assert not hasattr(pipeline, "DEFAULT_CACHE")
    scenario = cheap_scenario()
    run(scenario)
    assert run(scenario).cached_stages == ()


# ---- 2. physically meaningful bounds, thin ring, invariants flagged -------------------------
@pytest.mark.parametrize(
    ("path", "value"),
    [
        ("soil.youngs_modulus", 1.0),  # −4223 mm "peak downward" displacement before
        ("soil.youngs_modulus", 1e5),  # profile not monotonic in depth before
        ("tunnel.inner_radius", 0.5),
        ("soil.poisson_ratio", 0.4999),
        ("numerics.dt", 0.005),
    ],
)
def test_2_values_outside_the_physical_bounds_are_refused(path, value):
    with pytest.raises(ValueError, match=rf"{path.split('.')[1]} = .* outside the allowed range"):
        Scenario.paper().set_value(path, str(value))


def test_2_a_thick_lining_breaks_the_thin_ring_model():
    """A 1 m lining on a 1 m inner radius (h/a = 0.67) was accepted silently."""
    scenario = Scenario.paper()
    scenario.tunnel.inner_radius = 1.0
    scenario.tunnel.thickness = 1.0
    with pytest.raises(ScenarioError, match=r"tunnel\.thickness = 1 m .*h/a = 0\.667"):
        scenario.validate()


def test_2_a_tunnel_above_the_ground_surface_is_refused():
    scenario = Scenario.paper()
    scenario.tunnel.axis_depth = 2.0
    with pytest.raises(ScenarioError, match=r"tunnel\.axis_depth = 2 m .*above the ground"):
        scenario.validate()


def test_2_a_record_too_short_for_the_deep_response_is_refused(cheap_scenario):
    """Soft undamped soil at 400 km/h: the default padding wrapped the deep response, which
    then grew with depth (0.28 → 0.32 mm from 28 to 35 m, the true values being 0.75 → 0.61).
    Refused, naming the padding; with the padding asked for, the peak decreases with depth."""
    scenario = cheap_scenario()
    scenario.update(
        {
            "soil": {"youngs_modulus": 1e6, "poisson_ratio": 0.49, "density": 1000.0},
            "train": {"speed_kmh": 400.0},
        }
    )
    scenario.soil.shear_loss_factor = 0.0
    # a soil as dense as water has no effective stress below the water table: keep it dry so
    # that the long-term stage accepts the run (its static state is not tested here)
    scenario.site.water_table_depth = 100.0  # the bottom of the default profile
    with pytest.raises(ScenarioError, match=r"numerics\.zero_pad_factor = 8 .*at least (\d+)"):
        run(scenario)
    scenario.numerics.zero_pad_factor = 32
    peak = run(scenario).soil.peak_disp_m
    assert np.all(np.diff(peak) < 0.0)


def _soil_response(peaks):
    """SoilResponse with the given peak profile (other arrays irrelevant to the check)."""
    empty = np.zeros(0)
    depth = np.linspace(0.0, 10.0, len(peaks))
    return SoilResponse(
        empty, empty, depth, np.asarray(peaks, float), empty, empty, empty, empty, empty
    )


@pytest.mark.parametrize(
    ("peaks", "flagged"),
    [
        ([3e-3, 2e-3, 1e-3], None),
        ([-4.2, 1e-3, 1e-4], "at the invert is -4.2 m, not > 0"),
        ([3e-3, 2e-3, 2.5e-3], "grows with depth from 5 m to 10 m"),
    ],
)
def test_2_results_breaking_the_elastic_invariants_are_flagged(peaks, flagged):
    found = invariant_warnings(_soil_response(peaks))
    if flagged is None:
        assert found == []
    else:
        assert any(flagged in text for text in found)
        assert all("soil.youngs_modulus" in text for text in found)


# ---- 3. booleans are not numbers, "1_0" is not 10 -------------------------------------------
@pytest.mark.parametrize(
    "values",
    [{"train": {"speed_kmh": True}}, {"train": {"n_cars": True}}, {"soil": {"density": False}}],
)
def test_3_booleans_are_refused_where_numbers_are_expected(values):
    section, (name, value) = next(iter(values.items()))[0], next(iter(values.values())).popitem()
    expected = rf"^{section}\.{name} = {value} is a boolean, not a (whole )?number"
    with pytest.raises(ValueError, match=expected):
        Scenario.from_json(json.dumps({section: {name: value}}))


@pytest.mark.parametrize(("path", "text"), [("train.n_cars", "1_0"), ("train.speed_kmh", "6_0")])
def test_3_digit_separators_are_refused_on_the_command_line(path, text):
    with pytest.raises(ValueError, match=rf"{path} = '{text}' is not a"):
        Scenario.paper().set_value(path, text)


# ---- 4. an edited profile with the same size and time stamp is not served stale -------------
def test_4_the_cache_key_follows_the_profile_content(tmp_path):
    profile = tmp_path / "profile.csv"
    shutil.copy(DATA_DIR / "example_profile.csv", profile)
    scenario = Scenario.preset("single_bogie")
    scenario.irregularity.profile_csv = str(profile)
    before = stage_keys(scenario)["vehicle_track"]
    stat = profile.stat()
    text = profile.read_text()
    edited = text.replace("0.", "1.", 1)
    assert len(edited) == len(text) and edited != text
    profile.write_text(edited)
    os.utime(profile, ns=(stat.st_atime_ns, stat.st_mtime_ns))
    assert profile.stat().st_size == stat.st_size
    assert stage_keys(scenario)["vehicle_track"] != before


# ---- 5. a failed update changes nothing -----------------------------------------------------
@pytest.mark.parametrize(
    "values",
    [
        {"train": {"speed_kmh": 50.0}, "soil": {"youngs_modulus": -1.0}},
        {"train": {"speed_kmh": 50.0, "n_cars": 99}},
        {"train": {"speed_kmh": 50.0}, "soil": {"stiffness": 1.0}},
    ],
)
def test_5_update_is_all_or_nothing(values):
    scenario = Scenario.paper()
    before = scenario.to_dict()
    with pytest.raises((ValueError, KeyError)):
        scenario.update(values)
    assert scenario.to_dict() == before


# ---- 6. the command line protects and checks its output folder ------------------------------
def test_6_an_existing_output_folder_is_not_overwritten_without_force(tmp_path, capsys):
    (tmp_path / "notes.txt").write_text("keep me")
    with pytest.raises(SystemExit) as info:
        main([*CHEAP_SET, "--out", str(tmp_path)])
    assert info.value.code == 2
    assert "--force" in capsys.readouterr().err
    assert (tmp_path / "notes.txt").read_text() == "keep me"  # refused: nothing touched
    assert main([*CHEAP_SET, "--out", str(tmp_path), "--force"]) == 0
    # --force replaces the folder whole (issue 29: no mixture of an old and a new run)
    assert (tmp_path / "summary.json").exists() and not (tmp_path / "notes.txt").exists()


@pytest.mark.parametrize("where", ["file", "parent_is_file"])
def test_6_an_unwritable_output_is_refused_before_computing(tmp_path, capsys, monkeypatch, where):
    blocker = tmp_path / "a_file"
    blocker.write_text("")
    out = blocker if where == "file" else blocker / "results"

    def must_not_run(*args, **kwargs):
        raise AssertionError("the run started before the output path was checked")

    monkeypatch.setattr("model.cli.run", must_not_run)
    with pytest.raises(SystemExit) as info:
        main([*CHEAP_SET, "--out", str(out)])
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert f"--out {out}" in err and "Traceback" not in err


# ---- 7. memory and time estimated before allocation ----------------------------------------
@pytest.mark.parametrize(
    ("path", "value"),
    [
        ("track.block_spacing", 1e-6),
        ("numerics.approach_distance", 5000.0),
        ("numerics.approach_distance", 1e300),
        ("numerics.soil_max_frequency", 3e-5),
    ],
)
def test_7_the_issue_runaway_inputs_are_refused_at_assignment(path, value):
    with pytest.raises(ValueError, match=rf"{path.split('.')[1]} = .* outside the allowed range"):
        Scenario.paper().set_value(path, repr(value))


def test_7_a_run_that_cannot_fit_in_memory_is_refused_before_computing(cheap_scenario, monkeypatch):
    monkeypatch.setattr(run_cost, "available_memory_bytes", lambda: 1e6)

    def must_not_run(*args, **kwargs):
        raise AssertionError("the simulation started before the memory check")

    monkeypatch.setattr(pipeline, "simulate", must_not_run)
    with pytest.raises(ValueError, match=r"stage would need .*numerics\.dt"):
        run(cheap_scenario())


def test_7_a_long_run_is_announced_before_it_starts(cheap_scenario, monkeypatch):
    monkeypatch.setattr(pipeline, "SLOW_RUN_SECONDS", 0.0)
    with pytest.warns(SlowRunWarning, match=r"estimated to take .*numerics\.dt"):
        run(cheap_scenario())


def test_7_the_estimate_counts_the_arrays_the_stages_build(cheap_scenario):
    """Sizes are exact counts (not timings): frequencies kept and FFT length of the soil stage."""
    scenario = cheap_scenario()
    results = run(scenario)
    estimate = estimate_run(scenario)
    n_freq = results.soil.interface_spectrum_f_hz.size
    assert f"{n_freq} frequencies" in estimate.blame["soil"]
    assert f"{results.vehicle_track.t_s.size - 1} time steps" in estimate.blame["vehicle_track"]
    disp_bytes = results.soil.disp_m.nbytes
    assert estimate.memory_bytes["soil"] > disp_bytes


# ---- 8. extreme values give messages naming the parameter ----------------------------------
@pytest.mark.parametrize(
    "path",
    [
        "train.speed_kmh",
        "numerics.dt",
        "track.rail_E",
        "soil.density",
        "vehicle.wheelset_mass",
    ],
)
def test_8_the_smallest_float_is_refused_naming_the_parameter(path):
    with pytest.raises(ValueError, match=rf"^{path} = 5e-324 \S+ is outside"):
        Scenario.paper().set_value(path, "5e-324")


def test_8_deeply_nested_json_is_a_clear_error():
    with pytest.raises(ValueError, match="nested too deeply"):
        Scenario.from_json("[" * 100_000 + "]" * 100_000)


# ---- 9. messages blame the right input ------------------------------------------------------
@pytest.mark.parametrize(
    ("path", "value"),
    [
        ("track.pad_stiffness", "5e-324"),
        ("vehicle.car_body_mass", "1e300"),
        ("soil.youngs_modulus", "1e300"),
    ],
)
def test_9_the_message_names_the_parameter_at_fault(path, value):
    section, name = path.split(".")
    with pytest.raises(ValueError) as info:
        Scenario.paper().set_value(path, value)
    assert f"{name} = {float(value)!r}" in str(info.value)
    assert "numerics.dt" not in str(info.value)


@pytest.mark.parametrize(
    ("path", "value", "named"),
    [
        ("track.fastener_stiffness", "1e10", "track.fastener_stiffness"),
        ("track.pad_damping", "1e6", "track.pad_damping"),
        ("numerics.n_rail_modes", "20000", "numerics.n_rail_modes"),
    ],
)
def test_9_the_stability_refusal_names_the_part_that_sets_the_limit(path, value, named):
    """It used to name the rail modes whatever set the limit (a stiff pad, a damper...)."""
    from model.track.vehicle_track import check_inputs

    scenario = Scenario.preset("single_bogie")
    scenario.set_value(path, value)
    with pytest.raises(ValueError, match=r"numerics\.dt = .* stability limit") as info:
        check_inputs(scenario)
    assert named in str(info.value)


def test_9_a_non_finite_soil_solution_names_the_inputs():
    """The kernel's last guard used to say only "check the inputs"."""
    scenario = Scenario.paper()
    with pytest.raises(ValueError, match=r"f = 1e\+300 Hz for tunnel\.inner_radius = .*soil\."):
        invert_receptance([1e300], [0.0, 5.0], scenario.tunnel, scenario.soil, 8)


# ---- 10. files: named in errors, any UTF-8 flavour, relative paths --------------------------
def test_10_a_malformed_scenario_file_is_named(tmp_path):
    path = tmp_path / "bad.json"
    path.write_text('{"train": {"speed_kmh": 80,}}')
    with pytest.raises(ValueError, match=rf"^{path}: .*line 1"):
        Scenario.from_file(path)


def test_10_a_scenario_file_with_a_bom_loads(tmp_path):
    path = tmp_path / "bom.json"
    path.write_bytes(b"\xef\xbb\xbf" + json.dumps({"train": {"speed_kmh": 60.0}}).encode())
    assert Scenario.from_file(path).train.speed_kmh == 60.0


def test_10_non_utf8_files_are_named_errors(tmp_path):
    scenario_path = tmp_path / "latin1.json"
    scenario_path.write_bytes('{"train": {"speed_kmh": 60}} # vitesse é'.encode("latin-1"))
    with pytest.raises(ValueError, match=rf"^{scenario_path}: .*not UTF-8"):
        Scenario.from_file(scenario_path)
    profile_path = tmp_path / "latin1.csv"
    profile_path.write_bytes("# profil mesuré\nx_m,eta_m\n0,0\n1,0\n".encode("latin-1"))
    scenario = Scenario.preset("single_bogie")
    scenario.irregularity.profile_csv = str(profile_path)
    with pytest.raises(ValueError, match=rf"^{profile_path}: not UTF-8"):
        run(scenario)


def test_10_a_profile_csv_with_a_bom_loads(tmp_path):
    from model.track.irregularity import load_profile_csv

    path = tmp_path / "bom.csv"
    path.write_bytes(b"\xef\xbb\xbfx_m,eta_mm\n0,1\n1,2\n")
    x, eta = load_profile_csv(path)
    np.testing.assert_array_equal(eta, [1e-3, 2e-3])


def test_10_a_relative_profile_path_is_read_next_to_the_scenario_file(tmp_path, monkeypatch):
    folder = tmp_path / "case"
    folder.mkdir()
    shutil.copy(DATA_DIR / "example_profile.csv", folder / "track.csv")
    scenario = Scenario.preset("single_bogie")
    scenario.update({"irregularity": {"profile_csv": "track.csv"}})
    (folder / "scenario.json").write_text(scenario.to_json())
    monkeypatch.chdir(tmp_path)  # not the scenario's folder
    loaded = Scenario.from_file(folder / "scenario.json")
    assert loaded.irregularity.profile_csv == str((folder / "track.csv").resolve())
    loaded.validate()


def test_10_the_command_line_names_a_bad_scenario_file(tmp_path, capsys):
    path = tmp_path / "broken.json"
    path.write_text("{")
    with pytest.raises(SystemExit) as info:
        main(["--scenario", str(path), "--out", str(tmp_path / "out")])
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert str(path) in err and "Traceback" not in err


# ---- the validity table stays in step with the parameters -----------------------------------
def test_docs_table_lists_every_bound_as_declared():
    """docs/validity.md has one 'bound' row per bounded number, with the declared range."""
    from pathlib import Path

    from model.params import SECTIONS, Count, Quantity
    from model.params.quantities import _format_range

    text = (Path(__file__).resolve().parent.parent / "docs" / "validity.md").read_text()
    rows = {
        cells[1].strip("` "): cells[3].strip()
        for line in text.splitlines()
        if line.startswith("| `") and (cells := line.split("|"))[2].strip() == "bound"
    }
    scenario = Scenario()
    declared = {
        f"{section}.{name}": _format_range(p.bounds, p.inclusive_bounds)
        for section in SECTIONS
        for name, p in getattr(scenario, section).param.objects("existing").items()
        if isinstance(p, Quantity | Count)
    }
    assert set(rows) == set(declared)
    for path, interval in declared.items():
        assert rows[path].startswith(interval), path
