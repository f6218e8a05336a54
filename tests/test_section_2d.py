"""Ring in an elastic full-space (model.soil.section_2d): closed forms, field equations, an
independent finite-element model, passivity, convergence and input errors."""

import multiprocessing
from types import SimpleNamespace

import numba
import numpy as np
import param
import pytest
import scipy.sparse
import scipy.sparse.linalg
from scipy.special import kv, kve

from model.params import Scenario, Soil, Tunnel
from model.soil.bessel import bessel_k01_scaled
from model.soil.inputs import invert_load_coefficients
from model.soil.section_2d import (
    harmonic_field,
    invert_receptance,
    ring_displacement,
    ring_displacement_harmonics,
    ring_soil_field_kernel,
    ring_soil_field_serial,
    soil_field,
)


def complex_moduli(soil):
    """(μ*, λ*) as the model sheet defines them, written out independently of the module."""
    shear = soil.shear_modulus * (1 + 1j * soil.shear_loss_factor)
    bulk = soil.bulk_modulus * (1 + 1j * soil.bulk_loss_factor)
    return shear, bulk - 2 * shear / 3


class IdealisedTunnel(Tunnel):
    """A Tunnel whose ring may leave the physical bounds, for closed-form limits only.

    The empty cavity and the vanishing radius are limits of the model, not linings: the
    subclass widens the declared bounds of model.params on purpose, and model.soil.section_2d
    checks an object against the bounds its own class declares.
    """

    inner_radius = param.Number(2.7, bounds=(0, None), inclusive_bounds=(False, True))
    thickness = param.Number(0.3, bounds=(0, None), inclusive_bounds=(False, True))
    youngs_modulus = param.Number(3.45e10, bounds=(0, None), inclusive_bounds=(False, True))
    density = param.Number(2450.0, bounds=(0, None), inclusive_bounds=(False, True))


def flexible_light_ring(**overrides):
    """A lining with negligible stiffness and mass: K/a² ≈ 0.04 Pa/m vs soil μ/a ≈ 8e5 Pa/m."""
    return IdealisedTunnel(**{"youngs_modulus": 1.0, "density": 1e-6, **overrides})


SOILS = {
    "paper": Soil(),
    "undamped": Soil(shear_loss_factor=0.0),
    "bulk_damped": Soil(bulk_loss_factor=0.05),
    "stiff_lame": Scenario.paper_soil_lame().soil,
    "wave_speeds": Scenario.paper_soil_wave_speeds().soil,
}


# ---- Bessel functions ---------------------------------------------------------------------
def test_bessel_k01_matches_scipy_over_the_right_half_plane():
    """K₀ eᶻ, K₁ eᶻ on |z| ∈ [1e-6, 1e3], arg z ∈ [0, π/2] (all three algorithms).

    Tolerance 5e-14: each series stops at 1e-17 relative, leaving rounding of a few ulp per
    term over ≲ 140 terms; observed ≤ 1e-14.
    """
    rng = np.random.default_rng(7)
    modulus = 10.0 ** rng.uniform(-6, 3, 4000)
    angle = rng.uniform(0, np.pi / 2, modulus.size)
    angle[:200] = np.pi / 2  # undamped soil: purely imaginary argument
    z = modulus * np.exp(1j * angle)
    ours = np.array([bessel_k01_scaled(value) for value in z])
    np.testing.assert_allclose(ours[:, 0], kve(0, z), rtol=5e-14)
    np.testing.assert_allclose(ours[:, 1], kve(1, z), rtol=5e-14)


# ---- static limits (empty cavity) ------------------------------------------------------------
def near_static_freq_hz(soil, tunnel):
    """Frequency with ωa/c₂ = 5e-4: static to O((ωr/c₂)² ln) and, with ωa/c₁ ≳ 1e-4, clear of
    the ε/(ωa/c₁)² rounding of the nearly parallel P and SV solutions (module docstring)."""
    return 5e-4 * soil.s_wave_speed / (2 * np.pi * tunnel.ring_radius)


