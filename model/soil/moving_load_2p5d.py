"""Cylindrical-shell tunnel in an elastic full-space, 2.5D moving-load model (docs/model.md §9).

Cylindrical coordinates (r, θ, x): x along the tunnel, θ = 0 at the invert pointing **down**,
(r, θ, x) right-handed as (r, θ, z) of ``model.soil.section_2d``; every field varies as
exp(i(ωt − ξx)) and, per ring harmonic n, as cos nθ (u_r, u_x, σ_rr, σ_θθ, σ_xx, σ_rx) or
sin nθ (u_θ, σ_rθ, σ_θx). Outward notation as in the 2D model: w = u_r(a), v = u_θ(a), u = u_x(a).
The axial quantities are written u_x = i Ũ, σ_rx = i S̃_rx, σ_θx = i S̃_θx so that every
coefficient below is a real expression of ξ, n, α, β (complex only through the moduli).

Lining: thin cylindrical shell after **Flügge** (Leissa 1973, eqs 2.2–2.3), radius a (middle
surface), K = Eh/(1−ν²), k = h²/(12a²), ζ = ξa, mass m = ρh per unit area. Flügge rather than
Donnell because at ξ = 0 Flügge's equations are exactly the plane-strain ring of the 2D model
(bending (n² − 1)², free rigid translation for n = 1, docs/model.md §7), which Donnell's are not
(bending n⁴: it stiffens the n = 1 translation and the n = 2 ovalling that carry most of the
invert load). Force per unit area = −S (Ũ, V, W) with the symmetric S = (K/a²) s,
    s11 = ζ² + (1−ν)(1+k) n²/2,      s12 = (1+ν) ζ n/2,      s13 = ζ (ν + kζ² − k(1−ν) n²/2),
    s22 = n² + (1−ν)(1+3k) ζ²/2,     s23 = n (1 + k(3−ν) ζ²/2),
    s33 = 1 + k (n² − 1)² + k ζ² (ζ² + 2n²),
so the shell equations are (S − ω²m I)(Ũ, V, W) = (S̃_rx, σ_rθ, σ_rr)(a) + load. At ζ = 0,
(s22, s23, s33) are the 2D ring's (n², n, 1 + k(n² − 1)²) and the axial row decouples.

Soil: u = ∇φ + ∇×(ψ e_x) + ∇×∇×(χ e_x) with φ = f(r) cos nθ (P), ψ = g(r) sin nθ (SV, the
in-plane shear wave of the 2D model) and χ = (c/i) h(r) cos nθ (SH, axially polarised shear).
The radial functions are K_n(αr)/K_n(αa) for P and K_n(βr)/K_n(βa) for SV and SH, with
α² = ξ² − k₁², β² = ξ² − k₂², k_j = ω/c_j*, the principal square root (Re ≥ 0, so that at
ξ = 0, α = iω/c₁* as in 2D: outgoing). With e(r) = K_n(zr)/K_n(za), e′/e = −n/r − δ
(δ = z K_{n−1}(zr)/K_n(zr), z K₁/K₀ for n = 0), the fields per unit amplitude are, as
(U_r, U_θ, Ũ):
    ∇φ (P, "grad_P"):   e_P (−n/r − δ_P, −n/r, −ξ)
    SV:                 e_S (n/r, n/r + δ_S, 0)
    SH:                 ξ · grad_S + k₂² e_S (0, 0, 1)     (grad_S: ∇φ with e_S, δ_S)
and the stresses follow from σ = λ* tr ε I + 2μ* ε (coefficients in :func:`_field_vectors`).

Conditioning. Three degeneracies are removed analytically by the choice of unknowns:
(i) as in 2D, for n ≥ 1 at low frequency grad_P ≈ −SV, so the second unknown is the amplitude
Y of the sum grad_P + SV; (ii) for ξ ≫ k (or ω → 0 along ξ = ω/v) the SH field tends to
ξ grad_P, so the third unknown Z multiplies SH − ξ grad_P = ξ (grad_S − grad_P) + k₂² e_S e_x,
whose interface values (ξ(δ_P − δ_S), 0, k₂²) and stresses are formed from the differences
δ_S − δ_P and k₁² − k₂² directly; (iii) the 2D ring-row difference (radial − tangential row,
for the n = 1 rigid translation) is kept, with the ξ terms of the shell added analytically.
The unknowns are the P amplitude X, Y and Z, A_P = X + Y − ξZ, A_SV = Y, A_SH = Z, and the
interface conditions u(a) = (Ũ, V, W) substituted into the three shell rows leave a 3×3
system per (n, ξ, ω): the 6×6 of Forrest & Hunt (2006) with its three kinematic rows
eliminated, as the 2D model eliminates two of its 4×4. For n = 0 the SV field does not
enter (sin 0θ = 0) and the system is the 2×2 of the radial and axial rows.

At ξ = 0 every ξ-coupling entry is exactly zero: the axial row and the Z column separate from
the 2×2 in-plane system of the 2D model, the unforced Z is 0 and H(ω, 0, d) is
``model.soil.section_2d.invert_receptance`` to rounding. The Bessel functions and their
ratio recurrence are those of ``model.soil.bessel``, the checked inputs and the load
coefficients those of ``model.soil.inputs``; the point load, the wavenumber integral of H, is
in ``model.soil.point_load``.

Zero frequency is refused: at ω = 0 the P and SH fields coincide (α = β = |ξ|) and the
potentials no longer span the static solution. Along ξ = ω/v the moving-frame receptance grows
like ln(1/ω) as ω → 0, as the 2D one does (``model.soil.response`` averages the DC bin).
"""

