"""Track irregularity: FRA PSD, trigonometric series, measured profiles (docs/model.md §4)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate, signal

from model.params import DATA_DIR, Irregularity
from model.track.irregularity import (
    fra_psd,
    load_profile_csv,
    profile_for,
    series_wavenumbers,
    synthesize_profile,
)

OMEGA_C = 0.8245  # rad/m, FRA cut-off
DEFAULT_BAND = (1.0, 50.0)


def band_variance_exact(track_class_amplitude_cm2, wavelength_band_m):
    """∫ S dΩ over the band in closed form (m²).

    Ω_c²/(Ω²(Ω² + Ω_c²)) = 1/Ω² − 1/(Ω² + Ω_c²), so the antiderivative of S is
    k A_v (−1/Ω − atan(Ω/Ω_c)/Ω_c) in cm².
    """
    lo, hi = 2 * math.pi / wavelength_band_m[1], 2 * math.pi / wavelength_band_m[0]

    def antiderivative(omega):
        return -1.0 / omega - math.atan(omega / OMEGA_C) / OMEGA_C

    return 0.25 * track_class_amplitude_cm2 * (antiderivative(hi) - antiderivative(lo)) * 1e-4


def one_period_grid(n_components, n_points, wavelength_band_m=DEFAULT_BAND):
    """Uniform grid over one period 2π/ΔΩ of the series' difference frequencies."""
    _, spacing = series_wavenumbers(wavelength_band_m, n_components)
    return np.arange(n_points) * (2 * math.pi / spacing / n_points)


# ---- FRA PSD --------------------------------------------------------------------------------


def test_fra_psd_hand_values():
    """S(Ω) = k A Ω_c²/(Ω²(Ω² + Ω_c²)) cm²/(rad/m), worked by hand with k = 0.25.

    Class 6 at Ω = Ω_c: k A/(2 Ω_c²) = 0.25·0.0339/(2·0.67980) = 6.2334e-3 cm² = 6.2334e-7 m².
    Class 1 at Ω = 1: 0.25·1.2107·0.67980/(1·1.67980) = 0.122490 cm² = 1.22490e-5 m².
    Class 4 at Ω = 2π: 0.25·0.5376·0.67980/(39.4784·40.1582) = 5.7629e-5 cm².
    Tolerance 1e-4 relative: the hand values carry 5 significant figures.
    """
    assert fra_psd(OMEGA_C, 6) == pytest.approx(6.2334e-7, rel=1e-4)
    assert fra_psd(1.0, 1) == pytest.approx(1.22490e-5, rel=1e-4)
    assert fra_psd(2 * math.pi, 4) == pytest.approx(5.7629e-9, rel=1e-4)


def test_fra_psd_asymptotes_and_class_order():
    """S → k A/Ω² for Ω ≪ Ω_c and k A Ω_c²/Ω⁴ for Ω ≫ Ω_c; worse class, more roughness.

    Tolerance: the relative deviation from each asymptote is (Ω/Ω_c)² resp. (Ω_c/Ω)² = 1e-6
    at the points chosen, so 2e-6.
    """
    low, high = 1e-3 * OMEGA_C, 1e3 * OMEGA_C
    assert fra_psd(low, 2) == pytest.approx(0.25 * 1.0181e-4 / low**2, rel=2e-6)
    assert fra_psd(high, 2) == pytest.approx(0.25 * 1.0181e-4 * OMEGA_C**2 / high**4, rel=2e-6)
    omega = np.geomspace(0.05, 20.0, 50)
    by_class = np.array([fra_psd(omega, c) for c in range(1, 7)])
    assert by_class.shape == (6, 50)
    assert np.all(np.diff(by_class, axis=0) < 0)


@pytest.mark.parametrize("track_class", [0, 7, 2.0, True, "6"])
def test_fra_psd_refuses_bad_class(track_class):
    with pytest.raises(ValueError, match=r"track_class = .* allowed: integers 1–6"):
        fra_psd(1.0, track_class)


@pytest.mark.parametrize("omega", [0.0, -1.0, np.nan, [1.0, np.inf]])
def test_fra_psd_refuses_nonpositive_wavenumber(omega):
    with pytest.raises(ValueError, match=r"wavenumber_rad_per_m = .* allowed range \(0, inf\)"):
        fra_psd(omega, 6)


# ---- variance of the synthesised profile -----------------------------------------------------


