"""What the dashboard shows, without a browser (issue 28): numbers as typed, legend labels, key
numbers' digits, a plot's style that does not depend on what else it draws, the report's other
model and inputs, the study's plan and partial results."""

from __future__ import annotations

import contextlib
import html

import holoviews as hv
import numpy as np
import pandas as pd
import param
import pytest
from holoviews.streams import Pipe

from dashboard import axes, key_numbers, plots, site_view
from dashboard.app import Dashboard
from dashboard.report import build_report, inputs_html
from dashboard.study_plots import band_plot, depth_envelope_plot, partial_note, study_bands
from dashboard.study_view import StudyView
from dashboard.typed_values import parse_typed
from model import scenarios
from model.params import Scenario
from model.pipeline import run
from model.study.execution import submission_order


@pytest.mark.parametrize(
    ("text", "unit", "value"),
    [
        ("6", "MPa", 6.0),
        ("6,5", "MPa", 6.5),  # a decimal comma
        (" 6.5e3 kPa ", "MPa", 6.5),
        ("6000kpa", "MPa", 6.0),  # units compared without case
        ("16.7 m/s", "km/h", 60.12),
        ("3 cm4", "cm⁴", 3.0),
        ("30 kN.s/m", "kN·s/m", 30.0),
        ("0.1 ms", "s", 1e-4),
        ("-5", "km/h", -5.0),  # a number: the parameter's bounds refuse it, not the parser
    ],
)
def test_typed_numbers_are_read_with_their_unit(text, unit, value):
    assert parse_typed(text, unit) == pytest.approx(value, rel=1e-12)


@pytest.mark.parametrize(
    ("text", "unit", "reason"),
    [
        ("1_00", "km/h", "is not a number in km/h (digits with one decimal point or comma"),
        ("6 000", "MPa", "no digit separators"),
        ("1,000.5", "MPa", "no digit separators"),
        ("abc", "MPa", "is not a number in MPa"),
        ("1e400", "s", "is not a finite number in s"),
        ("6 m", "MPa", "has the unit m, not a unit of pressure: type it in Pa, kPa, MPa, GPa"),
        ("5 x", "-", "has a unit (x); this number has none"),
    ],
)
def test_typed_text_is_refused_with_the_reason(text, unit, reason):
    with pytest.raises(ValueError) as refused:
        parse_typed(text, unit)
    assert reason in str(refused.value)


def test_key_numbers_show_three_significant_digits():
    shown = [
        key_numbers.significant(v) for v in (0.49731, 7.899, 19.92, 66.39, 1234.6, 0.0, 2.5e-6)
    ]
    assert shown == ["0.497", "7.90", "19.9", "66.4", "1235", "0", "2.5e-06"]


def test_long_legend_names_are_cut_and_stay_distinct():
    long = "tunnel–soil model 2.5d, soil class user, law coefficient a 0.8787% + 2 more"
    labels = plots.legend_labels([long, long.replace("2 more", "3 more"), "speed 60 km/h"])
    assert all(len(label) <= plots.LEGEND_LABEL_CHARS for label in labels)
    assert len(set(labels)) == 3 and labels[2] == "speed 60 km/h"
    # a legend of long labels fits the narrowest plot in one column
    assert plots.legend_options(labels)["legend_cols"] == 1
    assert plots.legend_options(["mean", "min–max of 3 seeds"])["legend_cols"] >= 1


def test_legend_entries_side_by_side_keep_apart():
    """The defect: in a legend of two columns one entry's label ran into the next one's line
    ("Vehicle–track model– – Winkler beam"); the rendered legend spaces its entries."""
    options = plots.legend_options(["Current run", "Winkler beam"])
    overlay = hv.Curve([0, 1], label="Current run") * hv.Curve([1, 0], label="Winkler beam")
    (legend,) = hv.render(overlay.opts(**options), backend="bokeh").legend
    assert legend.ncols == options["legend_cols"] >= 2
    assert legend.spacing == plots.LEGEND_SPACING_PX >= 10


def test_the_long_term_legends_keep_their_entries_apart(cheap_scenario):
    """The same defect on the long-term tab: "u after 10 y– – u_g after 20 y" in the excess
    pore-pressure plot's legend of three columns."""
    results = run(cheap_scenario())
    for spec in site_view.SITE_PLOTS:
        for legend in hv.render(spec.draw(results), backend="bokeh").legend:
            assert legend.spacing == plots.LEGEND_SPACING_PX, spec.key