from __future__ import annotations

import cmath
from dataclasses import dataclass

import numba
import numpy as np

from model.soil.bessel import bessel_ratios, log_derivative, next_ratio, radial_start
from model.soil.inputs import (
    as_1d,
    check_harmonics,
    checked_depths,
    invert_load_coefficients,
    ring_constants,
    soil_constants,
)
from model.soil.section_2d import _compiled_as, use_serial_kernel


# ---- kernel -----------------------------------------------------------------------------------
@numba.njit(cache=True, nogil=True)
def _field_vectors(n, r, xi, delta_p, delta_s, omega2_rho, k1sq, k2sq, shear, lame):
    """(U_r, Ũ, S_rr, S_θθ, S_xx, S̃_rx) at θ-phase cos of the four field vectors at r.

    Returned as four 6-tuples per unit e: grad_P, the sum grad_P + SV, the difference
    grad_S − grad_P and the axial unit field e_x (module docstring); omega2_rho = ρω²,
    k1sq = k₁², k2sq = k₂². Static parts that cancel in the sum and the
    difference are cancelled analytically.
    """
    inv_r = 1.0 / r
    n_r = n * inv_r
    nn1 = n * (n + 1.0) * inv_r
    two_mu = 2.0 * shear
    lame_k1 = lame * k1sq
    axial = two_mu * xi * xi
    ddelta = delta_s - delta_p
    grad_p = (
        -n_r - delta_p,
        -xi + 0j,
        axial - omega2_rho + two_mu * (nn1 + delta_p) * inv_r,
        -lame_k1 - two_mu * (nn1 + delta_p) * inv_r,
        -lame_k1 - axial,
        two_mu * xi * (n_r + delta_p),
    )
    total = (
        -delta_p,
        -xi + 0j,
        axial - omega2_rho + two_mu * (delta_p - n * delta_s) * inv_r,
        -lame_k1 + two_mu * (n * delta_s - delta_p) * inv_r,
        -lame_k1 - axial,
        shear * xi * (n_r + 2.0 * delta_p),
    )
    dk = lame * (k1sq - k2sq)
    diff = (
        -ddelta,
        0j,
        omega2_rho - (lame + two_mu) * k2sq + two_mu * ddelta * inv_r,
        dk - two_mu * ddelta * inv_r,
        dk,
        two_mu * xi * ddelta,
    )
    unit_axial = (
        0j,
        1.0 + 0j,
        lame * xi,
        lame * xi,
        (lame + two_mu) * xi,
        -shear * (n_r + delta_s),
    )
    return grad_p, total, diff, unit_axial


