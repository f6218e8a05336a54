"""Time one passage of the paper case through the FE section (docs/model.md §12).

Run: ``python benchmarks/bench_fe.py [elastic|mohr_coulomb ...] [--engine native|opensees|both]``
(default: both laws, the native engine). For each soil law it runs the pipeline once for the
line load, then ``run_fe`` with one passage on the default mesh (R = 30 m, element size
λ_min/6 from the load band, 20 steps per period of f_high), and prints the mesh, the time steps
and the mean iterations per step (1 for the elastic law: one solve), the wall time of each phase
and the peak and permanent displacement at the invert and at 11 m, beside the analytical 2D
model on the same load. Target: minutes, not hours.
Timings are wall-clock on a shared machine, with the process's CPU time beside them (the
figure to compare between machines). With ``--engine both`` each law runs on both engines, and
the largest differences of the peak and permanent profiles (whole depth) and of the histories
are printed as fractions of the invert peak (issue 27 item 5: "results unchanged within the
mesh study's tolerance").
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from model.fe.analysis import run_fe  # noqa: E402
from model.params import Scenario  # noqa: E402
from model.pipeline import run  # noqa: E402

MM = 1e3


def main(laws: list[str], engines: list[str]) -> None:
    """Run and print each law on each engine."""
    scenario = Scenario.paper()
    results = run(scenario, cache=None)
    load = (results.load.line_load_N_per_m, float(results.load.t_s[1]))
    depth, analytical = results.soil.depth_m, results.soil.peak_disp_m
    print(
        f"analytical 2D: invert {analytical[0] * MM:.2f} mm, "
        f"11 m {np.interp(11.0, depth, analytical) * MM:.2f} mm"
    )
    for law in laws:
        done = {}
        for engine in engines:
            done[engine] = _timed(scenario, law, load, engine)
        if len(done) == 2:
            a, b = done.values()
            scale = a.peak_disp_m[0]
            print(
                f"  {' − '.join(done)}, over the invert peak: peak profile "
                f"{np.abs(a.peak_disp_m - b.peak_disp_m).max() / scale:.1e}, permanent "
                f"{np.abs(a.residual_disp_m - b.residual_disp_m).max() / scale:.1e}, histories "
                f"{np.abs(a.disp_m - b.disp_m).max() / scale:.1e}"
            )


def _timed(scenario, law, load, engine):
    """One passage of ``law`` on ``engine``, printed; returns the FEResult."""
    start, cpu_start = time.perf_counter(), time.process_time()
    fe = run_fe(scenario, law, load=load, engine=engine)
    total, cpu = time.perf_counter() - start, time.process_time() - cpu_start
    mesh = fe.mesh
    print(
        f"{law} ({engine}): {mesh['n_elements']} elements ({mesh['n_plastic_elements']} "
        f"plastic), {mesh['n_theta']} × {mesh['n_rings']}, h = {mesh['element_size_m']:.2f} m, "
        f"R = {mesh['outer_radius_m']:.0f} m, band {mesh['band_hz'][0]:.2f}–"
        f"{mesh['band_hz'][1]:.2f} Hz, Δt = {mesh['dt_s'] * 1e3:.1f} ms × "
        f"{mesh['steps_per_passage']} steps, {mesh['iterations_per_step']:.2f} iterations "
        "per step"
    )
    phases = ", ".join(f"{name} {seconds:.1f} s" for name, seconds in fe.timings_s.items())
    print(f"  wall time {total:.0f} s ({phases}); CPU time {cpu:.0f} s")
    print(
        f"  peak: invert {fe.peak_disp_m[0] * MM:.5f} mm, "
        f"11 m {np.interp(11.0, fe.depth_m, fe.peak_disp_m) * MM:.5f} mm; permanent: "
        f"invert {fe.residual_disp_m[0] * MM:.5f} mm, "
        f"11 m {np.interp(11.0, fe.depth_m, fe.residual_disp_m) * MM:.5f} mm",
        flush=True,
    )
    return fe


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("laws", nargs="*", default=["elastic", "mohr_coulomb"])
    parser.add_argument("--engine", choices=["native", "opensees", "both"], default="native")
    args = parser.parse_args()
    main(args.laws, ["native", "opensees"] if args.engine == "both" else [args.engine])
