"""Tunnel lining ring in an elastic full-space, per circumferential harmonic (docs/model.md §7).

Plane strain, polar coordinates (r, θ) about the tunnel axis, θ = 0 at the invert pointing
**down**, time convention exp(+iωt). Everything is in the outward notation: w = u_r(a) radial
(positive away from the axis), v = u_θ(a) tangential (positive towards increasing θ).

Ring (thin, radius a, K = Eh/(1−ν²), D = Eh³/(12(1−ν²)), mass m = ρh per unit arc length):
    −ω² m w = −(K/a²)(v′ + w) − (D/a⁴)(w'''' + 2w″ + w) + q_r + σ_rr(a)
    −ω² m v =  (K/a²)(v″ + w′) + q_θ + σ_rθ(a)
where σ_rr(a), σ_rθ(a) are the soil stresses at the interface: they are the traction the soil
exerts on the ring (the ring's outward normal is +e_r).

Soil: φ = f(r) cos nθ, ψ = g(r) sin nθ, u = ∇φ + ∇×(ψ e_z), so
    u_r = (f′ + n g/r) cos nθ,   u_θ = (−n f/r − g′) sin nθ,
f = A_P K_n(αr)/K_n(αa), g = A_S K_n(βr)/K_n(βa), α = iω/c₁*, β = iω/c₂*, with the complex
moduli μ* = μ(1 + iη_G), K* = K(1 + iη_K), λ* = K* − 2μ*/3. K_n of these arguments is the
outgoing wave (Re α, Re β > 0). Per harmonic, the two interface kinematic conditions
u_r(a) = W, u_θ(a) = V are substituted into the two ring equations, which leaves a 2×2 system
for the two soil amplitudes (the 4×4 of the paper with its two kinematic rows eliminated). For
n = 0 the SV potential does not enter (sin 0θ = 0) and the system is the 1×1 radial one; the
torsional n = 0 motion is not excited by a radial load and is omitted.

Conditioning at low frequency: as ωa/c → 0 the P and SV solutions of harmonic n ≥ 1 tend to
the same static field with opposite signs, and a stiff lining (K/a ≫ μ) would amplify the
cancellation. So the log-derivatives are written f′/f = −n/r − δ_P, g′/g = −n/r − δ_S with the
small δ_P = α K_{n−1}(αr)/K_n(αr) (δ_P = α K₁/K₀ for n = 0) formed directly, and the unknowns
are the amplitudes X of the P solution and Y of the sum P + SV (A_P = X + Y, A_S = Y), whose
coefficients are O(δ) expressions with the static parts cancelled analytically. The interface
values are then accurate to rounding at any frequency; at r > a the term Y (e_P − e_S), with
e = K_n(zr)/K_n(za), keeps a relative rounding error ~ε/(ωa/c₁)² (≈ 1e-10 at 1e-3 Hz for the
paper soil).

A downward line load F′ (N/m) at the invert is an outward radial load there, with Fourier
coefficients F′/(2πa) (n = 0) and F′/(πa) (n ≥ 1) per unit arc length.

Bessel functions: only K₀, K₁ are evaluated (exponentially scaled, power series / Steed's
continued fraction / asymptotic series); higher orders follow from the forward recurrence of the
ratio R_n = K_{n+1}/K_n = 1/R_{n−1} + 2n/z, which is stable for K, and all fields are formed from
ratios K_n(z r)/K_n(z a), which neither overflow at low frequency nor underflow at depth.

The 2D static response is infinite for n = 1 (it grows like ln 1/ω), so f = 0 is refused; see
``model.settlement`` for the zero-frequency bin.
"""

from __future__ import annotations

import cmath
import math
from dataclasses import dataclass

import numba
import numpy as np

from model.params import Soil, Tunnel

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
        d = _reciprocal(b + a * d)
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


# ---- ring–soil solution per harmonic ----------------------------------------------------------
@numba.njit(cache=True)
def _reciprocal(z):
    """1/z, cheaper than a general complex division."""
    scale = 1.0 / _abs2(z)
    return complex(z.real * scale, -z.imag * scale)