@numba.njit(cache=True, nogil=True)
def _shear_row_stresses(n, r, delta_p, delta_s, beta2, shear):
    """S_rθ (sin-phase) of grad_P, of the sum grad_P + SV and of grad_S − grad_P at r."""
    inv_r = 1.0 / r
    two_mu = 2.0 * shear
    grad_p = two_mu * n * ((n + 1.0) * inv_r + delta_p) * inv_r
    total = shear * (2.0 * (n * delta_p - delta_s) * inv_r - beta2)
    diff = two_mu * n * (delta_s - delta_p) * inv_r
    return grad_p, total, diff


@numba.njit(cache=True, nogil=True)
def _solve_unit_radial(m00, m01, m02, m10, m11, m12, m20, m21, m22):
    """x of the complex 3×3 system M x = (1, 0, 0) by cofactors (no array allocation)."""
    c00 = m11 * m22 - m12 * m21
    c01 = m12 * m20 - m10 * m22
    c02 = m10 * m21 - m11 * m20
    inv_det = 1.0 / (m00 * c00 + m01 * c01 + m02 * c02)
    return c00 * inv_det, c01 * inv_det, c02 * inv_det


@numba.njit(cache=True, nogil=True)
def _interface_amplitudes(
    n, xi, omega, a, mass, extensional, bending, nu, alpha, beta, delta_p, delta_s,
    shear, lame, density,
):  # fmt: skip
    """Amplitudes (X, Y, Z) of harmonic n per unit radial traction cos nθ (1 Pa) on the shell."""
    k_shell = bending / (extensional * a * a)  # h²/(12a²)
    zeta = xi * a
    z2 = zeta * zeta
    stiff = extensional / (a * a)
    inertia = -(omega**2) * mass
    omega2_rho = omega * omega * density
    k1sq = omega2_rho / (lame + 2.0 * shear)
    k2sq = omega2_rho / shear
    beta2 = beta * beta
    ring_bending = bending * (n * n - 1.0) ** 2 / a**4
    s11 = stiff * (z2 + 0.5 * (1.0 - nu) * (1.0 + k_shell) * n * n) + inertia
    s12 = stiff * 0.5 * (1.0 + nu) * zeta * n
    s13 = stiff * zeta * (nu + k_shell * z2 - 0.5 * k_shell * (1.0 - nu) * n * n)
    s23 = stiff * n * (1.0 + 0.5 * k_shell * (3.0 - nu) * z2)
    s22 = inertia + stiff * (n * n + 0.5 * (1.0 - nu) * (1.0 + 3.0 * k_shell) * z2)
    # Shell bending beyond the ring's, k ζ²(ζ² + 2n²), added to the ring's (n² − 1)² term.
    s33 = inertia + stiff * (1.0 + k_shell * z2 * (z2 + 2.0 * n * n)) + ring_bending
    grad_p, total, diff, unit_axial = _field_vectors(
        n, a, xi, delta_p, delta_s, omega2_rho, k1sq, k2sq, shear, lame
    )
    # Column Z: SH − ξ grad_P = ξ (grad_S − grad_P) + k₂² e_x at r = a.
    z_col = (
        xi * diff[0],
        xi * diff[1] + k2sq * unit_axial[1],
        xi * diff[2] + k2sq * unit_axial[2],
        0j,
        0j,
        xi * diff[5] + k2sq * unit_axial[5],
    )
    if n == 0:  # radial and axial rows; columns X, Z (no SV)
        m00 = s13 * grad_p[1] + s33 * grad_p[0] - grad_p[2]
        m01 = s13 * z_col[1] + s33 * z_col[0] - z_col[2]
        m10 = s11 * grad_p[1] + s13 * grad_p[0] - grad_p[5]
        m11 = s11 * z_col[1] + s13 * z_col[0] - z_col[5]
        det = m00 * m11 - m01 * m10
        return m11 / det, 0j, -m10 / det
    srt_p, srt_sum, srt_diff = _shear_row_stresses(n, a, delta_p, delta_s, beta2, shear)
    srt_z = xi * srt_diff
    # Radial − tangential row, formed analytically (the K/a² terms cancel for n = 1 at ζ = 0).
    d_u = s13 - s12
    d_v = -inertia + stiff * (
        n * (1.0 - n)
        + z2 * (0.5 * k_shell * n * (3.0 - nu) - 0.5 * (1.0 - nu) * (1.0 + 3.0 * k_shell))
    )
    d_w = (
        inertia
        + stiff * ((1.0 - n) + k_shell * z2 * (z2 + 2.0 * n * n - 0.5 * n * (3.0 - nu)))
        + ring_bending
    )
    # S_rr − S_rθ of each column, formed analytically like the 2D model's difference terms.
    axial_p = 2.0 * shear * xi * xi - omega2_rho
    diff_p = axial_p + 2.0 * shear * (1.0 - n) * delta_p / a
    diff_sum = axial_p + shear * beta2 + 2.0 * shear * (1.0 - n) * (delta_p + delta_s) / a
    ddelta = delta_s - delta_p
    diff_z = (
        xi * (omega2_rho - (lame + 2.0 * shear) * k2sq + 2.0 * shear * (1.0 - n) * ddelta / a)
        + k2sq * lame * xi
    )
    # Tangential displacement U_θ of each column at r = a: −n/a, δ_S, 0.
    v_p = -n / a + 0j
    v_sum = delta_s
    return _solve_unit_radial(
        d_u * grad_p[1] + d_v * v_p + d_w * grad_p[0] - diff_p,
        d_u * total[1] + d_v * v_sum + d_w * total[0] - diff_sum,
        d_u * z_col[1] + d_w * z_col[0] - diff_z,
        s12 * grad_p[1] + s22 * v_p + s23 * grad_p[0] - srt_p,
        s12 * total[1] + s22 * v_sum + s23 * total[0] - srt_sum,
        s12 * z_col[1] + s23 * z_col[0] - srt_z,
        s11 * grad_p[1] + s12 * v_p + s13 * grad_p[0] - grad_p[5],
        s11 * total[1] + s12 * v_sum + s13 * total[0] - total[5],
        s11 * z_col[1] + s13 * z_col[0] - z_col[5],
    )


