"""The Study view without a browser: choices from the params, grids, plots, start/cancel logic;
the study report (dashboard/study_report.py) and its command line (dashboard/export.py).

The view's own logic is tested with ``run_study`` replaced by the same study run in this
process (no cluster; the Dask path itself is covered by tests/test_study.py). Plots are checked
against :func:`model.study.tables.aggregate` of the rows, exactly (same arithmetic, same order).
"""

from __future__ import annotations

import html
import re
import threading

import holoviews as hv
import numba
import numpy as np
import pandas as pd
import pytest
from test_dashboard import EXTERNAL_TAG, _markup_texts

from dashboard import study_view
from dashboard.export import main as export_main
from dashboard.study_plots import RESULTS, band_plot, heat_map, study_bands, study_plots
from dashboard.study_report import study_band_table, study_report_html
from dashboard.study_view import NONE, StudyView, grid_values, study_parameters
from model.longterm.statements import SETTLEMENT_COVERS
from model.params import Scenario
from model.study import execution
from model.study.definition import define_study
from model.study.execution import run_summary
from model.study.tables import aggregate, save_study


def _in_process_study(
    base, vary, seeds, scheduler=None, depth_profile=False, progress=None, cancel=None, **kwargs
):
    """run_study's contract (rows streamed, cancel honoured) computed in this thread."""
    study = define_study(base, vary, seeds, depth_profile=depth_profile)
    rows, threads = {}, numba.get_num_threads()
    try:
        for index, (inputs, scenario_json) in enumerate(study.runs()):
            if cancel is not None and cancel.is_set():
                break
            rows[index] = {**inputs, **run_summary(scenario_json, depth_profile)}
            progress(len(rows), study.n_runs, rows[index])
    finally:
        numba.set_num_threads(threads)  # run_summary limits the calling thread to one
    cancelled = len(rows) < study.n_runs
    return execution.study_table(study, rows, cancelled)


@pytest.fixture
def view(cheap_scenario, monkeypatch):
    """A view on the cheap scenario, studies computed in this process and thread."""
    monkeypatch.setattr(study_view, "run_study", _in_process_study)
    return StudyView(scenario_source=cheap_scenario, threaded=False)


def _choose(view, select, path):
    select.value = next(label for label, p in view.choices.items() if p == path)


def test_choices_are_the_number_parameters_with_their_labels():
    """Every offered parameter is a number with softbounds, labelled by its param label; the
    irregularity seed is not offered (it is the seeds input)."""
    choices = study_parameters()
    assert choices["Speed (km/h) — train.speed_kmh"] == "train.speed_kmh"
    assert "irregularity.seed" not in choices.values()
    assert "train.single_bogie" not in choices.values()
    assert any(path.startswith("soil.") for path in choices.values())


def test_choosing_a_parameter_sets_its_softbounds_as_the_range(view):
    """Range slider of a chosen parameter: its softbounds and its label, in its display unit
    (MPa for the soil modulus); the second parameter's inputs appear only when one is chosen."""
    _choose(view, view.first, "soil.youngs_modulus")
    low, high = Scenario.param["soil"].class_.param["youngs_modulus"].softbounds
    assert view.first_range.value == (low / 1e6, high / 1e6)
    assert (view.first_range.start, view.first_range.end) == (low / 1e6, high / 1e6)
    assert view.first_range.label == "Soil Young's modulus (MPa)"
    assert not view.second_range.visible
    _choose(view, view.second, "train.speed_kmh")
    assert view.second_range.visible and view.second_range.value == (20.0, 160.0)
    view.second.value = NONE
    assert not view.second_range.visible and list(view.vary()) == ["soil.youngs_modulus"]


def test_grid_values_are_even_and_whole_for_integers():
    """linspace for numbers (ends included); distinct rounded values for integer parameters."""
    assert grid_values("train.speed_kmh", 40.0, 80.0, 5) == [40.0, 50.0, 60.0, 70.0, 80.0]
    assert grid_values("irregularity.track_class", 1, 6, 11) == [1, 2, 3, 4, 5, 6]
    assert grid_values("train.speed_kmh", 40.0, 80.0, 1) == [40.0]


def test_a_range_in_display_units_gives_si_grid_values(view):
    """Soil E from 4.1 to 6.1 MPa on the slider → 4.1e6 … 6.1e6 Pa in the study, exactly (no
    conversion noise), and a slider end a drag left at 55.99999999999999 counts as 56."""
    _choose(view, view.first, "soil.youngs_modulus")
    view.first_range.value = (4.1, 6.1)
    view.first_points.value = 3
    assert view.vary() == {"soil.youngs_modulus": [4.1e6, 5.1e6, 6.1e6]}
    view.first_range.value = (20.0, 55.99999999999999)
    view.first_points.value = 2
    assert view.vary() == {"soil.youngs_modulus": [20e6, 56e6]}
    _choose(view, view.first, "irregularity.track_class")
    view.first_range.value = (1.0, 3.0)
    view.first_points.value = 3
    assert view.vary() == {"irregularity.track_class": [1, 2, 3]}
    assert all(isinstance(v, int) for v in view.vary()["irregularity.track_class"])


