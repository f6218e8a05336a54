"""The Ground vibration view without a browser: the plots carry the ground results in dB, mm and
mm/s with the criterion line, the statement says how far the criterion is exceeded, the view's
settings redraw without a run, a full-space run says how to get surface results, and the report
gains the ground section in a half-space only."""

import dataclasses

import holoviews as hv
import numpy as np
import pytest

from dashboard import ground_view as view
from dashboard.report import build_report
from model.pipeline import StageCache, run


@pytest.fixture(scope="module")
def both(cheap_scenario):
    """(half-space results, full-space results) of the cheap scenario, 2.5D."""
    cache = StageCache()
    half, full = cheap_scenario(), cheap_scenario()
    half.tunnel.model = full.tunnel.model = "2.5d"
    half.tunnel.ground = "half_space"
    return run(half, cache=cache), run(full, cache=cache)


def _of_type(overlay, element_type):
    return [element for element in overlay.traverse(lambda e: e, [element_type])]


def test_band_levels_plot_draws_the_chosen_distances_and_the_criterion(both):
    results = both[0]
    ground = results.ground
    plot = view.band_levels_plot(results, criterion_db=75.0, distances_m=(0.0, 21.6))
    curves = _of_type(plot, hv.Curve)
    assert [c.label for c in curves] == ["0 m", "22 m"]  # 21.6 m → the nearest computed, 22 m
    np.testing.assert_array_equal(curves[0].dimension_values("band"), ground.band_nominal_hz)
    np.testing.assert_array_equal(
        curves[0].dimension_values("level"), ground.velocity_level_dB[:, 0]
    )
    (line,) = _of_type(plot, hv.HLine)
    assert line.data == 75.0
    assert hv.Store.lookup_options("bokeh", plot, "plot").kwargs["logx"] is True
    hv.render(plot, backend="bokeh")


def test_profiles_are_against_distance_in_engineering_units(both):
    results = both[0]
    ground = results.ground
    overall = _of_type(view.overall_level_plot(results, criterion_db=60.0), hv.Curve)[0]
    np.testing.assert_array_equal(overall.dimension_values("distance"), ground.distance_m)
    np.testing.assert_array_equal(overall.dimension_values("level"), ground.overall_level_dB)
    trough = view.surface_trough_plot(results)
    np.testing.assert_allclose(trough.dimension_values("trough"), ground.peak_disp_m * 1e3)
    speed = view.peak_velocity_plot(results)
    np.testing.assert_allclose(
        speed.dimension_values("peak_velocity"), ground.peak_velocity_m_per_s * 1e3
    )
    for spec in view.GROUND_PLOTS:
        hv.render(spec.draw(results, criterion_db=60.0), backend="bokeh")
    assert {spec.stage for spec in view.GROUND_PLOTS} == {"soil"}


def test_the_statement_says_how_far_the_criterion_is_exceeded(both):
    results = both[0]
    ground = results.ground
    level = float(ground.overall_level_dB[3])  # exceeded out to the third point, not beyond
    criterion = level + 0.01
    reach = ground.distance_m[ground.overall_level_dB > criterion].max()
    text = view.ground_statement(results, criterion)
    assert f"exceeded from the axis out to {reach:g} m" in text
    assert "not exceeded at any distance" in view.ground_statement(results, 200.0)
    assert "re 1e-9 m/s" in text
    assert "lower bound" in text  # the excitation caveat is always stated


def test_the_excitation_note_follows_the_train_s_speed_against_the_shear_waves(both):
    """100 km/h against c_s = 129 km/h: the field does not radiate; the same results labelled
    200 km/h say it radiates (only the statement's wording is checked here)."""
    results = both[0]
    assert "slower than the soil's shear waves (129 km/h)" in view.ground_statement(results)
    faster = results.scenario.copy()
    faster.train.speed_kmh = 200.0
    text = view.ground_statement(dataclasses.replace(results, scenario_json=faster.to_json()))
    assert "faster than the soil's shear waves (129 km/h): this field radiates" in text


def test_a_full_space_run_draws_empty_plots_and_says_why(both):
    results = both[1]
    assert view.ground_statement(results) == view.NO_GROUND
    for spec in view.GROUND_PLOTS:
        hv.render(spec.draw(results), backend="bokeh")


def test_the_view_follows_a_run_and_redraws_on_its_settings(both):
    half, full = both
    tab = view.GroundView()
    tab.show(half, {"soil"})
    assert tab.distance_select.options[0] == "0" and tab._plots_box.visible
    assert tab.distance_select.value == ["0", "10", "20", "50"]
    tab.criterion_input.value = 40.0
    assert tab.display.criterion_db == 40.0
    assert "Criterion 40 dB" in tab.statement.object
    tab.distance_select.value = ["4"]
    assert tab.display.distances_m == [4.0]
    tab.show(full, {"soil"})
    assert not tab._plots_box.visible and tab.statement.object == view.NO_GROUND
    tab.close()


def test_the_report_has_a_ground_section_in_the_half_space_only(both):
    half, full = both

    def texts(layout):
        return " ".join(str(getattr(pane, "object", "")) for pane in layout.select(lambda p: True))

    assert "### Ground vibration" in texts(build_report(half))
    assert "### Ground vibration" not in texts(build_report(full))
