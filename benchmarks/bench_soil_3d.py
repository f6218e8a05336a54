"""Time the 2.5D tunnel–soil model against the 2D one.

Run: ``python benchmarks/bench_soil_3d.py``. Prints, for the first call (Numba compilation or
loading it from the cache) and the best of N warm calls:

- the soil stage ``soil_response`` of the paper case with the 2D model and with the 2.5D model
  (kernel at ξ = ω/v), on the same line load (the vehicle–track run of the paper preset), in
  the same process; target: 2.5D ≤ 2 × 2D;
- ``point_load_response`` for 64 frequencies (0.5–32 Hz, the load's band, paper Fig. 7) ×
  64 positions (−50…50 m) × 20 depths (0–35 m), default numerics; target ≤ 10 s.

Timings are wall-clock on a shared machine: read the best of N. The 2D kernel runs its
frequencies in parallel over Numba's threads; the 2.5D kernels are serial (nogil).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numba
import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from benchmarks.bench_soil import best_of  # noqa: E402
from model.params import Scenario  # noqa: E402
from model.pipeline import run  # noqa: E402
from model.soil.point_load import point_load_response  # noqa: E402
from model.soil.response import soil_response  # noqa: E402

REPEATS = 3


def main() -> None:
    print(f"Numba threads: {numba.get_num_threads()}")
    scenario = Scenario.paper()
    result = run(scenario, cache=None)
    load, t_s = result.load.line_load_N_per_m, result.load.t_s
    dt = float(t_s[1] - t_s[0])
    best = {}
    for model in ("2d", "2.5d"):
        scenario.tunnel.model = model
        response = None

        def soil_stage():
            nonlocal response
            response = soil_response(
                load, dt, scenario.tunnel, scenario.soil, scenario.numerics, scenario.train.speed
            )

        first, best[model] = best_of(soil_stage, REPEATS)
        rows = [int(np.argmin(np.abs(response.depth_m - d))) for d in (0.0, 11.0, 35.0)]
        peaks = ", ".join(
            f"{response.depth_m[r]:g} m: {1e3 * response.peak_disp_m[r]:.2f} mm" for r in rows
        )
        print(
            f"soil_response {model:>4}, paper case, {load.size} samples, "
            f"{response.interface_spectrum_f_hz.size} frequencies x {response.depth_m.size} "
            f"depths: first {first:.3f} s, best of {REPEATS} {best[model]:.3f} s; peaks {peaks}"
        )
    print(f"  2.5D / 2D soil stage: {best['2.5d'] / best['2d']:.2f} (target <= 2)")

    freq = np.linspace(0.5, 32.0, 64)
    x = np.linspace(-50.0, 50.0, 64)
    depth = np.linspace(0.0, 35.0, 20)
    first, best_point = best_of(
        lambda: point_load_response(freq, x, depth, scenario.tunnel, scenario.soil, 32), REPEATS
    )
    print(
        f"point_load_response 64 frequencies x 64 x x 20 depths: first {first:.2f} s, "
        f"best of {REPEATS} {best_point:.2f} s (target 10 s)"
    )


if __name__ == "__main__":
    main()
