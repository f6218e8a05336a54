"""Modified Bessel functions K_n of complex argument, as the tunnel–soil kernels use them.

Only K₀ and K₁ are evaluated, exponentially scaled (:func:`bessel_k01_scaled`: power series for
|z| ≤ 2, Steed's continued fraction between, Hankel's asymptotic series for |z| ≥ 20). Higher
orders follow from the forward recurrence of the ratio

    R_n(z) = K_{n+1}(z)/K_n(z) = 1/R_{n−1}(z) + 2n/z,

which is stable for K and is written once, in :func:`next_ratio` (tabulated at the ring radius by
:func:`bessel_ratios`). The fields of the 2D section (``model.soil.section_2d``) and of the 2.5D
moving-load model (``model.soil.moving_load_2p5d``) are formed from

- the radial functions e_n(r) = K_n(z r)/K_n(z a), which neither overflow at low frequency nor
  underflow at depth: e_0 from :func:`radial_start`, then e_{n+1} = e_n R_n(zr)/R_n(za);
- the small log-derivative δ_n = z K_{n−1}(z)/K_n(z) = z/R_{n−1} (z R_0 = z K₁/K₀ for n = 0),
  from the same ratios (:func:`log_derivative` at the ring radius).
"""

from __future__ import annotations

import cmath
import math

import numba

EULER_GAMMA = 0.5772156649015329

# |z| below which K₀, K₁ come from their power series (no cancellation there: the series terms
# stay below ~e^|z| ≈ 7 times the result), and above which from the asymptotic series (whose
# smallest term, ~e^(−2|z|), is below 1e-17 there). Steed's continued fraction covers between.
_SERIES_MAX_ABS_Z = 2.0
_ASYMPTOTIC_MIN_ABS_Z = 20.0
# Relative size (squared) of the last term kept in every series / continued fraction.
_TERM_TOLERANCE_SQ = 1e-34


# ---- Bessel functions K₀, K₁ of complex argument, exponentially scaled ------------------------
@numba.njit(cache=True)
def _abs2(z):
    """Squared modulus of a complex number."""
    return z.real * z.real + z.imag * z.imag


@numba.njit(cache=True)
def reciprocal(z):
    """1/z, cheaper than a general complex division."""
    scale = 1.0 / _abs2(z)
    return complex(z.real * scale, -z.imag * scale)


@numba.njit(cache=True)
def _k01_series(z):
    """(K₀(z) eᶻ, K₁(z) eᶻ) from the ascending series (DLMF 10.31.1–2), for |z| ≤ 2."""
    quarter_z2 = 0.25 * z * z
    log_half_z = cmath.log(0.5 * z)
    term0 = 1.0 + 0j  # (z²/4)^k / (k!)²
    term1 = 1.0 + 0j  # (z²/4)^k / (k! (k+1)!)
    i0 = term0
    sum0 = 0j
    i1_over_half_z = term1
    sum1 = (1.0 - 2.0 * EULER_GAMMA) * term1  # ψ(1) + ψ(2)
    harmonic = 0.0
    for k in range(1, 60):
        term0 = term0 * quarter_z2 * (1.0 / (k * k))
        term1 = term1 * quarter_z2 * (1.0 / (k * (k + 1)))
        harmonic += 1.0 / k
        i0 += term0
        sum0 += harmonic * term0
        i1_over_half_z += term1
        sum1 += (2.0 * harmonic + 1.0 / (k + 1) - 2.0 * EULER_GAMMA) * term1
        if _abs2(term0) < _TERM_TOLERANCE_SQ * _abs2(i0):
            break
    k0 = -(log_half_z + EULER_GAMMA) * i0 + sum0
    k1 = 1.0 / z + log_half_z * (0.5 * z * i1_over_half_z) - 0.25 * z * sum1
    scale = cmath.exp(z)
    return k0 * scale, k1 * scale


