"""Static, self-contained HTML reports: the document they are written in, and the report of one
run (the dashboard's plots, key numbers, long-term settlement and scenario).

:func:`standalone_html` makes any Panel layout one HTML file with its JavaScript and CSS inline,
so it opens offline; the what-if session report (:mod:`dashboard.whatif_report`) and the study
report (:mod:`dashboard.study_report`) are written with it too. The command line is
``python -m dashboard.export`` (:mod:`dashboard.export`).
"""

from __future__ import annotations

import datetime
import html
import importlib.metadata
import io
from collections.abc import Callable
from pathlib import Path

import panel as pn
from bokeh.document import Document
from bokeh.models import ImportedStyleSheet, InlineStyleSheet
from bokeh.resources import INLINE
from panel.io.resources import CDN_DIST, DIST_DIR, set_resource_mode
from panel.io.state import set_curdoc

from dashboard import key_numbers, plots
from dashboard.controls import clean_number, format_value
from dashboard.ground_view import GROUND_PLOTS, ground_statement
from dashboard.longterm_view import LONGTERM_PLOTS, law_statement
from dashboard.site_view import layers_html
from model.params import SECTIONS, Scenario, display_label, display_unit, parameter_of
from model.pipeline import Results, SimulationError, StageCache, run

REPORT_TITLE = "tunnelsettle report"
# Panel's page template links its favicons from a CDN; empty values keep the file offline.
_OFFLINE_TEMPLATE_VARIABLES = {"app_favicon": "", "apple_icon": ""}


def items_html(items: list[key_numbers.SummaryItem], css_class: str) -> str:
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

LAYERS_CSS = """
table.layers { border-collapse: collapse; font-size: 12px; display: block; overflow-x: auto; }
table.layers th, table.layers td { border: 1px solid #d0d7de; padding: 2px 6px; }
table.layers th { background: #f6f8fa; font-weight: 600; }
"""
"""Style of the report's layer table (:func:`dashboard.site_view.layers_html`)."""


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


def other_model_results(results: Results, cache: StageCache | None = None) -> Results | None:
    """The run of ``results``' scenario with the other tunnel–soil model, drawn faint on the
    depth plot as in the dashboard (None if that run fails)."""
    other = results.scenario
    other.tunnel.model = plots.OTHER_MODEL[other.tunnel.model]
    try:
        return run(other, cache=cache)
    except (ValueError, SimulationError):
        return None


def inputs_html(scenario: Scenario) -> str:
    """Every input of ``scenario`` in a table per section, in the dashboard's units (MPa, MN/m,
    …) with its dotted name."""
    sections = []
    for section in SECTIONS:
        rows = []
        for name, value in getattr(scenario, section).param.values().items():
            path = f"{section}.{name}"
            if name == "name":
                continue
            unit, factor = display_unit(path)
            shown = value
            if isinstance(value, int | float) and not isinstance(value, bool):
                shown = format_value(clean_number(value * factor), parameter_of(path))
            elif value is None:
                shown = "automatic"
            rows.append(
                f"<tr><td>{html.escape(display_label(path))}</td>"
                f"<td class='value'>{html.escape(str(shown))}</td>"
                f"<td><code>{path}</code></td></tr>"
            )
        sections.append(
            f"<h4>{html.escape(section)}</h4><table class='inputs'>{''.join(rows)}</table>"
        )
    return "".join(sections)


INPUTS_CSS = """
table.inputs { border-collapse: collapse; margin-bottom: 8px; }
table.inputs td { border-bottom: 1px solid #d0d7de; padding: 2px 10px 2px 0; }
table.inputs td.value { text-align: right; font-variant-numeric: tabular-nums; }
"""


