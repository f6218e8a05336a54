"""Pipeline end to end on a cheap scenario, stage caching, warnings and the command line."""

import json
import subprocess
import sys
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest

from model import pipeline, run_checks
from model.cli import main
from model.longterm.statements import SETTLEMENT_COVERS
from model.params import Numerics, Scenario, ScenarioError
from model.pipeline import StageCache, run

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="module")
def results(cheap_scenario):
    return run(cheap_scenario(), cache=None)


def test_result_fields_have_the_documented_shapes(results):
    vt, load, soil = results.vehicle_track, results.load, results.soil
    nt = vt.t_s.size
    assert nt > 1000
    for name in ("block_force_N", "block_disp_m", "rail_disp_m", "winkler_block_disp_m"):
        assert getattr(vt, name).shape == (nt,), name
    assert vt.wheel_force_N.shape == (2, nt)
    assert load.t_s.shape == load.line_load_N_per_m.shape == (nt,)
    assert load.f_hz.shape == load.psd.shape and load.f_hz[0] == 0.0
    assert soil.f_hz.shape == soil.interface_psd.shape
    assert soil.depth_m.shape == soil.peak_disp_m.shape == (11,)
    assert soil.disp_m.shape == (11, soil.t_s.size)
    for array in (vt.block_force_N, load.psd, soil.interface_psd, soil.peak_disp_m):
        assert np.all(np.isfinite(array))


def test_line_load_is_the_coupling_rule_of_the_model_sheet(results):
    """q = 2 F_b / L_s exactly (docs/model.md §6)."""
    np.testing.assert_allclose(
        results.load.line_load_N_per_m, 2 * results.vehicle_track.block_force_N / 0.6, rtol=1e-15
    )


def test_units_and_magnitudes_are_physical(results):
    """Loose sanity ranges in SI (a unit slip would miss them by 10³): kN forces, mm motions."""
    summary = results.summary()
    assert 5e3 < summary["peak_invert_force_N"] < 1e5
    assert 1e-5 < summary["peak_block_disp_m"] < 1e-2
    assert 1e-5 < summary["peak_disp_invert_m"] < 0.1
    assert summary["peak_disp_deepest_m"] < summary["peak_disp_invert_m"]
    assert summary["soil_s_wave_speed_m_s"] == pytest.approx(35.806, abs=1e-3)


def test_results_carry_the_scenario_that_made_them(results, cheap_scenario):
    assert results.scenario.to_dict() == cheap_scenario().to_dict()


def test_cache_serves_exactly_the_stages_a_change_does_not_touch(cheap_scenario):
    cache = StageCache()
    scenario = cheap_scenario()
    first = run(scenario, cache=cache)
    assert first.cached_stages == ()
    again = run(scenario, cache=cache)
    assert again.cached_stages == pipeline.STAGES
    assert again.soil.peak_disp_m is first.soil.peak_disp_m  # served, not recomputed

    scenario.soil.youngs_modulus = 12e6
    soil_change = run(scenario, cache=cache)
    assert soil_change.cached_stages == ("vehicle_track", "load")
    assert soil_change.vehicle_track.block_force_N is first.vehicle_track.block_force_N
    assert not np.allclose(soil_change.soil.peak_disp_m, first.soil.peak_disp_m)
    # the load's spectrum was served: the same numbers as a run from scratch
    fresh = run(scenario, cache=None)
    np.testing.assert_array_equal(soil_change.soil.disp_m, fresh.soil.disp_m)
    np.testing.assert_array_equal(
        soil_change.stress.deviator_history_Pa, fresh.stress.deviator_history_Pa
    )

    scenario.tunnel.thickness = 0.35
    assert run(scenario, cache=cache).cached_stages == ("vehicle_track", "load")

    scenario.numerics.psd_segment = 0.5
    assert run(scenario, cache=cache).cached_stages == ("vehicle_track",)

    scenario.train.speed_kmh = 90.0
    assert run(scenario, cache=cache).cached_stages == ()
    downstream = {"soil": 5, "longterm": 5}
    transfer = {pipeline.TRANSFER: 5}  # each soil computation above had new soil inputs
    # the padded load's spectrum: new with each new load, reused by the soil and tunnel changes
    spectrum = {pipeline.LOAD_SPECTRUM: 3}
    assert cache.misses == {"vehicle_track": 2, "load": 3, **downstream, **transfer, **spectrum}
    assert cache.hits == {
        "vehicle_track": 4, "load": 3, **dict.fromkeys(downstream, 1), pipeline.TRANSFER: 0,
        pipeline.LOAD_SPECTRUM: 2,
    }  # fmt: skip


