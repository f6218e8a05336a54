"""Dashboard response times measured in a real browser (headless Debian Chromium).

Prints best-of-N wall times for:

* first page load of the ``paper`` preset (six-car train) on a freshly started server whose
  Numba caches are warm: navigation until every plot is drawn with data;
* a soil-parameter change (soil Young's modulus typed and entered) until the soil plots are
  redrawn, on the ``paper`` page;
* a speed change until every plot is redrawn, with the single bogie and with the full train.

Each change uses a value not computed before, so no stage cache can serve it. Usage::

    python benchmarks/bench_dashboard.py [--repeat 3]
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT), str(ROOT / "tests")]

from test_browser import (  # noqa: E402  (shared browser helpers)
    STAGE_OF_PLOT,
    launch_chromium,
    render_counts,
    serve_app,
    signatures,
    type_value,
    wait_for_new_data,
    wait_for_plots,
    wait_for_renders,
)

from model.pipeline import STAGES  # noqa: E402

TARGETS_S = {
    "first page load (paper, warm Numba caches)": 10.0,
    "soil change → soil plots updated (full train)": 1.5,
    "speed change → all plots updated (single bogie)": 2.0,
    "speed change → all plots updated (full train)": 6.0,
}

# Two animation frames: the browser has painted what the last model change drew.
PAINTED_JS = "() => new Promise(r => requestAnimationFrame(() => requestAnimationFrame(r)))"


def warm_numba_caches() -> None:
    """Compile (or load) every kernel once in a separate process, as a previous run would."""
    code = (
        "from model.params import Scenario; from model.pipeline import run; "
        "s = Scenario.preset('single_bogie'); s.numerics.n_depths = 11; run(s, cache=None)"
    )
    subprocess.run([sys.executable, "-c", code], cwd=ROOT, check=True)


def first_load(browser, url: str) -> float:
    """Seconds from navigation to every plot drawn with data."""
    page = browser.new_page(viewport={"width": 1400, "height": 1000})
    start = time.perf_counter()
    page.goto(f"{url}?preset=paper")
    wait_for_plots(page)
    page.evaluate(PAINTED_JS)
    elapsed = time.perf_counter() - start
    page.close()
    return elapsed


def timed_change(page, path: str, value: str, stages: tuple[str, ...]) -> float:
    """Seconds from entering ``value`` for ``path`` until the plots of ``stages`` show new data
    and the page has been painted."""
    counts = render_counts(page)
    before = signatures(page)
    titles = [title for title, stage in STAGE_OF_PLOT.items() if stage in stages]
    start = time.perf_counter()
    type_value(page, path, value)
    for stage in stages:
        wait_for_renders(page, stage, counts[stage] + 1)
    wait_for_new_data(page, before, titles)
    page.evaluate(PAINTED_JS)
    return time.perf_counter() - start


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=3, help="samples per figure (best kept)")
    args = parser.parse_args(argv)
    from playwright.sync_api import sync_playwright

    warm_numba_caches()
    samples: dict[str, list[float]] = {name: [] for name in TARGETS_S}
    names = list(TARGETS_S)
    with sync_playwright() as playwright, tempfile.TemporaryDirectory() as tmp:
        browser = launch_chromium(playwright)
        for i in range(args.repeat):  # a fresh server each time: the stage cache starts empty
            with serve_app(Path(tmp) / f"panel-{i}.log") as url:
                samples[names[0]].append(first_load(browser, url))
        with serve_app(Path(tmp) / "panel.log") as url:
            page = browser.new_page(viewport={"width": 1400, "height": 1000})
            page.goto(f"{url}?preset=paper")
            wait_for_plots(page)
            for i in range(args.repeat):
                samples[names[1]].append(
                    timed_change(page, "soil.youngs_modulus", f"{7e6 + 1e6 * i:g}", ("soil",))
                )
            for i in range(args.repeat):
                samples[names[3]].append(
                    timed_change(page, "train.speed_kmh", f"{70 + 2 * i}", STAGES)
                )
            page.goto(f"{url}?preset=single_bogie")
            wait_for_plots(page)
            for i in range(args.repeat):
                samples[names[2]].append(
                    timed_change(page, "train.speed_kmh", f"{70 + 2 * i}", STAGES)
                )
        browser.close()

    print(f"{'measurement':<50} {'best':>7} {'all samples (s)':<24} target")
    for name, values in samples.items():
        listed = ", ".join(f"{v:.2f}" for v in values)
        print(f"{name:<50} {min(values):6.2f}s {listed:<24} ≤ {TARGETS_S[name]:g} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
