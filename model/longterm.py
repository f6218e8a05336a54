"""Permanent settlement under the tunnel from each passage's stresses (docs/model.md §10).

The chain, per depth d below the ring–soil interface directly under the invert:

1. **Dynamic stresses.** The stress transfer functions of the tunnel–soil model (stress per unit
   downward line load at the invert, six components of :class:`StressField`) times the spectrum
   of the line load, transformed back to time on the soil stage's grid
   (:func:`model.soil.response.padded_record_grid`: same zero padding, band limit and output step),
   the kernel sampled and interpolated alike (:func:`model.soil.response.record_grid_transfer`).
   In 2D the axial stress is the plane-strain one, σ_xx = λ*(ε_rr + ε_θθ) =
   λ*/(2(λ* + μ*)) (σ_rr + σ_θθ), and σ_rx = σ_θx = 0.
2. **Zero-frequency bin.** Unlike the 2D static displacement, the 2D static *stresses* are
   finite: the ln ω growth of the n = 1 harmonic is a rigid translation, which carries no strain,
   so σ(f) = σ(0) + O((ωr/c₂)² ln ω). The DC bin stands for the band [−Δf/2, Δf/2]; with
   σ(−f) = conj σ(f) its average is Re of the average over [0, Δf/2], which to that order is
   Re σ(Δf/(2e)), the same evaluation point as the displacement's DC bin
   (:func:`model.soil.response.dc_band_receptance`), so both stages follow one rule.
3. **Deviator.** q(t, d) = √(3 J₂) of the dynamic stress tensor, J₂ = ½ s:s with s its
   deviatoric part; in a triaxial state (σ₂ = σ₃) this is |σ₁ − σ₃|. q_d(d) = max over t.
4. **Static state and strength.** Depth below ground z = H_t + a + d (H_t the axis depth, a the
   ring radius, where the soil model's soil begins); σ_v = ρ g z, pore pressure
   u = ρ_w g max(0, z − z_w), σ′_v0 = σ_v − u (ρ the soil density, taken as saturated, and the
   same above the water table); K0 = 1 − sin φ′, static deviator q_s = σ′_v0 (1 − K0);
   c_u = ratio · σ′_v0 or given; σ_s = q_f = 2 c_u.
5. **Cycles.** N = trains per day × 365 × years × cycles per train; cycles per train is the number
   of bogies, or the rainflow count (ASTM E1049) of q(t, d) at each depth with each cycle
   weighted by its range over q_d, Σ count · range / q_d (one full cycle from 0 to q_d counts 1).
6. **Strain law** (ε_p in %, stresses enter as ratios): Li & Selig (1996)
   ε_p = a (q_d/σ_s)^m N^b; Chai & Miura (2002) ε_p = a (q_d/q_f)^m (1 + q_s/q_f)^n N^b;
   Monismith (1975) ε_p = A N^b wherever the soil is loaded (q_d > 0).
7. **Settlement** S = Σ ε_p/100 · Δz over the depth grid (trapezoidal cell thicknesses, so the
   sum is the trapezoidal integral from the invert to the deepest depth), and the depth within
   which 90 % of S accumulates.
"""

from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import rainflow
from scipy.integrate import cumulative_trapezoid

from model.soil.moving_load_2p5d import StressField, invert_response_2p5d
from model.soil.response import (
    SoilResponse,
    displacement_response,
    output_depths,
    padded_record_grid,
    record_grid_transfer,
)
from model.soil.section_2d import soil_field

GRAVITY = 9.81  # m/s²
WATER_DENSITY = 1000.0  # kg/m³
DAYS_PER_YEAR = 365.0
SETTLEMENT_FRACTION = 0.9  # the reported depth holds this fraction of the settlement
N_YEARS = 61  # points of the settlement–time curve, log-spaced from one day of traffic
LAW_NAMES = {
    "li_selig": "Li & Selig (1996)",
    "chai_miura": "Chai & Miura (2002)",
    "monismith": "Monismith (1975)",
}
TRIAXIAL_COLUMNS = ("n_cycles", "strain_percent", "deviator_kPa", "strength_kPa")
COMMENT = "#"
N_LAW_PARAMETERS = 3  # a, b, m


# ---- dynamic stresses under the invert -------------------------------------------------------
STRESS_COMPONENTS = (
    "sigma_rr",
    "sigma_thetatheta",
    "sigma_xx",
    "sigma_rtheta",
    "sigma_rx",
    "sigma_thetax",
)
"""Field names of a stress field, in the argument order of :func:`deviator_stress`; read by name
so that any container with these attributes (e.g. the 2.5D model's) can be used."""


def stress_components(field) -> list[np.ndarray]:
    """The six components of a stress field, in the order of ``STRESS_COMPONENTS``."""
    return [getattr(field, name) for name in STRESS_COMPONENTS]