@numba.njit(cache=True)
def _displacement_terms(n, r, delta_p, delta_s):
    """U, V coefficients of the P solution and of the P + SV sum of harmonic n at r.

    With f′/f = −n/r − δ_P and g′/g = −n/r − δ_S (module docstring), the P solution
    (f = 1, g = 0) has U = f′ + n g/r, V = −n f/r − g′ and the sum (f = g = 1) the small,
    explicitly formed U = −δ_P, V = δ_S.
    """
    n_r = n / r
    return -n_r - delta_p, -n_r + 0j, -delta_p, delta_s


@numba.njit(cache=True)
def _normal_stress_parts(n, inv_r, delta_p, delta_s):
    """T of the P solution and of the P + SV sum at r, with S_rr = (λ* + 2μ*)α² + 2μ* T/r and
    S_θθ = λ*α² − 2μ* T/r (:func:`_stress_terms`): T_P = n(n + 1)/r + δ_P, T_sum = δ_P − n δ_S."""
    return n * (n + 1.0) * inv_r + delta_p, delta_p - n * delta_s


@numba.njit(cache=True)
def _stress_terms(n, r, alpha, beta, delta_p, delta_s, shear, lame):
    """S_rr, S_θθ, S_rθ coefficients of the P solution and of the P + SV sum at r.

    σ_rr = S_rr cos nθ, σ_θθ = S_θθ cos nθ, σ_rθ = S_rθ sin nθ; arguments as in
    :func:`_displacement_terms`, shear = μ*, lame = λ*. The leading static parts of P and SV
    cancel analytically in the sum, so its O(δ) terms keep full relative precision.
    """
    inv_r = 1.0 / r
    t_p, t_sum = _normal_stress_parts(n, inv_r, delta_p, delta_s)
    srr_p = (lame + 2.0 * shear) * alpha * alpha + 2.0 * shear * t_p * inv_r
    srr_sum = (lame + 2.0 * shear) * alpha * alpha + 2.0 * shear * t_sum * inv_r
    stt_p = lame * alpha * alpha - 2.0 * shear * t_p * inv_r
    stt_sum = lame * alpha * alpha - 2.0 * shear * t_sum * inv_r
    srt_p = 2.0 * shear * n * ((n + 1.0) * inv_r + delta_p) * inv_r
    srt_sum = shear * (2.0 * (n * delta_p - delta_s) * inv_r - beta * beta)
    return srr_p, srr_sum, stt_p, stt_sum, srt_p, srt_sum


@numba.njit(cache=True)
def _stress_difference_terms(n, r, alpha, beta, delta_p, delta_s, shear, lame):
    """S_rr − S_rθ of the P solution and of the P + SV sum, formed analytically.

    For n = 1 this is the soil's net force on a rigidly translating ring, which is small
    against each stress when the lining is stiff; forming it by subtraction would lose it.
    """
    inv_r = 1.0 / r
    inertia_p = (lame + 2.0 * shear) * alpha * alpha  # = −ρω²
    diff_p = inertia_p + 2.0 * shear * (1.0 - n) * delta_p * inv_r
    diff_sum = (
        inertia_p + shear * beta * beta + 2.0 * shear * (1.0 - n) * (delta_p + delta_s) * inv_r
    )
    return diff_p, diff_sum


@numba.njit(cache=True)
def _bessel_ratios(z, n_max, out):
    """out[m] = K_{m+1}(z)/K_m(z), m = 0..n_max (forward recurrence); returns K₀(z) eᶻ."""
    k0, k1 = bessel_k01_scaled(z)
    ratio = k1 / k0
    two_over_z = 2.0 / z
    for m in range(n_max + 1):
        out[m] = ratio
        ratio = _reciprocal(ratio) + (m + 1) * two_over_z
    return k0


