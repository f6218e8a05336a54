"""The half-space Green's function (model.soil.halfspace, docs/halfspace.md): Mindlin's static
solution at the surface and at depth, its low-frequency limit, Lamb's problem (the surface far
field travels at the Rayleigh speed), Stokes' full-space field and its deep-source limit,
reciprocity, the traction-free surface and Navier's equation, convergence of the wavenumber
integration with its stated tolerance, and refused inputs."""

import numpy as np
import pytest
from scipy import integrate, special

import model
from model.params import Soil
from model.soil import halfspace as hs
from model.soil.inputs import soil_constants

SOIL = Soil()  # E = 6 MPa, ν = 0.3, ρ = 1800 kg/m³, η_G = 0.06, η_K = 0


# ---- Mindlin's static solution ----------------------------------------------------------------
def test_static_limit_is_mindlin_at_the_surface_and_at_depth():
    """At ω = 0 the regularised kernel is Mindlin's solution (complex moduli, the correspondence
    principle), at the surface (z = 0), above, beside and below the force (c = 5 m), r = 0–30 m.
    Tolerance 1e-8: the integration's own tolerance is 1e-9 of the largest |u| per depth."""
    soil = Soil(shear_loss_factor=0.02)
    r = np.array([0.0, 0.5, 3.0, 10.0, 30.0])
    z = np.array([0.0, 2.0, 4.5, 8.0, 20.0])
    u = model.halfspace_point_response(0.0, r, 0.0, z, 5.0, soil, rtol=1e-9)[0, :, 0, :]
    w = hs.mindlin_vertical(r[:, None], z[None, :], 5.0, soil)
    assert np.max(np.abs(u / w - 1.0)) < 1e-8


def test_an_elastic_soil_at_zero_frequency_is_mindlin_s_elastic_solution():
    """η_G = 0 is allowed at ω = 0: with the default tolerance the public function is the elastic
    Mindlin solution (real G, ν) to 1e-6, at the surface and at depth (c = 10 m)."""
    soil = Soil(shear_loss_factor=0.0)
    r = np.array([0.0, 1.0, 5.0, 15.0, 40.0])
    z = np.array([0.0, 5.0, 9.0, 15.0, 25.0])
    u = model.halfspace_point_response(0.0, r, 0.0, z, 10.0, soil)[0, :, 0, :]
    w = hs.mindlin_vertical(r[:, None], z[None, :], 10.0, soil, elastic=True)
    assert np.max(np.abs(u / w - 1.0)) < 1e-6


def test_mindlin_formula_against_boussinesq_and_kelvin():
    """The closed form itself: as c → 0 at the surface it is Boussinesq's (1 − ν)/(2πμr); far
    from the surface (c → ∞, z − c fixed) Kelvin's ((3 − 4ν) + cos²)/(16πμ(1 − ν)R)."""
    soil = Soil()
    mu, nu = soil.shear_modulus, soil.poisson_ratio
    r = np.array([1.0, 4.0, 20.0])
    surface = hs.mindlin_vertical(r, 0.0, 1e-7, soil, elastic=True)
    assert np.allclose(surface, (1 - nu) / (2 * np.pi * mu * r), rtol=1e-6)
    deep = hs.mindlin_vertical(3.0, 1e7 + 4.0, 1e7, soil, elastic=True)
    big_r = 5.0
    kelvin = ((3 - 4 * nu) + (4.0 / big_r) ** 2) / (16 * np.pi * mu * (1 - nu) * big_r)
    assert abs(deep / kelvin - 1) < 1e-6