def plane_strain_stress_transfer(freq_hz, depth_m, tunnel, soil, n_harmonics: int) -> StressField:
    """Stresses under the invert per unit downward line load, 2D plane-strain model.

    σ_rr, σ_θθ, σ_rθ from :func:`model.soil.section_2d.soil_field` at θ = 0; the axial stress of
    plane strain σ_xx = λ*/(2(λ* + μ*)) (σ_rr + σ_θθ); σ_rx = σ_θx = 0.

    Parameters
    ----------
    freq_hz : array_like
        Frequencies (Hz), > 0.
    depth_m : array_like
        Depths d ≥ 0 below the ring–soil interface (m).
    tunnel, soil : model.params.Tunnel, model.params.Soil
        Lining and soil.
    n_harmonics : int
        Highest circumferential harmonic N ≥ 0.

    Returns
    -------
    StressField
        Complex (n_freq, n_depth), Pa per N/m.
    """
    return _plane_strain_invert_field(freq_hz, depth_m, tunnel, soil, n_harmonics)[1]


def _plane_strain_invert_field(freq_hz, depth_m, tunnel, soil, n_harmonics: int):
    """(receptance, StressField) under the invert from one 2D kernel evaluation."""
    depth = np.atleast_1d(np.asarray(depth_m, dtype=float))
    if np.any(depth < 0.0):
        raise ValueError(
            f"depth_m = {float(depth[depth < 0.0][0])!r} is inside the lining: depths are "
            "measured from the ring–soil interface and must be ≥ 0 m"
        )
    field = soil_field(freq_hz, tunnel.ring_radius + depth, 0.0, tunnel, soil, n_harmonics)
    shear = soil.shear_modulus * (1.0 + 1j * soil.shear_loss_factor)
    lame = soil.bulk_modulus * (1.0 + 1j * soil.bulk_loss_factor) - 2.0 * shear / 3.0
    axial = lame / (2.0 * (lame + shear)) * (field.sigma_rr + field.sigma_thetatheta)
    zero = np.zeros_like(field.sigma_rr)
    return field.u_r, StressField(
        sigma_rr=field.sigma_rr,
        sigma_thetatheta=field.sigma_thetatheta,
        sigma_xx=axial,
        sigma_rtheta=field.sigma_rtheta,
        sigma_rx=zero,
        sigma_thetax=zero.copy(),
    )


def stress_transfer(freq_hz, depth_m, scenario) -> StressField:
    """Stresses under the invert per unit line load, from the scenario's tunnel–soil model.

    Parameters
    ----------
    freq_hz : array_like
        Frequencies (Hz), > 0.
    depth_m : array_like
        Depths d ≥ 0 below the ring–soil interface (m).
    scenario : model.params.Scenario
        Uses tunnel, soil, numerics.n_harmonics and (2.5D model) train.speed.

    Returns
    -------
    StressField
        Complex (n_freq, n_depth), Pa per N/m.
    """
    return invert_transfer(freq_hz, depth_m, scenario)[1]


def invert_transfer(freq_hz, depth_m, scenario) -> tuple[np.ndarray, StressField]:
    """Receptance and stresses under the invert per unit line load, one kernel evaluation.

    The receptance is :func:`model.soil.response.section_receptance`'s and the stresses
    :func:`stress_transfer`'s (the same numbers), from a single evaluation of the scenario's
    tunnel–soil kernel (2D, or 2.5D at ξ = ω/v, docs/model.md §9).

    Parameters
    ----------
    freq_hz : array_like
        Frequencies (Hz), > 0.
    depth_m : array_like
        Depths d ≥ 0 below the ring–soil interface (m).
    scenario : model.params.Scenario
        Uses tunnel, soil, numerics.n_harmonics and (2.5D model) train.speed.

    Returns
    -------
    (ndarray, StressField)
        Complex (n_freq, n_depth) receptance (m per N/m) and stresses (Pa per N/m).
    """
    tunnel, soil, n_harmonics = scenario.tunnel, scenario.soil, scenario.numerics.n_harmonics
    if tunnel.model == "2.5d":  # the moving train: the kernel at ξ = ω/v (docs/model.md §9)
        freq = np.atleast_1d(np.asarray(freq_hz, dtype=float))
        wavenumber = 2.0 * np.pi * freq / scenario.train.speed
        return invert_response_2p5d(freq, wavenumber, depth_m, tunnel, soil, n_harmonics)
    return _plane_strain_invert_field(freq_hz, depth_m, tunnel, soil, n_harmonics)


def _grid_transfer(f_hz, depth, scenario) -> tuple[np.ndarray, StressField]:
    """:func:`invert_transfer` on a record grid, row 0 the DC band value (module docstring,
    step 2), by :func:`model.soil.response.record_grid_transfer` like the displacements."""

    def evaluate(freq):
        receptance, stresses = invert_transfer(freq, depth, scenario)
        return receptance, *stress_components(stresses)

    receptance, *components = record_grid_transfer(
        f_hz, depth, evaluate, scenario.tunnel, scenario.soil, scenario.numerics
    )
    return receptance, StressField(**dict(zip(STRESS_COMPONENTS, components, strict=True)))