@numba.njit(cache=True, parallel=True, nogil=True)
def ring_soil_field_kernel(
    omega,
    radius,
    cos_weight,
    sin_weight,
    ring_radius,
    ring_mass,
    ring_extensional,
    ring_bending,
    shear,
    lame,
    density,
    with_stresses,
):
    """Soil field of a radially loaded ring in a full-space, summed over harmonics.

    The ring (radius a, mass per arc length m, stiffnesses K, D) carries a radial traction
    Σ_n p_n cos nθ; the field at point j is Σ_n cos_weight[j, n] X_n(r_j) for the cos-type
    quantities (u_r, σ_rr, σ_θθ) and Σ_n sin_weight[j, n] X_n(r_j) for the sin-type ones
    (u_θ, σ_rθ), X_n being the radial function of harmonic n per unit p_n (1 Pa).

    Parameters: omega (nf,) rad/s > 0; radius (np,) m ≥ a; weights (np, n_max + 1);
    shear = μ*, lame = λ* complex (Pa); density (kg/m³); with_stresses: compute σ or leave 0.
    Returns u_r, u_θ, σ_rr, σ_θθ, σ_rθ, each complex (nf, np).
    """
    n_freq = omega.size
    n_points = radius.size
    n_max = cos_weight.shape[1] - 1
    shape = (n_freq, n_points)
    u_r = np.zeros(shape, np.complex128)
    u_t = np.zeros(shape, np.complex128)
    s_rr = np.zeros(shape, np.complex128)
    s_tt = np.zeros(shape, np.complex128)
    s_rt = np.zeros(shape, np.complex128)
    a = ring_radius
    slowness_p = cmath.sqrt(density / (lame + 2.0 * shear))
    slowness_s = cmath.sqrt(density / shear)
    for i in numba.prange(n_freq):
        alpha = 1j * omega[i] * slowness_p
        beta = 1j * omega[i] * slowness_s
        ratio_p_a = np.empty(n_max + 1, np.complex128)
        ratio_s_a = np.empty(n_max + 1, np.complex128)
        k0p_a = _bessel_ratios(alpha * a, n_max, ratio_p_a)
        k0s_a = _bessel_ratios(beta * a, n_max, ratio_s_a)
        amp_p = np.empty(n_max + 1, np.complex128)  # amplitude X of the P solution
        amp_sum = np.empty(n_max + 1, np.complex128)  # amplitude Y of the P + SV sum
        inertia = -(omega[i] ** 2) * ring_mass
        for n in range(n_max + 1):
            # Ring impedance rows: radial (z_rr, z_rt), tangential (z_rt, z_tt). The system is
            # solved with rows (radial − tangential, tangential); their difference (d_r, d_t) is
            # formed analytically because the K/a² terms cancel for the rigid translation n = 1.
            bending = ring_bending * (n * n - 1.0) ** 2 / a**4
            z_rt = ring_extensional * n / a**2
            z_tt = inertia + ring_extensional * n * n / a**2
            d_r = inertia + ring_extensional * (1.0 - n) / a**2 + bending
            d_t = -inertia + ring_extensional * n * (1.0 - n) / a**2
            if n == 0:
                delta_p = alpha * ratio_p_a[0]
                delta_s = beta * ratio_s_a[0]
            else:
                delta_p = alpha * _reciprocal(ratio_p_a[n - 1])
                delta_s = beta * _reciprocal(ratio_s_a[n - 1])
            u_p, v_p, u_sum, v_sum = _displacement_terms(n, a, delta_p, delta_s)
            if n == 0:  # sin 0θ = 0: no SV potential, radial equation only
                srr_p = _stress_terms(n, a, alpha, beta, delta_p, delta_s, shear, lame)[0]
                amp_p[n] = 1.0 / ((inertia + ring_extensional / a**2 + bending) * u_p - srr_p)
                amp_sum[n] = 0.0
                continue
            _, _, _, _, srt_p, srt_sum = _stress_terms(
                n, a, alpha, beta, delta_p, delta_s, shear, lame
            )
            diff_p, diff_sum = _stress_difference_terms(
                n, a, alpha, beta, delta_p, delta_s, shear, lame
            )
            m00 = d_r * u_p + d_t * v_p - diff_p
            m01 = d_r * u_sum + d_t * v_sum - diff_sum
            m10 = z_rt * u_p + z_tt * v_p - srt_p
            m11 = z_rt * u_sum + z_tt * v_sum - srt_sum
            det = m00 * m11 - m01 * m10
            amp_p[n] = m11 / det  # right-hand side (1, 0): unit radial traction
            amp_sum[n] = -m10 / det
        inv_ratio_p_a = 1.0 / ratio_p_a  # so the inner loop multiplies instead of dividing
        inv_ratio_s_a = 1.0 / ratio_s_a
        for j in range(n_points):
            r = radius[j]
            zp = alpha * r
            zs = beta * r
            k0p, k1p = bessel_k01_scaled(zp)
            k0s, k1s = bessel_k01_scaled(zs)
            # e_P = K_n(αr)/K_n(αa), advanced in n with the ratio recurrence. At r = a it is 1
            # exactly (a complex x/x can be off by an ulp, which Y (e_P − e_S) would amplify).
            if r == a:
                e_p = 1.0 + 0j
                e_s = 1.0 + 0j
            else:
                e_p = k0p / k0p_a * cmath.exp(-alpha * (r - a))
                e_s = k0s / k0s_a * cmath.exp(-beta * (r - a))
            ratio_p = k1p / k0p  # R_n(αr) = K_{n+1}/K_n, advanced in n below
            ratio_s = k1s / k0s
            delta_p = alpha * ratio_p  # δ_P = α R_0 for n = 0, α/R_{n−1} for n ≥ 1
            delta_s = beta * ratio_s
            two_over_zp = 2.0 / zp
            two_over_zs = 2.0 / zs
            inv_r = 1.0 / r
            # Sums over n of the cos-type terms: u_r; Σ cw (c_P + c_sum) and Σ cw (c_P T_P +
            # c_sum T_sum), from which σ_rr and σ_θθ follow after the loop
            # (_normal_stress_parts); and the sin-type u_θ, σ_rθ (zero weights skipped).
            sum_ur = 0j
            sum_ut = 0j
            sum_amp = 0j
            sum_t = 0j
            sum_srt = 0j
            for n in range(n_max + 1):
                cw = cos_weight[j, n]
                sw = sin_weight[j, n]
                if cw != 0.0 or sw != 0.0:
                    # X e_P P + Y (e_P P + e_S SV) = (X e_P + Y (e_P − e_S)) P + Y e_S (P + SV)
                    c_sum = amp_sum[n] * e_s
                    c_p = amp_p[n] * e_p + amp_sum[n] * (e_p - e_s)
                    u_p, v_p, u_sum, v_sum = _displacement_terms(n, r, delta_p, delta_s)
                    sum_ur += cw * (c_p * u_p + c_sum * u_sum)
                    if sw != 0.0:
                        sum_ut += sw * (c_p * v_p + c_sum * v_sum)
                    if with_stresses:
                        t_p, t_sum = _normal_stress_parts(n, inv_r, delta_p, delta_s)
                        sum_amp += cw * (c_p + c_sum)
                        sum_t += cw * (c_p * t_p + c_sum * t_sum)
                        if sw != 0.0:
                            srt_p, srt_sum = _stress_terms(
                                n, r, alpha, beta, delta_p, delta_s, shear, lame
                            )[4:]
                            sum_srt += sw * (c_p * srt_p + c_sum * srt_sum)
                if r != a:  # at r = a, e_P = e_S = 1 exactly, and Y (e_P − e_S) must vanish
                    e_p *= ratio_p * inv_ratio_p_a[n]
                    e_s *= ratio_s * inv_ratio_s_a[n]
                recip_p = _reciprocal(ratio_p)
                recip_s = _reciprocal(ratio_s)
                delta_p = alpha * recip_p
                delta_s = beta * recip_s
                ratio_p = recip_p + (n + 1) * two_over_zp
                ratio_s = recip_s + (n + 1) * two_over_zs
            u_r[i, j] = sum_ur
            u_t[i, j] = sum_ut
            if with_stresses:
                shear_part = 2.0 * shear * sum_t * inv_r
                s_rr[i, j] = (lame + 2.0 * shear) * alpha * alpha * sum_amp + shear_part
                s_tt[i, j] = lame * alpha * alpha * sum_amp - shear_part
                s_rt[i, j] = sum_srt
    return u_r, u_t, s_rr, s_tt, s_rt


