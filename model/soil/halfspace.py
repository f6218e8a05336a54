"""Green's function of a homogeneous hysteretic half-space (docs/halfspace.md).

Coordinates x along the tunnel, y across, z **down** from the free surface; exp(+iωt). The
field of a point force at depth c is Stokes' full-space field, in closed form
(:func:`fullspace_point_tensor`; Kelvin's at ω = 0), plus the field the free surface reflects,
a Hankel transform over the radial wavenumber of the closed-form plane-wave reflection of
``model.soil.halfspace_kernels`` (:func:`halfspace_point_response`). At ω = 0 the sum is
Mindlin's solution (:func:`mindlin_vertical`); the surface far field travels at the Rayleigh
speed (:func:`rayleigh_wavenumber`). The soil is ``model.params.Soil``'s: μ* = μ(1 + iη_G),
λ* = K(1 + iη_K) − 2μ*/3, from ``model.soil.inputs.soil_constants``.
"""

from __future__ import annotations

import math

import numpy as np

from model.soil.halfspace_kernels import greens_tensor_kernel, zz_radial_kernel
from model.soil.hankel import hankel_transform
from model.soil.inputs import as_1d, soil_constants

# The reflected field decays at least as e^{−k (z + c)}: the transform is cut where that is
# e^{−42} ≈ 6e-19 of its value at k = 0.
_CUT_EXPONENT = 42.0
# Default tolerance of the wavenumber integration, relative to the largest |u| per depth.
DEFAULT_RTOL = 1e-6


def _omega(freq_hz) -> np.ndarray:
    """ω = 2πf (rad/s) of frequencies refused unless finite and ≥ 0."""
    freq = as_1d(freq_hz, "freq_hz", "Hz")
    if np.any(freq < 0.0):
        raise ValueError(
            f"freq_hz = {float(freq[freq < 0][0])!r} is outside the allowed range [0, inf) Hz "
            "(0 gives the static, Mindlin, solution)"
        )
    return 2.0 * np.pi * freq


def _checked_source_depth(source_depth_m) -> float:
    """The source depth c (m), refused unless finite and > 0."""
    c = float(source_depth_m)
    if not (math.isfinite(c) and c > 0.0):
        raise ValueError(
            f"source_depth_m = {source_depth_m!r} is outside the allowed range (0, inf) m: the "
            "force acts below the free surface"
        )
    return c


def _checked_receiver_depths(z_m) -> np.ndarray:
    """Receiver depths z ≥ 0 (m) below the free surface."""
    z = as_1d(z_m, "z_m", "m")
    if np.any(z < 0.0):
        raise ValueError(
            f"z_m = {float(z[z < 0][0])!r} is above the ground surface: depths are measured down "
            "from the free surface and must be ≥ 0 m"
        )
    return z


def poisson_ratio_of(shear, lame) -> complex:
    """ν = λ/(2(λ + μ)) of (possibly complex) Lamé constants."""
    return lame / (2.0 * (lame + shear))


def wavenumber_greens_tensor(freq_hz, xi, k_y, z_m, source_depth_m, soil, part="total"):
    """Half-space displacement Green's tensor Ĝ_ij(ω, ξ, k_y, z) of a point force at depth c.

    u_i at depth z per unit force F_j at (0, 0, c), i, j = x, y, z (z down), in the
    wavenumber domain of ``model.soil.halfspace_kernels`` (fields ∝ exp(i(ωt − ξx − k_y y)),
    u(x, y) = (1/4π²)∬ Ĝ e^{−i(ξx + k_y y)} dξ dk_y).

    Parameters
    ----------
    freq_hz, xi, k_y : float or array_like
        Frequencies (Hz, ≥ 0) and wavenumbers (rad/m), broadcast together to (n,).
    z_m : float or array_like
        (n_z,) receiver depths z ≥ 0 (m).
    source_depth_m : float
        Source depth c > 0 (m).
    soil : model.params.Soil
        Soil.
    part : {"total", "full", "reflected"}
        Full-space (Stokes) part, the free-surface reflected part, or their sum.

    Returns
    -------
    ndarray
        Complex (n, n_z, 3, 3), m/N · (rad/m)⁻² (the 2D Fourier transform over x and y).
    """
    shear, lame, density = soil_constants(soil)
    freq, xi, k_y = np.broadcast_arrays(
        _omega(freq_hz) / (2.0 * np.pi), as_1d(xi, "xi", "rad/m"), as_1d(k_y, "k_y", "rad/m")
    )
    z = _checked_receiver_depths(z_m)
    c = _checked_source_depth(source_depth_m)
    code = {"total": 0, "full": 1, "reflected": 2}[part]
    return greens_tensor_kernel(
        np.ascontiguousarray(2.0 * np.pi * freq),
        np.ascontiguousarray(xi, dtype=float),
        np.ascontiguousarray(k_y, dtype=float),
        np.ascontiguousarray(z),
        c,
        shear,
        lame,
        density,
        code,
    )