def test_plot_axes_carry_the_display_unit():
    """The band plot's and the heat map's parameter axes are in the display unit, labelled
    with it (MPa for the soil modulus, km/h for the speed), and so is the hover."""
    table = pd.DataFrame(
        {
            "soil.youngs_modulus": [4.1e6, 4.1e6, 6.1e6, 6.1e6],
            "train.speed_kmh": [60.0, 80.0, 60.0, 80.0],
            "seed": [1, 1, 1, 1],
            "peak_disp_invert_m": [1e-3, 2e-3, 3e-3, 4e-3],
        }
    )
    one = table[table["train.speed_kmh"] == 60.0].drop(columns="train.speed_kmh")
    curve, points = band_plot(
        study_bands(one), "soil.youngs_modulus", "peak_disp_invert_m"
    ).values()
    for element in (curve, points):  # one seed per point: no band
        assert element.kdims[0].pprint_label == "Soil Young's modulus (MPa)"
        assert list(element.dimension_values(0)) == [4.1, 6.1]
    bands = aggregate(table)
    heat = heat_map(bands, "soil.youngs_modulus", "train.speed_kmh", "peak_disp_invert_m")
    assert [d.pprint_label for d in heat.kdims] == ["Soil Young's modulus (MPa)", "Speed (km/h)"]
    assert sorted(set(heat.dimension_values("x"))) == [4.1, 6.1]


def test_one_parameter_study_draws_mean_and_band(view):
    """Start → every run comes back, progress full, the band plot holds aggregate()'s mean and
    5–95 % band in mm, and the depth envelope bounds every run's profile."""
    view.first_range.value = (90.0, 100.0)
    view.first_points.value = 2
    view.seeds.value = 2
    assert not view.progress.visible  # no empty bar before the first Start
    view.start()
    assert not view.running and view.status.object.startswith("Done: 4 of 4 runs")
    assert view.progress.value == 4 == view.progress.max and view.progress.visible
    table = view.table
    bands = aggregate(table)
    band, depth = view.plots.objects[0].object[()], view.plots.objects[-1].object[()]
    area, curve, points = band.values()
    np.testing.assert_array_equal(curve.dimension_values(1), bands["peak_disp_invert_m_mean"] * 1e3)
    np.testing.assert_array_equal(points.dimension_values(1), curve.dimension_values(1))
    # two seeds: the band is their whole range, and says so
    assert area.label == "min–max of 2 seeds"
    extremes = aggregate(table, band=(0.0, 1.0))
    np.testing.assert_array_equal(
        area.dimension_values(1), extremes["peak_disp_invert_m_p00"] * 1e3
    )
    np.testing.assert_array_equal(
        area.dimension_values(2), extremes["peak_disp_invert_m_p100"] * 1e3
    )
    panes = list(view.plots.objects)
    view._draw(table.iloc[:3])  # fewer rows: same plots, new data, figures kept
    assert view.plots.objects == panes
    assert len(panes[0].object[()].values()[1]) == 2 and panes[0].object[()] is not band
    assert "(partial: 3 of 4 runs)" in panes[0].object[()].opts.get().kwargs["title"]
    envelope = next(c for c in depth.values() if c.label == "envelope")
    profiles = table[[c for c in table if c.startswith("profile_")]].to_numpy() * 1e3
    np.testing.assert_array_equal(envelope.dimension_values(0), profiles.max(axis=0))


def test_two_parameter_study_draws_a_heat_map(view):
    """Two parameters → a heat map with one cell per grid point holding the seeds' mean."""
    view.first_range.value = (90.0, 100.0)
    view.first_points.value = 2
    _choose(view, view.second, "soil.youngs_modulus")
    view.second_range.value = (5.0, 10.0)
    view.second_points.value = 2
    view.seeds.value = 1
    view.start()
    heat = view.plots.objects[0].object[()]
    assert isinstance(heat, hv.HeatMap)
    assert len(heat) == 4
    # the colour bar's label fits the plot's height and keeps the unit (the dimension's long
    # label was cut off)
    colour_bar_label = heat.opts.get("plot").kwargs["clabel"]
    assert colour_bar_label.endswith("(mm)") and len(colour_bar_label) <= 12
    assert sorted(set(view.table["soil.youngs_modulus"])) == [5e6, 1e7]
    bands = aggregate(view.table)
    np.testing.assert_array_equal(
        np.sort(heat.dimension_values("mean")), np.sort(bands["peak_disp_invert_m_mean"] * 1e3)
    )