# ---- public wrappers --------------------------------------------------------------------------
@dataclass(frozen=True)
class SoilField:
    """Displacements (m) and stresses (Pa) in the soil, complex, shape (n_freq, n_points).

    Per unit load as stated by the function that returns it; exp(+iωt); outward notation
    (u_r away from the tunnel axis, u_θ towards increasing θ, tension positive).
    """

    u_r: np.ndarray
    u_theta: np.ndarray
    sigma_rr: np.ndarray
    sigma_thetatheta: np.ndarray
    sigma_rtheta: np.ndarray


def _checked_values(obj, section_class: type, names: tuple[str, ...]) -> None:
    """Refuse values of ``obj`` outside the bounds that ``model.params`` declares for them.

    The parameter classes are the only table of bounds: a Tunnel or Soil object was checked on
    assignment against its own declared parameters (a subclass may widen them on purpose, e.g.
    for an idealised limit in a test); any other object is checked against the declarations of
    ``section_class``, with the same message.
    """
    if isinstance(obj, section_class):
        return
    for name in names:
        section_class.param[name]._validate(getattr(obj, name))


def _finite_constants(section: str, obj, names: tuple[str, ...], compute) -> tuple:
    """Result of ``compute()``, refused (naming the inputs) if a constant is not finite."""
    try:
        constants = compute()
    except ArithmeticError:
        constants = (math.nan,)
    if not all(cmath.isfinite(value) for value in constants):
        values = ", ".join(f"{section}.{name} = {getattr(obj, name)!r}" for name in names)
        raise ValueError(f"{values} give non-finite model constants; check these inputs")
    return constants


