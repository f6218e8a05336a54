"""Long-term view without a browser: the plots carry the stage's numbers, the calibration panel
fits an upload and hands the parameters over."""

import holoviews as hv
import numpy as np
import pytest

from dashboard import longterm_view as view
from model.longterm.calibration import load_triaxial_csv
from model.params import DATA_DIR, LongTerm
from model.pipeline import run

SYNTHETIC_CSV = DATA_DIR / "triaxial_synthetic.csv"


def _of_type(overlay, element_type):
    """Elements of one type in an overlay, in order."""
    return [element for element in overlay if isinstance(element, element_type)]


@pytest.fixture(scope="module")
def results(cheap_scenario):
    return run(cheap_scenario(), cache=None)


def test_settlement_plot_is_the_settlement_in_mm_on_a_log_time_axis(results):
    curve = view.settlement_time_plot(results)
    lt = results.longterm
    np.testing.assert_array_equal(curve.dimension_values(0), lt.years)
    np.testing.assert_allclose(curve.dimension_values(1), lt.settlement_m * 1e3, rtol=1e-15)
    assert hv.Store.lookup_options("bokeh", curve, "plot").kwargs["logx"] is True
    figure = hv.render(curve, backend="bokeh")
    assert figure.x_scale.__class__.__name__ == "LogScale"


def test_depth_plots_carry_strain_ratio_and_the_90_percent_depth(results):
    lt = results.longterm
    strain = view.strain_depth_plot(results)
    curve, line = _of_type(strain, hv.Curve)
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
    scenario = results.scenario
    scenario.longterm.undrained_strength = 1e3  # σ_s = 2 kPa, below q_d near the invert
    failing = run(scenario, cache=None)
    assert "⚠" in view.law_statement(failing) and "not valid near failure" in failing.warnings[-1]
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


def test_calibration_panel_fits_an_upload_and_applies_it():
    longterm = LongTerm()
    panel = view.CalibrationPanel(longterm=longterm)
    panel.__panel__()
    panel.file_input.filename = "triaxial_synthetic.csv"
    panel.file_input.value = SYNTHETIC_CSV.read_bytes()
    assert panel.fit is not None and not panel.apply_button.disabled
    assert "Fit of triaxial_synthetic.csv" in panel.message.object
    assert isinstance(panel.plot.object, hv.Overlay)
    assert longterm.soil_class == "CH"  # nothing applied before the click
    panel.apply_button.clicks += 1
    assert longterm.law == "li_selig" and longterm.soil_class == "user"
    assert longterm.law_parameters() == (panel.fit["a"], panel.fit["b"], panel.fit["m"])


def test_calibration_panel_refuses_a_bad_upload_and_says_why():
    panel = view.CalibrationPanel()
    panel.load_text("N,e,q,s\n1,0.1,10,50\n10,0.2,10,50\n20,0.3,10,50\n40,0.4,10,50\n", "one.csv")
    assert panel.fit is None and panel.apply_button.disabled and panel.plot.object is None
    assert "Refused" in panel.message.object and "m is not identifiable" in panel.message.object
    before = panel.longterm.law_parameters()
    panel.apply()
    assert panel.longterm.law_parameters() == before