def test_low_frequency_tends_to_mindlin():
    """0.01 Hz, η_G = 0.001, R ≤ 10 m (k_s R ≤ 0.02): |u/w − 1| ≤ 2 %, the real part within
    0.1 %, and the difference is the position-independent O(ω) radiation term iωC (uniform to
    1 %): the first dynamic correction of a point source, the same at every receiver."""
    soil = Soil(shear_loss_factor=0.001)
    r = np.array([0.0, 1.0, 3.0, 6.0])
    z = np.array([0.0, 2.0, 8.0, 12.0])
    f = 0.01
    u = model.halfspace_point_response(f, r, 0.0, z, 5.0, soil)[0, :, 0, :]
    w = hs.mindlin_vertical(r[:, None], z[None, :], 5.0, soil)
    assert np.max(np.abs(u / w - 1.0)) < 0.02
    assert np.max(np.abs((u - w).real / w.real)) < 1e-3
    radiation = (u - w).imag / (2 * np.pi * f)
    assert np.ptp(radiation) < 0.01 * np.abs(radiation).mean()


def test_point_response_grid_shape_and_symmetry():
    """(n_freq, n_x, n_y, n_z), and u depends on x, y only through r = √(x² + y²)."""
    x, y = np.array([0.0, 3.0, 4.0]), np.array([0.0, 4.0, 3.0])
    u = model.halfspace_point_response([0.0, 2.0], x, y, [0.0, 6.0], 8.0, SOIL)
    assert u.shape == (2, 3, 3, 2)
    assert np.allclose(u[:, 1, 1], u[:, 2, 2], rtol=1e-12)  # r = 5 both
    assert np.allclose(u[:, 1, 0], u[:, 0, 2], rtol=1e-12)  # r = 3 both


# ---- Lamb's problem: the Rayleigh wave ----------------------------------------------------------
@pytest.mark.parametrize("eta", [0.01, 0.06])
def test_surface_far_field_travels_at_the_rayleigh_speed(eta):
    """Phase slope of u_z(r) at the surface, 6–16 Rayleigh wavelengths from a shallow source
    (20 Hz, c = 0.5 m): the fitted speed is the Rayleigh root's to 0.1 % and Viktorov's estimate
    (accurate to ~0.5 % for ν = 0.3) to 1 %; |u|√r decays as exp(Im k_R r) to 6 % (body waves
    and the near field, ∝ r⁻², still perturb the amplitude at 6 wavelengths)."""
    soil = Soil(shear_loss_factor=eta)
    f, c = 20.0, 0.5
    k_r = hs.rayleigh_wavenumber(f, soil)[0]
    wavelength = 2 * np.pi / k_r.real
    r = np.linspace(6 * wavelength, 16 * wavelength, 81)
    u = model.halfspace_point_response(f, r, 0.0, 0.0, c, soil)[0, :, 0, 0]
    slope, _ = np.polyfit(r, np.unwrap(np.angle(u)), 1)
    c_fit = 2 * np.pi * f / -slope
    nu = soil.poisson_ratio
    viktorov = (0.862 + 1.14 * nu) / (1 + nu) * soil.s_wave_speed
    assert abs(c_fit / (2 * np.pi * f / k_r.real) - 1) < 1e-3
    assert abs(c_fit / viktorov - 1) < 0.01
    decay, _ = np.polyfit(r, np.log(np.abs(u) * np.sqrt(r)), 1)
    assert abs(decay / k_r.imag - 1) < 0.06


def test_rayleigh_root_elastic_value():
    """Nearly undamped root against the exact ν = 0.25 value c_R/c_s = √(2 − 2/√3) (Lamb)."""
    soil = Soil(poisson_ratio=0.25, shear_loss_factor=1e-9)
    k_r = hs.rayleigh_wavenumber(10.0, soil)[0]
    ratio = 2 * np.pi * 10.0 / k_r.real / soil.s_wave_speed
    assert abs(ratio - np.sqrt(2 - 2 / np.sqrt(3))) < 1e-7


