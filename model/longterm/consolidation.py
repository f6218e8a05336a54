"""Consolidation of train-generated excess pore pressure below the invert (docs/model.md §15).

The column runs from the invert (the ring–soil interface directly under the tunnel) down to the
deepest depth of the long-term stage; z is depth, positive downward (m). In terms of the water
stored per unit soil volume, m_v u (m_v the volume compressibility, 1/Pa):

    m_v ∂u/∂t = ∂/∂z ((k/γ_w) ∂u/∂z) + m_v ∂u_g/∂t,     u(z, 0⁻) = 0,

k the hydraulic conductivity (m/s), γ_w = 9.81 kN/m³, u_g the generated (undrained) pore
pressure of ``model.longterm.pore_pressure``. Within a layer of uniform k and m_v this is
∂u/∂t = c_v ∂²u/∂z² + ∂u_g/∂t with c_v = k/(m_v γ_w); across a layer boundary u and the flux
(k/γ_w) ∂u/∂z are continuous (not c_v ∂u/∂z). A nonzero u_g(z, 0) is an instantaneous
undrained load: u(z, 0⁺) = u_g(z, 0) except on a drained boundary.

**Boundaries.** Invert: sealed ∂u/∂z = 0; drained u = 0; leaking through the lining
k_s ∂u/∂z = (k_l/t_l) u (the upward Darcy flux out of the soil, (k_s/γ_w) ∂u/∂z, equals the flux
through a lining of conductivity k_l and thickness t_l driven by u against the tunnel's zero
excess pressure). Base: drained or sealed.

**Settlement.** Consolidation strain ε_c = m_v (u_g − u); S_c(t) = ∫ m_v (u_g − u) dz, which is
also the water expelled through the boundaries per unit area.

**Discretisation** (docs/longterm.md, "Consolidation"). Vertex-centred finite volumes: one
unknown per depth node, control volumes halfway to the neighbours, so the storage of node i is
m_v,i Δz_i with Δz_i the trapezoidal cell thickness (``model.longterm.column``) and S_c is the
trapezoidal integral. The flux between neighbouring nodes uses the harmonic mean of their
conductivities (two half segments in series). A **layer boundary** is a depth given twice, the
upper row with the upper layer's values, the lower row with the lower layer's: the two rows share
one unknown, each storing over its own half cell, and the solution is second-order accurate
across the boundary. Time: θ-scheme on a step grid that is geometric below the first requested
time and hits every requested time exactly; Crank–Nicolson after a few backward-Euler steps
(Rannacher start-up, which damps CN's oscillation after a step load); the generation enters
exactly as the increment of m_v u_g over each step. Each step is a tridiagonal (Thomas) solve
in one Numba loop, the factorization reused while Δt repeats.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numba
import numpy as np

from model.longterm.column import check_depths, trapezoid_thickness
from model.longterm.geostatic import UNIT_WEIGHT_WATER

TOP_BOUNDARIES = ("sealed", "drained", "leaking")
BOTTOM_BOUNDARIES = ("sealed", "drained")
STEPS_PER_DECADE = 20  # default time resolution (docs/longterm.md: accuracy against the count)
BACKWARD_EULER_STEPS = 4  # Rannacher start-up steps
GRADING_DECADES = 3.0  # the first step is this many decades below the first break time
EQUAL_SUBSTEP_RATIO = 2.0  # intervals up to this ratio t_end/t_start get equal substeps


def _finite_volumes(depth, row_storage, conductivity):
    """Node storage C_j (m/Pa), face conductances G (m/(Pa s)), row → node, first rows.

    C_j sums the rows' m_v Δz (``row_storage``) over the one or two rows of node j.
    """
    spacing = np.diff(depth)
    new_node = np.concatenate([[True], spacing > 0.0])
    node_of_row = np.cumsum(new_node) - 1
    first_rows = np.flatnonzero(new_node)
    storage = np.add.reduceat(row_storage, first_rows)
    face = spacing > 0.0  # the pairs of consecutive rows that form a segment
    upper, lower = conductivity[:-1][face], conductivity[1:][face]
    mean = 2.0 * upper * lower / (upper + lower)
    return storage, mean / (UNIT_WEIGHT_WATER * spacing[face]), node_of_row, first_rows


# ---- time steps ------------------------------------------------------------------------------
def _time_grid(break_times, steps_per_decade: int, first_step_s: float):
    """Step end times and step lengths (s) through every break time.

    Below the first break time, a geometric ladder from ``first_step_s`` (``steps_per_decade``
    per decade; one step from 0 to ``first_step_s``); between consecutive break times t₀ < t₁,
    ⌈steps_per_decade · log10(t₁/t₀)⌉ steps, equal when t₁/t₀ ≤ EQUAL_SUBSTEP_RATIO (so the
    factorization is reused; Δt/t then varies by at most that ratio across the interval) and
    geometric otherwise. Each break time is a step end exactly.
    """
    ladder = np.empty(0)
    if first_step_s < break_times[0]:
        n_ladder = math.ceil(steps_per_decade * math.log10(break_times[0] / first_step_s))
        ladder = np.geomspace(first_step_s, break_times[0], n_ladder + 1)[:-1]
    ends = np.concatenate([ladder, break_times])
    starts = np.concatenate([[0.0], ends[:-1]])
    ratio = ends[1:] / starts[1:]
    count = np.concatenate(
        [[1], np.maximum(1, np.ceil(steps_per_decade * np.log10(ratio) - 1e-9)).astype(int)]
    )
    equal = np.concatenate([[True], ratio <= EQUAL_SUBSTEP_RATIO])
    interval = np.repeat(np.arange(ends.size), count)
    last = np.cumsum(count) - 1  # the step that ends each interval
    fraction = (np.arange(interval.size) - (last - count + 1)[interval] + 1) / count[interval]
    start, end = starts[interval], ends[interval]
    base = np.where(start > 0.0, start, end)  # the first interval starts at 0 and is equal
    geometric = base * (end / base) ** fraction
    times = np.where(equal[interval], start + (end - start) * fraction, geometric)
    times[last] = ends
    steps = np.where(equal[interval], (end - start) / count[interval], np.diff(times, prepend=0.0))
    return times, steps


# ---- the solver ------------------------------------------------------------------------------
@dataclass(frozen=True)
class Consolidation:
    """Excess pore pressure and consolidation settlement over time."""

    times_s: np.ndarray
    """(nt,) output times (s)."""
    pore_pressure_Pa: np.ndarray
    """(nt, nd) excess pore pressure u at each input row (Pa); the two rows of a layer
    boundary hold the same value."""
    generated_Pa: np.ndarray
    """(nt, nd) generated (undrained) pore pressure u_g (Pa)."""
    settlement_m: np.ndarray
    """(nt,) consolidation settlement S_c = Σ m_v (u_g − u) Δz (m)."""
    outflow_top_m: np.ndarray
    """(nt,) water expelled through the invert since t = 0, per unit area (m³/m²)."""
    outflow_bottom_m: np.ndarray
    """(nt,) water expelled through the base since t = 0, per unit area (m³/m²)."""
    n_steps: int
    """Time steps taken."""


def solve_consolidation(
    depth_m,
    compressibility_per_Pa,
    hydraulic_conductivity_m_per_s,
    generated_Pa: np.ndarray | Callable[[np.ndarray], np.ndarray],
    times_s,
    *,
    generated_times_s=None,
    top: str = "drained",
    bottom: str = "sealed",
    lining_permeability_m_per_s: float | None = None,
    lining_thickness_m: float | None = None,
    steps_per_decade: int = STEPS_PER_DECADE,
    first_step_s: float | None = None,
    backward_euler_steps: int = BACKWARD_EULER_STEPS,
) -> Consolidation:
    """Dissipation of train-generated excess pore pressure in a 1-D column (module docstring).

    Parameters
    ----------
    depth_m : array_like
        (nd,) non-decreasing depths from the invert to the base (m); a depth given twice marks
        a layer boundary, the upper row carrying the upper layer's values (see
        :func:`model.longterm.column.trapezoid_thickness`).
    compressibility_per_Pa : array_like
        m_v per row (1/Pa), > 0 (scalar or (nd,)).
    hydraulic_conductivity_m_per_s : array_like
        k per row (m/s), > 0 (scalar or (nd,)); from c_v by
        :func:`model.longterm.pore_pressure.hydraulic_conductivity`.
    generated_Pa : ndarray or callable
        u_g (Pa): an (ng, nd) array at ``generated_times_s``, linear in time between them, or a
        callable taking the step times (n,) (s, the first 0) and returning (n, nd).
    times_s : array_like
        (nt,) increasing output times (s), > 0.
    generated_times_s : array_like, optional
        (ng,) increasing sample times of an array ``generated_Pa`` (s), the first 0 and the last
        ≥ times_s[-1]; each is a step end, so the piecewise-linear u_g is integrated exactly.
    top : {"drained", "sealed", "leaking"}
        Invert boundary.
    bottom : {"sealed", "drained"}
        Base boundary.
    lining_permeability_m_per_s, lining_thickness_m : float, optional
        k_l (m/s) ≥ 0 and t_l (m) > 0 of the lining, for ``top="leaking"`` only.
    steps_per_decade : int
        Time steps per decade of t (≥ 1), see design.md for the accuracy.
    first_step_s : float, optional
        Length of the first step (s), > 0; default 10⁻³ × the first output or sample time.
    backward_euler_steps : int
        Backward-Euler steps before Crank–Nicolson (≥ 0).

    Returns
    -------
    Consolidation

    Raises
    ------
    ValueError
        Invalid column, properties, boundary conditions, times or generation.
    """
    depth = np.asarray(depth_m, dtype=float)
    check_depths(depth)
    n_rows = depth.size
    compressibility = _positive_rows("compressibility_per_Pa", compressibility_per_Pa, n_rows)
    conductivity = _positive_rows(
        "hydraulic_conductivity_m_per_s", hydraulic_conductivity_m_per_s, n_rows
    )
    lining = _lining_conductance(top, bottom, lining_permeability_m_per_s, lining_thickness_m)
    times = np.asarray(times_s, dtype=float)
    if times.ndim != 1 or times.size == 0 or times[0] <= 0.0 or np.any(np.diff(times) <= 0.0):
        raise ValueError("times_s must be a non-empty increasing 1-D array of times > 0")
    if steps_per_decade < 1 or backward_euler_steps < 0:
        raise ValueError("steps_per_decade must be ≥ 1 and backward_euler_steps ≥ 0")

    samples = None
    if callable(generated_Pa):
        breaks = times
    else:
        samples, sample_times = _generation_samples(generated_Pa, generated_times_s, n_rows, times)
        breaks = np.union1d(times, sample_times[sample_times <= times[-1]][1:])
    first = breaks[0] * 10.0**-GRADING_DECADES if first_step_s is None else float(first_step_s)
    if not first > 0.0:
        raise ValueError(f"first_step_s = {first_step_s!r} must be > 0")
    step_end, step = _time_grid(breaks, int(steps_per_decade), first)
    step_times = np.concatenate([[0.0], step_end])
    if samples is None:
        generated = np.asarray(generated_Pa(step_times), dtype=float)
        if generated.shape != (step_times.size, n_rows) or not np.all(np.isfinite(generated)):
            raise ValueError(
                f"generated_Pa(t) must return a finite (len(t), {n_rows}) array, got "
                f"shape {generated.shape}"
            )
    else:
        generated = _interpolate_rows(sample_times, samples, step_times)

    row_storage = compressibility * trapezoid_thickness(depth)  # m_v Δz (m/Pa)
    storage, conductance, node_of_row, first_rows = _finite_volumes(
        depth, row_storage, conductivity
    )
    water_generated = np.add.reduceat(row_storage * generated, first_rows, axis=1)
    # Σ m_v Δz u_g per node (m), (n_step_times, n_nodes)
    top_drained, bottom_drained = top == "drained", bottom == "drained"
    pore = water_generated[0] / storage  # the undrained response to u_g(0)
    outflow_top = outflow_bottom = 0.0
    if top_drained:
        outflow_top, pore[0] = water_generated[0, 0], 0.0
    if bottom_drained:
        outflow_bottom, pore[-1] = water_generated[0, -1], 0.0
    theta = np.full(step.size, 0.5)
    theta[:backward_euler_steps] = 1.0
    record = np.isin(step_end, times)
    pore_nodes, top_nodes, bottom_nodes = _march(
        storage,
        conductance,
        lining,
        top_drained,
        bottom_drained,
        pore,
        outflow_top,
        outflow_bottom,
        np.ascontiguousarray(np.diff(water_generated, axis=0)),
        step,
        theta,
        record,
    )
    recorded = np.concatenate([[False], record])
    generated_out = generated[recorded]
    pore_out = pore_nodes[:, node_of_row]
    settlement = (generated_out - pore_out) @ row_storage
    return Consolidation(
        times_s=times,
        pore_pressure_Pa=pore_out,
        generated_Pa=generated_out,
        settlement_m=settlement,
        outflow_top_m=top_nodes,
        outflow_bottom_m=bottom_nodes,
        n_steps=int(step.size),
    )


def _positive_rows(name: str, value, n_rows: int) -> np.ndarray:
    """A scalar or (nd,) property as a finite positive (nd,) array."""
    array = np.asarray(value, dtype=float)
    if array.ndim > 1 or (array.ndim == 1 and array.size != n_rows):
        raise ValueError(f"{name} must be a scalar or have one value per depth ({n_rows})")
    if not np.all(np.isfinite(array) & (array > 0.0)):
        raise ValueError(f"{name} must be finite and > 0")
    return np.broadcast_to(array, (n_rows,)).astype(float)


def _lining_conductance(top, bottom, permeability, thickness) -> float:
    """k_l/(γ_w t_l) (m/(Pa s)) for a leaking invert, 0 for a sealed one; checks the names."""
    if top not in TOP_BOUNDARIES:
        raise ValueError(f"top = {top!r} is not one of {', '.join(TOP_BOUNDARIES)}")
    if bottom not in BOTTOM_BOUNDARIES:
        raise ValueError(f"bottom = {bottom!r} is not one of {', '.join(BOTTOM_BOUNDARIES)}")
    given = permeability is not None or thickness is not None
    if top != "leaking":
        if given:
            raise ValueError(
                "lining_permeability_m_per_s and lining_thickness_m need top='leaking'"
            )
        return 0.0
    if permeability is None or thickness is None:
        raise ValueError("top='leaking' needs lining_permeability_m_per_s and lining_thickness_m")
    if not (math.isfinite(permeability) and permeability >= 0.0):
        raise ValueError(f"lining_permeability_m_per_s = {permeability!r} must be ≥ 0")
    if not (math.isfinite(thickness) and thickness > 0.0):
        raise ValueError(f"lining_thickness_m = {thickness!r} must be > 0")
    return permeability / (UNIT_WEIGHT_WATER * thickness)


def _generation_samples(generated, sample_times, n_rows: int, times: np.ndarray):
    """An array u_g and its sample times, checked against the column and the output times."""
    samples = np.asarray(generated, dtype=float)
    if sample_times is None:
        raise ValueError("an array generated_Pa needs generated_times_s")
    sample_times = np.asarray(sample_times, dtype=float)
    if sample_times.ndim != 1 or sample_times.size < 2 or np.any(np.diff(sample_times) <= 0.0):
        raise ValueError("generated_times_s must be an increasing 1-D array of ≥ 2 times")
    if sample_times[0] != 0.0 or sample_times[-1] < times[-1]:
        raise ValueError("generated_times_s must start at 0 and reach the last output time")
    if samples.shape != (sample_times.size, n_rows) or not np.all(np.isfinite(samples)):
        raise ValueError(
            f"generated_Pa must be a finite ({sample_times.size}, {n_rows}) array, got "
            f"shape {samples.shape}"
        )
    return samples, sample_times


def _interpolate_rows(sample_times, samples, times) -> np.ndarray:
    """Each depth's column of ``samples`` (ng, nd) linearly interpolated in time at ``times``."""
    index = np.clip(
        np.searchsorted(sample_times, times, side="right") - 1, 0, sample_times.size - 2
    )
    weight = ((times - sample_times[index]) / (sample_times[index + 1] - sample_times[index]))[
        :, None
    ]
    return samples[index] * (1.0 - weight) + samples[index + 1] * weight


