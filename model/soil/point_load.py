"""Point load on the invert of the 2.5D tunnel: the wavenumber integral of H (docs/model.md §9).

G(ω, x, d) = (1/2π)∫ H(ω, ξ, d) e^{−iξx} dξ, with H the line-load receptance of
``model.soil.moving_load_2p5d``: the displacement at depth d below the invert, at distance x
along the tunnel, per unit downward point force on the invert at x = 0. Far below a
quasi-static load it tends to Kelvin's 1/(4πμd). The integral is Filon's rule on a graded
wavenumber grid, with its error and its tail estimated and refused above
``numerics.wavenumber_tolerance`` (:func:`point_load_response`).
"""

from __future__ import annotations

import cmath
import math

import numba
import numpy as np

from model.params import Numerics
from model.soil.inputs import as_1d, checked_depths, soil_constants
from model.soil.moving_load_2p5d import paired_inputs, receptance_2p5d

# Points of each refinement at the P and S wavenumbers, per base-grid point; relative half-width
# of the refined window around Re k, and the least relative width resolved there (undamped soil).
_REFINE_FRACTION = 1 / 16
_REFINE_HALF_WIDTH = 0.5
_REFINE_MIN_WIDTH = 1e-3


def _wavenumber_grid(omega, corner, reach, soil, numerics) -> np.ndarray:
    """Nodes on [0, ξ_max] (rad/m): uniform in asinh(ξ/ξ_c); uniform on [0, 1.5 Re k₂], where
    H oscillates in ξ with period ~2π/reach (waves to depth), with n_wavenumbers/(64π) nodes
    per rad/m per metre of reach (12 per period of 2π/reach at the default 384); refined around
    Re k₁ and Re k₂."""
    xi_max = numerics.max_wavenumber
    base = corner * np.sinh(np.linspace(0.0, math.asinh(xi_max / corner), numerics.n_wavenumbers))
    shear, lame, density = soil_constants(soil)
    band = 1.5 * (omega * cmath.sqrt(density / shear)).real
    n_band = math.ceil(band * reach * numerics.n_wavenumbers / (64.0 * math.pi))
    parts = [base, np.linspace(0.0, band, n_band + 1)]
    n_refine = max(8, int(_REFINE_FRACTION * numerics.n_wavenumbers))
    for modulus in (lame + 2.0 * shear, shear):
        k = omega * cmath.sqrt(density / modulus)
        width = max(abs(k.imag) / abs(k.real), _REFINE_MIN_WIDTH)
        offset = width * np.sinh(np.linspace(0.0, math.asinh(_REFINE_HALF_WIDTH / width), n_refine))
        # Re k itself is left out: for an undamped soil it is the branch point α or β = 0.
        parts.append(k.real * (1.0 + np.concatenate([-offset[:0:-1], offset[1:]])))
    nodes = np.unique(np.concatenate(parts))
    return nodes[(nodes >= 0.0) & (nodes <= xi_max)]


@numba.njit(cache=True, nogil=True)
def filon_cosine_kernel(nodes, values, x):
    """∫ h(ξ) cos(ξx) dξ over [nodes[0], nodes[-1]] for h linear between the nodes.

    Filon's rule: on a panel of half-width c about ξ_m, with h = h̄ + s(ξ − ξ_m) and θ = c x,
    ∫ h cos ξx dξ = 2c h̄ sinc θ cos ξ_m x − 2c² s g(θ) sin ξ_m x, g(θ) = (sin θ − θ cos θ)/θ²
    (series below |θ| = 1e-3, where the closed forms cancel). values (n_nodes, n_cols) complex,
    x (n_x,); returns (n_x, n_cols).
    """
    n_cols = values.shape[1]
    out = np.zeros((x.size, n_cols), np.complex128)
    for i in range(x.size):
        for p in range(nodes.size - 1):
            half = 0.5 * (nodes[p + 1] - nodes[p])
            theta = half * x[i]
            if abs(theta) < 1e-3:
                sinc = 1.0 - theta * theta / 6.0
                g = theta / 3.0 - theta**3 / 30.0
            else:
                sinc = math.sin(theta) / theta
                g = (sinc - math.cos(theta)) / theta
            middle_phase = 0.5 * (nodes[p + 1] + nodes[p]) * x[i]
            even = half * sinc * math.cos(middle_phase)
            odd = half * g * math.sin(middle_phase)
            left = even + odd
            right = even - odd
            for c in range(n_cols):
                out[i, c] += left * values[p, c] + right * values[p + 1, c]
    return out


