"""What-if sessions in the served dashboard, in headless Debian Chromium (issue 16).

Pin the cheap run, change the speed, see both curves and the right differences; restore the
pinned run; save the session, reload the page, load the file and get the same table; the
session report opens offline with the overlays. Expected numbers come from running the same
two scenarios in this process (the pipeline is deterministic: same inputs, same floats).
"""

from __future__ import annotations

import re
import time

import pytest
from system_requirements import needs_chromium
from test_browser import (
    CHEAP_QUERY,
    FIGURES_JS,
    PLOT_TITLES,
    RUN_WAIT_MS,
    launch_chromium,
    open_dashboard,
    render_counts,
    serve_app,
    signatures,
    type_value,
    wait_for_new_data,
    wait_for_plots,
    wait_for_renders,
)

from dashboard.whatif import CURRENT_LABEL, WhatIfSession
from dashboard.whatif_report import comparison_html
from model.params import Scenario
from model.pipeline import StageCache, run

pytestmark = [
    pytest.mark.browser,
    pytest.mark.slow,
    needs_chromium,
]

PINNED = "today"

# Every figure's legend entries in drawing order, as the browser draws them: a legend item
# labelled by a data field (the pinned runs' lines) stands for one entry per run; an item hidden
# (its curve is, dashboard.legend_swatches) is not drawn.
LEGENDS_JS = """() => {
  const out = {};
  for (const doc of (window.Bokeh ? window.Bokeh.documents : [])) {
    for (const model of doc.all_models) {
      if (model.type !== "Figure" || !model.title) continue;
      const legends = [...model.center, ...model.below].filter(m => m.type === "Legend");
      out[model.title.text] = legends.flatMap(legend => legend.items
        .filter(item => item.visible)
        .flatMap(item => item.get_labels_list_from_label_prop()));
    }
  }
  return out;
}"""


@pytest.fixture(scope="module")
def app_url(tmp_path_factory):
    with serve_app(tmp_path_factory.mktemp("server") / "panel.log") as url:
        yield url


@pytest.fixture(scope="module")
def browser():
    from playwright.sync_api import sync_playwright

    with sync_playwright() as playwright:
        chromium = launch_chromium(playwright)
        yield chromium
        chromium.close()


@pytest.fixture(scope="module")
def expected_table():
    """The comparison table the page must show: the cheap run pinned, the current at 90 km/h."""
    cache = StageCache()
    pinned = Scenario.preset("single_bogie")
    for item in CHEAP_QUERY.split("&")[1:]:
        path, _, value = item.partition("=")
        pinned.set_value(path, value)
    current = pinned.copy()
    current.train.speed_kmh = 90.0
    session = WhatIfSession()
    session.pin(run(pinned, cache=cache), PINNED)
    return _text(comparison_html(session.comparison(run(current, cache=cache))))


def _text(table_html: str) -> str:
    """Cell texts of an HTML table, whitespace-normalised (to compare with the page's)."""
    return " ".join(re.sub(r"<[^>]+>", " ", table_html).split())


@pytest.fixture
def page(browser, app_url):
    context = browser.new_context(viewport={"width": 1400, "height": 1400}, accept_downloads=True)
    page = context.new_page()
    open_dashboard(page, app_url)
    yield page
    context.close()


def _legends(page) -> dict[str, list[str]]:
    return page.evaluate(LEGENDS_JS)


def _pin(page, name: str) -> None:
    page.locator(".whatif-name input").fill(name)
    page.locator(".whatif-name input").press("Tab")  # the text box sends its value on blur
    page.locator(".whatif-pin button").click()
    page.wait_for_function(
        f"""() => Object.values(({LEGENDS_JS})()).every(n => n.includes({PINNED!r}))""",
        timeout=RUN_WAIT_MS,
    )


def _table(page) -> str:
    """Cell texts of the comparison table on the page, whitespace-normalised."""
    tables = page.locator(".whatif-table table")
    return " ".join(tables.inner_text().split()) if tables.count() else ""


