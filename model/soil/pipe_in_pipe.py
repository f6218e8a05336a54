"""The 2.5D tunnel in a half-space by the pipe-in-pipe method (docs/halfspace.md).

Hussein & Hunt's pipe-in-pipe (PiP) recipe: solve the tunnel in a full-space (the shell–soil
model of ``model.soil.moving_load_2p5d``, Forrest & Hunt 2006), then add the field that the free
surface reflects from the waves that tunnel radiates, and stop there: the reflected field is not
scattered back by the tunnel. The full-space field outside the cavity is exactly the field of
equivalent forces on the cavity surface, so this is the same as applying the full-space cavity
forces to the half-space Green's function and keeping its reflected part; here the reflection is
done on the up-going plane-wave spectrum of the tunnel's field, in closed form
(``model.soil.halfspace_kernels``), which replaces the integral over the cavity.

Frame: x along the tunnel, y across, z down from the surface, tunnel axis at z = H
(``tunnel.axis_depth``); the shell model's θ = 0 (the invert) points down, y = −r sin θ,
z − H = r cos θ; fields ∝ exp(i(ωt − ξx)).

Plane-wave expansion (z < H; ζ = z − H, w = −y, e^{inθ} = ((ζ + iw)/r)ⁿ), with γ = √(k_y² + α²)
= ν_p and t = (γ − k_y)/α (the same for β, ν_s):

    K_n(αr) cos nθ = (1/2π) ∫ π (−1)ⁿ (tⁿ + t⁻ⁿ)/2 · e^{γζ}/γ · e^{−ik_y y} dk_y,
    K_n(αr) sin nθ = (1/2π) ∫ π (−1)ⁿ (tⁿ − t⁻ⁿ)/(2i) · e^{γζ}/γ · e^{−ik_y y} dk_y,

from K₀(αr) = ½∫ e^{−γ|ζ|} e^{−ik_w w}/γ dk_w and (∂_ζ + i∂_w)[K_n e^{inθ}] = −α K_{n+1}
e^{i(n+1)θ}. The 1/K_n(za) normalisation of the shell model's radial functions is applied through
the ratio recurrence of ``model.soil.bessel`` (no overflow at low frequency). The potentials
φ (P), ψ (in-plane SV, u = ∇×(ψe_x)) and χ (axial SH, u = ∇×∇×(χe_x)) give the up-going field
û = (−iξ, −ik_y, ν_p)φ̂ + (0, ν_s, ik_y)ψ̂ + (k_s² − ξ², −ξk_y, −iξν_s)χ̂.

The inverse k_y transform uses 12-point Gauss–Legendre panels (:func:`ky_panel_edges`); the
response is even in y, so k_y ≥ 0 with cos k_y y. Where every wave is evanescent, ξ > Re k_s
(a subsonic train), and the field has decayed by e^{−36} ≈ 2e-16 over the cover H − a, the
pair is left at 0. Units: displacement per unit downward line load (N/m) on the invert varying
as exp(i(ωt − ξx)), the half-space counterpart of H(ω, ξ, d) of docs/model.md §9.
"""

from __future__ import annotations

import cmath
import math

import numba
import numpy as np

from model.soil.bessel import bessel_ratios, log_derivative
from model.soil.halfspace import rayleigh_wavenumber
from model.soil.halfspace_kernels import (
    divided_difference,
    downgoing_uw,
    reflect_at_surface,
    vertical_wavenumbers,
)
from model.soil.inputs import (
    as_1d,
    check_harmonics,
    checked_depths,
    invert_load_coefficients,
    ring_constants,
    soil_constants,
)
from model.soil.moving_load_2p5d import _interface_amplitudes, paired_inputs

_GL_ORDER = 12
_GL_NODES, _GL_WEIGHTS = np.polynomial.legendre.leggauss(_GL_ORDER)
# The plane waves decay at least as e^{−k_y (H − a + z)}: beyond e^{−36} ≈ 2e-16 they are cut.
DECAY_EXPONENT = 36.0
REFLECTED_STRESSES = ("sigma_rr", "sigma_thetatheta", "sigma_xx", "sigma_rx")
"""The stresses of the reflected field below the invert (σ_rθ = σ_θx = 0 there)."""