def test_long_term_settlement_is_drawn_when_the_key_exists():
    """A table with ``longterm_settlement_m`` gets its own band plot (synthetic numbers)."""
    table = pd.DataFrame(
        {
            "train.speed_kmh": [60.0, 60.0, 80.0, 80.0],
            "seed": [1, 2, 1, 2],
            "peak_disp_invert_m": [1e-3, 2e-3, 3e-3, 4e-3],
            "longterm_settlement_m": [0.01, 0.02, 0.03, 0.05],
        }
    )
    titles = [plot.opts.get().kwargs.get("title") for plot in study_plots(table)]
    assert titles == [RESULTS[k] for k in RESULTS]
    plot = band_plot(study_bands(table), "train.speed_kmh", "longterm_settlement_m")
    np.testing.assert_allclose(plot.values()[1].dimension_values(1), [15.0, 40.0], rtol=1e-12)
    assert isinstance(
        heat_map(
            aggregate(table.assign(**{"soil.density": 1800.0})),
            "train.speed_kmh",
            "soil.density",
            "peak_disp_invert_m",
        ),
        hv.HeatMap,
    )


def test_cancel_keeps_the_finished_rows_and_frees_the_buttons(cheap_scenario, monkeypatch):
    """Threaded: the study waits after its first row, Cancel is pressed, the view ends
    'Cancelled' with that row, Start enabled, Cancel disabled."""
    first_row = threading.Event()

    def study_that_waits(*args, progress=None, cancel=None, **kwargs):
        def progress_then_wait(done, total, row):
            progress(done, total, row)
            first_row.set()
            assert cancel.wait(timeout=60)

        return _in_process_study(*args, progress=progress_then_wait, cancel=cancel, **kwargs)

    monkeypatch.setattr(study_view, "run_study", study_that_waits)
    view = StudyView(scenario_source=cheap_scenario, threaded=True)
    view.first_range.value = (90.0, 100.0)
    view.first_points.value = 2
    view.seeds.value = 2
    view.start()
    assert first_row.wait(timeout=60)
    assert view.running and view.start_button.disabled and not view.cancel_button.disabled
    view.start()  # ignored while running
    view.cancel()
    view._thread.join(timeout=60)
    assert not view.running
    assert view.status.object.startswith("Cancelled: 1 of 4 runs")
    assert len(view.table) == 1
    assert not view.start_button.disabled and view.cancel_button.disabled


def test_bad_choices_are_refused_before_starting(view, monkeypatch):
    """The same parameter twice, or more than MAX_RUNS_UNCONFIRMED runs: a message, no study."""
    monkeypatch.setattr(study_view, "run_study", None)  # would fail if called
    _choose(view, view.second, "train.speed_kmh")
    view.start()
    assert "chosen twice" in view.status.object and not view.running
    _choose(view, view.second, "soil.youngs_modulus")
    view.first_points.value = view.second_points.value = 50
    view.seeds.value = 10
    view.start()
    assert "at most" in view.status.object and not view.running


def test_a_failed_study_is_shown_not_raised(view, monkeypatch):
    """An error from the study (e.g. an unreachable scheduler) is a message on the page."""

    def refuse(*args, **kwargs):
        raise ValueError("cannot reach the Dask scheduler at tcp://127.0.0.1:1")

    monkeypatch.setattr(study_view, "run_study", refuse)
    view.start()
    assert view.status.object == (
        "**Study failed:** cannot reach the Dask scheduler at tcp://127.0.0.1:1"
    )
    assert not view.running and not view.start_button.disabled


# ---- the study report ----------------------------------------------------------------------
@pytest.fixture(scope="module")
def study_table(cheap_scenario):
    """Soil E 5 and 10 MPa × seeds 7, 8 of the cheap scenario, with the depth profile."""
    return _in_process_study(
        cheap_scenario(),
        {"soil.youngs_modulus": [5e6, 1e7]},
        [7, 8],
        depth_profile=True,
        progress=lambda done, total, row: None,
    )


def _band_rows(report: str) -> list[list[str]]:
    """Cells of the band table's body rows, as shown."""
    table = next(t for t in _markup_texts(report) if "study-bands" in t)
    body = table.partition("<tbody>")[2]
    return [re.findall(r"<td>(.*?)</td>", row) for row in body.split("</tr>")[:-1]]


