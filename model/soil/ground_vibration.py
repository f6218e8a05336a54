"""Ground-borne vibration at the surface: one-third-octave velocity levels (docs/halfspace.md).

- **Bands**: one-third octaves per IEC 61260-1 (base 10): exact midband frequencies
  f_m = 1000 · 10^{x/10} Hz (x an integer), band edges f_m · 10^{∓1/20}; the nominal
  frequencies (1, 1.25, 1.6, …, 80 Hz) label them. 1–80 Hz is the range of ground-borne
  vibration from railways (:data:`BAND_RANGE_HZ`).
- **Band level**: L_v = 10 log₁₀(v²_rms,band / v_ref²) dB with v_ref = 1e-9 m/s
  (:data:`REFERENCE_VELOCITY_M_PER_S`; some codes use 5e-8 m/s, 34 dB less). v²_rms,band is
  the energy of the band over the averaging time T (the passage record): (1/T) · 2∫_band |V(f)|²
  df, V the Fourier transform of the velocity history, each frequency bin split between the
  bands its width [f − Δf/2, f + Δf/2] overlaps, so that the band energies add up to the energy
  of their whole range exactly (Parseval).
- **Overall level**: the energetic sum 10 log₁₀ Σ 10^{L/10} over the bands.
- **Levels floor**: a band whose level is below :data:`LEVEL_FLOOR_DB` (a velocity of 1e-12 m/s,
  far below any sensor's noise) is reported at the floor, so that a band with no content (the
  evanescent field of a subsonic train at high frequency) reads as a finite "nothing".
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

REFERENCE_VELOCITY_M_PER_S = 1e-9
"""v_ref of the velocity levels (m/s)."""
BAND_RANGE_HZ = (1.0, 80.0)
"""Nominal centre frequencies of the first and last band reported (Hz)."""
LEVEL_FLOOR_DB = -60.0
"""Lowest level reported, dB re 1e-9 m/s (1e-12 m/s): below it a band reads as this value."""
_NOMINAL = (1.0, 1.25, 1.6, 2.0, 2.5, 3.15, 4.0, 5.0, 6.3, 8.0)  # × 10^k (IEC 61260-1)


@dataclass(frozen=True)
class ThirdOctaveBands:
    """One-third-octave bands (IEC 61260-1, base 10)."""

    centre_hz: np.ndarray
    """(n_band,) exact midband frequencies f_m = 1000 · 10^{x/10} (Hz)."""
    lower_hz: np.ndarray
    """(n_band,) lower edges f_m · 10^{−1/20} (Hz)."""
    upper_hz: np.ndarray
    """(n_band,) upper edges f_m · 10^{1/20} (Hz)."""
    nominal_hz: np.ndarray
    """(n_band,) nominal midband frequencies, the bands' labels (Hz)."""


def third_octave_bands(
    first_hz: float = BAND_RANGE_HZ[0], last_hz: float = BAND_RANGE_HZ[1]
) -> ThirdOctaveBands:
    """The one-third-octave bands whose nominal centres lie in [first_hz, last_hz].

    Parameters
    ----------
    first_hz, last_hz : float
        Nominal centre frequencies of the first and last band (Hz), 0 < first ≤ last.

    Returns
    -------
    ThirdOctaveBands
    """
    if not (0.0 < first_hz <= last_hz):
        raise ValueError(
            f"the band range {first_hz!r}–{last_hz!r} Hz must satisfy 0 < first ≤ last"
        )
    x = np.arange(np.floor(10 * np.log10(first_hz / 1000.0)) - 1, 10 * np.log10(last_hz / 1000) + 2)
    centre = 1000.0 * 10.0 ** (x / 10.0)
    decade = np.floor(np.log10(centre * 1.0001))
    nominal = np.array([_NOMINAL[int(i) % 10] for i in x]) * 10.0**decade
    keep = (nominal >= first_hz * 0.999) & (nominal <= last_hz * 1.001)
    centre = centre[keep]
    return ThirdOctaveBands(
        centre_hz=centre,
        lower_hz=centre * 10.0**-0.05,
        upper_hz=centre * 10.0**0.05,
        nominal_hz=nominal[keep],
    )


