"""What-if sessions without Panel: naming, the comparison table, the session file, overlays.

Hand-checked numbers use synthetic summaries (exact arithmetic on display units); everything
that needs real results uses two cheap pipeline runs that differ only in the soil (so the second
reuses the first's vehicle–track and load stages from a module cache).
"""

import dataclasses
import gc
import json
import math

import holoviews as hv
import numpy as np
import pandas as pd
import pytest

from dashboard import plots
from dashboard.whatif import (
    COMPARED,
    CURRENT_COLOUR,
    CURRENT_LABEL,
    DIFFERENCE,
    INPUTS_COLUMN,
    MAX_PINNED,
    PERCENT,
    PINNED_COLOURS,
    SESSION_FORMAT,
    SESSION_VERSION,
    VALUE,
    ComparedRun,
    WhatIfSession,
    comparison_table,
    default_name,
    describe_change,
    flat_inputs,
    load_session,
    read_session,
    save_session,
)
from model.params import Scenario
from model.pipeline import run


class CountingCompute:
    """A compute function that counts its calls and serves runs from the module cache."""

    def __init__(self, cache):
        self.cache, self.scenarios = cache, []

    def __call__(self, scenario):
        self.scenarios.append(scenario.to_json())
        return run(scenario, cache=self.cache)


# ---- naming ---------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "path, value, text",
    [
        ("track.fastener_stiffness", 4e7, "fastener stiffness 40 MN/m"),
        ("train.speed_kmh", 60.0, "speed 60 km/h"),
        ("soil.youngs_modulus", 6e6, "soil Young's modulus 6 MPa"),
        ("tunnel.youngs_modulus", 3.45e10, "lining Young's modulus 34.5 GPa"),
        ("track.fastener_damping", 5e4, "fastener damping 50 kN·s/m"),
        ("soil.poisson_ratio", 0.35, "soil Poisson's ratio 0.35"),  # "(-)": no unit
        ("irregularity.track_class", 5, "FRA track class 5"),  # acronym keeps its capitals
        ("longterm.lining_permeability", 1e-10, "lining permeability k_l 1e-10 m/s"),
        ("site.water_table_depth", 2.0, "water table depth 2 m"),
        ("site.layers", [{"name": "clay"}, {"name": "sand"}], "layers clay, sand"),
        ("train.single_bogie", True, "single bogie only: yes"),
        ("numerics.n_rail_modes", None, "rail modes automatic"),
        ("tunnel.model", "2.5d", "tunnel–soil model 2.5d"),
    ],
)
def test_describe_change_uses_the_label_and_an_engineering_unit(path, value, text):
    assert describe_change(path, value) == text


def test_describe_change_refuses_an_unknown_parameter():
    with pytest.raises(KeyError, match="train.nope"):
        describe_change("train.nope", 1.0)


def test_default_name_lists_what_differs_from_the_preset():
    scenario = Scenario.paper()
    assert default_name(scenario, Scenario.paper(), "paper") == "paper"
    scenario.track.fastener_stiffness = 4e7
    scenario.train.speed_kmh = 60.0
    assert default_name(scenario, Scenario.paper()) == (
        "speed 60 km/h, fastener stiffness 40 MN/m"  # in the order of the scenario's sections
    )
    scenario.soil.youngs_modulus = 12e6
    scenario.soil.density = 1900.0
    scenario.tunnel.thickness = 0.35
    assert default_name(scenario, Scenario.paper()) == (
        "speed 60 km/h, fastener stiffness 40 MN/m, lining thickness 0.35 m + 2 more"
    )


# ---- the comparison table -------------------------------------------------------------------
def _summary(force_kn, block_mm, invert_mm, at11_mm, deepest_mm, depth=35.0, **extra):
    """A synthetic Results.summary() (SI) from values in display units."""
    return {
        "peak_invert_force_N": force_kn * 1e3,
        "peak_block_disp_m": block_mm * 1e-3,
        "peak_disp_invert_m": invert_mm * 1e-3,
        "peak_disp_11m_m": at11_mm * 1e-3,
        "peak_disp_deepest_m": deepest_mm * 1e-3,
        "deepest_depth_m": depth,
        **extra,
    }


def _inputs(**changes):
    scenario = Scenario.paper()
    for path, value in changes.items():
        scenario.set_value(path.replace("__", "."), value)
    return flat_inputs(scenario)