@numba.njit(cache=True, nogil=True)
def cavity_amplitudes(
    omega, xi, load_coefficients, a, mass, extensional, bending, poisson, shear, lame, density
):  # fmt: skip
    """Soil potential amplitudes of the shell in a full-space, per pair (ω_i, ξ_i) and harmonic.

    A_P = X + Y − ξZ, A_SV = Y, A_SH = Z of ``model.soil.moving_load_2p5d`` (its
    ``_interface_amplitudes``, per unit radial traction) times the load coefficient p_n. Also
    α, β, the scaled K₀(αa)e^{αa}, K₀(βa)e^{βa} and the inverse ratios 1/R_m = K_m/K_{m+1} at
    αa, βa (the plane-wave expansion divides by K_n(za) = K₀(za) Π_{m<n} R_m).

    Returns
    -------
    tuple
        amp_p, amp_sv, amp_sh, inverse_ratio_p, inverse_ratio_s complex (n_pairs, N + 1);
        alpha, beta, k0_p, k0_s complex (n_pairs,).
    """
    n_pairs = omega.size
    n_max = load_coefficients.size - 1
    shape = (n_pairs, n_max + 1)
    amp_p = np.zeros(shape, np.complex128)
    amp_sv = np.zeros(shape, np.complex128)
    amp_sh = np.zeros(shape, np.complex128)
    ratio_p = np.zeros(shape, np.complex128)
    ratio_s = np.zeros(shape, np.complex128)
    alpha = np.zeros(n_pairs, np.complex128)
    beta = np.zeros(n_pairs, np.complex128)
    k0_p = np.zeros(n_pairs, np.complex128)
    k0_s = np.zeros(n_pairs, np.complex128)
    for i in range(n_pairs):
        w, q = omega[i], xi[i]
        alpha[i] = cmath.sqrt(q * q - w * w * density / (lame + 2.0 * shear))
        beta[i] = cmath.sqrt(q * q - w * w * density / shear)
        k0_p[i] = bessel_ratios(alpha[i] * a, n_max, ratio_p[i])
        k0_s[i] = bessel_ratios(beta[i] * a, n_max, ratio_s[i])
        for n in range(n_max + 1):
            x, y, z = _interface_amplitudes(
                n, q, w, a, mass, extensional, bending, poisson, alpha[i], beta[i],
                log_derivative(alpha[i], ratio_p[i], n), log_derivative(beta[i], ratio_s[i], n),
                shear, lame, density,
            )  # fmt: skip
            p = load_coefficients[n]
            amp_p[i, n] = p * (x + y - q * z)
            amp_sv[i, n] = p * y
            amp_sh[i, n] = p * z
    return amp_p, amp_sv, amp_sh, 1.0 / ratio_p, 1.0 / ratio_s, alpha, beta, k0_p, k0_s