def _wait_for_table(page, expected: str) -> None:
    """Wait until the page's comparison table reads ``expected`` (it follows each run)."""
    deadline = time.monotonic() + RUN_WAIT_MS / 1000
    while _table(page) != expected and time.monotonic() < deadline:
        page.wait_for_timeout(200)
    assert _table(page) == expected


def _change_speed(page, value: str) -> None:
    counts, before = render_counts(page), signatures(page)
    type_value(page, "train.speed_kmh", value)
    wait_for_renders(page, "soil", counts["soil"] + 1)
    wait_for_new_data(page, before, PLOT_TITLES)


def test_pin_then_change_shows_both_curves_and_the_differences(page, expected_table):
    _pin(page, PINNED)
    _change_speed(page, "90")
    for title in PLOT_TITLES:
        names = _legends(page)[title]
        assert names.index(PINNED) < names.index(CURRENT_LABEL), (title, names)  # current on top
    figures = {f["title"]: f for f in page.evaluate(FIGURES_JS)}
    assert figures["Invert load"]["points"] > 20
    _wait_for_table(page, expected_table)


def test_restore_makes_the_pinned_run_current(page):
    _pin(page, PINNED)
    _change_speed(page, "90")
    counts = render_counts(page)
    page.locator(".whatif-chosen select").select_option(PINNED)
    page.locator(".whatif-restore button").click()
    wait_for_renders(page, "soil", counts["soil"] + 1)
    box = page.locator(".param-train-speed_kmh input").first
    assert float(box.input_value()) == 100.0
    # the current run equals the pinned one again: every difference is zero, no input differs
    row = page.locator(".whatif-table tr", has_text=CURRENT_LABEL)
    cells = [c.strip() for c in row.locator("td").all_inner_texts()]
    n = (len(cells) - 1) // 3  # (value, Δ, Δ %) per quantity, then the inputs that differ
    assert n >= 5 and len(cells) == 3 * n + 1, cells  # long-term settlement included
    assert cells[1 : 3 * n : 3] == ["0"] * n and cells[2 : 3 * n : 3] == ["0"] * n, cells
    assert cells[-1] == "", cells


def test_saved_session_reloads_to_the_same_table(page, app_url, tmp_path):
    _pin(page, PINNED)
    _change_speed(page, "90")
    before = _table(page)
    with page.expect_download(timeout=RUN_WAIT_MS) as download:
        page.locator(".whatif-save button").click()
    saved = tmp_path / "session.json"
    download.value.save_as(saved)
    page.reload()
    open_dashboard(page, app_url)
    assert page.locator(".whatif-run").count() == 0
    page.locator(".whatif-load input[type=file]").set_input_files(str(saved))
    page.locator(".whatif-run").first.wait_for(timeout=RUN_WAIT_MS)
    _wait_for_table(page, before)  # the saved current run (90 km/h) is current again
    assert float(page.locator(".param-train-speed_kmh input").first.input_value()) == 90.0


def test_session_report_opens_offline_with_the_overlays(page, browser, tmp_path):
    _pin(page, PINNED)
    _change_speed(page, "90")
    with page.expect_download(timeout=RUN_WAIT_MS) as download:
        page.locator(".whatif-report button").click()
    report = tmp_path / "report.html"
    download.value.save_as(report)
    offline = browser.new_context(offline=True)
    network = []
    offline.route(
        re.compile(r"^https?://"), lambda route: (network.append(route.request.url), route.abort())
    )
    viewer = offline.new_page()
    viewer.goto(report.as_uri())
    wait_for_plots(viewer, timeout_ms=30_000)
    for title, names in _legends(viewer).items():
        if title in PLOT_TITLES:
            assert PINNED in names and CURRENT_LABEL in names, (title, names)
    assert viewer.locator("table.comparison").count() == 1
    assert network == []
    offline.close()