def deviator_stress(
    sigma_rr, sigma_thetatheta, sigma_xx, sigma_rtheta, sigma_rx, sigma_thetax
) -> np.ndarray:
    """Deviator q = √(3 J₂) of a stress tensor (the von Mises equivalent stress).

    J₂ = ⅙[(σ_rr − σ_θθ)² + (σ_θθ − σ_xx)² + (σ_xx − σ_rr)²] + σ_rθ² + σ_rx² + σ_θx²; for a
    triaxial state (two equal principal stresses) q = |σ₁ − σ₃|.

    Parameters
    ----------
    sigma_rr, sigma_thetatheta, sigma_xx, sigma_rtheta, sigma_rx, sigma_thetax : array_like
        Real stress components (any one unit, e.g. Pa), broadcast together.

    Returns
    -------
    ndarray
        q in the unit of the stresses, ≥ 0.
    """
    rr, tt, xx, rt, rx, tx = np.broadcast_arrays(
        *(
            np.asarray(c, dtype=float)
            for c in (sigma_rr, sigma_thetatheta, sigma_xx, sigma_rtheta, sigma_rx, sigma_thetax)
        )
    )
    j2 = ((rr - tt) ** 2 + (tt - xx) ** 2 + (xx - rr) ** 2) / 6.0 + rt**2 + rx**2 + tx**2
    return np.sqrt(3.0 * j2)


@dataclass(frozen=True)
class StressResponse:
    """The dynamic deviator under the invert during one passage (from the soil stage)."""

    depth_m: np.ndarray
    """(nd,) depths below the ring–soil interface (m), as in the soil stage."""
    t_s: np.ndarray
    """(nt,) time (s), the soil stage's output grid."""
    deviator_history_Pa: np.ndarray
    """(nd, nt) deviator q(t, d) = √(3 J₂) of the dynamic stress tensor (Pa)."""
    deviator_Pa: np.ndarray
    """(nd,) q_d(d), the maximum of q over the passage (Pa)."""
    rainflow_cycles: np.ndarray
    """(nd,) range-weighted rainflow count of q(t, d) per passage (cycles)."""


def stress_response(line_load_N_per_m, dt_s: float, depth_m, scenario) -> StressResponse:
    """Dynamic deviator histories under the invert for a line-load history.

    Parameters
    ----------
    line_load_N_per_m : array_like
        Downward line load on the invert q(t) (N/m), sampled from t = 0 at ``dt_s``.
    dt_s : float
        Sampling interval (s), > 0.
    depth_m : array_like
        Depths d ≥ 0 below the ring–soil interface (m).
    scenario : model.params.Scenario
        Uses tunnel, soil and numerics (n_harmonics, soil_max_frequency, zero_pad_factor,
        max_depth, kernel_samples_per_cycle).

    Returns
    -------
    StressResponse
    """
    depth = np.atleast_1d(np.asarray(depth_m, dtype=float))
    grid = padded_record_grid(
        line_load_N_per_m, dt_s, scenario.numerics, scenario.soil.s_wave_speed
    )
    return _deviator_response(grid, depth, _grid_transfer(grid.f_hz, depth, scenario)[1])


@dataclass(frozen=True)
class SectionTransfer:
    """The tunnel–soil kernel at a padded record's frequencies and the output depths.

    It depends on the record's length and step, the tunnel, the soil and the numerics, not on
    the load itself: runs that differ only in the load (irregularity seed, vehicle, track)
    share it, which is what :func:`model.pipeline.run` caches.
    """

    f_hz: np.ndarray
    """(nf,) frequencies of the padded record's grid (Hz); row 0 of the transfer functions
    holds the DC band value."""
    depth_m: np.ndarray
    """(nd,) output depths below the ring–soil interface (m)."""
    receptance: np.ndarray
    """(nf, nd) complex displacement per unit line load (m per N/m)."""
    stresses: StressField
    """(nf, nd) complex stresses per unit line load (Pa per N/m)."""


def section_transfer(line_load_N_per_m, dt_s: float, scenario) -> SectionTransfer:
    """Receptance and stresses under the invert on the grid of a load record.

    Parameters
    ----------
    line_load_N_per_m : array_like
        Load record q(t) (N/m); only its length and step set the grid.
    dt_s : float
        Sampling interval (s), > 0.
    scenario : model.params.Scenario
        As :func:`section_response`.

    Returns
    -------
    SectionTransfer
    """
    numerics = scenario.numerics
    grid = padded_record_grid(line_load_N_per_m, dt_s, numerics, scenario.soil.s_wave_speed)
    depth = output_depths(numerics)
    receptance, stresses = _grid_transfer(grid.f_hz, depth, scenario)
    return SectionTransfer(grid.f_hz, depth, receptance, stresses)