_RING_INPUTS = ("inner_radius", "thickness", "youngs_modulus", "poisson_ratio", "density")
_SOIL_INPUTS = (
    "youngs_modulus",
    "poisson_ratio",
    "density",
    "shear_loss_factor",
    "bulk_loss_factor",
)


def _ring_constants(tunnel) -> tuple[float, float, float, float]:
    """(a, m, K, D) of the lining ring, after checking its parameters."""
    _checked_values(tunnel, Tunnel, _RING_INPUTS)
    return _finite_constants(
        "tunnel",
        tunnel,
        _RING_INPUTS,
        lambda: (
            tunnel.ring_radius,
            tunnel.density * tunnel.thickness,
            tunnel.extensional_stiffness,
            tunnel.bending_stiffness,
        ),
    )


def _soil_constants(soil) -> tuple[complex, complex, float]:
    """(μ*, λ*, ρ) of the hysteretically damped soil, after checking its parameters."""
    _checked_values(soil, Soil, _SOIL_INPUTS)

    def moduli():
        shear = soil.shear_modulus * (1.0 + 1j * soil.shear_loss_factor)
        bulk = soil.bulk_modulus * (1.0 + 1j * soil.bulk_loss_factor)
        return shear, bulk - 2.0 * shear / 3.0, soil.density

    return _finite_constants("soil", soil, _SOIL_INPUTS, moduli)


def _as_1d(values, name: str, unit: str) -> np.ndarray:
    """Float array of at most one dimension, refusing NaN and infinity."""
    array = np.atleast_1d(np.asarray(values, dtype=float))
    if array.ndim != 1:
        raise ValueError(f"{name} must be a scalar or a 1-D array, got shape {array.shape}")
    if not np.all(np.isfinite(array)):
        raise ValueError(
            f"{name} contains {float(array[~np.isfinite(array)][0])!r}; finite values "
            f"in {unit} are required"
        )
    return array


def _angular_frequency(freq_hz) -> np.ndarray:
    """ω = 2πf (rad/s) for frequencies that must all be > 0."""
    freq = _as_1d(freq_hz, "freq_hz", "Hz")
    if np.any(freq <= 0.0):
        bad = float(freq[freq <= 0.0][0])
        raise ValueError(
            f"freq_hz = {bad!r} is outside the allowed range (0, inf) Hz: the 2D static (f = 0) "
            f"response is infinite; model.settlement treats the zero-frequency bin by averaging "
            f"over its band"
        )
    return 2.0 * np.pi * freq


def _check_harmonics(n_harmonics) -> int:
    """n_harmonics as an int ≥ 0."""
    if (
        isinstance(n_harmonics, bool)
        or not isinstance(n_harmonics, int | np.integer)
        or (n_harmonics < 0)
    ):
        raise ValueError(f"n_harmonics = {n_harmonics!r} must be an integer ≥ 0")
    return int(n_harmonics)


def _check_radius(radius_m, ring_radius: float) -> np.ndarray:
    """Radii (m) that must lie in the soil, r ≥ a."""
    radius = _as_1d(radius_m, "radius_m", "m")
    if np.any(radius < ring_radius):
        bad = float(radius[radius < ring_radius][0])
        raise ValueError(
            f"radius_m = {bad!r} is inside the lining: soil points need "
            f"r ≥ a = {ring_radius:g} m (ring radius)"
        )
    return radius


