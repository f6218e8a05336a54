"""Time the irregularity synthesis on the vehicle–track grid: 316 m at 5 mm, 2000 components.

Run: ``python benchmarks/bench_irregularity.py``. Prints the first call (includes Numba
compilation, or loading it from the cache) and the best of N warm calls, for the uniform-grid
(phasor rotation) path and the arbitrary-points (direct cosine) path.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from model.track.irregularity import synthesize_profile  # noqa: E402

GRID_LENGTH_M = 316.0
GRID_STEP_M = 0.005
N_COMPONENTS = 2000
REPEATS = 7


def time_calls(x_m: np.ndarray, repeats: int) -> tuple[float, float]:
    """Seconds of the first call and best of ``repeats`` further calls."""
    start = time.perf_counter()
    synthesize_profile(x_m, 6, 2024, (1.0, 50.0), N_COMPONENTS)
    first = time.perf_counter() - start
    best = np.inf
    for _ in range(repeats):
        start = time.perf_counter()
        synthesize_profile(x_m, 6, 2024, (1.0, 50.0), N_COMPONENTS)
        best = min(best, time.perf_counter() - start)
    return first, best


def main() -> None:
    uniform = np.arange(0.0, GRID_LENGTH_M + 0.5 * GRID_STEP_M, GRID_STEP_M)
    # Same points, made non-uniform by a 1 µm shift of one point: forces the direct path.
    scattered = uniform.copy()
    scattered[1] += 1e-6
    print(
        f"grid: {uniform.size} points ({GRID_LENGTH_M:g} m at {GRID_STEP_M * 1e3:g} mm), "
        f"{N_COMPONENTS} components"
    )
    first, best = time_calls(uniform, REPEATS)
    print(
        f"uniform grid (phasor rotation): first call {first:.3f} s, "
        f"best of {REPEATS} warm {best * 1e3:.1f} ms"
    )
    first, best = time_calls(scattered, 2)
    print(
        f"arbitrary points (direct cosines): first call {first:.3f} s, best of 2 warm "
        f"{best * 1e3:.0f} ms"
    )


if __name__ == "__main__":
    main()