def point_load_response(
    freq_hz, x_m, depth_m, tunnel, soil, n_harmonics: int, numerics: Numerics | None = None
) -> np.ndarray:
    """Displacement below the invert per unit downward point force on the invert (m/N).

    G(ω, x, d) = (1/2π)∫ H(ω, ξ, d) e^{−iξx} dξ = (1/π)∫₀^∞ H(ω, ξ, d) cos ξx dξ (H is even),
    docs/model.md §9: the force acts at the invert at x = 0, the displacement is taken at depth d
    below the invert at distance x along the tunnel. The integral is Filon's rule (H linear
    between nodes, the cosine integrated exactly, so x needs no extra nodes) on nodes uniform
    in asinh(ξ/ξ_c) from 0 to ``numerics.max_wavenumber`` (ξ_c = min(0.1 Re k₂,
    0.1/(a + d_max)), the scale of the smallest feature), uniform nodes over the band of
    propagating waves ξ < 1.5 Re k₂ (where H oscillates with depth) and refinements around the
    P and S wavenumbers Re k₁, Re k₂ where H has branch points. Its error is estimated as a third of
    the change when every other node is dropped (Filon-linear converges as Δξ²); the tail
    beyond ξ_max as |H(ξ_max)| ξ_max/(3π) (the shell's ξ⁻⁴ decay).

    Parameters
    ----------
    freq_hz : float or array_like
        Frequencies f (Hz), > 0.
    x_m : float or array_like
        Distances along the tunnel from the force (m).
    depth_m : float or array_like
        Depths d ≥ 0 below the ring–soil interface (m).
    tunnel, soil : model.params.Tunnel, model.params.Soil
        Lining and soil.
    n_harmonics : int
        Highest circumferential harmonic N ≥ 0.
    numerics : model.params.Numerics, optional
        Uses n_wavenumbers, max_wavenumber, wavenumber_tolerance (defaults if omitted).

    Returns
    -------
    ndarray
        Complex (n_freq, n_x, n_depth) displacement in m per N, exp(+iωt).

    Raises
    ------
    ValueError
        Bad input, or an integral whose estimated error (or tail) exceeds
        ``numerics.wavenumber_tolerance`` times the largest |G| at that frequency and depth;
        the message names the numerics parameter to raise.
    """
    numerics = Numerics() if numerics is None else numerics
    omega, _ = paired_inputs(freq_hz, 0.0)
    x = as_1d(x_m, "x_m", "m")
    depth = checked_depths(depth_m)
    shear, _, density = soil_constants(soil)
    reach = tunnel.ring_radius + float(depth.max())
    grids = []
    for w in omega:
        k2 = w * math.sqrt(density / abs(shear))
        corner = min(0.1 * k2, 0.1 / reach)
        grids.append(_wavenumber_grid(w, corner, reach, soil, numerics))
    sizes = [grid.size for grid in grids]
    h_all = receptance_2p5d(
        np.repeat(omega / (2.0 * np.pi), sizes), np.concatenate(grids), depth, tunnel, soil,
        n_harmonics,
    )  # fmt: skip
    tolerance = numerics.wavenumber_tolerance
    response = np.empty((omega.size, x.size, depth.size), dtype=complex)
    start = 0
    for i, nodes in enumerate(grids):
        h = h_all[start : start + nodes.size]
        start += nodes.size
        response[i] = filon_cosine_kernel(nodes, h, x) / np.pi
        coarse = filon_cosine_kernel(nodes[::2], np.ascontiguousarray(h[::2]), x) / np.pi
        if (nodes.size - 1) % 2:  # the coarse rule must reach ξ_max too
            coarse += filon_cosine_kernel(nodes[-2:], np.ascontiguousarray(h[-2:]), x) / np.pi
        scale = np.abs(response[i]).max(axis=0)
        error = np.abs(response[i] - coarse).max(axis=0) / 3.0
        tail = np.abs(h[-1]) * nodes[-1] / (3.0 * np.pi)
        freq = omega[i] / (2.0 * np.pi)
        if np.any(error > tolerance * scale):
            raise ValueError(
                f"the wavenumber integral has not converged at {freq:.4g} Hz (estimated "
                f"relative error {np.max(error / scale):.2g} > numerics.wavenumber_tolerance = "
                f"{tolerance:g}): raise numerics.n_wavenumbers (now {numerics.n_wavenumbers})"
            )
        if np.any(tail > tolerance * scale):
            raise ValueError(
                f"the wavenumber integral is cut too early at {freq:.4g} Hz (estimated tail "
                f"{np.max(tail / scale):.2g} > numerics.wavenumber_tolerance = {tolerance:g}): "
                f"raise numerics.max_wavenumber (now {numerics.max_wavenumber:g} rad/m)"
            )
    return response
