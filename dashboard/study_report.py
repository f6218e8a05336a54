"""The report of a study: its definition, its plots (:mod:`dashboard.study_plots`), the mean and
5–95 % band across seeds at every point, and the base scenario.
"""

from __future__ import annotations

import html

import pandas as pd
import panel as pn

from dashboard import plots
from dashboard.report import REPORT_TITLE, report_header, standalone_html
from dashboard.study_plots import RESULTS, display_values, study_plots
from dashboard.whatif_report import COMPARISON_CSS
from model.longterm.statements import SETTLEMENT_COVERS
from model.params import display_label
from model.scenarios import matching_preset
from model.study.definition import Study
from model.study.tables import aggregate, input_columns

STUDY_BANDS_CSS = "table.study-bands td:last-child { text-align: right; min-width: 0; }"
"""The band table is all numbers: no wide text column at its end (see :data:`COMPARISON_CSS`)."""


def study_band_table(table: pd.DataFrame) -> pd.DataFrame:
    """Mean and 5–95 % band across seeds at every point of a study, for the displacement results
    (mm), the varied parameters in their display units.

    Columns are (heading, statistic) pairs: each varied parameter's label, "Runs" (runs that
    succeeded), then mean, 5 % and 95 % of each result the table has.
    """
    bands = aggregate(table)
    deepest = table["deepest_depth_m"].dropna().unique() if "deepest_depth_m" in table else []
    results = {
        "peak_disp_invert_m": RESULTS["peak_disp_invert_m"],
        "peak_disp_11m_m": "Peak displacement 11 m below the invert",
        "peak_disp_deepest_m": f"Peak displacement {deepest[0]:g} m below the invert"
        if len(deepest) == 1
        else "Peak displacement at the deepest depth",
        "longterm_settlement_m": RESULTS["longterm_settlement_m"],
    }
    columns = {
        (display_label(path), ""): display_values(path, bands[path])
        for path in input_columns(table)
    }
    columns["Runs", ""] = bands["n_runs"].to_numpy()
    for key, label in results.items():
        if f"{key}_mean" in bands:
            for stat, heading in (("mean", "mean"), ("p05", "5 %"), ("p95", "95 %")):
                columns[f"{label} (mm)", heading] = bands[f"{key}_{stat}"].to_numpy() * plots.MM
    return pd.DataFrame(columns)


def study_band_html(table: pd.DataFrame) -> str:
    """HTML of :func:`study_band_table`: inputs to six significant digits, results (mm) to four,
    "–" where no run succeeded."""
    n_inputs = len(input_columns(table))
    bands = study_band_table(table)
    formats = [f"{{:.{6 if i < n_inputs else 4}g}}".format for i in range(bands.shape[1])]
    formats[n_inputs] = str  # runs
    return bands.to_html(
        formatters=formats,
        na_rep="–",
        classes="comparison study-bands",
        border=0,
        index=False,
    )


def _seeds_text(seeds: list[int]) -> str:
    """Seeds as text: a run of consecutive ones as "2024–2043 (20 seeds)", others listed."""
    if len(seeds) > 2 and seeds == list(range(seeds[0], seeds[0] + len(seeds))):
        return f"{seeds[0]}–{seeds[-1]} ({len(seeds)} seeds)"
    return ", ".join(str(seed) for seed in seeds)


def study_definition_html(table: pd.DataFrame) -> str:
    """HTML list of what a study varied (display units), its seeds and how its runs ended."""
    study = Study.from_json(table.attrs["study"])
    if study.sampling == "grid":
        how = "every combination of the values below"
    else:
        kind = "Latin hypercube" if study.sampling == "lhs" else "uniform random"
        how = f"{study.n_samples} points, {kind} within the ranges below (sampling seed "
        how += f"{study.sampling_seed})"
    varied = "".join(
        f"<li>{html.escape(display_label(path))}: "
        + (" – " if study.sampling != "grid" else ", ").join(
            f"{value:.6g}" for value in display_values(path, spec)
        )
        + "</li>"
        for path, spec in study.vary.items()
    )
    failed = int((table["error"] != "").sum()) if "error" in table else 0
    not_run = study.n_runs - len(table)
    return (
        f"<h3>Study</h3><p>Points: {html.escape(how)}.</p><ul>{varied or '<li>nothing varied</li>'}"
        f"</ul><p>Irregularity seeds: {_seeds_text(study.seeds)}.</p>"
        f'<p class="study-runs">Runs: {study.n_runs} in the study; {len(table) - failed} finished,'
        f" {failed} failed, {not_run} cancelled"
        + (" (the study was cancelled)" if table.attrs.get("cancelled") else "")
        + ".</p>"
    )


def build_study_report(table: pd.DataFrame, name: str | None = None) -> pn.Column:
    """Panel layout of a study's report: header, definition, plots, band table, base scenario.

    Parameters
    ----------
    table : pandas.DataFrame
        A study's rows with their ``attrs`` (:func:`model.study.execution.run_study`,
        :func:`model.study.tables.read_study`).
    name : str, optional
        Name of the base scenario in the header; default its preset's name, or "custom".
    """
    study = Study.from_json(table.attrs["study"])
    covers = (
        f"<p>The long-term settlement is {html.escape(SETTLEMENT_COVERS)}.</p>"
        if "longterm_settlement_m" in table
        else ""
    )
    header = pn.pane.HTML(
        f"<h1>{REPORT_TITLE}: study</h1>"
        + report_header(name or matching_preset(study.base))
        + "<p>The base scenario run over the varied inputs times the irregularity seeds; per "
        "point, the mean and the 5–95 % band across the seeds. Displacements are positive "
        "downward.</p>" + covers + study_definition_html(table),
        sizing_mode="stretch_width",
    )
    figures = pn.GridBox(
        *[pn.pane.HoloViews(plot, sizing_mode="stretch_width") for plot in study_plots(table)],
        ncols=2,
        sizing_mode="stretch_width",
    )
    bands = pn.pane.HTML(
        "<h3>Mean and 5–95 % band per point</h3>" + study_band_html(table),
        stylesheets=[COMPARISON_CSS, STUDY_BANDS_CSS],
        sizing_mode="stretch_width",
    )
    scenario_block = pn.pane.HTML(
        "<h3>Base scenario</h3><details><summary>All inputs (JSON, SI units except km/h)"
        f'</summary><pre class="scenario-json">{html.escape(study.base_json)}</pre></details>',
        sizing_mode="stretch_width",
    )
    return pn.Column(header, figures, bands, scenario_block, sizing_mode="stretch_width")


def study_report_html(table: pd.DataFrame, name: str | None = None) -> str:
    """The report of a study as one self-contained HTML document."""
    return standalone_html(lambda: build_study_report(table, name))
