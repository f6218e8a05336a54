"""Static, self-contained HTML report of one run: the dashboard's plots, summary and scenario;
of a what-if session: the plots with the pinned runs overlaid and the comparison table; or of a
study: its definition, plots and the band of every grid point.

All JavaScript and CSS are inlined, so the file opens offline. Command line::

    python -m dashboard.export --preset paper --out report.html
    python -m dashboard.export --scenario scenario.json --set train.speed_kmh=60 --out report.html
    python -m dashboard.export --session whatif_session.json --out report.html
    python -m dashboard.export --study study/ --out report.html
"""

from __future__ import annotations

import argparse
import datetime
import html
import importlib.metadata
import io
import sys
from collections.abc import Callable
from pathlib import Path

import pandas as pd
import panel as pn
from bokeh.document import Document
from bokeh.models import ImportedStyleSheet, InlineStyleSheet
from bokeh.resources import INLINE
from panel.io.resources import CDN_DIST, DIST_DIR, set_resource_mode
from panel.io.state import set_curdoc

from dashboard import plots
from dashboard.longterm_view import LONGTERM_PLOTS, law_statement
from dashboard.study_view import RESULTS, display_values, study_plots
from dashboard.whatif import CURRENT_LABEL, WhatIfSession, load_session
from model.cli import add_scenario_arguments, load_scenario
from model.params import display_label
from model.pipeline import Results, SimulationError, StageCache, run
from model.scenarios import CUSTOM, matching_preset
from model.study.definition import Study
from model.study.tables import aggregate, input_columns, read_study

REPORT_TITLE = "tunnelsettle report"
# Panel's page template links its favicons from a CDN; empty values keep the file offline.
_OFFLINE_TEMPLATE_VARIABLES = {"app_favicon": "", "apple_icon": ""}


def items_html(items: list[plots.SummaryItem], css_class: str) -> str:
    """HTML block of labelled key numbers; each value carries ``data-key`` for tests."""
    cells = "".join(
        f'<div class="item"><div class="label">{html.escape(item.label)}</div>'
        f'<div class="value" data-key="{item.key}">{html.escape(item.text)}</div></div>'
        for item in items
    )
    return f'<div class="{css_class}">{cells}</div>'


ITEMS_CSS = """
.summary, .soil { display: flex; flex-wrap: wrap; gap: 8px; }
.item { border: 1px solid #d0d7de; border-radius: 6px; padding: 6px 10px; min-width: 120px; }
.item .label { font-size: 12px; color: #57606a; }
.item .value { font-size: 18px; font-weight: 600; }
"""
"""Style of :func:`items_html` blocks, shared by the dashboard and the report."""


def package_version() -> str:
    """Installed version of tunnelsettle, or "not installed" when run from a source tree."""
    try:
        return importlib.metadata.version("tunnelsettle")
    except importlib.metadata.PackageNotFoundError:
        return "not installed"


def report_header(scenario_name: str, when: datetime.datetime | None = None) -> str:
    """HTML line naming the scenario, the date (UTC) and the program's version."""
    when = when or datetime.datetime.now(datetime.UTC)
    return (
        f'<p class="report-meta">Scenario: <b>{html.escape(scenario_name)}</b> · '
        f"{when:%Y-%m-%d %H:%M} UTC · tunnelsettle {html.escape(package_version())}</p>"
    )


def build_report(results: Results, scenario_name: str = "custom") -> pn.Column:
    """Panel layout of the report: header (scenario name, date, version), summary, warnings,
    every plot and the full scenario JSON."""
    scenario = results.scenario
    warnings = "".join(f"<li>{html.escape(w)}</li>" for w in results.warnings)
    warning_block = (
        f'<div class="warnings"><h3>Warnings</h3><ul>{warnings}</ul></div>' if warnings else ""
    )
    header = pn.pane.HTML(
        f"<h1>{REPORT_TITLE}</h1>"
        + report_header(scenario_name)
        + "<p>Train → track → tunnel → soil: peak dynamic displacement below a metro tunnel in "
        "soft soil, and its permanent settlement over years of traffic. Displacements are "
        "positive downward. Tunnel–soil model: "
        + f"<b>{plots.MODEL_NAMES[scenario.tunnel.model]}</b>.</p>"
        "<h3>Key numbers</h3>"
        + items_html(plots.summary_items(results), "summary")
        + "<h3>Derived soil quantities</h3>"
        + items_html(plots.soil_items(scenario.soil), "soil")
        + warning_block,
        stylesheets=[ITEMS_CSS],
        sizing_mode="stretch_width",
    )
    figures = pn.GridBox(
        *[
            pn.pane.HoloViews(
                spec.draw(results), sizing_mode="stretch_width", css_classes=[f"plot-{spec.key}"]
            )
            for spec in (*plots.PLOTS, *LONGTERM_PLOTS)
        ],
        ncols=2,
        sizing_mode="stretch_width",
    )
    longterm = pn.pane.Markdown(
        "### Long-term settlement\n\n" + law_statement(results), sizing_mode="stretch_width"
    )
    scenario_block = pn.pane.HTML(
        "<h3>Scenario</h3><details open><summary>All inputs (JSON, SI units except "
        f'km/h)</summary><pre class="scenario-json">{html.escape(results.scenario_json)}'
        "</pre></details>",
        sizing_mode="stretch_width",
    )
    return pn.Column(header, figures, longterm, scenario_block, sizing_mode="stretch_width")