def test_comparison_table_differences_in_units_and_percent():
    """Hand-checked: today's track 50 kN, 2.0 mm … against a softer fastener at 60 km/h.

    Every number is a short decimal; tolerance 1e-12 relative only absorbs the SI ↔ display
    conversion (×1e3, ×1e-3), which is not exact in binary.
    """
    runs = [
        ComparedRun("today", _summary(50.0, 2.0, 6.0, 3.0, 1.0), _inputs()),
        ComparedRun(
            "soft",
            _summary(60.0, 1.5, 6.6, 3.0, 0.0),
            _inputs(track__fastener_stiffness=4e7, train__speed_kmh=60.0),
        ),
        ComparedRun("fast", _summary(45.0, 2.5, 7.5, 2.4, 1.2), _inputs(train__speed_kmh=100.0)),
    ]
    table = comparison_table(runs, reference="today")
    force, block, invert, at11, deepest = (q.column for q in COMPARED[:5])
    deepest = "Peak displacement 35 m below (mm)"  # every run shares the deepest depth
    assert list(table.index) == ["today", "soft", "fast"]
    expected = {
        (force, VALUE): [50.0, 60.0, 45.0],
        (force, DIFFERENCE): [0.0, 10.0, -5.0],
        (force, PERCENT): [0.0, 20.0, -10.0],
        (block, DIFFERENCE): [0.0, -0.5, 0.5],
        (block, PERCENT): [0.0, -25.0, 25.0],
        (invert, DIFFERENCE): [0.0, 0.6, 1.5],
        (invert, PERCENT): [0.0, 10.0, 25.0],
        (at11, PERCENT): [0.0, 0.0, -20.0],
        (deepest, DIFFERENCE): [0.0, -1.0, 0.2],
        (deepest, PERCENT): [0.0, -100.0, 20.0],
    }
    for column, values in expected.items():
        np.testing.assert_allclose(table[column].to_numpy(), values, rtol=1e-12, atol=1e-12)
    assert "Long-term settlement (mm)" not in table.columns.get_level_values(0)
    assert list(table[INPUTS_COLUMN]) == [
        "speed 80 km/h, fastener stiffness 80 MN/m",
        "speed 60 km/h, fastener stiffness 40 MN/m",
        "speed 100 km/h, fastener stiffness 80 MN/m",
    ]
    # against another reference, a zero reference value gives no percentage
    other = comparison_table(runs, reference="soft")
    assert other.loc["today", (force, DIFFERENCE)] == pytest.approx(-10.0, rel=1e-12)
    assert math.isnan(other.loc["fast", (deepest, PERCENT)])
    assert other.loc["fast", (deepest, DIFFERENCE)] == pytest.approx(1.2, rel=1e-12)


def test_comparison_table_takes_long_term_settlement_when_a_summary_has_it():
    runs = [
        ComparedRun("a", _summary(50, 2, 6, 3, 1, longterm_settlement_m=0.040), _inputs()),
        ComparedRun("b", _summary(50, 2, 6, 3, 1, depth=40.0), _inputs()),
    ]
    table = comparison_table(runs, reference="a")
    column = "Long-term settlement (mm)"
    assert table.loc["a", (column, VALUE)] == pytest.approx(40.0, rel=1e-12)
    assert math.isnan(table.loc["b", (column, VALUE)])
    # the deepest depths differ, so the heading does not name one
    assert "Peak displacement at the deepest depth (mm)" in table.columns.get_level_values(0)
    assert list(table[INPUTS_COLUMN]) == ["", ""]  # identical inputs
    with pytest.raises(KeyError, match="unknown reference run 'c'"):
        comparison_table(runs, reference="c")


