"""Time the whole pipeline as a dashboard user meets it: soil-only change, speed change.

Run: ``python benchmarks/bench_pipeline.py``. Prints best-of-N wall times (warm Numba caches)
and the stage times of the best run; the soil stage includes the stresses under the invert
(displacements and stresses come from one tunnel–soil kernel pass).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from model.params import Scenario  # noqa: E402
from model.pipeline import StageCache, run  # noqa: E402

REPEATS = 5


def best_of(make_change, preset: str) -> tuple[float, dict[str, float]]:
    """Best wall time of ``run`` after ``make_change`` on a warm cache, with stage times."""
    best, stages = float("inf"), {}
    for i in range(REPEATS):
        scenario, cache = Scenario.preset(preset), StageCache()
        run(scenario, cache=cache)
        make_change(scenario, i)
        start = time.perf_counter()
        result = run(scenario, cache=cache)
        elapsed = time.perf_counter() - start
        if elapsed < best:
            best, stages = elapsed, result.stage_seconds
    return best, stages


def main() -> None:
    run(Scenario.preset("single_bogie"), cache=None)  # load the Numba caches
    cases = {
        "soil modulus change (soil+stress stage)": lambda s, i: setattr(
            s.soil, "youngs_modulus", 7e6 + i * 1e5
        ),
        "speed change (every stage)": lambda s, i: setattr(s.train, "speed_kmh", 70.0 + i),
    }
    for preset in ("single_bogie", "paper", "paper_2p5d"):
        for label, change in cases.items():
            seconds, stages = best_of(change, preset)
            detail = ", ".join(f"{k} {v:.3f} s" for k, v in stages.items())
            print(f"{preset:12s} {label:40s} {seconds:6.3f} s  ({detail})")


if __name__ == "__main__":
    main()
