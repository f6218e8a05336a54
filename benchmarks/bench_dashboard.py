"""Dashboard response times and server memory, measured in a real browser (headless Debian
Chromium) against one ``panel serve dashboard/app.py --warm`` server.

Prints, in one run (best of N where repeated):

* a speed typed on the ``paper`` page (six-car train) until every plot shows new data and is
  painted, next to the pipeline's own time for that change (sum of its stage times, as the
  page reports them) and their ratio (target ≤ 1.5);
* a soil Young's modulus typed on the ``paper`` page until the soil plots are repainted
  (target ≤ 1.0 s);
* one ``paper`` page opened alone, then ten opened at once, until every plot of every page is
  drawn (target: ten ≤ 3 × one);
* the server's resident memory before and after 20 more sessions have opened and closed
  (target: back within 50 MB); measured once the stage cache holds its results, so that
  only what sessions keep is counted.

Each typed change uses a value not computed before, so no stage cache can serve it. Other jobs
may share the machine; the figures are wall times. Usage::

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
    PAINTED_JS,
    STAGE_OF_PLOT,
    launch_chromium,
    render_counts,
    serve_app_process,
    signatures,
    type_value,
    wait_for_new_data,
    wait_for_plots,
    wait_for_renders,
)

from model.pipeline import STAGES  # noqa: E402

VIEWPORT = {"width": 1280, "height": 720}
# Sessions are dropped 1 s after their page closes (Bokeh's default waits 15 s, checked every
# 17 s), so that the memory figure does not wait on the clean-up timer.
SESSION_CLEANUP_ARGS = ("--check-unused-sessions", "1000", "--unused-session-lifetime", "1000")
SESSION_CLEANUP_WAIT_S = 8.0


def warm_numba_caches() -> None:
    """Compile (or load) every kernel once in a separate process, as a previous run would."""
    code = (
        "from model.params import Scenario; from model.pipeline import run; "
        "s = Scenario.preset('single_bogie'); s.numerics.n_depths = 11; run(s, cache=None)"
    )
    subprocess.run([sys.executable, "-c", code], cwd=ROOT, check=True)


def note(text: str) -> None:
    """Progress of the benchmark on stderr (a stuck wait shows where it is)."""
    print(f"[{time.strftime('%H:%M:%S')}] {text}", file=sys.stderr, flush=True)


def pipeline_seconds(page) -> float:
    """The last run's own time: the sum of its stage times, from the page's status line."""
    return sum(
        float(item.get_attribute("data-seconds")) for item in page.locator(".stage-status").all()
    )


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


def open_pages(browser, url: str, n: int) -> tuple[float, list]:
    """Open ``n`` pages at once; seconds until every plot of every page is drawn."""
    pages = [browser.new_page(viewport=VIEWPORT) for _ in range(n)]
    start = time.perf_counter()
    for page in pages:
        page.goto(f"{url}?preset=paper", wait_until="commit")
    for page in pages:
        wait_for_plots(page, timeout_ms=600_000)
        page.evaluate(PAINTED_JS)
    return time.perf_counter() - start, pages


def resident_mb(pid: int) -> float:
    """Resident set size of a process (MB), from /proc."""
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024.0
    raise RuntimeError("no VmRSS")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=3, help="samples per typed change")
    args = parser.parse_args(argv)
    from playwright.sync_api import sync_playwright

    warm_numba_caches()
    rows = []
    with (
        sync_playwright() as playwright,
        tempfile.TemporaryDirectory() as tmp,
        serve_app_process(Path(tmp) / "panel.log", SESSION_CLEANUP_ARGS) as (url, server),
    ):
        browser = launch_chromium(playwright)
        page = browser.new_page(viewport=VIEWPORT)
        page.goto(f"{url}?preset=paper")
        wait_for_plots(page, timeout_ms=600_000)
        note("first page drawn")
        speed = []
        for i in range(args.repeat):
            seconds = timed_change(page, "train.speed_kmh", f"{70 + 2 * i}", STAGES)
            speed.append((seconds, pipeline_seconds(page)))
            note(f"speed change {i + 1}: {seconds:.2f} s")
        soil = []
        for i in range(args.repeat):
            seconds = timed_change(page, "soil.youngs_modulus", f"{7 + i}", ("soil",))
            soil.append((seconds, pipeline_seconds(page)))
            note(f"soil change {i + 1}: {seconds:.2f} s")
        page.close()

        one, pages = open_pages(browser, url, 1)
        note(f"one page: {one:.2f} s")
        for p in pages:
            p.close()
        ten, pages = open_pages(browser, url, 10)
        note(f"ten pages: {ten:.2f} s")
        for p in pages:
            p.close()
        # the stage cache is full by now (it holds the paper page's results): what remains to
        # be seen is whether closed sessions give their memory back
        time.sleep(SESSION_CLEANUP_WAIT_S)
        memory_start = resident_mb(server.pid)
        for _ in range(2):  # 20 sessions in all, ten at a time
            _, pages = open_pages(browser, url, 10)
            for p in pages:
                p.close()
        time.sleep(SESSION_CLEANUP_WAIT_S)
        memory_end = resident_mb(server.pid)
        browser.close()

    best_speed = min(speed)
    ratios = [b / p for b, p in speed]
    rows.append(
        (
            "typed speed → new numbers (paper), browser",
            f"{best_speed[0]:.2f} s",
            ", ".join(f"{b:.2f}" for b, _ in speed),
            "",
        )
    )
    rows.append(
        (
            "  pipeline's own time for that change",
            f"{best_speed[1]:.2f} s",
            ", ".join(f"{p:.2f}" for _, p in speed),
            "",
        )
    )
    rows.append(
        (
            "  ratio browser / pipeline",
            f"{min(ratios):.2f}",
            ", ".join(f"{r:.2f}" for r in ratios),
            "≤ 1.5",
        )
    )
    best_soil = min(soil)
    rows.append(
        (
            "typed soil E → soil plots (paper), browser",
            f"{best_soil[0]:.2f} s",
            ", ".join(f"{b:.2f}" for b, _ in soil),
            "≤ 1.0 s",
        )
    )
    rows.append(
        (
            "  pipeline's own time for that change",
            f"{best_soil[1]:.2f} s",
            ", ".join(f"{p:.2f}" for _, p in soil),
            "",
        )
    )
    rows.append(("one page opened alone (paper)", f"{one:.2f} s", "", ""))
    rows.append(("ten pages opened at once, all drawn", f"{ten:.2f} s", "", "≤ 3 × one"))
    rows.append(("  ratio ten / one", f"{ten / one:.2f}", "", "≤ 3"))
    rows.append(
        (
            "server memory: start → after 20 sessions closed",
            f"{memory_end - memory_start:+.0f} MB",
            f"{memory_start:.0f} → {memory_end:.0f} MB",
            "≤ +50 MB",
        )
    )
    print(f"{'measurement':<50} {'best':>8}  {'all samples':<22} target")
    for name, best, samples, target in rows:
        print(f"{name:<50} {best:>8}  {samples:<22} {target}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