@numba.njit(cache=True)
def _k01_continued_fraction(z):
    """(K₀(z) eᶻ, K₁(z) eᶻ) by Steed's method for Temme's CF2, for 2 < |z| < 20, Re z ≥ 0."""
    b = 2.0 * (1.0 + z)
    d = 1.0 / b
    h = d
    delh = d
    q1 = 0j
    q2 = 1.0 + 0j
    a1 = 0.25
    q = a1 + 0j
    c = a1 + 0j
    a = -a1
    s = 1.0 + q * delh
    for i in range(2, 2000):
        a -= 2.0 * (i - 1)
        c = c * (-a / i)
        q_new = (q1 - b * q2) * (1.0 / a)
        q1 = q2
        q2 = q_new
        q += c * q_new
        b += 2.0
        d = reciprocal(b + a * d)
        delh = (b * d - 1.0) * delh
        h += delh
        ds = q * delh
        s += ds
        if _abs2(ds) < _TERM_TOLERANCE_SQ * _abs2(s):
            break
    k0 = cmath.sqrt(math.pi / (2.0 * z)) / s
    return k0, k0 * (z + 0.5 - a1 * h) / z


@numba.njit(cache=True)
def _k01_asymptotic(z):
    """(K₀(z) eᶻ, K₁(z) eᶻ) from Hankel's asymptotic series (DLMF 10.40.2), for |z| ≥ 20."""
    inv_z = 1.0 / z
    term0 = 1.0 + 0j
    term1 = 1.0 + 0j
    sum0 = term0
    sum1 = term1
    for k in range(1, 80):
        odd_sq = (2.0 * k - 1.0) ** 2
        term0 = term0 * inv_z * (-odd_sq / (8.0 * k))
        term1 = term1 * inv_z * ((4.0 - odd_sq) / (8.0 * k))
        sum0 += term0
        sum1 += term1
        if _abs2(term0) + _abs2(term1) < _TERM_TOLERANCE_SQ:
            break
    prefactor = cmath.sqrt(0.5 * math.pi * inv_z)
    return prefactor * sum0, prefactor * sum1


@numba.njit(cache=True)
def bessel_k01_scaled(z):
    """(K₀(z) eᶻ, K₁(z) eᶻ) for complex z ≠ 0 with Re z ≥ 0; relative error ≲ 1e-14."""
    abs2 = _abs2(z)
    if abs2 <= _SERIES_MAX_ABS_Z**2:
        return _k01_series(z)
    if abs2 >= _ASYMPTOTIC_MIN_ABS_Z**2:
        return _k01_asymptotic(z)
    return _k01_continued_fraction(z)


# ---- orders n ≥ 2: the ratio recurrence ---------------------------------------------------------
@numba.njit(cache=True)
def next_ratio(ratio, n, two_over_z):
    """(1/R_n, R_{n+1}) from R_n = K_{n+1}(z)/K_n(z) and 2/z: R_{n+1} = 1/R_n + 2(n + 1)/z."""
    recip = reciprocal(ratio)
    return recip, recip + (n + 1) * two_over_z


@numba.njit(cache=True)
def bessel_ratios(z, n_max, out):
    """out[m] = K_{m+1}(z)/K_m(z), m = 0..n_max (forward recurrence); returns K₀(z) eᶻ."""
    k0, k1 = bessel_k01_scaled(z)
    ratio = k1 / k0
    two_over_z = 2.0 / z
    for m in range(n_max + 1):
        out[m] = ratio
        ratio = next_ratio(ratio, m, two_over_z)[1]
    return k0


@numba.njit(cache=True)
def log_derivative(z, ratios, n):
    """δ_n = z K_{n−1}(z)/K_n(z) (z K₁(z)/K₀(z) for n = 0) from ``bessel_ratios(z)``'s table."""
    if n == 0:
        return z * ratios[0]
    return z * reciprocal(ratios[n - 1])


@numba.njit(cache=True)
def radial_start(z, r, a, k0_scaled_a):
    """(e_0, R_0, 2/(z r)) at radius r: e_0 = K₀(z r)/K₀(z a), R_0 = K₁(z r)/K₀(z r).

    ``k0_scaled_a`` is K₀(z a) eᶻᵃ (returned by :func:`bessel_ratios`). At r = a, e_0 is 1
    exactly: a complex x/x can be off by an ulp, which the kernels' differences of radial
    functions (e_P − e_S) would amplify.
    """
    zr = z * r
    k0, k1 = bessel_k01_scaled(zr)
    if r == a:
        e = 1.0 + 0j
    else:
        e = k0 / k0_scaled_a * cmath.exp(-z * (r - a))
    return e, k1 / k0, 2.0 / zr