@pytest.mark.parametrize("soil_name", ["undamped", "paper", "bulk_damped"])
def test_uniform_pressure_on_empty_cavity_gives_lame_solution(soil_name):
    """n = 0, radial pressure p on a cavity: u_r = p a²/(2μ r) (plane strain, any r ≥ a).

    With loss factors the static limit is the same formula with μ* (correspondence principle).
    Tolerance 2e-5: the dynamic solution differs from the static one by O((ωr/c₂)² ln(ωr/c₂)),
    ≤ 1e-5 for r ≤ 5a at ωa/c₂ = 5e-4 (observed ≤ 7e-6).
    """
    soil = SOILS[soil_name]
    tunnel = flexible_light_ring()
    a = tunnel.ring_radius
    radius = a * np.array([1.0, 1.3, 2.0, 5.0])
    shear, _ = complex_moduli(soil)
    field = harmonic_field(near_static_freq_hz(soil, tunnel), radius, tunnel, soil, 0)
    np.testing.assert_allclose(field.u_r[0], a**2 / (2 * shear * radius), rtol=2e-5)
    np.testing.assert_allclose(field.sigma_rr[0], -((a / radius) ** 2), rtol=2e-5)
    np.testing.assert_allclose(field.sigma_thetatheta[0], (a / radius) ** 2, rtol=2e-5)


@pytest.mark.parametrize("soil_name", ["undamped", "paper", "bulk_damped", "stiff_lame"])
def test_cos2theta_pressure_on_empty_cavity(soil_name):
    """n = 2, radial pressure p cos 2θ on a cavity: u_r(a) = (pa/2μ)(5/3 − 2ν) cos 2θ.

    (Michell solution; with loss factors μ*, ν* = λ*/(2(λ* + μ*)).) Tolerance 2e-5 as above.
    """
    soil = SOILS[soil_name]
    tunnel = flexible_light_ring()
    a = tunnel.ring_radius
    shear, lame = complex_moduli(soil)
    poisson = lame / (2 * (lame + shear))
    field = harmonic_field(near_static_freq_hz(soil, tunnel), a, tunnel, soil, 2)
    np.testing.assert_allclose(field.u_r[0, 0], a / (2 * shear) * (5 / 3 - 2 * poisson), rtol=2e-5)
    # Traction boundary condition of the empty cavity: σ_rr = −p, σ_rθ = 0 at r = a.
    assert field.sigma_rr[0, 0] == pytest.approx(-1.0, rel=1e-6)
    assert abs(field.sigma_rtheta[0, 0]) < 1e-6


def kelvin_log_slope(soil):
    """B = −(3 − 4ν*)/(8πμ*(1 − ν*)): coefficient of ln ω in the 2D line-load response."""
    shear, lame = complex_moduli(soil)
    poisson = lame / (2 * (lame + shear))
    return -(3 - 4 * poisson) / (8 * np.pi * shear * (1 - poisson))


@pytest.mark.parametrize("soil_name", ["undamped", "paper", "stiff_lame"])
def test_interface_receptance_grows_like_log_of_one_over_frequency(soil_name):
    """2D line load: H(f) = A + B ln f + O((ωa/c₂)² ln ω) as f → 0, with Kelvin's B.

    The coefficient of ln is fixed by the net force alone, so it holds for the real, stiff
    lining, whose K/a ≫ μ would amplify rounding in a naive P/SV basis. The relative error of
    the slope (H(2f) − H(f))/ln 2 must be the physical curvature only: it falls like f²
    (observed order 1.8–1.9, the ln makes it < 2; fit 1.6–2.1) from 1e-3 to 1e-5 Hz, where it
    is < 1e-8 (observed 4e-9); rounding would instead grow as f falls.
    """
    soil = SOILS[soil_name]
    freq = np.array([1e-5, 1e-4, 1e-3])
    errors = []
    for f in freq:
        h = invert_receptance([f, 2 * f], 0.0, Tunnel(), soil, 32)[:, 0]
        errors.append(abs((h[1] - h[0]) / np.log(2.0) / kelvin_log_slope(soil) - 1))
    order = np.polyfit(np.log(freq), np.log(errors), 1)[0]
    assert 1.6 < order < 2.1
    assert errors[0] < 1e-8 and errors[2] < 3e-5