def test_session_comparison_has_every_pinned_run_and_the_current_one(base_results, stiff_results):
    session = WhatIfSession(baseline=base_results.scenario, baseline_name="cheap")
    session.pin(base_results)
    session.pin(stiff_results)
    session.set_visible("cheap", False)  # hidden from the plots, still compared
    table = session.comparison(current=stiff_results)
    assert list(table.index) == ["cheap", "soil Young's modulus 12 MPa", CURRENT_LABEL]
    force = COMPARED[0].column
    summary = base_results.summary()
    assert table.loc["cheap", (force, VALUE)] == summary["peak_invert_force_N"] * 1e-3
    # the soil does not change the vehicle–track stage: the same load, Δ = 0 exactly
    assert table.loc[CURRENT_LABEL, (force, DIFFERENCE)] == 0.0
    invert = COMPARED[2].column
    expected = (
        stiff_results.summary()["peak_disp_invert_m"] / summary["peak_disp_invert_m"] - 1
    ) * 100
    assert table.loc[CURRENT_LABEL, (invert, PERCENT)] == pytest.approx(expected, rel=1e-12)
    assert list(table[INPUTS_COLUMN]) == [
        "soil Young's modulus 6 MPa",
        "soil Young's modulus 12 MPa",
        "soil Young's modulus 12 MPa",
    ]
    session.reference = CURRENT_LABEL
    stiff_invert = stiff_results.summary()["peak_disp_invert_m"]
    assert session.comparison(current=stiff_results).loc["cheap", (invert, PERCENT)] == (
        pytest.approx((summary["peak_disp_invert_m"] / stiff_invert - 1) * 100, rel=1e-12)
    )
    # without a current run, a current-run reference falls back to the first pinned run
    assert session.comparison().loc["cheap", (invert, DIFFERENCE)] == 0.0


# ---- pinning --------------------------------------------------------------------------------
def test_pinning_keeps_the_results_and_never_recomputes(base_results, monkeypatch):
    """Pinning stores the very Results object given: no pipeline call at all."""

    def no_run(*args, **kwargs):
        raise AssertionError("pinning must not run the pipeline")

    monkeypatch.setattr("dashboard.whatif.run", no_run)
    session = WhatIfSession()
    pinned = session.pin(base_results, "today")
    assert pinned.results is base_results
    assert pinned.scenario_json == base_results.scenario_json
    assert pinned.summary == base_results.summary()
    assert session.overlays() == [("today", base_results, PINNED_COLOURS[0])]


def test_at_most_eight_runs_with_distinct_colours(base_results):
    session = WhatIfSession(baseline=base_results.scenario, baseline_name="cheap")
    for _ in range(MAX_PINNED):
        session.pin(base_results)
    assert session.names() == ["cheap", *[f"cheap ({k})" for k in range(2, MAX_PINNED + 1)]]
    assert [r.colour for r in session.runs] == list(PINNED_COLOURS)
    assert CURRENT_COLOUR not in PINNED_COLOURS
    with pytest.raises(ValueError, match=f"at most {MAX_PINNED} runs can be pinned"):
        session.pin(base_results, "one more")
    assert len(session.runs) == MAX_PINNED
    session.remove("cheap (3)")  # its colour is free again and goes to the next pin
    assert session.pin(base_results, "again").colour == PINNED_COLOURS[2]


def test_rename_hide_restore_remove(base_results, stiff_results):
    session = WhatIfSession()
    session.pin(base_results, "today")
    session.pin(stiff_results, "stiff")
    session.reference = "stiff"
    session.rename("stiff", "stiff soil")
    assert session.reference == "stiff soil"  # the reference follows the rename
    for bad, message in (
        ("today", "already named"),
        (CURRENT_LABEL, "current run"),
        (" ", "needs a name"),
    ):
        with pytest.raises(ValueError, match=message):
            session.rename("stiff soil", bad)
    session.set_visible("today", False)
    assert [name for name, _, _ in session.overlays()] == ["stiff soil"]
    restored = session.restore("stiff soil")
    assert restored.to_json() == stiff_results.scenario_json
    restored.soil.youngs_modulus = 1e6  # an independent copy
    assert session.get("stiff soil").scenario.soil.youngs_modulus == 12e6
    session.remove("stiff soil")
    assert session.names() == ["today"] and session.reference == "today"
    with pytest.raises(KeyError, match="no pinned run is named 'stiff soil'"):
        session.restore("stiff soil")
    session.clear()
    assert session.runs == [] and session.reference == CURRENT_LABEL


def test_two_sessions_share_nothing(base_results):
    first, second = WhatIfSession(), WhatIfSession()
    first.pin(base_results, "mine")
    first.baseline.train.speed_kmh = 50.0
    assert second.runs == [] and second.overlays() == []
    assert second.baseline.train.speed_kmh == 80.0
    second.pin(base_results, "mine")  # the same name is free in another session
    second.rename("mine", "theirs")
    assert first.names() == ["mine"] and second.names() == ["theirs"]