@numba.njit(cache=True, nogil=True)
def _march(
    storage,
    conductance,
    lining,
    top_drained,
    bottom_drained,
    pore,
    outflow_top,
    outflow_bottom,
    water_increment,
    step,
    theta,
    record,
):
    """θ-scheme steps of C du/dt = −K u + dW/dt with a Thomas solve per step.

    (C + θΔt K) u⁺ = (C − (1 − θ)Δt K) u + ΔW on the nodes that are not drained; K couples node
    j to j ± 1 through the face conductances, node 0 to the tunnel (u = 0) through ``lining``.
    The water leaving through each boundary over a step is its θ-weighted flux times Δt, plus,
    at a drained node, the water generated in its half cell. Returns u (n_recorded, n_nodes) and
    the cumulative outflows (n_recorded,) at the recorded steps.
    """
    n = storage.size
    first = 1 if top_drained else 0
    last = n - 2 if bottom_drained else n - 1  # the last unknown
    left = np.zeros(n)  # conductance to the node above (to the tunnel for node 0)
    right = np.zeros(n)
    left[0] = lining
    left[1:] = conductance
    right[:-1] = conductance
    n_recorded = 0
    for flag in record:
        n_recorded += flag
    pore_out = np.empty((n_recorded, n))
    top_out = np.empty(n_recorded)
    bottom_out = np.empty(n_recorded)
    u = pore.copy()
    rhs = np.empty(n)
    upper = np.zeros(n)  # eliminated super-diagonal c′_j
    pivot_inverse = np.zeros(n)
    factored_step, factored_theta = -1.0, -1.0
    k = 0
    for s in range(step.size):
        dt, th = step[s], theta[s]
        implicit, explicit = th * dt, (1.0 - th) * dt
        if dt != factored_step or th != factored_theta:
            for j in range(first, last + 1):
                diagonal = storage[j] + implicit * (left[j] + right[j])
                if j > first:
                    diagonal += implicit * left[j] * upper[j - 1]  # − a_j c′_{j−1}, a_j = −θΔt G
                pivot_inverse[j] = 1.0 / diagonal
                upper[j] = -implicit * right[j] * pivot_inverse[j] if j < last else 0.0
            factored_step, factored_theta = dt, th
        for j in range(first, last + 1):
            flux = (left[j] + right[j]) * u[j]
            if j > 0:
                flux -= left[j] * u[j - 1]
            if j < n - 1:
                flux -= right[j] * u[j + 1]
            rhs[j] = storage[j] * u[j] - explicit * flux + water_increment[s, j]
        old_top = u[1] if top_drained else u[0]
        old_bottom = u[n - 2] if bottom_drained else 0.0
        for j in range(first, last + 1):  # forward elimination, then back substitution
            if j > first:
                rhs[j] += implicit * left[j] * rhs[j - 1]
            rhs[j] *= pivot_inverse[j]
        for j in range(last, first - 1, -1):
            u[j] = rhs[j] - (upper[j] * u[j + 1] if j < last else 0.0)
        if top_drained:
            outflow_top += water_increment[s, 0] + conductance[0] * (
                implicit * u[1] + explicit * old_top
            )
        else:
            outflow_top += lining * (implicit * u[0] + explicit * old_top)
        if bottom_drained:
            outflow_bottom += water_increment[s, n - 1] + conductance[n - 2] * (
                implicit * u[n - 2] + explicit * old_bottom
            )
        if record[s]:
            pore_out[k] = u
            top_out[k] = outflow_top
            bottom_out[k] = outflow_bottom
            k += 1
    return pore_out, top_out, bottom_out