def section_response(
    line_load_N_per_m, dt_s: float, scenario, transfer: SectionTransfer | None = None
) -> tuple[SoilResponse, StressResponse]:
    """Displacements and stresses under the invert for a line-load history, one kernel pass.

    The same results as :func:`model.soil.response.soil_response` and :func:`stress_response` at
    the depths :func:`model.soil.response.output_depths`, with the tunnel–soil kernel evaluated
    once per frequency for both.

    Parameters
    ----------
    line_load_N_per_m : array_like
        Downward line load on the invert q(t) (N/m), sampled from t = 0 at ``dt_s``.
    dt_s : float
        Sampling interval (s), > 0.
    scenario : model.params.Scenario
        Uses tunnel, soil, train.speed (2.5D model) and numerics (n_harmonics,
        soil_max_frequency, zero_pad_factor, psd_segment, max_depth, n_depths,
        kernel_samples_per_cycle).
    transfer : SectionTransfer, optional
        :func:`section_transfer` of a record of the same length and step and the same
        scenario, to reuse; computed when not given.

    Returns
    -------
    (SoilResponse, StressResponse)

    Raises
    ------
    ValueError
        ``transfer`` was made on another frequency grid or other depths.
    """
    numerics = scenario.numerics
    grid = padded_record_grid(line_load_N_per_m, dt_s, numerics, scenario.soil.s_wave_speed)
    depth = output_depths(numerics)
    if transfer is None:
        receptance, stresses = _grid_transfer(grid.f_hz, depth, scenario)
    elif np.array_equal(transfer.f_hz, grid.f_hz) and np.array_equal(transfer.depth_m, depth):
        receptance, stresses = transfer.receptance, transfer.stresses
    else:
        raise ValueError(
            "transfer was computed on another frequency grid or other depths than this record's"
        )
    soil = displacement_response(grid, depth, receptance, numerics)
    return soil, _deviator_response(grid, depth, stresses)


def _deviator_response(grid, depth, stresses: StressField) -> StressResponse:
    """Deviator histories, peaks and rainflow counts from stress transfer functions on a grid.

    Components that vanish identically (σ_rθ, σ_θx at θ = 0; σ_rx in 2D) are not transformed;
    the others go through one batched inverse FFT.
    """
    components = stress_components(stresses)
    nonzero = [k for k, component in enumerate(components) if np.any(component)]
    spectra = np.stack([components[k] for k in nonzero]) * grid.load_spectrum[:, None]
    n_depth = depth.size
    transformed = grid.time_histories(spectra.transpose(0, 2, 1).reshape(-1, grid.f_hz.size))
    histories = [np.zeros((n_depth, grid.n_out))] * len(components)
    for row, k in enumerate(nonzero):
        histories[k] = transformed[row * n_depth : (row + 1) * n_depth]
    deviator = deviator_stress(*histories)
    return StressResponse(
        depth_m=depth,
        t_s=np.arange(grid.n_out) * grid.dt_out,
        deviator_history_Pa=deviator,
        deviator_Pa=deviator.max(axis=1),
        rainflow_cycles=np.array([range_weighted_cycles(row) for row in deviator]),
    )


def range_weighted_cycles(history) -> float:
    """Rainflow count of a load history, each cycle weighted by its range over the peak.

    Σ count_i · range_i / max(history), with count 1 for full and ½ for half cycles (ASTM
    E1049, the ``rainflow`` package): k pulses from zero to the same peak count k, small
    ripples count in proportion to their size. 0 for a history that never exceeds 0.
    The history is taken to start and end at zero (no train before the passage, none after):
    a record that begins or ends with the train still loading the soil (the 2.5D model's
    long-range field) would otherwise count one passage as less than one cycle.

    Parameters
    ----------
    history : array_like
        1-D load history (e.g. the deviator q(t), Pa), ≥ 0.

    Returns
    -------
    float
        Equivalent number of cycles.
    """
    series = np.concatenate([[0.0], np.asarray(history, dtype=float), [0.0]])
    peak = float(series.max())
    if peak <= 0.0:
        return 0.0
    slope = np.sign(np.diff(series))
    nonflat = np.flatnonzero(slope)
    turning = nonflat[1:][slope[nonflat[1:]] != slope[nonflat[:-1]]]
    points = series[np.concatenate([[0], turning, [series.size - 1]])]
    return sum(rng * count for rng, _, count, _, _ in rainflow.extract_cycles(points)) / peak


# ---- static state, strength and strain laws --------------------------------------------------
@dataclass(frozen=True)
class StaticState:
    """Geostatic stresses and strength per depth below the invert (Pa)."""

    depth_m: np.ndarray
    """(nd,) depths below the ring–soil interface (m)."""
    depth_below_ground_m: np.ndarray
    """(nd,) z = H_t + a + d (m)."""
    vertical_effective_stress_Pa: np.ndarray
    """(nd,) σ′_v0."""
    static_deviator_Pa: np.ndarray
    """(nd,) q_s = σ′_v0 (1 − K0)."""
    undrained_strength_Pa: np.ndarray
    """(nd,) c_u."""
    strength_Pa: np.ndarray
    """(nd,) σ_s = q_f = 2 c_u."""