def test_a_legend_stays_below_the_axes_through_updates():
    """HoloViews took a legend placed below the axes out of its figure and put it back on
    every update, and the browser laid the figure out again each time: it is now moved there
    once, and an update leaves the figure's panels alone."""
    stream = Pipe(data=1.0)
    labels = ["Current run", "Winkler beam"]

    def draw(data):
        curves = [hv.Curve([0, data], label=labels[0]), hv.Curve([1, 0], label=labels[1])]
        return hv.Overlay(curves).opts(**plots.legend_options(labels))

    figure = hv.renderer("bokeh").get_plot(hv.DynamicMap(draw, streams=[stream])).state
    (legend,) = figure.legend
    assert legend in figure.below and legend not in figure.center
    changes = []
    figure.on_change("below", lambda attr, old, new: changes.append(new))
    stream.send(2.0)
    assert figure.legend[0] is legend and legend in figure.below and not changes
    assert [item.label.value for item in legend.items] == labels


@pytest.fixture(scope="module")
def cheap_results(cheap_scenario, cache):
    return run(cheap_scenario(), cache=cache)


def test_a_long_legend_makes_its_plot_taller(cheap_results):
    """8 pinned runs with long names (one legend column, ten entries) squeezed the axes of a
    plot of fixed height to a strip and cut off the legend's last entries: the plot grows by a
    row's height for each row beyond what it holds."""
    names = [f"pinned run number {k + 1} at {60 + 10 * k} km/h" for k in range(8)]
    overlays = [(name, cheap_results, "#1f77b4") for name in names]
    alone = hv.render(plots.block_displacement_plot(cheap_results), backend="bokeh")
    pinned = plots.block_displacement_plot(cheap_results, overlays=overlays)
    assert plots.legend_options(plots.legend_labels(names))["legend_cols"] == 1
    rows = len(names) + 2  # the current run and the Winkler beam
    extra = plots.LEGEND_ROW_PX * (rows - plots.LEGEND_FREE_ROWS)
    assert alone.height == plots.PLOT_HEIGHT
    assert hv.render(pinned, backend="bokeh").height == plots.PLOT_HEIGHT + extra


def _style(element: hv.Element) -> dict:
    kwargs = element.opts.get("style").kwargs
    return {key: kwargs.get(key) for key in ("color", "line_dash")}


def test_the_current_curve_keeps_its_style_with_the_other_model_and_pins(cheap_results, cache):
    """The chosen model's curve was blue, then orange once the other model's curve came, and
    the paper's points changed colour once a run was pinned."""
    other_scenario = cheap_results.scenario
    other_scenario.tunnel.model = "2.5d"
    other = run(other_scenario, cache=cache)
    alone = plots.depth_profile_plot(cheap_results)
    compared = plots.depth_profile_plot(cheap_results, other_model=other)
    pinned = plots.depth_profile_plot(
        cheap_results, overlays=[("pinned", cheap_results, "#E69F00")]
    )

    def by_label(plot):
        return {layer.label: layer for layer in plot if not isinstance(layer, hv.Contours)}

    current_styles = {
        str(_style(by_label(plot)[name]))
        for plot, name in ((alone, "2D section"), (compared, "2D section"), (pinned, "Current run"))
    }
    assert len(current_styles) == 1
    for name in ("Paper Fig. 11", "Paper conclusions"):
        assert _style(by_label(alone)[name]) == _style(by_label(pinned)[name])


def test_the_psd_axis_spans_ten_decades_below_the_peak(cheap_results):
    psd = plots.interface_psd_plot(cheap_results)
    low, high = psd.vdims[0].range
    assert high is None
    assert low == pytest.approx(psd.dimension_values(1).max() * 1e-10, rel=1e-12)