def _packaged_stylesheet(sheet):
    """Inline copy of a stylesheet Panel links from its CDN, read from the installed package."""
    if not isinstance(sheet, ImportedStyleSheet) or not sheet.url.startswith(CDN_DIST):
        return sheet
    path = DIST_DIR / sheet.url.removeprefix(CDN_DIST).split("?")[0]
    return InlineStyleSheet(css=path.read_text(encoding="utf-8")) if path.exists() else sheet


def report_html(results: Results, scenario_name: str = "custom") -> str:
    """The report as one self-contained HTML document (inline JS and CSS)."""
    return standalone_html(lambda: build_report(results, scenario_name))


def standalone_html(build: Callable[[], pn.viewable.Viewable]) -> str:
    """One self-contained HTML document (inline JS and CSS) of the layout ``build()`` makes."""
    document = Document()
    # A document of its own even inside a served session (Panel caches stylesheet models per
    # current document), with stylesheet links in CDN form, whatever the session uses.
    with set_curdoc(document), set_resource_mode("cdn"):
        root = build().get_root(document)
    document.add_root(root)
    # INLINE resources inline the JavaScript but Panel still links component stylesheets from
    # its CDN (holoviz/panel#6759); swap them for the packaged files so the file works offline.
    for model in root.references():
        sheets = getattr(model, "stylesheets", None)
        if sheets:
            model.stylesheets = [_packaged_stylesheet(sheet) for sheet in sheets]
    buffer = io.StringIO()
    pn.io.save.save(
        document,
        buffer,
        title=REPORT_TITLE,
        resources=INLINE,
        template_variables=_OFFLINE_TEMPLATE_VARIABLES,
    )
    return buffer.getvalue()


def write_report(results: Results, path: Path, scenario_name: str = "custom") -> Path:
    """Write :func:`report_html` to ``path`` (UTF-8) and return the path."""
    path = Path(path)
    path.write_text(report_html(results, scenario_name), encoding="utf-8")
    return path


COMPARISON_CSS = """
table.comparison { border-collapse: collapse; font-size: 13px; }
table.comparison th, table.comparison td { border: 1px solid #d0d7de; padding: 3px 6px; }
table.comparison td { text-align: right; }
table.comparison tbody th { text-align: left; min-width: 10em; }
table.comparison td:last-child { text-align: left; min-width: 16em; }
"""
"""Style of :func:`comparison_html` tables, shared by the dashboard and the session report."""


def comparison_html(table: pd.DataFrame) -> str:
    """HTML of a what-if comparison table (numbers to four significant digits, "–" if absent)."""
    return table.to_html(
        float_format=lambda value: f"{value:.4g}",
        na_rep="–",
        classes="comparison",
        border=0,
        index_names=False,
    )


