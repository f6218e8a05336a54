"""Spectral helpers shared by the load and soil stages: Welch PSDs and Fourier transforms.

Conventions: one-sided PSDs in unit²/Hz; Fourier transforms approximate the continuous
X(f) = ∫ x(t) e^(−i2πft) dt (unit·s = unit/Hz), whose inverse x(t) = ∫ X(f) e^(+i2πft) df is the
project's exp(+iωt) convention, so X can be multiplied directly by a receptance.
"""

from __future__ import annotations

import numpy as np
import scipy.fft
import scipy.signal


def checked_record(x, dt_s) -> np.ndarray:
    """``x`` as a 1-D finite float array of ≥ 2 samples, after checking that dt_s (s) is > 0.

    Raises ValueError naming the offending input otherwise.
    """
    record = np.asarray(x, dtype=float)
    if record.ndim != 1 or record.size < 2:
        raise ValueError(f"x must be a 1-D record of at least 2 samples, got shape {record.shape}")
    if not np.all(np.isfinite(record)):
        raise ValueError("x contains NaN or infinite samples")
    if not (np.isfinite(dt_s) and dt_s > 0.0):
        raise ValueError(f"dt_s = {dt_s!r} is outside the allowed range (0, inf) s")
    return record


def welch_tiling(n_samples: int, n_target: int) -> tuple[int, int]:
    """Segment length and hop (samples) near ``n_target`` and half of it whose segments, with at
    least 50 % overlap, start at sample 0 and end exactly at the last sample."""
    if n_samples <= n_target:
        return n_samples, n_samples
    n_segments = max(2, round(2 * n_samples / n_target - 1))
    hop = n_samples // (n_segments + 1)
    return n_samples - (n_segments - 1) * hop, hop


def one_sided_psd(x, dt_s: float, segment_s: float) -> tuple[np.ndarray, np.ndarray]:
    """One-sided power spectral density by Welch's method.

    Hann window (periodic), segments of about ``segment_s`` overlapping by at least 50 %, each
    segment's mean removed (constant detrending), density scaling. The segment length and hop
    are adjusted (by less than one hop) so that the segments tile the record exactly: a train
    passage is a transient, and plain Welch would drop the samples after the last whole
    segment, where the trailing bogie passes. A record shorter than ``segment_s`` is analysed
    whole as one segment.

    Normalisation (Parseval, exact): Σ psd · Δf equals the average over segments of the
    Hann-weighted mean square of the mean-removed segment, Σ w²(x − x̄)² / Σ w². For a
    stationary record this is the variance of x.

    Parameters
    ----------
    x : array_like
        Uniformly sampled record (any unit), 1-D, ≥ 2 samples.
    dt_s : float
        Sampling interval (s), > 0.
    segment_s : float
        Welch segment length (s), > 0; the frequency resolution is about 1/segment_s.

    Returns
    -------
    f_hz : ndarray
        Frequencies 0 … 1/(2 dt) (Hz), spacing 1/(n_seg dt).
    psd : ndarray
        One-sided PSD in unit²/Hz.
    """
    record = checked_record(x, dt_s)
    if not (np.isfinite(segment_s) and segment_s > 0.0):
        raise ValueError(f"segment_s = {segment_s!r} is outside the allowed range (0, inf) s")
    n_segment, hop = welch_tiling(record.size, max(2, round(segment_s / dt_s)))
    return scipy.signal.welch(
        record,
        fs=1.0 / dt_s,
        window="hann",
        nperseg=n_segment,
        noverlap=n_segment - hop,
        detrend="constant",
        return_onesided=True,
        scaling="density",
    )


def fourier_transform(x, dt_s: float, n_fft: int | None = None):
    """Continuous Fourier transform of a sampled record, X(f) ≈ ∫ x(t) e^(−i2πft) dt.

    The record starts at t = 0 and is zero-padded to ``n_fft`` samples (default: its own
    length), so the frequency spacing is 1/(n_fft dt).

    Parameters
    ----------
    x : array_like
        Uniformly sampled record (any unit), 1-D.
    dt_s : float
        Sampling interval (s), > 0.
    n_fft : int, optional
        Transform length ≥ len(x).

    Returns
    -------
    f_hz : ndarray
        Frequencies 0 … 1/(2 dt) (Hz).
    spectrum : ndarray
        Complex X(f) in unit·s (= unit/Hz).
    """
    record = checked_record(x, dt_s)
    n = record.size if n_fft is None else int(n_fft)
    if n < record.size:
        raise ValueError(f"n_fft = {n_fft!r} is shorter than the record ({record.size} samples)")
    return scipy.fft.rfftfreq(n, dt_s), scipy.fft.rfft(record, n) * dt_s