# ---- the full-space part and the deep-source limit -----------------------------------------------
def test_stokes_closed_form_matches_the_wavenumber_full_space():
    """Hankel transform of the regularised full-space Ĝ_zz = closed-form Stokes, 0.01–40 Hz."""
    r = np.array([0.0, 1.0, 3.0, 10.0, 30.0])
    z = np.array([0.0, 2.0, 8.0])
    for f in (0.01, 1.0, 10.0, 40.0):
        u, _ = hs.hankel_zz(f, r, z, 5.0, SOIL, rtol=1e-9, part="full")
        stokes = hs.fullspace_point_tensor(f, r[:, None], 0.0, (z - 5.0)[None, :], SOIL)
        assert np.max(np.abs(u / stokes[0, ..., 2, 2] - 1)) < 1e-8


def test_stokes_static_is_kelvin():
    d = np.array([1.0, -2.0, 0.5])
    gst = hs.fullspace_point_tensor(0.0, *d, SOIL)[0]
    mu, lam, _ = soil_constants(SOIL)
    nu = lam / (2 * (lam + mu))
    r = np.linalg.norm(d)
    kelvin = ((3 - 4 * nu) * np.eye(3) + np.outer(d, d) / r**2) / (16 * np.pi * mu * (1 - nu) * r)
    assert np.max(np.abs(gst - kelvin)) < 1e-12 * np.abs(kelvin).max()


def test_deep_source_tends_to_the_full_space():
    """Near a source at depth c (r = 1–3 m, z = c ± 2 m) the reflected part relative to the
    full-space one falls monotonically with c and is < 1e-3 at c = 160 m (10 Hz, η_G = 0.06;
    the reflected P wave, damped only through μ*, sets the rate ~e^{2 Im k_p c}/2c)."""
    r = np.array([1.0, 2.0, 3.0])
    dz = np.array([-2.0, 0.0, 2.0])
    errors = []
    for c in (5.0, 10.0, 20.0, 40.0, 80.0, 160.0):
        full = hs.fullspace_point_tensor(10.0, r[:, None], 0.0, dz[None, :], SOIL)[0, ..., 2, 2]
        reflected, _ = hs.hankel_zz(
            10.0, r, c + dz, c, SOIL, rtol=1e-9, scale=np.abs(full).max(axis=0)
        )
        errors.append(np.max(np.abs(reflected) / np.abs(full)))
    assert all(b < a for a, b in zip(errors, errors[1:], strict=False))
    assert errors[-1] < 1e-3


# ---- reciprocity --------------------------------------------------------------------------------
def test_point_response_reciprocity():
    """u_z(r, z; source at c) = u_z(r, c; source at z), 0–25 Hz, to 1e-8 (tolerance 1e-9)."""
    r = np.array([0.0, 2.0, 7.0, 20.0])
    for f in (0.0, 3.0, 25.0):
        a = model.halfspace_point_response(f, r, 0.0, 9.0, 3.0, SOIL, rtol=1e-9)[0, :, 0, 0]
        b = model.halfspace_point_response(f, r, 0.0, 3.0, 9.0, SOIL, rtol=1e-9)[0, :, 0, 0]
        assert np.max(np.abs(a - b)) < 1e-8 * np.abs(a).max()


@pytest.mark.parametrize("part", ["full", "reflected", "total"])
def test_wavenumber_tensor_reciprocity(part):
    """Ĝ_ij(ξ, k_y; z, c) = Ĝ_ji(−ξ, −k_y; c, z) for all nine components, to rounding."""
    xi = np.array([0.05, 0.7, 3.0, 0.3])
    ky = np.array([0.4, -1.1, 0.2, 0.0])
    for f in (0.0, 2.0, 30.0):
        a = hs.wavenumber_greens_tensor(f, xi, ky, [1.5], 6.0, SOIL, part)[:, 0]
        b = hs.wavenumber_greens_tensor(f, -xi, -ky, [6.0], 1.5, SOIL, part)[:, 0]
        assert np.max(np.abs(a - np.swapaxes(b, 1, 2))) < 1e-12 * np.abs(a).max()


