"""What produced a long-term result, in words: the laws and their constants, and the warnings.

Read by people (the dashboard, the report, ``summary.json``), so each sentence names the law,
the layer and the values in the units an engineer reads (%, MPa⁻¹, m²/year, kN/m³).
"""

from __future__ import annotations

import numpy as np

from model.longterm.pore_pressure import PORE_PRESSURE_LAWS
from model.longterm.strain_laws import LAW_NAMES
from model.params.site import SECONDS_PER_YEAR, Layer
from model.params.soil_sets import LAYERS, SOIL_SETS, strain_law_constants

SETTLEMENT_COVERS = (
    "train-induced: cyclic plastic strain and consolidation of train-induced pore pressure; "
    "not construction, leakage or regional subsidence"
)
"""What every long-term settlement of this program covers, said wherever one is shown."""
OUTSIDE_LAW_RANGE = "outside the strain laws' range: q_d reaches σ_s below the invert"
"""Said with a long-term settlement wherever q_d/σ_s ≥ 1 somewhere in its column."""
UNIT_WEIGHT_TOLERANCE = 0.10  # host layer γ against s.soil's ρ g (docs/model.md §14)
POWER_CONSTANTS = ("a_u", "b_u", "m_u", "r_u_max")
HYPERBOLIC_CONSTANTS = ("alpha_u", "beta_u", "m_u", "r_u_max")
SYMBOLS = {
    "a_u": "a_u",
    "b_u": "b_u",
    "m_u": "m_u",
    "alpha_u": "α",
    "beta_u": "β",
    "r_u_max": "r_u,max",
    "compressibility": "m_v",
    "recompression_index": "C_r",
    "void_ratio": "e0",
    "permeability": "k",
}


def law_statement(longterm, layers: list[Layer], cycles_per_train) -> str:
    """One sentence naming the strain law, each layer's constants and the traffic.

    Parameters
    ----------
    longterm : model.params.LongTerm
        Law, traffic and years.
    layers : list of Layer
        The layers the long-term column crosses, top down.
    cycles_per_train : array_like
        (nd,) cycles per passage.
    """
    lt = longterm
    parts = []
    for layer in layers:
        parameters = law_parameters(lt, layer)
        source = ""
        if lt.soil_set != LAYERS:
            source = f" (soil set {lt.soil_set}: {SOIL_SETS[lt.soil_set].citation})"
        elif lt.law == "li_selig":
            user = layer.soil_class == "user"
            source = " (user values)" if user else f" (soil class {layer.soil_class})"
        values = ", ".join(f"{k} = {v:g}{' %' if k == 'a' else ''}" for k, v in parameters.items())
        parts.append((layer.name, source, values))
    if len(parts) == 1:
        _, source, values = parts[0]
        constants = f"{LAW_NAMES[lt.law]}{source}: {values}"
    else:
        constants = f"{LAW_NAMES[lt.law]}: " + "; ".join(
            f"{name}{source} {values}" for name, source, values in parts
        )
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
        f"{constants}; {lt.trains_per_day:g} trains per day, {count}, "
        f"{lt.years:g} years of service."
    )


def law_parameters(longterm, layer: Layer) -> dict[str, float]:
    """The strain-law constants in force in a layer (a in %, exponents), n for Chai & Miura:
    the layer's own, or those of the named set ``longterm.soil_set``."""
    law = longterm.law
    constants = strain_law_constants(longterm.soil_set, law, layer)
    names = ("a", "b") if law == "monismith" else ("a", "b", "m")
    parameters = {name: constants[name] for name in names}
    if law == "chai_miura":
        parameters["n"] = constants["n"]
    return parameters


def pore_pressure_statement(longterm, tunnel, layers: list[Layer]) -> str:
    """One sentence naming the pore-pressure law, each layer's constants and the drainage."""
    lt = longterm
    if lt.pore_pressure_law == "none":
        return (
            "No pore pressure (longterm.pore_pressure_law = 'none'): the settlement is the "
            "plastic part alone."
        )
    names = POWER_CONSTANTS if lt.pore_pressure_law == "power" else HYPERBOLIC_CONSTANTS
    parts = []
    for layer in layers:
        constants = ", ".join(f"{SYMBOLS[n]} = {getattr(layer, n):g}" for n in names)
        parts.append(f"{layer.name}: {constants}, {_consolidation_constants(layer)}")
    drainage = f"invert {lt.invert_drainage}"
    if lt.invert_drainage == "leaking":
        drainage += (
            f" (lining k_l = {lt.lining_permeability:g} m/s through t_l = {tunnel.thickness:g} m)"
        )
    defaults = [
        f"{', '.join(SYMBOLS.get(n, n) for n in unsourced)} of {layer.name}"
        for layer in layers
        if (unsourced := _illustrative(layer, names))
    ]
    note = (
        f" Illustrative defaults, not from a test or a source: {'; '.join(defaults)}; replace "
        "them with the site's data."
        if defaults
        else ""
    )
    closed = lt.invert_drainage == "sealed" and lt.base_drainage == "sealed"
    undrained = ": no boundary drains, so the water stays and S_c = 0" if closed else ""
    return (
        f"Pore pressure: {PORE_PRESSURE_LAWS[lt.pore_pressure_law]}, u_g = σ′_v0 r_u; "
        + "; ".join(parts)
        + f"; consolidating while traffic goes on, {drainage}, base {lt.base_drainage}"
        + f"{undrained}."
        + note
    )