def static_state(depth_m, longterm, tunnel, soil) -> StaticState:
    """Static stress state and undrained strength below the invert (module docstring, step 4).

    Parameters
    ----------
    depth_m : array_like
        Depths d ≥ 0 below the ring–soil interface (m).
    longterm : model.params.LongTerm
        Uses axis_depth, water_table_depth, friction_angle (K0), cu_ratio, undrained_strength.
    tunnel : model.params.Tunnel
        Uses ring_radius.
    soil : model.params.Soil
        Uses density (kg/m³), taken as the saturated density.

    Returns
    -------
    StaticState

    Raises
    ------
    ValueError
        If σ′_v0 is not positive somewhere (a soil lighter than water below the water table).
    """
    depth = np.atleast_1d(np.asarray(depth_m, dtype=float))
    below_ground = longterm.axis_depth + tunnel.ring_radius + depth
    total = soil.density * GRAVITY * below_ground
    pore = WATER_DENSITY * GRAVITY * np.maximum(0.0, below_ground - longterm.water_table_depth)
    effective = total - pore
    if np.any(effective <= 0.0):
        raise ValueError(
            f"soil.density = {soil.density:g} kg/m³ is not above the density of water "
            f"({WATER_DENSITY:g} kg/m³): the vertical effective stress below the water table "
            "would not be positive"
        )
    if longterm.undrained_strength is None:
        undrained = longterm.cu_ratio * effective
    else:
        undrained = np.full_like(effective, longterm.undrained_strength)
    return StaticState(
        depth_m=depth,
        depth_below_ground_m=below_ground,
        vertical_effective_stress_Pa=effective,
        static_deviator_Pa=effective * (1.0 - longterm.earth_pressure_coefficient),
        undrained_strength_Pa=undrained,
        strength_Pa=2.0 * undrained,
    )


def check_longterm_inputs(scenario) -> None:
    """Refuse a static state that cannot exist, before any computation (ValueError).

    The tunnel must lie below the ground surface (axis depth ≥ outer radius of the lining) and
    σ′_v0 must be positive from the invert to the deepest depth.
    """
    tunnel, longterm = scenario.tunnel, scenario.longterm
    outer_radius = tunnel.inner_radius + tunnel.thickness
    if longterm.axis_depth < outer_radius:
        raise ValueError(
            f"longterm.axis_depth = {longterm.axis_depth:g} m is less than the lining's outer "
            f"radius {outer_radius:g} m: the tunnel would stand out of the ground; allowed "
            f"range [{outer_radius:g}, 200] m"
        )
    static_state([0.0, scenario.numerics.max_depth], longterm, tunnel, scenario.soil)


def permanent_strain_percent(
    law: str,
    a: float,
    b: float,
    m: float,
    n: float,
    deviator,
    strength,
    static_deviator,
    n_cycles,
) -> np.ndarray:
    """Accumulated permanent strain ε_p (%) of a cyclic strain-accumulation law.

    Li & Selig: ε_p = a (q_d/σ_s)^m N^b; Chai & Miura: ε_p = a (q_d/q_f)^m (1 + q_s/q_f)^n N^b
    with q_f = σ_s; Monismith: ε_p = a N^b where q_d > 0 and 0 where the soil is not loaded.

    Parameters
    ----------
    law : {"li_selig", "chai_miura", "monismith"}
        Strain law.
    a : float
        Coefficient (%), > 0.
    b, m, n : float
        Exponents of N, of the stress ratio and (Chai & Miura) of 1 + q_s/q_f, ≥ 0.
    deviator : array_like
        Dynamic deviator q_d, ≥ 0 (any stress unit, the same for all three stresses).
    strength : array_like
        Static strength σ_s = q_f, > 0.
    static_deviator : array_like
        Static deviator q_s, ≥ 0 (used by Chai & Miura).
    n_cycles : array_like
        Number of load cycles N, ≥ 0; broadcast against the stresses.

    Returns
    -------
    ndarray
        ε_p in %.
    """
    if law not in LAW_NAMES:
        raise ValueError(f"law = {law!r} is not one of {', '.join(LAW_NAMES)}")
    for name, value, low in (("a", a, 0.0), ("b", b, None), ("m", m, None), ("n", n, None)):
        if not (math.isfinite(value) and (value > low if low is not None else value >= 0.0)):
            allowed = "(0, inf)" if low is not None else "[0, inf)"
            raise ValueError(f"{name} = {value!r} is outside the allowed range {allowed}")
    q_d, q_f, q_s, cycles = np.broadcast_arrays(
        *(np.asarray(x, dtype=float) for x in (deviator, strength, static_deviator, n_cycles))
    )
    if np.any(q_f <= 0.0):
        raise ValueError(f"strength = {float(q_f[q_f <= 0.0][0])!r} must be > 0")
    if np.any(q_d < 0.0) or np.any(cycles < 0.0) or np.any(q_s < 0.0):
        raise ValueError("deviator, static_deviator and n_cycles must be ≥ 0")
    growth = a * cycles**b
    if law == "monismith":
        return np.where(q_d > 0.0, growth, 0.0)
    strain = growth * (q_d / q_f) ** m
    if law == "chai_miura":
        strain = strain * (1.0 + q_s / q_f) ** n
    return strain


def trapezoid_thickness(depth_m) -> np.ndarray:
    """Cell thickness Δz_i (m) of each depth point: Σ f_i Δz_i is the trapezoidal ∫ f dz.

    Parameters
    ----------
    depth_m : array_like
        Increasing depths (m), ≥ 2 points.

    Returns
    -------
    ndarray
        (nd,) thicknesses (m): half the neighbouring spacings.
    """
    depth = np.asarray(depth_m, dtype=float)
    if depth.ndim != 1 or depth.size < 2 or np.any(np.diff(depth) <= 0.0):
        raise ValueError("depth_m must be a 1-D increasing array of at least 2 depths")
    spacing = np.diff(depth)
    return 0.5 * (np.concatenate([spacing, [0.0]]) + np.concatenate([[0.0], spacing]))


