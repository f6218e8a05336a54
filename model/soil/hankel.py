"""Adaptive Hankel transform (1/2π)∫₀^∞ F(k) J₀(kr) k dk of a wavenumber-domain field.

Used by the half-space Green's function (``model.soil.halfspace``) to go from the radial
wavenumber k to the horizontal distance r. Gauss–Kronrod (7, 15) panels (QUADPACK's qk15 nodes
and weights), the initial panels placed by the caller (breakpoints at the branch points and the
Rayleigh pole, widths ≤ two periods of J₀ at the largest r), then bisected, largest error
estimate first, until the summed estimate |K15 − G7| (the largest over r and the output
columns, relative to a reference magnitude per column) is below the tolerance. J₀ comes from a
table with cubic Hermite interpolation (J₀′ = −J₁): step 0.01, absolute error ≤ h⁴/384 ≈ 3e-11;
beyond x = 2000, Hankel's asymptotic series (error < 1e-14 there).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numba
import numpy as np
from scipy import special

# Gauss–Kronrod 7/15 nodes on [−1, 1] (QUADPACK qk15).
_XGK = np.array([
    0.991455371120812639206854697526329, 0.949107912342758524526189684047851,
    0.864864423359769072789712788640926, 0.741531185599394439863864773280788,
    0.586087235467691130294144845693013, 0.405845151377397166906606412076961,
    0.207784955007898467600689403773245, 0.000000000000000000000000000000000,
])  # fmt: skip
_WGK = np.array([
    0.022935322010529224963732008058970, 0.063092092629978553290700663189204,
    0.104790010322250183839876322541518, 0.140653259715525918745189590510238,
    0.169004726639267902826583426598550, 0.190350578064785409913256402421014,
    0.204432940075298892414161999234649, 0.209482141084727828012999174891714,
])  # fmt: skip
_WG = np.array([
    0.129484966168869693270611432679082, 0.279705391489276667901467771423780,
    0.381830050505118944950369775488975, 0.417959183673469387755102040816327,
])  # fmt: skip
GK_NODES = np.concatenate([-_XGK[:-1], _XGK[::-1]])
GK_WEIGHTS = np.concatenate([_WGK[:-1], _WGK[::-1]])
_G_WEIGHTS = np.zeros(15)
_G_WEIGHTS[1::2] = np.concatenate([_WG[:-1], _WG[::-1]])

_J0_STEP = 0.01
_J0_TABLE_END = 2000.0
_J0_GRID = np.arange(0.0, _J0_TABLE_END + 2 * _J0_STEP, _J0_STEP)
_J0_VALUES = special.j0(_J0_GRID)
_J0_SLOPES = -special.j1(_J0_GRID)
# Panels a transform may be bisected into before it is refused (memory ~ panels × r × columns).
MAX_PANELS = 200_000


@numba.njit(cache=True, nogil=True)
def bessel_j0(x, values, slopes):
    """J₀(x), x ≥ 0, from the Hermite table (module docstring) or the asymptotic series."""
    if x < _J0_TABLE_END:
        t = x / _J0_STEP
        i = int(t)
        s = t - i
        s2 = s * s
        s3 = s2 * s
        return (
            (2.0 * s3 - 3.0 * s2 + 1.0) * values[i]
            + (3.0 * s2 - 2.0 * s3) * values[i + 1]
            + _J0_STEP * ((s3 - 2.0 * s2 + s) * slopes[i] + (s3 - s2) * slopes[i + 1])
        )
    inv2 = 1.0 / (x * x)
    p = 1.0 - 9.0 / 128.0 * inv2 + 3675.0 / 32768.0 * inv2 * inv2
    q = (-0.125 + 75.0 / 1024.0 * inv2) / x
    phase = x - 0.25 * math.pi
    return math.sqrt(2.0 / (math.pi * x)) * (p * math.cos(phase) - q * math.sin(phase))


@numba.njit(cache=True, nogil=True)
def _panel_sums_kernel(k, w_kronrod, w_diff, r, field, values, slopes):
    """Σ_n w_n J₀(k_n r) k_n/(2π) F(k_n) per panel: (n_p, n_r, n_c) for K15 and for K15 − G7."""
    n_p, n_n = k.shape
    n_c = field.shape[2]
    kron = np.zeros((n_p, r.size, n_c), np.complex128)
    diff = np.zeros((n_p, r.size, n_c), np.complex128)
    for p in range(n_p):
        for n in range(n_n):
            scale = k[p, n] / (2.0 * math.pi)
            for j in range(r.size):
                b = bessel_j0(k[p, n] * r[j], values, slopes) * scale
                bk = b * w_kronrod[p, n]
                bd = b * w_diff[p, n]
                for m in range(n_c):
                    kron[p, j, m] += bk * field[p, n, m]
                    diff[p, j, m] += bd * field[p, n, m]
    return kron, diff


def _panel_sums(lo, hi, r, field_at):
    """K15 sums and K15 − G7 differences of the transform on the panels [lo, hi]."""
    half = 0.5 * (hi - lo)
    k = 0.5 * (hi + lo)[:, None] + half[:, None] * GK_NODES[None, :]
    field = field_at(k.ravel())
    field = np.ascontiguousarray(field.reshape(lo.size, 15, field.shape[-1]))
    w_kronrod = GK_WEIGHTS[None, :] * half[:, None]
    w_diff = (GK_WEIGHTS - _G_WEIGHTS)[None, :] * half[:, None]
    return _panel_sums_kernel(k, w_kronrod, w_diff, r, field, _J0_VALUES, _J0_SLOPES)


def hankel_transform(
    field_at: Callable[[np.ndarray], np.ndarray],
    edges: np.ndarray,
    r_m: np.ndarray,
    rtol: float,
    scale: np.ndarray | None = None,
) -> tuple[np.ndarray, float]:
    """(1/2π)∫ F(k) J₀(kr) k dk over [edges[0], edges[-1]] by adaptive Gauss–Kronrod panels.

    Parameters
    ----------
    field_at : callable
        ``field_at(k)`` → complex (n_k, n_c) values F(k) of n_c columns (e.g. receiver depths).
    edges : ndarray
        Increasing initial panel edges (rad/m); the caller resolves the integrand's features.
    r_m : ndarray
        (n_r,) horizontal distances (m), ≥ 0.
    rtol : float
        Tolerance on the summed error estimate, relative to ``scale``.
    scale : ndarray, optional
        (n_c,) reference magnitude per column; default the largest |result| over r, updated
        after each pass.

    Returns
    -------
    (ndarray, float)
        Complex (n_r, n_c) transform and the final error estimate relative to ``scale``.

    Raises
    ------
    RuntimeError
        More than ``MAX_PANELS`` panels would be needed.
    """
    r = np.ascontiguousarray(np.asarray(r_m, float))
    lo, hi = edges[:-1].copy(), edges[1:].copy()
    kron, diff = _panel_sums(lo, hi, r, field_at)
    fixed = None if scale is None else np.asarray(scale, float).reshape(1, 1, -1)
    while True:
        total = kron.sum(axis=0)
        reference = (
            np.maximum(np.abs(total).max(axis=0), 1e-300).reshape(1, 1, -1)
            if fixed is None
            else fixed
        )
        error = (np.abs(diff) / reference).max(axis=(1, 2))
        estimate = float(error.sum())
        if estimate <= rtol:
            return total, estimate
        # split the largest estimates until what is left unsplit is a quarter of the tolerance
        order = np.argsort(error)[::-1]
        left = estimate - np.cumsum(error[order])
        n_split = int(np.argmax(left <= 0.25 * rtol)) + 1 if left[-1] <= 0.25 * rtol else lo.size
        split = np.zeros(lo.size, bool)
        split[order[:n_split]] = True
        if lo.size + n_split > MAX_PANELS:
            raise RuntimeError(
                f"the Hankel transform did not reach the tolerance {rtol:g} within {MAX_PANELS} "
                f"panels (estimate {estimate:.2g})"
            )
        mid = 0.5 * (lo[split] + hi[split])
        new_lo, new_hi = np.concatenate([lo[split], mid]), np.concatenate([mid, hi[split]])
        new_kron, new_diff = _panel_sums(new_lo, new_hi, r, field_at)
        keep = ~split
        lo, hi = np.concatenate([lo[keep], new_lo]), np.concatenate([hi[keep], new_hi])
        kron = np.concatenate([kron[keep], new_kron])
        diff = np.concatenate([diff[keep], new_diff])
