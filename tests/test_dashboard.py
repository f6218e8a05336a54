"""Dashboard without a browser: plots carry the pipeline's numbers, the app builds and reacts.

All runs use a cheap scenario (single bogie at 100 km/h, 11 output depths) and the real
pipeline; one stage cache per module keeps repeated stages out of the test time.
"""

import asyncio
import dataclasses
import datetime
import html
import io
import json
import re
import time
from concurrent.futures import Future
from types import SimpleNamespace

import bokeh.models
import bokeh.plotting
import holoviews as hv
import numpy as np
import panel as pn
import param
import pytest
from bokeh.core.property.vectorization import Field, Value
from bokeh.document import Document
from panel.io.resources import set_resource_mode
from panel.io.state import set_curdoc

from dashboard import key_numbers, legend_swatches, parsed, plot_panes, plots
from dashboard import runs as runs_module
from dashboard.app import Dashboard
from dashboard.export import main as export_main
from dashboard.inputs import HIDDEN, PRIMARY, SWITCHES
from dashboard.legend_swatches import SWATCH_TAG
from dashboard.longterm_view import LONGTERM_PLOTS
from dashboard.report import package_version, report_html
from dashboard.scheduler import RunCancelled
from dashboard.whatif import CURRENT_LABEL
from model import scenarios
from model.longterm.statements import SETTLEMENT_COVERS
from model.params import SECTIONS, Scenario, display_label, display_unit, parameter_of
from model.pipeline import STAGES, StageCache, run

MM = 1e3
ALL_PLOTS = (*plots.PLOTS, *LONGTERM_PLOTS)


@pytest.fixture(scope="module")
def cache():
    return StageCache()


@pytest.fixture(scope="module")
def results(cache, cheap_scenario):
    return run(cheap_scenario(), cache=cache)


@pytest.fixture
def dashboard(cache, cheap_scenario):
    board = Dashboard(scenario=cheap_scenario(), preset="single_bogie", cache=cache)
    board.refresh()
    return board


def _curves(element):
    """Every Curve/Scatter of an element or overlay, by label."""
    layers = element.values() if isinstance(element, hv.Overlay) else [element]
    return {layer.label: layer for layer in layers}


def _plot_views(board):
    """The page's plot panes: the passage plots, then the long-term ones."""
    return (board.passage.plots, board.longterm.plots)


def _panes(board):
    """Every plot pane of the page, by plot key."""
    return {key: pane for view in _plot_views(board) for key, pane in view.panes.items()}


def _streams(board):
    """The stream of every plot drawn so far, by plot key."""
    return {key: stream for view in _plot_views(board) for key, stream in view.streams.items()}


def _is_stale(board, key):
    """True while the plot ``key`` waits for a run that will change it."""
    return next(view for view in _plot_views(board) if key in view.panes).is_stale(key)


def _shown(board, key):
    """The element a dashboard plot shows now (its DynamicMap evaluated on its stream)."""
    return _panes(board)[key].object[()]


def _drawn_plot(pane):
    """The HoloViews plot a pane draws on its page (its one root)."""
    return next(iter(pane._plots.values()))[0]


def _pane_data(board, key):
    """(x, y) arrays of the first curve shown in a dashboard plot."""
    curve = next(iter(_curves(_shown(board, key)).values()))
    return curve.dimension_values(0), curve.dimension_values(1)


# ---- plots.py -------------------------------------------------------------------------------
def test_decimation_keeps_extremes_ends_and_order():
    """A 100 001-sample record thinned to ≤ 1000 points keeps its exact max, min, ends, order."""
    x = np.linspace(0.0, 1.0, 100_001)
    y = np.sin(40 * np.pi * x) * np.exp(-x) + 1e-3 * np.cos(997 * x)
    xd, yd = plots.decimate_min_max(x, y, max_points=1000)
    assert xd.size <= 1000
    assert yd.max() == y.max() and yd.min() == y.min()
    assert (xd[0], xd[-1]) == (x[0], x[-1])
    assert np.all(np.diff(xd) > 0)
    np.testing.assert_array_equal(yd, np.interp(xd, x, y))  # points are samples, not averages


def test_decimation_leaves_short_records_alone():
    x = np.arange(10.0)
    xd, yd = plots.decimate_min_max(x, x**2, max_points=10)
    assert xd is x and np.array_equal(yd, x**2)


def test_time_plots_show_the_pipeline_numbers_in_display_units(results):
    """Peaks on screen equal the summary's (exact: decimation keeps extremes; ×1e3 for mm/kN)."""
    summary = results.summary()
    disp = _curves(plots.block_displacement_plot(results))
    assert set(disp) == {"Vehicle–track model", "Winkler beam (BOEF)"}
    assert disp["Vehicle–track model"].dimension_values(1).max() == pytest.approx(
        summary["peak_block_disp_m"] * MM, rel=1e-12
    )
    assert disp["Winkler beam (BOEF)"].dimension_values(1).max() == pytest.approx(
        results.vehicle_track.winkler_block_disp_m.max() * MM, rel=1e-12
    )
    load = plots.invert_load_plot(results)
    assert load.dimension_values(1).max() == pytest.approx(
        summary["peak_invert_force_N"] / 1e3, rel=1e-12
    )
    assert load.dimensions()[0].pprint_label == "Time (s)"
    assert load.dimensions()[1].pprint_label.endswith("(kN)")


def test_psd_plots_are_positive_and_within_the_soil_frequency_limit(results):
    limit = results.scenario.numerics.soil_max_frequency
    for draw, unit in ((plots.load_psd_plot, "(kN/m)²/Hz"), (plots.interface_psd_plot, "mm²/Hz")):
        curve = draw(results)
        f, p = curve.dimension_values(0), curve.dimension_values(1)
        assert f.size > 10 and np.all(f > 0) and f.max() <= limit and np.all(p > 0)
        assert curve.dimensions()[1].unit == unit
    interface = plots.interface_psd_plot(results)
    f = interface.dimension_values(0)
    keep = (results.soil.f_hz > 0) & (results.soil.f_hz <= limit)
    np.testing.assert_allclose(
        interface.dimension_values(1),
        results.soil.interface_psd[keep][np.isin(results.soil.f_hz[keep], f)] * MM**2,
        rtol=1e-12,
    )


def test_depth_plot_overlays_both_paper_series_separately(results):
    layers = _curves(plots.depth_profile_plot(results))
    assert set(layers) == {"2D section", "Paper Fig. 11", "Paper conclusions"}
    model = layers["2D section"]
    np.testing.assert_allclose(model.dimension_values(0), results.soil.peak_disp_m * MM)
    np.testing.assert_allclose(model.dimension_values(1), results.soil.depth_m)
    fig11 = layers["Paper Fig. 11"]
    np.testing.assert_allclose(fig11.dimension_values(0), [6.72, 2.94])  # docs/model.md §8, mm
    np.testing.assert_allclose(fig11.dimension_values(1), [0.0, 11.0])
    conclusions = layers["Paper conclusions"]
    np.testing.assert_allclose(conclusions.dimension_values(0), [7.27, 0.91])
    np.testing.assert_allclose(conclusions.dimension_values(1), [0.0, 35.0])