def _shell_soil_field(
    omega, xi, radius, load_coefficients, ring_radius, ring_mass, ring_extensional,
    ring_bending, ring_poisson, shear, lame, density, with_stresses, evanescent_cutoff,
    point_mask,
):  # fmt: skip
    """Soil field below the invert (θ = 0) of a radially loaded shell in a full-space.

    The shell (radius a, mass per area m, Flügge stiffnesses K, D, ν) carries the radial
    traction Σ_n p_n cos nθ exp(i(ωt − ξx)), p_n = load_coefficients[n] (Pa per unit load).

    Parameters: omega, xi (n_pairs,) paired rad/s > 0 and rad/m; radius (n_points,) m ≥ a;
    shear = μ*, lame = λ* complex (Pa); density (kg/m³); with_stresses: compute σ or leave 0;
    evanescent_cutoff: a point whose radial functions have both decayed by more than
    exp(−cutoff) from the shell, min(Re α, Re β)(r − a) > cutoff, is left 0 (its field is that
    small against the shell's: K_n(z r)/K_n(z a) ≤ e^{−Re z (r − a)} where it matters);
    point_mask (n_pairs, n_points) bool: the points to compute (the others left 0).
    Returns u_r, σ_rr, σ_θθ, σ_xx, S̃_rx (σ_rx = i S̃_rx), each complex (n_pairs, n_points),
    and done (n_pairs,), True for every frequency completed.
    """
    n_pairs = omega.size
    n_points = radius.size
    n_max = load_coefficients.size - 1
    shape = (n_pairs, n_points)
    u_r = np.zeros(shape, np.complex128)
    s_rr = np.zeros(shape, np.complex128)
    s_tt = np.zeros(shape, np.complex128)
    s_xx = np.zeros(shape, np.complex128)
    s_rx = np.zeros(shape, np.complex128)
    done = np.zeros(n_pairs, np.bool_)
    a = ring_radius
    slowness2_p = density / (lame + 2.0 * shear)
    slowness2_s = density / shear
    for i in numba.prange(n_pairs):
        w = omega[i]
        q = xi[i]
        ratio_p_a = np.empty(n_max + 1, np.complex128)  # per frequency: per thread
        ratio_s_a = np.empty(n_max + 1, np.complex128)
        amp_x = np.empty(n_max + 1, np.complex128)
        amp_y = np.empty(n_max + 1, np.complex128)
        amp_z = np.empty(n_max + 1, np.complex128)
        alpha = cmath.sqrt(q * q - w * w * slowness2_p)
        beta = cmath.sqrt(q * q - w * w * slowness2_s)
        omega2_rho = w * w * density
        k1sq = w * w * slowness2_p
        k2sq = w * w * slowness2_s
        k0p_a = bessel_ratios(alpha * a, n_max, ratio_p_a)
        k0s_a = bessel_ratios(beta * a, n_max, ratio_s_a)
        for n in range(n_max + 1):
            delta_p = log_derivative(alpha, ratio_p_a, n)
            delta_s = log_derivative(beta, ratio_s_a, n)
            x, y, z = _interface_amplitudes(
                n, q, w, a, ring_mass, ring_extensional, ring_bending, ring_poisson,
                alpha, beta, delta_p, delta_s, shear, lame, density,
            )  # fmt: skip
            p = load_coefficients[n]
            amp_x[n] = p * x
            amp_y[n] = p * y
            amp_z[n] = p * z
        # an explicit loop, not 1.0 / array, whose parallel compilation rounds differently
        inv_ratio_p_a = np.empty(n_max + 1, np.complex128)
        inv_ratio_s_a = np.empty(n_max + 1, np.complex128)
        for n in range(n_max + 1):
            inv_ratio_p_a[n] = 1.0 / ratio_p_a[n]
            inv_ratio_s_a[n] = 1.0 / ratio_s_a[n]
        decay_rate = min(alpha.real, beta.real)
        for j in range(n_points):
            r = radius[j]
            if not point_mask[i, j] or (r - a) * decay_rate > evanescent_cutoff:
                continue
            # at r = a, e_P = e_S = 1 exactly, so the differences e_P − e_S vanish
            e_p, ratio_p, two_over_zp = radial_start(alpha, r, a, k0p_a)
            e_s, ratio_s, two_over_zs = radial_start(beta, r, a, k0s_a)
            delta_p = alpha * ratio_p
            delta_s = beta * ratio_s
            inv_r = 1.0 / r
            # Sums over n from which the stresses follow after the loop: the coefficients of
            # _field_vectors are linear in c_P + c_sum, in the T terms (2μ* T/r in S_rr, minus
            # that in S_θθ), in c_diff and in c_axial, whose factors depend only on (ω, ξ).
            sum_ur = 0j
            sum_amp = 0j  # Σ c_P + c_sum
            sum_t = 0j  # Σ c_P (n(n+1)/r + δ_P) + c_sum (δ_P − n δ_S) + c_diff (δ_S − δ_P)
            sum_diff = 0j  # Σ c_diff
            sum_axial = 0j  # Σ c_axial
            sum_rx = 0j  # Σ S̃_rx / μ*
            for n in range(n_max + 1):
                # X e_P P + Y (e_P P + e_S SV) + Z (ξ e_S G_S − ξ e_P P + k₂² e_S e_x)
                #   = c_p P + c_sum (P + SV) + c_diff (G_S − P) + c_axial e_x
                c_p = amp_x[n] * e_p + (amp_y[n] - q * amp_z[n]) * (e_p - e_s)
                c_sum = amp_y[n] * e_s
                c_diff = q * amp_z[n] * e_s
                # U_r of grad_P, of the sum and of the difference: −n/r − δ_P, −δ_P, δ_P − δ_S
                sum_ur += c_p * (-n / r - delta_p) - c_sum * delta_p + c_diff * (delta_p - delta_s)
                if with_stresses:
                    c_axial = k2sq * amp_z[n] * e_s
                    n_r = n * inv_r
                    ddelta = delta_s - delta_p
                    sum_amp += c_p + c_sum
                    sum_t += (
                        c_p * (n_r * (n + 1.0) + delta_p)
                        + c_sum * (delta_p - n * delta_s)
                        + c_diff * ddelta
                    )
                    sum_diff += c_diff
                    sum_axial += c_axial
                    sum_rx += q * (
                        2.0 * c_p * (n_r + delta_p) + c_sum * (n_r + 2.0 * delta_p)
                        + 2.0 * c_diff * ddelta
                    ) - c_axial * (n_r + delta_s)  # fmt: skip
                if r != a:
                    e_p *= ratio_p * inv_ratio_p_a[n]
                    e_s *= ratio_s * inv_ratio_s_a[n]
                recip_p, ratio_p = next_ratio(ratio_p, n, two_over_zp)
                recip_s, ratio_s = next_ratio(ratio_s, n, two_over_zs)
                delta_p = alpha * recip_p
                delta_s = beta * recip_s
            u_r[i, j] = sum_ur
            if with_stresses:  # _field_vectors' coefficients applied to the sums
                two_mu = 2.0 * shear
                axial = two_mu * q * q
                lame_k1 = lame * k1sq
                dk = lame * (k1sq - k2sq)
                shear_part = two_mu * sum_t * inv_r
                lame_xi_axial = lame * q * sum_axial
                s_rr[i, j] = (
                    (axial - omega2_rho) * sum_amp + shear_part
                    + (omega2_rho - (lame + two_mu) * k2sq) * sum_diff + lame_xi_axial
                )  # fmt: skip
                s_tt[i, j] = -lame_k1 * sum_amp - shear_part + dk * sum_diff + lame_xi_axial
                s_xx[i, j] = (
                    (-lame_k1 - axial) * sum_amp + dk * sum_diff + (lame + two_mu) * q * sum_axial
                )
                s_rx[i, j] = shear * sum_rx
        done[i] = True
    return u_r, s_rr, s_tt, s_xx, s_rx, done