def layered_settlement_m(strain_percent, thickness_m) -> np.ndarray:
    """Settlement S = Σ ε_p/100 · Δz (m) over layers (the last axis).

    Parameters
    ----------
    strain_percent : array_like
        ε_p (%) per layer, (..., n_layers).
    thickness_m : array_like
        Layer thicknesses Δz (m), (n_layers,), ≥ 0.

    Returns
    -------
    ndarray or float
        S (m), shape (...).
    """
    thickness = np.asarray(thickness_m, dtype=float)
    if np.any(thickness < 0.0):
        raise ValueError("thickness_m must be ≥ 0")
    return np.asarray(strain_percent, dtype=float) / 100.0 @ thickness


def depth_holding_fraction(depth_m, strain_percent, fraction: float = SETTLEMENT_FRACTION):
    """Depth below the invert within which ``fraction`` of the settlement accumulates (m).

    The settlement down to depth d is the trapezoidal ∫₀^d ε_p/100 dz, linear between grid
    points is interpolated; NaN when the settlement is zero.

    Parameters
    ----------
    depth_m : array_like
        Increasing depths (m).
    strain_percent : array_like
        ε_p (%) at those depths.
    fraction : float
        Fraction of the total settlement, in (0, 1].

    Returns
    -------
    float
        Depth (m).
    """
    cumulative = cumulative_trapezoid(np.asarray(strain_percent, float) / 100.0, depth_m, initial=0)
    if cumulative[-1] <= 0.0:
        return math.nan
    return float(np.interp(fraction * cumulative[-1], cumulative, depth_m))


@dataclass(frozen=True)
class LongTermResult:
    """Long-term stage result: permanent settlement at the invert over years of service."""

    years: np.ndarray
    """(ny,) service time (years), log-spaced from one day of traffic to longterm.years."""
    settlement_m: np.ndarray
    """(ny,) settlement at the invert S (m)."""
    depth_m: np.ndarray
    """(nd,) depths below the ring–soil interface (m)."""
    deviator_Pa: np.ndarray
    """(nd,) dynamic deviator q_d (Pa)."""
    strength_Pa: np.ndarray
    """(nd,) static strength σ_s = 2 c_u (Pa)."""
    static_deviator_Pa: np.ndarray
    """(nd,) static deviator q_s (Pa)."""
    vertical_effective_stress_Pa: np.ndarray
    """(nd,) σ′_v0 (Pa)."""
    strain_percent: np.ndarray
    """(nd,) permanent strain ε_p after longterm.years (%)."""
    cycles_per_train: np.ndarray
    """(nd,) load cycles per passage."""
    n_cycles: np.ndarray
    """(nd,) N after longterm.years."""
    depth90_m: float
    """Depth below the invert holding 90 % of the final settlement (m); NaN if S = 0."""
    law: str
    """Strain law key."""
    law_parameters: dict[str, float]
    """Parameters in force (a in %, exponents), with ``n`` for Chai & Miura."""
    statement: str
    """Which law, parameters and traffic produced the result, in words."""
    warnings: tuple[str, ...]

    @property
    def stress_ratio(self) -> np.ndarray:
        """(nd,) q_d/σ_s."""
        return self.deviator_Pa / self.strength_Pa


def n_bogies(train) -> int:
    """Bogies in the train (two axles each)."""
    return train.n_wheels // 2


def long_term_settlement(stress: StressResponse, scenario) -> LongTermResult:
    """Static state, cycles, strain law and settlement over service time (module docstring).

    Parameters
    ----------
    stress : StressResponse
        Deviator under the invert per passage (computed with the soil stage, Results.stress).
    scenario : model.params.Scenario
        Uses longterm, tunnel.ring_radius, soil.density and train (number of bogies).

    Returns
    -------
    LongTermResult
    """
    lt = scenario.longterm
    state = static_state(stress.depth_m, lt, scenario.tunnel, scenario.soil)
    if lt.cycles_per_train == "bogies":
        per_train = np.full(stress.depth_m.size, float(n_bogies(scenario.train)))
    else:
        per_train = stress.rainflow_cycles
    years = np.geomspace(min(1.0 / DAYS_PER_YEAR, lt.years), lt.years, N_YEARS)
    n_cycles = lt.trains_per_day * DAYS_PER_YEAR * years[:, None] * per_train
    a, b, m = lt.law_parameters()
    strain = permanent_strain_percent(
        lt.law,
        a,
        b,
        m,
        lt.n,
        stress.deviator_Pa,
        state.strength_Pa,
        state.static_deviator_Pa,
        n_cycles,
    )
    settlement = layered_settlement_m(strain, trapezoid_thickness(stress.depth_m))
    parameters = {"a": a, "b": b, "m": m} if lt.law != "monismith" else {"a": a, "b": b}
    if lt.law == "chai_miura":
        parameters["n"] = lt.n
    return LongTermResult(
        years=years,
        settlement_m=settlement,
        depth_m=stress.depth_m,
        deviator_Pa=stress.deviator_Pa,
        strength_Pa=state.strength_Pa,
        static_deviator_Pa=state.static_deviator_Pa,
        vertical_effective_stress_Pa=state.vertical_effective_stress_Pa,
        strain_percent=strain[-1],
        cycles_per_train=per_train,
        n_cycles=n_cycles[-1],
        depth90_m=depth_holding_fraction(stress.depth_m, strain[-1]),
        law=lt.law,
        law_parameters=parameters,
        statement=law_statement(lt, parameters, per_train),
        warnings=tuple(_failure_warnings(stress.depth_m, stress.deviator_Pa, state.strength_Pa)),
    )


