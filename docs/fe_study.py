"""Mesh, time-step and boundary study of the FE section against the analytical 2D model.

Prints the Markdown tables of docs/fe_section.md: elastic FE (model.fe.analysis.run_fe) and the
analytical model (model.soil.response through model.fe.analysis.analytical_profile) under the same
load, a Hann pulse at the invert (50 kN/m peak, 0.4 s long in a 1 s record: band 1–4 Hz,
λ_min = c₂/4 Hz = 8.95 m),
without and with the soil's hysteretic damping. Run: ``python docs/fe_study.py`` (~15 min).

The paper case (the pipeline's line load, three passages) is run per soil law and stored, then
tabulated: ``python docs/fe_study.py paper elastic DIR [PASSAGES]``, ``... paper mohr_coulomb
DIR``,
``python docs/fe_study.py table DIR``.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from model.fe.analysis import analytical_profile, run_fe  # noqa: E402
from model.fe.inputs import load_band  # noqa: E402
from model.fe.mesh import FEMesh  # noqa: E402
from model.fe.store import save_fe_result, stored_fe_result  # noqa: E402
from model.params import Scenario  # noqa: E402

DT_S, PULSE_S, PEAK_N_PER_M = 1e-3, 0.4, 50e3
COMPARE_DEPTH_M = 12.0  # deepest depth compared (inside the smallest boundary studied)
PAPER_MESH = FEMesh(outer_radius=20.0, plastic_radius=8.0)
PAPER_PASSAGES = 3
TABLE_DEPTHS_M = (0.0, 1.0, 2.0, 3.0, 5.0, 8.0, 11.0, 15.0)


def pulse() -> np.ndarray:
    """Hann pulse (N/m) sampled at DT_S, followed by zeros to 1 s."""
    t = np.arange(0.0, 1.0, DT_S)
    return np.where(t < PULSE_S, PEAK_N_PER_M * np.sin(np.pi * t / PULSE_S) ** 2, 0.0)


def errors(scenario: Scenario, mesh: FEMesh) -> tuple[float, float, int, float]:
    """(invert error, max error to COMPARE_DEPTH_M relative to the invert peak, elements, s)."""
    start = time.perf_counter()
    result = run_fe(scenario, "elastic", mesh=mesh, load=(pulse(), DT_S))
    seconds = time.perf_counter() - start
    keep = result.depth_m <= COMPARE_DEPTH_M
    exact = analytical_profile(scenario, pulse(), DT_S, result.depth_m[keep])
    diff = result.peak_disp_m[keep] - exact
    return diff[0] / exact[0], np.abs(diff).max() / exact[0], result.mesh["n_elements"], seconds


def main() -> None:
    """Print the refinement and boundary tables."""
    wavelength = load_band(pulse(), DT_S, Scenario.paper().soil.s_wave_speed).shortest_wavelength_m
    for loss in (0.0, 0.06):
        scenario = Scenario.paper()
        scenario.soil.shear_loss_factor = loss
        print(f"\nη_G = {loss}: refinement of h and Δt together (R = 20 m)\n")
        print("| h (m) | steps/period | elements | invert error | max error 0–12 m | time (s) |")
        print("|---|---|---|---|---|---|")
        for factor in (1, 1.5, 2):
            mesh = FEMesh(
                outer_radius=20.0,
                element_size=wavelength / 6 / factor,
                steps_per_period=round(20 * factor),
            )
            e0, emax, n, s = errors(scenario, mesh)
            print(
                f"| {mesh.element_size:.2f} | {mesh.steps_per_period} | {n} | {e0:+.2%} | "
                f"{emax:.2%} | {s:.0f} |"
            )
        print(
            f"\nη_G = {loss}: boundary radius "
            f"(h = λ_min/6 = {wavelength / 6:.2f} m, 20 steps/period)\n"
        )
        print("| R (m) | elements | invert error | max error 0–12 m | time (s) |")
        print("|---|---|---|---|---|")
        for radius in (15.0, 20.0, 30.0, 40.0):
            e0, emax, n, s = errors(scenario, FEMesh(outer_radius=radius))
            print(f"| {radius:.0f} | {n} | {e0:+.2%} | {emax:.2%} | {s:.0f} |")


def paper(law: str, folder: str, passages: int = PAPER_PASSAGES) -> None:
    """Run the paper case with one soil law and store it in ``folder``."""
    start = time.perf_counter()
    result = run_fe(Scenario.paper(), law, passages=passages, mesh=PAPER_MESH)
    path = save_fe_result(result, folder)
    print(f"{law}: {time.perf_counter() - start:.0f} s, {result.mesh}, {result.timings_s} → {path}")


def table(folder: str) -> None:
    """Depth table of the stored paper-case results beside the analytical model."""
    from model.pipeline import run

    scenario = Scenario.paper()
    analytical = run(scenario, cache=None).soil
    elastic = stored_fe_result(scenario, folder, "elastic")
    plastic = stored_fe_result(scenario, folder, "mohr_coulomb")
    print(
        "| depth (m) | analytical peak (mm) | FE elastic peak (mm) | FE Mohr–Coulomb peak (mm) | "
        + " | ".join(f"permanent after {p + 1} (mm)" for p in range(plastic.passages))
        + " |"
    )
    print("|---" * (4 + plastic.passages) + "|")
    for depth in TABLE_DEPTHS_M:
        row = [
            np.interp(depth, analytical.depth_m, analytical.peak_disp_m),
            np.interp(depth, elastic.depth_m, elastic.peak_disp_m),
            np.interp(depth, plastic.depth_m, plastic.peak_disp_m),
            *(np.interp(depth, plastic.depth_m, r) for r in plastic.residual_per_passage_m),
        ]
        print(f"| {depth:g} | " + " | ".join(f"{v * 1e3:.3f}" for v in row) + " |")
    print(f"\nmesh: {plastic.mesh}\ntimings (s): elastic {elastic.timings_s}, "
          f"Mohr–Coulomb {plastic.timings_s}")  # fmt: skip


if __name__ == "__main__":
    if sys.argv[1:2] == ["paper"]:
        paper(sys.argv[2], sys.argv[3], *map(int, sys.argv[4:5]))
    elif sys.argv[1:2] == ["table"]:
        table(sys.argv[2])
    else:
        main()
