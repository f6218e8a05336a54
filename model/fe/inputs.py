"""What the FE section takes from the scenario and the load record (docs/model.md §12).

The load band (where the fluctuating load energy passes 5 % and 99 %), Rayleigh damping matched
to η_G/2 at its ends, the Drucker–Prager match of Mohr–Coulomb in plane strain, the load
averaged over each FE step, and the linear geostatic stress field about the tunnel axis
(σ_v = ρ g z at depth z = H_t − y below the surface, u = γ_w (z − z_w), σ_h = K0 σ′_v + u) with
the undrained strength c_u of docs/model.md §10.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from model.params import Scenario

GRAVITY = 9.81  # m/s²
WATER_UNIT_WEIGHT = 9810.0  # γ_w, N/m³
BAND_ENERGY_LOW, BAND_ENERGY_HIGH = 0.05, 0.99
"""Load band: where the fluctuating (mean-removed) load energy passes 5 % and 99 %."""


@dataclass(frozen=True)
class LoadBand:
    """Frequency band of a load record and what the FE needs from it."""

    f_low_hz: float
    f_high_hz: float
    shortest_wavelength_m: float
    """c₂ / f_high (m)."""


# ---- inputs ---------------------------------------------------------------------------------
def load_band(line_load_N_per_m, dt_s: float, s_wave_speed: float) -> LoadBand:
    """Band of a load record: where its fluctuating energy passes 5 % and 99 %.

    Parameters
    ----------
    line_load_N_per_m : array_like
        Load history (N/m), sampled at ``dt_s``.
    dt_s : float
        Sampling interval (s), > 0.
    s_wave_speed : float
        Soil S-wave speed c₂ (m/s), > 0.

    Returns
    -------
    LoadBand
    """
    q = np.asarray(line_load_N_per_m, dtype=float)
    # no zero padding: after removing the mean it would add a step at the record's end
    energy = np.abs(np.fft.rfft(q - q.mean())) ** 2
    if q.size < 4 or not np.any(energy > 0):
        raise ValueError("the load history must have at least 4 samples and vary in time")
    f_hz = np.fft.rfftfreq(q.size, dt_s)
    cumulative = np.cumsum(energy) / energy.sum()
    f_low = float(f_hz[np.searchsorted(cumulative, BAND_ENERGY_LOW)])
    f_high = float(f_hz[np.searchsorted(cumulative, BAND_ENERGY_HIGH)])
    f_low = max(f_low, f_hz[1])
    f_high = max(f_high, 2.0 * f_low)
    return LoadBand(f_low, f_high, s_wave_speed / f_high)


def rayleigh_coefficients(loss_factor: float, f_low_hz: float, f_high_hz: float):
    """(a₀, a₁) of C = a₀M + a₁K with damping ratio η/2 at f_low and f_high.

    Parameters
    ----------
    loss_factor : float
        Hysteretic loss factor η_G (-), ≥ 0.
    f_low_hz, f_high_hz : float
        Matching frequencies (Hz), 0 < f_low < f_high.

    Returns
    -------
    tuple of float
        a₀ (1/s), a₁ (s).
    """
    w1, w2 = 2 * math.pi * f_low_hz, 2 * math.pi * f_high_hz
    zeta = 0.5 * loss_factor
    return 2 * zeta * w1 * w2 / (w1 + w2), 2 * zeta / (w1 + w2)


def drucker_prager_plane_strain(cohesion_Pa: float, friction_angle_deg: float):
    """OpenSees Drucker–Prager (σ_Y, ρ) matching Mohr–Coulomb (c, φ) in plane strain.

    Plane-strain match with associated flow: √J₂ = k − α I₁, α = tan φ / √(9 + 12 tan²φ),
    k = 3c / √(9 + 12 tan²φ); OpenSees writes ‖s‖ + ρ I₁ ≤ √(2/3) σ_Y, so ρ = √2 α and
    σ_Y = √3 k. For φ = 0 (undrained, Tresca) σ_Y = √3 c_u and ρ = 0.

    Parameters
    ----------
    cohesion_Pa : float
        c (Pa), ≥ 0.
    friction_angle_deg : float
        φ (degrees), 0 ≤ φ < 90.

    Returns
    -------
    tuple of float
        σ_Y (Pa), ρ (-).
    """
    tan_phi = math.tan(math.radians(friction_angle_deg))
    root = math.sqrt(9.0 + 12.0 * tan_phi**2)
    return math.sqrt(3.0) * 3.0 * cohesion_Pa / root, math.sqrt(2.0) * tan_phi / root


def resample_load(line_load_N_per_m, dt_s: float, dt_fe_s: float):
    """Average the load over each FE step of k·dt (k = round(dt_fe/dt)); returns (q, k·dt)."""
    q = np.asarray(line_load_N_per_m, dtype=float)
    k = max(1, math.floor(dt_fe_s / dt_s + 1e-9))
    n = q.size // k
    return q[: n * k].reshape(n, k).mean(axis=1), k * dt_s


# ---- geostatic stress -------------------------------------------------------------------------
@dataclass(frozen=True)
class Geostatic:
    """Linear geostatic stress field about the tunnel axis (compression positive, Pa)."""

    axis_depth: float
    unit_weight: float
    water_table_depth: float
    k0: float

    def depth(self, y):
        """Depth below the ground surface z = H_t − y (m)."""
        return self.axis_depth - np.asarray(y, dtype=float)

    def pore_pressure(self, y):
        """u = γ_w (z − z_w), extended linearly (Pa)."""
        return WATER_UNIT_WEIGHT * (self.depth(y) - self.water_table_depth)

    def vertical(self, y):
        """Total vertical stress σ_v = ρ g z (Pa)."""
        return self.unit_weight * self.depth(y)

    def effective_vertical(self, y):
        """σ′_v = σ_v − u (Pa)."""
        return self.vertical(y) - self.pore_pressure(y)

    def horizontal(self, y):
        """Total horizontal stress σ_h = K0 σ′_v + u (Pa)."""
        return self.k0 * self.effective_vertical(y) + self.pore_pressure(y)


def host_layer(scenario: Scenario):
    """The site layer that holds the tunnel axis (its K0 and c_u rule the homogeneous section)."""
    site = scenario.site
    return site.layers[site.layer_index(scenario.tunnel.axis_depth)]


def geostatic(scenario: Scenario) -> Geostatic:
    """The geostatic field of the tunnel's axis depth, the section's soil density, the site's
    water table and the K0 of the layer holding the tunnel (docs/model.md §10, §14)."""
    return Geostatic(
        axis_depth=scenario.tunnel.axis_depth,
        unit_weight=scenario.soil.density * GRAVITY,
        water_table_depth=scenario.site.water_table_depth,
        k0=host_layer(scenario).earth_pressure_coefficient,
    )


def undrained_strength(scenario: Scenario, y) -> np.ndarray:
    """c_u at height y above the axis (Pa): the host layer's, given or cu_ratio · σ′_v0
    (docs/model.md §10)."""
    layer = host_layer(scenario)
    if layer.undrained_strength is not None:
        return np.full(np.shape(y), float(layer.undrained_strength))
    return layer.cu_ratio * geostatic(scenario).effective_vertical(y)
