"""The long-term tab's checks without a browser (issue 25): every long-term result says what it
covers; the settlement band drawn behind the curve is model.settlement_band's; the smooth rail
drawn over it is model.run's with the irregularity off; results of other inputs drop both."""

import holoviews as hv
import numpy as np
import pytest

from dashboard import longterm_checks as checks
from dashboard.longterm_view import SETTLEMENT_PLOT, LongTermView, law_statement
from dashboard.whatif import WhatIfSession
from dashboard.whatif_report import build_session_report
from model.longterm.statements import SETTLEMENT_COVERS
from model.pipeline import STAGES, run
from model.study.band import settlement_band
from model.study.execution import study_client


@pytest.fixture(scope="module")
def client():
    """A LocalCluster of two single-threaded workers shared by the module's bands."""
    with study_client(None, n_workers=2) as dask_client:
        yield dask_client


@pytest.fixture(scope="module")
def results(cheap_scenario, cache):
    return run(cheap_scenario(), cache=cache)


@pytest.fixture(scope="module")
def other_results(cheap_scenario, cache):
    """The cheap scenario with a stiffer soil: results of other inputs."""
    scenario = cheap_scenario()
    scenario.soil.youngs_modulus = 12e6
    return run(scenario, cache=cache)


@pytest.fixture
def view(results, cache, client):
    """The tab, headless and unthreaded, showing ``results``; bands on the module's cluster."""
    tab = LongTermView(
        results.scenario.longterm,
        results.scenario.site,
        compute=lambda scenario: run(scenario, cache=cache),
        scheduler=client,
    )
    tab.__panel__()
    tab.show(results, set(STAGES))
    return tab


def shown_settlement(view) -> hv.Overlay:
    """The settlement plot as drawn now."""
    return view.plots.panes[SETTLEMENT_PLOT].object[()]


def labelled(overlay: hv.Overlay, start: str) -> list[hv.Element]:
    return [element for element in overlay if element.label.startswith(start)]


def test_every_long_term_result_says_what_it_covers(results):
    assert SETTLEMENT_COVERS.startswith("train-induced: cyclic plastic strain")
    assert f"**What it covers:** {SETTLEMENT_COVERS}." in law_statement(results)
    title = hv.Store.lookup_options("bokeh", checks.settlement_plot(results), "plot").kwargs
    assert title["title"].startswith("Train-induced settlement: ")
    header = build_session_report(WhatIfSession(), results).objects[0].object
    assert SETTLEMENT_COVERS in header  # the what-if report compares long-term settlements


def test_the_band_drawn_is_model_settlement_band_s_with_its_draw_count(view, results, client):
    """Three draws over two seeds with a CV of a: the plan before Start, then p05–p95 shaded
    behind the curve and p50, equal to model.settlement_band's of the same inputs (both run on
    the same workers: to rounding, 1e-12 relative)."""
    band = view.band
    band.draws.value, band.seeds.value, band.cv_a.value = 3, 2, 0.2
    assert band.plan.object.startswith("**3 draws** over 2 passages: ")
    assert labelled(shown_settlement(view), "band of") == []  # nothing before the click
    band.start_button.clicks += 1
    expected = settlement_band(results.scenario, 3, seeds=2, scheduler=client, law_cv={"a": 0.2})
    overlay = shown_settlement(view)
    (area,), (p50,) = labelled(overlay, "band of"), labelled(overlay, "p50 of")
    assert area.label == "band of 3 draws: p05–p95" and p50.label == "p50 of 3 draws"
    np.testing.assert_array_equal(area.dimension_values(0), expected["years"])
    for values, column in ((area.dimension_values(1), "p95"), (area.dimension_values(2), "p05")):
        np.testing.assert_allclose(values, expected[column] * 1e3, rtol=1e-12, atol=0.0)
    np.testing.assert_allclose(p50.dimension_values(1), expected["p50"] * 1e3, rtol=1e-12)
    assert [element.label for element in overlay] == [  # behind the total, over the parts
        "plastic S_p",
        "consolidation S_c",
        "band of 3 draws: p05–p95",
        "p50 of 3 draws",
        "total S",
    ]
    assert band.status.object.startswith("**Settlement band of 3 of 3 draws** (2 irregularity")
    hv.render(overlay, backend="bokeh")