def invert_load_coefficients(ring_radius: float, n_harmonics: int) -> np.ndarray:
    """Fourier coefficients of a unit downward line load at the invert (1/m).

    q_r(θ) = δ(aθ) = Σ_n c_n cos nθ per unit arc length with c_0 = 1/(2πa), c_n = 1/(πa).

    Parameters
    ----------
    ring_radius : float
        Ring radius a (m).
    n_harmonics : int
        Highest harmonic N; coefficients for n = 0..N.

    Returns
    -------
    ndarray
        (N + 1,) coefficients in 1/m (radial traction in Pa per N/m of line load).
    """
    coefficients = np.full(_check_harmonics(n_harmonics) + 1, 1.0 / (np.pi * ring_radius))
    coefficients[0] *= 0.5
    return coefficients


def _run_kernel(omega, radius, cos_weight, sin_weight, tunnel, soil, with_stresses):
    """Unpack the parameter objects and run the kernel; refuse a non-finite result (ValueError)."""
    a, mass, extensional, bending = _ring_constants(tunnel)
    shear, lame, density = _soil_constants(soil)
    fields = ring_soil_field_kernel(
        omega,
        radius,
        np.ascontiguousarray(cos_weight),
        np.ascontiguousarray(sin_weight),
        a,
        mass,
        extensional,
        bending,
        shear,
        lame,
        density,
        with_stresses,
    )
    for field in fields:
        bad = ~np.isfinite(field)
        if np.any(bad):
            row = int(np.argwhere(bad)[0, 0])
            inputs = ", ".join(
                [f"tunnel.{name} = {getattr(tunnel, name):g}" for name in _RING_INPUTS]
                + [f"soil.{name} = {getattr(soil, name):g}" for name in _SOIL_INPUTS]
            )
            raise ValueError(
                f"the ring–soil solution is not finite at f = {omega[row] / (2 * np.pi):.4g} Hz "
                f"for {inputs}; the frequency comes from numerics.soil_max_frequency"
            )
    return fields


def invert_receptance(freq_hz, depth_m, tunnel, soil, n_harmonics: int) -> np.ndarray:
    """Downward displacement under the invert per unit downward line load at the invert.

    The point is r = a + d, θ = 0 (directly below the tunnel axis, d below the ring–soil
    interface); the load is a line load F′ (N/m) at the invert, harmonics n = 0..N summed.

    Parameters
    ----------
    freq_hz : float or array_like
        Frequencies (Hz), finite and > 0 (the 2D static response is infinite).
    depth_m : float or array_like
        Depths d ≥ 0 below the ring–soil interface (m).
    tunnel : model.params.Tunnel
        Lining (thin ring of radius ``tunnel.ring_radius``).
    soil : model.params.Soil
        Full-space soil with hysteretic loss factors.
    n_harmonics : int
        Highest circumferential harmonic N ≥ 0.

    Returns
    -------
    ndarray
        Complex (n_freq, n_depth) receptance in m per N/m, time convention exp(+iωt); its
        imaginary part at d = 0 is ≤ 0 (the soil absorbs power).
    """
    omega = _angular_frequency(freq_hz)
    depth = _as_1d(depth_m, "depth_m", "m")
    if np.any(depth < 0.0):
        bad = float(depth[depth < 0.0][0])
        raise ValueError(
            f"depth_m = {bad!r} is inside the lining: depths are measured from "
            f"the ring–soil interface and must be ≥ 0 m"
        )
    coefficients = invert_load_coefficients(tunnel.ring_radius, n_harmonics)
    cos_weight = np.broadcast_to(coefficients, (depth.size, coefficients.size))
    sin_weight = np.zeros_like(cos_weight)
    u_r = _run_kernel(
        omega, tunnel.ring_radius + depth, cos_weight, sin_weight, tunnel, soil, with_stresses=False
    )[0]
    return u_r


