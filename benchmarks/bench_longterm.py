"""Time the long-term stage and the soil stage's stresses on the paper case (docs/model.md §10,
§15).

Run: ``python benchmarks/bench_longterm.py``. Prints best-of-N wall times with warm Numba
caches: the long-term stage alone (target ≤ 50 ms, so that a 1000-draw Monte-Carlo band of the
long-term stage takes under a minute), without pore pressure, with the default pore pressure and
its consolidation, and on the four-layer example borehole; a pipeline re-run after a change of
the long-term inputs only (every other stage served from the cache), and the soil stage with and
without the stresses (the pipeline's soil stage, ``section_response``, computes both from one
kernel pass; ``soil_response`` the displacements alone).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from model.longterm.settlement import long_term_settlement  # noqa: E402
from model.params import DATA_DIR, Scenario  # noqa: E402
from model.params.borehole import load_borehole_csv  # noqa: E402
from model.pipeline import STAGES, StageCache, run  # noqa: E402
from model.soil.response import soil_response  # noqa: E402
from model.soil.stresses import section_response  # noqa: E402

REPEATS = 5


def best_time(action) -> float:
    """Best wall time (s) of ``action(i)`` over REPEATS calls."""
    best = float("inf")
    for i in range(REPEATS):
        start = time.perf_counter()
        action(i)
        best = min(best, time.perf_counter() - start)
    return best


def main() -> None:
    scenario, cache = Scenario.paper(), StageCache()
    results = run(scenario, cache=cache)  # warm caches, and the stages to reuse
    load = results.load
    dt = float(load.t_s[1] - load.t_s[0])

    def longterm_stage(i):
        scenario.longterm.trains_per_day = 200.0 + i
        long_term_settlement(results.stress, scenario)

    def longterm_rainflow(i):
        scenario.longterm.cycles_per_train = "rainflow"
        longterm_stage(i)
        scenario.longterm.cycles_per_train = "bogies"

    def longterm_plastic_only(i):
        scenario.longterm.pore_pressure_law = "none"
        longterm_stage(i)
        scenario.longterm.pore_pressure_law = "power"

    layered = scenario.copy()
    layered.site.layers = load_borehole_csv(DATA_DIR / "borehole_example.csv")

    def longterm_layered(i):
        layered.longterm.trains_per_day = 200.0 + i
        long_term_settlement(results.stress, layered)

    def rerun(i):
        scenario.longterm.years = 10.0 + i
        assert run(scenario, cache=cache).cached_stages == STAGES[:-1]

    figures = {
        "long-term stage alone (bogies)": best_time(longterm_stage),
        "long-term stage alone (rainflow)": best_time(longterm_rainflow),
        "long-term stage alone, no pore pressure": best_time(longterm_plastic_only),
        "long-term stage alone, example borehole": best_time(longterm_layered),
        "pipeline re-run, long-term inputs changed": best_time(rerun),
        "soil stage, displacements only": best_time(
            lambda i: soil_response(
                load.line_load_N_per_m, dt, scenario.tunnel, scenario.soil, scenario.numerics
            )
        ),
        "soil stage, displacements + stresses": best_time(
            lambda i: section_response(load.line_load_N_per_m, dt, scenario)
        ),
    }
    for label, seconds in figures.items():
        print(f"paper  {label:45s} {seconds:7.4f} s")


if __name__ == "__main__":
    main()
