"""Geostatic stress state and undrained strength below the invert, layer by layer (§10, §14).

Depth below ground z = H_t + a + d (H_t the tunnel's axis depth, a the ring radius, where the
soil model's soil begins, d below the ring–soil interface). Layers top down from the surface
with unit weights γ_i (saturated below the water table, used as is above it):
σ_v(z) = Σ γ_i h_i down to z, u_0 = γ_w max(0, z − z_w), σ′_v0 = σ_v − u_0 (γ_w = 9.81 kN/m³).
Each depth takes its layer's K0 = 1 − sin φ′ (static deviator q_s = σ′_v0 (1 − K0)) and
c_u = ratio · σ′_v0 or the given c_u; σ_s = q_f = 2 c_u.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

GRAVITY = 9.81  # m/s²
WATER_DENSITY = 1000.0  # kg/m³
UNIT_WEIGHT_WATER = WATER_DENSITY * GRAVITY  # γ_w (N/m³)


@dataclass(frozen=True)
class StaticState:
    """Geostatic stresses and strength per depth below the invert (Pa)."""

    depth_m: np.ndarray
    """(nd,) depths below the ring–soil interface (m)."""
    depth_below_ground_m: np.ndarray
    """(nd,) z = H_t + a + d (m)."""
    layer_index: np.ndarray
    """(nd,) index of each depth's layer in ``site.layers``."""
    vertical_effective_stress_Pa: np.ndarray
    """(nd,) σ′_v0."""
    static_deviator_Pa: np.ndarray
    """(nd,) q_s = σ′_v0 (1 − K0)."""
    undrained_strength_Pa: np.ndarray
    """(nd,) c_u."""
    strength_Pa: np.ndarray
    """(nd,) σ_s = q_f = 2 c_u."""


def vertical_stresses(depth_below_ground_m, site) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Total vertical stress, hydrostatic pore pressure and σ′_v0 at depths below the surface.

    Parameters
    ----------
    depth_below_ground_m : array_like
        Depths z ≥ 0 below the ground surface (m).
    site : model.params.Site
        Layers (thickness, unit_weight) and water_table_depth.

    Returns
    -------
    (ndarray, ndarray, ndarray)
        σ_v = Σ γ_i h_i to z, u_0 = γ_w max(0, z − z_w) and σ′_v0 = σ_v − u_0 (Pa).
    """
    depth = np.atleast_1d(np.asarray(depth_below_ground_m, dtype=float))
    thickness = np.array([layer.thickness for layer in site.layers])
    weight = np.array([layer.unit_weight for layer in site.layers])
    tops = np.concatenate([[0.0], np.cumsum(thickness)[:-1]])
    within = np.clip(depth[None, :] - tops[:, None], 0.0, thickness[:, None])
    total = np.sum(weight[:, None] * within, axis=0)
    pore = UNIT_WEIGHT_WATER * np.maximum(0.0, depth - site.water_table_depth)
    return total, pore, total - pore


def layer_values(site, layer_index, name: str) -> np.ndarray:
    """A layer property at each depth, from the index of each depth's layer."""
    values = np.array([getattr(layer, name) for layer in site.layers], dtype=float)
    return values[np.asarray(layer_index, dtype=int)]


def static_state(depth_m, site, tunnel, layer_index=None) -> StaticState:
    """Static stress state and undrained strength below the invert (module docstring).

    Parameters
    ----------
    depth_m : array_like
        Depths d ≥ 0 below the ring–soil interface (m).
    site : model.params.Site
        Layers (unit weight, φ′, c_u or its ratio) and the water table.
    tunnel : model.params.Tunnel
        Uses axis_depth and ring_radius.
    layer_index : array_like of int, optional
        The layer of each depth (e.g. the two rows of a boundary); by default the layer that
        holds it, a boundary taking the lower layer.

    Returns
    -------
    StaticState

    Raises
    ------
    ValueError
        If σ′_v0 is not positive at some depth, naming the layer.
    """
    depth = np.atleast_1d(np.asarray(depth_m, dtype=float))
    below_ground = tunnel.axis_depth + tunnel.ring_radius + depth
    if layer_index is None:
        layer_index = [site.layer_index(z) for z in below_ground]
    index = np.asarray(layer_index, dtype=int)
    _, _, effective = vertical_stresses(below_ground, site)
    if np.any(effective <= 0.0):
        _refuse_effective_stress(site, below_ground, effective, index)
    ratio = layer_values(site, index, "cu_ratio")
    given = [layer.undrained_strength for layer in site.layers]
    given = np.array([np.nan if g is None else g for g in given])[index]
    undrained = np.where(np.isnan(given), ratio * effective, given)
    k0 = np.array([layer.earth_pressure_coefficient for layer in site.layers])[index]
    return StaticState(
        depth_m=depth,
        depth_below_ground_m=below_ground,
        layer_index=index,
        vertical_effective_stress_Pa=effective,
        static_deviator_Pa=effective * (1.0 - k0),
        undrained_strength_Pa=undrained,
        strength_Pa=2.0 * undrained,
    )


def _refuse_effective_stress(site, below_ground, effective, index) -> None:
    """ValueError naming the first depth and layer where σ′_v0 ≤ 0."""
    first = int(np.flatnonzero(effective <= 0.0)[0])
    layer = site.layers[index[first]]
    raise ValueError(
        f"the vertical effective stress σ′_v0 = {effective[first] * 1e-3:.3g} kPa at "
        f"{below_ground[first]:.4g} m below the surface (layer {layer.name!r}, site.layers"
        f"[{index[first]}].unit_weight = {layer.unit_weight * 1e-3:.4g} kN/m³) is not positive: "
        f"below the water table the layers must weigh more than water "
        f"({UNIT_WEIGHT_WATER * 1e-3:.2f} kN/m³), or site.water_table_depth be deeper"
    )


def check_longterm_inputs(scenario) -> None:
    """Refuse a static state that cannot exist, before any computation (ValueError).

    The tunnel must lie below the ground surface (axis depth ≥ outer radius of the lining) and
    σ′_v0 must be positive from the invert to the deepest depth (it is linear between the
    layer boundaries and the water table, so those depths and the column's ends suffice).
    """
    tunnel, site = scenario.tunnel, scenario.site
    outer_radius = tunnel.inner_radius + tunnel.thickness
    if tunnel.axis_depth < outer_radius:
        raise ValueError(
            f"tunnel.axis_depth = {tunnel.axis_depth:g} m is less than the lining's outer "
            f"radius {outer_radius:g} m: the tunnel would stand out of the ground; allowed "
            f"range [{outer_radius:g}, 200] m"
        )
    top = tunnel.axis_depth + tunnel.ring_radius
    bottom = top + scenario.numerics.max_depth
    kinks = [*site.bottoms, site.water_table_depth]
    depths = np.array([top, bottom, *(z for z in kinks if top < z < bottom)])
    index = [site.layer_index(z) for z in depths]
    index[1] = site.layer_index(np.nextafter(bottom, top))  # the base belongs to the layer above
    static_state(depths - top, site, tunnel, index)
