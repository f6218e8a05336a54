"""Long-term view without a browser: the plots carry the stage's numbers, the calibration panel
fits an upload and hands the parameters over."""

import holoviews as hv
import numpy as np
import pytest

from dashboard import longterm_view as view
from dashboard import site_view
from model.longterm.calibration import load_triaxial_csv
from model.longterm.statements import OUTSIDE_LAW_RANGE
from model.params import DATA_DIR, LongTerm, Site
from model.pipeline import run

SYNTHETIC_CSV = DATA_DIR / "triaxial_synthetic.csv"


def _of_type(overlay, element_type):
    """Elements of one type in an overlay, in order."""
    return [element for element in overlay if isinstance(element, element_type)]


@pytest.fixture(scope="module")
def results(cheap_scenario):
    return run(cheap_scenario(), cache=None)


def test_settlement_plot_stacks_plastic_and_consolidation_in_mm_on_a_log_time_axis(results):
    """The long-term tab's settlement plot: the plastic part from 0, the consolidation part
    on top of it, their sum as a line (mm, exact unit conversion)."""
    overlay = view.LONGTERM_PLOTS[0].draw(results)
    plastic, consolidation = _of_type(overlay, hv.Area)
    (total,) = [element for element in overlay if type(element) is hv.Curve]  # an Area is one
    lt = results.longterm
    np.testing.assert_array_equal(total.dimension_values(0), lt.years)
    np.testing.assert_allclose(total.dimension_values(1), lt.settlement_m * 1e3, rtol=1e-15)
    np.testing.assert_allclose(plastic.dimension_values(1), lt.plastic_settlement_m * 1e3)
    assert np.all(plastic.dimension_values(2) == 0.0)
    np.testing.assert_allclose(consolidation.dimension_values(1), lt.settlement_m * 1e3)
    np.testing.assert_allclose(consolidation.dimension_values(2), lt.plastic_settlement_m * 1e3)
    assert hv.Store.lookup_options("bokeh", overlay, "plot").kwargs["logx"] is True
    figure = hv.render(overlay, backend="bokeh")
    assert figure.x_scale.__class__.__name__ == "LogScale"


def test_depth_plots_carry_strain_ratio_and_the_90_percent_depth(results):
    lt = results.longterm
    strain = view.strain_depth_plot(results)
    curve, line = _of_type(strain, hv.Curve)
    (boundaries,) = _of_type(strain, hv.HLines)  # the layer boundaries (none: one layer)
    assert len(boundaries) == 0
    np.testing.assert_array_equal(curve.dimension_values("strain"), lt.strain_percent)
    np.testing.assert_array_equal(curve.dimension_values("depth"), lt.depth_m)
    # the 90 % depth is a line across the data with a legend entry (an HLine has none)
    assert line.label == view.DEPTH90_LABEL
    np.testing.assert_array_equal(line.dimension_values("depth"), [lt.depth90_m] * 2)
    np.testing.assert_array_equal(
        line.dimension_values("strain"), [lt.strain_percent.min(), lt.strain_percent.max()]
    )
    ratio = view.stress_ratio_depth_plot(results)
    ratio_curve, _ = _of_type(ratio, hv.Curve)
    np.testing.assert_allclose(
        ratio_curve.dimension_values("stress_ratio"), lt.deviator_Pa / lt.strength_Pa
    )
    np.testing.assert_allclose(ratio_curve.dimension_values("deviator"), lt.deviator_Pa / 1e3)
    assert len(_of_type(ratio, hv.Curve)) == 2  # far from failure: no failure line
    for element in (strain, ratio):
        hv.render(element, backend="bokeh")


def test_plots_are_registered_with_their_stage():
    assert {spec.stage for spec in view.LONGTERM_PLOTS} == {"longterm"}


def test_statement_names_law_parameters_results_and_warnings(results):
    text = view.law_statement(results)
    assert "Li & Selig (1996) (soil class CH): a = 1.2 %, b = 0.18, m = 2.4" in text
    assert "200 trains per day" in text and "1 cycle per train" in text
    assert f"{results.longterm.settlement_m[-1] * 1e3:.3g} mm" in text
    assert "plastic" in text and "consolidation" in text and "Illustrative defaults" in text
    scenario = results.scenario
    scenario.site.layers[0].undrained_strength = 1e3  # σ_s = 2 kPa, below q_d near the invert
    failing = run(scenario, cache=None)
    assert "⚠" in view.law_statement(failing)
    assert any("not valid near failure" in warning for warning in failing.warnings)
    # the settlement is flagged where it is shown, not left to stand (issue 29)
    assert OUTSIDE_LAW_RANGE not in text and results.summary()["longterm_stress_ratio_max"] < 1
    assert f"years ({OUTSIDE_LAW_RANGE}):** " in view.law_statement(failing)
    assert failing.summary()["longterm_stress_ratio_max"] >= 1.0
    *_, failure_line = _of_type(view.stress_ratio_depth_plot(failing), hv.Curve)
    assert failure_line.label == "failure (laws not valid)"
    np.testing.assert_array_equal(failure_line.dimension_values("stress_ratio"), [1.0, 1.0])