# ---- the session file -----------------------------------------------------------------------
def test_session_file_round_trip_recomputes_through_the_given_function(
    cache, base_results, stiff_results
):
    session = WhatIfSession()
    session.pin(base_results, "today")
    session.pin(stiff_results, "stiff soil")
    session.set_visible("today", False)
    session.reference = "stiff soil"
    current = base_results.scenario
    current.train.speed_kmh = 90.0
    text = save_session(session, current=current)
    data = json.loads(text)
    assert (data["format"], data["version"]) == (SESSION_FORMAT, SESSION_VERSION)
    assert "results" not in text and "block_force" not in text  # inputs only

    compute = CountingCompute(cache)
    loaded, loaded_current = load_session(text, compute=compute)
    assert compute.scenarios == [base_results.scenario_json, stiff_results.scenario_json]
    assert loaded.names() == ["today", "stiff soil"]
    assert [r.visible for r in loaded.runs] == [False, True]
    assert [r.colour for r in loaded.runs] == [r.colour for r in session.runs]
    assert loaded.reference == "stiff soil"
    assert loaded_current.to_json() == current.to_json()
    pd.testing.assert_frame_equal(
        loaded.comparison(stiff_results), session.comparison(stiff_results)
    )
    assert save_session(loaded, current=loaded_current) == text


def _session_text(**changes):
    data = {
        "format": SESSION_FORMAT,
        "version": SESSION_VERSION,
        "reference": None,
        "runs": [
            {"name": "a", "visible": True, "colour": PINNED_COLOURS[0], "scenario": {}},
        ],
        "current": None,
    }
    data.update(changes)
    return json.dumps(data)


@pytest.mark.parametrize(
    "text, message",
    [
        ("{not json", "not valid JSON"),
        ("[" * 100_000 + "]" * 100_000, "nested too deeply"),  # Python's parser recurses
        (b"\xff\xfe", "not UTF-8"),
        (Scenario.paper().to_json(), "format tag is not 'tunnelsettle-whatif-session'"),
        ("[1, 2]", "format tag"),
        (_session_text(version=2), "version 2 is not supported"),
        (_session_text(runs={}), "'runs' must be a list"),
        (
            _session_text(
                runs=[
                    {
                        "name": "soft",
                        "colour": PINNED_COLOURS[0],
                        "scenario": {"soil": {"youngs_modulus": -1.0}},
                    }
                ]
            ),
            "run 'soft': soil.youngs_modulus = -1 Pa is outside the allowed range",
        ),
        (
            _session_text(runs=[{"name": "x", "colour": "red", "scenario": {}}]),
            "colour 'red'",
        ),
        (
            _session_text(runs=[{"name": "x", "colour": "#E69F00", "scenario": {"ship": {}}}]),
            "run 'x': unknown section 'ship'",
        ),
        (
            _session_text(runs=[{"name": "x", "colour": "#E69F00", "scenario": {}}] * 2),
            "names must be unique",
        ),
        (
            _session_text(
                runs=[{"name": f"r{i}", "colour": "#E69F00", "scenario": {}} for i in range(9)]
            ),
            "9 runs, at most 8",
        ),
        (_session_text(reference="zz"), "reference 'zz' is not one of the runs"),
        (
            _session_text(current={"train": {"speed_kmh": 0}}),
            "the current scenario: train.speed_kmh = 0 km/h",
        ),
    ],
)
def test_bad_or_foreign_session_files_are_refused_clearly(text, message):
    with pytest.raises(ValueError) as refused:
        read_session(text)
    assert message in str(refused.value)


def test_a_failing_run_names_the_run(cache):
    def failing(scenario):
        raise RuntimeError("diverged")

    with pytest.raises(ValueError, match="run 'a' of the session failed: diverged"):
        load_session(_session_text(), compute=failing)


# ---- overlays -------------------------------------------------------------------------------
def _layers(element):
    """Curves of an element or overlay in drawing order (the last is on top)."""
    layers = list(element.values()) if isinstance(element, hv.Overlay) else [element]
    return [layer for layer in layers if isinstance(layer, hv.Curve)]