def test_other_inputs_drop_the_band_and_say_so(view, other_results):
    band = view.band
    band.draws.value, band.seeds.value = 2, 1
    band.start_button.clicks += 1
    assert band.table is not None and labelled(shown_settlement(view), "band of")
    view.show(other_results, set(STAGES))
    assert band.table is None and labelled(shown_settlement(view), "band of") == []
    assert band.status.object.startswith("**Band of 2 draws dropped:** the inputs changed")


def test_a_band_running_when_the_inputs_change_is_cancelled_and_not_drawn(
    view, other_results, monkeypatch
):
    """The results of a change arrive while the band computes: its cancel event is set and
    what it returns is not drawn."""
    seen = {}

    def band_meanwhile(scenario, n_draws, cancel, **kwargs):
        view.show(other_results, set(STAGES))
        seen["cancelled"] = cancel.is_set()
        return settlement_band(scenario, n_draws, cancel=cancel, **kwargs)

    monkeypatch.setattr(checks, "settlement_band", band_meanwhile)
    view.band.draws.value, view.band.seeds.value = 1, 1
    view.band.start_button.clicks += 1
    assert seen == {"cancelled": True}
    assert view.band.table is None and not view.band.running
    assert view.band.status.object == "**Band cancelled:** the inputs changed while it ran."


def test_a_closed_session_cancels_its_band(view, monkeypatch):
    seen = {}

    def band_closed_meanwhile(scenario, n_draws, cancel, **kwargs):
        view.close()
        seen["cancelled"] = cancel.is_set()
        return settlement_band(scenario, n_draws, cancel=cancel, **kwargs)

    monkeypatch.setattr(checks, "settlement_band", band_closed_meanwhile)
    view.band.draws.value, view.band.seeds.value = 1, 1
    view.band.start_button.clicks += 1
    assert seen == {"cancelled": True} and view.band.table is None


def test_the_smooth_rail_is_model_run_without_the_irregularity(view, results, other_results):
    """One click: the curve over the settlement plot is model.run's of the same inputs with
    irregularity.enabled = False (same process, same code: exactly), and the tab's statement
    gives irregular/smooth after the service time; other inputs drop it."""
    view.smooth_rail.button.clicks += 1
    smooth_scenario = results.scenario
    smooth_scenario.irregularity.enabled = False
    smooth = run(smooth_scenario, cache=None).longterm
    (curve,) = labelled(shown_settlement(view), "smooth rail")
    np.testing.assert_array_equal(curve.dimension_values(0), smooth.years)
    np.testing.assert_array_equal(curve.dimension_values(1), smooth.settlement_m * 1e3)
    ratio = results.longterm.settlement_m[-1] / smooth.settlement_m[-1]
    assert f"irregular/smooth = {ratio:.3g}" in view.law_statement.object
    assert f"{smooth.settlement_m[-1] * 1e3:.3g} mm on a smooth rail" in view.law_statement.object
    assert checks.irregularity_ratio(results, view.smooth_rail.smooth) == pytest.approx(
        ratio, rel=1e-15
    )
    view.show(other_results, set(STAGES))
    assert labelled(shown_settlement(view), "smooth rail") == []
    assert "irregular/smooth" not in view.law_statement.object
    assert view.smooth_rail.status.object.startswith("**Smooth rail dropped:**")


def test_a_smooth_rail_already_is_said_not_run(cheap_scenario, cache):
    scenario = cheap_scenario()
    scenario.irregularity.enabled = False
    smooth = run(scenario, cache=cache)
    tab = LongTermView(scenario.longterm, scenario.site, compute=lambda s: pytest.fail(str(s)))
    tab.show(smooth, set(STAGES))
    tab.smooth_rail.button.clicks += 1
    assert tab.smooth_rail.smooth is None
    assert "smooth already" in tab.smooth_rail.status.object


def test_an_empty_count_is_refused_with_its_range(view):
    view.band.draws.value = None
    expected = "Cannot start: Draws is empty: give a whole number from 1 to 1000"
    assert view.band.plan.object == expected
    view.band.start_button.clicks += 1
    assert view.band.status.object.startswith("**Not started:** Draws is empty")
    assert not view.band.running and view.band.table is None
