"""Vertical rail-profile irregularity (paper §2.4, docs/model.md §4).

The US FRA vertical-profile PSD, its trigonometric-series synthesis and measured profiles read
from CSV. Sign convention: vertical displacements are positive **downward** in this project and
the wheel–rail compression is δ = Z_w − Z_r(x_w) − η(x_w) (δ > 0 in compression), so the rail
surface under a wheel sits at Z_r + η: **η > 0 is a dip** (surface below nominal) and η < 0 a
bump. A measured profile must be given in this convention.
"""

from __future__ import annotations

import math

import numba
import numpy as np
import scipy.fft

from model.params import FRA_ROUGHNESS_CM2_RAD_PER_M, Irregularity
from model.params.measured_profile import (
    MeasuredProfile,
    parse_profile,
    read_profile_file,
)

FRA_SCALE_FACTOR = 0.25  # k of the FRA formula (docs/model.md §4)
FRA_CUTOFF_WAVENUMBER = 0.8245  # Ω_c (rad/m)
CM2_TO_M2 = 1e-4

# A grid counts as uniform when every point is within this fraction of the step of the ideal
# grid; the profile's slope is O(1e-3), so the resulting error is below 1e-9 · step.
_UNIFORM_GRID_TOLERANCE = 1e-6


def _check_track_class(track_class) -> int:
    """Return ``track_class`` as an int, or raise naming the allowed classes."""
    if (
        isinstance(track_class, bool)
        or not isinstance(track_class, int | np.integer)
        or (int(track_class) not in FRA_ROUGHNESS_CM2_RAD_PER_M)
    ):
        raise ValueError(
            f"track_class = {track_class!r} is not an FRA track class; allowed: "
            f"integers 1–6 (6 is the best track)"
        )
    return int(track_class)


def fra_psd(wavenumber_rad_per_m, track_class: int) -> np.ndarray:
    """US FRA vertical-profile PSD, one-sided.

    S(Ω) = k A_v Ω_c² / (Ω² (Ω² + Ω_c²)), k = 0.25, Ω_c = 0.8245 rad/m, A_v of the class
    (``model.params.FRA_ROUGHNESS_CM2_RAD_PER_M``), converted from cm²/(rad/m) to m²/(rad/m).

    Parameters
    ----------
    wavenumber_rad_per_m : float or array_like
        Angular spatial frequency Ω = 2π/λ (rad/m), finite and > 0.
    track_class : int
        FRA track class 1–6 (6 is the best track).

    Returns
    -------
    ndarray
        S(Ω) in m²/(rad/m), same shape as the input.
    """
    amplitude = FRA_ROUGHNESS_CM2_RAD_PER_M[_check_track_class(track_class)]
    omega = np.asarray(wavenumber_rad_per_m, dtype=float)
    if not np.all(np.isfinite(omega)) or np.any(omega <= 0.0):
        bad = omega[~(np.isfinite(omega) & (omega > 0.0))].ravel()[0]
        raise ValueError(
            f"wavenumber_rad_per_m = {bad!r} is outside the allowed range (0, inf) rad/m"
        )
    omega_c2 = FRA_CUTOFF_WAVENUMBER**2
    psd_cm2 = FRA_SCALE_FACTOR * amplitude * omega_c2 / (omega**2 * (omega**2 + omega_c2))
    return psd_cm2 * CM2_TO_M2


def series_wavenumbers(wavelength_band_m: tuple[float, float], n_components: int):
    """Wavenumbers of the trigonometric series: midpoints of ``n_components`` equal bins.

    Parameters
    ----------
    wavelength_band_m : (float, float)
        (λ_min, λ_max) in m, 0 < λ_min < λ_max; the series covers Ω in [2π/λ_max, 2π/λ_min].
    n_components : int
        Number of cosines, ≥ 1.

    Returns
    -------
    wavenumbers : ndarray
        Ω_k (rad/m), shape (n_components,).
    spacing : float
        Bin width ΔΩ (rad/m).
    """
    try:
        wavelength_min, wavelength_max = (float(v) for v in wavelength_band_m)
    except (TypeError, ValueError):
        raise ValueError(
            f"wavelength_band_m = {wavelength_band_m!r} must be a pair "
            f"(shortest, longest) of wavelengths in m"
        ) from None
    if not (
        math.isfinite(wavelength_min)
        and math.isfinite(wavelength_max)
        and 0.0 < wavelength_min < wavelength_max
    ):
        raise ValueError(
            f"wavelength_band_m = {wavelength_band_m!r} must satisfy "
            f"0 < shortest < longest < inf (m)"
        )
    if (
        isinstance(n_components, bool)
        or not isinstance(n_components, int | np.integer)
        or (n_components < 1)
    ):
        raise ValueError(
            f"n_components = {n_components!r} is outside the allowed range: integers >= 1"
        )
    omega_min = 2.0 * math.pi / wavelength_max
    omega_max = 2.0 * math.pi / wavelength_min
    spacing = (omega_max - omega_min) / n_components
    return omega_min + (np.arange(n_components) + 0.5) * spacing, spacing


