"""Train-generated excess pore pressure and the soil constants of its consolidation (§15).

**Generation.** Each passage adds undrained excess pore pressure; after N cycles the generated
(undrained) value is u_g = σ′_v0 · min(r_u(N), r_u,max), with

- the power form r_u = a_u (q_d/σ_s)^m_u N^b_u, or
- the hyperbolic form r_u = (q_d/σ_s)^m_u · N/(α + βN),

constants per layer (one value per depth here). N(t) is the count of ``model.longterm.cycles``.

**Consolidation constants.** m_v given per layer, or on the recompression line tangent at σ′_v0,
m_v = C_r/((1 + e0) σ′_v0 ln 10) ≈ 0.434 C_r/((1 + e0) σ′_v0); the hydraulic conductivity k
given, or k = c_v m_v γ_w from a given c_v; c_v = k/(m_v γ_w).

Arrays over time and depth are (n_times, n_depths), as in the rest of ``model.longterm``.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from model.longterm.geostatic import UNIT_WEIGHT_WATER, layer_values

PORE_PRESSURE_LAWS = {
    "power": "power law r_u = a_u (q_d/σ_s)^m_u N^b_u",
    "hyperbolic": "hyperbolic law r_u = (q_d/σ_s)^m_u N/(α + βN)",
    "none": "no pore pressure",
}


class GeneratedPorePressure(NamedTuple):
    """Generated (undrained) excess pore pressure and where its ratio was capped."""

    pressure_Pa: np.ndarray
    """(nt, nd) u_g = σ′_v0 · min(r_u, r_u,max) (Pa)."""
    capped: np.ndarray
    """(nd,) True where r_u exceeded r_u,max at some time."""


def generated_pore_pressure_power(
    vertical_effective_stress_Pa, stress_ratio, n_cycles, a_u, b_u, m_u, r_u_max=0.9
) -> GeneratedPorePressure:
    """Power-law generation u_g = σ′_v0 · min(a_u (q_d/σ_s)^m_u N^b_u, r_u,max).

    Parameters
    ----------
    vertical_effective_stress_Pa : array_like
        σ′_v0 per depth (Pa), > 0, shape (nd,).
    stress_ratio : array_like
        q_d/σ_s per depth, ≥ 0, shape (nd,).
    n_cycles : array_like
        N ≥ 0, shape (nt,) (the same at every depth) or (nt, nd).
    a_u : float or array_like
        Coefficient (dimensionless), > 0, scalar or per depth (nd,).
    b_u, m_u : float or array_like
        Exponents of N and of the stress ratio, ≥ 0, scalar or per depth (nd,).
    r_u_max : float or array_like
        Cap of the pore-pressure ratio, in (0, 1], scalar or per depth (nd,).

    Returns
    -------
    GeneratedPorePressure
    """
    a_u, b_u, m_u = _constants(("a_u", a_u, True), ("b_u", b_u, False), ("m_u", m_u, False))
    stress, ratio, cycles = _generation_inputs(vertical_effective_stress_Pa, stress_ratio, n_cycles)
    return _capped(stress, ratio, cycles, a_u * ratio**m_u * cycles**b_u, r_u_max)


def generated_pore_pressure_hyperbolic(
    vertical_effective_stress_Pa, stress_ratio, n_cycles, alpha, beta, m_u, r_u_max=0.9
) -> GeneratedPorePressure:
    """Hyperbolic generation u_g = σ′_v0 · min((q_d/σ_s)^m_u · N/(α + βN), r_u,max).

    Parameters
    ----------
    vertical_effective_stress_Pa : array_like
        σ′_v0 per depth (Pa), > 0, shape (nd,).
    stress_ratio : array_like
        q_d/σ_s per depth, ≥ 0, shape (nd,).
    n_cycles : array_like
        N ≥ 0, shape (nt,) or (nt, nd).
    alpha : float or array_like
        α > 0 (cycles): r_u grows as N/α for N ≪ α/β.
    beta : float or array_like
        β ≥ 0: r_u tends to (q_d/σ_s)^m_u/β for N ≫ α/β.
    m_u : float or array_like
        Exponent of the stress ratio, ≥ 0.
    r_u_max : float or array_like
        Cap of the pore-pressure ratio, in (0, 1].

    Returns
    -------
    GeneratedPorePressure
    """
    alpha, beta, m_u = _constants(
        ("alpha", alpha, True), ("beta", beta, False), ("m_u", m_u, False)
    )
    stress, ratio, cycles = _generation_inputs(vertical_effective_stress_Pa, stress_ratio, n_cycles)
    return _capped(stress, ratio, cycles, ratio**m_u * cycles / (alpha + beta * cycles), r_u_max)


def _constants(*specs) -> list[np.ndarray]:
    """Law constants as scalars or (nd,) arrays (broadcast over time), checked by sign."""
    values = []
    for name, value, positive in specs:
        array = np.asarray(value, dtype=float)
        if array.ndim > 1 or not np.all(np.isfinite(array)):
            raise ValueError(f"{name} must be a finite scalar or a 1-D array over depth")
        if np.any(array <= 0.0) if positive else np.any(array < 0.0):
            raise ValueError(f"{name} must be {'> 0' if positive else '≥ 0'}, got {array.tolist()}")
        values.append(array)
    return values


def _generation_inputs(vertical_effective_stress_Pa, stress_ratio, n_cycles):
    """σ′_v0 and q_d/σ_s as (nd,) arrays and N as (nt, nd), checked."""
    stress = np.asarray(vertical_effective_stress_Pa, dtype=float)
    ratio = np.asarray(stress_ratio, dtype=float)
    if stress.ndim != 1 or ratio.shape != stress.shape:
        raise ValueError("vertical_effective_stress_Pa and stress_ratio must be (nd,) arrays")
    if not (np.all(stress > 0.0) and np.all(ratio >= 0.0) and np.all(np.isfinite(ratio))):
        raise ValueError("vertical_effective_stress_Pa must be > 0 and stress_ratio finite, ≥ 0")
    cycles = np.asarray(n_cycles, dtype=float)
    if cycles.ndim == 1:
        cycles = cycles[:, None]
    if cycles.ndim != 2 or not np.all(np.isfinite(cycles)) or np.any(cycles < 0.0):
        raise ValueError("n_cycles must be a finite (nt,) or (nt, nd) array, ≥ 0")
    return stress, ratio, np.broadcast_to(cycles, (cycles.shape[0], stress.size))


def _capped(stress, stress_ratio, cycles, pore_ratio, r_u_max) -> GeneratedPorePressure:
    """u_g = σ′_v0 · min(r_u, r_u,max), zero where the soil is not loaded (q_d = 0 or N = 0,
    where x⁰ = 1 would otherwise leave a pressure without a load), and where the cap acted."""
    cap = np.asarray(r_u_max, dtype=float)
    if not np.all((cap > 0.0) & (cap <= 1.0)):
        raise ValueError(f"r_u_max = {r_u_max!r} must be in (0, 1]")
    pore_ratio = np.where((stress_ratio > 0.0) & (cycles > 0.0), pore_ratio, 0.0)
    return GeneratedPorePressure(
        pressure_Pa=stress * np.minimum(pore_ratio, cap),
        capped=np.any(pore_ratio > cap, axis=0),
    )


def recompression_compressibility(
    recompression_index, initial_void_ratio, vertical_effective_stress_Pa
) -> np.ndarray:
    """Volume compressibility on the recompression line, tangent at σ′_v0.

    m_v = C_r / ((1 + e0) σ′_v0 ln 10) ≈ 0.434 C_r / ((1 + e0) σ′_v0), from
    e = e0 − C_r log10(σ′/σ′_v0).

    Parameters
    ----------
    recompression_index : float or array_like
        C_r (dimensionless), > 0.
    initial_void_ratio : float or array_like
        e0 (dimensionless), > 0.
    vertical_effective_stress_Pa : float or array_like
        σ′_v0 (Pa), > 0.

    Returns
    -------
    ndarray
        m_v (1/Pa).
    """
    c_r, e0, stress = (
        np.asarray(x, dtype=float)
        for x in (recompression_index, initial_void_ratio, vertical_effective_stress_Pa)
    )
    if np.any(c_r <= 0.0) or np.any(e0 <= 0.0) or np.any(stress <= 0.0):
        raise ValueError("recompression_index, initial_void_ratio and the stress must be > 0")
    return c_r / ((1.0 + e0) * stress * math.log(10.0))


def hydraulic_conductivity(consolidation_coefficient_m2_per_s, compressibility_per_Pa):
    """Hydraulic conductivity k = c_v m_v γ_w (m/s) from a given c_v.

    Parameters
    ----------
    consolidation_coefficient_m2_per_s : float or array_like
        c_v (m²/s), > 0.
    compressibility_per_Pa : float or array_like
        m_v (1/Pa), > 0.

    Returns
    -------
    ndarray
        k (m/s).
    """
    c_v = np.asarray(consolidation_coefficient_m2_per_s, dtype=float)
    m_v = np.asarray(compressibility_per_Pa, dtype=float)
    if np.any(c_v <= 0.0) or np.any(m_v <= 0.0):
        raise ValueError("c_v and m_v must be > 0")
    return c_v * m_v * UNIT_WEIGHT_WATER


def consolidation_coefficient(hydraulic_conductivity_m_per_s, compressibility_per_Pa):
    """Coefficient of consolidation c_v = k/(m_v γ_w) (m²/s).

    Parameters
    ----------
    hydraulic_conductivity_m_per_s : float or array_like
        k (m/s), > 0.
    compressibility_per_Pa : float or array_like
        m_v (1/Pa), > 0.

    Returns
    -------
    ndarray
        c_v (m²/s).
    """
    k = np.asarray(hydraulic_conductivity_m_per_s, dtype=float)
    m_v = np.asarray(compressibility_per_Pa, dtype=float)
    if np.any(k <= 0.0) or np.any(m_v <= 0.0):
        raise ValueError("k and m_v must be > 0")
    return k / (m_v * UNIT_WEIGHT_WATER)


def layer_compressibility(site, layer_index, vertical_effective_stress_Pa) -> np.ndarray:
    """m_v at each depth (1/Pa): the layer's, or its recompression line's tangent at σ′_v0."""
    m_v = np.empty(len(layer_index))
    for index, layer in enumerate(site.layers):
        rows = np.asarray(layer_index) == index
        if layer.compressibility is not None:
            m_v[rows] = layer.compressibility
        else:
            m_v[rows] = recompression_compressibility(
                layer.recompression_index, layer.void_ratio, vertical_effective_stress_Pa[rows]
            )
    return m_v


def layer_conductivity(site, layer_index, compressibility_per_Pa) -> np.ndarray:
    """k at each depth (m/s): the layer's, or c_v m_v γ_w from its given c_v."""
    k = np.empty(len(layer_index))
    for index, layer in enumerate(site.layers):
        rows = np.asarray(layer_index) == index
        if layer.consolidation_coefficient is None:
            k[rows] = layer.permeability
        else:
            k[rows] = hydraulic_conductivity(
                layer.consolidation_coefficient, compressibility_per_Pa[rows]
            )
    return k


