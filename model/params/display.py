"""Units, labels and ranges in which a person reads and types a parameter (the interface only)."""

from __future__ import annotations

import param

from model.params.quantities import _format_range, split_label
from model.params.scenario import SECTIONS, Scenario
from model.params.site import SECONDS_PER_YEAR, Layer

LAYER_PATH = "site.layers."
"""Prefix of a layer property's path: ``"site.layers.unit_weight"`` (any layer's)."""

DISPLAY_UNITS: dict[str, tuple[str, float]] = {
    "vehicle.car_body_mass": ("t", 1e-3),
    "vehicle.car_body_pitch_inertia": ("t·m²", 1e-3),
    "vehicle.primary_stiffness": ("MN/m", 1e-6),
    "vehicle.primary_damping": ("kN·s/m", 1e-3),
    "vehicle.secondary_stiffness": ("MN/m", 1e-6),
    "vehicle.secondary_damping": ("kN·s/m", 1e-3),
    "track.rail_E": ("GPa", 1e-9),
    "track.rail_I": ("cm⁴", 1e8),
    "track.fastener_stiffness": ("MN/m", 1e-6),
    "track.fastener_damping": ("kN·s/m", 1e-3),
    "track.pad_stiffness": ("MN/m", 1e-6),
    "track.pad_damping": ("kN·s/m", 1e-3),
    "tunnel.youngs_modulus": ("GPa", 1e-9),
    "soil.youngs_modulus": ("MPa", 1e-6),
    "numerics.dt": ("ms", 1e3),
    "site.layers.unit_weight": ("kN/m³", 1e-3),
    "site.layers.undrained_strength": ("kPa", 1e-3),
    "site.layers.compressibility": ("1/MPa", 1e6),
    "site.layers.consolidation_coefficient": ("m²/year", SECONDS_PER_YEAR),
}
"""Unit in which a person reads and types a parameter, and the factor SI value → display value.

Parameters not listed are shown in the SI unit of their label."""


def parameter_of(path: str) -> param.Parameter:
    """The parameter declaration of a dotted path, e.g. ``"soil.youngs_modulus"``, or of a
    layer property, ``"site.layers.thickness"``."""
    if path.startswith(LAYER_PATH) and path.removeprefix(LAYER_PATH) in Layer.param:
        return Layer.param[path.removeprefix(LAYER_PATH)]
    section, _, name = path.partition(".")
    if section not in SECTIONS or name not in Scenario.param[section].class_.param:
        raise KeyError(f"unknown parameter {path!r}")
    return Scenario.param[section].class_.param[name]


def display_unit(path: str) -> tuple[str, float]:
    """(unit, factor) in which ``path`` is shown: display value = factor × SI value."""
    if path in DISPLAY_UNITS:
        return DISPLAY_UNITS[path]
    return split_label(parameter_of(path).label or path)[1], 1.0


def display_label(path: str) -> str:
    """The parameter's label with its display unit in place of the SI unit."""
    bare = split_label(parameter_of(path).label or path)[0]
    unit, _ = display_unit(path)
    return f"{bare} ({unit})" if unit and unit != "-" else bare


def display_range(path: str) -> str:
    """Allowed (hard) range of ``path`` in its display unit, e.g. "(0, inf) MPa"."""
    p = parameter_of(path)
    unit, factor = display_unit(path)
    bounds = tuple(None if b is None else b * factor for b in p.bounds or (None, None))
    text = _format_range(bounds, p.inclusive_bounds, isinstance(p, param.Integer))
    return f"{text} {unit}" if unit and unit != "-" else text