def _series_on_uniform_grid(x_start, x_step, n_points, amplitudes, wavenumbers, phases):
    """Σ_k a_k cos(Ω_k x + φ_k) at x_j = x_start + j·h, Ω_k = Ω_0 + kΔΩ, by the chirp-z transform.

    With d_k = a_k exp(i(Ω_k x_start + φ_k)) and w = exp(iΔΩh) the sum is
    Re[exp(iΩ_0 jh) Σ_k d_k w^{kj}]; Bluestein's kj = (k² + j² − (j − k)²)/2 turns Σ_k into a
    convolution, evaluated by FFT in O((n + K) log(n + K)) instead of n·K rotations. The chirp
    phases (ΔΩh/2)m² are rounded to ~1e-16 of themselves (≤ 1e-12 rad on 10⁵ points); the
    tests compare against direct cosines to 1e-12 m.
    """
    n_comp = amplitudes.size
    spacing = (wavenumbers[-1] - wavenumbers[0]) / (n_comp - 1) if n_comp > 1 else 0.0
    half_chirp = 0.5 * spacing * x_step
    k = np.arange(n_comp, dtype=float)
    j = np.arange(n_points, dtype=float)
    weighted = amplitudes * np.exp(1j * (wavenumbers * x_start + phases + half_chirp * k * k))
    lags = np.arange(-(n_comp - 1), n_points, dtype=float)
    size = scipy.fft.next_fast_len(n_comp + n_points - 1)
    convolved = scipy.fft.ifft(
        scipy.fft.fft(weighted, size) * scipy.fft.fft(np.exp(-1j * half_chirp * lags * lags), size)
    )[n_comp - 1 : n_comp - 1 + n_points]
    return (np.exp(1j * (wavenumbers[0] * x_step * j + half_chirp * j * j)) * convolved).real


@numba.njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def _series_at_points(x, amplitudes, wavenumbers, phases):
    """Σ_k a_k cos(Ω_k x + φ_k) at arbitrary points x by direct evaluation."""
    out = np.empty(x.size)
    for j in range(x.size):
        total = 0.0
        for k in range(amplitudes.size):
            total += amplitudes[k] * math.cos(wavenumbers[k] * x[j] + phases[k])
        out[j] = total
    return out


def _uniform_step(x: np.ndarray) -> float | None:
    """The step of ``x`` if it is a uniform grid (to ``_UNIFORM_GRID_TOLERANCE``), else None."""
    if x.size < 3:
        return None
    step = (x[-1] - x[0]) / (x.size - 1)
    if step == 0.0:
        return None
    ideal = x[0] + np.arange(x.size) * step
    if np.max(np.abs(x - ideal)) > _UNIFORM_GRID_TOLERANCE * abs(step):
        return None
    return step