@pytest.mark.parametrize("soil_name", ["undamped", "paper"])
def test_receptance_at_depth_grows_like_log_of_one_over_frequency(soil_name):
    """Same log slope at 5 m and 30 m below the interface, at 1e-4 and 2e-4 Hz.

    Tolerance 3e-5: physical corrections O((ωr/c₂)² ln) ≤ 1e-5 for r ≤ 33 m, rounding
    ε/(ωa/c₁)² ≈ 1e-8 (module docstring), ×10 for the difference of two values.
    """
    soil = SOILS[soil_name]
    h = invert_receptance([1e-4, 2e-4], [5.0, 30.0], Tunnel(), soil, 32)
    np.testing.assert_allclose((h[1] - h[0]) / np.log(2.0), kelvin_log_slope(soil), rtol=3e-5)


# ---- field equations by finite differences --------------------------------------------------
def cartesian_field(freq_hz, x, y, tunnel, soil, n_harmonics):
    """Displacement (u_x, u_y) and stress (σ_xx, σ_yy, σ_xy) at Cartesian points, x down."""
    radius, theta = np.hypot(x, y), np.arctan2(y, x)
    field = soil_field(freq_hz, radius, theta, tunnel, soil, n_harmonics)
    c, s = np.cos(theta), np.sin(theta)
    u_x = field.u_r[0] * c - field.u_theta[0] * s
    u_y = field.u_r[0] * s + field.u_theta[0] * c
    s_rr, s_tt, s_rt = field.sigma_rr[0], field.sigma_thetatheta[0], field.sigma_rtheta[0]
    s_xx = s_rr * c**2 + s_tt * s**2 - 2 * s_rt * c * s
    s_yy = s_rr * s**2 + s_tt * c**2 + 2 * s_rt * c * s
    s_xy = (s_rr - s_tt) * c * s + s_rt * (c**2 - s**2)
    return np.array([u_x, u_y]), np.array([s_xx, s_yy, s_xy])


# Points in the soil (x down, y sideways): below, beside and above the tunnel, near and far.
FD_POINTS = np.array([[4.5, 1.9], [-3.2, 6.1], [0.4, -3.3], [9.0, -4.0]])
FD_FREQ_HZ = 5.0


def navier_residual(step, soil, tunnel):
    """max |μ∇²u + (λ+μ)∇(∇·u) + ρω²u| / max |ρω²u| over FD_POINTS, central differences."""
    shear, lame = complex_moduli(soil)
    omega2 = (2 * np.pi * FD_FREQ_HZ) ** 2
    offsets = (
        np.array([[0, 0], [1, 0], [-1, 0], [0, 1], [0, -1], [1, 1], [1, -1], [-1, 1], [-1, -1]])
        * step
    )
    points = (FD_POINTS[:, None, :] + offsets[None]).reshape(-1, 2)
    u, _ = cartesian_field(FD_FREQ_HZ, points[:, 0], points[:, 1], tunnel, soil, 24)
    u = u.reshape(2, len(FD_POINTS), len(offsets))
    uxx = (u[..., 1] - 2 * u[..., 0] + u[..., 2]) / step**2
    uyy = (u[..., 3] - 2 * u[..., 0] + u[..., 4]) / step**2
    uxy = (u[..., 5] - u[..., 6] - u[..., 7] + u[..., 8]) / (4 * step**2)
    grad_div = np.array([uxx[0] + uxy[1], uxy[0] + uyy[1]])
    residual = shear * (uxx + uyy) + (lame + shear) * grad_div + soil.density * omega2 * u[..., 0]
    return np.abs(residual).max() / np.abs(soil.density * omega2 * u[..., 0]).max()


@pytest.mark.parametrize("soil_name", ["paper", "bulk_damped"])
def test_soil_field_satisfies_navier_equations(soil_name):
    """The summed field solves μ*∇²u + (λ*+μ*)∇(∇·u) + ρω²u = 0 in the soil.

    Central differences have error O(h²): the residual must fall at observed order ≈ 2
    (fit 1.8–2.2; observed 2.00) and be below 5e-4 of the inertia term at h = 2.5 cm
    (observed 1.4e-4: the point 0.47 m from the lining carries harmonics up to n = 24, whose
    truncation is ~(n/r)² h²/12 of their size; rounding ε/(kh)² ≈ 1e-10).
    """
    soil, tunnel = SOILS[soil_name], Tunnel()
    steps = np.array([0.2, 0.1, 0.05, 0.025])
    residuals = np.array([navier_residual(h, soil, tunnel) for h in steps])
    order = np.polyfit(np.log(steps), np.log(residuals), 1)[0]
    assert 1.8 < order < 2.2
    assert residuals[-1] < 5e-4