def _pinned(element) -> dict[str, np.ndarray]:
    """The pinned runs' lines of a plot by name: (n, 2) x, y of each, in drawing order."""
    layers = list(element.values()) if isinstance(element, hv.Overlay) else [element]
    (pinned,) = [layer for layer in layers if isinstance(layer, hv.Contours)]
    return {line.dimension_values("run")[0]: line.array(line.kdims) for line in pinned.split()}


def _colour(element):
    return element.opts.get().kwargs.get("color")


def test_every_plot_overlays_the_pinned_runs_under_the_current_one(base_results, stiff_results):
    session = WhatIfSession()
    session.pin(base_results, "today")
    session.pin(stiff_results, "stiff soil")
    overlays = session.overlays()
    for spec in plots.PLOTS:
        alone = _layers(spec.draw(base_results))
        drawn = spec.draw(base_results, overlays=overlays)
        layers = list(drawn.values())
        pinned_layer = next(x for x in layers if isinstance(x, hv.Contours))
        curves = _layers(drawn)
        # the pinned runs under the current run (on top, in its colour); on the block
        # displacement plot the current run's Winkler curve follows as a reference line
        assert layers.index(pinned_layer) < layers.index(curves[0]), spec.key
        assert curves[0].label == CURRENT_LABEL and _colour(curves[0]) == CURRENT_COLOUR
        assert pinned_layer.opts.get().kwargs["cmap"] == dict(
            zip(["today", "stiff soil"], PINNED_COLOURS[:2], strict=True)
        )
        pinned = _pinned(drawn)
        assert list(pinned) == ["today", "stiff soil"], spec.key
        # each pinned line is that run's own curve (its data, drawn alone), thinned to
        # PINNED_DISPLAY_POINTS by min/max decimation: every extreme stays
        own = _layers(spec.draw(stiff_results))[0]
        own_x, own_y = own.dimension_values(0), own.dimension_values(1)
        x, y = pinned["stiff soil"].T
        assert y.size <= max(plots.PINNED_DISPLAY_POINTS, 1)
        assert y.max() == own_y.max() and y.min() == own_y.min()
        assert np.isin(y, own_y).all() and np.isin(x, own_x).all()
        if own_y.size <= plots.PINNED_DISPLAY_POINTS:
            np.testing.assert_array_equal(y, own_y)
        np.testing.assert_array_equal(curves[0].dimension_values(1), alone[0].dimension_values(1))
    session.set_visible("today", False)
    assert list(_pinned(plots.invert_load_plot(base_results, overlays=session.overlays()))) == [
        "stiff soil"
    ]


def test_plots_without_a_current_run_show_only_the_pinned_ones(base_results, stiff_results):
    overlays = [("a", base_results, PINNED_COLOURS[0]), ("b", stiff_results, PINNED_COLOURS[1])]
    for spec in plots.PLOTS:
        drawn = spec.draw(None, overlays=overlays)
        assert list(_pinned(drawn)) == ["a", "b"]
        assert not any(c.label == CURRENT_LABEL for c in _layers(drawn))


def test_pinned_layers_are_built_once_and_released_with_their_run(base_results):
    """Redrawing with the same pinned run reuses its very layer (so a plot updated in place
    re-sends no data for it); the layer is forgotten once the run is released."""
    pinned_run = dataclasses.replace(base_results)  # a Results object of its own
    overlays = [("pinned", pinned_run, PINNED_COLOURS[0])]

    def pinned_layer(overlays):
        drawn = plots.invert_load_plot(base_results, overlays=overlays)
        return next(x for x in drawn.values() if isinstance(x, hv.Contours))

    first = pinned_layer(overlays)
    assert pinned_layer(overlays) is first
    held = [key for key in plots._PINNED_LAYERS if key[1][0][0] == id(pinned_run)]
    assert len(held) == 1
    del overlays, pinned_run, first
    gc.collect()
    assert not any(key in plots._PINNED_LAYERS for key in held)


def test_a_pinned_time_history_is_thinned_with_its_extremes_kept():
    t = np.linspace(0.0, 1.0, 20_001)
    y = np.sin(40 * t) * np.exp(-t)
    y[12_345] = 3.0  # one sharp peak
    thinned = plots._thinned(hv.Curve((t, y)))
    assert len(thinned) <= plots.PINNED_DISPLAY_POINTS
    assert thinned.dimension_values(1).max() == 3.0
    assert thinned.dimension_values(1).min() == y.min()
