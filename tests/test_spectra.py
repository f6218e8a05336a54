"""Welch PSD and Fourier-transform helpers (model.spectra): normalisation and conventions."""

import numpy as np
import pytest

from model.spectra import fourier_transform, one_sided_psd, welch_tiling


def hann_weighted_mean_square(x, n_segment, hop=None):
    """Average over segments (hop default n/2) of Σ w²(x − x̄)² / Σ w², periodic Hann window."""
    window = 0.5 - 0.5 * np.cos(2 * np.pi * np.arange(n_segment) / n_segment)
    starts = range(0, x.size - n_segment + 1, hop or n_segment // 2)
    values = [
        np.sum(window**2 * (x[s : s + n_segment] - x[s : s + n_segment].mean()) ** 2)
        / np.sum(window**2)
        for s in starts
    ]
    return np.mean(values)


def test_psd_integral_equals_the_window_weighted_variance_exactly():
    """Parseval per segment, exact up to rounding (rtol 1e-12), for an arbitrary record."""
    rng = np.random.default_rng(3)
    dt, segment = 1e-3, 0.5
    x = np.cumsum(rng.normal(size=5250)) + 40.0  # non-stationary, non-zero mean; 21 hops
    f_hz, psd = one_sided_psd(x, dt, segment)
    df = f_hz[1] - f_hz[0]
    assert df == pytest.approx(1 / segment)
    assert np.sum(psd) * df == pytest.approx(hann_weighted_mean_square(x, 500), rel=1e-12)


@pytest.mark.parametrize("n_samples", [5321, 66645, 1999])
def test_segments_tile_the_whole_record(n_samples):
    """Segments start at 0, end at the last sample, overlap ≥ 50 %, stay within one hop of the
    requested length; Parseval then holds exactly (rtol 1e-12) with the adjusted tiling."""
    n_target = 500
    n_segment, hop = welch_tiling(n_samples, n_target)
    n_segments = (n_samples - n_segment) // hop + 1
    assert (n_segments - 1) * hop + n_segment == n_samples
    assert n_segment >= 2 * hop and abs(n_segment - n_target) <= hop
    x = np.random.default_rng(1).normal(size=n_samples)
    f_hz, psd = one_sided_psd(x, 1e-3, n_target * 1e-3)
    assert np.sum(psd) * (f_hz[1] - f_hz[0]) == pytest.approx(
        hann_weighted_mean_square(x, n_segment, hop), rel=1e-12
    )


def test_a_pulse_at_the_end_of_the_record_is_analysed():
    """A pulse two samples before the end of a record that does not tile into whole 50 %
    segments still carries energy into the PSD (plain Welch would drop it)."""
    x = np.zeros(5321)
    x[-3] = 1.0
    f_hz, psd = one_sided_psd(x, 1e-3, 0.5)
    assert np.sum(psd) > 0.0


def test_psd_of_a_sinusoid_integrates_to_its_variance_at_its_frequency():
    """A² /2 exactly (rtol 1e-12) for a sinusoid on a bin frequency ≥ 2/T_seg (the Hann-weighted
    mean of sin² is then exactly ½), concentrated within ±1 bin of f₀."""
    dt, segment, amplitude, f0 = 1e-3, 1.0, 3.0, 12.0
    t = np.arange(10000) * dt
    x = amplitude * np.sin(2 * np.pi * f0 * t + 0.3) + 7.0
    f_hz, psd = one_sided_psd(x, dt, segment)
    df = f_hz[1] - f_hz[0]
    assert np.sum(psd) * df == pytest.approx(amplitude**2 / 2, rel=1e-12)
    near = np.abs(f_hz - f0) <= df
    assert np.sum(psd[near]) * df == pytest.approx(amplitude**2 / 2, rel=1e-12)


def test_psd_of_white_noise_has_level_two_sigma_squared_dt_and_its_variance():
    """One-sided white-noise level 2σ²Δt and ∫ PSD df = σ².

    2¹⁸ Gaussian samples in ~510 half-overlapping segments: the relative standard error of the
    variance is ≈ 0.3 % and of the mean level ≈ 0.3 %; tolerance 1.5 % (5σ, seeded).
    """
    rng = np.random.default_rng(11)
    dt, sigma = 2e-4, 0.7
    x = rng.normal(scale=sigma, size=2**18)
    f_hz, psd = one_sided_psd(x, dt, 1024 * dt)
    assert np.sum(psd) * (f_hz[1] - f_hz[0]) == pytest.approx(sigma**2, rel=0.015)
    assert np.mean(psd[1:-1]) == pytest.approx(2 * sigma**2 * dt, rel=0.015)


def test_a_record_shorter_than_the_segment_is_analysed_whole():
    """One segment of the whole record, no warning (warnings are errors in this test suite)."""
    rng = np.random.default_rng(5)
    x = rng.normal(size=301)
    f_hz, psd = one_sided_psd(x, 0.01, 10.0)
    assert f_hz.size == 301 // 2 + 1
    assert np.sum(psd) * (f_hz[1] - f_hz[0]) == pytest.approx(
        hann_weighted_mean_square(x, 301), rel=1e-12
    )


def test_fourier_transform_of_a_gaussian_pulse_matches_the_closed_form():
    """x = A exp(−(t − t₀)²/(2σ²)) → X(f) = A σ√(2π) exp(−2π²σ²f²) exp(−i2πf t₀).

    The sampled sum is the trapezoid rule of a smooth, fully decayed integrand, exact to
    ~exp(−2π²σ²/Δt²) ≈ 0: tolerance 1e-12 of the peak.
    """
    dt, sigma, t0, amplitude = 1e-3, 0.02, 0.3, 5.0
    t = np.arange(700) * dt
    x = amplitude * np.exp(-0.5 * ((t - t0) / sigma) ** 2)
    f_hz, spectrum = fourier_transform(x, dt, 4096)
    assert f_hz[1] == pytest.approx(1 / (4096 * dt))
    expected = (
        amplitude
        * sigma
        * np.sqrt(2 * np.pi)
        * np.exp(-2 * (np.pi * sigma * f_hz) ** 2)
        * np.exp(-2j * np.pi * f_hz * t0)
    )
    np.testing.assert_allclose(spectrum, expected, rtol=0, atol=1e-12 * np.abs(expected[0]))


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: one_sided_psd([1.0, 2.0, 3.0], 0.0, 1.0), r"dt_s = 0\.0 is outside"),
        (lambda: one_sided_psd([1.0, np.nan, 3.0], 0.1, 1.0), r"NaN"),
        (lambda: one_sided_psd(np.ones((3, 3)), 0.1, 1.0), r"1-D record"),
        (lambda: one_sided_psd([1.0, 2.0, 3.0], 0.1, -1.0), r"segment_s = -1\.0 is outside"),
        (lambda: fourier_transform([1.0, 2.0, 3.0], 0.1, 2), r"n_fft = 2 is shorter"),
    ],
)
def test_bad_input_is_refused_with_a_message_naming_it(call, message):
    with pytest.raises(ValueError, match=message):
        call()