def law_statement(longterm, parameters: dict[str, float], cycles_per_train) -> str:
    """One sentence naming the law, its parameters and the traffic that produced a result."""
    lt = longterm
    source = ""
    if lt.law == "li_selig":
        source = " (user values)" if lt.soil_class == "user" else f" (soil class {lt.soil_class})"
    values = ", ".join(f"{k} = {v:g}{' %' if k == 'a' else ''}" for k, v in parameters.items())
    cycles = np.asarray(cycles_per_train)
    if lt.cycles_per_train == "bogies":
        plural = "" if cycles[0] == 1 else "s"
        count = f"{cycles[0]:g} cycle{plural} per train (one per bogie)"
    else:
        count = (
            f"{cycles.min():.3g}–{cycles.max():.3g} cycles per train (rainflow count of the "
            "deviator, by depth)"
        )
    return (
        f"{LAW_NAMES[lt.law]}{source}: {values}; {lt.trains_per_day:g} trains per day, {count}, "
        f"{lt.years:g} years of service."
    )


def _failure_warnings(depth_m, deviator, strength) -> list[str]:
    """One warning per contiguous depth range where q_d ≥ σ_s."""
    failing = np.asarray(deviator) >= np.asarray(strength)
    if not failing.any():
        return []
    edges = np.flatnonzero(np.diff(np.concatenate([[0], failing.astype(int), [0]])))
    ranges = ", ".join(
        f"{depth_m[start]:.3g} m"
        if stop - start == 1
        else f"{depth_m[start]:.3g}–{depth_m[stop - 1]:.3g} m"
        for start, stop in zip(edges[::2], edges[1::2], strict=True)
    )
    return [
        f"the dynamic deviator q_d reaches the static strength σ_s = 2c_u at depths {ranges} "
        "below the invert: the strain-accumulation laws are not valid near failure, so the "
        "long-term settlement there is outside their range"
    ]


# ---- calibration from cyclic triaxial tests --------------------------------------------------
@dataclass(frozen=True)
class TriaxialData:
    """Cyclic triaxial test points: one row per (stress level, cycle count)."""

    n_cycles: np.ndarray
    """(n,) cycle number N."""
    strain_percent: np.ndarray
    """(n,) accumulated permanent axial strain (%)."""
    deviator_kPa: np.ndarray
    """(n,) cyclic deviator q_d (kPa)."""
    strength_kPa: np.ndarray
    """(n,) static strength σ_s (kPa)."""
    source: str = "arrays"
    """Where the data came from (file name)."""

    @property
    def stress_ratio(self) -> np.ndarray:
        """(n,) q_d/σ_s."""
        return self.deviator_kPa / self.strength_kPa


def _check_calibration_data(n_cycles, strain_percent, stress_ratio, source: str):
    """The three arrays as floats, or ValueError saying what is missing for a fit."""
    arrays = [
        np.atleast_1d(np.asarray(x, dtype=float)) for x in (n_cycles, strain_percent, stress_ratio)
    ]
    if len({x.shape for x in arrays}) != 1 or arrays[0].ndim != 1:
        raise ValueError(
            f"{source}: n_cycles, strain_percent and stress_ratio must be 1-D arrays of the "
            f"same length, got shapes {[x.shape for x in arrays]}"
        )
    for name, values in zip(("n_cycles", "strain_percent", "stress_ratio"), arrays, strict=True):
        bad = ~(np.isfinite(values) & (values > 0.0))
        if bad.any():
            raise ValueError(
                f"{source}: {name} must be finite and > 0 (the law is fitted in log space); "
                f"point {int(np.flatnonzero(bad)[0]) + 1} has {float(values[bad][0])!r}"
            )
    count = arrays[0].size
    if count <= N_LAW_PARAMETERS:
        raise ValueError(
            f"{source}: {count} points cannot give a, b, m with standard errors: at least "
            f"{N_LAW_PARAMETERS + 1} points are needed (3 parameters + 1 for the error estimate)"
        )
    if np.ptp(np.log(arrays[2])) == 0.0:
        raise ValueError(
            f"{source}: every point has the same stress ratio q_d/σ_s = {arrays[2][0]:g}, so m "
            "is not identifiable: add tests at a second stress level"
        )
    if np.ptp(np.log(arrays[0])) == 0.0:
        raise ValueError(
            f"{source}: every point has the same cycle number N = {arrays[0][0]:g}, so b is "
            "not identifiable: add strains read at other cycle numbers"
        )
    return arrays