# Two compilations of one source, like the 2D kernel's (model.soil.section_2d): across the
# frequencies on Numba's threads, and serial (one Numba thread, or a forked process); the same
# arithmetic in the same order, so the same numbers.
shell_soil_field_kernel = numba.njit(cache=True, parallel=True, nogil=True)(_shell_soil_field)
shell_soil_field_serial = numba.njit(cache=True, nogil=True)(
    _compiled_as(_shell_soil_field, "shell_soil_field_serial")
)


# Decay exponent beyond which the kernel leaves a point's field 0: e^−45 ≈ 3e-20 of the field
# at the shell, far below rounding against any depth's peak (along ξ = ω/v at a subsonic speed
# the fields are evanescent, and most deep points at the higher frequencies are skipped).
EVANESCENT_CUTOFF = 45.0


# ---- public wrappers --------------------------------------------------------------------------
@dataclass(frozen=True)
class StressField:
    """Soil stresses (Pa) directly below the invert, complex, shape (n, n_depth).

    Per unit downward line load (N/m) at the invert varying as exp(i(ωt − ξx)), at θ = 0, x = 0;
    tension positive, exp(+iωt). By the symmetry of the load about θ = 0 the sin-type
    components σ_rθ and σ_θx vanish there; they are kept so the six components match the 2D
    notation.
    """

    sigma_rr: np.ndarray
    sigma_thetatheta: np.ndarray
    sigma_xx: np.ndarray
    sigma_rtheta: np.ndarray
    sigma_rx: np.ndarray
    sigma_thetax: np.ndarray


