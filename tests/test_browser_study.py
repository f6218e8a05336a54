"""The Study view served and driven in headless Debian Chromium (Playwright), as a user would.

A one-line app with ``StudyView`` on the cheap single-bogie scenario is written to a temporary
folder and served with ``panel serve``; the study runs on a real LocalCluster. Follows
tests/test_browser.py (same browser, helpers reused); skipped only when Chromium is absent.
"""

from __future__ import annotations

import contextlib
import os
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from system_requirements import needs_chromium
from test_browser import (
    FIGURES_JS,
    RUN_WAIT_MS,
    SERVER_START_S,
    free_port,
    launch_chromium,
)

ROOT = Path(__file__).resolve().parent.parent
APP = """
from dashboard.study_view import StudyView
from model.params import Scenario


def cheap():
    scenario = Scenario.preset("single_bogie")
    scenario.train.speed_kmh = 100.0
    scenario.numerics.n_depths = 11
    return scenario


StudyView(scenario_source=cheap).servable()
"""
PLOTS = ("Peak displacement at the invert", "Depth profile across the study")
STUDY_WAIT_MS = 240_000  # LocalCluster start and kernel loading on a busy 2-core machine

pytestmark = [
    pytest.mark.browser,
    pytest.mark.slow,
    needs_chromium,
]


@contextlib.contextmanager
def serve_study_app(folder: Path) -> Iterator[str]:
    """``panel serve`` of the one-line Study app on a free port; yield its URL."""
    (folder / "study_app.py").write_text(APP, encoding="utf-8")
    port = free_port()
    command = [sys.executable, "-m", "panel", "serve", str(folder / "study_app.py")]
    command += ["--port", str(port), "--address", "127.0.0.1"]
    command += ["--allow-websocket-origin", f"127.0.0.1:{port}"]
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    env.pop("TUNNELSETTLE_SCHEDULER", None)
    log_path = folder / "serve.log"
    with log_path.open("w") as log:
        process = subprocess.Popen(command, cwd=ROOT, env=env, stdout=log, stderr=subprocess.STDOUT)
        try:
            deadline = time.monotonic() + SERVER_START_S
            while True:
                if process.poll() is not None:
                    raise RuntimeError(f"panel serve exited: {log_path.read_text()}")
                with (
                    contextlib.suppress(OSError),
                    socket.create_connection(("127.0.0.1", port), timeout=1),
                ):
                    break
                if time.monotonic() > deadline:
                    raise RuntimeError(f"panel serve did not answer: {log_path.read_text()}")
                time.sleep(0.2)
            yield f"http://127.0.0.1:{port}/study_app"
        finally:
            process.terminate()  # the study thread's LocalCluster goes with the server
            try:
                process.wait(timeout=30)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait()


def test_study_streams_stays_responsive_and_cancels(tmp_path):
    """Start a 500-run study; once rows stream in (plots drawn), the page still answers: choosing
    a second parameter shows its range at once while the study runs; Cancel ends the study
    with the finished rows plotted and Start enabled again. (500 runs: on an idle machine a
    200-run study finished before the checks and Cancel came.)"""
    from playwright.sync_api import sync_playwright

    with serve_study_app(tmp_path) as url, sync_playwright() as playwright:
        browser = launch_chromium(playwright)
        try:
            page = browser.new_page(viewport={"width": 1300, "height": 1000})
            page.goto(url, timeout=RUN_WAIT_MS)
            seeds = page.locator("input").last
            seeds.fill("100")
            seeds.press("Enter")
            page.get_by_role("button", name="Start study").click()
            page.get_by_text("runs done").wait_for(timeout=STUDY_WAIT_MS)
            # a running study's titles end in "(partial: 37 of 500 runs)": match their start, or
            # the wait would last until the study ends, when Cancel is rightly disabled
            page.wait_for_function(
                f"""() => {{
                  const shown = ({FIGURES_JS})().filter(f => f.points > 0).map(f => f.title);
                  return {list(PLOTS)!r}.every(t => shown.some(s => s.startsWith(t)));
                }}""",
                timeout=RUN_WAIT_MS,
            )

            page.locator("select").nth(1).select_option(
                label="Soil Young's modulus (MPa) — soil.youngs_modulus"
            )
            page.locator(".study-range-second").wait_for(state="visible", timeout=RUN_WAIT_MS)
            # answered while the study ran: Cancel below still finds it unfinished

            page.get_by_role("button", name="Cancel").click()
            page.get_by_text("Cancelled:").wait_for(timeout=STUDY_WAIT_MS)
            status = page.get_by_text("Cancelled:").inner_text()
            done = int(status.split()[1])
            assert 0 < done < 500, status
            assert page.get_by_role("button", name="Start study").is_enabled()
        finally:
            browser.close()