def rayleigh_wavenumber(freq_hz, soil) -> np.ndarray:
    """Complex Rayleigh wavenumber k_R(ω) of the half-space, the surface-wave pole.

    Root of (2k² − k_s²)² − 4k²ν_pν_s = 0 on the principal sheet (Re ν ≥ 0), by Newton's
    iteration from Viktorov's estimate c_R/c_s ≈ (0.862 + 1.14ν)/(1 + ν) (docs/halfspace.md);
    damping makes it complex, Im k_R < 0 for exp(+iωt).

    Parameters
    ----------
    freq_hz : float or array_like
        Frequencies (Hz, > 0).
    soil : model.params.Soil
        Soil.

    Returns
    -------
    ndarray
        Complex (n,) k_R (rad/m).
    """
    shear, lame, density = soil_constants(soil)
    omega = _omega(freq_hz)
    ks = omega * np.sqrt(density / shear)
    kp = omega * np.sqrt(density / (lame + 2.0 * shear))
    nu = poisson_ratio_of(shear.real, lame.real)
    k = ks * (1.0 + nu) / (0.862 + 1.14 * nu)

    def dispersion(k):
        return (2 * k * k - ks * ks) ** 2 - 4 * k * k * np.sqrt(k * k - kp * kp) * np.sqrt(
            k * k - ks * ks
        )

    for _ in range(50):
        step = 1e-7 * k
        dk = dispersion(k) / ((dispersion(k + step) - dispersion(k - step)) / (2.0 * step))
        k = k - dk
        if np.all(np.abs(dk) <= 1e-15 * np.abs(k)):
            break
    return k


def _near_field_integral(x):
    """(e^{−ix}(1 + ix) − 1)/x² for complex x (array), by its series below |x| = 0.5."""
    x = np.asarray(x, complex)
    out = np.empty_like(x)
    small = np.abs(x) < 0.5
    xs = x[small]
    term = np.ones_like(xs)  # x^(n−2)/n!
    total = np.zeros_like(xs)
    factorial = 2.0
    for n in range(2, 30):
        if n > 2:
            term = term * xs
            factorial *= n
        total += (-1j) ** n * (1 - n) / factorial * term
    out[small] = total
    xl = x[~small]
    out[~small] = (np.exp(-1j * xl) * (1 + 1j * xl) - 1) / (xl * xl)
    return out


def fullspace_point_tensor(freq_hz, dx, dy, dz, soil) -> np.ndarray:
    """Stokes' full-space Green's tensor G_ij(ω, Δx) in closed form (m/N).

    G_ij = (1/4πρ)[(3γ_iγ_j − δ_ij) I/R³ + γ_iγ_j e^{−ik_pR}/(c_p²R)
    − (γ_iγ_j − δ_ij) e^{−ik_sR}/(c_s²R)], γ = Δx/R, I = ∫_{R/c_p}^{R/c_s} τ e^{−iωτ} dτ
    formed without cancellation at low frequency (complex c_p, c_s); at ω = 0 it is Kelvin's
    solution ((3 − 4ν)δ_ij + γ_iγ_j)/(16πμ(1 − ν)R).

    Parameters
    ----------
    freq_hz : float or array_like
        (n_f,) frequencies (Hz, ≥ 0).
    dx, dy, dz : array_like
        Receiver minus source position (m), broadcast together to a shape S; R > 0.
    soil : model.params.Soil
        Soil.

    Returns
    -------
    ndarray
        Complex (n_f, *S, 3, 3).
    """
    shear, lame, density = soil_constants(soil)
    omega = _omega(freq_hz)
    d = np.stack(np.broadcast_arrays(*(np.asarray(v, float) for v in (dx, dy, dz))), axis=-1)
    r = np.linalg.norm(d, axis=-1)
    if np.any(r == 0.0):
        raise ValueError(
            "a receiver coincides with the source (R = 0), where the Green's function is "
            "singular; move it off the source point"
        )
    g = d / r[..., None]
    gg = g[..., :, None] * g[..., None, :]
    eye = np.eye(3)
    cp = np.sqrt((lame + 2 * shear) / density)
    cs = np.sqrt(shear / density)
    out = np.empty((omega.size, *r.shape, 3, 3), complex)
    for i, w in enumerate(omega):
        tp, ts = r / cp, r / cs
        near = ts**2 * _near_field_integral(w * ts) - tp**2 * _near_field_integral(w * tp)
        ep = np.exp(-1j * w * tp) / (cp**2 * r)
        es = np.exp(-1j * w * ts) / (cs**2 * r)
        out[i] = (
            (3 * gg - eye) * (near / r**3)[..., None, None]
            + gg * ep[..., None, None]
            - (gg - eye) * es[..., None, None]
        ) / (4 * np.pi * density)
    return out


