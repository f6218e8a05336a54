"""Time the vehicle–track simulation (model/track/vehicle_track.py) and print the figures.

Run: ``python benchmarks/bench_vehicle_track.py [--quick | --ratio]``. Prints

1. cold start: a fresh process with an empty Numba cache (compilation) and one with the cache
   filled (loading), for the single-bogie passage;
2. warm wall time, best of N, of the single bogie and of the six-car train (paper preset,
   80 km/h, Δt = 1e-4 s, FRA class 6), with steps/s and the cost per step;
3. how the cost per step grows with the number of cars (rail length and wheel count grow
   together) and with the rail length alone (six cars, longer end margins), with a
   least-squares fit cost ≈ c0 + c1·N_m + c2·N_m·n_wheels;
4. the block–rail coupling alone, three ways, at the paper's size (527 blocks, 528 modes):
   dense mode-shape matrices, DST-I through rocket-fft, and the diagonal block-modal form the
   model uses.

Other processes share the two cores, so every figure is a best of several runs.

``--ratio`` prints only the six-car passage against the plain-NumPy baseline on the same job
(``tests/vehicle_track_numpy.py``, the same equations as whole-array NumPy expressions; run
once, the whole passage, its histories checked against the kernels'): the time stepping of both,
``simulate()`` and the ratio simulate() ÷ baseline (issue 27: ≤ 0.0125).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numba
import numpy as np
import scipy.fft

try:  # rocket-fft teaches Numba scipy.fft; optional, the DST-I case is skipped without it
    import rocket_fft  # noqa: F401
except ImportError:
    rocket_fft = None

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT), str(ROOT / "tests")]

from vehicle_track_numpy import integrate_numpy  # noqa: E402

from model.params import Scenario  # noqa: E402
from model.track import assembly  # noqa: E402
from model.track import vehicle_track as vt  # noqa: E402

COLD_SCRIPT = """
import time
t0 = time.perf_counter()
from model.params import Scenario
from model.track.vehicle_track import simulate
s = Scenario.preset("single_bogie")
t1 = time.perf_counter()
simulate(s)
t2 = time.perf_counter()
simulate(s)
t3 = time.perf_counter()
print(t1 - t0, t2 - t1, t3 - t2)
"""


def best_of(function, repeats: int) -> float:
    """Best wall time (s) of ``repeats`` calls."""
    best = np.inf
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        best = min(best, time.perf_counter() - start)
    return best


def cold_start() -> None:
    """First simulate() in a fresh process: empty Numba cache, then filled cache."""
    with tempfile.TemporaryDirectory() as cache_dir:
        env = {**os.environ, "NUMBA_CACHE_DIR": cache_dir, "PYTHONPATH": str(ROOT)}
        for label in ("empty Numba cache (compile)", "filled Numba cache (load)"):
            out = subprocess.run(
                [sys.executable, "-c", COLD_SCRIPT],
                env=env,
                cwd=ROOT,
                capture_output=True,
                text=True,
                check=True,
            ).stdout.split()
            imports, first, warm = (float(v) for v in out)
            print(
                f"  {label}: imports {imports:.2f} s, first single-bogie run {first:.2f} s "
                f"(warm run {warm * 1e3:.0f} ms, so ~{first - warm:.2f} s of JIT)"
            )


def integration_cost(scenario: Scenario, repeats: int) -> tuple[float, int]:
    """Best seconds of the time-stepping alone, and the number of steps."""
    dt = scenario.numerics.dt
    n_steps = vt.n_time_steps(scenario)
    track, vehicle = assembly.assemble_track(scenario), assembly.assemble_vehicle(scenario)
    wheels = assembly.assemble_wheels(scenario, n_steps * dt)

    def run():
        state = assembly.static_equilibrium(scenario, track, vehicle, wheels)
        vt.integrate(track, vehicle, wheels, state, n_steps, dt)

    return best_of(run, repeats), n_steps


def passage_timings(repeats: int) -> None:
    """Warm simulate() of the paper's single bogie and six-car train."""
    for label, preset in (("single bogie", "single_bogie"), ("six-car train", "paper")):
        scenario = Scenario.preset(preset)
        vt.simulate(scenario)
        total = best_of(lambda s=scenario: vt.simulate(s), repeats)
        stepping, n_steps = integration_cost(scenario, repeats)
        print(
            f"  {label}: {scenario.rail_length:g} m rail, {scenario.rail_modes} modes, "
            f"{scenario.train.n_wheels} wheels, {n_steps} steps: simulate() {total:.3f} s; "
            f"time stepping {stepping:.3f} s = {n_steps / stepping / 1e3:.0f} k steps/s, "
            f"{stepping / n_steps * 1e6:.2f} µs/step"
        )


def scaling(repeats: int, quick: bool) -> None:
    """Cost per step against cars (N_m and wheels grow) and rail length (N_m grows)."""
    rows = []

    def measure(scenario: Scenario) -> None:
        seconds, n_steps = integration_cost(scenario, repeats)
        rows.append((scenario.rail_modes, scenario.train.n_wheels, seconds / n_steps))
        print(
            f"  {scenario.train.n_cars:4d}  {scenario.train.n_wheels:6d}  "
            f"{scenario.rail_length:8.1f}  {scenario.rail_modes:5d}  "
            f"{seconds / n_steps * 1e6:7.2f}"
        )

    print("  cars  wheels  rail (m)  modes  µs/step")
    for n_cars in (1, 3, 6) if quick else (1, 2, 3, 4, 6, 8):
        scenario = Scenario.paper()
        scenario.train.n_cars = n_cars
        measure(scenario)
    print("  six cars, longer rail (end margin):")
    for margin in (60.0, 180.0) if quick else (60.0, 120.0, 240.0, 480.0):
        scenario = Scenario.paper()
        scenario.numerics.rail_end_margin = margin
        measure(scenario)
    modes, wheels, cost = (np.array(c, dtype=float) for c in zip(*rows, strict=True))
    design = np.column_stack([np.ones_like(modes), modes, modes * wheels])
    c0, c1, c2 = np.linalg.lstsq(design, cost, rcond=None)[0]
    print(
        f"  fit: cost/step ≈ {c0 * 1e6:.2f} µs + {c1 * 1e9:.2f} ns·N_m "
        f"+ {c2 * 1e9:.3f} ns·N_m·n_wheels"
    )