def test_stresses_are_hookes_law_of_the_displacement_gradient():
    """σ from the module equals λ*(∇·u)I + μ*(∇u + ∇uᵀ) with ∇u by central differences.

    Step 1 mm: truncation ≲ (n/r)² h²/6 ≈ 9e-6 relative (n ≤ 24 at r ≥ 3.3 m), rounding
    ≈ ε/(kh) ≈ 3e-13; tolerance 1e-5 of the largest stress component at each point (observed
    1.6e-7).
    """
    soil, tunnel = Soil(), Tunnel()
    shear, lame = complex_moduli(soil)
    step = 1e-3
    offsets = np.array([[0, 0], [1, 0], [-1, 0], [0, 1], [0, -1]]) * step
    points = (FD_POINTS[:, None, :] + offsets[None]).reshape(-1, 2)
    u, stress = cartesian_field(FD_FREQ_HZ, points[:, 0], points[:, 1], tunnel, soil, 24)
    u = u.reshape(2, len(FD_POINTS), len(offsets))
    stress = stress.reshape(3, len(FD_POINTS), len(offsets))[..., 0]
    du_dx = (u[..., 1] - u[..., 2]) / (2 * step)
    du_dy = (u[..., 3] - u[..., 4]) / (2 * step)
    divergence = du_dx[0] + du_dy[1]
    expected = np.array(
        [
            lame * divergence + 2 * shear * du_dx[0],
            lame * divergence + 2 * shear * du_dy[1],
            shear * (du_dy[0] + du_dx[1]),
        ]
    )
    scale = np.abs(stress).max(axis=0)
    assert np.all(np.abs(stress - expected) / scale < 1e-5)


def test_ring_obeys_newtons_second_law_as_a_whole():
    """Net vertical force on the ring: F′ + soil traction resultant = −ω² m ∮ u_x ds.

    Only n = 1 carries a resultant; its elastic ring terms vanish for a rigid translation, so
    this checks the ring operator and the interface traction sign together. Tolerance 1e-10:
    the identity is exact, up to rounding.
    """
    soil, tunnel = Soil(), Tunnel()
    a, mass = tunnel.ring_radius, tunnel.density * tunnel.thickness
    freq = np.array([0.7, 6.0, 25.0])
    field = harmonic_field(freq, a, tunnel, soil, 1)
    coefficient = invert_load_coefficients(a, 1)[1]
    # ∮ (σ_rr cos θ − σ_rθ sin θ) a dθ for the n = 1 field is π a (S_rr − S_rθ), likewise for u.
    traction = np.pi * a * coefficient * (field.sigma_rr[:, 0] - field.sigma_rtheta[:, 0])
    momentum = np.pi * a * coefficient * (field.u_r[:, 0] - field.u_theta[:, 0])
    omega2 = (2 * np.pi * freq) ** 2
    np.testing.assert_allclose(1.0 + traction, -omega2 * mass * momentum, rtol=1e-10)


# ---- small cavity → full-space line-load Green's function -----------------------------------
def line_load_green_function(freq_hz, distance_m, soil):
    """u_x at (x = r, y = 0) from a unit line load along x at the origin, full space, e^{iωt}.

    G = [k₂² g₂ I + ∇∇(g₂ − g₁)]/(ρω²), g = K₀(s r)/(2π); along the load direction this gives
    u = [(β K₁(βr) − α K₁(αr))/r − α² K₀(αr)] / (2πρω²).
    """
    shear, lame = complex_moduli(soil)
    omega = 2 * np.pi * np.asarray(freq_hz)[:, None]
    alpha = 1j * omega * np.sqrt(soil.density / (lame + 2 * shear))
    beta = 1j * omega * np.sqrt(soil.density / shear)
    r = np.asarray(distance_m)[None, :]
    return (
        (beta * kv(1, beta * r) - alpha * kv(1, alpha * r)) / r - alpha**2 * kv(0, alpha * r)
    ) / (2 * np.pi * soil.density * omega**2)