def test_cache_holds_a_scenario_once_every_stage_of_it_is_stored(cheap_scenario):
    cache = StageCache()
    scenario = cheap_scenario()
    assert not cache.holds(pipeline.stage_keys(scenario))
    run(scenario, cache=cache)
    hits, misses = dict(cache.hits), dict(cache.misses)
    assert cache.holds(pipeline.stage_keys(scenario))
    assert (cache.hits, cache.misses) == (hits, misses)  # asking counts nothing
    scenario.soil.youngs_modulus = 12e6  # its vehicle–track and load stages are stored
    assert not cache.holds(pipeline.stage_keys(scenario))


def test_a_new_load_on_the_same_record_grid_reuses_the_soil_transfer_bit_for_bit(
    cheap_scenario,
):
    """A seed or vehicle change gives a new load of the same length: the soil stage reuses the
    tunnel–soil kernel's values (the costly part) and gives what a fresh run gives."""
    cache = StageCache()
    scenario = cheap_scenario()
    run(scenario, cache=cache)
    for change in ({"irregularity": {"seed": 8}}, {"vehicle": {"primary_stiffness": 1.2e6}}):
        scenario.update(change)
        served = run(scenario, cache=cache)
        fresh = run(scenario, cache=None)
        assert served.cached_stages == ()
        np.testing.assert_array_equal(served.soil.disp_m, fresh.soil.disp_m)
        np.testing.assert_array_equal(
            served.stress.deviator_history_Pa, fresh.stress.deviator_history_Pa
        )
    assert cache.hits[pipeline.TRANSFER] == 2 and cache.misses[pipeline.TRANSFER] == 1


@pytest.mark.parametrize(
    "tunnel",
    [{"model": "2d"}, {"model": "2.5d"}, {"model": "2.5d", "ground": "half_space"}],
    ids=["2d", "2.5d", "half-space"],
)
def test_transfer_functions_prefetched_before_a_run_are_the_ones_it_uses(cheap_scenario, tunnel):
    """The record grid is known from the inputs: the transfer functions computed ahead (here in
    another thread, while the run's vehicle–track stage computes) are the run's, found under
    the key the run asks for, and the results equal a fresh run's bit for bit."""
    scenario = cheap_scenario()
    scenario.tunnel.param.update(**tunnel)
    cache = StageCache()
    with ThreadPoolExecutor(1) as pool:
        ahead = pool.submit(pipeline.prefetch_transfer, scenario, cache)
        served = run(scenario, cache=cache)
        ahead.result()
    assert cache.misses[pipeline.TRANSFER] == 1  # computed once, by whichever came first
    assert cache.hits[pipeline.TRANSFER] == 1
    fresh = run(scenario, cache=None)
    np.testing.assert_array_equal(served.soil.disp_m, fresh.soil.disp_m)
    np.testing.assert_array_equal(
        served.stress.deviator_history_Pa, fresh.stress.deviator_history_Pa
    )
    if served.ground is not None:
        np.testing.assert_array_equal(
            served.ground.velocity_level_dB, fresh.ground.velocity_level_dB
        )


def test_prefetching_refuses_what_a_run_refuses(cheap_scenario):
    scenario = cheap_scenario()
    scenario.numerics.dt = 1e-3  # beyond the explicit integration's stable step
    cache = StageCache()
    with pytest.raises(ValueError, match="dt"):
        pipeline.prefetch_transfer(scenario, cache)
    assert cache.misses[pipeline.TRANSFER] == 0


