"""Plane-wave kernels of the homogeneous half-space: free-surface reflection in a regular basis.

Coordinates x, y horizontal, z **down** from the free surface z = 0; time convention exp(+iωt);
horizontal wavenumbers (ξ, k_y), fields ∝ exp(−i(ξx + k_y y)), k = √(ξ² + k_y²). Soil μ*, λ*
(hysteretic, complex), ρ; k_p² = ρω²/(λ* + 2μ*), k_s² = ρω²/μ*, γ² = μ*/(λ* + 2μ*).

Per k the problem splits into P-SV (u_s along the horizontal wave vector, u_z) and SH (u_t,
t = e_z × s). Vertical wavenumbers ν_j = √(k² − k_j²), principal root (Re ν ≥ 0: outgoing or
decaying). The P-SV part is written in U = i u_s and W = u_z, in which every coefficient is a
real expression of k, ν_p, ν_s (complex only through the moduli).

Regular basis. At ω → 0 the P and SV plane waves become parallel (ν_p, ν_s → k), and the
classical reflection coefficients grow like (k/k_s)² with cancelling source amplitudes ∝ 1/ω²,
a loss of ~(k/k_s)⁴ in precision. The basis here is

    P(σ) = (k, σν_p) e^{σν_p z},   Q(σ) = (S(σ) − σP(σ))/δ_s,   S(σ) = (σν_s, k) e^{σν_s z},

σ = +1 up-going, −1 down-going, δ_j = k − ν_j = k_j²/(k + ν_j) (formed without cancellation),
ρ_ps = δ_p/δ_s = γ²(k + ν_s)/(k + ν_p). Q stays independent of P at ω = 0 (it becomes the
static z e^{−kz} solution). With the divided difference

    D(h) = (e^{−ν_s h} − e^{−ν_p h})/δ_s = e^{−ν_p h} (1 − ρ_ps) h E₁((δ_s − δ_p) h),
    E₁(x) = (eˣ − 1)/x,

every quantity is O(1) at any frequency, ω = 0 included (k > 0), where the half-space field
is Mindlin's.

Point force at depth c (unit force; up-going side z < c): for F_z, c_P = 1/(2μν_s(k + ν_s)),
c_Q = k c_P; for F_U = −iF_s, c_P = −1/(2(λ + 2μ)ν_p(k + ν_p)), c_Q = 1/(2μ(k + ν_s)). The
full-space (Stokes) field is c_P P(+)(z − c) + c_Q Q(+)(z − c) above the source and its mirror
image below (W even and U odd in z − c for F_z; U even and W odd for F_U). The up-going field
re-expanded about z = 0 has a_P = c_P e^{−ν_p c} + c_Q D(c), a_Q = c_Q e^{−ν_s c}, and the
traction-free surface (τ_zz = τ_zs = 0, in the traction variables (iτ_zs, τ_zz)/μ)

    [−2kν_p   2kρ_ps − k − ν_s] [b_P]      [2kν_p   2kρ_ps − k − ν_s] [a_P]
    [  χ            δ_s       ] [b_Q]  = − [  χ           −δ_s       ] [a_Q],   χ = 2k² − k_s²,

gives the reflected field b_P P(−)(z) + b_Q Q(−)(z); its determinant vanishes at the Rayleigh
pole. SH: u_t reflects with coefficient 1 (τ_zt = μ ∂_z u_t = 0), Ĝ_tt = (e^{−ν_s|z−c|} +
e^{−ν_s(z+c)})/(2μν_s).

A layer over a stiffer base (docs/halfspace.md, "Layered ground") replaces the 2 × 2 surface
condition by the reflection matrix of the layer stack, built in the same regular basis per layer.
"""

from __future__ import annotations

import cmath
import math

import numba
import numpy as np


@numba.njit(cache=True, nogil=True)
def expm1_over_x(x):
    """E₁(x) = (eˣ − 1)/x for complex x, E₁(0) = 1, relative error ~1e-16."""
    if abs(x) < 0.1:
        term = 1.0 + 0j
        total = 1.0 + 0j
        for n in range(2, 12):
            term = term * x / n
            total += term
        return total
    return (cmath.exp(x) - 1.0) / x


@numba.njit(cache=True, nogil=True)
def vertical_wavenumbers(k, kp2, ks2, gamma2):
    """(ν_p, ν_s, δ_s, ρ_ps) at horizontal wavenumber k ≥ 0 (module docstring)."""
    nu_p = cmath.sqrt(k * k - kp2)
    nu_s = cmath.sqrt(k * k - ks2)
    delta_s = ks2 / (k + nu_s)
    ratio = gamma2 * (k + nu_s) / (k + nu_p)
    return nu_p, nu_s, delta_s, ratio