def build_session_report(session: WhatIfSession, current: Results | None) -> pn.Column:
    """Panel layout of a what-if session's report: comparison table, every plot with the
    visible pinned runs overlaid on the current run, and the inputs of every run."""
    overlays = session.overlays()
    header = pn.pane.HTML(
        f"<h1>{REPORT_TITLE}: what-if session</h1>"
        + report_header("what-if session")
        + "<p>Pinned runs compared with each other"
        + (" and with the current run" if current is not None else "")
        + f". Differences are taken to <b>{html.escape(session.reference)}</b>. Displacements "
        "are positive downward.</p><h3>Comparison</h3>"
        + comparison_html(session.comparison(current)),
        stylesheets=[COMPARISON_CSS],
        sizing_mode="stretch_width",
    )
    figures = pn.GridBox(
        *[
            pn.pane.HoloViews(
                spec.draw(current, overlays=overlays),
                sizing_mode="stretch_width",
                css_classes=[f"plot-{spec.key}"],
            )
            for spec in plots.PLOTS
        ],
        ncols=2,
        sizing_mode="stretch_width",
    )
    runs = [(r.name, r.scenario_json) for r in session.runs]
    if current is not None:
        runs.append((CURRENT_LABEL, current.scenario_json))
    inputs = "".join(
        f"<details><summary>{html.escape(name)}</summary>"
        f'<pre class="scenario-json">{html.escape(text)}</pre></details>'
        for name, text in runs
    )
    scenario_block = pn.pane.HTML(
        f"<h3>Inputs of every run (JSON, SI units except km/h)</h3>{inputs}",
        sizing_mode="stretch_width",
    )
    return pn.Column(header, figures, scenario_block, sizing_mode="stretch_width")


def session_report_html(session: WhatIfSession, current: Results | None = None) -> str:
    """The report of a what-if session as one self-contained HTML document."""
    return standalone_html(lambda: build_session_report(session, current))


def write_session_report(text: str, path: Path) -> Path:
    """Recompute the runs of a saved session file's ``text`` and write its report to ``path``."""
    cache = StageCache()  # runs that differ only downstream share their upstream stages
    session, current_scenario = load_session(text, cache=cache)
    current = None if current_scenario is None else run(current_scenario, cache=cache)
    path = Path(path)
    path.write_text(session_report_html(session, current), encoding="utf-8")
    return path


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
    header = pn.pane.HTML(
        f"<h1>{REPORT_TITLE}: study</h1>"
        + report_header(name or matching_preset(study.base))
        + "<p>The base scenario run over the varied inputs times the irregularity seeds; per "
        "point, the mean and the 5–95 % band across the seeds. Displacements are positive "
        "downward.</p>" + study_definition_html(table),
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


def build_parser() -> argparse.ArgumentParser:
    """Argument parser of ``python -m dashboard.export``."""
    parser = argparse.ArgumentParser(
        prog="python -m dashboard.export",
        description="Write a self-contained HTML report of a run, a what-if session or a study.",
    )
    add_scenario_arguments(parser)
    parser.add_argument(
        "--session",
        type=Path,
        help="what-if session file saved by the dashboard: report its runs side by side "
        "(instead of --scenario and --set)",
    )
    parser.add_argument(
        "--study",
        type=Path,
        help="study folder written by python -m model study --out: report its definition, "
        "plots and bands (instead of --scenario, --set and --session)",
    )
    parser.add_argument("--out", type=Path, required=True, help="HTML file to write")
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point; returns the process exit code (2 for bad input)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.study is not None:
        return _study_main(parser, args)
    if args.session is not None:
        return _session_main(parser, args)
    try:
        scenario = load_scenario(args)
        results = run(scenario, cache=None)
        name = matching_preset(scenario)
        if name == CUSTOM and args.scenario:
            name = args.scenario.name
        write_report(results, args.out, name)
    except (ValueError, KeyError, OSError, SimulationError) as error:
        message = error.args[0] if isinstance(error, KeyError) and error.args else error
        parser.exit(2, f"error: {message}\n")
    for warning in results.warnings:
        print(f"warning: {warning}", file=sys.stderr)
    print(f"report written to {args.out}")
    return 0


def _session_main(parser: argparse.ArgumentParser, args: argparse.Namespace) -> int:
    """``--session``: the report of a saved what-if session."""
    if args.scenario is not None or args.overrides:
        parser.error("--session cannot be combined with --scenario or --set")
    try:
        write_session_report(args.session.read_text(encoding="utf-8"), args.out)
    except (ValueError, OSError, SimulationError) as error:
        parser.exit(2, f"error: {error}\n")
    print(f"session report written to {args.out}")
    return 0


def _study_main(parser: argparse.ArgumentParser, args: argparse.Namespace) -> int:
    """``--study``: the report of a saved study folder."""
    if args.scenario is not None or args.overrides or args.session is not None:
        parser.error("--study cannot be combined with --scenario, --set or --session")
    try:
        table = read_study(args.study)
        name = matching_preset(Study.from_json(table.attrs["study"]).base)
        if name == CUSTOM:
            name = args.study.resolve().name
        args.out.write_text(study_report_html(table, name), encoding="utf-8")
    except (ValueError, OSError) as error:
        parser.exit(2, f"error: {error}\n")
    print(f"study report written to {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