def band_energies(f_hz, spectrum, bands: ThirdOctaveBands) -> np.ndarray:
    """Energy 2∫_band |X(f)|² df of each band of a one-sided continuous Fourier transform.

    Bin k stands for [f_k − Δf/2, f_k + Δf/2] (from 0 for the DC bin) with |X_k|² constant
    there; the band energies are differences of that piecewise-linear cumulative energy at the
    band edges, so a bin the edge cuts is shared in proportion to the overlap.

    Parameters
    ----------
    f_hz : ndarray
        (n_f,) uniform frequencies f_k = k Δf from 0 (Hz).
    spectrum : ndarray
        (n_f, ...) X(f) in unit·s (``model.spectra.fourier_transform``).
    bands : ThirdOctaveBands
        The bands.

    Returns
    -------
    ndarray
        (n_band, ...) energies in unit²·s (∫ x² dt of the band-limited signal).
    """
    f_hz = np.asarray(f_hz, float)
    df = f_hz[1] - f_hz[0]
    edges = np.concatenate([[0.0], f_hz + 0.5 * df])
    power = np.abs(np.asarray(spectrum)) ** 2
    widths = np.diff(edges).reshape((-1,) + (1,) * (power.ndim - 1))
    cumulative = np.concatenate([np.zeros((1,) + power.shape[1:]), np.cumsum(power * widths, 0)])
    flat = cumulative.reshape(edges.size, -1)
    at = np.stack(
        [np.interp(np.concatenate([bands.lower_hz, bands.upper_hz]), edges, c) for c in flat.T],
        axis=-1,
    )
    n = bands.centre_hz.size
    return 2.0 * (at[n:] - at[:n]).reshape((n,) + power.shape[1:])


def velocity_levels(f_hz, velocity_spectrum, averaging_s: float, bands: ThirdOctaveBands):
    """Band velocity levels L_v = 10 log₁₀(E_band / (T v_ref²)) in dB re 1e-9 m/s.

    Parameters
    ----------
    f_hz : ndarray
        (n_f,) uniform frequencies from 0 (Hz).
    velocity_spectrum : ndarray
        (n_f, ...) Fourier transform of the velocity (m/s · s).
    averaging_s : float
        Averaging time T (s), > 0: the passage record.
    bands : ThirdOctaveBands
        The bands.

    Returns
    -------
    ndarray
        (n_band, ...) levels (dB), at least :data:`LEVEL_FLOOR_DB`.
    """
    if not averaging_s > 0.0:
        raise ValueError(f"averaging_s = {averaging_s!r} must be > 0 s")
    mean_square = band_energies(f_hz, velocity_spectrum, bands) / averaging_s
    floor = REFERENCE_VELOCITY_M_PER_S**2 * 10.0 ** (LEVEL_FLOOR_DB / 10.0)
    return 10.0 * np.log10(np.maximum(mean_square, floor) / REFERENCE_VELOCITY_M_PER_S**2)


def overall_level(levels_db, axis: int = 0) -> np.ndarray:
    """Energetic sum 10 log₁₀ Σ 10^{L/10} of band levels along ``axis`` (dB)."""
    levels = np.asarray(levels_db, float)
    top = levels.max(axis=axis, keepdims=True)
    return np.squeeze(top, axis) + 10.0 * np.log10(
        np.sum(10.0 ** ((levels - top) / 10.0), axis=axis)
    )


@dataclass(frozen=True)
class GroundResponse:
    """Ground-surface vibration of one passage (``res.ground``), the half-space models only."""

    distance_m: np.ndarray
    """(n_distance,) horizontal distance from the tunnel axis on the ground surface (m)."""
    band_centre_hz: np.ndarray
    """(n_band,) exact one-third-octave midband frequencies (Hz)."""
    band_nominal_hz: np.ndarray
    """(n_band,) their nominal labels (1, 1.25, …, 80 Hz)."""
    velocity_level_dB: np.ndarray
    """(n_band, n_distance) vertical velocity level per band, dB re 1e-9 m/s over the passage."""
    overall_level_dB: np.ndarray
    """(n_distance,) energetic sum of the band levels (dB re 1e-9 m/s)."""
    peak_velocity_m_per_s: np.ndarray
    """(n_distance,) peak |vertical velocity| during the passage (m/s)."""
    peak_disp_m: np.ndarray
    """(n_distance,) peak downward dynamic displacement: the dynamic surface trough (m)."""
    t_s: np.ndarray
    """(nt,) time (s), the soil stage's output grid."""
    velocity_m_per_s: np.ndarray
    """(n_distance, nt) vertical velocity, down + (m/s)."""
    averaging_s: float
    """Averaging time T of the levels: the passage record (s)."""
    free_surface_effect: float
    """Relative change of the peak invert displacement that the free surface makes (-): the
    size of the pipe-in-pipe correction at the tunnel (docs/halfspace.md, accuracy)."""
    reference_velocity_m_per_s: float = REFERENCE_VELOCITY_M_PER_S
    """v_ref of the levels (m/s)."""