@numba.njit(cache=True)
def _dense_coupling(reps, shapes, q, force):
    """Rail at the blocks = Φᵀq and modal block forces = Φ F as dense BLAS products."""
    modal = np.zeros(q.size)
    for _ in range(reps):
        rail = np.dot(shapes.T, q)
        modal = np.dot(shapes, force + 1e-12 * rail)
    return modal


@numba.njit(cache=True)
def _dst_coupling(reps, q, force):
    """The same two products as DST-I through rocket-fft (scipy.fft inside Numba)."""
    modal = np.zeros(q.size)
    for _ in range(reps):
        rail = scipy.fft.dst(q[: force.size], 1)
        modal[: force.size] = scipy.fft.dst(force + 1e-12 * rail, 1)
    return modal


@numba.njit(cache=True)
def _diagonal_coupling(reps, q, qd, s, sd, kr, cr, gain, force):
    """The model's form: one fastener force per block mode, O(N)."""
    modal = np.zeros(q.size)
    for _ in range(reps):
        for r in range(s.size):
            force[r] = kr * (gain * q[r] - s[r]) + cr * (gain * qd[r] - sd[r])
            modal[r] = -gain * force[r]
    return modal


def coupling_alternatives(repeats: int) -> None:
    """Per-step cost of the block–rail coupling alone, at 527 blocks and 528 modes."""
    n_modes, n_blocks, reps = 528, 527, 2000
    rng = np.random.default_rng(1)
    x = 0.6 * np.arange(1, n_blocks + 1)
    shapes = np.sin(np.outer(np.arange(1, n_modes + 1), x) * np.pi / 316.8)
    q, qd, s, sd, force = (
        rng.standard_normal(n) for n in (n_modes, n_modes, n_blocks, n_blocks, n_blocks)
    )
    cases = {
        "dense mode-shape matrices (BLAS gemv)": lambda: _dense_coupling(reps, shapes, q, force),
        "diagonal block-modal form (this model)": lambda: _diagonal_coupling(
            reps, q, qd, s, sd, 8e7, 5e4, 0.16, force
        ),
    }
    if rocket_fft is not None:
        cases["DST-I via rocket-fft (scipy.fft in Numba)"] = lambda: _dst_coupling(reps, q, force)
    else:
        print("  (DST-I via rocket-fft skipped: rocket-fft is not installed)")
    for label, call in cases.items():
        call()
        seconds = best_of(call, repeats)
        print(f"  {label}: {seconds / reps * 1e6:.2f} µs per step")


def numpy_ratio(repeats: int) -> None:
    """Six-car passage: the kernels (best of ``repeats``) against the NumPy baseline (once)."""
    scenario = Scenario.preset("paper")
    dt, n_steps = scenario.numerics.dt, vt.n_time_steps(scenario)
    track, vehicle = assembly.assemble_track(scenario), assembly.assemble_vehicle(scenario)
    wheels = assembly.assemble_wheels(scenario, n_steps * dt)
    vt.simulate(scenario)
    total = best_of(lambda: vt.simulate(scenario), repeats)
    stepping, _ = integration_cost(scenario, repeats)
    state = assembly.static_equilibrium(scenario, track, vehicle, wheels)
    start = time.perf_counter()
    reference = integrate_numpy(track, vehicle, wheels, state, n_steps, dt)
    baseline = time.perf_counter() - start
    run = vt.integrate(track, vehicle, wheels, state, n_steps, dt)
    gap = np.abs(run.outputs.block_force - reference["block_force"]).max()
    print(
        f"  six-car passage, {n_steps} steps: simulate() {total:.3f} s, time stepping "
        f"{stepping:.3f} s ({stepping / n_steps * 1e6:.2f} µs/step); NumPy baseline "
        f"{baseline:.1f} s ({baseline / n_steps * 1e6:.0f} µs/step; invert force equal to "
        f"{gap / reference['block_force'].max():.0e} of its peak)"
    )
    print(
        f"  ratio simulate() / baseline = {total / baseline:.4f} (target ≤ 0.0125); "
        f"time stepping / baseline = {stepping / baseline:.4f}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="fewer repeats and sizes")
    parser.add_argument("--ratio", action="store_true", help="only the NumPy-baseline ratio")
    args = parser.parse_args()
    print(f"cores: {os.cpu_count()}, numba {numba.__version__}, numpy {np.__version__}")
    if args.ratio:
        numpy_ratio(5)
        return
    quick = args.quick
    repeats = 3 if quick else 7
    print("cold start:")
    cold_start()
    print(f"warm passages (best of {repeats}):")
    passage_timings(repeats)
    print(f"cost per step (best of {repeats}):")
    scaling(max(2, repeats // 2), quick)
    print("block–rail coupling alone (528 modes, 527 blocks):")
    coupling_alternatives(repeats)


if __name__ == "__main__":
    main()