def synthesize_profile(
    x_m,
    track_class: int,
    seed: int,
    wavelength_band_m: tuple[float, float] = (1.0, 50.0),
    n_components: int = 2000,
) -> np.ndarray:
    """Random vertical profile η(x) with the FRA PSD, by trigonometric series.

    η(x) = Σ_k sqrt(2 S(Ω_k) ΔΩ) cos(Ω_k x + φ_k), Ω_k the midpoints of ``n_components`` equal
    bins across [2π/λ_max, 2π/λ_min], φ_k uniform on [0, 2π) from
    ``np.random.default_rng(seed)``. Its spatial variance is Σ_k S(Ω_k) ΔΩ, the midpoint rule
    for the integral of S over the band. η > 0 is a dip (down positive, see module docstring).

    A uniform grid (the usual case) is evaluated by phasor rotation, O(n_points · n_components)
    multiply–adds; any other set of points by direct cosines (about 30× slower).

    Parameters
    ----------
    x_m : array_like
        Positions along the rail (m), 1-D, finite.
    track_class : int
        FRA track class 1–6.
    seed : int
        Seed of the random phases, ≥ 0.
    wavelength_band_m : (float, float)
        Shortest and longest wavelength (m) of the series.
    n_components : int
        Number of cosines.

    Returns
    -------
    ndarray
        η at ``x_m`` (m), positive downward.
    """
    track_class = _check_track_class(track_class)
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise ValueError(f"seed = {seed!r} is outside the allowed range: integers >= 0")
    x = np.asarray(x_m, dtype=float)
    if x.ndim != 1:
        raise ValueError(f"x_m must be 1-D; got an array of shape {x.shape}")
    if not np.all(np.isfinite(x)):
        raise ValueError("x_m contains NaN or infinite positions; allowed: finite values (m)")
    wavenumbers, spacing = series_wavenumbers(wavelength_band_m, n_components)
    amplitudes = np.sqrt(2.0 * fra_psd(wavenumbers, track_class) * spacing)
    phases = np.random.default_rng(seed).uniform(0.0, 2.0 * math.pi, wavenumbers.size)
    step = _uniform_step(x)
    if step is None:
        return _series_at_points(x, amplitudes, wavenumbers, phases)
    return _series_on_uniform_grid(x[0], step, x.size, amplitudes, wavenumbers, phases)


def load_profile_csv(path) -> tuple[np.ndarray, np.ndarray]:
    """Measured vertical profile from a CSV file named by the person running the program.

    The format is :mod:`model.params.measured_profile`'s: ``#`` comments and blank lines
    ignored, the header ``x_m,eta_m`` or ``x_m,eta_mm`` (η in mm is converted to m), then at
    least two ``x,η`` lines, x strictly increasing, all values finite. η follows the
    project's convention: positive is a dip.

    Parameters
    ----------
    path : str or Path
        File to read (any readable regular file: servers go through
        :func:`model.params.measured_profile.admit_profile` instead).

    Returns
    -------
    x_m : ndarray
        Positions (m), strictly increasing.
    eta_m : ndarray
        Profile (m), positive downward.

    Raises
    ------
    ValueError
        If the file cannot be read, is not a regular file, not UTF-8 or malformed; the message
        names the file, the line number and the fault (never a line's text).
    """
    profile = parse_profile(read_profile_file(path), str(path))
    return profile.x_m, profile.eta_m


def measured_profile(irregularity: Irregularity) -> MeasuredProfile | None:
    """The measured profile of an Irregularity (its text, else its file), or None."""
    if irregularity.profile_data is not None:
        return parse_profile(irregularity.profile_data)
    if irregularity.profile_csv:
        path = irregularity.profile_csv
        return parse_profile(read_profile_file(path), str(path))
    return None


def profile_for(irregularity: Irregularity, x_m) -> np.ndarray:
    """Rail profile η (m, positive downward) at positions ``x_m`` for an Irregularity.

    Zeros if ``irregularity.enabled`` is false; else the measured profile
    (:func:`measured_profile`: ``irregularity.profile_data``, else the file
    ``irregularity.profile_csv``), linearly interpolated, if set; else
    :func:`synthesize_profile` with the object's class, seed, wavelength band and number of
    components.

    Parameters
    ----------
    irregularity : model.params.Irregularity
        Irregularity settings.
    x_m : array_like
        Positions along the track (m), 1-D. The vehicle–track model measures them from the
        monitored block (negative before it), and so must a measured profile's x column.

    Returns
    -------
    ndarray
        η at ``x_m`` (m).

    Raises
    ------
    ValueError
        If ``x_m`` reaches outside the range covered by a measured profile.
    """
    x = np.asarray(x_m, dtype=float)
    if not irregularity.enabled:
        return np.zeros_like(x)
    profile = measured_profile(irregularity)
    if profile is not None:
        x_measured, eta_measured = profile.x_m, profile.eta_m
        if x.size and (x.min() < x_measured[0] or x.max() > x_measured[-1]):
            name = irregularity.profile_csv or "irregularity.profile_data"
            raise ValueError(
                f"x_m spans [{x.min():g}, {x.max():g}] m but the measured profile "
                f"{name} covers only [{x_measured[0]:g}, {x_measured[-1]:g}] m"
            )
        return np.interp(x, x_measured, eta_measured)
    return synthesize_profile(
        x,
        irregularity.track_class,
        irregularity.seed,
        (irregularity.wavelength_min, irregularity.wavelength_max),
        irregularity.n_components,
    )