def ground_response(
    grid, distance_m, surface_transfer, free_surface_effect: float
) -> GroundResponse:
    """Surface velocity levels, peaks and the dynamic trough from a surface transfer function.

    Parameters
    ----------
    grid : model.soil.response.RecordGrid
        The padded, band-limited load record (its spectrum Q(f), frequencies and time grid).
    distance_m : ndarray
        (n_distance,) distances from the tunnel axis (m).
    surface_transfer : ndarray
        Complex (n_f, n_distance) surface displacement per unit invert line load at
        ``grid.f_hz`` (m per N/m), row 0 the DC band value.
    free_surface_effect : float
        Relative change of the peak invert displacement due to the free surface (-), recorded.

    Returns
    -------
    GroundResponse
        The bands are those of :data:`BAND_RANGE_HZ` that end below the grid's highest
        frequency (``numerics.soil_max_frequency``).
    """
    f_hz = grid.f_hz
    disp_spectrum = surface_transfer * grid.load_spectrum[:, None]
    velocity_spectrum = 2j * np.pi * f_hz[:, None] * disp_spectrum
    histories = grid.time_histories(np.concatenate([disp_spectrum.T, velocity_spectrum.T]))
    n = distance_m.size
    disp, velocity = histories[:n], histories[n:]
    bands = third_octave_bands()
    inside = bands.upper_hz <= f_hz[-1]
    bands = ThirdOctaveBands(*(getattr(bands, k)[inside] for k in ThirdOctaveBands.__annotations__))
    levels = velocity_levels(f_hz, velocity_spectrum, grid.record_s, bands)
    return GroundResponse(
        distance_m=np.asarray(distance_m, float),
        band_centre_hz=bands.centre_hz,
        band_nominal_hz=bands.nominal_hz,
        velocity_level_dB=levels,
        overall_level_dB=overall_level(levels) if levels.size else np.full(n, LEVEL_FLOOR_DB),
        peak_velocity_m_per_s=np.abs(velocity).max(axis=1),
        peak_disp_m=disp.max(axis=1),
        t_s=np.arange(grid.n_out) * grid.dt_out,
        velocity_m_per_s=velocity,
        averaging_s=grid.record_s,
        free_surface_effect=float(free_surface_effect),
    )


def ground_summary(ground: GroundResponse) -> dict[str, float]:
    """Key numbers of the ground-surface results for ``Results.summary`` (SI units, dB).

    Above the axis (distance 0) and at the farthest distance: the overall velocity level and
    the peak velocity; the dynamic trough's depth above the axis and its half-width (where it
    has fallen to half, interpolated; the farthest distance if it does not); and the free
    surface's effect on the peak invert displacement.
    """
    distance, trough = ground.distance_m, ground.peak_disp_m
    below_half = np.nonzero(trough <= 0.5 * trough[0])[0]
    if below_half.size and below_half[0] > 0:
        k = below_half[0]
        half_width = float(np.interp(0.5 * trough[0], trough[[k, k - 1]], distance[[k, k - 1]]))
    else:
        half_width = float(distance[-1])
    return {
        "ground_overall_level_axis_dB": float(ground.overall_level_dB[0]),
        "ground_overall_level_farthest_dB": float(ground.overall_level_dB[-1]),
        "ground_farthest_distance_m": float(distance[-1]),
        "ground_peak_velocity_axis_m_per_s": float(ground.peak_velocity_m_per_s[0]),
        "ground_peak_velocity_farthest_m_per_s": float(ground.peak_velocity_m_per_s[-1]),
        "ground_trough_axis_m": float(trough[0]),
        "ground_trough_half_width_m": half_width,
        "free_surface_effect_invert": ground.free_surface_effect,
    }