def test_band_integral_closed_form_matches_quad_and_model_md_rms():
    """Closed-form band integral = scipy quad; class 6 over 1–50 m gives RMS 2.30 mm.

    quad tolerance 1e-9 relative (smooth integrand, quad's own error estimate is ~1e-14).
    docs/model.md quotes the RMS as ≈ 2.3 mm (2 significant figures): 0.05 mm tolerance.
    """
    for track_class, amplitude in [(1, 1.2107), (6, 0.0339)]:
        lo, hi = 2 * math.pi / 50.0, 2 * math.pi / 1.0
        quad_value, _ = integrate.quad(
            lambda om, c=track_class: float(fra_psd(om, c)),
            lo,
            hi,
            epsabs=0.0,
            epsrel=1e-12,
            limit=200,
        )
        assert band_variance_exact(amplitude, DEFAULT_BAND) == pytest.approx(quad_value, rel=1e-9)
    rms_class6 = math.sqrt(band_variance_exact(0.0339, DEFAULT_BAND))
    assert rms_class6 == pytest.approx(2.3e-3, abs=0.05e-3)


def test_series_variance_is_midpoint_rule_of_band_integral_second_order():
    """Σ S(Ω_k) ΔΩ is the midpoint rule of ∫ S dΩ: error falls as ΔΩ² (observed order 2 ± 0.05).

    At the default 2000 components it is within 2e-4 of the exact integral (the midpoint error
    ΔΩ² S''/24S ≈ 1.5e-4 at the low-wavenumber end dominates).
    """
    exact = band_variance_exact(0.0339, DEFAULT_BAND)
    counts = np.array([250, 500, 1000, 2000, 4000])
    errors = []
    for n in counts:
        omega, spacing = series_wavenumbers(DEFAULT_BAND, int(n))
        errors.append(abs(np.sum(fra_psd(omega, 6)) * spacing - exact) / exact)
    order = -np.polyfit(np.log(counts), np.log(errors), 1)[0]
    assert order == pytest.approx(2.0, abs=0.05)
    assert errors[3] < 2e-4


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_profile_variance_over_one_period_equals_series_variance(seed):
    """Mean square of η over one period 2π/ΔΩ = Σ a_k²/2 = Σ S(Ω_k) ΔΩ.

    Cross terms at difference frequencies (multiples of ΔΩ) vanish exactly on a uniform grid
    over one period; sum-frequency terms average to O(1/(Ω_min·period)) ≈ 0.4 % at most
    (observed ≤ 0.35 %), so 1 % tolerance. Class 6 RMS over 1–50 m is then 2.3 mm (docs/model.md).
    """
    n_components = 2000
    x = one_period_grid(n_components, 2**16)
    eta = synthesize_profile(x, 6, seed)
    omega, spacing = series_wavenumbers(DEFAULT_BAND, n_components)
    series_variance = np.sum(fra_psd(omega, 6)) * spacing
    assert np.mean(eta**2) == pytest.approx(series_variance, rel=1e-2)
    assert math.sqrt(np.mean(eta**2)) == pytest.approx(2.3e-3, abs=0.05e-3)


def test_welch_psd_follows_fra_psd_across_band():
    """Welch estimate of synthesized profiles (16 seeds) follows fra_psd in six log bands.

    One period (2041 m) at 0.1 m, 4096-point Hann segments (ΔΩ_Welch = 0.015 rad/m, 9 segments
    with 50 % overlap): per-bin relative standard error ≈ 0.35, averaged over ≥ 9 bins and 16
    seeds ≈ 4 % in the worst band, so 12 % (3σ) tolerance; a convention slip (factor 2 or 2π)
    fails by far. Three Welch bins are left out at each band edge (Hann main lobe). Above the
    band the estimate must be < 1e-3 of the FRA value (only Hann leakage).
    """
    spacing_welch_m = 0.1
    n_components = 2000
    _, spacing = series_wavenumbers(DEFAULT_BAND, n_components)
    x = np.arange(0.0, 2 * math.pi / spacing, spacing_welch_m)
    estimates = []
    for seed in range(16):
        eta = synthesize_profile(x, 6, seed)
        freq_cycles_per_m, psd_per_cycle = signal.welch(eta, fs=1 / spacing_welch_m, nperseg=4096)
        estimates.append(psd_per_cycle / (2 * math.pi))  # m²/(cycle/m) → m²/(rad/m)
    omega = 2 * math.pi * freq_cycles_per_m
    estimate = np.mean(estimates, axis=0)
    bin_width = omega[1]
    lo, hi = 2 * math.pi / 50.0 + 3 * bin_width, 2 * math.pi / 1.0 - 3 * bin_width
    edges = np.geomspace(lo, hi, 7)
    for band_lo, band_hi in zip(edges[:-1], edges[1:], strict=True):
        in_band = (omega >= band_lo) & (omega < band_hi)
        assert in_band.sum() >= 9
        ratio = np.mean(estimate[in_band] / fra_psd(omega[in_band], 6))
        assert ratio == pytest.approx(1.0, abs=0.12), f"{band_lo:.3f}–{band_hi:.3f} rad/m"
    above = (omega > 2 * math.pi + 3 * bin_width) & (omega < 4 * math.pi)
    assert np.max(estimate[above] / fra_psd(omega[above], 6)) < 1e-3