# ---- the full tensor: Stokes, Navier's equation, the free surface -------------------------------
def test_full_space_tensor_matches_stokes_all_components():
    """All nine full-space components by Hankel transforms of orders 0, 1, 2 (scipy quad) vs the
    closed form, to 1e-7 of the largest (quad's relative tolerance 1e-10)."""
    f, c, z = 8.0, 6.0, 4.0
    r, phi = 3.0, np.deg2rad(30.0)
    mu, lam, rho = soil_constants(SOIL)
    omega = np.array([2 * np.pi * f])

    def kernels(k):
        out = hs.greens_tensor_kernel(
            omega, np.array([k]), np.array([0.0]), np.array([z]), c, mu, lam, rho, 1
        )[0, 0]
        g_ss, g_tt, g_sz, g_zs, g_zz = out[0, 0], out[1, 1], out[0, 2], out[2, 0], out[2, 2]
        j0, j1, j2 = special.jv([0, 1, 2], k * r)
        c1, s1, c2, s2 = np.cos(phi), np.sin(phi), np.cos(2 * phi), np.sin(2 * phi)
        avg, dif = 0.5 * (g_ss + g_tt), 0.5 * (g_ss - g_tt)
        m = np.array([
            [avg * j0 - dif * j2 * c2, -dif * j2 * s2, -1j * g_sz * j1 * c1],
            [-dif * j2 * s2, avg * j0 + dif * j2 * c2, -1j * g_sz * j1 * s1],
            [-1j * g_zs * j1 * c1, -1j * g_zs * j1 * s1, g_zz * j0],
        ])  # fmt: skip
        return (m * k / (2 * np.pi)).ravel()

    ks, kp = 2 * np.pi * f / SOIL.s_wave_speed, 2 * np.pi * f / SOIL.p_wave_speed
    values, _ = integrate.quad_vec(
        kernels, 0.0, 30.0, points=[kp, ks], epsabs=1e-16, epsrel=1e-10, limit=2000
    )
    exact = hs.fullspace_point_tensor(f, r * np.cos(phi), r * np.sin(phi), z - c, SOIL)[0]
    assert np.max(np.abs(values.reshape(3, 3) - exact)) < 1e-7 * np.abs(exact).max()


def _tensor(f, xi, ky, z, c, part):
    return hs.wavenumber_greens_tensor(f, xi, ky, z, c, SOIL, part)[0]


@pytest.mark.parametrize("f", [0.0, 0.5, 5.0, 40.0])
def test_free_surface_is_traction_free(f):
    """τ_zx = τ_zy = τ_zz = 0 at z = 0 for the total field, by 4th-order one-sided differences
    (step 0.01/max(k, k_s): truncation ~1e-8), to 1e-6 of μ max(k, k_s) |u|."""
    mu, lam, _ = soil_constants(SOIL)
    for xi, ky in ((0.3, 0.2), (1.5, -0.7), (0.05, 0.02)):
        k = np.hypot(xi, ky)
        ks = 2 * np.pi * f / SOIL.s_wave_speed
        h = 0.01 / max(k, ks)
        u = _tensor(f, xi, ky, h * np.arange(5), 4.0, "total")
        dudz = (-25 * u[0] + 48 * u[1] - 36 * u[2] + 16 * u[3] - 3 * u[4]) / (12 * h)
        t_zx = mu * (dudz[0] - 1j * xi * u[0][2])
        t_zy = mu * (dudz[1] - 1j * ky * u[0][2])
        t_zz = lam * (-1j * xi * u[0][0] - 1j * ky * u[0][1]) + (lam + 2 * mu) * dudz[2]
        scale = abs(mu) * max(k, ks) * np.abs(u[0]).max()
        for t in (t_zx, t_zy, t_zz):
            assert np.max(np.abs(t)) < 1e-6 * scale


