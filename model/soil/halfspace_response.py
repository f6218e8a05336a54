"""The soil stage in a half-space: under the invert and at the ground surface (docs/halfspace.md).

With ``tunnel.ground == "half_space"`` the soil stage of ``model.pipeline.run`` comes here
instead of ``model.soil.stresses.section_response``. The tunnel is the 2.5D shell of
``model.soil.moving_load_2p5d`` at ξ = ω/v (the moving-frame rule of §9, exact on a smooth rail),
placed at ``tunnel.axis_depth`` under a free surface by the pipe-in-pipe method
(``model.soil.pipe_in_pipe``):

- **under the invert**: the full-space receptance and stresses plus those of the field the
  surface reflects, so the displacements, the deviator and the long-term stage all see the free
  surface;
- **at the ground surface**: the vertical displacement per unit invert line load at the
  distances :func:`ground_distances`, which ``model.soil.ground_vibration`` turns into velocity
  levels, peaks and the dynamic trough.

The transfer functions are sampled in frequency and interpolated by
``model.soil.response.record_grid_transfer``: the full-space ones as the full-space stage
samples them, the reflected and surface ones finely enough for their longest wave path, to the
farthest surface point or up to the surface and back down to the deepest output point
(:func:`sampling_depth`). The stage also reports how much the
free surface changes the peak invert displacement, the size of the correction that the
pipe-in-pipe method adds without letting the tunnel scatter it (docs/halfspace.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from model.soil.ground_vibration import GroundResponse, ground_response
from model.soil.moving_load_2p5d import StressField
from model.soil.pipe_in_pipe import (
    REFLECTED_STRESSES,
    reflected_below_invert,
    surface_receptance,
)
from model.soil.response import (
    SoilResponse,
    displacement_response,
    output_depths,
    padded_record_grid,
    record_grid_transfer,
)
from model.soil.stresses import (
    STRESS_COMPONENTS,
    StressResponse,
    _deviator_response,
    invert_transfer,
    section_transfer,
)


def ground_distances(numerics) -> np.ndarray:
    """Ground-surface distances from the tunnel axis at which the stage reports (m).

    Parameters
    ----------
    numerics : model.params.Numerics
        Uses ground_max_distance and n_ground_distances.

    Returns
    -------
    ndarray
        (n_ground_distances,) from 0 to ``ground_max_distance``, evenly spaced.
    """
    return np.linspace(0.0, numerics.ground_max_distance, numerics.n_ground_distances)


def sampling_depth(scenario) -> float:
    """Depth below the invert whose distance from the axis is the stage's longest wave path (m).

    The kernel sampling of ``record_grid_transfer`` follows waves out to radius a + d_max; here
    the longest path is the largest of that, the distance √(y_max² + H²) to the farthest surface
    point, and the path up to the surface and back down to the deepest point, 2H + d_max.
    """
    tunnel, numerics = scenario.tunnel, scenario.numerics
    a, h, d_max = tunnel.ring_radius, tunnel.axis_depth, numerics.max_depth
    return max(d_max, math.hypot(numerics.ground_max_distance, h) - a, 2.0 * h + d_max - a)


def halfspace_invert_transfer(freq_hz, depth_m, scenario) -> tuple[np.ndarray, StressField]:
    """Receptance and stresses under the invert in the half-space, per unit line load.

    The full-space 2.5D ones at ξ = ω/v (``model.soil.stresses.invert_transfer``) plus those of
    the field the free surface reflects (``model.soil.pipe_in_pipe.reflected_below_invert``).

    Parameters
    ----------
    freq_hz : array_like
        Frequencies (Hz), > 0.
    depth_m : array_like
        Depths d ≥ 0 below the ring–soil interface (m).
    scenario : model.params.Scenario
        Uses tunnel (axis_depth), soil, numerics.n_harmonics and train.speed.

    Returns
    -------
    (ndarray, StressField)
        Complex (n_freq, n_depth) receptance (m per N/m) and stresses (Pa per N/m).
    """
    freq = np.atleast_1d(np.asarray(freq_hz, dtype=float))
    receptance, stresses = invert_transfer(freq, depth_m, scenario)
    wavenumber = 2.0 * np.pi * freq / scenario.train.speed
    reflected, reflected_stresses = reflected_below_invert(
        freq, wavenumber, depth_m, scenario.tunnel, scenario.soil, scenario.numerics.n_harmonics
    )
    return receptance + reflected, StressField(
        **{
            name: getattr(stresses, name) + reflected_stresses.get(name, 0.0)
            for name in STRESS_COMPONENTS
        }
    )


@dataclass(frozen=True)
class HalfspaceTransfer:
    """The half-space stage's transfer functions on a padded record's frequency grid.

    Like ``model.soil.stresses.SectionTransfer``, independent of the load itself (cached by
    ``model.pipeline.run`` apart from it).
    """

    f_hz: np.ndarray
    """(nf,) frequencies of the grid (Hz), row 0 the DC band value."""
    depth_m: np.ndarray
    """(nd,) output depths below the ring–soil interface (m)."""
    receptance: np.ndarray
    """(nf, nd) displacement under the invert per unit line load, half-space (m per N/m)."""
    stresses: StressField
    """(nf, nd) stresses under the invert per unit line load, half-space (Pa per N/m)."""
    fullspace_invert: np.ndarray
    """(nf, 1) the full-space receptance at the invert, for the size of the correction."""
    distance_m: np.ndarray
    """(n_distance,) ground-surface distances from the axis (m)."""
    surface: np.ndarray
    """(nf, n_distance) ground-surface displacement per unit invert line load (m per N/m)."""


def halfspace_transfer(line_load_N_per_m, dt_s: float, scenario) -> HalfspaceTransfer:
    """Every transfer function of the half-space stage on the grid of a load record.

    The full-space ones are ``model.soil.stresses.section_transfer``'s, sampled for waves out
    to the deepest output point; the reflected and the surface ones are sampled for the longest
    path of :func:`sampling_depth`, and added.

    Parameters
    ----------
    line_load_N_per_m : array_like
        Load record q(t) (N/m); only its length and step set the grid.
    dt_s : float
        Sampling interval (s), > 0.
    scenario : model.params.Scenario
        As :func:`halfspace_response`.

    Returns
    -------
    HalfspaceTransfer
    """
    numerics, tunnel, soil = scenario.numerics, scenario.tunnel, scenario.soil
    fullspace = section_transfer(line_load_N_per_m, dt_s, scenario)
    distance = ground_distances(numerics)

    def evaluate(freq):
        wavenumber = 2.0 * np.pi * freq / scenario.train.speed
        reflected, stresses = reflected_below_invert(
            freq, wavenumber, fullspace.depth_m, tunnel, soil, numerics.n_harmonics
        )
        surface = surface_receptance(freq, wavenumber, distance, tunnel, soil, numerics.n_harmonics)
        return reflected, *stresses.values(), surface

    reflected, *components, surface = record_grid_transfer(
        fullspace.f_hz, np.array([sampling_depth(scenario)]), evaluate, tunnel, soil, numerics
    )
    added = dict(zip(REFLECTED_STRESSES, components, strict=True))
    stresses = StressField(
        **{
            name: getattr(fullspace.stresses, name) + added.get(name, 0.0)
            for name in STRESS_COMPONENTS
        }
    )
    return HalfspaceTransfer(
        f_hz=fullspace.f_hz,
        depth_m=fullspace.depth_m,
        receptance=fullspace.receptance + reflected,
        stresses=stresses,
        fullspace_invert=fullspace.receptance[:, :1],
        distance_m=distance,
        surface=surface,
    )


def halfspace_response(
    line_load_N_per_m,
    dt_s: float,
    scenario,
    transfer: HalfspaceTransfer | None = None,
    load_spectrum=None,
) -> tuple[SoilResponse, StressResponse, GroundResponse]:
    """Displacements and stresses under the invert and vibration at the ground surface.

    Parameters
    ----------
    line_load_N_per_m : array_like
        Downward line load on the invert q(t) (N/m), sampled from t = 0 at ``dt_s``.
    dt_s : float
        Sampling interval (s), > 0.
    scenario : model.params.Scenario
        Uses tunnel (axis_depth; ``model`` must be "2.5d"), soil, train.speed and numerics
        (n_harmonics, soil_max_frequency, zero_pad_factor, psd_segment, max_depth, n_depths,
        kernel_samples_per_cycle, ground_max_distance, n_ground_distances).
    transfer : HalfspaceTransfer, optional
        :func:`halfspace_transfer` of a record of the same length and step and the same
        scenario, to reuse; computed when not given.
    load_spectrum : ndarray, optional
        :func:`model.soil.response.padded_load_spectrum` of this record and numerics, to
        reuse; computed when not given.

    Returns
    -------
    (SoilResponse, StressResponse, GroundResponse)
        ``GroundResponse.free_surface_effect`` is the relative change of the peak invert
        displacement that the free surface makes.

    Raises
    ------
    ValueError
        ``transfer`` was made on another frequency grid, other depths or other distances.
    """
    numerics = scenario.numerics
    grid = padded_record_grid(
        line_load_N_per_m, dt_s, numerics, scenario.soil.s_wave_speed, load_spectrum
    )
    depth, distance = output_depths(numerics), ground_distances(numerics)
    if transfer is None:
        transfer = halfspace_transfer(line_load_N_per_m, dt_s, scenario)
    elif not (
        np.array_equal(transfer.f_hz, grid.f_hz)
        and np.array_equal(transfer.depth_m, depth)
        and np.array_equal(transfer.distance_m, distance)
    ):
        raise ValueError(
            "transfer was computed on another frequency grid, other depths or other ground "
            "distances than this record's"
        )
    soil = displacement_response(grid, depth, transfer.receptance, numerics)
    fullspace_peak = grid.time_histories(
        (transfer.fullspace_invert * grid.load_spectrum[:, None]).T
    )
    effect = soil.peak_disp_m[0] / fullspace_peak[0].max() - 1.0
    ground = ground_response(grid, distance, transfer.surface, effect)
    return soil, _deviator_response(grid, depth, transfer.stresses), ground
