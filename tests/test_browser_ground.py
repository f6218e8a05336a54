"""The Ground vibration tab in a real browser (headless Debian Chromium, Playwright): the cheap
scenario in a half-space draws the four ground plots with data, and a typed criterion moves the
criterion line and the statement without a run."""

from __future__ import annotations

import pytest

from tests.test_browser import (
    CHEAP_QUERY,
    CHROMIUM,
    RUN_WAIT_MS,
    figures,
    launch_chromium,
    serve_app,
    wait_for_renders,
)

pytestmark = [
    pytest.mark.browser,
    pytest.mark.slow,
    pytest.mark.skipif(
        not CHROMIUM.exists(), reason="Debian Chromium (/usr/bin/chromium) is not installed"
    ),
]
GROUND_TITLES = (
    "One-third-octave velocity levels at the surface",
    "Overall velocity level against distance",
    "Dynamic surface trough during the passage",
    "Peak surface velocity",
)
HALF_SPACE_QUERY = f"{CHEAP_QUERY}&tunnel.model=2.5d&tunnel.ground=half_space"
# The server's first half-space run also loads or compiles the pipe-in-pipe kernels: on the
# shared machine it can take longer than a cached full-space run's RUN_WAIT_MS.
FIRST_RUN_WAIT_MS = 3 * RUN_WAIT_MS


def test_the_ground_tab_draws_its_plots_and_follows_the_criterion(tmp_path):
    from playwright.sync_api import sync_playwright

    with serve_app(tmp_path / "panel.log") as url, sync_playwright() as playwright:
        browser = launch_chromium(playwright)
        try:
            page = browser.new_page(viewport={"width": 1400, "height": 1000})
            page.goto(f"{url}?{HALF_SPACE_QUERY}")
            wait_for_renders(page, "soil", 1, FIRST_RUN_WAIT_MS)
            page.get_by_text("Ground vibration", exact=True).click()
            page.wait_for_function(
                """(titles) => {
                  const shown = [];
                  for (const doc of (window.Bokeh ? window.Bokeh.documents : []))
                    for (const m of doc.all_models)
                      if (m.type === "Figure" && m.title && m.title.text) shown.push(m.title.text);
                  return titles.every(t => shown.includes(t));
                }""",
                arg=list(GROUND_TITLES),
                timeout=60_000,
            )
            drawn = {f["title"]: f["points"] for f in figures(page)}
            assert all(drawn[title] > 0 for title in GROUND_TITLES), drawn
            statement = page.locator(".ground-statement p")  # the text is in its shadow root
            assert "overall velocity level" in " ".join(statement.all_inner_texts())
            box = page.locator(".ground-criterion input").first
            box.fill("30")
            box.press("Enter")
            page.get_by_text("Criterion 30 dB:").wait_for(timeout=30_000)
            assert "exceeded from the axis out to" in " ".join(statement.all_inner_texts())
        finally:
            browser.close()