@numba.njit(cache=True, nogil=True)
def divided_difference(h, nu_p, delta_s, ratio):
    """(e^{−ν_p h}, D(h)), D(h) = (e^{−ν_s h} − e^{−ν_p h})/δ_s for h ≥ 0, stable as ω → 0.

    With x = (δ_s − δ_p) h = (ν_p − ν_s) h: the E₁ form for |x| < 1 (no cancellation), the
    difference of the exponentials beyond (no overflow of eˣ).
    """
    e_p = cmath.exp(-nu_p * h)
    one_minus = 1.0 - ratio
    x = delta_s * one_minus * h
    if abs(x) < 1.0:
        return e_p, e_p * one_minus * h * expm1_over_x(x)
    nu_s = nu_p - delta_s * one_minus  # ν_s = ν_p − (δ_s − δ_p)
    return e_p, (cmath.exp(-nu_s * h) - e_p) / delta_s


@numba.njit(cache=True, nogil=True)
def reflect_at_surface(a_p, a_q, k, nu_p, nu_s, delta_s, ratio, ks2):
    """(b_P, b_Q) of the down-going field that the free surface reflects from a_P P(+) + a_Q Q(+).

    Both fields referenced to z = 0 (module docstring, the traction-free surface).
    """
    chi = 2.0 * k * k - ks2
    m11 = -2.0 * k * nu_p
    m12 = 2.0 * k * ratio - k - nu_s
    det = m11 * delta_s - chi * m12
    r1 = m11 * a_p - m12 * a_q  # −(2kν_p a_P + m12 a_Q)
    r2 = delta_s * a_q - chi * a_p
    return (r1 * delta_s - m12 * r2) / det, (m11 * r2 - chi * r1) / det


@numba.njit(cache=True, nogil=True)
def downgoing_uw(b_p, b_q, z, k, nu_p, nu_s, delta_s, ratio):
    """(U, W, ∂U/∂z, ∂W/∂z) at depth z of the down-going field b_P P(−) + b_Q Q(−)."""
    e_p, d_z = divided_difference(z, nu_p, delta_s, ratio)
    return downgoing_from_exponentials(b_p, b_q, e_p, d_z, k, nu_p, nu_s, ratio)


@numba.njit(cache=True, nogil=True)
def downgoing_from_exponentials(b_p, b_q, e_p, d_z, k, nu_p, nu_s, ratio):
    """(U, W, ∂U/∂z, ∂W/∂z) of b_P P(−) + b_Q Q(−) from e^{−ν_p z} and D(z).

    P(−) = (k, −ν_p) e^{−ν_p z}, Q(−) = (e^{−ν_p z} − ν_s D, k D + ρ_ps e^{−ν_p z}); their
    derivatives ∂P(−) = −ν_p P(−), ∂Q(−) = −ν_s Q(−) − (1 − ρ_ps) P(−) (regular as ω → 0).
    """
    pu, pw = k * e_p, -nu_p * e_p
    qu, qw = e_p - nu_s * d_z, k * d_z + ratio * e_p
    u = b_p * pu + b_q * qu
    w = b_p * pw + b_q * qw
    coupling = 1.0 - ratio
    du = -nu_p * b_p * pu - b_q * (nu_s * qu + coupling * pu)
    dw = -nu_p * b_p * pw - b_q * (nu_s * qw + coupling * pw)
    return u, w, du, dw


@numba.njit(cache=True, nogil=True)
def _source_coefficients(k, nu_p, nu_s, mu, lam2mu):
    """(c_P, c_Q) of unit forces F_U and F_z (module docstring), up-going side."""
    cu_p = -1.0 / (2.0 * lam2mu * nu_p * (k + nu_p))
    cu_q = 1.0 / (2.0 * mu * (k + nu_s))
    cz_p = 1.0 / (2.0 * mu * nu_s * (k + nu_s))
    return cu_p, cu_q, cz_p, k * cz_p


@numba.njit(cache=True, nogil=True)
def psv_reflected(k, z, c, kp2, ks2, gamma2, mu, lam2mu):
    """Free-surface reflected field at depth z of unit forces at depth c, wavenumber k.

    Returns (G_UU, G_UW, G_WU, G_WW, G_tt): U = i u_s, W = u_z per F_U = −iF_s (first index
    the response) and per F_z; G_tt the reflected SH part u_t per F_t (m/N · m², wavenumber
    domain).
    """
    nu_p, nu_s, delta_s, ratio = vertical_wavenumbers(k, kp2, ks2, gamma2)
    ep_c, d_c = divided_difference(c, nu_p, delta_s, ratio)
    es_c = cmath.exp(-nu_s * c)
    cu_p, cu_q, cz_p, cz_q = _source_coefficients(k, nu_p, nu_s, mu, lam2mu)
    bu_p, bu_q = reflect_at_surface(
        cu_p * ep_c + cu_q * d_c, cu_q * es_c, k, nu_p, nu_s, delta_s, ratio, ks2
    )
    bz_p, bz_q = reflect_at_surface(
        cz_p * ep_c + cz_q * d_c, cz_q * es_c, k, nu_p, nu_s, delta_s, ratio, ks2
    )
    g_uu, g_wu, _, _ = downgoing_uw(bu_p, bu_q, z, k, nu_p, nu_s, delta_s, ratio)
    g_uw, g_ww, _, _ = downgoing_uw(bz_p, bz_q, z, k, nu_p, nu_s, delta_s, ratio)
    g_tt = cmath.exp(-nu_s * (z + c)) / (2.0 * mu * nu_s)
    return g_uu, g_uw, g_wu, g_ww, g_tt