# ---- synthesis: determinism, grids, inputs ---------------------------------------------------


def test_same_seed_same_profile_other_seed_differs():
    x = np.linspace(0.0, 300.0, 6001)
    first = synthesize_profile(x, 6, 11)
    assert np.array_equal(first, synthesize_profile(x, 6, 11))
    other = synthesize_profile(x, 6, 12)
    # Independent phases: the two profiles are (nearly) uncorrelated, far from equal.
    assert np.max(np.abs(first - other)) > np.std(first)
    assert abs(np.corrcoef(first, other)[0, 1]) < 0.5


def test_uniform_grid_kernel_matches_direct_cosines():
    """The phasor-rotation path on a 65 000-point grid equals the direct sum of cosines.

    The rotation is re-anchored every 1024 points, so rounding stays ~1e-15 of the amplitude;
    tolerance 1e-12 m (the profile is ~1e-3 m). The direct path is taken by perturbing the grid
    out of uniformity by 1e-3 of a step at two points and comparing there and elsewhere.
    """
    x = np.arange(0.0, 316.0 + 1e-9, 0.005) + 3.7
    uniform = synthesize_profile(x, 5, 3, (0.5, 80.0), 500)
    jittered = x.copy()
    jittered[[100, 50_000]] += 0.005e-3
    direct = synthesize_profile(jittered, 5, 3, (0.5, 80.0), 500)
    untouched = np.ones(x.size, dtype=bool)
    untouched[[100, 50_000]] = False
    assert np.max(np.abs(uniform[untouched] - direct[untouched])) < 1e-12
    # At the moved points the profile moved by slope × 5e-6 m: |η'| < 0.1, so < 1e-6 m.
    assert np.max(np.abs(uniform - direct)) < 1e-6
    # Arbitrary order and a single point go through the direct path too.
    reversed_profile = synthesize_profile(x[::-1][::7], 5, 3, (0.5, 80.0), 500)
    assert np.allclose(reversed_profile, uniform[::-1][::7], rtol=0.0, atol=1e-12)
    single = synthesize_profile([x[10]], 5, 3, (0.5, 80.0), 500)
    assert single[0] == pytest.approx(uniform[10], abs=1e-12)


def test_single_component_is_the_stated_cosine():
    """With one component the series is sqrt(2 S(Ω₀) ΔΩ) cos(Ω₀ x + φ₀), φ₀ from the seed."""
    band = (2.0, 10.0)
    omega0 = 0.5 * (2 * math.pi / 10.0 + 2 * math.pi / 2.0)
    spacing = 2 * math.pi / 2.0 - 2 * math.pi / 10.0
    phase = np.random.default_rng(5).uniform(0.0, 2 * math.pi, 1)[0]
    x = np.linspace(0.0, 40.0, 401)
    expected = math.sqrt(2 * fra_psd(omega0, 3) * spacing) * np.cos(omega0 * x + phase)
    assert np.allclose(synthesize_profile(x, 3, 5, band, 1), expected, rtol=0.0, atol=1e-15)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"track_class": 0}, r"track_class = 0"),
        ({"seed": -1}, r"seed = -1 is outside the allowed range"),
        ({"wavelength_band_m": (50.0, 1.0)}, r"wavelength_band_m = \(50.0, 1.0\) must satisfy"),
        ({"wavelength_band_m": (0.0, 1.0)}, r"0 < shortest < longest"),
        ({"wavelength_band_m": (1.0, np.inf)}, r"0 < shortest < longest < inf"),
        ({"wavelength_band_m": 5.0}, r"must be a pair"),
        ({"n_components": 0}, r"n_components = 0 is outside the allowed range"),
        ({"x_m": np.zeros((2, 2))}, r"x_m must be 1-D"),
        ({"x_m": [0.0, np.nan]}, r"x_m contains NaN"),
    ],
)
def test_synthesize_profile_refuses_bad_input(kwargs, message):
    arguments = {"x_m": np.linspace(0, 10, 11), "track_class": 6, "seed": 1, **kwargs}
    with pytest.raises(ValueError, match=message):
        synthesize_profile(**arguments)


