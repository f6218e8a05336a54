"""Permanent settlement at the invert over years of service: the long-term stage (§10).

S = Σ ε_p/100 · Δz over the depth grid (trapezoidal cell thicknesses, so the sum is the
trapezoidal integral from the invert to the deepest depth), and the depth within which 90 % of
S accumulates. :func:`long_term_settlement` chains the static state (``geostatic``), the cycles
(``cycles``) and the strain law (``strain_laws``) on the soil stage's deviator
(``model.soil.stresses``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import cumulative_trapezoid

from model.longterm.cycles import DAYS_PER_YEAR, cycles_per_train, load_cycles
from model.longterm.geostatic import static_state
from model.longterm.strain_laws import LAW_NAMES, permanent_strain_percent
from model.soil.stresses import StressResponse

SETTLEMENT_FRACTION = 0.9  # the reported depth holds this fraction of the settlement
N_YEARS = 61  # points of the settlement–time curve, log-spaced from one day of traffic


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


def long_term_settlement(stress: StressResponse, scenario) -> LongTermResult:
    """Static state, cycles, strain law and settlement over service time (``model.longterm``).

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
    per_train = cycles_per_train(stress, scenario)
    years = np.geomspace(min(1.0 / DAYS_PER_YEAR, lt.years), lt.years, N_YEARS)
    n_cycles = load_cycles(years, lt.trains_per_day, per_train)
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
