"""The long-term tab's settlement band and smooth rail in headless Debian Chromium (issue 25):
two draws on one seed started from the tab draw their band with its draw count in the legend;
one click on the smooth rail puts the ratio irregular/smooth in the tab's statement.

Waits are on the panels' text and the legend entries, not on plot titles (a title changes
while a run computes). Helpers from tests/test_browser.py.
"""

from __future__ import annotations

import pytest
from test_browser import (
    CHROMIUM,
    RUN_WAIT_MS,
    launch_chromium,
    open_dashboard,
    serve_app,
)

pytestmark = [
    pytest.mark.browser,
    pytest.mark.slow,
    pytest.mark.skipif(
        not CHROMIUM.exists(), reason="Debian Chromium (/usr/bin/chromium) is not installed"
    ),
]

BAND_WAIT_MS = 240_000  # a LocalCluster starts, then one passage and two long-term stages
LEGEND_JS = """() => [...window.Bokeh.documents].flatMap(doc => [...doc.all_models])
  .filter(m => m.type === "LegendItem").flatMap(i => i.label ? [i.label.value] : [])"""


def test_the_band_and_the_smooth_rail_of_the_long_term_tab(tmp_path):
    from playwright.sync_api import sync_playwright

    with serve_app(tmp_path / "panel.log") as url, sync_playwright() as playwright:
        browser = launch_chromium(playwright)
        try:
            page = browser.new_page(viewport={"width": 1400, "height": 1000})
            open_dashboard(page, url)
            page.locator(".bk-tab", has_text="Long-term settlement").click()
            for css, text in ((".band-draws", "2"), (".band-seeds", "1")):
                box = page.locator(f"{css} input").first
                box.fill(text)
                box.press("Enter")
            page.locator(".band-plan", has_text="2 draws over 1 passage:").wait_for(
                timeout=RUN_WAIT_MS
            )
            page.get_by_role("button", name="Start band").click()
            page.locator(".band-status", has_text="Settlement band of 2 of 2 draws").wait_for(
                timeout=BAND_WAIT_MS
            )
            page.wait_for_function(
                f"() => ({LEGEND_JS})().includes('band of 2 draws: p05–p95')",
                timeout=RUN_WAIT_MS,
            )
            page.get_by_role("button", name="Compare with a smooth rail").click()
            share = page.locator(".longterm-statement p", has_text="irregular/smooth = ")
            share.wait_for(timeout=RUN_WAIT_MS)
            assert "on a smooth rail (irregularity.enabled = False" in share.inner_text()
            page.wait_for_function(
                f"() => ({LEGEND_JS})().some(label => label.startsWith('smooth rail: '))",
                timeout=RUN_WAIT_MS,
            )
            legends = page.evaluate(LEGEND_JS)
            assert "band of 2 draws: p05–p95" in legends  # the band stays with the smooth rail
        finally:
            browser.close()
