"""Regenerate assets/dashboard.png: the running dashboard on the paper's case.

Run: ``python docs/screenshot.py`` (needs Debian's Chromium at /usr/bin/chromium).
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT), str(ROOT / "tests")]

from playwright.sync_api import sync_playwright  # noqa: E402
from test_browser import launch_chromium, serve_app, wait_for_plots  # noqa: E402

OUT = ROOT / "assets" / "dashboard.png"


def main() -> None:
    with (
        tempfile.TemporaryDirectory() as tmp,
        serve_app(Path(tmp) / "server.log") as url,
        sync_playwright() as playwright,
    ):
        browser = launch_chromium(playwright)
        page = browser.new_page(viewport={"width": 1400, "height": 1300})
        page.goto(f"{url}?preset=paper")
        wait_for_plots(page)
        page.get_by_text("Soil", exact=True).first.click()
        page.wait_for_timeout(1500)
        page.screenshot(path=str(OUT))
        browser.close()
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()