def soil_field(freq_hz, radius_m, theta_rad, tunnel, soil, n_harmonics: int) -> SoilField:
    """Soil displacements and stresses per unit downward line load at the invert.

    Parameters
    ----------
    freq_hz : float or array_like
        Frequencies (Hz), > 0.
    radius_m, theta_rad : float or array_like
        Points (r, θ), broadcast to a common 1-D shape; r ≥ a (m), θ from the downward
        vertical (rad).
    tunnel, soil : model.params.Tunnel, model.params.Soil
        Lining and soil.
    n_harmonics : int
        Highest circumferential harmonic N ≥ 0.

    Returns
    -------
    SoilField
        u_r, u_θ (m per N/m) and σ_rr, σ_θθ, σ_rθ (Pa per N/m), complex (n_freq, n_points).
    """
    omega = _angular_frequency(freq_hz)
    radius, theta = np.broadcast_arrays(
        _check_radius(radius_m, tunnel.ring_radius), _as_1d(theta_rad, "theta_rad", "rad")
    )
    coefficients = invert_load_coefficients(tunnel.ring_radius, n_harmonics)
    n_theta = np.outer(theta, np.arange(coefficients.size))
    fields = _run_kernel(
        omega,
        np.ascontiguousarray(radius),
        coefficients * np.cos(n_theta),
        coefficients * np.sin(n_theta),
        tunnel,
        soil,
        with_stresses=True,
    )
    return SoilField(*fields)


def harmonic_field(freq_hz, radius_m, tunnel, soil, n: int) -> SoilField:
    """Radial functions of harmonic n for a radial traction p cos nθ (p = 1 Pa) on the ring.

    The field is u_r = U(r) cos nθ, u_θ = V(r) sin nθ, σ_rr = S_rr(r) cos nθ,
    σ_θθ = S_θθ(r) cos nθ, σ_rθ = S_rθ(r) sin nθ; this returns U, V, S_rr, S_θθ, S_rθ.
    At r = a, U and V are the ring's W_n, V_n.

    Parameters
    ----------
    freq_hz : float or array_like
        Frequencies (Hz), > 0.
    radius_m : float or array_like
        Radii r ≥ a (m).
    tunnel, soil : model.params.Tunnel, model.params.Soil
        Lining and soil.
    n : int
        Harmonic number ≥ 0.

    Returns
    -------
    SoilField
        Radial functions in m/Pa (U, V) and Pa/Pa (stresses), complex (n_freq, n_radius).
    """
    omega = _angular_frequency(freq_hz)
    radius = _check_radius(radius_m, tunnel.ring_radius)
    weight = np.zeros((radius.size, _check_harmonics(n) + 1))
    weight[:, n] = 1.0
    return SoilField(*_run_kernel(omega, radius, weight, weight, tunnel, soil, with_stresses=True))


def ring_displacement_harmonics(freq_hz, tunnel, soil, n_harmonics: int):
    """Ring displacement amplitudes per harmonic per unit downward line load at the invert.

    Parameters
    ----------
    freq_hz : float or array_like
        Frequencies (Hz), > 0.
    tunnel, soil : model.params.Tunnel, model.params.Soil
        Lining and soil.
    n_harmonics : int
        Highest circumferential harmonic N ≥ 0.

    Returns
    -------
    (W, V) : ndarray, ndarray
        Complex (n_freq, N + 1) in m per N/m: w(θ) = Σ W_n cos nθ (outward),
        v(θ) = Σ V_n sin nθ.
    """
    omega = _angular_frequency(freq_hz)
    coefficients = invert_load_coefficients(tunnel.ring_radius, n_harmonics)
    weight = np.diag(coefficients)
    radius = np.full(coefficients.size, tunnel.ring_radius)
    u_r, u_t, *_ = _run_kernel(omega, radius, weight, weight, tunnel, soil, with_stresses=False)
    return u_r, u_t


def ring_displacement(freq_hz, theta_rad, tunnel, soil, n_harmonics: int):
    """Ring displacements w (outward) and v (tangential) per unit downward invert line load.

    Parameters
    ----------
    freq_hz : float or array_like
        Frequencies (Hz), > 0.
    theta_rad : float or array_like
        Angles from the downward vertical (rad).
    tunnel, soil : model.params.Tunnel, model.params.Soil
        Lining and soil.
    n_harmonics : int
        Highest circumferential harmonic N ≥ 0.

    Returns
    -------
    (w, v) : ndarray, ndarray
        Complex (n_freq, n_theta) in m per N/m.
    """
    theta = _as_1d(theta_rad, "theta_rad", "rad")
    field = soil_field(freq_hz, tunnel.ring_radius, theta, tunnel, soil, n_harmonics)
    return field.u_r, field.u_theta
