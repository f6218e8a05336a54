"""Settlement at the invert over years of service: the long-term stage (§10, §14, §15).

S = S_p + S_c. The plastic part S_p = Σ ε_p/100 · Δz sums the cyclic strain-accumulation law
over the depth column (``model.longterm.column``: trapezoidal cells taken layer by layer, so the
sum is the trapezoidal integral from the invert to the deepest depth and does not straddle a
layer boundary). The consolidation part S_c = Σ m_v (u_g − u) Δz is the volume change as the
generated pore pressure u_g drains while traffic goes on (``model.longterm.consolidation``,
solved on a column refined to ``CONSOLIDATION_SPACING_M``). :func:`long_term_settlement` chains
the static state (``geostatic``), the cycles (``cycles``), the strain law (``strain_laws``), the
generation (``pore_pressure``) and the dissipation on the soil stage's deviator
(``model.soil.stresses``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import cumulative_trapezoid

from model.longterm.column import (
    Column,
    layered_column,
    refined_column,
    trapezoid_thickness,
)
from model.longterm.consolidation import solve_consolidation
from model.longterm.cycles import DAYS_PER_YEAR, cycles_per_train, load_cycles
from model.longterm.geostatic import GRAVITY, StaticState, layer_values, static_state
from model.longterm.pore_pressure import (
    consolidation_coefficient,
    layer_compressibility,
    layer_conductivity,
    layer_generated_pore_pressure,
)
from model.longterm.statements import (
    cap_warnings,
    failure_warnings,
    law_parameters,
    law_statement,
    pore_pressure_statement,
    unit_weight_warnings,
)
from model.longterm.strain_laws import permanent_strain_percent
from model.params.site import SECONDS_PER_YEAR
from model.params.soil_sets import strain_law_constants
from model.soil.stresses import StressResponse

__all__ = ["LongTermResult", "long_term_settlement", "trapezoid_thickness"]

SETTLEMENT_FRACTION = 0.9  # the reported depth holds this fraction of the settlement
N_YEARS = 61  # points of the settlement–time curve, log-spaced from one day of traffic
# Largest node spacing of the consolidation column (m): the soil stage's grid (0.5 m by default)
# is divided to this; docs/longterm.md ("Consolidation", grid convergence) gives the error.
CONSOLIDATION_SPACING_M = 0.1


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

    The settlement down to depth d is the trapezoidal ∫₀^d ε/100 dz (a depth given twice, a
    layer boundary, adds nothing between its rows), linear between grid points; NaN when the
    settlement is zero.

    Parameters
    ----------
    depth_m : array_like
        Non-decreasing depths (m).
    strain_percent : array_like
        Strain (%) at those depths.
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
    """Long-term stage result: settlement at the invert over years of service, and its causes.

    Per-depth arrays are on the soil stage's depths plus the layer boundaries inside the column
    (each once, with the lower layer's values); the settlements are the layer-by-layer
    trapezoidal sums (``model.longterm.column``).
    """

    years: np.ndarray
    """(ny,) service time (years of 365 days), log-spaced from one day of traffic to
    longterm.years."""
    settlement_m: np.ndarray
    """(ny,) settlement at the invert S = S_p + S_c (m)."""
    plastic_settlement_m: np.ndarray
    """(ny,) cyclic plastic part S_p = Σ ε_p/100 Δz (m)."""
    consolidation_settlement_m: np.ndarray
    """(ny,) consolidation part S_c = Σ m_v (u_g − u) Δz (m); 0 without pore pressure."""
    depth_m: np.ndarray
    """(nd,) depths below the ring–soil interface (m)."""
    depth_below_ground_m: np.ndarray
    """(nd,) z = H_t + a + d (m)."""
    layer_index: np.ndarray
    """(nd,) index in ``site.layers`` of each depth's layer (a boundary: the lower one)."""
    layer_names: tuple[str, ...]
    """Names of ``site.layers``, top down."""
    layer_boundaries_m: np.ndarray
    """Depths below the invert of the layer boundaries inside the column (m)."""
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
    consolidation_strain_percent: np.ndarray
    """(nd,) consolidation strain ε_c = m_v (u_g − u) after longterm.years (%)."""
    cycles_per_train: np.ndarray
    """(nd,) load cycles per passage."""
    n_cycles: np.ndarray
    """(nd,) N after longterm.years."""
    generated_pore_pressure_Pa: np.ndarray
    """(ny, nd) generated (undrained) excess pore pressure u_g = σ′_v0 r_u (Pa)."""
    excess_pore_pressure_Pa: np.ndarray
    """(ny, nd) excess pore pressure u left after consolidation (Pa)."""
    compressibility_per_Pa: np.ndarray
    """(nd,) volume compressibility m_v (1/Pa)."""
    hydraulic_conductivity_m_per_s: np.ndarray
    """(nd,) hydraulic conductivity k (m/s)."""
    consolidation_coefficient_m2_per_s: np.ndarray
    """(nd,) c_v = k/(m_v γ_w) (m²/s)."""
    depth90_m: float
    """Depth below the invert holding 90 % of the final settlement S (m); NaN if S = 0."""
    law: str
    """Strain law key."""
    law_parameters: dict[str, float]
    """Parameters in force at the invert (a in %, exponents), with ``n`` for Chai & Miura."""
    pore_pressure_law: str
    """Pore-pressure law key ("none", "power", "hyperbolic")."""
    statement: str
    """Which strain law, parameters and traffic produced the result, in words."""
    pore_pressure_statement: str
    """Which pore-pressure law, constants and drainage produced S_c, in words."""
    warnings: tuple[str, ...]

    @property
    def stress_ratio(self) -> np.ndarray:
        """(nd,) q_d/σ_s."""
        return self.deviator_Pa / self.strength_Pa

    @property
    def outside_law_range(self) -> bool:
        """Whether q_d ≥ σ_s somewhere in the column, where the strain laws do not hold."""
        return bool(np.any(self.deviator_Pa >= self.strength_Pa))


def long_term_settlement(stress: StressResponse, scenario) -> LongTermResult:
    """Static state, cycles, laws, consolidation and settlement over service time.

    Parameters
    ----------
    stress : StressResponse
        Deviator under the invert per passage (computed with the soil stage, Results.stress).
    scenario : model.params.Scenario
        Uses longterm, site, tunnel (axis depth, ring radius, lining thickness), soil.density
        (for the unit-weight warning) and train (number of bogies).

    Returns
    -------
    LongTermResult
    """
    lt, site, tunnel = scenario.longterm, scenario.site, scenario.tunnel
    column = _column(stress.depth_m, site, tunnel)
    rows = column.layer_index
    state = static_state(column.depth_m, site, tunnel, rows)
    deviator = column.interpolate(stress.deviator_Pa)
    per_train = column.interpolate(cycles_per_train(stress, scenario))
    years = np.geomspace(min(1.0 / DAYS_PER_YEAR, lt.years), lt.years, N_YEARS)
    n_cycles = load_cycles(years, lt.trains_per_day, per_train)
    laws = [strain_law_constants(lt.soil_set, lt.law, layer) for layer in site.layers]
    a, b, m, n = (np.array([law[name] for law in laws])[rows] for name in ("a", "b", "m", "n"))
    strain = permanent_strain_percent(
        lt.law,
        a,
        b,
        m,
        n,
        deviator,
        state.strength_Pa,
        state.static_deviator_Pa,
        n_cycles,
    )
    plastic = layered_settlement_m(strain, trapezoid_thickness(column.depth_m))
    m_v = layer_compressibility(site, rows, state.vertical_effective_stress_Pa)
    k = layer_conductivity(site, rows, m_v)
    generated, excess, consolidation, capped = _consolidation(
        column, state, deviator, per_train, years, scenario
    )
    strain_c = 100.0 * m_v * (generated[-1] - excess[-1])
    shown = column.reported
    crossed = [site.layers[i] for i in sorted(set(rows.tolist()))]
    depth = column.depth_m[shown]
    cap = layer_values(site, rows, "r_u_max")[shown]
    return LongTermResult(
        years=years,
        settlement_m=plastic + consolidation,
        plastic_settlement_m=plastic,
        consolidation_settlement_m=consolidation,
        depth_m=depth,
        depth_below_ground_m=state.depth_below_ground_m[shown],
        layer_index=rows[shown],
        layer_names=tuple(layer.name for layer in site.layers),
        layer_boundaries_m=column.boundaries_m,
        deviator_Pa=deviator[shown],
        strength_Pa=state.strength_Pa[shown],
        static_deviator_Pa=state.static_deviator_Pa[shown],
        vertical_effective_stress_Pa=state.vertical_effective_stress_Pa[shown],
        strain_percent=strain[-1][shown],
        consolidation_strain_percent=strain_c[shown],
        cycles_per_train=per_train[shown],
        n_cycles=n_cycles[-1][shown],
        generated_pore_pressure_Pa=generated[:, shown],
        excess_pore_pressure_Pa=excess[:, shown],
        compressibility_per_Pa=m_v[shown],
        hydraulic_conductivity_m_per_s=k[shown],
        consolidation_coefficient_m2_per_s=consolidation_coefficient(k, m_v)[shown],
        depth90_m=depth_holding_fraction(column.depth_m, strain[-1] + strain_c),
        law=lt.law,
        law_parameters=law_parameters(lt, site.layers[rows[0]]),
        pore_pressure_law=lt.pore_pressure_law,
        statement=law_statement(lt, crossed, per_train[shown]),
        pore_pressure_statement=pore_pressure_statement(lt, tunnel, crossed),
        warnings=tuple(
            failure_warnings(depth, deviator[shown], state.strength_Pa[shown])
            + cap_warnings(depth, capped[shown], cap)
            + unit_weight_warnings(site, tunnel, scenario.soil, GRAVITY)
        ),
    )


def _column(grid_depth_m, site, tunnel) -> Column:
    """The soil stage's depths with the layer boundaries inside the column added twice."""
    top = tunnel.axis_depth + tunnel.ring_radius
    bottoms = np.array(site.bottoms) - top
    last = len(site.layers) - 1

    def layer_of(depth: float) -> int:
        return min(int(np.searchsorted(bottoms, depth, side="right")), last)

    return layered_column(grid_depth_m, bottoms, layer_of)


def _consolidation(column: Column, state: StaticState, deviator, per_train, years, scenario):
    """Generated and remaining excess pore pressure (ny, nr) on the column's rows, S_c (ny,)
    and the rows where r_u was capped (nr,); zeros without a pore-pressure law."""
    lt, site, tunnel = scenario.longterm, scenario.site, scenario.tunnel
    n_rows = column.depth_m.size
    if lt.pore_pressure_law == "none":
        zeros = np.zeros((years.size, n_rows))
        return zeros, zeros.copy(), np.zeros(years.size), np.zeros(n_rows, bool)
    fine, coarse_rows = refined_column(column, CONSOLIDATION_SPACING_M)
    fine_state = static_state(fine.depth_m, site, tunnel, fine.layer_index)
    fine_ratio = fine.interpolate(deviator) / fine_state.strength_Pa
    fine_per_train = fine.interpolate(per_train)

    def generated(times_s):
        cycles = load_cycles(times_s / SECONDS_PER_YEAR, lt.trains_per_day, fine_per_train)
        return layer_generated_pore_pressure(
            lt.pore_pressure_law,
            site,
            fine.layer_index,
            fine_state.vertical_effective_stress_Pa,
            fine_ratio,
            cycles,
        ).pressure_Pa

    m_v = layer_compressibility(site, fine.layer_index, fine_state.vertical_effective_stress_Pa)
    leaking = lt.invert_drainage == "leaking"
    solution = solve_consolidation(
        fine.depth_m,
        m_v,
        layer_conductivity(site, fine.layer_index, m_v),
        generated,
        years * SECONDS_PER_YEAR,
        top=lt.invert_drainage,
        bottom=lt.base_drainage,
        lining_permeability_m_per_s=lt.lining_permeability if leaking else None,
        lining_thickness_m=tunnel.thickness if leaking else None,
    )
    capped = layer_generated_pore_pressure(
        lt.pore_pressure_law,
        site,
        column.layer_index,
        state.vertical_effective_stress_Pa,
        deviator / state.strength_Pa,
        load_cycles(years[-1:], lt.trains_per_day, per_train),
    ).capped
    return (
        solution.generated_Pa[:, coarse_rows],
        solution.pore_pressure_Pa[:, coarse_rows],
        solution.settlement_m,
        capped,
    )