@numba.njit(cache=True, nogil=True)
def ky_panel_edges(xi, features, widths, decay_length, y_max, refine):
    """Panel edges on [0, k_max] for the k_y integral at ξ ≥ 0.

    k_max = k_prop + 36/decay_length, k_prop the largest propagating k_y = √(Re k_j² − ξ²);
    geometric grading from ξ/16 up to 1/decay_length (where k = √(ξ² + k_y²) turns from ξ to
    k_y) and towards each real-axis feature k_y = √(Re k_j² − ξ²) (P and S branch points,
    Rayleigh pole: only for Re k_j > ξ, waves the load radiates) down to its damping width;
    panels no wider than min(4π/y_max, 4/decay_length)/refine in between, so that a 12-point
    Gauss–Legendre panel spans at most two periods of cos k_y y (tests: the change from
    refine = 1 to 2 is ≲ 1e-6 of the largest response).
    """
    k_prop = 0.0
    for j in range(features.size):
        if features[j] > xi:
            k_prop = max(k_prop, math.sqrt(features[j] ** 2 - xi * xi))
    k_max = k_prop + DECAY_EXPONENT / decay_length
    width = min(4.0 * math.pi / max(y_max, 1e-9), 4.0 / decay_length) / refine
    points = [0.0, k_max]
    start = xi / 16.0
    while 0.0 < start < 1.0 / decay_length:
        points.append(start)
        start *= 2.0
    for j in range(features.size):
        if features[j] > xi:
            centre = math.sqrt(features[j] ** 2 - xi * xi)
            # |dk_y| = |dk| k/k_y near the feature: its damping width in k_y
            step = max(widths[j] * features[j] / max(centre, 1e-12), 1e-9 * features[j])
            points.append(centre)
            while step < width:
                points.append(centre + step)
                if centre - step > 0.0:
                    points.append(centre - step)
                step *= 2.0
    ordered = np.sort(np.array(points))
    edges = [0.0]
    for i in range(1, ordered.size):
        lo, hi = edges[-1], min(ordered[i], k_max)
        if hi > lo:
            n_sub = int(math.ceil((hi - lo) / width))
            for m in range(1, n_sub + 1):
                edges.append(lo + (hi - lo) * m / n_sub)
    return np.array(edges)


@numba.njit(cache=True, nogil=True)
def _potential_sums(ky, nu_p, nu_s, alpha, beta, amp_p, amp_sv, amp_sh, inverse_ratio_p,
                    inverse_ratio_s):  # fmt: skip
    """Σ_n A_P (T⁺+T⁻)/2, Σ_n A_SV (S⁺−S⁻)/(2i), Σ_n i A_SH (S⁺+S⁻)/2, T^± = (−t^{±1})ⁿ/Π R_m
    (``inverse_ratio_*`` holds 1/R_m).

    k_y ≥ 0: t⁻¹ = (ν + k_y)/z is formed directly and t = z/(ν + k_y) (no cancellation).
    """
    t_inv_p, t_p = (nu_p + ky) / alpha, alpha / (nu_p + ky)
    t_inv_s, t_s = (nu_s + ky) / beta, beta / (nu_s + ky)
    tp_plus = tp_minus = ts_plus = ts_minus = 1.0 + 0j
    sum_p, sum_sv, sum_sh = amp_p[0] + 0j, 0j, 1j * amp_sh[0]
    for n in range(1, amp_p.size):
        rp, rs = inverse_ratio_p[n - 1], inverse_ratio_s[n - 1]
        tp_plus = tp_plus * (-t_p) * rp
        tp_minus = tp_minus * (-t_inv_p) * rp
        ts_plus = ts_plus * (-t_s) * rs
        ts_minus = ts_minus * (-t_inv_s) * rs
        sum_p += amp_p[n] * 0.5 * (tp_plus + tp_minus)
        sum_sv += amp_sv[n] * (-0.5j) * (ts_plus - ts_minus)
        sum_sh += amp_sh[n] * 0.5j * (ts_plus + ts_minus)
    return sum_p, sum_sv, sum_sh