def fit_strain_law(n_cycles, strain_percent, stress_ratio) -> dict[str, float]:
    """Fit Li & Selig's ε_p = a (q_d/σ_s)^m N^b by linear least squares in log space.

    log ε_p = log a + m log(q_d/σ_s) + b log N (natural logarithms), ordinary least squares;
    standard errors from the residual variance s² = RSS/(n − 3) and (XᵀX)⁻¹; the error of a
    by the delta method, a · se(log a).

    Parameters
    ----------
    n_cycles : array_like
        Cycle numbers N, > 0.
    strain_percent : array_like
        Accumulated permanent strains ε_p (%), > 0.
    stress_ratio : array_like
        q_d/σ_s of each point, > 0, at least two distinct values.

    Returns
    -------
    dict
        ``a`` (%), ``b``, ``m``, their standard errors ``a_se``, ``b_se``, ``m_se``,
        ``log_a_se``, ``n_points`` and ``residual_std`` (of log ε_p).

    Raises
    ------
    ValueError
        Fewer than 4 points, non-positive values, a single stress level or a single N.
    """
    cycles, strain, ratio = _check_calibration_data(
        n_cycles, strain_percent, stress_ratio, "calibration data"
    )
    design = np.column_stack([np.ones_like(cycles), np.log(ratio), np.log(cycles)])
    target = np.log(strain)
    coefficients, *_ = np.linalg.lstsq(design, target, rcond=None)
    residual = target - design @ coefficients
    dof = cycles.size - N_LAW_PARAMETERS
    variance = float(residual @ residual) / dof
    errors = np.sqrt(variance * np.diag(np.linalg.inv(design.T @ design)))
    a = float(np.exp(coefficients[0]))
    return {
        "a": a,
        "m": float(coefficients[1]),
        "b": float(coefficients[2]),
        "a_se": a * float(errors[0]),
        "log_a_se": float(errors[0]),
        "m_se": float(errors[1]),
        "b_se": float(errors[2]),
        "n_points": int(cycles.size),
        "residual_std": math.sqrt(variance),
    }


def load_triaxial_csv(path) -> TriaxialData:
    """Read cyclic triaxial results from a CSV file.

    Lines starting with ``#`` are comments (e.g. "SYNTHETIC data"); blank lines are skipped.
    The first other line may be a header (any names, e.g. ``n_cycles,strain_percent,
    deviator_kPa,strength_kPa``); every data row holds four numbers in that order: cycle
    number N, accumulated permanent strain (%), cyclic deviator q_d and static strength σ_s
    (both kPa, or any one stress unit).

    Parameters
    ----------
    path : str or Path
        The CSV file.

    Returns
    -------
    TriaxialData

    Raises
    ------
    ValueError
        Bad rows (with the file name and line numbers), or data from which a, b, m cannot be
        fitted (fewer than 4 points, non-positive values, a single stress level).
    """
    path = Path(path)
    return parse_triaxial_csv(path.read_text(encoding="utf-8"), path.name)


def parse_triaxial_csv(text: str, source: str = "triaxial data") -> TriaxialData:
    """Cyclic triaxial results from CSV text (format and errors as :func:`load_triaxial_csv`).

    Parameters
    ----------
    text : str
        Contents of the CSV file.
    source : str
        Name used in error messages (e.g. the uploaded file's name).

    Returns
    -------
    TriaxialData
    """
    rows, problems = [], []
    header_allowed = True
    text = text.removeprefix("\ufeff")  # a UTF-8 byte-order mark would hide the first number
    for line_number, fields in enumerate(csv.reader(io.StringIO(text)), start=1):
        if not fields or not "".join(fields).strip() or fields[0].lstrip().startswith(COMMENT):
            continue
        try:
            values = [float(field) for field in fields]
        except ValueError:
            if header_allowed:
                header_allowed = False
                continue
            problems.append(f"line {line_number}: not numbers: {','.join(fields)!r}")
            continue
        header_allowed = False
        if len(values) != len(TRIAXIAL_COLUMNS):
            problems.append(
                f"line {line_number}: {len(values)} values, expected "
                f"{len(TRIAXIAL_COLUMNS)} ({', '.join(TRIAXIAL_COLUMNS)})"
            )
        elif not all(math.isfinite(v) and v > 0.0 for v in values):
            bad = next(
                f"{name} = {v!r}"
                for name, v in zip(TRIAXIAL_COLUMNS, values, strict=True)
                if not (math.isfinite(v) and v > 0.0)
            )
            problems.append(f"line {line_number}: {bad} must be finite and > 0")
        else:
            rows.append(values)
    if problems:
        shown = "; ".join(problems[:5]) + ("; …" if len(problems) > 5 else "")
        raise ValueError(f"{source}: {len(problems)} bad row(s): {shown}")
    data = np.array(rows, dtype=float).reshape(-1, len(TRIAXIAL_COLUMNS))
    result = TriaxialData(*data.T, source=source)
    _check_calibration_data(result.n_cycles, result.strain_percent, result.stress_ratio, source)
    return result