def test_calibration_plot_has_points_and_fitted_lines_per_level_on_log_axes():
    data = load_triaxial_csv(SYNTHETIC_CSV)
    fit = {"a": 0.9, "b": 0.15, "m": 2.1}
    overlay = view.calibration_plot(data, fit)
    curves = _of_type(overlay, hv.Curve)
    assert len(_of_type(overlay, hv.Scatter)) == len(curves) == 4
    first_curve = curves[0]
    n = first_curve.dimension_values(0)
    np.testing.assert_allclose(first_curve.dimension_values(1), 0.9 * 0.2**2.1 * n**0.15)
    options = hv.Store.lookup_options("bokeh", overlay, "plot").kwargs
    assert options["logx"] is True and options["logy"] is True
    hv.render(overlay, backend="bokeh")


def test_calibration_panel_fits_an_upload_and_applies_it_to_the_chosen_layer():
    longterm, site = LongTerm(law="monismith", pore_pressure_law="none"), Site()
    site.layers = [site.layers[0], type(site.layers[0])(name="silt")]
    panel = view.CalibrationPanel(site=site, longterm=longterm)
    panel.__panel__()
    panel.file_input.filename = "triaxial_synthetic.csv"
    panel.file_input.value = SYNTHETIC_CSV.read_bytes()
    assert panel.fit is not None and not panel.apply_button.disabled
    assert panel.pore_fit is not None and not panel.apply_pore_button.disabled
    assert "Fit of triaxial_synthetic.csv" in panel.message.object
    assert "Pore pressure:" in panel.message.object
    assert isinstance(panel.plot.object, hv.Overlay)
    silt = site.layers[1]
    assert silt.soil_class == "CH"  # nothing applied before the click
    panel.layer_select.value = 1
    panel.apply_button.clicks += 1
    assert longterm.law == "li_selig" and silt.soil_class == "user"
    assert silt.law_parameters() == (panel.fit["a"], panel.fit["b"], panel.fit["m"])
    assert site.layers[0].soil_class == "CH"  # the other layer keeps its law
    panel.apply_pore_button.clicks += 1
    assert longterm.pore_pressure_law == "power"
    assert (silt.a_u, silt.b_u, silt.m_u) == tuple(panel.pore_fit[n] for n in ("a_u", "b_u", "m_u"))
    assert "Applied to layer 'silt'" in panel.message.object


def test_calibration_panel_refuses_a_bad_upload_and_says_why():
    panel = view.CalibrationPanel()
    header = "n_cycles,strain_percent,deviator_kPa,strength_kPa\n"
    panel.load_text(header + "1,0.1,10,50\n10,0.2,10,50\n20,0.3,10,50\n40,0.4,10,50\n", "one.csv")
    assert panel.fit is None and panel.apply_button.disabled and panel.plot.object is None
    assert "Refused" in panel.message.object and "not identifiable" in panel.message.object
    before = panel.layer.law_parameters()
    panel.apply()
    assert panel.layer.law_parameters() == before


def test_pore_pressure_plot_draws_u_at_the_chosen_years_and_the_layers(results):
    """u after each chosen year within the service time and after the last, u_g dashed, the
    boundaries and the layer names; u at a year between outputs interpolated in log time."""
    lt = results.longterm
    overlay = site_view.pore_pressure_depth_plot(results, years=(1.0, 100.0))
    curves = _of_type(overlay, hv.Curve)
    final = results.scenario.longterm.years
    assert [c.label for c in curves] == [
        "u after 1 y",
        f"u after {final:g} y",
        f"u_g after {final:g} y",
    ]
    np.testing.assert_allclose(curves[1].dimension_values(0), lt.excess_pore_pressure_Pa[-1] / 1e3)
    np.testing.assert_allclose(
        curves[2].dimension_values(0), lt.generated_pore_pressure_Pa[-1] / 1e3
    )
    exact_year = lt.years[30]
    np.testing.assert_allclose(
        site_view.pore_pressure_at(results, exact_year), lt.excess_pore_pressure_Pa[30], rtol=1e-9
    )
    (labels,) = _of_type(overlay, hv.Labels)
    assert list(labels.dimension_values("name")) == ["soft clay"]
    hv.render(overlay, backend="bokeh")
