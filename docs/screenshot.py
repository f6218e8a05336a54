"""Regenerate the dashboard's screenshots in assets/ (README.md and docs/dashboard.md show
them): each tab on the paper's case at 1400 px, and the page at 420 px with its drawer open.

Run: ``python docs/screenshot.py`` (needs Debian's Chromium at /usr/bin/chromium).
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT), str(ROOT / "tests")]

from playwright.sync_api import sync_playwright  # noqa: E402
from test_browser import (  # noqa: E402
    FIGURES_JS,
    PAINTED_JS,
    RUN_WAIT_MS,
    launch_chromium,
    serve_app,
    wait_for_plots,
)
from test_browser_views import LONGTERM_TITLES  # noqa: E402

ASSETS = ROOT / "assets"
SETTLE_MS = 1500  # the last plot's layout and the tab's fonts settle


def save(page, name: str) -> None:
    """Screenshot of the page as the browser painted it, to assets/<name>."""
    page.evaluate(PAINTED_JS)
    page.wait_for_timeout(SETTLE_MS)
    page.screenshot(path=str(ASSETS / name))
    print(f"wrote {ASSETS / name}")


def wait_for_comparison(page) -> None:
    """Wait until the depth plot shows the other tunnel–soil model's curve."""
    page.locator('.comparison-status[data-state="shown"]').wait_for(timeout=RUN_WAIT_MS)


def show_tab(page, tab: str) -> None:
    """Open ``tab`` and wait until it is drawn (the long-term tab's plots, the study's plan)."""
    page.locator(".bk-tab", has_text=tab).click()
    if tab.startswith("Long-term"):
        page.wait_for_function(
            f"""() => {{
              const shown = ({FIGURES_JS})().filter(f => f.points > 0).map(f => f.title);
              return {list(LONGTERM_TITLES)!r}.every(t => shown.includes(t));
            }}""",
            timeout=RUN_WAIT_MS,
        )
    else:
        page.get_by_text("Start study").wait_for(timeout=RUN_WAIT_MS)


def main() -> None:
    with (
        tempfile.TemporaryDirectory() as tmp,
        serve_app(Path(tmp) / "server.log") as url,
        sync_playwright() as playwright,
    ):
        browser = launch_chromium(playwright)
        page = browser.new_page(viewport={"width": 1400, "height": 1500})
        page.goto(f"{url}?preset=paper")
        wait_for_plots(page)
        wait_for_comparison(page)
        save(page, "dashboard.png")
        for tab, name in (
            ("Long-term settlement", "dashboard_longterm.png"),
            ("Study", "dashboard_study.png"),
        ):
            show_tab(page, tab)
            save(page, name)
        narrow = browser.new_page(viewport={"width": 420, "height": 900})
        narrow.goto(f"{url}?preset=paper")
        wait_for_plots(narrow)
        wait_for_comparison(narrow)
        narrow.locator("#sidebar-toggle").click()
        save(narrow, "dashboard_narrow.png")
        browser.close()


if __name__ == "__main__":
    main()