@pytest.mark.parametrize("part", ["full", "reflected"])
def test_navier_equation_away_from_the_source(part):
    """μ(∂_z² − k²)u + (λ + μ)∇(∇·u) + ρω²u = 0 at z ≠ c (4th-order central differences),
    to 1e-6 of the largest term."""
    mu, lam, rho = soil_constants(SOIL)
    f, c = 12.0, 5.0
    omega = 2 * np.pi * f
    for xi, ky, z0 in ((0.4, 0.9, 2.0), (2.5, -0.3, 7.5), (0.1, 0.0, 3.0)):
        k = np.hypot(xi, ky)
        h = 0.02 / max(k, omega / SOIL.s_wave_speed)
        u = _tensor(f, xi, ky, z0 + h * np.arange(-2, 3), c, part)
        d1 = (-u[4] + 8 * u[3] - 8 * u[1] + u[0]) / (12 * h)
        d2 = (-u[4] + 16 * u[3] - 30 * u[2] + 16 * u[1] - u[0]) / (12 * h * h)
        u0 = u[2]
        div = -1j * xi * u0[0] - 1j * ky * u0[1] + d1[2]
        ddiv_dz = -1j * xi * d1[0] - 1j * ky * d1[1] + d2[2]
        grad_div = np.array([-1j * xi * div, -1j * ky * div, ddiv_dz])
        residual = mu * (d2 - k * k * u0) + (lam + mu) * grad_div + rho * omega**2 * u0
        scale = (abs(rho) * omega**2 + abs(mu) * k * k) * np.abs(u0).max()
        assert np.max(np.abs(residual)) < 1e-6 * scale


# ---- convergence of the wavenumber integration --------------------------------------------------
@pytest.mark.parametrize("f", [0.5, 10.0, 60.0])
def test_hankel_quadrature_converges_within_its_stated_tolerance(f):
    """The error estimate is conservative: |u(rtol) − u(1e-11)| ≤ rtol · scale and the estimate
    itself ≤ rtol, for rtol = 1e-3, 1e-5, 1e-7, on r = 0–60 m at three depths."""
    r = np.linspace(0.0, 60.0, 31)
    z = np.array([0.0, 3.0, 10.0])
    c = 4.0
    full = hs.fullspace_point_tensor(f, r[:, None], 0.0, (z - c)[None, :], SOIL)[0, ..., 2, 2]
    scale = np.abs(full).max(axis=0)
    reference, _ = hs.hankel_zz(f, r, z, c, SOIL, rtol=1e-11, scale=scale)
    for rtol in (1e-3, 1e-5, 1e-7):
        u, estimate = hs.hankel_zz(f, r, z, c, SOIL, rtol=rtol, scale=scale)
        assert estimate <= rtol
        assert np.max(np.abs(u - reference) / scale) <= rtol


# ---- refused inputs -----------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"soil": Soil(shear_loss_factor=0.0)}, "soil.shear_loss_factor"),
        ({"source_depth_m": 0.0}, "source_depth_m"),
        ({"source_depth_m": -2.0}, "source_depth_m"),
        ({"z_m": -1.0}, "z_m"),
        ({"freq_hz": -1.0}, "freq_hz"),
        ({"freq_hz": np.nan}, "freq_hz"),
        ({"x_m": [0.0, np.inf]}, "x_m"),
        ({"rtol": 0.0}, "rtol"),
    ],
)
def test_bad_inputs_are_refused_with_the_parameter_named(kwargs, match):
    args = {"freq_hz": 1.0, "x_m": 0.0, "y_m": 1.0, "z_m": 0.0, "source_depth_m": 3.0}
    args |= {"soil": SOIL, **kwargs}
    with pytest.raises(ValueError, match=match):
        model.halfspace_point_response(**args)


def test_a_receiver_on_the_source_point_is_refused():
    with pytest.raises(ValueError, match="coincides with the source"):
        model.halfspace_point_response(1.0, 0.0, 0.0, 3.0, 3.0, SOIL)
