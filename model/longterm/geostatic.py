"""Geostatic stress state and undrained strength below the invert (docs/model.md §10).

Depth below ground z = H_t + a + d (H_t the tunnel's axis depth, a the ring radius, where the
soil model's soil begins, d below the ring–soil interface); σ_v = ρ g z, pore pressure
u = ρ_w g max(0, z − z_w), σ′_v0 = σ_v − u (ρ the soil density, taken as saturated, and the
same above the water table); K0 = 1 − sin φ′, static deviator q_s = σ′_v0 (1 − K0);
c_u = ratio · σ′_v0 or given; σ_s = q_f = 2 c_u.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

GRAVITY = 9.81  # m/s²
WATER_DENSITY = 1000.0  # kg/m³


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
    """Static stress state and undrained strength below the invert (module docstring).

    Parameters
    ----------
    depth_m : array_like
        Depths d ≥ 0 below the ring–soil interface (m).
    longterm : model.params.LongTerm
        Uses water_table_depth, friction_angle (K0), cu_ratio, undrained_strength.
    tunnel : model.params.Tunnel
        Uses axis_depth and ring_radius.
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
    below_ground = tunnel.axis_depth + tunnel.ring_radius + depth
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
    if tunnel.axis_depth < outer_radius:
        raise ValueError(
            f"tunnel.axis_depth = {tunnel.axis_depth:g} m is less than the lining's outer "
            f"radius {outer_radius:g} m: the tunnel would stand out of the ground; allowed "
            f"range [{outer_radius:g}, 200] m"
        )
    static_state([0.0, scenario.numerics.max_depth], longterm, tunnel, scenario.soil)
