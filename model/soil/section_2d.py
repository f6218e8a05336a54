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

Bessel functions K_n, their ratio recurrence and the radial functions K_n(z r)/K_n(z a):
``model.soil.bessel``.

The 2D static response is infinite for n = 1 (it grows like ln 1/ω), so f = 0 is refused; see
``model.soil.response`` for the zero-frequency bin.
"""

from __future__ import annotations

import cmath
import os
import types
from dataclasses import dataclass

import numba
import numpy as np

from model.soil.bessel import (
    bessel_ratios,
    log_derivative,
    next_ratio,
    radial_start,
)
from model.soil.inputs import (
    RING_INPUTS,
    SOIL_INPUTS,
    as_1d,
    check_harmonics,
    checked_depths,
    invert_load_coefficients,
    ring_constants,
    soil_constants,
)


# ---- ring–soil solution per harmonic ----------------------------------------------------------
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


def _ring_soil_field(
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
    point_mask,
):
    """Soil field of a radially loaded ring in a full-space, summed over harmonics.

    The ring (radius a, mass per arc length m, stiffnesses K, D) carries a radial traction
    Σ_n p_n cos nθ; the field at point j is Σ_n cos_weight[j, n] X_n(r_j) for the cos-type
    quantities (u_r, σ_rr, σ_θθ) and Σ_n sin_weight[j, n] X_n(r_j) for the sin-type ones
    (u_θ, σ_rθ), X_n being the radial function of harmonic n per unit p_n (1 Pa).

    Parameters: omega (nf,) rad/s > 0; radius (np,) m ≥ a; weights (np, n_max + 1);
    shear = μ*, lame = λ* complex (Pa); density (kg/m³); with_stresses: compute σ or leave 0;
    point_mask (nf, np) bool: the points to compute at each frequency (the others left 0).
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
        k0p_a = bessel_ratios(alpha * a, n_max, ratio_p_a)
        k0s_a = bessel_ratios(beta * a, n_max, ratio_s_a)
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
            delta_p = log_derivative(alpha, ratio_p_a, n)
            delta_s = log_derivative(beta, ratio_s_a, n)
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
        # Reciprocals, so the inner loop multiplies instead of dividing; an explicit loop, not
        # 1.0 / array, whose parallel compilation rounds differently from the serial one
        inv_ratio_p_a = np.empty(n_max + 1, np.complex128)
        inv_ratio_s_a = np.empty(n_max + 1, np.complex128)
        for n in range(n_max + 1):
            inv_ratio_p_a[n] = 1.0 / ratio_p_a[n]
            inv_ratio_s_a[n] = 1.0 / ratio_s_a[n]
        for j in range(n_points):
            if not point_mask[i, j]:
                continue
            r = radius[j]
            # e_P = K_n(αr)/K_n(αa) and R_n(αr) = K_{n+1}/K_n, advanced in n below (e_S alike)
            e_p, ratio_p, two_over_zp = radial_start(alpha, r, a, k0p_a)
            e_s, ratio_s, two_over_zs = radial_start(beta, r, a, k0s_a)
            delta_p = alpha * ratio_p  # δ_P = α R_0 for n = 0, α/R_{n−1} for n ≥ 1
            delta_s = beta * ratio_s
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
                recip_p, ratio_p = next_ratio(ratio_p, n, two_over_zp)
                recip_s, ratio_s = next_ratio(ratio_s, n, two_over_zs)
                delta_p = alpha * recip_p
                delta_s = beta * recip_s
            u_r[i, j] = sum_ur
            u_t[i, j] = sum_ut
            if with_stresses:
                shear_part = 2.0 * shear * sum_t * inv_r
                s_rr[i, j] = (lame + 2.0 * shear) * alpha * alpha * sum_amp + shear_part
                s_tt[i, j] = lame * alpha * alpha * sum_amp - shear_part
                s_rt[i, j] = sum_srt
    return u_r, u_t, s_rr, s_tt, s_rt


def _compiled_as(function, name: str):
    """``function`` under another name, so that Numba caches a second compilation of it apart
    (its cache files are named after the function's qualified name)."""
    renamed = types.FunctionType(
        function.__code__, function.__globals__, name, function.__defaults__
    )
    renamed.__qualname__ = renamed.__name__ = name
    renamed.__doc__ = function.__doc__
    return renamed