@numba.njit(cache=True, nogil=True)
def _plane_wave_node(i, q, ky, kp2, ks2, gamma2, h, a, amps):
    """The tunnel's up-going plane wave at (ξ, k_y) and its free-surface reflection, at z = 0.

    Returns (k, ν_p, ν_s, δ_s, ρ_ps, φ0, a_S, a_T, b_P, b_Q): the P amplitude φ0, the SV
    amplitude a_S (W = k a_S) and the SH displacement a_T = u_t of the incident wave; b_P, b_Q
    of the reflected P-SV wave (the reflected SH wave is a_T e^{−ν_s z}).
    """
    amp_p, amp_sv, amp_sh, inverse_ratio_p, inverse_ratio_s, alpha, beta, k0_p, k0_s = amps
    k = math.sqrt(q * q + ky * ky)
    nu_p, nu_s, delta_s, ratio = vertical_wavenumbers(k, kp2, ks2, gamma2)
    s_p, s_sv, s_sh = _potential_sums(
        ky,
        nu_p,
        nu_s,
        alpha[i],
        beta[i],
        amp_p[i],
        amp_sv[i],
        amp_sh[i],
        inverse_ratio_p[i],
        inverse_ratio_s[i],
    )
    # 1/K_n(za) = e^{za}/(K₀(za)e^{za} Π R_m): the e^{za} joins the plane-wave exponent
    phi0 = math.pi / k0_p[i] / nu_p * cmath.exp(-nu_p * h + alpha[i] * a) * s_p
    shear_wave = math.pi / k0_s[i] / nu_s * cmath.exp(-nu_s * h + beta[i] * a)
    psi0, chi0 = shear_wave * s_sv, shear_wave * s_sh
    a_s = 1j * (ky * psi0 - q * nu_s * chi0) / k
    a_t = (q * nu_s * psi0 - ky * ks2 * chi0) / k
    # in the regular basis: a'_P = a_P + a_S, a'_Q = δ_s a_S (S(+) = P(+) + δ_s Q(+))
    b_p, b_q = reflect_at_surface(phi0 + a_s, delta_s * a_s, k, nu_p, nu_s, delta_s, ratio, ks2)
    return k, nu_p, nu_s, delta_s, ratio, phi0, a_s, a_t, b_p, b_q


@numba.njit(cache=True, nogil=True, parallel=True)
def surface_kernel(omega, xi, y, z, h, a, amps, shear, lame, density, features, widths,
                   incident, reflected, refine):  # fmt: skip
    """u_z(ω_i, ξ_i; y_j, z_m) above the tunnel axis (z < H): incident and/or reflected parts.

    amps: :func:`cavity_amplitudes`; features, widths (n_pairs, 3): Re and |Im| of k_p, k_s,
    k_R. Returns complex (n_pairs, n_y, n_z).
    """
    out = np.zeros((omega.size, y.size, z.size), np.complex128)
    lam2mu = lame + 2.0 * shear
    gamma2 = shear / lam2mu
    decay = h - a - z.max() if incident else h - a + z.min()
    y_max = np.abs(y).max()
    for i in numba.prange(omega.size):
        q = abs(xi[i])
        kp2 = omega[i] ** 2 * density / lam2mu
        ks2 = omega[i] ** 2 * density / shear
        if cmath.sqrt(q * q - ks2).real * decay > DECAY_EXPONENT:
            continue
        edges = ky_panel_edges(q, features[i], widths[i], decay, y_max, refine)
        for p in range(edges.size - 1):
            half, mid = 0.5 * (edges[p + 1] - edges[p]), 0.5 * (edges[p + 1] + edges[p])
            for g in range(_GL_ORDER):
                ky = mid + half * _GL_NODES[g]
                weight = half * _GL_WEIGHTS[g] / math.pi
                k, nu_p, nu_s, delta_s, ratio, phi0, a_s, _, b_p, b_q = _plane_wave_node(
                    i, q, ky, kp2, ks2, gamma2, h, a, amps
                )
                for m in range(z.size):
                    value = 0j
                    if reflected:
                        value += downgoing_uw(b_p, b_q, z[m], k, nu_p, nu_s, delta_s, ratio)[1]
                    if incident:
                        value += nu_p * phi0 * cmath.exp(nu_p * z[m])
                        value += k * a_s * cmath.exp(nu_s * z[m])
                    for j in range(y.size):
                        out[i, j, m] += weight * math.cos(ky * y[j]) * value
    return out