def paired_inputs(freq_hz, wavenumber_rad_per_m) -> tuple[np.ndarray, np.ndarray]:
    """(ω, ξ) as paired 1-D arrays (a scalar pairs with every entry of the other), ω > 0."""
    freq = as_1d(freq_hz, "freq_hz", "Hz")
    xi = as_1d(wavenumber_rad_per_m, "wavenumber_rad_per_m", "rad/m")
    if freq.size != xi.size and 1 not in (freq.size, xi.size):
        raise ValueError(
            f"freq_hz ({freq.size} values) and wavenumber_rad_per_m ({xi.size} values) must be "
            "paired: the same length, or one of them a scalar"
        )
    freq, xi = np.broadcast_arrays(freq, xi)
    if np.any(freq <= 0.0):
        bad = float(freq[freq <= 0.0][0])
        raise ValueError(
            f"freq_hz = {bad!r} is outside the allowed range (0, inf) Hz: at zero frequency the "
            "P and SH potentials coincide; evaluate a small positive frequency instead"
        )
    return np.ascontiguousarray(2.0 * np.pi * freq), np.ascontiguousarray(xi)


def _run_kernel(omega, xi, depth, tunnel, soil, n_harmonics, with_stresses, point_mask=None):
    """Unpack the parameter objects and run the kernel; refuse a non-finite result (ValueError).
    ``point_mask`` (n_pairs, n_depth) bool: the points to compute (default all)."""
    if point_mask is None:
        point_mask = np.ones((omega.size, np.size(depth)), dtype=bool)
    a, mass, extensional, bending = ring_constants(tunnel)
    shear, lame, density = soil_constants(soil)
    coefficients = invert_load_coefficients(a, check_harmonics(n_harmonics))
    arguments = (
        omega,
        xi,
        np.ascontiguousarray(a + depth),
        coefficients,
        a,
        mass,
        extensional,
        bending,
        float(tunnel.poisson_ratio),
        shear,
        lame,
        density,
        with_stresses,
        EVANESCENT_CUTOFF,
        np.ascontiguousarray(point_mask, dtype=bool),
    )
    try:
        if use_serial_kernel():
            fields = shell_soil_field_serial(*arguments)
        else:
            # An exception in one of Numba's threads (a division by zero at a branch point)
            # comes back garbled (a SystemError) or not at all (its frequencies not done): the
            # serial compilation then raises it properly (or gives the same numbers).
            try:
                fields = shell_soil_field_kernel(*arguments)
            except Exception:
                fields = None
            if fields is None or not np.all(fields[-1]):
                fields = shell_soil_field_serial(*arguments)
    except ZeroDivisionError:
        raise ValueError(
            "a wavenumber equals the P- or S-wavenumber ω/c of an undamped soil (a branch "
            "point, α or β = 0, where the potentials degenerate); move it slightly or give the "
            "soil a loss factor"
        ) from None
    fields = fields[:-1]
    for field in fields:
        if not np.all(np.isfinite(field)):
            raise ValueError(
                "the shell–soil solution is not finite; check the inputs "
                "(extreme frequency, wavenumber or parameters)"
            )
    return fields