def test_a_transfer_from_another_grid_is_refused(cheap_scenario):
    from model.soil.stresses import section_response, section_transfer

    results = run(cheap_scenario(), cache=None)
    q, dt = results.load.line_load_N_per_m, float(results.load.t_s[1])
    transfer = section_transfer(q[: q.size // 2], dt, results.scenario)
    with pytest.raises(ValueError, match="another frequency grid"):
        section_response(q, dt, results.scenario, transfer)


def test_an_edited_profile_file_is_not_served_from_the_cache(tmp_path):
    path = tmp_path / "profile.csv"
    path.write_text("x_m,eta_mm\n-200,0\n200,0\n")
    scenario = Scenario.paper()
    scenario.irregularity.profile_csv = str(path)
    before = pipeline.stage_keys(scenario)["vehicle_track"]
    path.write_text("x_m,eta_mm\n-200,0\n0,1\n200,0\n")
    assert pipeline.stage_keys(scenario)["vehicle_track"] != before


def test_cache_is_bounded():
    cache = StageCache(size=2, transfer_size=1)
    for key in "abc":
        for stage in ("soil", pipeline.TRANSFER):
            cache.fetch(stage, key, lambda key=key: key)
    assert cache.get("soil", "a") is None
    assert cache.get("soil", "b") == "b" and cache.get("soil", "c") == "c"
    assert cache.get(pipeline.TRANSFER, "b") is None
    assert cache.get(pipeline.TRANSFER, "c") == "c"


def test_a_value_being_computed_is_waited_for_not_computed_again():
    """Threads asking for the same stage value while one computes it get that value; an
    exception of the computing thread reaches them too, and the next call computes afresh."""
    cache = StageCache()
    calls, gate = [], threading.Event()

    def slow():
        calls.append(1)
        gate.wait(5.0)
        return "value"

    with ThreadPoolExecutor(4) as pool:
        futures = [pool.submit(cache.fetch, "soil", "k", slow) for _ in range(4)]
        time.sleep(0.2)
        gate.set()
        outcomes = [f.result() for f in futures]
    assert len(calls) == 1
    assert sorted(outcomes) == [("value", False)] + [("value", True)] * 3

    def failing():
        gate.wait(5.0)
        raise ValueError("bad input")

    gate.clear()
    with ThreadPoolExecutor(2) as pool:
        futures = [pool.submit(cache.fetch, "load", "k", failing) for _ in range(2)]
        time.sleep(0.2)
        gate.set()
        for future in futures:
            with pytest.raises(ValueError, match="bad input"):
                future.result()
    assert cache.fetch("load", "k", lambda: "now") == ("now", False)


def test_concurrent_runs_of_one_scenario_compute_each_stage_once(cheap_scenario):
    cache = StageCache()
    with ThreadPoolExecutor(2) as pool:
        first, second = pool.map(lambda s: run(s, cache=cache), [cheap_scenario()] * 2)
    assert cache.misses["vehicle_track"] == 1 and cache.misses["soil"] == 1
    assert first.soil.peak_disp_m is second.soil.peak_disp_m


def test_every_numerics_parameter_is_in_some_stage_key():
    """A setting missing from every key would be silently ignored by the cache; the only ones
    left out are the point-load wavenumber numerics, which no stage reads."""
    used = set(pipeline.VEHICLE_TRACK_NUMERICS + pipeline.LOAD_NUMERICS + pipeline.SOIL_NUMERICS)
    assert used.isdisjoint(pipeline.WAVENUMBER_NUMERICS)
    assert used | set(pipeline.WAVENUMBER_NUMERICS) == set(Numerics.param) - {"name"}


@pytest.mark.parametrize("model", ["2d", "2.5d"])
def test_the_axis_depth_re_runs_the_long_term_stage_only(cheap_scenario, model):
    """tunnel.axis_depth is read by the static stress state alone (pipeline.LONGTERM_TUNNEL): a
    change leaves the soil key and the transfer functions' key as they were, and a cached run
    serves every stage but the long-term one, whose static strength changes with the depth."""
    scenario = cheap_scenario()
    scenario.tunnel.model = model
    before = pipeline.stage_keys(scenario)
    scenario.tunnel.axis_depth = 25.0
    after = pipeline.stage_keys(scenario)
    assert {stage for stage in before if before[stage] != after[stage]} == {"longterm"}
    if model == "2.5d":
        return  # the keys are the point; one run of the cheap 2D case checks the cache
    cache = StageCache()
    shallow = run(cheap_scenario(), cache=cache)
    deep = run(scenario, cache=cache)
    assert deep.cached_stages == ("vehicle_track", "load", "soil")
    assert np.all(deep.longterm.strength_Pa > shallow.longterm.strength_Pa)


@pytest.mark.parametrize("model", ["2d", "2.5d"])
def test_kernel_sampling_changes_the_soil_keys_only(model):
    """The kernel sampling changes the transfer functions (tests/test_soil_sampling.py): a cached
    soil stage or transfer made with another sampling must not be served."""
    scenario = Scenario.paper()
    scenario.tunnel.model = model
    before = pipeline.stage_keys(scenario)
    scenario.numerics.kernel_samples_per_cycle = 0
    after = pipeline.stage_keys(scenario)
    changed = {stage for stage in before if before[stage] != after[stage]}
    assert changed == {"soil", "longterm", pipeline.TRANSFER}


def test_progress_reports_each_stage_in_order_from_zero_to_one(cheap_scenario):
    calls = []
    run(cheap_scenario(), progress=lambda stage, f: calls.append((stage, f)), cache=None)
    stages = [stage for stage, _ in calls]
    assert [s for i, s in enumerate(stages) if i == 0 or stages[i - 1] != s] == list(
        pipeline.STAGES
    )
    for stage in pipeline.STAGES:
        fractions = [f for s, f in calls if s == stage]
        assert fractions[0] == 0.0 and fractions[-1] == 1.0
        assert all(np.diff(fractions) >= 0)


def test_each_stage_output_is_handed_on_once_it_is_ready(cheap_scenario):
    """``on_stage`` is told each stage's output, in order, before the next stage starts (a
    page draws the first stages' plots while the soil stage computes), computed or served."""
    shared = StageCache()
    for cache in (None, shared, shared):  # no cache, every stage computed, every stage served
        events, outputs = [], {}

        def on_stage(stage, output, events=events, outputs=outputs):
            events.append(("done", stage))
            outputs[stage] = output

        results = run(
            cheap_scenario(),
            progress=lambda stage, f, events=events: events.append((f"at {f:g}", stage)),
            cache=cache,
            on_stage=on_stage,
        )
        assert [stage for kind, stage in events if kind == "done"] == list(pipeline.STAGES)
        assert outputs["vehicle_track"] is results.vehicle_track
        assert outputs["load"] is results.load
        soil = (results.soil, results.stress, results.ground)
        assert all(a is b for a, b in zip(outputs["soil"], soil, strict=True))
        assert outputs["longterm"] is results.longterm
        for stage, following in zip(pipeline.STAGES, pipeline.STAGES[1:], strict=False):
            assert events.index(("done", stage)) < events.index(("at 0", following))
    assert set(results.cached_stages) == set(pipeline.STAGES)


def test_fast_train_on_soft_soil_and_short_records_give_warnings_not_errors():
    scenario = Scenario.paper()
    assert run_checks.scenario_warnings(scenario) == []
    scenario.soil.youngs_modulus = 1e6  # c2 = 14.6 m/s, below the train's 22.2 m/s
    scenario.train.single_bogie = True  # a 1.0 s passage, shorter than the 4 s PSD segment
    warnings = run_checks.scenario_warnings(scenario)
    assert any("152% of the soil shear-wave speed 14.6 m/s" in w for w in warnings)
    assert any("less than numerics.psd_segment = 4 s" in w for w in warnings)


def test_numerics_that_cut_the_response_short_give_warnings_or_are_refused():
    """approach · β < 4 leaves the block loaded at the record's ends (a warning); a padded
    record shorter than the passage plus 2 shear-wave transits to the deepest point wraps the
    deep response (refused, issue 10: no silently wrong number)."""
    scenario = Scenario.paper()
    scenario.numerics.approach_distance = 2.0
    scenario.numerics.zero_pad_factor = 1
    warnings = run_checks.scenario_warnings(scenario)
    assert any("approach_distance = 2 m is shorter than 4/β = 3.5 m" in w for w in warnings)
    with pytest.raises(ScenarioError, match=r"zero_pad_factor = 1 pads.*at least 2"):
        run_checks.check_record_padding(scenario)


def test_inconsistent_scenario_is_refused_before_any_computation(cheap_scenario):
    cache = StageCache()
    scenario = cheap_scenario()
    scenario.irregularity.wavelength_min = 80.0
    with pytest.raises(ScenarioError, match="wavelength_min"):
        run(scenario, cache=cache)
    assert sum(cache.misses.values()) == 0


def test_unstable_integration_stops_the_pipeline_with_the_reason(monkeypatch, cheap_scenario):
    """Δt = 2.5e-4 s is beyond the explicit limit; with the input check bypassed the run
    diverges, and the pipeline refuses to feed a truncated record to the soil stage."""
    from model.track import vehicle_track

    scenario = cheap_scenario()
    scenario.numerics.dt = 2.5e-4
    monkeypatch.setattr(vehicle_track, "stable_time_step", lambda s: 1.0)
    cache, handed_on = StageCache(), []
    with pytest.raises(pipeline.SimulationError, match="went unstable.*numerics.dt"):
        run(scenario, cache=cache, on_stage=lambda stage, output: handed_on.append(stage))
    assert cache.misses["load"] == cache.misses["soil"] == 0
    assert handed_on == []  # the diverged record is not handed on either


# ---- command line ---------------------------------------------------------------------------

CHEAP_SET = [
    "--preset",
    "single_bogie",
    "--set",
    "train.speed_kmh=100",
    "--set",
    "numerics.n_depths=11",
]


def test_cli_writes_readable_files(tmp_path, capsys):
    assert main([*CHEAP_SET, "--out", str(tmp_path)]) == 0
    printed = capsys.readouterr().out
    assert "peak invert force" in printed and f"({SETTLEMENT_COVERS})" in printed
    profile = np.loadtxt(tmp_path / "depth_profile.csv", delimiter=",", skiprows=1)
    assert profile.shape == (11, 2)
    header = (tmp_path / "time_histories.csv").read_text().splitlines()[0].split(",")
    assert header[:3] == ["t_s", "block_force_N", "block_disp_m"]
    wheels = np.loadtxt(tmp_path / "wheel_forces.csv", delimiter=",", skiprows=1)
    assert wheels.shape[1] == 3
    scenario = Scenario.from_json((tmp_path / "scenario.json").read_text())
    assert scenario.train.speed_kmh == 100.0
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["summary"]["peak_disp_invert_m"] == pytest.approx(profile[0, 1], rel=1e-6)
    assert summary["settlement_covers"] == SETTLEMENT_COVERS  # issue 25: what it covers


@pytest.mark.parametrize(
    ("override", "message"),
    [
        (
            "train.speed_kmh=-5",
            "train.speed_kmh = -5 km/h is outside the allowed range [1, 400] km/h (Speed)",
        ),
        ("train.speed_kmh=fast", "train.speed_kmh = 'fast' is not a number"),
        ("train.speed=5", "unknown parameter 'train.speed'; train has:"),
        ("speed_kmh", "must be of the form section.parameter=value"),
    ],
)
def test_cli_refuses_a_bad_set_with_a_clear_message(tmp_path, capsys, override, message):
    with pytest.raises(SystemExit) as info:
        main(["--set", override, "--out", str(tmp_path)])
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert message in err
    assert "Traceback" not in err


def test_cli_runs_as_a_module(tmp_path):
    """The real entry point, in a fresh interpreter (Numba's on-disk cache keeps it quick)."""
    done = subprocess.run(
        [sys.executable, "-m", "model", *CHEAP_SET, "--quiet", "--out", str(tmp_path)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "summary.json").exists()
