"""Time the consolidation solver (model.longterm.consolidation) at the project's sizes.

Run: ``python benchmarks/bench_consolidation.py``. Best-of-REPEATS wall times with a warm Numba
cache on a 35 m two-layer traffic column (the boundary at 8 m given twice; power-law generation
evaluated inside the solve, as the long-term stage does; illustrative constants) with 61
outputs log-spaced from one day to 100 years; by node count, and by time steps per decade.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from model.longterm.consolidation import solve_consolidation  # noqa: E402
from model.longterm.cycles import load_cycles  # noqa: E402
from model.longterm.pore_pressure import (  # noqa: E402
    generated_pore_pressure_power,
    recompression_compressibility,
)
from model.params.site import SECONDS_PER_YEAR  # noqa: E402

REPEATS = 20
NODE_COUNTS = (51, 151, 351, 801)
STEP_DENSITIES = (5, 10, 20, 40, 80)
YEARS = np.geomspace(1.0 / 365.0, 100.0, 61)


def train_column(n_nodes: int):
    """Depths (boundary at 8 m twice), m_v, k and the traffic generation u_g(t)."""
    grid = np.linspace(0.0, 35.0, n_nodes)
    depth = np.sort(np.concatenate([grid[grid != 8.0], [8.0, 8.0]]))
    lower = np.arange(depth.size) > np.searchsorted(depth, 8.0)
    stress = 1.2e5 + 8e3 * depth
    ratio = 0.3 * np.exp(-depth / 5.0)
    m_v = recompression_compressibility(np.where(lower, 0.02, 0.05), 1.2, stress)
    k = np.where(lower, 5e-9, 1e-9)
    a_u = np.where(lower, 0.025, 0.05)

    def generation(t_s):
        cycles = load_cycles(t_s / SECONDS_PER_YEAR, 200.0, np.full(depth.size, 6.0))
        return generated_pore_pressure_power(stress, ratio, cycles, a_u, 0.15, 1.5).pressure_Pa

    return depth, m_v, k, generation


def best_time(action) -> float:
    """Best wall time (s) of ``action()`` over REPEATS calls."""
    best = float("inf")
    for _ in range(REPEATS):
        start = time.perf_counter()
        action()
        best = min(best, time.perf_counter() - start)
    return best


def main() -> None:
    times = YEARS * SECONDS_PER_YEAR
    print("nodes  steps  solve (ms)")
    for n_nodes in NODE_COUNTS:
        column = train_column(n_nodes)
        solution = solve_consolidation(*column, times)  # compiles once
        seconds = best_time(lambda column=column: solve_consolidation(*column, times))
        print(f"{column[0].size:5d}  {solution.n_steps:5d}  {seconds * 1e3:10.2f}")
    depth, m_v, k, generation = train_column(151)
    print("steps/decade  steps  solve (ms), 153 rows")
    for density in STEP_DENSITIES:

        def solve(density=density):
            return solve_consolidation(depth, m_v, k, generation, times, steps_per_decade=density)

        steps = solve().n_steps
        print(f"{density:12d}  {steps:5d}  {best_time(solve) * 1e3:.2f}")


if __name__ == "__main__":
    main()
