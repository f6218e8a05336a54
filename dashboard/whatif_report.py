"""The report of a what-if session: the comparison table, every plot with the visible pinned runs
overlaid on the current run, and the inputs of every run; the comparison table's HTML, which the
what-if panel shows too.
"""

from __future__ import annotations

import html
from pathlib import Path

import pandas as pd
import panel as pn

from dashboard import plots
from dashboard.report import REPORT_TITLE, report_header, standalone_html
from dashboard.whatif import CURRENT_LABEL, WhatIfSession, load_session
from model.longterm.statements import SETTLEMENT_COVERS
from model.pipeline import Results, StageCache, run

COMPARISON_CSS = """
table.comparison { border-collapse: collapse; font-size: 13px; }
table.comparison th, table.comparison td { border: 1px solid #d0d7de; padding: 3px 6px; }
table.comparison td { text-align: right; }
table.comparison tbody th { text-align: left; min-width: 10em; }
table.comparison td:last-child { text-align: left; min-width: 16em; }
"""
"""Style of :func:`comparison_html` tables: the what-if panel's, the session report's, and the
study report's band table."""


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
        + comparison_html(session.comparison(current))
        + f"<p>The long-term settlement is {html.escape(SETTLEMENT_COVERS)}.</p>",
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
