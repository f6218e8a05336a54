"""Estimated against measured run time and memory (model.run_cost), for the record in docs.

Run: ``python benchmarks/bench_run_cost.py``. For a few scenarios of growing cost, prints the
estimate of :func:`model.run_cost.estimate_run` per stage and the measured wall time of a warm
run (best of ``REPEATS``, after one run that loads the Numba caches), and the ratio. The cost
model's coefficients come from the benchmark tables in docs/vehicle_track.md and
docs/tunnel_soil.md; this script checks them on the current machine (shared with other jobs:
read the ratios, not the seconds).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from model.params import Scenario  # noqa: E402
from model.pipeline import run  # noqa: E402
from model.run_cost import estimate_run, machine_load_factor  # noqa: E402

REPEATS = 3


def cases() -> dict[str, Scenario]:
    """Scenarios from a fraction of a second to several seconds."""
    out = {"single_bogie": Scenario.preset("single_bogie"), "paper": Scenario.paper()}
    finer = Scenario.preset("single_bogie")
    finer.numerics.dt = 2e-5
    out["single_bogie dt=2e-5"] = finer
    harmonics = Scenario.paper()
    harmonics.numerics.n_harmonics = 128
    out["paper 128 harmonics"] = harmonics
    depths = Scenario.paper()
    depths.numerics.n_depths = 201
    out["paper 201 depths"] = depths
    out["type_b"] = Scenario.type_b()
    return out


def main() -> None:
    print(f"machine load factor now: {machine_load_factor():.2f} (included in the estimates)")
    print(f"{'case':<22} {'stage':<14} {'estimate s':>10} {'measured s':>10} {'ratio':>6}")
    for name, scenario in cases().items():
        run(scenario)  # loads the Numba caches
        estimate = estimate_run(scenario)
        best: dict[str, float] = {}
        for _ in range(REPEATS):
            start = time.perf_counter()
            results = run(scenario)
            total = time.perf_counter() - start
            for stage in ("vehicle_track", "soil"):
                best[stage] = min(best.get(stage, total), results.stage_seconds[stage])
            best["total"] = min(best.get("total", total), total)
        estimated = {**estimate.seconds, "total": estimate.total_seconds}
        for stage in ("vehicle_track", "soil", "total"):
            ratio = best[stage] / estimated[stage]
            print(
                f"{name:<22} {stage:<14} {estimated[stage]:>10.3f} {best[stage]:>10.3f} "
                f"{ratio:>6.2f}"
            )
        memory = ", ".join(f"{k} {v / 1e6:.0f} MB" for k, v in estimate.memory_bytes.items())
        print(f"{'':<22} estimated peak memory: {memory}")


if __name__ == "__main__":
    main()
