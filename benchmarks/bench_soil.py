"""Time the tunnel–soil stage.

Run: ``python benchmarks/bench_soil.py``. Prints, for the first call (Numba compilation or
loading it from the cache) and the best of N warm calls:

- ``invert_receptance`` for 64 harmonics × 4096 frequencies (0.024–100 Hz) × 50 depths
  (0–35 m); target ≤ 1 s;
- the whole soil stage ``soil_response`` for the paper preset: a 6.66 s line load at 1e-4 s
  (the synthetic six-car train of tests/test_soil_response.py), default numerics (32 harmonics,
  100 Hz, padding 8, 71 depths); target ≤ 1 s.
- the tunnel–soil transfer functions of the soil stage (``model.soil.stresses.section_transfer``,
  receptance and stresses) on that load's record grid, 2D and 2.5D, with the kernel evaluated at
  every frequency (``kernel_samples_per_cycle = 0``) and sampled at the default.

Timings are wall-clock on a shared machine: read the best of N.

``python benchmarks/bench_soil.py --change [--baseline DIR] [--rounds R]``: the pipeline's soil
stage after a soil-only change (``soil.youngs_modulus``, a warm ``StageCache``: the vehicle–track
and load stages are served, the tunnel–soil transfer functions recomputed), 2D (``paper``) and
2.5D (``paper_2p5d``), best of 5 per round, each round in a fresh process (also the CPU time of
the run, all threads, which the other jobs on a shared machine disturb less); with ``--baseline``
the same measurement of another checkout (e.g. ``git archive a9630a4 | tar -x -C /tmp/base``)
alternates with this one's, and the ratios are printed. Also prints the load average.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numba
import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from model.params import Scenario, Soil, Tunnel  # noqa: E402
from model.soil.response import soil_response  # noqa: E402
from model.soil.section_2d import invert_receptance  # noqa: E402
from model.soil.stresses import section_transfer  # noqa: E402
from tests.test_soil_response import synthetic_train_load  # noqa: E402

REPEATS = 7


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


CHANGE_REPEATS = 5
CHANGE_PRESETS = ("paper", "paper_2p5d")
# Run in a fresh interpreter with the checkout to time first on sys.path: prints JSON
# {preset: best soil-stage seconds after a soil-modulus change}.
CHANGE_PROBE = """
import json, sys, time
from model.params import Scenario
from model.pipeline import StageCache, run
run(Scenario.preset("single_bogie"))
best = {}
for preset in PRESETS:
    for i in range(REPEATS + 1):
        scenario, cache = Scenario.preset(preset), StageCache()
        run(scenario, cache=cache)
        scenario.soil.youngs_modulus = 7e6 + i * 1e5
        cpu = time.process_time()
        seconds = run(scenario, cache=cache).stage_seconds["soil"]
        cpu = time.process_time() - cpu
        if i:  # the first change of a process pays for loading code
            best[preset] = min(best.get(preset, 1e9), seconds)
            best[preset + " cpu"] = min(best.get(preset + " cpu", 1e9), cpu)
print(json.dumps(best))
"""


def soil_change_seconds(root: Path) -> dict[str, float]:
    """Best soil-stage seconds after a soil-only change, per preset, timed in ``root``."""
    code = CHANGE_PROBE.replace("PRESETS", repr(CHANGE_PRESETS)).replace(
        "REPEATS", str(CHANGE_REPEATS)
    )
    env = {**os.environ, "PYTHONPATH": str(root)}
    out = subprocess.run(
        [sys.executable, "-c", code], cwd=root, env=env, capture_output=True, text=True, check=True
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


def change_main(baseline: Path | None, rounds: int) -> None:
    """Soil-only change, this checkout (and a baseline, alternating): figures and ratios."""
    trees = {"this": ROOT} | ({"baseline": baseline} if baseline else {})
    best: dict[str, dict[str, float]] = {name: {} for name in trees}
    for k in range(rounds):
        for name, root in trees.items():
            load = os.getloadavg()[0]
            seconds = soil_change_seconds(root)
            for preset, value in seconds.items():
                best[name][preset] = min(best[name].get(preset, 1e9), value)
            figures = ", ".join(f"{p} {v:.3f} s" for p, v in seconds.items())  # cpu: all threads
            print(f"round {k + 1} {name:8s} (load {load:.2f}): {figures}")
    for name, figures in best.items():
        two_d, moving = figures["paper"], figures["paper_2p5d"]
        print(
            f"{name:8s} best: 2D {two_d:.3f} s, 2.5D {moving:.3f} s, 2.5D / 2D {moving / two_d:.2f}"
        )
    if baseline:
        for preset in CHANGE_PRESETS:
            ratio = best["baseline"][preset] / best["this"][preset]
            cpu = best["baseline"][preset + " cpu"] / best["this"][preset + " cpu"]
            print(
                f"{preset}: baseline / this = {ratio:.2f}x faster (CPU time, whole run: {cpu:.2f}x)"
            )
    print(f"load average at the end: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--change", action="store_true", help="soil-only change of the pipeline")
    parser.add_argument("--baseline", type=Path, help="another checkout to compare with")
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    if args.change:
        change_main(args.baseline, args.rounds)
    else:
        kernel_main()


def kernel_main() -> None:
    print(f"Numba threads: {numba.get_num_threads()}")
    tunnel, soil = Tunnel(), Soil()
    freq = np.linspace(100.0 / 4096, 100.0, 4096)
    depth = np.linspace(0.0, 35.0, 50)
    first, best = best_of(lambda: invert_receptance(freq, depth, tunnel, soil, 64), REPEATS)
    print(
        f"invert_receptance 64 harmonics x 4096 frequencies x 50 depths: first {first:.3f} s, "
        f"best of {REPEATS} {best:.3f} s (target 1 s)"
    )

    scenario = Scenario.paper()
    dt, _, load, *_ = synthetic_train_load(scenario)
    result = None

    def soil_stage():
        nonlocal result
        result = soil_response(load, dt, scenario.tunnel, scenario.soil, scenario.numerics)

    first, best = best_of(soil_stage, REPEATS)
    print(
        f"soil_response, paper preset, {load.size} samples ({load.size * dt:.2f} s at "
        f"{dt:g} s): first {first:.3f} s, best of {REPEATS} {best:.3f} s (target 1 s)"
    )
    rows = [int(np.argmin(np.abs(result.depth_m - d))) for d in (0.0, 11.0, 35.0)]
    peaks = ", ".join(
        f"{result.depth_m[r]:g} m: {1e3 * result.peak_disp_m[r]:.2f} mm" for r in rows
    )
    print(f"  synthetic load peak {load.max() / 1e3:.1f} kN/m; peak downward displacement {peaks}")

    default = scenario.numerics.kernel_samples_per_cycle
    for model in ("2d", "2.5d"):
        for samples in (0, default):
            case = scenario.copy()
            case.tunnel.model = model
            case.numerics.kernel_samples_per_cycle = samples
            first, best = best_of(lambda case=case: section_transfer(load, dt, case), REPEATS)
            print(
                f"section_transfer {model}, kernel_samples_per_cycle = {samples}: first "
                f"{first:.3f} s, best of {REPEATS} {best:.3f} s"
            )


if __name__ == "__main__":
    main()