@numba.njit(cache=True, nogil=True)
def _below_invert_coefficients(q, ky, k, nu_p, nu_s, delta_s, ratio, a_t, b_p, b_q, shear,
                               lame, weight):  # fmt: skip
    """Weighted coefficients (of e^{−ν_p z}, of D(z)) of u_z, σ_zz, σ_yy, σ_xx, σ_zx, (5, 2).

    Every field of the reflected wave is linear in e^{−ν_p z} and D(z)
    (``model.soil.halfspace_kernels.downgoing_from_exponentials``; SH: a_T e^{−ν_s z} =
    a_T (e^{−ν_p z} + δ_s D)); u_s = −iU, (u_x, u_y) the rotation of (u_s, u_t) by the wave
    direction, σ = λ* tr ε I + 2μ* ε.
    """
    c = np.empty((5, 2), np.complex128)
    for j in range(2):  # j = 0: the e^{−ν_p z} part, 1: the D(z) part
        if j == 0:
            u = b_p * k + b_q
            w = -b_p * nu_p + b_q * ratio
            du = -nu_p * b_p * k - b_q * (nu_s + (1.0 - ratio) * k)
            dw = nu_p * nu_p * b_p - b_q * (nu_s * ratio - (1.0 - ratio) * nu_p)
            u_t = a_t
        else:
            u = -b_q * nu_s
            w = b_q * k
            du = b_q * nu_s * nu_s
            dw = -b_q * nu_s * k
            u_t = a_t * delta_s
        cs, sn = q / k, ky / k
        u_x = cs * (-1j * u) - sn * u_t
        u_y = sn * (-1j * u) + cs * u_t
        du_x = cs * (-1j * du) + sn * nu_s * u_t
        e_xx = -1j * q * u_x
        e_yy = -1j * ky * u_y
        volumetric = lame * (e_xx + e_yy + dw)
        c[0, j] = weight * w
        c[1, j] = weight * (volumetric + 2.0 * shear * dw)
        c[2, j] = weight * (volumetric + 2.0 * shear * e_yy)
        c[3, j] = weight * (volumetric + 2.0 * shear * e_xx)
        c[4, j] = weight * shear * (du_x - 1j * q * w)
    return c


@numba.njit(cache=True, nogil=True, parallel=True)
def below_invert_kernel(omega, xi, z, h, a, amps, shear, lame, density, features, widths, refine):
    """The reflected field on the vertical through the axis (y = 0) at increasing depths z.

    Returns complex (5, n_pairs, n_z): u_z, σ_zz, σ_yy, σ_xx, σ_zx (at x = 0), i.e. u_r, σ_rr,
    σ_θθ, σ_xx, σ_rx of the shell model's frame at θ = 0 (σ_zy = σ_xy = 0 by symmetry). On
    equally spaced depths the exponentials go by the recurrences e^{−ν_p(z+Δ)} = e^{−ν_p z}
    e^{−ν_p Δ} and D(z + Δ) = e^{−ν_s Δ} D(z) + e^{−ν_p z} D(Δ) (both stable: |e^{−νΔ}| ≤ 1).
    """
    out = np.zeros((5, omega.size, z.size), np.complex128)
    lam2mu = lame + 2.0 * shear
    gamma2 = shear / lam2mu
    decay = h - a + z[0]
    step = z[1] - z[0] if z.size > 1 else 0.0
    uniform = z.size > 2 and np.max(np.abs(np.diff(z) - step)) <= 1e-12 * z[-1]
    for i in numba.prange(omega.size):
        q = abs(xi[i])
        kp2 = omega[i] ** 2 * density / lam2mu
        ks2 = omega[i] ** 2 * density / shear
        if cmath.sqrt(q * q - ks2).real * decay > DECAY_EXPONENT:
            continue
        # panels twice as wide as the surface's: four periods per 12-point panel leave an
        # error ≲ 2e-6 of the full-space field below the invert (tests), at half the cost
        edges = ky_panel_edges(q, features[i], widths[i], decay, 0.0, 0.5 * refine)
        for p in range(edges.size - 1):
            half, mid = 0.5 * (edges[p + 1] - edges[p]), 0.5 * (edges[p + 1] + edges[p])
            for g in range(_GL_ORDER):
                ky = mid + half * _GL_NODES[g]
                weight = half * _GL_WEIGHTS[g] / math.pi
                k, nu_p, nu_s, delta_s, ratio, _, _, a_t, b_p, b_q = _plane_wave_node(
                    i, q, ky, kp2, ks2, gamma2, h, a, amps
                )
                coefficients = _below_invert_coefficients(
                    q, ky, k, nu_p, nu_s, delta_s, ratio, a_t, b_p, b_q, shear, lame, weight
                )
                e_p, d_z = divided_difference(z[0], nu_p, delta_s, ratio)
                if uniform:
                    step_p, step_d = divided_difference(step, nu_p, delta_s, ratio)
                    step_s = step_p + delta_s * step_d
                for m in range(z.size):
                    if m > 0:
                        if uniform:
                            e_p, d_z = e_p * step_p, step_s * d_z + e_p * step_d
                        else:
                            e_p, d_z = divided_difference(z[m], nu_p, delta_s, ratio)
                    for c in range(5):
                        out[c, i, m] += coefficients[c, 0] * e_p + coefficients[c, 1] * d_z
    return out