@pytest.mark.parametrize(
    ("low", "high", "padding", "log", "floor", "expected"),
    [
        (0.0, 10.0, 0.1, False, None, (-1.0, 11.0)),
        (2.0, 4.0, 0.0, False, None, (2.0, 4.0)),  # a time axis: the record's ends
        (1e-3, 1e1, 0.25, True, None, (1e-4, 1e2)),  # 4 decades, a decade more at each end
        (1e-18, 5.0, 0.1, True, 5e-10, (5e-10, 50.0)),  # the floor: only the top is padded
        (3.0, 3.0, 0.1, False, None, (2.7, 3.3)),  # one value: ±10 %, as HoloViews does
        (0.0, 0.0, 0.1, False, None, (-0.5, 0.5)),
        (np.inf, -np.inf, 0.1, False, None, None),  # no data
        (-1.0, 2.0, 0.1, True, None, None),  # a log axis reaching 0 without a floor
        (1.0001, 1.0001, 0.1, True, None, (0.90009, 1.10011)),  # one value on a log axis
        (1e-20, 1e-12, 0.1, True, 1e-10, None),  # every value below the floor
    ],
)
def test_an_axis_covers_its_data_with_the_stated_padding(low, high, padding, log, floor, expected):
    limits = axes.padded_range(low, high, padding, log=log, floor=floor)
    if expected is None:
        assert limits is None
    else:
        assert limits == pytest.approx(expected, rel=1e-12)


def test_the_axis_limits_cover_every_layer_and_the_lowest_floor():
    """Along x and y the union of the layers' extents; a PSD's y axis starts at the lowest of
    its curves' floors; an empty layer (the other model's curve while it computes) counts for
    nothing."""
    psd = hv.Dimension("psd", range=(1e-9, None))
    layers = [
        hv.Curve(([1.0, 2.0], [1e-3, 1.0]), vdims=[psd]),
        hv.Curve(([0.5, 4.0], [1e-2, 0.1]), vdims=[psd.clone(range=(1e-11, None))]),
        hv.Curve(([], [])),
    ]
    limits = axes.axis_limits(layers, (0.0, 0.1), logy=True)
    assert limits["xlim"] == pytest.approx((0.5, 4.0), rel=1e-12)
    assert limits["ylim"] == pytest.approx((1e-11, 10.0**1.1), rel=1e-12)
    assert axes.axis_limits([hv.Curve(([], []))], (0.1, 0.1)) == {}
    assert axes.axis_limits([], (0.1, 0.1)) == {}


def test_each_passage_plot_states_the_limits_of_its_data(cheap_results):
    """The passage plots carry their axis limits (what an update in place sets again): the
    time axis ends at the record's ends, with or without a pinned run (HoloViews padded it
    by 10 % once a run was pinned), and the depth axis is inverted around 0–deepest."""
    pinned = [("pinned", cheap_results, "#E69F00")]
    for spec in plots.PLOTS:
        for overlays in ((), pinned):
            element = spec.draw(cheap_results, overlays=overlays)
            limits = hv.Store.lookup_options("bokeh", element, "plot").kwargs
            assert {"xlim", "ylim"} <= set(limits), spec.key
    vt = cheap_results.vehicle_track
    for overlays in ((), pinned):
        element = plots.block_displacement_plot(cheap_results, overlays=overlays)
        xlim = hv.Store.lookup_options("bokeh", element, "plot").kwargs["xlim"]
        assert xlim == pytest.approx((vt.t_s[0], vt.t_s[-1]), rel=1e-12)
    figure = hv.render(plots.depth_profile_plot(cheap_results), backend="bokeh")
    deepest = cheap_results.soil.depth_m.max()
    pad = plots.DEPTH_PADDING[1] * deepest
    assert (figure.y_range.start, figure.y_range.end) == pytest.approx((deepest + pad, -pad))


def test_the_report_has_the_other_model_and_the_inputs_in_engineering_units(cheap_results):
    report = build_report(cheap_results, "cheap")
    depth = report.objects[1].objects[4].object  # the depth plot, fifth of the figures
    assert {layer.label for layer in depth} >= {"2D section", "2.5D moving load"}
    table = inputs_html(cheap_results.scenario)
    assert "Soil Young&#x27;s modulus (MPa)" in table and "<td class='value'>6</td>" in table
    assert "<code>soil.youngs_modulus</code>" in table