# The kernel compiled twice from one source: across the frequencies on Numba's threads, and in
# one thread (``prange`` is then ``range``, the same arithmetic in the same order: the results
# are identical). The serial one runs where Numba has one thread (a study worker: the thread
# pool would only add its overhead) and in any process forked after this module was imported
# (a study worker forked from a dashboard): the parent may have started the OpenMP threads of
# the parallel one, and GNU OpenMP terminates a forked child that uses them again.
_IMPORTING_PROCESS = os.getpid()
ring_soil_field_kernel = numba.njit(cache=True, parallel=True, nogil=True)(_ring_soil_field)
ring_soil_field_serial = numba.njit(cache=True, nogil=True)(
    _compiled_as(_ring_soil_field, "ring_soil_field_serial")
)


def use_serial_kernel() -> bool:
    """True where the kernels' serial compilations run: one Numba thread, or a process forked
    after this module was imported (see above)."""
    return numba.get_num_threads() == 1 or os.getpid() != _IMPORTING_PROCESS


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


def _angular_frequency(freq_hz) -> np.ndarray:
    """ω = 2πf (rad/s) for frequencies that must all be > 0."""
    freq = as_1d(freq_hz, "freq_hz", "Hz")
    if np.any(freq <= 0.0):
        bad = float(freq[freq <= 0.0][0])
        raise ValueError(
            f"freq_hz = {bad!r} is outside the allowed range (0, inf) Hz: the 2D static (f = 0) "
            f"response is infinite; model.soil.response treats the zero-frequency bin by averaging "
            f"over its band"
        )
    return 2.0 * np.pi * freq


def _check_radius(radius_m, ring_radius: float) -> np.ndarray:
    """Radii (m) that must lie in the soil, r ≥ a."""
    radius = as_1d(radius_m, "radius_m", "m")
    if np.any(radius < ring_radius):
        bad = float(radius[radius < ring_radius][0])
        raise ValueError(
            f"radius_m = {bad!r} is inside the lining: soil points need "
            f"r ≥ a = {ring_radius:g} m (ring radius)"
        )
    return radius


def _run_kernel(
    omega, radius, cos_weight, sin_weight, tunnel, soil, with_stresses, point_mask=None
):
    """Unpack the parameter objects and run the kernel; refuse a non-finite result (ValueError).
    ``point_mask`` (n_freq, n_points) bool: the points to compute (default all)."""
    if point_mask is None:
        point_mask = np.ones((omega.size, radius.size), dtype=bool)
    a, mass, extensional, bending = ring_constants(tunnel)
    shear, lame, density = soil_constants(soil)
    kernel = ring_soil_field_serial if use_serial_kernel() else ring_soil_field_kernel
    fields = kernel(
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
        np.ascontiguousarray(point_mask, dtype=bool),
    )
    for field in fields:
        bad = ~np.isfinite(field)
        if np.any(bad):
            row = int(np.argwhere(bad)[0, 0])
            inputs = ", ".join(
                [f"tunnel.{name} = {getattr(tunnel, name):g}" for name in RING_INPUTS]
                + [f"soil.{name} = {getattr(soil, name):g}" for name in SOIL_INPUTS]
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
    depth = checked_depths(depth_m)
    coefficients = invert_load_coefficients(tunnel.ring_radius, n_harmonics)
    cos_weight = np.broadcast_to(coefficients, (depth.size, coefficients.size))
    sin_weight = np.zeros_like(cos_weight)
    u_r = _run_kernel(
        omega, tunnel.ring_radius + depth, cos_weight, sin_weight, tunnel, soil, with_stresses=False
    )[0]
    return u_r


def soil_field(
    freq_hz, radius_m, theta_rad, tunnel, soil, n_harmonics: int, point_mask=None
) -> SoilField:
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
    point_mask : ndarray, optional
        (n_freq, n_points) bool: only these (frequency, point) pairs are computed, the others
        are 0 (default: all).

    Returns
    -------
    SoilField
        u_r, u_θ (m per N/m) and σ_rr, σ_θθ, σ_rθ (Pa per N/m), complex (n_freq, n_points).
    """
    omega = _angular_frequency(freq_hz)
    radius, theta = np.broadcast_arrays(
        _check_radius(radius_m, tunnel.ring_radius), as_1d(theta_rad, "theta_rad", "rad")
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
        point_mask=point_mask,
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
    weight = np.zeros((radius.size, check_harmonics(n) + 1))
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
    theta = as_1d(theta_rad, "theta_rad", "rad")
    field = soil_field(freq_hz, tunnel.ring_radius, theta, tunnel, soil, n_harmonics)
    return field.u_r, field.u_theta