# ---- wrappers: parameter objects in, checked arrays out ----------------------------------------
def _pip_setup(freq_hz, wavenumber_rad_per_m, tunnel, soil, n_harmonics):
    """Checked pairs, the cavity amplitudes and the real-axis features of every pair."""
    omega, xi = paired_inputs(freq_hz, wavenumber_rad_per_m)
    xi = np.abs(xi)  # the response is even in ξ
    a, mass, extensional, bending = ring_constants(tunnel)
    shear, lame, density = soil_constants(soil)
    h = float(tunnel.axis_depth)
    if not h > a:
        raise ValueError(
            f"tunnel.axis_depth = {h:g} m must exceed the ring radius a = {a:g} m: the tunnel "
            "must lie below the ground surface"
        )
    if soil.shear_loss_factor <= 0.0:
        raise ValueError(
            "soil.shear_loss_factor = 0: the half-space's Rayleigh pole lies on the real "
            "wavenumber axis without damping; the half-space model needs "
            "soil.shear_loss_factor > 0"
        )
    coefficients = invert_load_coefficients(a, check_harmonics(n_harmonics))
    amps = cavity_amplitudes(
        omega, xi, coefficients, a, mass, extensional, bending, float(tunnel.poisson_ratio),
        shear, lame, density,
    )  # fmt: skip
    freq = omega / (2.0 * np.pi)
    waves = [omega * np.sqrt(density / (lame + 2.0 * shear)), omega * np.sqrt(density / shear)]
    waves.append(rayleigh_wavenumber(freq, soil))
    features = np.ascontiguousarray(np.stack([k.real for k in waves], axis=1))
    widths = np.ascontiguousarray(np.stack([np.abs(k.imag) for k in waves], axis=1))
    return omega, xi, amps, (shear, lame, density), features, widths, h, a


def _finite(values, what: str):
    """``values``, refused (ValueError) when not finite."""
    if not np.all(np.isfinite(values)):
        raise ValueError(
            f"the half-space {what} is not finite; check the inputs (extreme frequency, "
            "wavenumber, axis depth or parameters)"
        )
    return values


