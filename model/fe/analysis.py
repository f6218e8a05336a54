"""Running the FE section: passages under the line-load history, peaks and permanent displacement.

- **Dynamics.** Newmark average acceleration (γ = 1/2, β = 1/4). Rayleigh damping
  C = a₀M + a₁K_init with ζ = η_G/2 at the two ends of the load band [f_lo, f_hi] (below that
  band the mass term over-damps, between the ends ζ dips below η_G/2). The line load of the
  pipeline (docs/model.md §6) is averaged over each FE step (a box filter that keeps the impulse)
  and applied downward at the invert.
- **Passages.** Each passage is followed by a quiet tail (R/c₂ plus the boundary's relaxation
  time ρc₁R/(α_N G): waves leave, the response decays),
  then a static equilibrium solve with the train gone: for elastic soil it returns exactly to
  the state before the passage, so the displacement left is the permanent (plastic) one. The
  next passage starts from rest.
- **Engines.** The section is solved by this package (``model.fe.native``, the default: 11 ×
  faster with Mohr–Coulomb soil) or by OpenSees (``model.fe.build``, the ``fe`` extra): the same
  model, element by element, held to each other in tests/test_fe_native.py.

Displacements are reported downward positive, relative to the state before the first passage,
on the nodes below the invert (depth = r − a, below the ring–soil interface as in
``model.soil.section_2d.invert_receptance``).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable

import numpy as np
from threadpoolctl import threadpool_limits

from model.fe.build import (
    SPRING_NORMAL,
    FEConvergenceError,
    OpenSeesSection,
    apply_gravity,
    build_section,
    opensees,
)
from model.fe.inputs import LoadBand, load_band, rayleigh_coefficients, resample_load
from model.fe.mesh import (
    ELEMENTS_PER_WAVELENGTH,
    FEMesh,
    SectionMesh,
    check_mesh_size,
    section_mesh,
)
from model.fe.native import NativeSection
from model.fe.store import FEResult
from model.params import Scenario
from model.run_cost import machine_load_factor

TAIL_BOUNDARY_TIMES = 1.0
"""Quiet tail after each passage, in units of R/c₂ plus the boundary relaxation time."""
SOIL_LAWS = ("elastic", "mohr_coulomb")
SECTION_ENGINES = {"native": NativeSection, "opensees": OpenSeesSection}
"""Who solves the section: this package (``model.fe.native``, the default) or OpenSees
(``model.fe.build``); the same model, agreeing to ~1e-7 of the peak (tests/test_fe_native.py)."""
UNBALANCE_TOLERANCE = 1e-6
"""Plastic soil: a time step has converged when the unbalanced force (N, 2-norm over the model)
is below this fraction of the peak invert load; one iteration then suffices where the soil
stays elastic (changes the result by < 1e-6 of it, docs/fe_section.md)."""

FE_CPU_SECONDS_PER_ELEMENT_STEP = {
    ("native", "elastic"): 11.0 / (8904 * 1851),
    ("native", "mohr_coulomb"): 23.0 / (8904 * 1851),
    ("opensees", "elastic"): 57.0 / (8904 * 1851),
    ("opensees", "mohr_coulomb"): 252.0 / (8904 * 1851),
}
"""CPU time per soil element and time step (s) by (engine, law), from docs/fe_section.md's speed
figures: one passage of the paper case on the default mesh (8904 soil elements, 1851 steps),
``python benchmarks/bench_fe.py --engine both`` on the 2-core development machine, idle. The
plastic law's cost grows with the yielding (iterations per step), so the estimate is a guide,
not a bound."""

Progress = Callable[[str, float], None]


def fe_time_hint(
    n_elements: int, steps_per_passage: int, passages: int, soil_law: str, engine: str = "native"
) -> str:
    """One line telling how long the gravity and dynamic stages will take, before they start.

    Parameters
    ----------
    n_elements : int
        Soil elements of the mesh.
    steps_per_passage : int
        FE time steps of one passage (load record and quiet tail).
    passages : int
        Passages in a row.
    soil_law : {"elastic", "mohr_coulomb"}
    engine : {"native", "opensees"}

    Returns
    -------
    str
        E.g. "the FE section: 8904 elements × 1851 time steps × 1 passage with the
        mohr_coulomb law, about 23 s of CPU time (...)".
    """
    per_step = FE_CPU_SECONDS_PER_ELEMENT_STEP[engine, soil_law]
    seconds = per_step * n_elements * steps_per_passage * passages
    load = machine_load_factor()
    busy = f", about {_duration(load * seconds)} at this machine's load" if load > 1.05 else ""
    plural = "s" if passages != 1 else ""
    return (
        f"the FE section: {n_elements} elements × {steps_per_passage} time steps × {passages} "
        f"passage{plural} with the {soil_law} law, about {_duration(seconds)} of CPU time on an "
        f"idle core{busy} (docs/fe_section.md)"
    )


def _duration(seconds: float) -> str:
    """Rounded duration text: "40 s", "6 min", "2.5 h"."""
    if seconds < 120:
        return f"{seconds:.0f} s"
    if seconds < 5400:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"


# ---- public entry points ----------------------------------------------------------------------
def _check_boundary(mesh: FEMesh, ring_radius: float) -> None:
    """Refuse a boundary too close to the lining, before any computation."""
    if not mesh.outer_radius > ring_radius + 1.0:
        raise ValueError(
            f"mesh.outer_radius = {mesh.outer_radius:g} m must exceed the ring radius "
            f"{ring_radius:g} m by more than 1 m"
        )


def _check_mesh(mesh: FEMesh, band: LoadBand) -> float:
    """Largest element size to use (m); ValueError naming the numbers when too coarse."""
    limit = band.shortest_wavelength_m / ELEMENTS_PER_WAVELENGTH
    size = limit if mesh.element_size is None else mesh.element_size
    if not size <= limit * (1 + 1e-9):
        raise ValueError(
            f"mesh.element_size = {size:g} m cannot resolve the shortest wavelength of the load "
            f"band: c₂/f_high = {band.shortest_wavelength_m:.3g} m at f_high = "
            f"{band.f_high_hz:.3g} Hz needs elements ≤ {limit:.3g} m "
            f"({ELEMENTS_PER_WAVELENGTH} per wavelength)"
        )
    return size


def run_fe(
    scenario: Scenario,
    soil_law: str = "elastic",
    passages: int = 1,
    mesh: FEMesh | None = None,
    progress: Progress | None = None,
    load: tuple[np.ndarray, float] | None = None,
    announce: Callable[[str], None] | None = None,
    engine: str = "native",
) -> FEResult:
    """Run the plane-strain FE section under the line-load history at the invert.

    Parameters
    ----------
    scenario : Scenario
        Tunnel (with its axis depth), soil (E, ν, ρ, η_G) and the long-term ground parameters
        (water table, φ′ for K0, c_u); the load comes from ``model.pipeline.run(scenario)``.
    soil_law : {"elastic", "mohr_coulomb"}
        Soil model (the soil laws of ``model.fe.build``).
    passages : int
        Passages in a row, ≥ 1.
    mesh : FEMesh, optional
        Mesh and boundary; default ``FEMesh()``.
    progress : callable(stage, fraction), optional
        Told "load", "gravity" and "dynamic" with the fraction done, 0 to 1.
    load : (ndarray, float), optional
        A line-load history (N/m) and its sampling interval (s) to use instead of the
        pipeline's.
    announce : callable(str), optional
        Told :func:`fe_time_hint` once the mesh and the time step are known, before the gravity
        and dynamic stages (the long part) start.
    engine : {"native", "opensees"}
        Who solves the section (:data:`SECTION_ENGINES`): this package, or OpenSeesPy (the
        ``fe`` extra). The same model; the results agree to ~1e-7 of the peak.

    Returns
    -------
    FEResult

    Raises
    ------
    ValueError
        Unknown law, engine or bad passages, a mesh that cannot resolve the load band or has
        more than ``MAX_FE_ELEMENTS`` elements.
    FEUnavailableError
        The OpenSees engine asked for and OpenSeesPy missing or its shared library not loadable.
    FEConvergenceError
        A static stage or a time step did not converge (the message says when).
    """
    if soil_law not in SOIL_LAWS:
        raise ValueError(f"soil_law = {soil_law!r} must be one of {SOIL_LAWS}")
    if not (isinstance(passages, int) and 1 <= passages <= 100):
        raise ValueError(f"passages = {passages!r} must be an integer in [1, 100]")
    mesh = mesh or FEMesh()
    _check_boundary(mesh, scenario.tunnel.ring_radius)
    if mesh.element_size is not None:  # refused before the pipeline run, not after it
        check_mesh_size(scenario.tunnel.ring_radius, mesh.outer_radius, mesh.element_size)
    if engine not in SECTION_ENGINES:
        raise ValueError(f"engine = {engine!r} must be one of {tuple(SECTION_ENGINES)}")
    report = progress or (lambda stage, fraction: None)
    if engine == "opensees":
        opensees()  # FEUnavailableError before the pipeline runs
    timings = {}
    start = time.perf_counter()
    report("load", 0.0)
    if load is None:
        from model.pipeline import STAGES, run

        def pipeline_progress(stage: str, fraction: float) -> None:
            report("load", (STAGES.index(stage) + fraction) / len(STAGES))

        results = run(scenario, progress=pipeline_progress, cache=None)
        q_raw, dt_raw = results.load.line_load_N_per_m, float(results.load.t_s[1])
    else:
        q_raw, dt_raw = np.asarray(load[0], dtype=float), float(load[1])
    soil, tunnel = scenario.soil, scenario.tunnel
    band = load_band(q_raw, dt_raw, soil.s_wave_speed)
    size = _check_mesh(mesh, band)
    q, dt = resample_load(q_raw, dt_raw, 1.0 / (mesh.steps_per_period * band.f_high_hz))
    grid = section_mesh(tunnel.ring_radius, mesh.outer_radius, size, mesh.radial_aspect)
    # one passage = load record + quiet tail; the boundary relaxes in ~ρ c₁ R / (α_N G)
    relax = soil.p_wave_speed * mesh.outer_radius / (SPRING_NORMAL * soil.s_wave_speed**2)
    n_tail = max(
        3, math.ceil(TAIL_BOUNDARY_TIMES * (mesh.outer_radius / soil.s_wave_speed + relax) / dt)
    )
    n_passage = q.size + n_tail
    timings["load"] = time.perf_counter() - start
    report("load", 1.0)
    if announce is not None:
        announce(fe_time_hint(grid.n_rings * grid.n_theta, n_passage, passages, soil_law, engine))

    history = np.concatenate([np.concatenate([q, np.zeros(n_tail)])] * passages)
    a0, a1 = rayleigh_coefficients(soil.shear_loss_factor, band.f_low_hz, band.f_high_hz)
    section = SECTION_ENGINES[engine](scenario, grid, soil_law, mesh.plastic_radius)
    # SuperLU's back-substitutions call BLAS on small dense blocks, 2.2 × slower on OpenBLAS'
    # threads than on one (paper case): one thread while the section runs (process-wide)
    try:
        with threadpool_limits(limits=1, user_api="blas"):
            disp, residual, iterations = _passages(
                section, history, dt, passages, (a0, a1), report, timings
            )
    finally:
        section.close()  # also after a stage that failed (OpenSees' domain is wiped)
    peaks = np.array(
        [disp[:, 1 + p * n_passage : 1 + (p + 1) * n_passage].max(axis=1) for p in range(passages)]
    )
    info = {
        "outer_radius_m": float(grid.radii[-1]),
        "element_size_m": float(size),
        "largest_edge_m": grid.largest_edge,
        "n_theta": grid.n_theta,
        "n_rings": grid.n_rings,
        "n_elements": section.n_elements,
        "n_plastic_elements": section.n_plastic,
        "n_nodes": (grid.n_rings + 1) * (grid.n_theta + 1),
        "band_hz": [band.f_low_hz, band.f_high_hz],
        "shortest_wavelength_m": band.shortest_wavelength_m,
        "dt_s": dt,
        "steps_per_passage": n_passage,
        "iterations_per_step": iterations / history.size,
        "rayleigh_a0_per_s": a0,
        "rayleigh_a1_s": a1,
        "engine": engine,
    }
    return FEResult(
        soil_law=soil_law,
        passages=passages,
        depth_m=grid.radii - grid.radii[0],
        peak_disp_m=peaks[0],
        residual_disp_m=residual[-1],
        peak_per_passage_m=peaks,
        residual_per_passage_m=residual,
        t_s=np.arange(history.size + 1) * dt,
        disp_m=disp,
        load_N_per_m=np.concatenate([[0.0], history]),
        mesh=info,
        timings_s=timings,
        scenario_json=scenario.to_json(),
    )


def _passages(section, history, dt, passages, rayleigh, report, timings):
    """Gravity, then the passages and a static equilibrium after each, on ``section``.

    Returns
    -------
    disp : ndarray
        (n_rings + 1, steps + 1) downward displacement below the invert (m), from the state
        before the first passage.
    residual : ndarray
        (passages, n_rings + 1) the same at rest after each passage.
    iterations : int
        Iterations (solves) over all time steps.
    """
    start = time.perf_counter()
    report("gravity", 0.0)
    section.prepare()
    timings["gravity"] = time.perf_counter() - start
    report("gravity", 1.0)
    section.set_history(history, dt)
    reference = section.invert_column_disp()
    disp = np.zeros((reference.size, history.size + 1))
    residual = np.zeros((passages, reference.size))
    start = time.perf_counter()
    step = iterations = 0
    report("dynamic", 0.0)
    for passage in range(passages):
        section.begin_passage(*rayleigh, UNBALANCE_TOLERANCE * 0.5 * np.abs(history).max())
        for _ in range(history.size // passages):
            try:
                iterations += section.step()
            except FEConvergenceError as error:
                raise FEConvergenceError(
                    f"the dynamic analysis did not converge at t = {(step + 1) * dt:.3f} s "
                    f"({error})"
                ) from error
            step += 1
            disp[:, step] = reference - section.invert_column_disp()
            if step % 50 == 0:
                report("dynamic", step / history.size)
        section.end_passage()
        residual[passage] = reference - section.invert_column_disp()
    timings["dynamic"] = time.perf_counter() - start
    report("dynamic", 1.0)
    return disp, residual, iterations


def gravity_state(scenario: Scenario, soil_law: str = "elastic", mesh: FEMesh | None = None):
    """Element stresses after the gravity stage (before the lining and the boundary).

    Parameters
    ----------
    scenario : Scenario
        Soil and long-term ground parameters.
    soil_law : {"elastic", "mohr_coulomb"}
        Soil model; the plastic one carries the deviatoric part of the field.
    mesh : FEMesh, optional
        Mesh; ``element_size`` must be given.

    Returns
    -------
    x_m, y_m : ndarray
        (n_rings, n_theta) element centroids (m), y up from the tunnel axis.
    stress_Pa : ndarray
        (n_rings, n_theta, 3) element-average σ_xx, σ_yy, τ_xy (Pa, tension positive).
    """
    mesh = mesh or FEMesh()
    if mesh.element_size is None:
        raise ValueError("gravity_state needs mesh.element_size (there is no load band)")
    ops = opensees()
    grid = section_mesh(
        scenario.tunnel.ring_radius, mesh.outer_radius, mesh.element_size, mesh.radial_aspect
    )
    build_section(ops, scenario, grid, soil_law, mesh.plastic_radius)
    apply_gravity(ops, scenario, grid, soil_law)
    stress = _element_stress(ops, grid)
    ops.wipe()
    return (*grid.centroids(), stress)


def _element_stress(ops, mesh: SectionMesh) -> np.ndarray:
    """(n_rings, n_theta, 3) element-average σ_xx, σ_yy, τ_xy (Pa, tension +)."""
    out = np.empty((mesh.n_rings, mesh.n_theta, 3))
    for i in range(mesh.n_rings):
        for j in range(mesh.n_theta):
            s = np.asarray(ops.eleResponse(1 + i * mesh.n_theta + j, "stresses"))
            out[i, j] = s.reshape(4, -1)[:, :3].mean(axis=0)
    return out


def analytical_profile(scenario: Scenario, line_load_N_per_m, dt_s: float, depth_m):
    """Peak downward displacement of the analytical 2D model (docs/model.md §7–8) at given depths.

    ``model.soil.response.soil_response`` on the same load history, its depth grid reaching the
    deepest requested depth; interpolated (linearly) to ``depth_m``.

    Parameters
    ----------
    scenario : Scenario
        Tunnel, soil and numerics (n_harmonics, soil_max_frequency, zero_pad_factor).
    line_load_N_per_m : array_like
        Line-load history (N/m) sampled at ``dt_s`` (s).
    dt_s : float
        Sampling interval (s).
    depth_m : array_like
        Depths below the ring–soil interface (m), ≥ 0.

    Returns
    -------
    ndarray
        Peak downward displacement (m) at each depth.
    """
    from model.soil.response import soil_response

    depth = np.asarray(depth_m, dtype=float)
    numerics = scenario.copy().numerics
    numerics.max_depth = max(11.0, float(depth.max()))  # the parameter's lower bound
    numerics.n_depths = max(2, math.ceil(numerics.max_depth / 0.25) + 1)
    response = soil_response(line_load_N_per_m, dt_s, scenario.tunnel, scenario.soil, numerics)
    return np.interp(depth, response.depth_m, response.peak_disp_m)