@numba.njit(cache=True, nogil=True)
def psv_fullspace(k, z, c, kp2, ks2, gamma2, mu, lam2mu):
    """Full-space (Stokes) field at depth z of unit forces at depth c, wavenumber k.

    Same outputs as :func:`psv_reflected`; z ≠ c or k > 0. Above the source the field is
    c_P P(+)(z − c) + c_Q Q(+)(z − c), below it the mirror image (the U–W couplings change sign).
    """
    nu_p, nu_s, delta_s, ratio = vertical_wavenumbers(k, kp2, ks2, gamma2)
    e_p, d_h = divided_difference(abs(z - c), nu_p, delta_s, ratio)
    sign = 1.0 if z <= c else -1.0
    # the up-going basis at z − c = −h: P(+) = (k, ν_p) e_p, Q(+) = (ν_s D − e_p, k D + ρ e_p)
    pu, pw = k * e_p, nu_p * e_p
    qu, qw = nu_s * d_h - e_p, k * d_h + ratio * e_p
    cu_p, cu_q, cz_p, cz_q = _source_coefficients(k, nu_p, nu_s, mu, lam2mu)
    g_uu = cu_p * pu + cu_q * qu
    g_wu = sign * (cu_p * pw + cu_q * qw)
    g_uw = sign * (cz_p * pu + cz_q * qu)
    g_ww = cz_p * pw + cz_q * qw
    g_tt = cmath.exp(-nu_s * abs(z - c)) / (2.0 * mu * nu_s)
    return g_uu, g_uw, g_wu, g_ww, g_tt


@numba.njit(cache=True, nogil=True)
def _to_cartesian(xi, ky, g_uu, g_uw, g_wu, g_ww, g_tt, out):
    """Rotate the (U, W; t) kernels of wavenumber (ξ, k_y) into the Cartesian 3 × 3 ``out``."""
    k = math.sqrt(xi * xi + ky * ky)
    cs, sn = (xi / k, ky / k) if k > 0.0 else (1.0, 0.0)
    g_ss = -g_uu  # u_s = −iU per F_s = iF_U
    g_sz = -1j * g_uw
    g_zs = -1j * g_wu
    out[0, 0] = cs * cs * g_ss + sn * sn * g_tt
    out[0, 1] = cs * sn * (g_ss - g_tt)
    out[1, 0] = out[0, 1]
    out[1, 1] = sn * sn * g_ss + cs * cs * g_tt
    out[0, 2] = cs * g_sz
    out[1, 2] = sn * g_sz
    out[2, 0] = cs * g_zs
    out[2, 1] = sn * g_zs
    out[2, 2] = g_ww


@numba.njit(cache=True, nogil=True)
def greens_tensor_kernel(omega, xi, ky, z, c, mu, lam, rho, part):
    """Cartesian Ĝ_ij(ω, ξ, k_y, z; c), complex (n, n_z, 3, 3); part 0 total, 1 full, 2 reflected.

    omega, xi, ky paired (n,) arrays (rad/s, rad/m); z (n_z,) receiver depths, c the source
    depth (m); mu, lam complex moduli (Pa), rho (kg/m³).
    """
    out = np.zeros((omega.size, z.size, 3, 3), np.complex128)
    lam2mu = lam + 2.0 * mu
    gamma2 = mu / lam2mu
    for i in range(omega.size):
        kp2 = omega[i] ** 2 * rho / lam2mu
        ks2 = omega[i] ** 2 * rho / mu
        k = math.sqrt(xi[i] * xi[i] + ky[i] * ky[i])
        for j in range(z.size):
            g = np.zeros(5, np.complex128)
            if part != 2:
                g += np.array(psv_fullspace(k, z[j], c, kp2, ks2, gamma2, mu, lam2mu))
            if part != 1:
                g += np.array(psv_reflected(k, z[j], c, kp2, ks2, gamma2, mu, lam2mu))
            _to_cartesian(xi[i], ky[i], g[0], g[1], g[2], g[3], g[4], out[i, j])
    return out


@numba.njit(cache=True, nogil=True)
def zz_radial_kernel(omega, k, z, c, mu, lam, rho, part):
    """Ĝ_zz(ω, k, z; c) on nodes k (n_k,) and depths z (n_z,); part 0 total, 1 full, 2 reflected.

    The vertical response to a vertical force depends on k = √(ξ² + k_y²) only (axisymmetry).
    """
    out = np.empty((k.size, z.size), np.complex128)
    lam2mu = lam + 2.0 * mu
    gamma2 = mu / lam2mu
    kp2 = omega * omega * rho / lam2mu
    ks2 = omega * omega * rho / mu
    for i in range(k.size):
        for j in range(z.size):
            value = 0j
            if part != 2:
                value += psv_fullspace(k[i], z[j], c, kp2, ks2, gamma2, mu, lam2mu)[3]
            if part != 1:
                value += psv_reflected(k[i], z[j], c, kp2, ks2, gamma2, mu, lam2mu)[3]
            out[i, j] = value
    return out