def layer_generated_pore_pressure(
    law: str, site, layer_index, vertical_effective_stress_Pa, stress_ratio, n_cycles
) -> GeneratedPorePressure:
    """u_g of ``law`` ("power" or "hyperbolic") with each depth's layer constants.

    Parameters
    ----------
    law : {"power", "hyperbolic"}
        Generation law (``longterm.pore_pressure_law``).
    site : model.params.Site
        Layers with a_u, b_u, m_u (power) or alpha_u, beta_u, m_u (hyperbolic) and r_u_max.
    layer_index : array_like of int
        (nd,) layer of each depth.
    vertical_effective_stress_Pa, stress_ratio : array_like
        (nd,) σ′_v0 (Pa) and q_d/σ_s.
    n_cycles : array_like
        (nt, nd) N.

    Returns
    -------
    GeneratedPorePressure
    """

    def constant(name):
        return layer_values(site, layer_index, name)

    stress, ratio, cap = vertical_effective_stress_Pa, stress_ratio, constant("r_u_max")
    if law == "power":
        return generated_pore_pressure_power(
            stress, ratio, n_cycles, constant("a_u"), constant("b_u"), constant("m_u"), cap
        )
    if law == "hyperbolic":
        return generated_pore_pressure_hyperbolic(
            stress, ratio, n_cycles, constant("alpha_u"), constant("beta_u"), constant("m_u"), cap
        )
    raise ValueError(f"pore_pressure_law = {law!r} is not one of power, hyperbolic")