def test_small_flexible_cavity_approaches_the_line_load_green_function():
    """As a → 0 the invert receptance at depth d tends to the full-space G_xx(d).

    The cavity and the distributed load perturb the far field by O(a/d): the error must fall
    at observed order 1 (fit 0.9–1.1) and be below 2.5 % at a = 1 cm (observed 2.2 %).
    """
    soil = Soil()
    freq, depth = np.array([0.5, 2.0, 8.0]), np.array([1.0, 3.0, 10.0])
    green = line_load_green_function(freq, depth, soil)
    radii = np.array([0.08, 0.04, 0.02, 0.01])
    errors = []
    for inner in radii:
        tunnel = flexible_light_ring(inner_radius=inner, thickness=inner / 20)
        h = invert_receptance(freq, depth, tunnel, soil, 200)
        errors.append(np.abs(h / green - 1).max())
    order = np.polyfit(np.log(radii), np.log(errors), 1)[0]
    assert 0.9 < order < 1.1
    assert errors[-1] < 0.025


# ---- passivity ------------------------------------------------------------------------------
@pytest.mark.parametrize("soil_name", sorted(SOILS))
def test_input_power_at_the_load_point_is_never_negative(soil_name):
    """P = ½ ω |F′|² (−Im H(f, 0)) ≥ 0 for exp(+iωt); radiation makes it strictly > 0.

    Exact sign condition, no tolerance; checked on 0.001–300 Hz and 4 harmonic counts.
    """
    freq = np.geomspace(1e-3, 300.0, 500)
    for n_harmonics in (0, 4, 32, 128):
        h = invert_receptance(freq, 0.0, Tunnel(), SOILS[soil_name], n_harmonics)
        assert np.all(h.imag < 0.0), n_harmonics


# ---- convergence in the number of harmonics ---------------------------------------------
def test_receptance_converges_in_harmonics_at_the_ring_bending_rate():
    """At the interface the tail of Σ W_n is ~N⁻³ (W_n ~ n⁻⁴ from the ring bending term).

    Fitted order over N = 16–128 against N = 512 must lie in [2.7, 3.3]; with the default
    N = 32 the error is below 1e-3 at d = 0 and 1e-4 at d ≥ 2 m on 0.5–100 Hz.
    """
    freq, depth = np.array([0.5, 3.0, 12.0, 40.0, 100.0]), np.array([0.0, 2.0, 11.0])
    tunnel, soil = Tunnel(), Soil()
    reference = invert_receptance(freq, depth, tunnel, soil, 512)
    counts = np.array([16, 32, 64, 128])
    errors = np.array(
        [
            np.abs(invert_receptance(freq, depth, tunnel, soil, n) / reference - 1).max(axis=0)
            for n in counts
        ]
    )
    order = -np.polyfit(np.log(counts), np.log(errors[:, 0]), 1)[0]
    assert 2.7 < order < 3.3
    assert errors[1, 0] < 1e-3 and np.all(errors[1, 1:] < 1e-4)


# ---- independent check: Fourier finite elements on a complex-scaled radial contour ----------
# Shares nothing with the closed form: no potentials, no Bessel functions. Per harmonic n the
# 2D field u_r = U(r) cos nθ, u_θ = V(r) sin nθ is discretised in r by quadratic elements of
# the plane-strain weak form; the ring enters through its strain energy (membrane strain
# (v′ + w)/a, curvature change (w″ + w)/a²) and kinetic energy at r = a; radiation is imposed
# by continuing r into the complex plane beyond R (r = R − is), where every outgoing wave
# decays like e^{−ks} without oscillating, and clamping the far end.
GAUSS_X, GAUSS_W = np.polynomial.legendre.leggauss(4)
SHAPE = np.array([GAUSS_X * (GAUSS_X - 1) / 2, 1 - GAUSS_X**2, GAUSS_X * (GAUSS_X + 1) / 2])
SHAPE_DERIV = np.array([GAUSS_X - 0.5, -2 * GAUSS_X, GAUSS_X + 0.5])


def fe_contour_nodes(a, real_end, step, decay_length, growth):
    """Quadratic-element nodes: uniform on [a, real_end], then geometric along r = R − is."""
    real = np.linspace(a, real_end, int(np.ceil((real_end - a) / step - 1e-9)) + 1)
    s, size = [0.0], step
    while s[-1] < 30 * decay_length:
        s.append(s[-1] + size)
        size *= growth
    vertices = np.concatenate([real, real_end - 1j * np.array(s[1:])])
    nodes = np.empty(2 * vertices.size - 1, dtype=complex)
    nodes[0::2], nodes[1::2] = vertices, 0.5 * (vertices[:-1] + vertices[1:])
    return nodes