def test_the_preset_note_follows_the_preset_and_custom_inputs(cheap_scenario):
    board = Dashboard(scenario=Scenario.preset("paper"), preset="paper")
    descriptions = scenarios.preset_descriptions()
    board.inputs.preset_select.value = "single_bogie"
    assert descriptions["single_bogie"][:40] in html.unescape(board.inputs.preset_note.object)
    board.scenario.train.speed_kmh = 61.0
    assert board.inputs.preset_select.value == scenarios.CUSTOM
    note = html.unescape(board.inputs.preset_note.object)
    assert "Custom inputs" in note and "single_bogie" in note


def test_the_study_says_how_many_runs_and_how_long_before_start(cheap_scenario):
    view = StudyView(scenario_source=cheap_scenario, threaded=False)
    view.first_points.value, view.seeds.value = 4, 3
    assert view.plan.object.startswith("**12 runs**") and "workers (estimate)" in view.plan.object


def test_few_seeds_draw_their_range_and_the_points_of_the_mean():
    table = pd.DataFrame(
        {
            "train.speed_kmh": [60.0, 60.0, 60.0, 80.0, 80.0, 80.0],
            "seed": [1, 2, 3, 1, 2, 3],
            "peak_disp_invert_m": [1e-3, 2e-3, 4e-3, 3e-3, 4e-3, 8e-3],
        }
    )
    area, curve, points = band_plot(study_bands(table), "train.speed_kmh", "peak_disp_invert_m")
    assert area.label == "min–max of 3 seeds"
    np.testing.assert_allclose(area.dimension_values(1), [1.0, 3.0])
    np.testing.assert_allclose(area.dimension_values(2), [4.0, 8.0])
    assert isinstance(points, hv.Scatter) and len(points) == 2  # two points are visible
    depths = {"profile_peak_disp_0m_m": [1e-3] * 6, "profile_peak_disp_5m_m": [5e-4] * 6}
    envelope = depth_envelope_plot(table.assign(**depths))
    assert "min–max of 6 runs" in {layer.label for layer in envelope}


def test_a_cancelled_study_is_partial_and_covers_every_point():
    table = pd.DataFrame({"train.speed_kmh": [60.0], "seed": [1], "peak_disp_invert_m": [1e-3]})
    table.attrs.update(n_runs=20, cancelled=True)
    assert partial_note(table) == " (partial: 1 of 20 runs)"
    table.attrs.update(n_runs=1, cancelled=False)
    assert partial_note(table) == ""
    # 5 points × 9 seeds: after the first third of the runs, every point has 3 seeds
    order = submission_order(5, 9)
    assert sorted(order) == list(range(45))
    first_third = {index // 9 for index in order[:15]}
    assert first_third == set(range(5))


@pytest.mark.parametrize("panel_first", [False, True])
def test_a_closed_session_lets_go_of_its_page_whatever_was_cleaned_up_first(
    cheap_scenario, cache, panel_first
):
    """The server runs a closed session's clean-ups in no set order: the dashboard's close
    after Panel's own destroyed the page's models failed ("ReactiveHTML … data doesn't have a
    value set") and stopped half-way, and each plot pane told to show nothing logged "could not
    be replaced with new model Spacer". It now drops its results without touching the page,
    and nothing is left holding the dashboard."""
    import gc
    import weakref

    from bokeh.document import Document
    from panel.io.document import _cleanup_doc
    from panel.io.state import set_curdoc

    board = Dashboard(scenario=cheap_scenario(), preset="single_bogie", cache=cache)
    document = Document()
    with set_curdoc(document):
        board.template().server_doc(document)
        board.refresh()
        board.tabs.active = 1  # the long-term plots are drawn too
        assert board.runs.results is not None and board.longterm.drawn
        if panel_first:
            _cleanup_doc(document)
        with warnings_as_errors():
            board.close()
        if not panel_first:
            _cleanup_doc(document)
    assert board.runs.results is None and board.passage.plots.streams == {}
    released = weakref.ref(board)
    del board, document  # what the server drops of a closed session
    gc.collect()
    assert released() is None


@contextlib.contextmanager
def warnings_as_errors():
    """Param's warnings (Panel logs them) raise inside the block."""
    before = param.parameterized.warnings_as_exceptions
    param.parameterized.warnings_as_exceptions = True
    try:
        yield
    finally:
        param.parameterized.warnings_as_exceptions = before