def mindlin_vertical(r_m, z_m, source_depth_m, soil, elastic: bool = False) -> np.ndarray:
    """Mindlin's static vertical displacement w (down +) per unit downward force at depth c (m/N).

    docs/halfspace.md: w = [(3−4ν)/R₁ + (8(1−ν)² − (3−4ν))/R₂ + (z−c)²/R₁³
    + ((3−4ν)(z+c)² − 2cz)/R₂³ + 6cz(z+c)²/R₂⁵] / (16πG(1−ν)),
    R₁ = √(r² + (z−c)²), R₂ = √(r² + (z+c)²).

    Parameters
    ----------
    r_m, z_m : array_like
        Horizontal distance from the force and depth below the surface (m), broadcast together.
    source_depth_m : float
        Depth c of the force (m), > 0.
    soil : model.params.Soil
        Soil.
    elastic : bool
        Use the elastic moduli μ, ν; by default the complex μ*, ν* of the hysteretic soil
        (the correspondence principle: the ω → 0 limit of the damped half-space).

    Returns
    -------
    ndarray
        w, complex unless ``elastic``.
    """
    shear, lame, _ = soil_constants(soil)
    if elastic:
        shear, lame = shear.real, lame.real
    nu = poisson_ratio_of(shear, lame)
    c = _checked_source_depth(source_depth_m)
    r, z = np.broadcast_arrays(np.asarray(r_m, float), np.asarray(z_m, float))
    r1 = np.sqrt(r**2 + (z - c) ** 2)
    r2 = np.sqrt(r**2 + (z + c) ** 2)
    a = 3 - 4 * nu
    w = (
        a / r1
        + (8 * (1 - nu) ** 2 - a) / r2
        + (z - c) ** 2 / r1**3
        + (a * (z + c) ** 2 - 2 * c * z) / r2**3
        + 6 * c * z * (z + c) ** 2 / r2**5
    )
    return w / (16 * np.pi * shear * (1 - nu))


def _initial_edges(omega, features, r_max, reach, k_max):
    """Panel edges on [0, k_max]: graded geometrically towards each feature down to its
    damping width, and no wider than two periods of J₀(k r_max) or 1/reach."""
    width = min(4.0 * np.pi / max(r_max, 1e-12), 1.0 / reach)
    points = [0.0, k_max]
    for feature in features:
        centre, damping = feature.real, max(abs(feature.imag), 1e-6 * abs(feature.real))
        offsets = damping * 2.0 ** np.arange(60)
        offsets = offsets[offsets < width]
        points += [centre, *(centre + offsets), *(centre - offsets)]
    points = np.unique(np.clip(np.array(points), 0.0, k_max))
    edges = [points[:1]]
    for lo, hi in zip(points[:-1], points[1:], strict=True):
        edges.append(np.linspace(lo, hi, max(1, math.ceil((hi - lo) / width)) + 1)[1:])
    return np.concatenate(edges)