def fe_harmonic(freq_hz, n, tunnel, soil, step=0.05, real_end=None):
    """Nodes on the real axis and U there, for a radial traction cos nθ (1 Pa) on the ring."""
    a = tunnel.ring_radius
    shear, lame = complex_moduli(soil)
    omega = 2 * np.pi * freq_hz
    p_wavenumber = omega / np.sqrt((lame + 2 * shear).real / soil.density)
    nodes = fe_contour_nodes(
        a, a + 12.0 if real_end is None else real_end, step, 1 / p_wavenumber, 1 + 2 * step
    )
    n_dof = 2 * nodes.size
    constitutive = np.array(
        [[lame + 2 * shear, lame, 0], [lame, lame + 2 * shear, 0], [0, 0, shear]]
    )
    rows, cols, values = [], [], []
    for e in range((nodes.size - 1) // 2):
        element = nodes[2 * e : 2 * e + 3]
        r, jacobian = element @ SHAPE, element @ SHAPE_DERIV
        d_shape = SHAPE_DERIV / jacobian
        strain = np.zeros((GAUSS_X.size, 3, 6), dtype=complex)  # (ε_rr, ε_θθ, γ_rθ) per dof
        strain[:, 0, 0::2] = d_shape.T
        strain[:, 1, 0::2] = (SHAPE / r).T
        strain[:, 1, 1::2] = (n * SHAPE / r).T
        strain[:, 2, 0::2] = (-n * SHAPE / r).T
        strain[:, 2, 1::2] = (d_shape - SHAPE / r).T
        displacement = np.zeros((GAUSS_X.size, 2, 6))
        displacement[:, 0, 0::2] = SHAPE.T
        displacement[:, 1, 1::2] = SHAPE.T
        weight = GAUSS_W * r * jacobian
        stiffness = np.einsum("g,gia,ij,gjb->ab", weight, strain, constitutive, strain)
        mass = np.einsum("g,gia,gib->ab", weight, displacement, displacement)
        dofs = (2 * np.arange(2 * e, 2 * e + 3)[:, None] + np.arange(2)).ravel()
        rows.append(np.repeat(dofs, 6))
        cols.append(np.tile(dofs, 6))
        values.append((stiffness - omega**2 * soil.density * mass).ravel())
    # Ring: energy ½∮[K ε² + D κ²] a dθ with ε = (nV + W)/a, κ = (1 − n²)W/a², minus kinetic.
    extensional, bending = tunnel.extensional_stiffness, tunnel.bending_stiffness
    membrane = np.array([1.0, n]) / a
    ring = a * (
        extensional * np.outer(membrane, membrane)
        + bending * np.diag([(1 - n * n) ** 2 / a**4, 0.0])
        - omega**2 * tunnel.density * tunnel.thickness * np.eye(2)
    )
    rows.append(np.array([0, 0, 1, 1]))
    cols.append(np.array([0, 1, 0, 1]))
    values.append(ring.ravel())
    matrix = scipy.sparse.coo_matrix(
        (np.concatenate(values), (np.concatenate(rows), np.concatenate(cols))), shape=(n_dof, n_dof)
    ).tocsc()[:-2, :-2]  # clamp the far end of the contour
    load = np.zeros(n_dof - 2, dtype=complex)
    load[0] = a  # work of the traction on the ring: ∮ p δW a dθ
    solution = scipy.sparse.linalg.spsolve(matrix, load)
    on_axis = nodes[:-1].imag == 0
    return nodes[:-1][on_axis].real, solution[0::2][on_axis]


def fe_values_at(freq_hz, n, tunnel, soil, depths, step=0.05):
    """FE U_n at the given depths below the ring (depths on the element grid)."""
    radius, u = fe_harmonic(freq_hz, n, tunnel, soil, step)
    index = [int(np.argmin(np.abs(radius - tunnel.ring_radius - d))) for d in depths]
    return u[index]


FE_DEPTHS = np.array([0.0, 3.0, 10.0])


@pytest.mark.parametrize("soil_name", ["paper", "stiff_lame"])
@pytest.mark.parametrize("freq_hz", [0.5, 4.0, 15.0])
def test_closed_form_matches_independent_finite_element_model(soil_name, freq_hz):
    """Per harmonic n = 0, 1, 2, 3, 8, the closed form agrees with the FE model of the same
    ring–soil section at d = 0, 3, 10 m.

    Tolerance 1e-4: the FE error at h = 5 cm is ≤ 4e-5 here (it converges at order ≈ 3.5, see
    the next test), the closed form is exact to rounding.
    """
    soil, tunnel = SOILS[soil_name], Tunnel()
    for n in (0, 1, 2, 3, 8):
        closed = harmonic_field(freq_hz, tunnel.ring_radius + FE_DEPTHS, tunnel, soil, n).u_r[0]
        fe = fe_values_at(freq_hz, n, tunnel, soil, FE_DEPTHS)
        np.testing.assert_allclose(fe, closed, rtol=1e-4, err_msg=f"n = {n}")


def test_finite_element_model_converges_to_the_closed_form():
    """FE error against the closed form falls with the element size at order 3–4.5 (quadratic
    elements: O(h³) in general, O(h⁴) at nodes), so the agreement is not a coincidence."""
    soil, tunnel = Soil(), Tunnel()
    steps = np.array([0.4, 0.2, 0.1, 0.05])
    for freq_hz, n in ((0.5, 1), (4.0, 2), (15.0, 6)):
        closed = harmonic_field(freq_hz, tunnel.ring_radius + FE_DEPTHS, tunnel, soil, n).u_r[0]
        errors = [
            np.abs(fe_values_at(freq_hz, n, tunnel, soil, FE_DEPTHS, h) / closed - 1).max()
            for h in steps
        ]
        order = np.polyfit(np.log(steps), np.log(errors), 1)[0]
        assert 3.0 < order < 4.5, (freq_hz, n, order)


def test_coupled_invert_receptance_matches_finite_element_sum():
    """Σ_n c_n U_n from the FE model (n = 0..16) equals invert_receptance with N = 16.

    Tolerance 1e-4 as for the single harmonics.
    """
    soil, tunnel = Soil(), Tunnel()
    n_harmonics, freq_hz = 16, 3.0
    coefficients = invert_load_coefficients(tunnel.ring_radius, n_harmonics)
    fe = sum(
        c * fe_values_at(freq_hz, n, tunnel, soil, FE_DEPTHS) for n, c in enumerate(coefficients)
    )
    closed = invert_receptance(freq_hz, FE_DEPTHS, tunnel, soil, n_harmonics)[0]
    np.testing.assert_allclose(fe, closed, rtol=1e-4)


# ---- consistency of the public views --------------------------------------------------------
def test_ring_views_agree_with_the_receptance_and_each_other():
    """Ring displacement at the invert = receptance at d = 0; harmonic amplitudes sum to the
    ring displacement at any θ (both exact up to rounding: rtol 1e-12)."""
    soil, tunnel, n = Soil(), Tunnel(), 20
    freq, theta = np.array([0.8, 7.0]), np.array([0.0, 0.9, np.pi / 2, np.pi])
    w, v = ring_displacement(freq, theta, tunnel, soil, n)
    np.testing.assert_allclose(
        w[:, 0], invert_receptance(freq, 0.0, tunnel, soil, n)[:, 0], rtol=1e-12
    )
    w_n, v_n = ring_displacement_harmonics(freq, tunnel, soil, n)
    orders = np.arange(n + 1)
    np.testing.assert_allclose(w, w_n @ np.cos(np.outer(orders, theta)), rtol=1e-12)
    np.testing.assert_allclose(
        v, v_n @ np.sin(np.outer(orders, theta)), rtol=1e-12, atol=1e-12 * np.abs(v).max()
    )


# ---- input errors ---------------------------------------------------------------------------
class LooseSoil(Soil):
    """A Soil whose parameters lack bounds, as a downstream subclass might define it."""

    poisson_ratio = param.Number(0.3, bounds=None, softbounds=None)
    shear_loss_factor = param.Number(0.06, bounds=None, softbounds=None)


def duck_soil(**overrides):
    """A plain object with a Soil's attributes and derived values (not a param object)."""
    values = {name: getattr(Soil(), name) for name in Soil.param if name != "name"}
    soil = Soil()
    return SimpleNamespace(
        **{**values, **overrides},
        shear_modulus=soil.shear_modulus,
        bulk_modulus=soil.bulk_modulus,
    )


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: invert_receptance(0.0, 1.0, Tunnel(), Soil(), 8), r"freq_hz = 0\.0 .*\(0, inf\)"),
        (lambda: invert_receptance([1.0, -2.0], 1.0, Tunnel(), Soil(), 8), r"freq_hz = -2\.0"),
        (lambda: invert_receptance(np.nan, 1.0, Tunnel(), Soil(), 8), r"freq_hz contains nan"),
        (lambda: invert_receptance(1.0, -0.1, Tunnel(), Soil(), 8), r"depth_m = -0\.1 is inside"),
        (lambda: soil_field(1.0, 2.0, 0.0, Tunnel(), Soil(), 8), r"radius_m = 2\.0 is inside"),
        (lambda: invert_receptance(1.0, 1.0, Tunnel(), Soil(), -1), r"n_harmonics = -1"),
        (lambda: invert_receptance(1.0, 1.0, Tunnel(), Soil(), 2.5), r"n_harmonics = 2\.5"),
        (
            lambda: invert_receptance(1.0, 1.0, Tunnel(), duck_soil(poisson_ratio=0.5), 8),
            r"^soil\.poisson_ratio = 0\.5 is outside the allowed range \[0, 0\.49\]",
        ),
        (
            lambda: invert_receptance(1.0, 1.0, Tunnel(), duck_soil(shear_loss_factor=-0.01), 8),
            r"^soil\.shear_loss_factor = -0\.01 is outside the allowed range \[0, 0\.4\]",
        ),
        (
            lambda: invert_receptance(1.0, 1.0, Tunnel(), LooseSoil(poisson_ratio=0.5), 8),
            r"soil\.poisson_ratio = 0\.5.* give non-finite model constants",
        ),
    ],
)
def test_bad_input_is_refused_with_a_message_naming_it(call, message):
    with pytest.raises(ValueError, match=message):
        call()


