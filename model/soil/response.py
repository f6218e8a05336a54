"""Displacement time histories below the tunnel and their peaks against depth (docs/model.md §8).

The line load q(t) on the invert is Fourier transformed, multiplied by the invert receptance
H(f, d) of ``model.soil.section_2d`` and transformed back, at every output depth d. With the 2.5D
model (``tunnel.model == "2.5d"``, docs/model.md §9) the receptance is that of
``model.soil.moving_load_2p5d`` at the wavenumber ξ = ω/v of the train moving at speed v: the invert
load is stationary in the moving frame, so U(ω, d) = H(ω, ω/v, d) Q(ω).

Record handling:

- **Zero padding.** The record of duration T is padded with zeros to ``zero_pad_factor`` × T,
  so the periodic inverse FFT approximates the transient response; the padded part also holds
  the response after the load has ended.
- **Anti-aliased decimation, in the frequency domain.** The padded record is transformed at its
  own sampling rate and only the bins with f ≤ ``soil_max_frequency`` are kept (an ideal
  low-pass filter, no ripple or filter transient); the inverse transform is taken on a coarser
  time grid, Δt_out = k Δt with k the largest integer giving at least 4 samples per period of
  ``soil_max_frequency`` (2.5 ms for 100 Hz). The peak of a component at f is then sampled to
  within 1 − cos(π f Δt_out): ≤ 0.3 % below 10 Hz, where the displacement content lies.
- **Zero frequency.** In 2D the static response to a line load is infinite: the n = 1 harmonic
  grows like B ln(1/ω). The DC bin stands for the band [−Δf/2, Δf/2], so it is given the band
  average of H. Near f = 0, H(f) = A + B ln f + O((ωr/c₂)² ln ω), whose exact average over
  [0, h] is A + B(ln h − 1) = H(h/e); the DC bin therefore uses Re H(Δf/(2e)) (real because
  H(−f) = conj H(f)). Its contribution, ~ q̄ (ln T_pad)/T_pad, vanishes as the padding grows,
  and the tests show the peak displacement converging to the directly integrated transform.
  In 2.5D the same holds along ξ = ω/v: U(0) = ∫u dt = (1/v)∫G(x) dx diverges logarithmically
  (a point load's static displacement falls off like 1/|x|), and H(f, f/v) = A′ + B ln f to
  O(f) (tested), so the DC bin uses Re H(h/e, h/(e v)) by the same argument.
- **Kernel sampling.** The tunnel–soil kernel is evaluated on a subset of the record's
  frequency grid and interpolated in between (:func:`record_grid_transfer`). Outgoing waves
  at radius r vary as K_n(iωr/c), whose phase turns by ωr/c: the transfer functions at the
  deepest output point, r = a + max_depth, oscillate in f with period c₂/r (c₂ the S-wave
  speed, the slower wave). With N = ``kernel_samples_per_cycle``, every s-th bin is
  evaluated, s = ⌊c₂/(N r Δf)⌋, and the bins between by 6-point Lagrange interpolation
  (degree 5: the error of a sampled oscillation falls like (2π/N)⁶). Every bin below N s
  (up to ≈ c₂/r) is evaluated, where the 2D kernel's ln f makes the step relative to f too
  large, and so are the DC bin and the last bin. With s = 1 or N = 0 every bin is evaluated.

The peak is the maximum of the computed history as it stands (no baseline is subtracted).
Frequency-independent hysteretic damping is not causal: with η_G = 0.06 the displacement moves
by ~1 % of its peak before the load arrives (−0.15 mm at the invert for the paper case); with
η = 0 the history is causal to the padding error.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np
import scipy.fft

from model.soil.kernel_sampling import (  # noqa: F401 (re-exported: their home until now)
    KERNEL_STENCIL,
    depth_sample_bins,
    depth_sampled_transfer,
    kernel_interpolation_matrix,
    kernel_sample_bins,
    record_grid_transfer,
)
from model.soil.moving_load_2p5d import receptance_2p5d
from model.soil.section_2d import invert_receptance, use_serial_kernel
from model.spectra import checked_record, fourier_transform, one_sided_psd

# Output samples per period of the highest retained frequency (see the module docstring).
SAMPLES_PER_MAX_FREQUENCY_PERIOD = 4
# Tail kept after the load record, in units of the S-wave transit time to the deepest output
# depth: the response at depth d lags the load by about d/c₂, twice that covers its peak.
TAIL_TRANSIT_TIMES = 2.0
# Depth below the invert at which the paper quotes its Fig. 11 value (2.94 mm); the summary
# always reports the peak displacement there (docs/model.md §8).
COMPARISON_DEPTH_M = 11.0
# Rows of histories per inverse FFT call (RecordGrid.time_histories); any count gives the same
# numbers (each row is transformed alone); 16 is faster than all rows at once on the paper case
# (benchmarks/bench_pipeline.py, docs/tunnel_soil.md).
INVERSE_FFT_ROWS = 16


def response_tail(max_depth_m: float, s_wave_speed_m_s: float) -> float:
    """Time kept after the load record for the response to reach the deepest depth (s).

    ``TAIL_TRANSIT_TIMES`` S-wave transit times d_max/c₂.

    Parameters
    ----------
    max_depth_m : float
        Deepest output depth d_max (m).
    s_wave_speed_m_s : float
        Soil shear-wave speed c₂ (m/s).

    Returns
    -------
    float
    """
    return TAIL_TRANSIT_TIMES * max_depth_m / s_wave_speed_m_s


@dataclass(frozen=True)
class SoilResponse:
    """Soil stage result: displacement below the invert per the line-load history."""

    f_hz: np.ndarray
    """(nf,) frequencies of the interface PSD, 0 … soil_max_frequency (Hz)."""
    interface_psd: np.ndarray
    """(nf,) one-sided PSD of the interface displacement over the load record, m²/Hz."""
    depth_m: np.ndarray
    """(nd,) depths below the ring–soil interface (m); row 0 is the interface."""
    peak_disp_m: np.ndarray
    """(nd,) peak downward dynamic displacement at each depth during the passage (m)."""
    t_s: np.ndarray
    """(nt,) time of the histories (s), load record plus tail."""
    disp_m: np.ndarray
    """(nd, nt) downward displacement at each depth (m)."""
    interface_spectrum_f_hz: np.ndarray
    """(nk,) frequencies of the amplitude spectra, 0 … soil_max_frequency, step 1/T_pad (Hz)."""
    interface_amplitude_m_per_hz: np.ndarray
    """(nk,) Fourier amplitude |U(f)| of the interface displacement (m/Hz)."""
    line_load_amplitude_N_per_m_per_hz: np.ndarray
    """(nk,) Fourier amplitude |Q(f)| of the line load ((N/m)/Hz)."""


def decimation_factor(dt_s: float, max_frequency_hz: float) -> int:
    """Largest k ≥ 1 with k Δt ≤ 1/(4 f_max): the output step of the soil stage is k Δt.

    Parameters
    ----------
    dt_s : float
        Sampling interval of the load (s), > 0.
    max_frequency_hz : float
        Highest frequency kept, f_max (Hz), > 0.

    Returns
    -------
    int
        The decimation factor k.
    """
    return max(
        1, math.floor(1.0 / (SAMPLES_PER_MAX_FREQUENCY_PERIOD * max_frequency_hz * dt_s) + 1e-9)
    )


def section_receptance(
    freq_hz, depth_m, tunnel, soil, n_harmonics: int, speed_m_s: float | None = None
) -> np.ndarray:
    """Invert receptance of the chosen tunnel model (m per N/m), complex (n_freq, n_depth).

    ``tunnel.model == "2d"``: ``invert_receptance``; ``"2.5d"``: ``receptance_2p5d`` at the
    wavenumber ξ = 2πf/v of a load moving at ``speed_m_s`` = v (docs/model.md §9).

    Parameters
    ----------
    freq_hz : array_like
        Frequencies (Hz), > 0.
    depth_m : array_like
        Depths below the ring–soil interface (m), ≥ 0.
    tunnel, soil : model.params.Tunnel, model.params.Soil
        Lining (its ``model`` chooses the kernel) and soil.
    n_harmonics : int
        Highest circumferential harmonic.
    speed_m_s : float, optional
        Train speed v (m/s), > 0; required for the 2.5D model.

    Returns
    -------
    ndarray
        Complex (n_freq, n_depth) receptance.
    """
    if tunnel.model != "2.5d":
        return invert_receptance(freq_hz, depth_m, tunnel, soil, n_harmonics)
    if speed_m_s is None or not (math.isfinite(speed_m_s) and speed_m_s > 0.0):
        raise ValueError(
            f"speed_m_s = {speed_m_s!r}: the 2.5D tunnel model needs the train speed, "
            "finite and > 0 m/s"
        )
    freq = np.atleast_1d(np.asarray(freq_hz, dtype=float))
    return receptance_2p5d(freq, 2.0 * np.pi * freq / speed_m_s, depth_m, tunnel, soil, n_harmonics)


def dc_band_receptance(
    band_halfwidth_hz: float,
    depth_m,
    tunnel,
    soil,
    n_harmonics: int,
    speed_m_s: float | None = None,
) -> np.ndarray:
    """Receptance averaged over the zero-frequency bin's band [−h, h] (m per N/m).

    Re H(h/e): exact for H = A + B ln f, the low-frequency form of the 2D receptance and of
    the 2.5D one along ξ = ω/v (module docstring).

    Parameters
    ----------
    band_halfwidth_hz : float
        h = Δf/2 (Hz), > 0.
    depth_m : array_like
        Depths below the ring–soil interface (m), ≥ 0.
    tunnel, soil : model.params.Tunnel, model.params.Soil
        Lining and soil.
    n_harmonics : int
        Highest circumferential harmonic.
    speed_m_s : float, optional
        Train speed (m/s), required for the 2.5D model.

    Returns
    -------
    ndarray
        Real (n_depth,) band-averaged receptance.
    """
    return section_receptance(
        band_halfwidth_hz / math.e, depth_m, tunnel, soil, n_harmonics, speed_m_s
    )[0].real


@dataclass(frozen=True)
class RecordGrid:
    """Band-limited spectrum of a zero-padded load record and its output time grid."""

    f_hz: np.ndarray
    """(nk,) kept frequencies 0 … soil_max_frequency, step 1/T_pad (Hz)."""
    load_spectrum: np.ndarray
    """(nk,) Fourier transform of the load at ``f_hz`` (load unit · s)."""
    n_out_pad: int
    """Samples of the padded record on the output grid."""
    dt_out: float
    """Output time step (s), a whole multiple of the load's."""
    n_out: int
    """Output samples kept: the load record plus the wave-travel tail."""
    record_s: float
    """Duration of the load record (s)."""

    def time_histories(self, spectra: np.ndarray) -> np.ndarray:
        """(n_rows, n_out) histories x(t) = ∫ X(f) e^{i2πft} df of (n_rows, nk) spectra."""
        return self._inverse_rows(spectra.shape[0], lambda rows: spectra[rows])

    def response_histories(
        self, transfer: np.ndarray, minus: np.ndarray | None = None
    ) -> np.ndarray:
        """(n_columns, n_out) histories of the responses H(f) Q(f) to the grid's load, from
        (nk, n_columns) transfer functions H (the same numbers as ``time_histories`` of the
        products, without forming them all); with ``minus`` (the same shape), of the
        differences (H − minus) Q."""
        load = np.ascontiguousarray(self.load_spectrum)
        columns = np.ascontiguousarray(transfer)
        other = None if minus is None else np.ascontiguousarray(minus)
        return self._inverse_rows(
            transfer.shape[1],
            None,
            lambda rows, out: _product_rows(
                columns, other, load, rows.start, rows.stop - rows.start, out
            ),
        )

    def _inverse_rows(self, n_rows: int, spectra_of, fill=None) -> np.ndarray:
        """Inverse transforms of the rows ``spectra_of(slice)`` gives (or that ``fill(slice,
        buffer)`` writes into the buffer's first columns), a block at a time."""
        n_freq = self.f_hz.size
        histories = np.empty((n_rows, self.n_out))
        # A block of rows at a time: one zero-padded buffer that stays in the processor's
        # cache, where all rows at once would allocate and fill (rows × n_out_pad) anew.
        padded = np.zeros((min(n_rows, INVERSE_FFT_ROWS), self.n_out_pad // 2 + 1), dtype=complex)
        workers = 1 if use_serial_kernel() else numba.get_num_threads()
        for first in range(0, n_rows, INVERSE_FFT_ROWS):
            rows = slice(first, min(first + INVERSE_FFT_ROWS, n_rows))
            count = rows.stop - rows.start
            if fill is None:
                padded[:count, :n_freq] = spectra_of(rows)
            else:
                fill(rows, padded)
            inverse = scipy.fft.irfft(padded[:count], self.n_out_pad, axis=1, workers=workers)
            histories[rows] = inverse[:, : self.n_out]
        # Δf · n_out_pad = 1/dt_out turns the inverse DFT into samples of the integral.
        histories /= self.dt_out
        return histories


@numba.njit(cache=True, nogil=True)
def _product_rows(transfer, minus, load, first, count, out):
    """out[r, k] = (transfer − minus)[k, first + r] · load[k], r < count (the transposed
    products; ``minus`` None: transfer alone)."""
    for k in range(load.size):
        q = load[k]
        for r in range(count):
            h = transfer[k, first + r]
            if minus is not None:
                h = h - minus[k, first + r]
            out[r, k] = h * q


def padded_record_grid(
    line_load_N_per_m, dt_s: float, numerics, s_wave_speed: float, load_spectrum=None
) -> RecordGrid:
    """Zero-pad, transform and band-limit a load record (module docstring: record handling).

    Parameters
    ----------
    line_load_N_per_m : array_like
        Load record q(t) (N/m), sampled from t = 0 at ``dt_s``.
    dt_s : float
        Sampling interval (s), > 0.
    numerics : model.params.Numerics
        Uses soil_max_frequency, zero_pad_factor, max_depth.
    s_wave_speed : float
        Soil shear-wave speed c₂ (m/s), which sets the tail kept after the record.
    load_spectrum : ndarray, optional
        :func:`padded_load_spectrum` of this record and numerics, to reuse (it does not depend
        on the soil: :func:`model.pipeline.run` keeps it across soil changes); computed when
        not given.

    Returns
    -------
    RecordGrid
    """
    load = checked_record(line_load_N_per_m, dt_s)
    n_record = load.size
    step, n_out_pad, f_hz = _record_grid_layout(n_record, dt_s, numerics)
    if load_spectrum is None:
        load_spectrum = _transformed_record(load, dt_s, step * n_out_pad, f_hz.size)
    elif np.shape(load_spectrum) != f_hz.shape:
        raise ValueError(
            f"load_spectrum has {np.size(load_spectrum)} frequencies, this record's grid "
            f"{f_hz.size}: it was made for another record or other numerics"
        )
    dt_out = step * dt_s
    record_s = n_record * dt_s
    tail_s = response_tail(numerics.max_depth, s_wave_speed)
    return RecordGrid(
        f_hz=f_hz,
        load_spectrum=load_spectrum,
        n_out_pad=n_out_pad,
        dt_out=dt_out,
        n_out=min(n_out_pad, math.ceil((record_s + tail_s) / dt_out)),
        record_s=record_s,
    )


def padded_load_spectrum(line_load_N_per_m, dt_s: float, numerics) -> np.ndarray:
    """The load spectrum of :func:`padded_record_grid` (load unit · s), complex (nk,).

    Parameters
    ----------
    line_load_N_per_m : array_like
        Load record q(t) (N/m), sampled from t = 0 at ``dt_s``.
    dt_s : float
        Sampling interval (s), > 0.
    numerics : model.params.Numerics
        Uses soil_max_frequency and zero_pad_factor.

    Returns
    -------
    ndarray
        Q(f) at the record grid's frequencies 0 … soil_max_frequency.
    """
    load = checked_record(line_load_N_per_m, dt_s)
    step, n_out_pad, f_hz = _record_grid_layout(load.size, dt_s, numerics)
    return _transformed_record(load, dt_s, step * n_out_pad, f_hz.size)


def _transformed_record(load, dt_s: float, n_fft: int, n_keep: int) -> np.ndarray:
    """The first ``n_keep`` bins of the record's transform zero-padded to ``n_fft`` samples."""
    return fourier_transform(load, dt_s, n_fft)[1][:n_keep].copy()


def _record_grid_layout(n_record: int, dt_s: float, numerics) -> tuple[int, int, np.ndarray]:
    """(decimation step k, padded length on the output grid, kept frequencies) of a record."""
    f_max = numerics.soil_max_frequency
    step = decimation_factor(dt_s, f_max)
    n_out_pad = scipy.fft.next_fast_len(
        math.ceil(numerics.zero_pad_factor * n_record / step), real=True
    )
    # scipy.fft.rfftfreq(step · n_out_pad, dt_s)'s values (k · val), only as far as f_max: the
    # whole grid of the undecimated record would be ~10⁵–10⁶ bins for ~10³ kept
    n_fft = step * n_out_pad
    val = 1.0 / (n_fft * dt_s)
    f_hz = np.arange(min(n_fft // 2 + 1, math.floor(f_max / val) + 3)) * val
    n_keep = min(int(np.searchsorted(f_hz, f_max, side="right")), n_out_pad // 2 + 1)
    if n_keep < 2:
        raise ValueError(
            f"numerics.soil_max_frequency = {f_max:g} Hz is below the frequency "
            f"step {f_hz[1]:.3g} Hz of the padded record: raise it or the padding"
        )
    return step, n_out_pad, f_hz[:n_keep].copy()


def record_grid_frequencies(line_load_N_per_m, dt_s: float, numerics) -> np.ndarray:
    """The frequencies of :func:`padded_record_grid` without transforming the load (Hz).

    Parameters
    ----------
    line_load_N_per_m : array_like
        Load record (only its length counts).
    dt_s : float
        Sampling interval (s), > 0.
    numerics : model.params.Numerics
        Uses soil_max_frequency and zero_pad_factor.

    Returns
    -------
    ndarray
        (nk,) 0 … soil_max_frequency, step 1/T_pad, equal to ``padded_record_grid(...).f_hz``.
    """
    n_record = checked_record(line_load_N_per_m, dt_s).size
    return _record_grid_layout(n_record, dt_s, numerics)[2]


def soil_response(
    line_load_N_per_m, dt_s: float, tunnel, soil, numerics, speed_m_s: float | None = None
) -> SoilResponse:
    """Displacement histories and peaks below the invert for a line-load history.

    Parameters
    ----------
    line_load_N_per_m : array_like
        Downward line load on the invert q(t) (N/m), sampled from t = 0 at ``dt_s``.
    dt_s : float
        Sampling interval (s), > 0.
    tunnel : model.params.Tunnel
        Lining; ``tunnel.model`` chooses the 2D or the 2.5D kernel.
    soil : model.params.Soil
        Soil.
    numerics : model.params.Numerics
        Uses n_harmonics, soil_max_frequency, zero_pad_factor, psd_segment, max_depth,
        n_depths, kernel_samples_per_cycle.
    speed_m_s : float, optional
        Train speed v (m/s): the 2.5D kernel is evaluated at ξ = ω/v (required for it).

    Returns
    -------
    SoilResponse
    """
    grid = padded_record_grid(line_load_N_per_m, dt_s, numerics, soil.s_wave_speed)
    depth = output_depths(numerics)
    (receptance,) = depth_sampled_transfer(
        grid.f_hz,
        depth,
        lambda freq, depth, _: (  # every point: the mask only saves work
            section_receptance(freq, depth, tunnel, soil, numerics.n_harmonics, speed_m_s),
        ),
        tunnel,
        soil,
        numerics,
    )
    return displacement_response(grid, depth, receptance, numerics)


def output_depths(numerics) -> np.ndarray:
    """Depths below the ring–soil interface at which the soil stage reports (m).

    Parameters
    ----------
    numerics : model.params.Numerics
        Uses max_depth and n_depths.

    Returns
    -------
    ndarray
        (n_depths,) depths from 0 to ``max_depth``, evenly spaced.
    """
    return np.linspace(0.0, numerics.max_depth, numerics.n_depths)


def displacement_response(grid: RecordGrid, depth_m, receptance, numerics) -> SoilResponse:
    """Displacement histories, peaks and spectra from the receptance at the grid's frequencies.

    Parameters
    ----------
    grid : RecordGrid
        The padded, band-limited load record (:func:`padded_record_grid`).
    depth_m : ndarray
        (nd,) depths below the ring–soil interface (m).
    receptance : ndarray
        Complex (nk, nd) receptance at ``grid.f_hz`` (m per N/m), row 0 the band-averaged
        zero-frequency value (:func:`dc_band_receptance`).
    numerics : model.params.Numerics
        Uses psd_segment and soil_max_frequency.

    Returns
    -------
    SoilResponse
    """
    f_hz, load_spectrum = grid.f_hz, grid.load_spectrum
    disp = grid.response_histories(receptance)
    n_out, dt_out = grid.n_out, grid.dt_out

    n_record_out = max(2, min(n_out, round(grid.record_s / dt_out)))
    psd_f_hz, psd = one_sided_psd(disp[0, :n_record_out], dt_out, numerics.psd_segment)
    in_band = psd_f_hz <= numerics.soil_max_frequency
    return SoilResponse(
        f_hz=psd_f_hz[in_band],
        interface_psd=psd[in_band],
        depth_m=depth_m,
        peak_disp_m=disp.max(axis=1),
        t_s=np.arange(n_out) * dt_out,
        disp_m=disp,
        interface_spectrum_f_hz=f_hz,
        interface_amplitude_m_per_hz=np.abs(receptance[:, 0] * load_spectrum),
        line_load_amplitude_N_per_m_per_hz=np.abs(load_spectrum),
    )
