"""Ground-surface vibration levels (model.soil.ground_vibration): the IEC 61260-1 one-third-octave
bands, a sine of known amplitude in its band at its level, Parseval across the bands, the
energetic sum, the reporting floor, and the results of a synthetic surface transfer."""

import numpy as np
import pytest

from model.params import Numerics
from model.soil import ground_vibration as gv
from model.soil.response import padded_record_grid
from model.spectra import fourier_transform

NOMINAL = [1, 1.25, 1.6, 2, 2.5, 3.15, 4, 5, 6.3, 8, 10, 12.5, 16, 20, 25, 31.5, 40, 50, 63, 80]


def test_the_bands_are_iec_61260_base_ten_thirds_from_1_to_80_hz():
    """20 bands; exact midbands 10^{x/10} (x = −30 … −11 with 1 kHz at x = 0), edges
    f_m 10^{∓1/20}, contiguous, f_m the geometric mean of its edges, nominal labels per IEC."""
    bands = gv.third_octave_bands()
    assert bands.nominal_hz.tolist() == NOMINAL
    x = np.arange(-30, -10)
    assert np.allclose(bands.centre_hz, 1000.0 * 10.0 ** (x / 10.0), rtol=1e-14)
    assert np.allclose(bands.upper_hz[:-1], bands.lower_hz[1:], rtol=1e-14)
    assert np.allclose(np.sqrt(bands.lower_hz * bands.upper_hz), bands.centre_hz, rtol=1e-14)
    assert np.allclose(bands.upper_hz / bands.lower_hz, 10**0.1, rtol=1e-14)
    assert np.allclose(bands.nominal_hz / bands.centre_hz, 1, atol=0.03)  # IEC's rounding


def _record(signal_of_t, duration_s=8.0, dt_s=1e-3):
    """(f, V(f), T) of a velocity record sampled over exactly ``duration_s``."""
    t = np.arange(round(duration_s / dt_s)) * dt_s
    f, spectrum = fourier_transform(signal_of_t(t), dt_s)
    return f, spectrum, duration_s


@pytest.mark.parametrize("band", [0, 5, 10, 19])
def test_a_sine_lands_in_its_band_at_its_level(band):
    """v = A sin(2π f t) with A = 1 mm/s at a band's midband frequency (rounded onto the 1/8 Hz
    bin grid, well inside the band) over a whole number of periods: L = 10 log₁₀(A²/2 / v_ref²)
    = 116.99 dB in that band to 1e-9 dB, every other band at the floor, and the overall level
    the same."""
    bands = gv.third_octave_bands()
    f0 = round(bands.centre_hz[band] * 8) / 8
    amplitude = 1e-3
    f, spectrum, duration = _record(lambda t: amplitude * np.sin(2 * np.pi * f0 * t))
    levels = gv.velocity_levels(f, spectrum, duration, bands)
    expected = 10 * np.log10(amplitude**2 / 2 / gv.REFERENCE_VELOCITY_M_PER_S**2)
    assert expected == pytest.approx(116.9897, abs=1e-4)
    assert levels[band] == pytest.approx(expected, abs=1e-9)
    assert np.all(np.delete(levels, band) < expected - 150.0)
    assert gv.overall_level(levels) == pytest.approx(expected, abs=1e-9)


def test_band_energies_add_up_to_the_record_s_energy_parseval():
    """A random record band-limited to 0.9–89 Hz (inside the 1–80 Hz bands' edges): the band
    energies add up to ∫ v² dt to 1e-12, with bins cut by band edges shared in proportion."""
    rng = np.random.default_rng(3)
    dt, n = 1e-3, 6000
    f = np.fft.rfftfreq(n, dt)
    coefficients = (rng.normal(size=f.size) + 1j * rng.normal(size=f.size)) * (
        (f > 0.9) & (f < 89.0)
    )
    v = np.fft.irfft(coefficients, n)
    freq, spectrum = fourier_transform(v, dt)
    energies = gv.band_energies(freq, spectrum, gv.third_octave_bands())
    assert energies.sum() == pytest.approx(np.sum(v**2) * dt, rel=1e-12)
    # a 2-D spectrum (several receivers) gives each column its own energies
    both = gv.band_energies(
        freq, np.stack([spectrum, 2 * spectrum], axis=1), gv.third_octave_bands()
    )
    assert np.allclose(both[:, 1], 4 * both[:, 0], rtol=1e-12)


def test_overall_level_is_the_energetic_sum():
    levels = np.array([[70.0, 50.0], [70.0, -60.0], [60.0, -60.0]])
    overall = gv.overall_level(levels)
    assert overall[0] == pytest.approx(10 * np.log10(2e7 + 1e6), abs=1e-12)
    assert overall[1] == pytest.approx(10 * np.log10(1e5 + 2e-6), abs=1e-12)


def test_a_silent_record_reads_the_floor():
    f, spectrum, duration = _record(np.zeros_like)
    levels = gv.velocity_levels(f, spectrum, duration, gv.third_octave_bands())
    assert np.all(levels == gv.LEVEL_FLOOR_DB)


def test_ground_response_of_a_synthetic_transfer():
    """A constant transfer c (m per N/m) times a load record q(t): the surface displacement is
    c q(t), so the peak is c max q, the velocity c q′(t), and the distances come through."""
    numerics = Numerics(soil_max_frequency=100.0, zero_pad_factor=4)
    dt = 1e-3
    t = np.arange(4000) * dt
    load = 1e4 * np.exp(-(((t - 2.0) / 0.3) ** 2))  # N/m, smooth pulse
    grid = padded_record_grid(load, dt, numerics, s_wave_speed=35.0)
    distance = np.array([0.0, 10.0])
    transfer = np.full((grid.f_hz.size, 2), 1e-8 + 0j)
    transfer[:, 1] *= 0.5
    ground = gv.ground_response(grid, distance, transfer, free_surface_effect=0.1)
    assert ground.distance_m.tolist() == [0.0, 10.0]
    assert ground.peak_disp_m == pytest.approx([1e-4, 5e-5], rel=1e-6)
    slope = np.max(np.abs(np.gradient(load, dt)))
    assert ground.peak_velocity_m_per_s == pytest.approx([1e-8 * slope, 5e-9 * slope], rel=1e-3)
    assert ground.velocity_level_dB.shape == (20, 2)
    top = ground.velocity_level_dB[:, 0] > gv.LEVEL_FLOOR_DB + 10
    assert np.allclose(
        ground.velocity_level_dB[top, 0] - ground.velocity_level_dB[top, 1],
        20 * np.log10(2),
        atol=1e-9,
    )
    assert ground.averaging_s == pytest.approx(4.0) and ground.free_surface_effect == 0.1
    summary = gv.ground_summary(ground)
    assert summary["ground_trough_axis_m"] == pytest.approx(1e-4, rel=1e-6)
    assert summary["ground_trough_half_width_m"] == pytest.approx(10.0)


def test_bands_above_the_soil_model_s_frequency_limit_are_left_out():
    numerics = Numerics(soil_max_frequency=30.0, zero_pad_factor=2)
    dt = 1e-3
    grid = padded_record_grid(np.ones(2000), dt, numerics, s_wave_speed=35.0)
    ground = gv.ground_response(grid, np.array([0.0]), np.ones((grid.f_hz.size, 1)), 0.0)
    assert ground.band_nominal_hz[-1] == 25.0
    assert ground.velocity_level_dB.shape == (ground.band_nominal_hz.size, 1)