@pytest.mark.parametrize(
    ("name", "value"),
    [
        ("poisson_ratio", 0.5),
        ("poisson_ratio", 0.7),
        ("shear_loss_factor", -0.1),
        ("bulk_loss_factor", -0.1),
    ],
)
def test_soil_parameters_out_of_physical_range_are_refused_at_assignment(name, value):
    with pytest.raises(ValueError, match=rf"{name} = {value!r} is outside the allowed range"):
        Soil(**{name: value})


# ---- the two compilations of the kernel --------------------------------------------------
def _receptance_case():
    """Paper section on a small grid: 60 frequencies to 100 Hz, 5 depths to 35 m."""
    scenario = Scenario.paper()
    return np.linspace(0.05, 100.0, 60), np.linspace(0.0, 35.0, 5), scenario.tunnel, scenario.soil


def _receptance_in_child(queue) -> None:
    """invert_receptance in a forked process (put on ``queue``)."""
    queue.put(invert_receptance(*_receptance_case(), 32))


@pytest.mark.skipif(numba.config.NUMBA_NUM_THREADS < 2, reason="one Numba thread: no parallel run")
def test_serial_compilation_gives_the_parallel_numbers_bit_for_bit():
    """One Numba thread (a study worker) runs ring_soil_field_serial, several the parallel
    kernel: two compilations of one source, the same receptance to the last bit."""
    parallel = invert_receptance(*_receptance_case(), 32)
    before = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        serial = invert_receptance(*_receptance_case(), 32)
    finally:
        numba.set_num_threads(before)
    np.testing.assert_array_equal(serial, parallel)
    assert ring_soil_field_serial.signatures and ring_soil_field_kernel.signatures


@pytest.mark.skipif(
    "fork" not in multiprocessing.get_all_start_methods() or numba.config.NUMBA_NUM_THREADS < 2,
    reason="needs fork and a parallel run in this process",
)
def test_a_process_forked_after_a_parallel_run_computes_the_same_receptance():
    """After this process ran the parallel kernel (OpenMP threads started), a forked child (a
    study worker) runs the serial compilation: GNU OpenMP would terminate it otherwise."""
    expected = invert_receptance(*_receptance_case(), 32)
    context = multiprocessing.get_context("fork")
    queue = context.Queue()
    child = context.Process(target=_receptance_in_child, args=(queue,))
    child.start()
    received = queue.get(timeout=60)
    child.join(timeout=30)
    assert child.exitcode == 0
    np.testing.assert_array_equal(received, expected)
