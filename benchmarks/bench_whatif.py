"""What-if sessions: the cost of pinning and of drawing every plot with 8 pinned runs.

Panel-free part (always run), on one run of the ``paper`` preset (six-car train, ~70 000 time
samples per history):

* pin: :meth:`WhatIfSession.pin` of a finished run (no recomputation: it stores the Results
  and takes their summary once);
* plot building: every function of ``dashboard.plots.PLOTS`` drawing the current run alone and
  with 8 pinned runs overlaid, as HoloViews elements, and rendered to Bokeh models (what the
  server builds when a plot is replaced, e.g. after pinning); best of ``--repeat``;
* in-place update: what the served dashboard does on a slider change, every plot of its
  ``PlotPanes`` (in a Bokeh document, as served) given new Results (the current run alternates
  between two runs that differ in the soil), their Bokeh sources and ranges set directly
  (``PlotPanes._update``); best of ``--repeat``.

The 8 pinned runs are the same Results object pinned under 8 names: drawing cost depends on
the array sizes, not the values. A pinned run's layers are built once and reused (see
``plots.pinned_runs_layer``), so the figures are for a redraw after the first.

Browser part (``--browser``): in headless Debian Chromium, the time from entering a new soil
Young's modulus (paper preset) or speed (single bogie) until the plots show the new data, first
with no pinned run, then in the same page and server with 8 pinned runs shown (the issue's
target: with 8 pinned runs no more than 20 % slower). A change is timed in the page, from the
Enter key to the first frame painted with the new data, once the page is idle
(``bench_dashboard.timed_change``). Each series starts with one untimed change, so that both
are timed in steady state (the first change after the figures were built costs the browser
several seconds more, with or without pinned runs).
Usage::

    python benchmarks/bench_whatif.py [--repeat 5] [--browser]
"""

from __future__ import annotations

import argparse
import itertools
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT), str(ROOT / "tests")]

import holoviews as hv  # noqa: E402
from bokeh.document import Document  # noqa: E402

from dashboard import plots  # noqa: E402
from dashboard.plot_panes import PlotPanes  # noqa: E402
from dashboard.whatif import MAX_PINNED, WhatIfSession  # noqa: E402
from model.params import Scenario  # noqa: E402
from model.pipeline import run  # noqa: E402


def best_of(repeat: int, action) -> float:
    """Smallest wall time of ``repeat`` calls of ``action()`` (s)."""
    samples = []
    for _ in range(repeat):
        start = time.perf_counter()
        action()
        samples.append(time.perf_counter() - start)
    return min(samples)


def panel_free(repeat: int) -> None:
    """Pin cost and plot-building time with 0 and 8 pinned runs."""
    start = time.perf_counter()
    results = run(Scenario.paper(), cache=None)
    print(f"paper run computed in {time.perf_counter() - start:.1f} s (not part of the figures)")

    def pin_once():
        WhatIfSession().pin(results, "pinned")

    print(
        f"{'pin one run (paper, no recomputation)':<58} {best_of(repeat, pin_once) * 1e3:8.2f} ms"
    )
    session = WhatIfSession()
    for k in range(MAX_PINNED):
        session.pin(results, f"run {k + 1}")
    overlays = session.overlays()

    def draw(pinned):
        return lambda: [spec.draw(results, overlays=pinned) for spec in plots.PLOTS]

    def render(pinned):
        return lambda: [hv.render(element) for element in draw(pinned)()]

    softer = Scenario.paper()
    softer.soil.youngs_modulus = 5e6
    other = run(softer, cache=None)

    def update(pinned):
        """A callable that sends the next current run to every plot, as a slider change does
        (the dashboard's own plot panes, drawn in a document as a served page has them)."""
        panes = PlotPanes(plots.PLOTS, lambda spec: {"overlays": pinned})
        panes.show(results, {spec.stage for spec in plots.PLOTS})
        document = Document()
        for pane in panes.panes.values():
            pane.get_root(document)  # the pane's plot, updated in place from now on
        currents = itertools.cycle((other, results))

        def send():
            data = next(currents)
            for spec in plots.PLOTS:
                panes.send(spec.key, data)

        send.document = document  # the plots live as long as the callable
        return send

    print(f"{'every plot (5), best of ' + str(repeat):<58} {'0 pinned':>11} {'8 pinned':>11} ratio")
    for name, build in (
        ("HoloViews elements", draw),
        ("elements rendered to Bokeh", render),
        ("in-place update of the plot panes (slider change)", update),
    ):
        alone, pinned = best_of(repeat, build(())), best_of(repeat, build(overlays))
        print(f"{name:<58} {alone * 1e3:8.1f} ms {pinned * 1e3:8.1f} ms {pinned / alone:5.2f}")


def browser(repeat: int) -> None:
    """Slider-change response in the browser with the 8 pinned runs hidden and shown."""
    from bench_dashboard import timed_change, wait_until_idle, warm_numba_caches
    from playwright.sync_api import sync_playwright
    from test_browser import launch_chromium, open_dashboard, serve_app

    def timed_in_page(page, path, value, stages):
        """Seconds from the Enter key to the new data painted (see bench_dashboard)."""
        wait_until_idle(page)
        return timed_change(page, path, value, stages)[0]

    def pin_all(page):
        for k in range(MAX_PINNED):
            page.locator(".whatif-name input").fill(f"run {k + 1}")
            page.locator(".whatif-name input").press("Tab")
            page.locator(".whatif-pin button").click()
            page.locator(".whatif-run").nth(k).wait_for(timeout=60_000)

    cases = [
        ("preset=paper", "soil.youngs_modulus", lambda i: f"{7 + 0.1 * i:g}", ("soil",)),  # MPa
        (
            "preset=single_bogie",
            "train.speed_kmh",
            lambda i: f"{70 + 0.5 * i:g}",
            ("vehicle_track", "load", "soil"),
        ),
    ]
    warm_numba_caches()
    with sync_playwright() as playwright, tempfile.TemporaryDirectory() as tmp:
        chromium = launch_chromium(playwright)
        with serve_app(Path(tmp) / "panel.log") as url:
            for query, path, value, stages in cases:
                page = chromium.new_page(viewport={"width": 1400, "height": 1400})
                open_dashboard(page, url, query)
                # every change is timed in steady state: one untimed change first, after
                # opening the page and after pinning (which rebuilds every figure)
                samples = {0: [], MAX_PINNED: []}
                values = iter(range(4 * repeat + 2))
                for n in (0, MAX_PINNED):
                    if n:
                        pin_all(page)
                    timed_in_page(page, path, value(next(values)), stages)
                    for _ in range(repeat):
                        samples[n].append(timed_in_page(page, path, value(next(values)), stages))
                page.close()
                alone, pinned = samples[0], samples[MAX_PINNED]
                print(
                    f"{path} change ({query}): 0 pinned best {min(alone):.2f} s median "
                    f"{statistics.median(alone):.2f} s; 8 pinned best {min(pinned):.2f} s median "
                    f"{statistics.median(pinned):.2f} s; ratio of medians "
                    f"{statistics.median(pinned) / statistics.median(alone):.2f} (target ≤ 1.2)"
                )
                print("  samples 0 pinned:", ", ".join(f"{v:.2f}" for v in alone))
                print("  samples 8 pinned:", ", ".join(f"{v:.2f}" for v in pinned))
        chromium.close()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=5, help="samples per figure")
    parser.add_argument("--browser", action="store_true", help="also time the served dashboard")
    args = parser.parse_args(argv)
    panel_free(args.repeat)
    if args.browser:
        browser(args.repeat)
    return 0


if __name__ == "__main__":
    sys.exit(main())
