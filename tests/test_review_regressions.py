"""Regression tests for defects found in review (one test per defect, each fails before its fix)."""

import pytest

from model.longterm.cycles import range_weighted_cycles
from model.params import LongTerm
from model.pipeline import run

# Six points at two stress levels whose strains fall slightly with N: the least-squares fit
# gives b < 0, outside LongTerm.b's bounds (0, 1).
FALLING_STRAINS_CSV = (
    "N,strain,q_d,sigma_s\n"
    "10,1.0,20,100\n100,0.9,20,100\n1000,0.8,20,100\n"
    "10,2.0,40,100\n100,1.9,40,100\n1000,1.8,40,100\n"
)


def test_a_fit_outside_the_bounds_is_refused_whole_and_said_on_screen():
    """Applying a fit with b < 0 must neither raise from the button nor half-apply.

    Before the fix, ``param.update`` set law, soil class 'user' and a, then refused b: the
    callback raised and the long-term stage ran with the fitted a and the default b, m.
    """
    from dashboard.longterm_view import CalibrationPanel

    longterm = LongTerm()
    before = {name: getattr(longterm, name) for name in ("law", "soil_class", "a", "b", "m")}
    panel = CalibrationPanel(longterm=longterm)
    panel.load_text(FALLING_STRAINS_CSV, "falling.csv")
    assert panel.fit is not None and panel.fit["b"] < 0.0
    panel.apply()
    assert {name: getattr(longterm, name) for name in before} == before
    assert "Not applied" in panel.message.object and "longterm.b = " in panel.message.object


def test_a_passage_recorded_with_the_soil_already_loaded_counts_at_least_one_cycle(
    cheap_scenario,
):
    """One pulse whose record starts and ends above zero (the 2.5D model: the whole train
    loads the section through the lining at the record's start) is one passage, 0 → q_d → 0.

    Before the fix [0.3, 1, 0.3] counted (0.7/2 + 0.7/2) = 0.7 cycles, and the single-bogie
    run with the 2.5D model counted 0.84 cycles at the invert and 0.40 at 35 m. Exact
    arithmetic for the synthetic pulse (rel 1e-12); the run: ≥ 1 at every depth (one bogie,
    one pulse 0 → q_d → 0 at least).
    """
    assert range_weighted_cycles([0.3, 1.0, 0.3]) == pytest.approx(1.0, rel=1e-12)
    assert range_weighted_cycles([0.0, 1.0, 0.0]) == pytest.approx(1.0, rel=1e-12)
    scenario = cheap_scenario()
    scenario.tunnel.model = "2.5d"
    assert run(scenario).stress.rainflow_cycles.min() >= 1.0


def test_a_byte_order_mark_does_not_drop_the_first_row_of_a_headerless_triaxial_csv():
    """Before the fix "\\ufeff10" was not a number, so the first data row was taken for a
    header and silently dropped (5 points read from 6)."""
    from model.longterm.calibration import parse_triaxial_csv

    rows = "10,1.0,20,100\n100,1.2,20,100\n1000,1.4,20,100\n10,2.0,40,100\n100,2.3,40,100\n"
    data = parse_triaxial_csv("\ufeff" + rows + "1000,2.6,40,100\n", "bom.csv")
    assert data.n_cycles.size == 6 and data.n_cycles[0] == 10.0


def test_stage_results_cannot_be_rebound_behind_the_cache(cheap_scenario):
    """Arrays are read-only, but the vehicle–track and load results were plain dataclasses:
    ``r.load.line_load_N_per_m = r.load.line_load_N_per_m / 1e3`` (to kN/m) changed what the
    cache served to the next run. Every stage result must refuse the assignment."""
    import dataclasses

    from model.pipeline import STAGES, StageCache

    cache = StageCache()
    results = run(cheap_scenario(), cache=cache)
    for stage in STAGES:
        value = getattr(results, stage)
        name = dataclasses.fields(value)[0].name
        with pytest.raises(dataclasses.FrozenInstanceError):
            setattr(value, name, getattr(value, name))


def test_the_run_estimate_counts_the_stresses(cheap_scenario):
    """The soil stage also computes the stresses of issue 12 (six transfer functions, spectra
    and histories): its tracemalloc peak is about twice that of the displacements alone, and
    it takes longer. Before the fix the estimate had no entry for them, so neither the memory
    guard nor the slow-run warning saw them. The counted bytes (soil + stress entries) must
    cover the measured peak of the stage (an upper count: sizes, not timings)."""
    import tracemalloc

    from model.run_cost import estimate_run
    from model.soil.stresses import section_response

    scenario = cheap_scenario()
    scenario.numerics.n_depths = 71
    results = run(scenario)
    load = results.load
    tracemalloc.start()
    try:
        section_response(load.line_load_N_per_m, load.t_s[1], scenario)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    estimate = estimate_run(scenario)
    assert estimate.memory_bytes["soil"] + estimate.memory_bytes["stress"] >= peak
    assert estimate.seconds["stress"] > estimate.seconds["soil"]
    assert "numerics.n_depths" in estimate.blame["stress"]


def test_the_vehicle_track_warnings_cannot_be_appended_to_behind_the_cache(cheap_scenario):
    """The warnings list of a cached vehicle–track result was shared: a caller's append showed
    up in the warnings of every later run served from the cache."""
    from model.pipeline import StageCache

    scenario, cache = cheap_scenario(), StageCache()
    first = run(scenario, cache=cache)
    assert isinstance(first.vehicle_track.warnings, tuple)
    assert run(scenario, cache=cache).warnings == first.warnings