def field_above_axis(freq_hz, wavenumber_rad_per_m, y_m, z_m, tunnel, soil, n_harmonics: int,
                     part: str = "total", refine: float = 1.0) -> np.ndarray:  # fmt: skip
    """Vertical displacement (down +) above the tunnel axis per unit invert line load.

    u_z(ω, ξ; y, z) at (x = 0, y, z), z < H, per unit downward line load (N/m) on the invert
    varying as exp(i(ωt − ξx)): the full-space tunnel's field ("incident", by its plane waves),
    the field the free surface reflects ("reflected", valid at any depth), or their sum
    ("total", the pipe-in-pipe half-space field).

    Parameters
    ----------
    freq_hz, wavenumber_rad_per_m : float or array_like
        Paired frequencies (Hz, > 0) and wavenumbers ξ along the tunnel (rad/m); ξ = ω/v for a
        train at speed v.
    y_m : array_like
        (n_y,) horizontal distances from the tunnel axis (m).
    z_m : array_like
        (n_z,) depths below the ground surface (m), 0 ≤ z < H ("reflected": any z ≥ 0).
    tunnel : model.params.Tunnel
        Lining and ``axis_depth`` H.
    soil : model.params.Soil
        Soil, η_G > 0.
    n_harmonics : int
        Highest ring harmonic N ≥ 0.
    part : {"total", "incident", "reflected"}
        Which field.
    refine : float
        Divides the k_y panel width (convergence checks), ≥ 1.

    Returns
    -------
    ndarray
        Complex (n_pairs, n_y, n_z) in m per N/m, exp(+iωt).
    """
    omega, xi, amps, moduli, features, widths, h, a = _pip_setup(
        freq_hz, wavenumber_rad_per_m, tunnel, soil, n_harmonics
    )
    y = np.ascontiguousarray(np.abs(as_1d(y_m, "y_m", "m")))
    z = np.ascontiguousarray(as_1d(z_m, "z_m", "m"))
    incident, reflected = {"total": (1, 1), "incident": (1, 0), "reflected": (0, 1)}[part]
    if np.any(z < 0.0) or (incident and np.any(z >= h - a)):
        raise ValueError(
            f"z_m must lie between the ground surface (0 m) and the tunnel crown "
            f"(H − a = {h - a:g} m) for the {part} field"
        )
    return _finite(
        surface_kernel(
            omega, xi, y, z, h, a, amps, *moduli, features, widths, incident, reflected,
            float(refine),
        ),
        "field above the tunnel",
    )  # fmt: skip


def surface_receptance(freq_hz, wavenumber_rad_per_m, y_m, tunnel, soil, n_harmonics: int,
                       refine: float = 1.0) -> np.ndarray:  # fmt: skip
    """Ground-surface vertical displacement (down +) per unit invert line load (m per N/m).

    :func:`field_above_axis` at z = 0, complex (n_pairs, n_y). For a train at speed v the
    surface displacement spectrum is U(ω, y) = surface_receptance(f, ω/v, y) · Q(ω), Q the
    invert line-load spectrum (docs/model.md §9), and the velocity iωU.
    """
    return field_above_axis(
        freq_hz, wavenumber_rad_per_m, y_m, 0.0, tunnel, soil, n_harmonics, "total", refine
    )[:, :, 0]


def reflected_below_invert(freq_hz, wavenumber_rad_per_m, depth_m, tunnel, soil,
                           n_harmonics: int, refine: float = 1.0):  # fmt: skip
    """The free-surface reflected field below the invert per unit invert line load.

    At depth d below the ring–soil interface under the invert (y = 0, z = H + a + d, x = 0):
    the vertical displacement and the stresses σ_rr = σ_zz, σ_θθ = σ_yy, σ_xx, σ_rx = σ_zx of
    the reflected field (σ_rθ = σ_θx = 0 by symmetry), to be added to the full-space tunnel's
    (docs/halfspace.md, the pipe-in-pipe field).

    Parameters
    ----------
    freq_hz, wavenumber_rad_per_m : float or array_like
        Paired frequencies (Hz, > 0) and wavenumbers (rad/m).
    depth_m : float or array_like
        (n_depth,) depths d ≥ 0 below the ring–soil interface (m).
    tunnel, soil : model.params.Tunnel, model.params.Soil
        Lining with its ``axis_depth``, and soil.
    n_harmonics : int
        Highest ring harmonic N ≥ 0.
    refine : float
        Divides the k_y panel width (convergence checks).

    Returns
    -------
    (ndarray, dict)
        Complex (n_pairs, n_depth) displacement (m per N/m) and the four stresses by
        ``model.soil.moving_load_2p5d.StressField`` name (Pa per N/m, tension positive).
    """
    omega, xi, amps, moduli, features, widths, h, a = _pip_setup(
        freq_hz, wavenumber_rad_per_m, tunnel, soil, n_harmonics
    )
    z = np.ascontiguousarray(h + a + checked_depths(depth_m))
    fields = _finite(
        below_invert_kernel(omega, xi, z, h, a, amps, *moduli, features, widths, float(refine)),
        "field below the invert",
    )
    return fields[0], dict(zip(REFLECTED_STRESSES, fields[1:], strict=True))