def _consolidation_constants(layer: Layer) -> str:
    """m_v and k (or c_v) of a layer as given, in MPa⁻¹, m/s and m²/year."""
    if layer.compressibility is not None:
        m_v = f"m_v = {layer.compressibility * 1e6:.3g} MPa⁻¹"
    else:
        m_v = f"m_v from C_r = {layer.recompression_index:g}, e0 = {layer.void_ratio:g}"
    if layer.consolidation_coefficient is not None:
        flow = f"c_v = {layer.consolidation_coefficient * SECONDS_PER_YEAR:.3g} m²/year"
    else:
        flow = f"k = {layer.permeability:.3g} m/s"
    return f"{m_v}, {flow}"


def _illustrative(layer: Layer, law_constants) -> list[str]:
    """The constants in force in a layer (of the law, m_v or C_r and e0, k or c_v) that are
    still the unsourced defaults (r_u,max is §15's rule, not a constant of the soil)."""
    names = [name for name in law_constants if name != "r_u_max"]
    if layer.compressibility is not None:
        names.append("compressibility")
    else:
        names += ["recompression_index", "void_ratio"]
    if layer.consolidation_coefficient is None:
        names.append("permeability")
    return [name for name in names if getattr(layer, name) == Layer.param[name].default]


def depth_ranges(depth_m, mask) -> str:
    """Contiguous depth ranges where ``mask`` holds, e.g. "0–1 m, 5 m"."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], np.asarray(mask, int), [0]])))
    return ", ".join(
        f"{depth_m[start]:.3g} m"
        if stop - start == 1
        else f"{depth_m[start]:.3g}–{depth_m[stop - 1]:.3g} m"
        for start, stop in zip(edges[::2], edges[1::2], strict=True)
    )


def failure_warnings(depth_m, deviator, strength) -> list[str]:
    """One warning for the depth ranges where q_d ≥ σ_s."""
    failing = np.asarray(deviator) >= np.asarray(strength)
    if not failing.any():
        return []
    return [
        f"the dynamic deviator q_d reaches the static strength σ_s = 2c_u at depths "
        f"{depth_ranges(depth_m, failing)} below the invert: the strain-accumulation laws are "
        "not valid near failure, so the long-term settlement there is outside their range"
    ]


def cap_warnings(depth_m, capped, r_u_max) -> list[str]:
    """One warning for the depth ranges where the generated r_u reached its cap."""
    capped = np.asarray(capped, bool)
    if not capped.any():
        return []
    caps = ", ".join(f"{c:g}" for c in np.unique(np.asarray(r_u_max)[capped]))
    return [
        f"the generated pore-pressure ratio r_u reaches its cap r_u,max = {caps} at depths "
        f"{depth_ranges(depth_m, capped)} below the invert: u_g is held at r_u,max σ′_v0 "
        "there, where the soil approaches cyclic failure and the laws are outside their range"
    ]


def unit_weight_warnings(site, tunnel, soil, gravity: float) -> list[str]:
    """A warning when the layer that holds the tunnel weighs more than 10 % off s.soil's ρ g."""
    index = site.layer_index(tunnel.axis_depth)
    host = site.layers[index]
    soil_weight = soil.density * gravity
    if abs(host.unit_weight - soil_weight) <= UNIT_WEIGHT_TOLERANCE * soil_weight:
        return []
    return [
        f"the layer that holds the tunnel ({host.name!r}, site.layers[{index}].unit_weight = "
        f"{host.unit_weight * 1e-3:.4g} kN/m³) differs by more than "
        f"{UNIT_WEIGHT_TOLERANCE:.0%} from soil.density × g = {soil_weight * 1e-3:.4g} kN/m³: "
        "the dynamic stresses come from the homogeneous s.soil, which should represent the "
        "ground around the tunnel"
    ]