def receptance_2p5d(
    freq_hz, wavenumber_rad_per_m, depth_m, tunnel, soil, n_harmonics: int
) -> np.ndarray:
    """Downward displacement under the invert per unit downward line load exp(i(ωt − ξx)).

    H(ω, ξ, d) of docs/model.md §9: the point is r = a + d, θ = 0, x = 0; the load a line load
    (N/m) at the invert varying as exp(i(ωt − ξx)); harmonics n = 0..N summed. H is even in ξ
    and H(ω, 0, d) is ``model.soil.section_2d.invert_receptance``.

    Parameters
    ----------
    freq_hz : float or array_like
        Frequencies f (Hz), finite and > 0.
    wavenumber_rad_per_m : float or array_like
        Wavenumbers ξ along the tunnel (rad/m), paired with ``freq_hz`` (same length, or
        either a scalar).
    depth_m : float or array_like
        Depths d ≥ 0 below the ring–soil interface (m).
    tunnel : model.params.Tunnel
        Lining (Flügge shell of radius ``tunnel.ring_radius``).
    soil : model.params.Soil
        Full-space soil with hysteretic loss factors.
    n_harmonics : int
        Highest circumferential harmonic N ≥ 0.

    Returns
    -------
    ndarray
        Complex (n, n_depth) receptance in m per N/m, exp(+iωt).
    """
    omega, xi = paired_inputs(freq_hz, wavenumber_rad_per_m)
    depth = checked_depths(depth_m)
    return _run_kernel(omega, xi, depth, tunnel, soil, n_harmonics, with_stresses=False)[0]