def build_report(
    results: Results, scenario_name: str = "custom", other_model: Results | None = None
) -> pn.Column:
    """Panel layout of the report: header (scenario name, date, version), summary, warnings,
    every plot (the depth plot with ``other_model``, the other tunnel–soil model's run,
    computed if not given; the ground-vibration section in a half-space), the inputs in
    engineering units and the scenario JSON."""
    scenario = results.scenario
    if other_model is None:
        other_model = other_model_results(results)
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
        + items_html(key_numbers.summary_items(results), "summary")
        + "<h3>Derived soil quantities</h3>"
        + items_html(key_numbers.soil_items(scenario.soil), "soil")
        + warning_block,
        stylesheets=[ITEMS_CSS],
        sizing_mode="stretch_width",
    )
    companions = {"other_model": other_model}
    figures = pn.GridBox(
        *[
            pn.pane.HoloViews(
                spec.draw(
                    results, **(companions if spec.key == plots.MODEL_COMPARISON_PLOT else {})
                ),
                sizing_mode="stretch_width",
                linked_axes=False,
                css_classes=[f"plot-{spec.key}"],
            )
            for spec in (*plots.PLOTS, *LONGTERM_PLOTS)
        ],
        ncols=2,
        sizing_mode="stretch_width",
    )
    longterm = pn.pane.Markdown(
        "### Long-term settlement\n\n" + law_statement(results), sizing_mode="stretch_width"
    )
    ground = []
    if results.ground is not None:  # the half-space model's ground surface
        ground = [
            pn.pane.Markdown(
                "### Ground vibration\n\n" + ground_statement(results),
                sizing_mode="stretch_width",
            ),
            pn.GridBox(
                *[
                    pn.pane.HoloViews(
                        spec.draw(results), sizing_mode="stretch_width",
                        css_classes=[f"plot-{spec.key}"],
                    )
                    for spec in GROUND_PLOTS
                ],
                ncols=2,
                sizing_mode="stretch_width",
            ),
        ]  # fmt: skip
    site = pn.pane.HTML(
        "<h4>Site profile</h4>" + layers_html(scenario.site),
        stylesheets=[LAYERS_CSS],
        sizing_mode="stretch_width",
        css_classes=["report-layers"],
    )
    scenario_block = pn.pane.HTML(
        "<h3>Inputs</h3><details open><summary>Every input, in the dashboard's units"
        f"</summary>{inputs_html(scenario)}</details>"
        "<details><summary>The same as a scenario file (JSON, SI units except km/h)"
        f'</summary><pre class="scenario-json">{html.escape(results.scenario_json)}'
        "</pre></details>",
        stylesheets=[INPUTS_CSS],
        sizing_mode="stretch_width",
    )
    return pn.Column(
        header, figures, longterm, site, *ground, scenario_block, sizing_mode="stretch_width"
    )


def _packaged_stylesheet(sheet):
    """Inline copy of a stylesheet Panel links from its CDN, read from the installed package."""
    if not isinstance(sheet, ImportedStyleSheet) or not sheet.url.startswith(CDN_DIST):
        return sheet
    path = DIST_DIR / sheet.url.removeprefix(CDN_DIST).split("?")[0]
    return InlineStyleSheet(css=path.read_text(encoding="utf-8")) if path.exists() else sheet


def report_html(
    results: Results, scenario_name: str = "custom", other_model: Results | None = None
) -> str:
    """The report as one self-contained HTML document (inline JS and CSS); see
    :func:`build_report`."""
    return standalone_html(lambda: build_report(results, scenario_name, other_model))


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


def write_report(
    results: Results,
    path: Path,
    scenario_name: str = "custom",
    other_model: Results | None = None,
) -> Path:
    """Write :func:`report_html` to ``path`` (UTF-8) and return the path."""
    path = Path(path)
    path.write_text(report_html(results, scenario_name, other_model), encoding="utf-8")
    return path


def report_button(
    results: Callable[[], Results],
    scenario_name: Callable[[], str],
    other_model: Callable[[], Results | None] = lambda: None,
) -> pn.widgets.FileDownload:
    """The dashboard's "Download HTML report" button.

    Parameters
    ----------
    results : callable
        Returns the results on screen; called when the button is pressed.
    scenario_name : callable
        Returns the name the report's header gives the scenario.
    other_model : callable, optional
        Returns the other tunnel–soil model's run on screen (None: the report computes it).

    Returns
    -------
    panel.widgets.FileDownload
        Disabled: the dashboard enables it once there are results to report.
    """

    def report_file() -> io.BytesIO:
        """The report of the results on screen, built when the button is pressed."""
        shown = results()
        other = other_model()
        if other is not None and other.scenario.tunnel.model == shown.scenario.tunnel.model:
            other = None  # not the companion of the results on screen
        return io.BytesIO(report_html(shown, scenario_name(), other).encode("utf-8"))

    return pn.widgets.FileDownload(
        callback=report_file,
        filename="tunnelsettle_report.html",
        label="Download HTML report",
        disabled=True,
        sizing_mode="stretch_width",
        css_classes=["report-button"],
    )