def test_study_report_is_offline_and_holds_definition_plots_and_bands(study_table):
    """Self-contained (no tag loads from the network); the definition in display units, the
    seeds and run counts; every study plot; per point the mean and 5–95 % band in mm of the
    four displacement results, equal to aggregate()'s numbers."""
    report = study_report_html(study_table, "cheap")
    assert report.startswith("<!DOCTYPE html>")
    assert not EXTERNAL_TAG.search(report), EXTERNAL_TAG.search(report)
    assert '"name":"ImportedStyleSheet"' not in report and "cdn.holoviz.org" not in report
    for plot in study_plots(study_table):
        assert plot.opts.get().kwargs["title"] in report
    assert "Depth profile across the study" in report
    shown = html.unescape("".join(_markup_texts(report)))
    assert "Scenario: <b>cheap</b>" in shown
    assert "<li>Soil Young's modulus (MPa): 5, 10</li>" in shown
    assert "Irregularity seeds: 7, 8." in shown
    assert "Runs: 4 in the study; 4 finished, 0 failed, 0 cancelled." in shown
    assert f"The long-term settlement is {SETTLEMENT_COVERS}." in shown  # issue 25

    keys = ["peak_disp_invert_m", "peak_disp_11m_m", "peak_disp_deepest_m"]
    keys.append("longterm_settlement_m")
    bands = aggregate(study_table)
    expected = np.column_stack(
        [bands[f"{key}_{stat}"] * 1e3 for key in keys for stat in ("mean", "p05", "p95")]
    )
    shown_bands = study_band_table(study_table)
    assert list(shown_bands.columns[:2]) == [("Soil Young's modulus (MPa)", ""), ("Runs", "")]
    assert shown_bands.columns[2] == ("Peak displacement at the invert (mm)", "mean")
    np.testing.assert_array_equal(shown_bands.iloc[:, 2:].to_numpy(), expected)
    rows = _band_rows(report)
    assert [row[:2] for row in rows] == [["5", "2"], ["10", "2"]]
    assert [row[2:] for row in rows] == [[f"{v:.4g}" for v in point] for point in expected]


def test_study_report_counts_failed_and_cancelled_runs(study_table):
    """A failed run (its numbers empty) and a run never made (cancelled) are counted apart;
    the band of a point leaves the failed run out."""
    table = study_table.iloc[:3].copy()
    table.loc[1, [c for c in table if c not in ("soil.youngs_modulus", "seed")]] = np.nan
    table["error"] = ["", "SimulationError: unstable", ""]
    table.attrs = {**study_table.attrs, "cancelled": True}
    shown = "".join(_markup_texts(study_report_html(table)))
    assert "Scenario: <b>custom</b>" in shown
    assert (
        "Runs: 4 in the study; 2 finished, 1 failed, 1 cancelled (the study was cancelled)."
        in shown
    )
    assert [row[1] for row in _band_rows(study_report_html(table))] == ["1", "1"]


def test_report_download_is_enabled_once_the_study_has_rows(view):
    """Disabled until a study ends with rows; the download is the study's report."""
    assert view.report_button.disabled
    view.first_range.value = (90.0, 100.0)
    view.first_points.value = 2
    view.seeds.value = 1
    view.start()
    assert not view.report_button.disabled
    report = view.report_button.callback().getvalue().decode("utf-8")
    assert report.startswith("<!DOCTYPE html>") and "tunnelsettle report: study" in report
    assert "<li>Speed (km/h): 90, 100</li>" in html.unescape("".join(_markup_texts(report)))


def test_export_command_line_writes_a_saved_studys_report(study_table, tmp_path, capsys):
    """``--study DIR``: the report of the folder save_study wrote, named after the folder."""
    save_study(study_table, tmp_path / "soft_soil")
    out = tmp_path / "report.html"
    assert export_main(["--study", str(tmp_path / "soft_soil"), "--out", str(out)]) == 0
    assert str(out) in capsys.readouterr().out
    report = out.read_text(encoding="utf-8")
    assert "Scenario: <b>soft_soil</b>" in "".join(_markup_texts(report))
    assert len(_band_rows(report)) == 2


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        ([], "runs.csv not found"),
        (["--set", "train.speed_kmh=60"], "--study cannot be combined"),
        (["--session", "s.json"], "--study cannot be combined"),
    ],
)
def test_export_command_line_refuses_a_bad_study(extra, message, tmp_path, capsys):
    """Not a study folder, or --study with another source: exit 2, a one-line error."""
    out = tmp_path / "report.html"
    with pytest.raises(SystemExit) as stop:
        export_main(["--study", str(tmp_path), "--out", str(out), *extra])
    assert stop.value.code == 2
    errors = [line for line in capsys.readouterr().err.splitlines() if "error" in line]
    assert len(errors) == 1 and message in errors[0], errors
    assert not out.exists()
