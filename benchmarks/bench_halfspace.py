"""Time the half-space soil stage against the full-space 2.5D one (target ≤ 3×).

Run: ``python benchmarks/bench_halfspace.py [--repeat N]``. On the paper case's load (2.5D at
80 km/h, its vehicle–track run computed once), prints the first call (Numba compilation or
loading from its cache) and the best of N warm calls of

- the full-space 2.5D soil stage, ``model.soil.stresses.section_response`` (the kernel and its
  transfer functions, the displacement and deviator histories);
- the half-space soil stage, ``model.soil.halfspace_response.halfspace_response`` (the same plus
  the reflected field under the invert and the ground-surface response and levels);
- of that, the half-space transfer functions alone (``halfspace_transfer``);
- the public Green's function ``model.halfspace_point_response`` on 20 frequencies × 26
  distances along x × 3 depths.

Also the same stages at 200 km/h (faster than the soil's shear waves: every frequency
radiates, the costly case). Timings are wall-clock on a shared 2-core machine: read the best.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numba
import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import model  # noqa: E402
from model.soil.halfspace_response import halfspace_response, halfspace_transfer  # noqa: E402
from model.soil.stresses import section_response  # noqa: E402


def best_of(function, repeats: int) -> tuple[float, float]:
    """Seconds of the first call and the best of ``repeats`` further calls."""
    start = time.perf_counter()
    function()
    first = time.perf_counter() - start
    best = np.inf
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        best = min(best, time.perf_counter() - start)
    return first, best


def compare(speed_kmh: float, repeats: int) -> None:
    """Full-space and half-space soil stages on the paper case's load at ``speed_kmh``."""
    scenario = model.Scenario.paper()
    scenario.tunnel.model = "2.5d"
    scenario.train.speed_kmh = speed_kmh
    results = model.run(scenario)
    q, dt = results.load.line_load_N_per_m, float(results.load.t_s[1] - results.load.t_s[0])
    half = scenario.copy()
    half.tunnel.ground = "half_space"
    print(f"paper case, 2.5D, {speed_kmh:g} km/h, record {q.size} samples at {dt:g} s:")
    _, full_best = best_of(lambda: section_response(q, dt, scenario), repeats)
    print(f"  full-space soil stage (section_response): best of {repeats} {full_best:.3f} s")
    first, half_best = best_of(lambda: halfspace_response(q, dt, half), repeats)
    print(
        f"  half-space soil stage (halfspace_response): first {first:.3f} s, best of {repeats} "
        f"{half_best:.3f} s — {half_best / full_best:.2f} × the full-space stage (target ≤ 3)"
    )
    _, transfer_best = best_of(lambda: halfspace_transfer(q, dt, half), repeats)
    print(f"  of which the transfer functions (halfspace_transfer): {transfer_best:.3f} s")
    soil, _, ground = halfspace_response(q, dt, half)
    print(
        f"  peak invert displacement {1e3 * soil.peak_disp_m[0]:.2f} mm (full space "
        f"{1e3 * results.soil.peak_disp_m[0]:.2f} mm, free-surface effect "
        f"{ground.free_surface_effect:+.1%}); surface trough {1e3 * ground.peak_disp_m[0]:.2f} mm"
        f"; overall level {ground.overall_level_dB[0]:.1f} dB at 0 m, "
        f"{ground.overall_level_dB[-1]:.1f} dB at {ground.distance_m[-1]:g} m"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    repeats = parser.parse_args().repeat
    print(f"Numba threads: {numba.get_num_threads()}")
    compare(80.0, repeats)
    compare(200.0, repeats)
    freq = np.linspace(0.5, 80.0, 20)
    first, best = best_of(
        lambda: model.halfspace_point_response(
            freq, np.linspace(0.0, 50.0, 26), 0.0, [0.0, 5.0, 10.0], 15.0, model.Scenario().soil
        ),
        repeats,
    )
    print(
        f"halfspace_point_response 20 frequencies x 26 distances x 3 depths: first {first:.3f} s,"
        f" best of {repeats} {best:.3f} s"
    )


if __name__ == "__main__":
    main()
