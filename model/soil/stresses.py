"""Dynamic stresses under the invert during one passage, and their deviator (docs/model.md §10).

Computed by the soil stage, from the same tunnel–soil kernel evaluation as the displacements of
``model.soil.response``; they drive the long-term stage (``model.longterm``). Per depth d below
the ring–soil interface directly under the invert:

1. **Dynamic stresses.** The stress transfer functions of the tunnel–soil model (stress per unit
   downward line load at the invert, six components of :class:`StressField`) times the spectrum
   of the line load, transformed back to time on the soil stage's grid
   (:func:`model.soil.response.padded_record_grid`: same zero padding, band limit and output
   step), the kernel sampled and interpolated alike
   (:func:`model.soil.response.record_grid_transfer`). In 2D the axial stress is the plane-strain
   one, σ_xx = λ*(ε_rr + ε_θθ) = λ*/(2(λ* + μ*)) (σ_rr + σ_θθ), and σ_rx = σ_θx = 0.
2. **Zero-frequency bin.** Unlike the 2D static displacement, the 2D static *stresses* are
   finite: the ln ω growth of the n = 1 harmonic is a rigid translation, which carries no strain,
   so σ(f) = σ(0) + O((ωr/c₂)² ln ω). The DC bin stands for the band [−Δf/2, Δf/2]; with
   σ(−f) = conj σ(f) its average is Re of the average over [0, Δf/2], which to that order is
   Re σ(Δf/(2e)), the same evaluation point as the displacement's DC bin
   (:func:`model.soil.response.dc_band_receptance`), so both stages follow one rule.
3. **Deviator.** q(t, d) = √(3 J₂) of the dynamic stress tensor, J₂ = ½ s:s with s its
   deviatoric part; in a triaxial state (σ₂ = σ₃) this is |σ₁ − σ₃|. q_d(d) = max over t, and
   the range-weighted rainflow count of q(t, d) per passage
   (:func:`model.longterm.cycles.range_weighted_cycles`) is taken here, where the histories are.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from model.longterm.cycles import range_weighted_cycles
from model.soil.kernel_sampling import depth_sampled_transfer
from model.soil.moving_load_2p5d import StressField, invert_response_2p5d
from model.soil.response import (
    SoilResponse,
    displacement_response,
    output_depths,
    padded_record_grid,
    record_grid_frequencies,
)
from model.soil.section_2d import soil_field

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


def _plane_strain_invert_field(freq_hz, depth_m, tunnel, soil, n_harmonics: int, mask=None):
    """(receptance, StressField) under the invert from one 2D kernel evaluation (``mask``: the
    (frequency, depth) pairs to compute, default all)."""
    depth = np.atleast_1d(np.asarray(depth_m, dtype=float))
    if np.any(depth < 0.0):
        raise ValueError(
            f"depth_m = {float(depth[depth < 0.0][0])!r} is inside the lining: depths are "
            "measured from the ring–soil interface and must be ≥ 0 m"
        )
    field = soil_field(
        freq_hz, tunnel.ring_radius + depth, 0.0, tunnel, soil, n_harmonics, point_mask=mask
    )
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


def invert_transfer(freq_hz, depth_m, scenario, mask=None) -> tuple[np.ndarray, StressField]:
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
    mask : ndarray, optional
        (n_freq, n_depth) bool: the pairs to compute; the others are 0 (default: all).

    Returns
    -------
    (ndarray, StressField)
        Complex (n_freq, n_depth) receptance (m per N/m) and stresses (Pa per N/m).
    """
    tunnel, soil, n_harmonics = scenario.tunnel, scenario.soil, scenario.numerics.n_harmonics
    if tunnel.model == "2.5d":  # the moving train: the kernel at ξ = ω/v (docs/model.md §9)
        freq = np.atleast_1d(np.asarray(freq_hz, dtype=float))
        wavenumber = 2.0 * np.pi * freq / scenario.train.speed
        return invert_response_2p5d(freq, wavenumber, depth_m, tunnel, soil, n_harmonics, mask)
    return _plane_strain_invert_field(freq_hz, depth_m, tunnel, soil, n_harmonics, mask)


def _grid_transfer(f_hz, depth, scenario) -> tuple[np.ndarray, StressField]:
    """:func:`invert_transfer` on a record grid, row 0 the DC band value (module docstring,
    step 2), by :func:`model.soil.response.record_grid_transfer` like the displacements."""

    def evaluate(freq, depth, mask):
        receptance, stresses = invert_transfer(freq, depth, scenario, mask)
        return receptance, *stress_components(stresses)

    receptance, *components = depth_sampled_transfer(
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
    rr, tt, xx = (np.asarray(c, dtype=float) for c in (sigma_rr, sigma_thetatheta, sigma_xx))
    return _deviator_of_differences(rr - tt, tt - xx, sigma_rtheta, sigma_rx, sigma_thetax)


def _deviator_of_differences(rr_tt, tt_xx, sigma_rtheta, sigma_rx, sigma_thetax) -> np.ndarray:
    """:func:`deviator_stress` from the normal-stress differences σ_rr − σ_θθ and σ_θθ − σ_xx
    (σ_xx − σ_rr is minus their sum) and the shear components, broadcast together."""
    rr_tt, tt_xx, rt, rx, tx = np.broadcast_arrays(
        *(np.asarray(c, dtype=float) for c in (rr_tt, tt_xx, sigma_rtheta, sigma_rx, sigma_thetax))
    )
    j2 = (rr_tt**2 + tt_xx**2 + (rr_tt + tt_xx) ** 2) / 6.0 + rt**2 + rx**2 + tx**2
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
    f_hz = record_grid_frequencies(line_load_N_per_m, dt_s, numerics)
    depth = output_depths(numerics)
    receptance, stresses = _grid_transfer(f_hz, depth, scenario)
    return SectionTransfer(f_hz, depth, receptance, stresses)


def section_response(
    line_load_N_per_m,
    dt_s: float,
    scenario,
    transfer: SectionTransfer | None = None,
    load_spectrum=None,
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
    load_spectrum : ndarray, optional
        :func:`model.soil.response.padded_load_spectrum` of this record and numerics, to
        reuse; computed when not given.

    Returns
    -------
    (SoilResponse, StressResponse)

    Raises
    ------
    ValueError
        ``transfer`` was made on another frequency grid or other depths.
    """
    numerics = scenario.numerics
    grid = padded_record_grid(
        line_load_N_per_m, dt_s, numerics, scenario.soil.s_wave_speed, load_spectrum
    )
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

    Only the normal-stress differences σ_rr − σ_θθ and σ_θθ − σ_xx enter the deviator: they
    are transformed (two histories per depth, not three), and so are the shear components that
    do not vanish identically (σ_rθ, σ_θx vanish at θ = 0, σ_rx in 2D).
    """
    differences = [
        grid.response_histories(stresses.sigma_rr, stresses.sigma_thetatheta),
        grid.response_histories(stresses.sigma_thetatheta, stresses.sigma_xx),
    ]
    shears = [
        grid.response_histories(component) if np.any(component) else 0.0
        for component in (stresses.sigma_rtheta, stresses.sigma_rx, stresses.sigma_thetax)
    ]
    deviator = _deviator_of_differences(*differences, *shears)
    return StressResponse(
        depth_m=depth,
        t_s=np.arange(grid.n_out) * grid.dt_out,
        deviator_history_Pa=deviator,
        deviator_Pa=deviator.max(axis=1),
        rainflow_cycles=np.array([range_weighted_cycles(row) for row in deviator]),
    )