# ---- measured profiles ----------------------------------------------------------------------


def write(tmp_path, text, name="profile.csv"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def test_load_profile_in_metres_with_comments(tmp_path):
    path = write(tmp_path, "# measured 2024\n\nx_m,eta_m\n0.0,0.001\n# gap\n1.5,-0.002\n3,0\n")
    x, eta = load_profile_csv(path)
    assert np.array_equal(x, [0.0, 1.5, 3.0])
    assert np.array_equal(eta, [0.001, -0.002, 0.0])


def test_load_profile_in_millimetres(tmp_path):
    path = write(tmp_path, "x_m, eta_mm\n10,1.5\n11,-2.0\n")
    x, eta = load_profile_csv(path)
    assert np.array_equal(x, [10.0, 11.0])
    assert np.allclose(eta, [1.5e-3, -2.0e-3], rtol=1e-15, atol=0.0)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("x,eta\n0,1\n1,2\n", r"line 1: the header must be 'x_m,eta_m' or 'x_m,eta_mm'"),
        ("# c\nx_m,eta_mm\n0,1\n1,2,3\n", r"line 4: expected 2 comma-separated values, found 3"),
        ("x_m,eta_mm\n0,1\n1,abc\n", r"line 3: the values are not two numbers"),
        ("x_m,eta_mm\n0,1\n1,nan\n", r"line 3: a value is not finite"),
        ("x_m,eta_mm\n0,1\n2,1\n# c\n2,3\n", r"line 5: x does not exceed the x of the line"),
        ("x_m,eta_mm\n0,1\n-1,1\n", r"line 3: x does not exceed"),
        ("# only comments\n", r"no header line"),
        ("x_m,eta_m\n0,1\n", r"1 data line\(s\); at least 2"),
    ],
)
def test_load_profile_refuses_malformed_file(tmp_path, text, message):
    """The message names the file, the line and the fault; it quotes nothing of the file."""
    path = write(tmp_path, text)
    with pytest.raises(ValueError, match=message) as excinfo:
        load_profile_csv(path)
    assert str(path) in str(excinfo.value)
    assert not any(line in str(excinfo.value) for line in text.splitlines()[1:] if line)


def test_example_profile_asset_loads_and_covers_default_rail():
    """model/data/example_profile.csv: −160…160 m from the monitored block at 1 m, η in mm, covering
    the paper-case rail (±158.4 m)."""
    x, eta = load_profile_csv(DATA_DIR / "example_profile.csv")
    assert x[0] == -160.0 and x[-1] == 160.0 and x.size == 321
    # Class 5 over 4–50 m has RMS ≈ 5 mm; the file holds a synthesized sample of it.
    assert 1e-3 < np.std(eta) < 2e-2


# ---- dispatch -------------------------------------------------------------------------------


def test_profile_for_disabled_is_zero():
    x = np.linspace(0.0, 100.0, 201)
    eta = profile_for(Irregularity(enabled=False), x)
    assert eta.shape == x.shape and not eta.any()


def test_profile_for_synthetic_uses_all_settings():
    irregularity = Irregularity(
        track_class=4, seed=99, wavelength_min=2.0, wavelength_max=30.0, n_components=300
    )
    x = np.arange(0.0, 200.0, 0.01)
    expected = synthesize_profile(x, 4, 99, (2.0, 30.0), 300)
    assert np.array_equal(profile_for(irregularity, x), expected)


def test_profile_for_measured_interpolates_linearly(tmp_path):
    path = write(tmp_path, "x_m,eta_mm\n0,0\n2,4\n4,-4\n")
    irregularity = Irregularity(profile_csv=str(path))
    eta = profile_for(irregularity, [0.0, 1.0, 2.0, 3.0, 4.0])
    assert np.allclose(eta, [0.0, 2e-3, 4e-3, 0.0, -4e-3], rtol=0.0, atol=1e-15)


def test_profile_for_measured_refuses_points_outside_coverage(tmp_path):
    path = write(tmp_path, "x_m,eta_mm\n0,0\n2,4\n4,-4\n")
    irregularity = Irregularity(profile_csv=str(path))
    with pytest.raises(ValueError, match=r"x_m spans \[-1, 3\] m .* covers only \[0, 4\] m"):
        profile_for(irregularity, [-1.0, 3.0])
    with pytest.raises(ValueError, match=r"covers only \[0, 4\] m"):
        profile_for(irregularity, np.linspace(0.0, 4.5, 10))