def invert_stress_2p5d(
    freq_hz, wavenumber_rad_per_m, depth_m, tunnel, soil, n_harmonics: int
) -> StressField:
    """All six soil stresses below the invert per unit downward line load exp(i(ωt − ξx)).

    At ξ = 0, σ_rr, σ_θθ, σ_rθ are those of ``model.soil.section_2d.soil_field`` at θ = 0 and
    σ_xx = λ*(ε_rr + ε_θθ) (plane strain).

    Parameters
    ----------
    freq_hz, wavenumber_rad_per_m : float or array_like
        Paired frequencies (Hz, > 0) and wavenumbers (rad/m), as in :func:`receptance_2p5d`.
    depth_m : float or array_like
        Depths d ≥ 0 below the ring–soil interface (m).
    tunnel, soil : model.params.Tunnel, model.params.Soil
        Lining and soil.
    n_harmonics : int
        Highest circumferential harmonic N ≥ 0.

    Returns
    -------
    StressField
        Complex (n, n_depth) stresses in Pa per N/m, tension positive, at θ = 0, x = 0.
    """
    return invert_response_2p5d(freq_hz, wavenumber_rad_per_m, depth_m, tunnel, soil, n_harmonics)[
        1
    ]


def invert_response_2p5d(
    freq_hz, wavenumber_rad_per_m, depth_m, tunnel, soil, n_harmonics: int, point_mask=None
) -> tuple[np.ndarray, StressField]:
    """Receptance and stresses below the invert from one kernel evaluation.

    The per-(n, ξ, ω) shell–soil solve is shared: the receptance equals
    :func:`receptance_2p5d`'s and the stresses :func:`invert_stress_2p5d`'s, at the cost of
    one evaluation.

    Parameters
    ----------
    freq_hz, wavenumber_rad_per_m : float or array_like
        Paired frequencies (Hz, > 0) and wavenumbers (rad/m), as in :func:`receptance_2p5d`.
    depth_m : float or array_like
        Depths d ≥ 0 below the ring–soil interface (m).
    tunnel, soil : model.params.Tunnel, model.params.Soil
        Lining and soil.
    n_harmonics : int
        Highest circumferential harmonic N ≥ 0.
    point_mask : ndarray, optional
        (n, n_depth) bool: only these (frequency, depth) pairs are computed, the others are 0
        (default: all).

    Returns
    -------
    (ndarray, StressField)
        Complex (n, n_depth) receptance in m per N/m and stresses in Pa per N/m.
    """
    omega, xi = paired_inputs(freq_hz, wavenumber_rad_per_m)
    depth = checked_depths(depth_m)
    u_r, s_rr, s_tt, s_xx, s_rx = _run_kernel(
        omega, xi, depth, tunnel, soil, n_harmonics, with_stresses=True, point_mask=point_mask
    )
    zero = np.zeros_like(s_rr)
    return u_r, StressField(
        sigma_rr=s_rr,
        sigma_thetatheta=s_tt,
        sigma_xx=s_xx,
        sigma_rtheta=zero,
        sigma_rx=1j * s_rx,
        sigma_thetax=zero.copy(),
    )