def hankel_zz(freq_hz, r_m, z_m, source_depth_m, soil, rtol=DEFAULT_RTOL, scale=None,
              part="reflected"):  # fmt: skip
    """(1/2π)∫₀^∞ Ĝ_zz(ω, k, z; c) J₀(kr) k dk, the vertical response by radial wavenumbers.

    The panels start at the breakpoints Re k_p, Re k_s, Re k_R (graded towards them down to
    their damping width |Im k|), no wider than 4π/r_max and 1/(z + c); the integral is cut
    where e^{−k (z + c)} < e^{−42} beyond Re k_s, and bisected until the error estimate of
    ``model.soil.hankel.hankel_transform`` is ≤ ``rtol``. The Rayleigh pole and the branch
    points lie on the real k axis only without damping: an undamped soil (η_G = 0) is refused
    at ω > 0.

    Parameters
    ----------
    freq_hz : float
        Frequency (Hz, ≥ 0).
    r_m, z_m : array_like
        (n_r,) horizontal distances ≥ 0 and (n_z,) receiver depths ≥ 0 (m).
    source_depth_m : float
        Source depth c > 0 (m).
    soil : model.params.Soil
        Soil.
    rtol : float
        Tolerance on the summed error estimate, relative to ``scale``.
    scale : array_like, optional
        (n_z,) reference magnitude per depth (m/N); default the largest |result| over r.
    part : {"reflected", "total", "full"}
        The reflected part (default; any z), the full-space part or their sum (z ≠ c).

    Returns
    -------
    (ndarray, float)
        Complex (n_r, n_z) displacement per unit force (m/N) and the final error estimate.
    """
    shear, lame, density = soil_constants(soil)
    omega = float(_omega(freq_hz)[0])
    r = as_1d(r_m, "r_m", "m")
    z = _checked_receiver_depths(z_m)
    c = _checked_source_depth(source_depth_m)
    code = {"total": 0, "full": 1, "reflected": 2}[part]
    if omega > 0.0 and soil.shear_loss_factor <= 0.0:
        raise ValueError(
            "soil.shear_loss_factor = 0: the Rayleigh pole of an undamped half-space lies on the "
            "real wavenumber axis; the Green's function needs soil.shear_loss_factor > 0"
        )
    reach = float(np.min(z) + c) if code == 2 else float(np.min(np.abs(z - c)))
    if reach <= 0.0:
        raise ValueError(
            "a receiver depth equals the source depth: the full-space part does not decay in "
            "wavenumber there; integrate the reflected part or use fullspace_point_tensor"
        )
    ks = omega * np.sqrt(density / shear)
    kp = omega * np.sqrt(density / (lame + 2.0 * shear))
    features = [kp, ks, complex(rayleigh_wavenumber(freq_hz, soil)[0])] if omega > 0 else []
    k_max = math.hypot(1.05 * abs(ks.real), _CUT_EXPONENT / reach)
    edges = _initial_edges(omega, features, float(np.max(r)), reach, k_max)
    moduli = (shear, lame, density)
    zc = np.ascontiguousarray(z)
    return hankel_transform(
        lambda k: zz_radial_kernel(omega, k, zc, c, *moduli, code), edges, r, rtol, scale
    )


def halfspace_point_response(freq_hz, x_m, y_m, z_m, source_depth_m, soil, rtol=DEFAULT_RTOL):
    """Vertical displacement (down +) per unit downward point force at depth c under (0, 0).

    docs/halfspace.md: the half-space Green's function u_z = G_zz(ω; x, y, z; c). Stokes'
    closed-form full-space field (:func:`fullspace_point_tensor`, exact to rounding) plus the
    free-surface reflected field, the Hankel transform (1/2π)∫ Ĝ^R_zz(k) J₀(kr) k dk over the
    radial wavenumber (:func:`hankel_zz`), whose estimated error is ≤ ``rtol`` relative to the
    largest full-space |u| over the (x, y) points at each depth and frequency. At ω = 0 it is
    Mindlin's solution with the complex moduli (:func:`mindlin_vertical`).

    Parameters
    ----------
    freq_hz : float or array_like
        (n_freq,) frequencies (Hz, ≥ 0).
    x_m, y_m : float or array_like
        (n_x,), (n_y,) horizontal receiver coordinates (m): x along the tunnel, y across.
    z_m : float or array_like
        (n_z,) receiver depths below the free surface (m), ≥ 0 (0: the ground surface).
    source_depth_m : float
        Depth c > 0 of the force (m).
    soil : model.params.Soil
        Soil; η_G > 0 for ω > 0 (the Rayleigh pole is softened by damping).
    rtol : float
        Wavenumber-integration tolerance (relative, default 1e-6).

    Returns
    -------
    ndarray
        Complex (n_freq, n_x, n_y, n_z) in m/N, exp(+iωt).

    Raises
    ------
    ValueError
        A negative frequency or depth, a source at or above the surface, a receiver at the
        source point, or an undamped soil at ω > 0.
    """
    omega = _omega(freq_hz)
    x, y = as_1d(x_m, "x_m", "m"), as_1d(y_m, "y_m", "m")
    z = _checked_receiver_depths(z_m)
    c = _checked_source_depth(source_depth_m)
    if not (isinstance(rtol, float | int) and 0.0 < rtol < 1.0):
        raise ValueError(f"rtol = {rtol!r} is outside the allowed range (0, 1)")
    radius = np.hypot(x[:, None], y[None, :])
    r_unique, inverse = np.unique(radius.ravel(), return_inverse=True)
    freq = omega / (2.0 * np.pi)
    full = fullspace_point_tensor(freq, r_unique[:, None], 0.0, (z - c)[None, :], soil)[..., 2, 2]
    out = np.empty((freq.size, r_unique.size, z.size), complex)
    for i, f in enumerate(freq):
        scale = np.abs(full[i]).max(axis=0)
        reflected, _ = hankel_zz(f, r_unique, z, c, soil, rtol=float(rtol), scale=scale)
        out[i] = full[i] + reflected
    return out[:, inverse.ravel(), :].reshape(freq.size, x.size, y.size, z.size)