def test_reference_data_is_found_from_any_working_directory(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert [s["label"] for s in plots.paper_reference()] == ["Paper Fig. 11", "Paper conclusions"]


def test_results_of_the_same_inputs_share_one_parsed_scenario(results):
    """The first stages' results drawn early and the whole run's share the scenario parsed
    for the first (each parse takes milliseconds); the summary then parses nothing."""
    early = dataclasses.replace(results, soil=None, stress=None, longterm=None)
    assert parsed.scenario_of(early) is parsed.scenario_of(results)
    assert parsed.scenario_of(results).to_dict() == results.scenario.to_dict()
    assert parsed.summary_of(results) == results.summary()
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(Scenario, "from_json", lambda text: pytest.fail("parsed again"))
        assert results.summary(parsed.scenario_of(results)) == parsed.summary_of(results)


def test_summary_items_are_the_summary_in_display_units(results):
    summary = results.summary()
    items = {item.key: item for item in key_numbers.summary_items(results)}
    assert items["peak_block_disp"].value == summary["peak_block_disp_m"] * MM
    assert items["peak_invert_force"].value == summary["peak_invert_force_N"] / 1e3
    assert items["peak_disp_11m"].value == summary["peak_disp_11m_m"] * MM
    assert items["peak_disp_deepest"].label == "… 35 m below the invert"
    soil = {item.key: item for item in key_numbers.soil_items(results.scenario.soil)}
    assert soil["soil_s_wave_speed"].value == results.scenario.soil.s_wave_speed
    assert soil["soil_shear_modulus"].unit == "MPa"


# ---- app.py and its parts ------------------------------------------------------------------------
def test_app_builds_with_a_control_for_every_parameter(dashboard):
    page = dashboard.template()
    assert isinstance(page, pn.template.BootstrapTemplate)
    expected = {
        f"{section}.{name}"
        for section in SECTIONS
        for name in getattr(dashboard.scenario, section).param
        if name != "name"
    }
    assert set(dashboard.inputs.controls) == expected - HIDDEN
    assert set(PRIMARY) <= set(dashboard.inputs.controls)
    pn.Row(dashboard).get_root()  # the whole layout renders to Bokeh models


def test_sidebar_has_the_main_inputs_up_front_and_the_rest_in_groups(dashboard):
    """Groups start collapsed and empty (fast page load) and fill on first opening."""
    sidebar = dashboard.sidebar()
    up_front = [item for item in sidebar if item in dashboard.inputs.controls.values()]
    assert up_front == [dashboard.inputs.controls[p] for p in (*SWITCHES, *PRIMARY)]
    assert dashboard.inputs.preset_select in sidebar and dashboard.inputs.train_type in sidebar
    cards = [item for item in sidebar if isinstance(item, pn.Card)]
    grouped = {}
    for card in cards[:-1]:  # the last card holds the scenario file controls
        assert card.collapsed and not card.objects
        card.collapsed = False
        grouped[card.title] = list(card.objects)
    in_groups = {
        path
        for path, control in dashboard.inputs.controls.items()
        if any(control.__panel__() in members for members in grouped.values())
    }
    assert in_groups == set(dashboard.inputs.controls) - set(PRIMARY) - set(SWITCHES)
    controls = dashboard.inputs.controls
    assert controls["soil.poisson_ratio"].__panel__() in grouped["Soil"]
    assert controls["longterm.years"].__panel__() in grouped["Long-term settlement"]


def test_controls_take_unit_label_range_value_and_tooltip_from_the_params(dashboard):
    """No default or range is repeated in the app: all come from model.params, scaled to the
    display unit (exact up to the 12 significant digits the conversion keeps)."""
    for path, control in dashboard.inputs.controls.items():
        p = parameter_of(path)
        unit, factor = display_unit(path)
        assert control.label == display_label(path), path
        assert p.doc in control.tooltip and control.label in control.tooltip, path
        value = getattr(getattr(dashboard.scenario, path.split(".")[0]), path.split(".")[1])
        if control.slider is not None:
            low, high = p.softbounds
            shown = value if isinstance(p, param.Integer) else value * factor
            assert control.slider.start == pytest.approx(min(low * factor, shown), rel=1e-12)
            assert control.slider.end == pytest.approx(max(high * factor, shown), rel=1e-12)
            assert control.slider.value == pytest.approx(shown, rel=1e-12), path
    soil = dashboard.inputs.controls["soil.youngs_modulus"]
    assert soil.label == "Soil Young's modulus (MPa)" and soil.text.value == "6"
    assert dashboard.inputs.controls["track.rail_E"].text.value == "205.9"  # GPa
    assert dashboard.inputs.controls["track.fastener_stiffness"].text.value == "80"  # MN/m


def test_first_refresh_fills_every_plot_and_the_summary(dashboard):
    for key, pane in _panes(dashboard).items():
        assert pane.object is not None and not _is_stale(dashboard, key), key
        x, y = _pane_data(dashboard, key)
        assert x.size > 10 and np.all(np.isfinite(y)), key
    assert 'data-key="peak_disp_invert"' in dashboard.passage.summary.object
    assert dashboard.runs.render_counts == dict.fromkeys(STAGES, 1)
    assert dashboard.report_button.disabled is False


def test_a_change_computes_before_it_returns_inside_a_running_event_loop(cache, cheap_scenario):
    """A Jupyter kernel runs an event loop in the notebook's thread (docs/dashboard.ipynb): a
    dashboard without a server still has its results when a change returns."""

    async def in_a_notebook():
        board = Dashboard(scenario=cheap_scenario(), preset="single_bogie", cache=cache)
        board.refresh()
        board.inputs.controls["train.speed_kmh"].enter("90")
        return board.runs.results

    results = asyncio.run(in_a_notebook())
    assert results is not None and results.scenario.train.speed_kmh == 90


def test_speed_change_updates_every_plot(dashboard):
    before = {key: np.concatenate(_pane_data(dashboard, key)) for key in _panes(dashboard)}
    dashboard.inputs.controls["train.speed_kmh"].slide(90.0)
    assert dashboard.scenario.train.speed_kmh == 90.0
    assert dashboard.runs.results.scenario.train.speed_kmh == 90.0
    for key in _panes(dashboard):
        after = np.concatenate(_pane_data(dashboard, key))
        assert after.shape != before[key].shape or not np.array_equal(after, before[key]), key
    assert dashboard.runs.render_counts == dict.fromkeys(STAGES, 2)


def _while_the_soil_stage_computes(monkeypatch, look=None, fail=False):
    """Make the soil stage call ``look()`` first, once the page has drawn the first stages'
    plots (it waits for them up to a minute), and raise after it if ``fail``."""
    from model import pipeline

    section_response = pipeline.section_response

    def soil_stage(*args):
        if look is not None:
            look()
        if fail:
            raise RuntimeError("the soil stage failed")
        return section_response(*args)

    monkeypatch.setattr(pipeline, "section_response", soil_stage)


def _early_drawn(board, deadline_s=60.0):
    """Wait until the block-displacement plot shows the results of a run still computing
    (its first stages only); True when it does."""
    end = time.monotonic() + deadline_s
    while time.monotonic() < end:
        if _streams(board)["block_displacement"].data.soil is None:
            return True
        time.sleep(0.01)
    return False


def test_the_first_stages_plots_are_drawn_while_the_soil_stage_computes(dashboard, monkeypatch):
    """A speed change: the vehicle–track and load plots show the new run before its soil
    stage ends (from its first stages' outputs), the soil plots and key numbers at its end."""
    old, summary = dashboard.runs.results, dashboard.passage.summary.object
    during = {}

    def look():
        if during:  # the other tunnel–soil model's run, after the results
            return
        assert _early_drawn(dashboard)
        streams = _streams(dashboard)
        for spec in plots.PLOTS:
            during[spec.key] = (streams[spec.key].data, _is_stale(dashboard, spec.key))
        during["summary"] = dashboard.passage.summary.object
        during["summary dimmed"] = dashboard.passage.summary.styles["opacity"] != "1"
        during["status"] = dashboard.runs.status.object

    _while_the_soil_stage_computes(monkeypatch, look)
    dashboard.inputs.controls["train.speed_kmh"].enter("86")  # a speed no other test runs
    new = dashboard.runs.results
    assert new.scenario.train.speed_kmh == 86.0 and during["summary"] == summary
    assert during["summary dimmed"]  # the key numbers follow at the end, dimmed till then
    assert "Computing" in during["status"] and "vehicle–track" not in during["status"]
    for spec in plots.PLOTS:
        shown, stale = during[spec.key]
        early = spec.stage in ("vehicle_track", "load")
        assert (shown is old) == (not early) and stale == (not early), spec.key
        if early:  # the new run's own outputs, drawn once
            assert shown.vehicle_track is new.vehicle_track and shown.load is new.load
        sent = _streams(dashboard)[spec.key].data
        assert (sent is shown) == early and (sent is new) == (not early), spec.key
        assert not _is_stale(dashboard, spec.key)
    assert dashboard.runs.render_counts == dict.fromkeys(STAGES, 2)
    assert dashboard.passage.summary.object != summary
    assert dashboard.passage.summary.styles["opacity"] == "1"


def test_a_run_failing_after_its_first_stages_leaves_the_previous_results_on_every_plot(
    dashboard, monkeypatch
):
    """The soil stage fails after the vehicle–track and load plots showed the new run: they
    show the previous results again, as the page says, and the next run draws them anew."""
    old = dashboard.runs.results
    _while_the_soil_stage_computes(monkeypatch, lambda: _early_drawn(dashboard), fail=True)
    dashboard.inputs.controls["train.speed_kmh"].enter("83")  # a speed no other test runs
    assert "the soil stage failed" in dashboard.messages.error_alert.object
    assert "the plots show the previous results" in dashboard.runs.status.object
    for key, stream in _streams(dashboard).items():
        assert stream.data is old and not _is_stale(dashboard, key), key
    assert dashboard.passage.summary.styles["opacity"] == "1"
    monkeypatch.undo()
    dashboard.inputs.controls["train.speed_kmh"].enter("84")
    new = dashboard.runs.results
    for spec in plots.PLOTS:
        assert _shown(dashboard, spec.key) is not None
        assert _streams(dashboard)[spec.key].data.vehicle_track is new.vehicle_track, spec.key


def test_slider_values_are_rounded_to_the_slider_step(dashboard):
    """A dragged position with binary noise (55.99999999999999) is set and shown as 56."""
    control = dashboard.inputs.controls["train.speed_kmh"]
    control.slide(95.99999999999999)
    assert dashboard.scenario.train.speed_kmh == 96.0
    assert control.text.value == "96"


def test_soil_change_in_display_units_redraws_only_the_soil_plots(dashboard):
    old = dashboard.runs.results
    panes = {key: pane.object for key, pane in _panes(dashboard).items()}
    summary_before = dashboard.passage.summary.object
    soil_before = dashboard.passage.soil_summary.object
    dashboard.inputs.controls["soil.youngs_modulus"].enter("12 MPa")
    assert dashboard.scenario.soil.youngs_modulus == 12e6  # SI inside
    assert set(dashboard.runs.results.cached_stages) == {"vehicle_track", "load"}
    for spec in plots.PLOTS:
        assert _panes(dashboard)[spec.key].object is panes[spec.key]  # updated in place
        sent = _streams(dashboard)[spec.key].data
        assert (sent is dashboard.runs.results) == (spec.stage == "soil"), spec.key
        assert (sent is old) == (spec.stage != "soil"), spec.key
    assert dashboard.runs.render_counts == {
        "vehicle_track": 1,
        "load": 1,
        **dict.fromkeys(STAGES[2:], 2),
    }
    assert dashboard.passage.summary.object != summary_before
    assert dashboard.passage.soil_summary.object != soil_before
    # doubling E at fixed ν doubles μ (2 × 2.3077 MPa from E = 6 MPa, ν = 0.3)
    assert "4.62 MPa" in dashboard.passage.soil_summary.object
    status = dashboard.runs.status.object
    assert 'data-renders="2"' in status and "cached" in status
    saved = json.loads(dashboard.inputs._scenario_file().getvalue())
    assert saved["soil"]["youngs_modulus"] == 12e6


def test_a_run_marks_only_the_plots_it_will_change_as_stale(dashboard):
    scenario = dashboard.scenario.copy()
    scenario.soil.density = 1900.0
    dashboard.runs._start(scenario)
    assert dashboard.runs.progress_shown
    for spec in plots.PLOTS:
        assert _is_stale(dashboard, spec.key) == (spec.stage == "soil"), spec.key
    dashboard.runs._note_progress("soil", 0.5)
    dashboard.runs._show_progress()
    assert dashboard.runs.progress.value == round(100 * 2.5 / len(STAGES))  # 2 stages done + 0.5
    assert "Computing soil… 50%" in dashboard.runs.status.object


def test_edits_during_a_run_give_one_more_run_with_the_newest_value(dashboard, monkeypatch):
    """Three edits while a run computes give exactly one further run, with the last value."""
    speeds = []
    compute = dashboard.runs.latest._compute

    def slow_user_compute(scenario):
        speeds.append(scenario.train.speed_kmh)
        if len(speeds) == 1:
            for speed in (91.0, 92.0, 93.0):
                dashboard.inputs.controls["train.speed_kmh"].enter(str(speed))
        return compute(scenario)

    monkeypatch.setattr(dashboard.runs.latest, "_compute", slow_user_compute)
    dashboard.inputs.controls["train.speed_kmh"].enter("90")
    assert speeds == [90.0, 93.0]
    assert dashboard.runs.results.scenario.train.speed_kmh == 93.0
    assert not dashboard.runs.latest.busy and not dashboard.runs.progress_shown


REFUSED = {
    "-5": "soil.youngs_modulus = -5 MPa is outside the allowed range [1, 100000] MPa; still 6 MPa",
    "0": "soil.youngs_modulus = 0 MPa is outside the allowed range [1, 100000] MPa; still 6 MPa",
    "-5000 kPa": "soil.youngs_modulus = -5 MPa (-5000 kPa) is outside the allowed range "
    "[1, 100000] MPa; still 6 MPa",
    "6 kPa": "soil.youngs_modulus = 0.006 MPa (6 kPa) is outside the allowed range "
    "[1, 100000] MPa; still 6 MPa",
    "abc": "soil.youngs_modulus = 'abc' is not a number in MPa; still 6 MPa",
    "1_00": "soil.youngs_modulus = '1_00' is not a number in MPa (digits with one decimal "
    "point or comma, no digit separators); still 6 MPa",
    "6 m": "soil.youngs_modulus = '6 m' has the unit m, not a unit of pressure: type it in Pa, "
    "kPa, MPa, GPa; still 6 MPa",
    "": "soil.youngs_modulus = '' is not a number in MPa; still 6 MPa",
}


@pytest.mark.parametrize("text", REFUSED)
def test_refused_text_gives_a_message_beside_the_field_and_changes_nothing(dashboard, text):
    control = dashboard.inputs.controls["soil.youngs_modulus"]
    results_before = dashboard.runs.results
    slider_range = (control.slider.start, control.slider.end)
    control.enter(text)
    assert control.refusal.visible and control.refused
    assert html.unescape(control.refusal.object) == REFUSED[text]
    assert not dashboard.messages.error_alert.visible  # beside the field, not above the tabs
    assert dashboard.scenario.soil.youngs_modulus == 6e6
    assert control.text.value == text  # the box keeps the typed text, to correct it
    assert control.slider.value == 6  # the slider shows the value in force
    assert (control.slider.start, control.slider.end) == slider_range
    assert dashboard.runs.results is results_before
    dashboard.inputs.controls["train.speed_kmh"].enter("90")  # a later accepted change...
    assert not control.refusal.visible  # ...clears the message
    assert control.text.value == "6"  # and the box shows the value in force


@pytest.mark.parametrize(
    ("text", "value"),
    [("6000 kPa", 6e6), ("6,5", 6.5e6), ("0.008 GPa", 8e6), ("7 mpa", 7e6), ("7.5MPa", 7.5e6)],
)
def test_typed_values_take_a_decimal_comma_and_units_of_the_same_kind(dashboard, text, value):
    control = dashboard.inputs.controls["soil.youngs_modulus"]
    control.enter(text)
    assert not control.refused
    assert dashboard.scenario.soil.youngs_modulus == value
    assert control.text.value == f"{value / 1e6:g}"


def test_the_speed_is_refused_in_km_h_with_its_dotted_name(dashboard):
    control = dashboard.inputs.controls["train.speed_kmh"]
    control.enter("-5")
    message = html.unescape(control.refusal.object)
    assert message == (
        "train.speed_kmh = -5 km/h is outside the allowed range [1, 400] km/h; still 100 km/h"
    )
    control.enter("50 m/s")  # 180 km/h
    assert dashboard.scenario.train.speed_kmh == 180.0 and not control.refused


def test_accepted_value_outside_the_soft_bounds_widens_the_slider(dashboard):
    control = dashboard.inputs.controls["train.speed_kmh"]
    control.enter("180")
    assert dashboard.scenario.train.speed_kmh == 180.0
    assert control.slider.end == 180.0 and control.slider.value == 180.0


def test_inconsistent_inputs_are_reported_not_raised(dashboard):
    dashboard.inputs.controls["irregularity.wavelength_min"].enter("60")
    assert dashboard.messages.error_alert.visible
    text = dashboard.messages.error_alert.object.replace("\\", "")
    assert "Inconsistent inputs" in text and "wavelength_max" in text
    assert not any(_is_stale(dashboard, key) for key in _panes(dashboard))


def test_optional_parameter_text_box_accepts_automatic(dashboard):
    control = dashboard.inputs.controls["numerics.n_rail_modes"]
    assert control.slider is None and control.text.value == ""
    control.enter("abc")
    assert "'abc' is not a number; still automatic" in html.unescape(control.refusal.object)
    control.enter("2.5")
    assert "'2.5' is not a whole number" in html.unescape(control.refusal.object)
    control.enter(str(dashboard.scenario.rail_modes))
    assert dashboard.scenario.numerics.n_rail_modes == dashboard.scenario.rail_modes
    assert not control.refused
    control.enter("")
    assert dashboard.scenario.numerics.n_rail_modes is None


def test_train_type_selector_applies_the_standard_geometry(dashboard):
    assert dashboard.inputs.train_type.value == "Type A"
    dashboard.inputs.train_type.value = "Type B"
    assert dashboard.scenario.train.car_length == 19.0  # Train.type_b, docs/model.md §1
    assert dashboard.inputs.controls["train.car_length"].text.value == "19"
    dashboard.inputs.controls["train.car_length"].enter("20")
    assert dashboard.inputs.train_type.value == scenarios.CUSTOM


def test_preset_label_says_custom_once_an_input_is_edited(cache, cheap_scenario):
    board = Dashboard(scenario=Scenario.preset("single_bogie"), preset="single_bogie", cache=cache)
    board.refresh = lambda: None  # runs are not needed here
    assert board.inputs.preset_select.value == "single_bogie"
    board.inputs.controls["soil.density"].enter("1900")
    assert board.inputs.preset_select.value == scenarios.CUSTOM
    board.inputs.controls["soil.density"].enter("1800")  # back to the preset's inputs
    assert board.inputs.preset_select.value == "single_bogie"


def test_preset_selector_replaces_the_scenario_and_the_controls(cache, cheap_scenario):
    board = Dashboard(scenario=cheap_scenario(), preset="single_bogie", cache=cache)
    board.refresh = lambda: None  # the paper case is a full-train run; not needed here
    board.inputs.preset_select.value = "paper_soil_lame"
    assert board.scenario.soil.youngs_modulus == pytest.approx(550.07e6, rel=1e-4)
    control = board.inputs.controls["soil.youngs_modulus"]
    assert control.slider.value == pytest.approx(550.07, rel=1e-4)  # MPa
    assert control.slider.end >= control.slider.value  # widened to an out-of-range preset value
    assert board.inputs.controls["train.single_bogie"].widget.value is False
    assert board.inputs.preset_select.value == "paper_soil_lame"


def test_scenario_save_and_load_round_trip(dashboard):
    dashboard.inputs.controls["train.speed_kmh"].enter("95")
    saved = dashboard.inputs._scenario_file().getvalue()
    assert Scenario.from_json(saved).train.speed_kmh == 95.0
    dashboard.inputs.controls["train.speed_kmh"].enter("100")
    dashboard.inputs.load_input.param.update(filename="s.json", value=saved.encode())
    assert dashboard.scenario.train.speed_kmh == 95.0
    assert dashboard.inputs.controls["train.speed_kmh"].text.value == "95"
    assert dashboard.runs.results.scenario.train.speed_kmh == 95.0


@pytest.mark.parametrize(
    "content, message",
    [
        (b"{not json", "Expecting property name"),
        (json.dumps({"soil": {"youngs_modulus": -1.0}}).encode(), "outside the allowed range"),
        (json.dumps({"spaceship": {}}).encode(), "unknown section"),
        (b"[1, 2]", "Could not load bad.json"),
    ],
)
def test_a_bad_scenario_file_gives_a_clear_message(dashboard, content, message):
    before = dashboard.scenario.to_json()
    dashboard.inputs.load_input.param.update(filename="bad.json", value=content)
    assert dashboard.messages.error_alert.visible
    assert message in dashboard.messages.error_alert.object.replace("\\", "")
    assert dashboard.scenario.to_json() == before


def test_query_arguments_choose_preset_and_overrides(cache):
    board = Dashboard.from_query(
        {"preset": [b"single_bogie"], "train.speed_kmh": [b"70"], "numerics.n_depths": [b"11"]},
        cache=cache,
    )
    assert board.scenario.train.single_bogie and board.scenario.train.speed_kmh == 70.0
    assert board.inputs.controls["train.speed_kmh"].text.value == "70"
    assert board.inputs.preset_select.value == scenarios.CUSTOM  # the preset with edits
    assert not board.messages.error_alert.visible
    plain = Dashboard.from_query({"preset": [b"single_bogie"]}, cache=cache)
    assert plain.inputs.preset_select.value == "single_bogie"
    bad = Dashboard.from_query({"preset": [b"nope"], "soil.youngs_modulus": [b"-3"]}, cache=cache)
    text = bad.messages.error_alert.object.replace("\\", "")
    assert "unknown preset 'nope'" in text and "youngs_modulus" in text
    assert bad.inputs.preset_select.value == "paper"


def test_views_are_tabs_and_an_added_view_becomes_one(dashboard):
    dashboard.add_view("Notes", pn.pane.Markdown("notes"))
    assert [title for title, _ in zip(dashboard.tabs._names, dashboard.tabs, strict=True)] == [
        "Passage",
        "Long-term settlement",
        "Ground vibration",
        "Study",
        "Notes",
    ]


def test_long_term_view_shows_the_law_and_its_plots(dashboard):
    """The long-term tab states the law that produced the numbers and draws each plot."""
    assert "Li & Selig" in dashboard.longterm.law_statement.object
    for spec in LONGTERM_PLOTS:
        assert _panes(dashboard)[spec.key].object is not None, spec.key


def test_depth_plot_draws_the_other_tunnel_model_faint(dashboard):
    """Issue 11: the depth plot shows the chosen model's profile and, dashed, the other one's,
    each with its own numbers."""
    assert dashboard.runs.other_model is not None
    assert dashboard.runs.other_model.scenario.tunnel.model == "2.5d"
    curves = _curves(_shown(dashboard, "depth_profile"))
    for results in (dashboard.runs.results, dashboard.runs.other_model):
        name = plots.MODEL_NAMES[results.scenario.tunnel.model]
        np.testing.assert_allclose(
            curves[name].dimension_values(0), results.soil.peak_disp_m * 1e3, rtol=1e-12
        )


def test_the_other_model_is_computed_after_the_results_are_shown(dashboard, monkeypatch):
    """The comparison run does not delay the chosen model's plots: it starts once they show
    the new results, and its curve then follows the new inputs."""
    compute = dashboard.runs.companion._compute
    shown_when_called = []

    def watching_compute(other):
        shown_when_called.append(dashboard.runs.results.scenario.soil.youngs_modulus)
        assert dashboard.runs.other_model is None  # the old scenario's curve is gone meanwhile
        # its legend entry stays, with an empty curve: the curve's arrival changes data only
        assert (
            _curves(_shown(dashboard, "depth_profile"))["2.5D moving load"].dimension_values(0).size
            == 0
        )
        return compute(other)

    monkeypatch.setattr(dashboard.runs.companion, "_compute", watching_compute)
    dashboard.inputs.controls["soil.youngs_modulus"].enter("9")  # MPa
    assert shown_when_called == [9e6]
    assert dashboard.runs.other_model.scenario.soil.youngs_modulus == 9e6
    assert not dashboard.runs.companion.busy


def test_a_new_run_replaces_no_data_that_a_legend_reaches(cache, cheap_scenario):
    """BokehJS draws a legend's entries again when any model they reach changes. The entries
    named by a value point at swatch renderers (hidden, one row of data, their curve's glyph
    style), so none of the data that a new run replaces is reached from a legend; the pinned
    runs' entry keeps its renderer, whose data a new run leaves as it is."""
    board = Dashboard(scenario=cheap_scenario(), preset="single_bogie", cache=cache)
    session_doc = Document()
    with set_curdoc(session_doc):
        board.template().server_doc(session_doc)
        board.refresh()
        board.whatif.pin_button.clicks += 1
        figures = [_drawn_plot(pane).state for pane in board.passage.plots.panes.values()]
        sources = {s for figure in figures for s in figure.select(bokeh.models.ColumnDataSource)}
        data_before = {source: source.data for source in sources}
        board.scenario.train.speed_kmh += 10.0
        replaced = {source for source, data in data_before.items() if source.data is not data}
    assert replaced  # the new run's curves
    for figure in figures:
        (legend,) = figure.legend
        assert not replaced & legend.references(), figure.title.text
        labels = [item.label for item in legend.items]
        assert any(isinstance(label, Field) for label in labels), figure.title.text  # pinned
        assert Value(CURRENT_LABEL) in labels, figure.title.text
        for item in legend.items:
            if not isinstance(item.label, Value):
                continue
            assert item.visible
            for swatch in item.renderers:
                owner = legend_swatches._owner(swatch)
                assert owner is not swatch and owner in figure.renderers and owner.visible
                assert SWATCH_TAG in swatch.tags and not swatch.visible
                assert {len(column) for column in swatch.data_source.data.values()} == {1}
                style = owner.glyph.properties_with_values(include_defaults=False)
                assert swatch.glyph.properties_with_values(include_defaults=False) == style


def test_a_failed_comparison_run_leaves_no_legend_entry_until_the_next_one(
    cache, cheap_scenario, monkeypatch
):
    """The empty curve that holds the other model's legend entry while its run computes goes
    when that run fails: the drawn legend names no curve that is not drawn. HoloViews hides
    that curve's glyph and entry and keeps its place; the next comparison's curve, at the
    same place, is drawn by HoloViews again (an update in place would fill the hidden glyph
    and leave it hidden)."""
    board = Dashboard(scenario=cheap_scenario(), preset="single_bogie", cache=cache)
    session_doc = Document()
    with set_curdoc(session_doc):
        board.template().server_doc(session_doc)
        board.refresh()
        figure = _drawn_plot(board.passage.plots.panes["depth_profile"]).state

        def legend():  # the entries drawn
            return {
                item.label["value"]
                for legend in figure.legend
                for item in legend.items
                if item.visible
            }

        assert "2.5D moving load" in legend()
        compute = board.runs.companion._compute
        monkeypatch.setattr(board.runs.companion, "_compute", lambda other: None)
        board.scenario.soil.youngs_modulus = 9e6
        assert board.runs.comparison_state == "unavailable"
        assert "2D section" in legend() and "2.5D moving load" not in legend()
        monkeypatch.setattr(board.runs.companion, "_compute", compute)
        board.scenario.soil.youngs_modulus = 11e6
    assert board.runs.comparison_state == "shown"
    assert "2.5D moving load" in legend()
    assert all(renderer.visible for renderer in figure.renderers if SWATCH_TAG not in renderer.tags)


def test_the_ground_plots_follow_a_change_to_the_half_space(cache, cheap_scenario):
    """The Ground tab's plots drawn in the full space (empty) are drawn again with the
    half-space results: the level plots are Overlays either way (HoloViews cannot turn a
    plot of a Curve into one of an Overlay; they stayed empty)."""
    scenario = cheap_scenario()
    scenario.tunnel.model = "2.5d"
    board = Dashboard(scenario=scenario, preset="single_bogie", cache=cache)
    session_doc = Document()
    with set_curdoc(session_doc):
        board.template().server_doc(session_doc)
        board.refresh()
        for pane in board.ground.plots.panes.values():
            pane.get_root(session_doc)  # the tab opened: its plots drawn
        board.scenario.tunnel.ground = "half_space"
    assert board.runs.results.ground is not None
    for key, pane in board.ground.plots.panes.items():
        figure = _drawn_plot(pane).state
        points = sum(
            len(next(iter(renderer.data_source.data.values()), []))
            for renderer in figure.renderers
            if hasattr(renderer, "data_source")
        )
        assert points > 0, key


def test_a_comparison_run_of_older_inputs_is_not_drawn(dashboard):
    """A comparison result that no longer matches the inputs on screen is dropped."""
    shown = dashboard.runs.other_model
    stale = dashboard.runs.results  # a Results of another scenario than the expected comparison
    dashboard.runs._finish_companion(stale.scenario, stale)
    assert dashboard.runs.other_model is shown


def test_a_page_of_cached_inputs_is_drawn_before_it_is_sent(cache, cheap_scenario):
    """Inputs another visitor has computed are drawn while the page is built (no run in the
    pool); others, or kernels still compiling, wait for the page's own run."""
    run(cheap_scenario(), cache=cache)
    board = Dashboard(scenario=cheap_scenario(), preset="single_bogie", cache=cache)
    assert board.runs.show_cached()
    assert set(_streams(board)) == {spec.key for spec in ALL_PLOTS}
    assert board.runs.results.scenario.to_dict() == cheap_scenario().to_dict()
    assert not board.runs.latest.busy and not any(_is_stale(board, key) for key in _panes(board))
    counts, hits = dict(board.runs.render_counts), dict(cache.hits)
    board.runs.compute_waiting()  # what the page does once loaded: only the comparison curve
    assert board.runs.comparison_state == "shown" and board.runs.render_counts == counts
    assert cache.hits["vehicle_track"] == hits["vehicle_track"] + 1  # the other model's run

    other = cheap_scenario()
    other.train.speed_kmh = 77.0
    fresh = Dashboard(scenario=other, preset="single_bogie", cache=cache)
    assert not fresh.runs.show_cached() and fresh.runs.results is None

    compiling = Future()  # the server's warm-up run, not finished
    waiting = Dashboard(
        scenario=cheap_scenario(), preset="single_bogie", cache=cache, warm=compiling
    )
    assert not waiting.runs.show_cached() and waiting.runs.results is None


def test_a_run_reaches_a_served_page_in_one_batch(cache, cheap_scenario, monkeypatch):
    """The results of a run change the page with the document's models re-indexed once (each
    re-indexing walks every model of the page; unbatched it ran once per redrawn plot)."""
    board = Dashboard(scenario=cheap_scenario(), preset="single_bogie", cache=cache)
    board.inputs.show_matching()  # as served (Dashboard.from_query): the preset is 'custom'
    session_doc = Document()
    with set_curdoc(session_doc):
        board.template().server_doc(session_doc)
        board.refresh()  # the first results create the plots
        manager = type(session_doc.models)
        recompute, indexings = manager.recompute, []

        def counted(models):
            indexings.append(1)
            return recompute(models)

        monkeypatch.setattr(manager, "recompute", counted)
        board.scenario.train.speed_kmh += 5.0  # a run that redraws every plot
    assert board.runs.results.scenario.train.speed_kmh == cheap_scenario().train.speed_kmh + 5.0
    assert board.runs.comparison_state == "shown"
    # the first stages' plots (drawn while the soil stage computes), the rest of the results
    # and the other model's curve after them change data only: no model reference
    assert indexings == []


def _figure_content(figure) -> dict:
    """What a Bokeh figure shows: every glyph's data (lists), in drawing order, and its axis
    ranges (a legend's swatch renderers are hidden and hold no data of the plot's)."""

    def listed(values):
        return (
            [listed(v) for v in values] if isinstance(values, list) else np.asarray(values).tolist()
        )

    return {
        "data": [
            {name: listed(values) for name, values in renderer.data_source.data.items()}
            for renderer in figure.renderers
            if SWATCH_TAG not in renderer.tags
        ],
        "x": (figure.x_range.start, figure.x_range.end),
        "y": (figure.y_range.start, figure.y_range.end),
    }


@pytest.mark.parametrize("pinned", [False, True], ids=["alone", "with a pinned run"])
def test_a_run_updates_each_passage_plot_in_place_as_a_fresh_drawing_shows_it(
    cache, cheap_scenario, monkeypatch, pinned
):
    """A speed change sets the passage plots' data and ranges on their Bokeh models, without
    HoloViews' update of the plot, and each figure then shows exactly what a new drawing of
    the new results shows (its data, the paper's points, the pinned run, the other model's
    curve once it came, the axis ranges, inverted on the depth plot)."""
    board = Dashboard(scenario=cheap_scenario(), preset="single_bogie", cache=cache)
    session_doc = Document()
    with set_curdoc(session_doc):
        board.template().server_doc(session_doc)
        board.refresh()
        if pinned:
            board.whatif.pin_button.clicks += 1
        drawn = {key: _drawn_plot(pane) for key, pane in board.passage.plots.panes.items()}
        before = {key: _figure_content(plot.state) for key, plot in drawn.items()}
        redrawn_by_holoviews = []
        for plot in drawn.values():
            monkeypatch.setattr(
                plot, "update_frame", lambda *a, **k: redrawn_by_holoviews.append(a)
            )
        board.scenario.train.speed_kmh += 20.0
    assert board.runs.comparison_state == "shown"
    assert not redrawn_by_holoviews
    for spec in plots.PLOTS:
        figure = drawn[spec.key].state
        assert _drawn_plot(board.passage.plots.panes[spec.key]).state is figure
        arguments = board.passage._draw_arguments(spec)
        fresh = hv.render(spec.draw(board.runs.results, **arguments), backend="bokeh")
        shown = _figure_content(figure)
        assert shown == _figure_content(fresh), spec.key
        assert shown != before[spec.key], spec.key


def test_a_plot_whose_layers_change_is_drawn_again_by_holoviews(cache, cheap_scenario):
    """A stored FE result adds a curve to the depth plot: no update in place can show it, so
    HoloViews draws the plot again (with the element drawn already), and the axes cover the
    new curve, far beyond the old range."""
    board = Dashboard(scenario=cheap_scenario(), preset="single_bogie", cache=cache)
    session_doc = Document()
    with set_curdoc(session_doc):
        board.template().server_doc(session_doc)
        board.refresh()
        plot = _drawn_plot(board.passage.plots.panes["depth_profile"])
        depth = board.runs.results.soil.depth_m
        far = 10.0 * board.runs.results.soil.peak_disp_m.max()
        fe = SimpleNamespace(
            peak_disp_m=np.full(depth.size, far), depth_m=depth, soil_law="elastic"
        )
        board.runs.fe_result = fe
        board.passage.redraw_depth_plot()
    legend = {item.label["value"] for legend in plot.state.legend for item in legend.items}
    assert "FE section (elastic)" in legend
    assert not board.passage.plots._drawn  # the element drawn for the check was used
    assert plot.state.x_range.end > far * plots.MM
    spec = next(spec for spec in plots.PLOTS if spec.key == "depth_profile")
    arguments = board.passage._draw_arguments(spec)
    fresh = _figure_content(hv.render(spec.draw(board.runs.results, **arguments), backend="bokeh"))
    shown = _figure_content(plot.state)
    # the same curves; HoloViews draws the one it added last, on top
    assert sorted(map(repr, shown.pop("data"))) == sorted(map(repr, fresh.pop("data")))
    assert shown == fresh


def test_a_plot_whose_element_turns_into_an_overlay_is_left_to_holoviews():
    """A plot drawn of a Curve that is sent an Overlay stating its limits is not updated in
    place (it has no subplots to pair the layers with): HoloViews has it, and the update goes
    on (the run's other plots and status line followed only once that no longer raised)."""

    def draw(value, **_):
        curve = hv.Curve([0.0, value])
        element = curve if value < 2 else hv.Overlay([curve, hv.Curve([1.0, 0.0])])
        return element.opts(xlim=(0.0, 1.0), ylim=(0.0, value))

    panes = plot_panes.PlotPanes([plots.PlotSpec("switching", "soil", draw)])
    panes.show(1.0, {"soil"})
    panes.panes["switching"].get_root(Document())
    panes.send("switching", 3.0)
    assert panes.streams["switching"].data == 3.0


def test_one_message_reindexes_the_page_when_a_model_reference_changes(monkeypatch):
    """:func:`plot_panes.message` skips Bokeh's re-indexing after changes of data alone, and
    re-indexes once when a model was added: by a new reference, or as a root."""
    figure = bokeh.plotting.figure()
    line = figure.line([0, 1], [0, 1])
    session_doc = Document()
    session_doc.add_root(figure)
    indexings = []
    recompute = type(session_doc.models).recompute
    monkeypatch.setattr(
        type(session_doc.models),
        "recompute",
        lambda models: indexings.append(1) or recompute(models),
    )
    with set_curdoc(session_doc):
        with plot_panes.message(reindex_once=True):
            line.data_source.data = {"x": [0, 2], "y": [1, 3]}
            figure.x_range.start = -1.0
        assert indexings == []

        title = bokeh.models.Title(text="new")
        with plot_panes.message(reindex_once=True):
            figure.title = title
            figure.x_range.end = 5.0
        assert indexings == [1] and session_doc.get_model_by_id(title.id) is title

        root = bokeh.models.Div(text="another root")
        with plot_panes.message(reindex_once=True):
            session_doc.add_root(root)
        assert indexings == [1, 1] and session_doc.get_model_by_id(root.id) is root

        with session_doc.models.freeze():  # an outer freeze: it re-indexes at its end
            with plot_panes.message(reindex_once=True):
                line.data_source.data = {"x": [0], "y": [0]}
            assert indexings == [1, 1]
        assert indexings == [1, 1, 1]
    assert "invalidate" not in vars(session_doc.models)  # Bokeh's own method again


def test_a_change_leaves_the_pinned_runs_alone_and_the_axes_cover_them(
    cache, cheap_scenario, monkeypatch
):
    """With a run pinned, a speed change redraws each plot's current run in place but neither
    updates the pinned runs' subplot nor ranges their data again (both cost most of what 8
    pinned runs added to the server's update); the axes still cover the pinned run where it
    outlasts the current one, and its legend entry stays, below the axes."""
    board = Dashboard(scenario=cheap_scenario(), preset="single_bogie", cache=cache)
    session_doc = Document()
    with set_curdoc(session_doc):
        board.template().server_doc(session_doc)
        board.scenario.train.speed_kmh = 60.0  # a slower passage: a longer time history
        board.refresh()
        board.whatif.pin_button.clicks += 1
        drawn = {key: _drawn_plot(pane) for key, pane in board.passage.plots.panes.items()}
        pinned_updates, rangings = [], []
        for plot in drawn.values():
            (subplot,) = [
                p for p in plot.subplots.values() if isinstance(p.current_frame, plots.PinnedRuns)
            ]
            monkeypatch.setattr(subplot, "update_frame", lambda *a, **k: pinned_updates.append(a))
        contours_range = hv.Contours.range
        monkeypatch.setattr(
            hv.Contours, "range", lambda *a, **k: rangings.append(a) or contours_range(*a, **k)
        )
        board.scenario.train.speed_kmh = 100.0
    assert board.runs.results.scenario.train.speed_kmh == 100.0
    assert not pinned_updates and not rangings
    for key in ("block_displacement", "invert_load"):
        frame = _shown(board, key)
        (pinned,) = [layer for layer in frame if isinstance(layer, plots.PinnedRuns)]
        current = _curves(frame)[CURRENT_LABEL]
        end, current_end = pinned.dimension_values(0).max(), current.dimension_values(0).max()
        figure = drawn[key].state
        assert current_end < end <= figure.x_range.end, key
        assert drawn[key].handles["plot"] is figure  # updated in place
        (legend,) = figure.legend
        assert legend in figure.below, key
        named = {
            name
            for item in legend.items
            if hasattr(item.label, "field")  # an entry per value of a column: the pinned runs
            for renderer in item.renderers
            for name in renderer.data_source.data[item.label.field]
        }
        assert named == set(plots.legend_labels(board.whatif.session.names())), key


def test_closing_a_session_drops_its_results(dashboard):
    dashboard.close()
    assert dashboard.runs.results is None and not _streams(dashboard)
    assert all(pane.object is None for pane in _panes(dashboard).values())


def test_a_closed_session_computes_no_more_runs(dashboard, monkeypatch):
    """Neither a change arriving after the close nor the other model's curve is computed."""
    monkeypatch.setattr(runs_module, "run", lambda *args, **kwargs: pytest.fail("a run"))
    dashboard.close()
    dashboard.scenario.train.speed_kmh += 5.0
    dashboard.runs.compute_waiting()
    assert dashboard.runs.results is None and not dashboard.runs.latest.busy


def test_a_closed_sessions_computing_run_stops_at_its_next_progress_report(dashboard, monkeypatch):
    """The tab closes while the vehicle–track stage computes: the run stops after that chunk
    of the integration instead of holding a server worker to the end."""
    reports = []
    note = dashboard.runs._note_progress

    def close_after_the_first_chunk(stage, fraction):
        reports.append((stage, fraction))
        if stage == "vehicle_track" and fraction > 0:
            dashboard.close()
        note(stage, fraction)

    monkeypatch.setattr(dashboard.runs, "cache", StageCache())  # every stage computes
    monkeypatch.setattr(dashboard.runs, "_note_progress", close_after_the_first_chunk)
    with pytest.raises(RunCancelled, match="the session closed during the vehicle"):
        dashboard.runs._compute(dashboard.scenario)
    stage, fraction = reports[-1]
    assert stage == "vehicle_track" and 0 < fraction < 1


def test_a_closed_sessions_comparison_run_stops_at_its_first_progress_report(dashboard):
    """The other model's run of a closed session, already handed to the server's workers, stops
    before it computes anything."""
    other = dashboard.scenario.copy()
    other.tunnel.model = "2.5d"
    dashboard.close()
    with pytest.raises(RunCancelled, match="the session closed during the vehicle"):
        dashboard.runs._compute_companion(other)


def test_a_closed_sessions_memory_is_given_back_once_its_runs_have_stopped(dashboard, monkeypatch):
    """The trim at the close comes too early for a run still computing; the end of the
    session's last run asks for it again."""
    released = []
    monkeypatch.setattr(runs_module, "release_soon", lambda call_later: released.append(1))
    asyncio.run(dashboard.runs._drain())
    assert released == []  # an open session keeps its memory
    dashboard.close()
    asyncio.run(dashboard.runs._drain())
    assert released == [1]


# ---- export.py ------------------------------------------------------------------------------
# A tag that loads from the network; (Bokeh's own script text mentions a MathJax URL that it
# fetches only for LaTeX labels, which the report has none of.)
EXTERNAL_TAG = re.compile(
    r"""<(?:script|link|img)\b[^>]*(?:src|href)\s*=\s*["']?(?:https?:)?//""", re.IGNORECASE
)


def _markup_texts(report: str) -> list[str]:
    """The HTML shown by every markup pane of a saved page, from its embedded document JSON."""
    found = re.search(r'<script type="application/json" id="[^"]+">(.*?)</script>', report, re.S)
    texts = []

    def walk(node):
        if isinstance(node, dict):
            for key, value in node.items():
                if key == "text" and isinstance(value, str):
                    texts.append(html.unescape(html.unescape(value)))  # escaped twice
                else:
                    walk(value)
        elif isinstance(node, list):
            for value in node:
                walk(value)

    walk(json.loads(found.group(1)))
    return texts


def test_report_is_self_contained_and_complete(results):
    """No tag loads from the network, no component stylesheet is linked (all are inline)."""
    text = report_html(results)
    assert not EXTERNAL_TAG.search(text), EXTERNAL_TAG.search(text)
    assert '"name":"ImportedStyleSheet"' not in text and '"name":"InlineStyleSheet"' in text
    assert "cdn.holoviz.org" not in text
    for title in (
        "Sleeper (block) displacement",
        "Invert load",
        "Invert line-load PSD",
        "Interface displacement PSD",
        "Peak dynamic displacement against depth",
        "Train-induced settlement: ",
    ):
        assert title in text, title
    shown = "".join(_markup_texts(text))
    assert SETTLEMENT_COVERS in shown  # issue 25: what the long-term settlement covers
    for item in key_numbers.summary_items(results):
        assert f'data-key="{item.key}">{item.text}<' in shown
    assert html.escape(results.scenario_json) in shown  # the full scenario, as <pre> text


def test_report_header_names_the_scenario_date_and_version(results):
    shown = "".join(_markup_texts(report_html(results, scenario_name="single_bogie")))
    today = datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d")
    assert "Scenario: <b>single_bogie</b>" in shown
    assert today in shown and f"tunnelsettle {package_version()}" in shown


def test_report_download_button_serves_the_report(dashboard):
    """Inside a served session (a current document holding the page) the report still builds
    in a document of its own, with every stylesheet inlined."""
    session_doc = Document()
    with set_curdoc(session_doc), set_resource_mode("server"):
        dashboard.template().server_doc(session_doc)
        data = dashboard.report_button.callback()
    assert isinstance(data, io.BytesIO)
    text = data.getvalue().decode("utf-8")
    assert text.startswith("<!DOCTYPE html>")
    assert not EXTERNAL_TAG.search(text)
    assert '"name":"ImportedStyleSheet"' not in text


def test_export_command_line_writes_the_report(tmp_path, capsys):
    out = tmp_path / "report.html"
    code = export_main(
        [
            "--preset",
            "single_bogie",
            "--set",
            "train.speed_kmh=100",
            "--set",
            "numerics.n_depths=11",
            "--out",
            str(out),
        ]
    )
    assert code == 0 and out.read_text(encoding="utf-8").startswith("<!DOCTYPE html>")
    assert str(out) in capsys.readouterr().out


def test_export_command_line_refuses_bad_input(tmp_path, capsys):
    with pytest.raises(SystemExit) as stop:
        export_main(
            [
                "--preset",
                "single_bogie",
                "--set",
                "soil.youngs_modulus=-1",
                "--out",
                str(tmp_path / "r.html"),
            ]
        )
    assert stop.value.code == 2
    assert "youngs_modulus" in capsys.readouterr().err
    assert not (tmp_path / "r.html").exists()


def test_pinning_works_once_the_inputs_are_custom(dashboard):
    """The preset label reads 'custom' after an edit; a pin still names what differs from the
    preset the inputs started from (a browser session showed a KeyError for 'custom')."""
    dashboard.scenario.soil.youngs_modulus = 8e6
    dashboard.refresh()
    assert dashboard.inputs.preset_select.value == scenarios.CUSTOM
    dashboard.whatif.pin_button.clicks += 1
    assert len(dashboard.whatif.session.runs) == 1
    assert "8 MPa" in dashboard.whatif.session.runs[0].name


def test_depth_plot_draws_a_stored_fe_result(results):
    """A stored FE result of the scenario appears on the depth plot as its own curve (mm)."""
    fe = SimpleNamespace(
        soil_law="mohr_coulomb", depth_m=np.array([0.0, 5.0]), peak_disp_m=np.array([2e-3, 1e-3])
    )
    curves = _curves(plots.depth_profile_plot(results, fe_result=fe))
    np.testing.assert_allclose(curves["FE section (Mohr–Coulomb)"].dimension_values(0), [2, 1])


def test_a_whole_number_from_the_slider_is_in_display_units(dashboard):
    """Bokeh sends a slider position of 16 (MPa) as the int 16: it must become 16e6 Pa, not
    16 Pa (which the soil bounds refuse; before those bounds it was silently taken as 16 Pa)."""
    control = dashboard.inputs.controls["soil.youngs_modulus"]
    control.slide(16)
    assert dashboard.scenario.soil.youngs_modulus == 16e6
