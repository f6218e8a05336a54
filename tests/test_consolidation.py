"""Consolidation of train-generated pore pressure (docs/model.md §15) against closed forms.

model.longterm.consolidation (the solver) and model.longterm.pore_pressure (generation,
compressibility): Terzaghi's series for each drainage case, steady states under constant
generation (one and two layers, the leaking lining), the two-layer eigenfunction series, the
observed orders in space and time, conservation of water, then the generation laws and bad
input. Every tolerance is stated where it is asserted; "achieved" lines print the measured
errors (shown with ``pytest -rP``). Arrays are (times, depths). Units SI; γ_w = 9.81 kN/m³.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg
import scipy.optimize
from scipy.special import hyp1f1

from model.longterm.column import trapezoid_thickness
from model.longterm.consolidation import solve_consolidation
from model.longterm.cycles import load_cycles
from model.longterm.geostatic import UNIT_WEIGHT_WATER
from model.longterm.pore_pressure import (
    consolidation_coefficient,
    generated_pore_pressure_hyperbolic,
    generated_pore_pressure_power,
    hydraulic_conductivity,
    recompression_compressibility,
)
from model.params.site import SECONDS_PER_YEAR

THICKNESS = 10.0  # m, column of the single-layer checks
CV = 1e-7  # m²/s (≈ 3 m²/year)
MV = 1e-6  # 1/Pa (1 /MPa)
K = CV * MV * UNIT_WEIGHT_WATER  # m/s
LOAD = 1.0e4  # Pa, instantaneous uniform u_g of the Terzaghi checks


def uniform_load(depth, value=LOAD):
    """u_g(z, t) = value for t ≥ 0 (an instantaneous undrained load at t = 0⁺)."""
    return lambda t: np.full((np.size(t), np.size(depth)), value)


def linear_growth(depth, rate):
    """u_g(z, t) = rate(z) · t: a constant generation rate g = ∂u_g/∂t (Pa/s)."""
    rate = np.broadcast_to(np.asarray(rate, dtype=float), (np.size(depth),))
    return lambda t: np.multiply.outer(t, rate)


def terzaghi_degree(time_factor, n_terms=2000):
    """Terzaghi's U(T_v) = 1 − Σ 2/M² exp(−M² T_v), M = π(2m + 1)/2, uniform initial u."""
    m = np.arange(n_terms)
    big_m = np.pi * (2 * m + 1) / 2
    return 1.0 - np.exp(-np.multiply.outer(time_factor, big_m**2)) @ (2.0 / big_m**2)


def terzaghi_pressure(depth, time_factor, drainage_length, n_terms=4000):
    """u/u0 = Σ 2/M sin(M z/H_dr) exp(−M² T_v), z from the drained face; (nT, nz)."""
    m = np.arange(n_terms)
    big_m = np.pi * (2 * m + 1) / 2
    modes = np.sin(np.multiply.outer(np.asarray(depth) / drainage_length, big_m)) * (2 / big_m)
    return np.exp(-np.multiply.outer(time_factor, big_m**2)) @ modes.T


def observed_order(step, error):
    """Slope of log(error) against log(step), np.polyfit degree 1."""
    return float(np.polyfit(np.log(step), np.log(error), 1)[0])


# ---- Terzaghi: instantaneous uniform load -----------------------------------------------------
@pytest.mark.parametrize(
    ("top", "bottom", "drainage_length"),
    [
        ("drained", "sealed", THICKNESS),
        ("sealed", "drained", THICKNESS),
        ("drained", "drained", THICKNESS / 2),
    ],
)
def test_terzaghi_degree_of_consolidation(top, bottom, drainage_length):
    """U(T_v) = S_c/(m_v u0 H) within 1e-3 of the series for T_v in [1e-3, 2], 151 nodes."""
    depth = np.linspace(0.0, THICKNESS, 151)
    factor = np.geomspace(1e-3, 2.0, 40)
    result = solve_consolidation(
        depth, MV, K, uniform_load(depth), factor * drainage_length**2 / CV, top=top, bottom=bottom
    )
    degree = result.settlement_m / (MV * LOAD * THICKNESS)
    error = np.abs(degree - terzaghi_degree(factor)).max()
    print(f"achieved: Terzaghi {top}/{bottom}: max |ΔU| = {error:.2e} ({result.n_steps} steps)")
    assert error <= 1e-3


def test_terzaghi_on_an_uneven_grid():
    """Randomly jittered spacing (±40 %), 151 nodes: |ΔU| ≤ 1e-3 and u within 3e-3 u0."""
    rng = np.random.default_rng(7)
    spacing = 1.0 + 0.4 * rng.uniform(-1.0, 1.0, 150)
    depth = np.concatenate([[0.0], np.cumsum(spacing)]) * THICKNESS / spacing.sum()
    factor = np.geomspace(1e-3, 2.0, 40)
    result = solve_consolidation(depth, MV, K, uniform_load(depth), factor * THICKNESS**2 / CV)
    degree_error = np.abs(result.settlement_m / (MV * LOAD * THICKNESS) - terzaghi_degree(factor))
    pressure_error = np.abs(
        result.pore_pressure_Pa / LOAD - terzaghi_pressure(depth, factor, THICKNESS)
    )[factor >= 1e-2]
    print(
        f"achieved: uneven grid max |ΔU| = {degree_error.max():.2e}, "
        f"max |Δu|/u0 (T_v ≥ 0.01) = {pressure_error.max():.2e}"
    )
    assert degree_error.max() <= 1e-3
    assert pressure_error.max() <= 3e-3


def test_rannacher_start_damps_the_crank_nicolson_oscillation():
    """A first step as long as the first output: pure CN leaves u < 0 next to the drained
    invert (the stiff modes' amplification → −1), the backward-Euler start keeps 0 ≤ u ≤ u0
    (the maximum principle, to 1e-12 u0)."""
    depth = np.linspace(0.0, THICKNESS, 151)
    times = np.geomspace(1e-3, 2.0, 40) * THICKNESS**2 / CV
    pure = solve_consolidation(
        depth, MV, K, uniform_load(depth), times, first_step_s=times[0], backward_euler_steps=0
    )
    damped = solve_consolidation(depth, MV, K, uniform_load(depth), times, first_step_s=times[0])
    print(f"achieved: min u/u0 pure CN {pure.pore_pressure_Pa.min() / LOAD:.3f}")
    assert pure.pore_pressure_Pa.min() < -0.1 * LOAD
    assert damped.pore_pressure_Pa.min() >= -1e-12 * LOAD
    assert damped.pore_pressure_Pa.max() <= LOAD * (1 + 1e-12)


# ---- steady state under a constant generation rate --------------------------------------------
STEADY_TIME = 20.0 * THICKNESS**2 / CV  # T_v = 20: the slowest transient mode is e^{−49}


@pytest.mark.parametrize(
    ("top", "bottom", "profile"),
    [  # u·c_v/g as a function of z (from the invert) and H
        ("drained", "sealed", lambda z, h: h * z - z**2 / 2),
        ("sealed", "drained", lambda z, h: (h**2 - z**2) / 2),
        ("drained", "drained", lambda z, h: z * (h - z) / 2),
    ],
)
def test_steady_state_with_constant_generation(top, bottom, profile):
    """c_v u'' = −g: the parabola on an uneven grid, to 1e-8 of its peak (the FV is exact on
    quadratics; what is left is round-off, u being the small difference of u_g and the water
    expelled); and the outflow rate equals the generation m_v g H to 1e-8."""
    rate = 1e-3  # Pa/s
    depth = THICKNESS * np.linspace(0.0, 1.0, 61) ** 1.5
    times = STEADY_TIME * np.array([1.0, 1.01])
    result = solve_consolidation(
        depth, MV, K, linear_growth(depth, rate), times, top=top, bottom=bottom
    )
    exact = rate / CV * profile(depth, THICKNESS)
    error = np.abs(result.pore_pressure_Pa[-1] - exact).max() / exact.max()
    outflow = result.outflow_top_m + result.outflow_bottom_m
    outflow_rate = np.diff(outflow)[0] / np.diff(times)[0]
    print(f"achieved: steady {top}/{bottom}: {error:.1e}")
    assert error <= 1e-8
    assert outflow_rate == pytest.approx(MV * rate * THICKNESS, rel=1e-8)


TWO_LAYERS = {  # upper soft clay over a stiffer, more permeable layer; per layer
    "thickness_m": (4.0, 6.0),
    "compressibility_per_Pa": (1e-6, 2e-7),
    "cv_m2_per_s": (1e-7, 1e-6),  # k ratio 2, c_v ratio 10
}


def two_layer_column(n_upper, n_lower, repeat_boundary=True):
    """Depths with the boundary repeated (or once, taking the lower layer) and row properties."""
    upper, lower = TWO_LAYERS["thickness_m"]
    top = np.linspace(0.0, upper, n_upper)
    bottom = np.linspace(upper, upper + lower, n_lower)
    depth = np.concatenate([top, bottom if repeat_boundary else bottom[1:]])
    in_lower = np.arange(depth.size) >= (n_upper if repeat_boundary else n_upper - 1)
    mv = np.where(in_lower, *TWO_LAYERS["compressibility_per_Pa"][::-1])
    cv = np.where(in_lower, *TWO_LAYERS["cv_m2_per_s"][::-1])
    return depth, in_lower, mv, hydraulic_conductivity(cv, mv)


def slowest_time_s():
    """(Σ H_i/√c_v,i)²: the diffusion time scale of the whole two-layer column (s)."""
    return (
        sum(
            h / math.sqrt(c)
            for h, c in zip(TWO_LAYERS["thickness_m"], TWO_LAYERS["cv_m2_per_s"], strict=True)
        )
        ** 2
    )


def test_two_layer_steady_state_continuity_of_flux():
    """Two layers, each with its own generation rate g_i, drained top, sealed base, at
    t = 20 × the slowest diffusion time. Closed form: the upward flux F(z) = ∫_z^H m_v g and
    u(z) = ∫_0^z γ_w F/k, piecewise quadratic with u' jumping by k_upper/k_lower. With the
    boundary as a repeated depth the FV is exact: 1e-8 of the peak (round-off)."""
    (h1, h2), (m1, m2) = TWO_LAYERS["thickness_m"], TWO_LAYERS["compressibility_per_Pa"]
    g1, g2 = 1e-3, 3e-3  # Pa/s
    depth, in_lower, mv, k = two_layer_column(17, 25)
    k1, k2 = k[0], k[-1]
    result = solve_consolidation(
        depth, mv, k, linear_growth(depth, np.where(in_lower, g2, g1)), [20 * slowest_time_s()]
    )
    upper = UNIT_WEIGHT_WATER / k1 * (m1 * g1 * (h1 * depth - depth**2 / 2) + m2 * g2 * h2 * depth)
    s = depth - h1
    at_boundary = UNIT_WEIGHT_WATER / k1 * (m1 * g1 * h1**2 / 2 + m2 * g2 * h2 * h1)
    lower = at_boundary + UNIT_WEIGHT_WATER / k2 * m2 * g2 * (h2 * s - s**2 / 2)
    exact = np.where(in_lower, lower, upper)
    error = np.abs(result.pore_pressure_Pa[0] - exact).max() / exact.max()
    print(f"achieved: two-layer steady state {error:.1e}")
    assert error <= 1e-8


# ---- two layers: the eigenfunction series -----------------------------------------------------
def two_layer_series(depth, times, thickness, compressibility, conductivity, cv, n_modes=600):
    """u(z, t)/u0 and S_c(t)/u0 after a unit instantaneous load, drained top, sealed base.

    Modes X = sin(ω₁z) in the upper layer and A cos(ω₂(H − z)) in the lower, ω_i = √(λ/c_v,i):
    u and k u' continuous at z = H₁ when k₁ω₁ cos(ω₁H₁) cos(ω₂H₂) = k₂ω₂ sin(ω₁H₁) sin(ω₂H₂),
    A from whichever of the two conditions is better conditioned. Orthogonal with weight m_v;
    coefficients a_n = ∫ m_v X_n / ∫ m_v X_n². Roots bracketed on a grid 1/50 of their mean
    spacing and refined by brentq. Returns (u (nt, nz), S_c (nt,), Parseval ratio).
    """
    (h1, h2), (m1, m2), (k1, k2) = thickness, compressibility, conductivity
    a1, a2 = (1.0 / math.sqrt(c) for c in cv)

    def characteristic(s):
        return k1 * a1 * math.cos(a1 * s * h1) * math.cos(a2 * s * h2) - k2 * a2 * math.sin(
            a1 * s * h1
        ) * math.sin(a2 * s * h2)

    spacing = math.pi / (a1 * h1 + a2 * h2)
    grid = np.arange(1e-9, (n_modes + 2) * spacing, spacing / 50)
    values = np.array([characteristic(s) for s in grid])
    brackets = np.flatnonzero(np.sign(values[:-1]) != np.sign(values[1:]))[:n_modes]
    root = np.array(
        [scipy.optimize.brentq(characteristic, grid[i], grid[i + 1], xtol=1e-15) for i in brackets]
    )
    w1, w2 = a1 * root, a2 * root
    by_value = np.cos(w2 * h2)  # A cos(ω₂H₂) = sin(ω₁H₁)
    by_flux = k2 * w2 * np.sin(w2 * h2) / (k1 * w1)  # A by_flux = cos(ω₁H₁)
    amp1 = 1.0
    amp2 = np.where(
        np.abs(by_value) >= np.abs(by_flux),
        np.sin(w1 * h1) / np.where(by_value == 0.0, 1.0, by_value),
        np.cos(w1 * h1) / np.where(by_flux == 0.0, 1.0, by_flux),
    )
    integral = m1 * amp1 * (1 - np.cos(w1 * h1)) / w1 + m2 * amp2 * np.sin(w2 * h2) / w2
    norm = m1 * amp1**2 * (h1 / 2 - np.sin(2 * w1 * h1) / (4 * w1)) + m2 * amp2**2 * (
        h2 / 2 + np.sin(2 * w2 * h2) / (4 * w2)
    )
    coefficient = integral / norm
    z = np.asarray(depth)[:, None]
    modes = np.where(z <= h1, amp1 * np.sin(z * w1), amp2 * np.cos((h1 + h2 - z) * w2))
    decay = np.exp(-np.multiply.outer(root**2, times))
    storage = m1 * h1 + m2 * h2
    return (
        ((modes * coefficient) @ decay).T,
        storage - (integral * coefficient) @ decay,
        float((coefficient**2 * norm).sum() / storage),
    )


def test_two_layer_series_reduces_to_terzaghi():
    """The helper with equal layers: U within 1e-6 of Terzaghi's series for T_v ≥ 1e-3."""
    factor = np.geomspace(1e-3, 2.0, 20)
    _, settlement, _ = two_layer_series(
        [0.0], factor * THICKNESS**2 / CV, (4.0, 6.0), (MV, MV), (K, K), (CV, CV)
    )
    assert np.abs(settlement / (MV * THICKNESS) - terzaghi_degree(factor)).max() <= 1e-6


def two_layer_errors(n_upper, n_lower, repeat_boundary, times):
    """Max |Δu|/u0 at t ≥ times[5] and max |ΔS_c|/S_c(∞) of the FV against the series."""
    depth, _, mv, k = two_layer_column(n_upper, n_lower, repeat_boundary)
    result = solve_consolidation(
        depth, mv, k, uniform_load(depth, 1.0), times, steps_per_decade=200
    )
    pressure, settlement, _ = two_layer_series(
        depth,
        times,
        TWO_LAYERS["thickness_m"],
        TWO_LAYERS["compressibility_per_Pa"],
        (k[0], k[-1]),
        TWO_LAYERS["cv_m2_per_s"],
    )
    ultimate = float(np.dot(TWO_LAYERS["thickness_m"], TWO_LAYERS["compressibility_per_Pa"]))
    return (
        np.abs(result.pore_pressure_Pa - pressure)[5:].max(),
        np.abs(result.settlement_m - settlement).max() / ultimate,
    )


TWO_LAYER_TIMES = np.geomspace(1e-3, 3.0, 30) * slowest_time_s()


def test_two_layer_transient_against_eigenfunction_series():
    """161 nodes (65 + 97, boundary repeated): |Δu| ≤ 1e-3 u0 and |ΔS_c| ≤ 1e-3 S_c(∞) for
    t/(Σ H_i/√c_v,i)² in [1e-3, 3] (u from the 6th time on, 3.6e-3). Series: 600 modes, whose
    Parseval sum holds 99.9 % of ∫ m_v u0²."""
    _, _, parseval = two_layer_series(
        [0.0],
        TWO_LAYER_TIMES[:1],
        TWO_LAYERS["thickness_m"],
        TWO_LAYERS["compressibility_per_Pa"],
        tuple(
            hydraulic_conductivity(TWO_LAYERS["cv_m2_per_s"], TWO_LAYERS["compressibility_per_Pa"])
        ),
        TWO_LAYERS["cv_m2_per_s"],
    )
    pressure_error, settlement_error = two_layer_errors(65, 97, True, TWO_LAYER_TIMES)
    print(
        f"achieved: two-layer transient |Δu|/u0 {pressure_error:.1e}, "
        f"|ΔS_c|/S_c(∞) {settlement_error:.1e}, Parseval {parseval:.5f}"
    )
    assert parseval >= 0.999
    assert pressure_error <= 1e-3
    assert settlement_error <= 1e-3


def test_two_layer_spatial_order():
    """Spacing halved four times: order 2 ± 0.2 with the boundary as a repeated depth, 1 ± 0.2
    with the boundary node carrying the lower layer only (interface half a spacing off)."""
    sizes = [(9, 13), (17, 25), (33, 49), (65, 97)]
    spacing = 4.0 / (np.array([n for n, _ in sizes]) - 1)
    for repeat, expected in ((True, 2.0), (False, 1.0)):
        errors = np.array([two_layer_errors(*n, repeat, TWO_LAYER_TIMES) for n in sizes])
        orders = [observed_order(spacing, errors[:, i]) for i in range(2)]
        print(
            f"achieved: two-layer order, boundary repeated={repeat}: u {orders[0]:.2f}, "
            f"S_c {orders[1]:.2f}"
        )
        assert orders == pytest.approx([expected, expected], abs=0.2)


# ---- the leaking invert (Robin) ---------------------------------------------------------------
LINING_THICKNESS = 0.3  # m


def leaking(depth, load, times, lining_permeability):
    """The uniform column under ``load`` with a leaking invert and a sealed base."""
    return solve_consolidation(
        depth,
        MV,
        K,
        load,
        times,
        top="leaking",
        bottom="sealed",
        lining_permeability_m_per_s=lining_permeability,
        lining_thickness_m=LINING_THICKNESS,
    )


def test_leaking_invert_limits():
    """k_l = 1e-30 m/s gives the sealed invert and k_l = 1e+30 m/s the drained one (S_c and u
    to 1e-9 of the load); in between S_c grows with k_l."""
    depth = np.linspace(0.0, THICKNESS, 101)
    times = np.geomspace(1e-3, 2.0, 30) * THICKNESS**2 / CV
    load = uniform_load(depth)
    sealed = solve_consolidation(depth, MV, K, load, times, top="sealed", bottom="drained")
    drained = solve_consolidation(depth, MV, K, load, times, top="drained", bottom="drained")
    previous = None
    for permeability, limit in (
        (1e-30, sealed),
        (1e-12, None),
        (1e-10, None),
        (1e-8, None),
        (1e30, drained),
    ):
        result = solve_consolidation(
            depth,
            MV,
            K,
            load,
            times,
            top="leaking",
            bottom="drained",
            lining_permeability_m_per_s=permeability,
            lining_thickness_m=LINING_THICKNESS,
        )
        if limit is not None:
            scale = MV * LOAD * THICKNESS
            assert np.abs(result.settlement_m - limit.settlement_m).max() <= 1e-9 * scale
            assert np.abs(result.pore_pressure_Pa - limit.pore_pressure_Pa).max() <= 1e-9 * LOAD
        if previous is not None:
            assert np.all(result.settlement_m >= previous.settlement_m)
        previous = result


def test_leaking_invert_steady_state():
    """Constant generation g, sealed base: u = g/c_v (Hz − z²/2) + g H t_l k_s/(c_v k_l) (the
    lining passes the generated water m_v g H at u_top = m_v g H γ_w t_l/k_l), to 1e-8;
    the water leaving through the lining at the rate (k_l/(γ_w t_l)) u_top, to 1e-8."""
    rate, permeability = 1e-3, 1e-10  # Pa/s, m/s: Biot number (k_l/t_l) H/k_s = 3.4, so the
    # slowest mode decays as exp(−1.45 T_v), e^{−29} at T_v = 20
    depth = np.linspace(0.0, THICKNESS, 41)
    times = STEADY_TIME * np.array([1.0, 1.01])
    result = leaking(depth, linear_growth(depth, rate), times, permeability)
    exact = rate / CV * (THICKNESS * depth - depth**2 / 2) + (
        rate * THICKNESS * LINING_THICKNESS * K / (CV * permeability)
    )
    error = np.abs(result.pore_pressure_Pa[-1] - exact).max() / exact.max()
    outflow_rate = np.diff(result.outflow_top_m)[0] / np.diff(times)[0]
    lining_rate = permeability / (UNIT_WEIGHT_WATER * LINING_THICKNESS) * exact[0]
    print(f"achieved: leaking steady state {error:.1e}")
    assert error <= 1e-8
    assert outflow_rate == pytest.approx(lining_rate, rel=1e-8)
    assert outflow_rate == pytest.approx(MV * rate * THICKNESS, rel=1e-8)


# ---- convergence ------------------------------------------------------------------------------
def test_spatial_order_terzaghi():
    """Single drainage, nodes 11 … 161 (spacing halved 4 times), 400 steps per decade (time
    error < 1e-6): max nodal |Δu|/u0 at T_v = 0.05, 0.2, 0.5 falls as h^(2 ± 0.1); 1e-5 on
    161 nodes."""
    factor = np.array([0.05, 0.2, 0.5])
    counts = np.array([11, 21, 41, 81, 161])
    errors = []
    for count in counts:
        depth = np.linspace(0.0, THICKNESS, count)
        result = solve_consolidation(
            depth, MV, K, uniform_load(depth), factor * THICKNESS**2 / CV, steps_per_decade=400
        )
        exact = terzaghi_pressure(depth, factor, THICKNESS)
        errors.append(np.abs(result.pore_pressure_Pa / LOAD - exact).max())
    order = observed_order(THICKNESS / (counts - 1), errors)
    print(f"achieved: spatial order {order:.2f}, errors {', '.join(f'{e:.1e}' for e in errors)}")
    assert order == pytest.approx(2.0, abs=0.1)
    assert errors[-1] <= 1.2e-5


def semi_discrete_modes(depth, drained_top):
    """Exact-in-time reference of the FV system on a uniform one-layer column, sealed base.

    C = m_v Δz, K the three-point conductance matrix (conductance k/(γ_w h)), the drained node
    removed; returns (λ, V) with K V = C V Λ, Vᵀ C V = I, and the kept node indices.
    """
    n = depth.size
    h = depth[1] - depth[0]
    g = K / (UNIT_WEIGHT_WATER * h)
    stiffness = g * (
        np.diag(np.r_[1.0, 2.0 * np.ones(n - 2), 1.0]) - np.eye(n, k=1) - np.eye(n, k=-1)
    )
    storage = np.diag(MV * np.r_[h / 2, h * np.ones(n - 2), h / 2])
    kept = np.arange(1 if drained_top else 0, n)
    eigenvalues, vectors = scipy.linalg.eigh(
        stiffness[np.ix_(kept, kept)], storage[np.ix_(kept, kept)]
    )
    return eigenvalues, vectors, storage[np.ix_(kept, kept)], kept


@pytest.mark.parametrize("load", ["step", "power"])
def test_time_order_crank_nicolson(load):
    """41 nodes, drained invert; error at T_v = 1e-2 … 1 against the exact time integral of the
    same FV system (eigenvectors; the power law t^0.2 by M(1, 1.2, −λt)), steps per decade
    5 … 80: the error falls as (Δt/t)^(2 ± 0.2), Δt/t measured as decades / steps."""
    depth = np.linspace(0.0, THICKNESS, 41)
    times = np.geomspace(1e-2, 1.0, 5) * THICKNESS**2 / CV
    eigenvalues, vectors, storage, kept = semi_discrete_modes(depth, drained_top=True)
    projection = vectors.T @ storage @ np.ones(kept.size)
    if load == "step":
        generation = uniform_load(depth, 1.0)
        amplitude = np.exp(-np.outer(eigenvalues, times))
    else:
        exponent = 0.2

        def generation(t):
            return np.multiply.outer((t / times[-1]) ** exponent, np.ones(depth.size))

        decay = hyp1f1(1.0, 1.0 + exponent, -np.outer(eigenvalues, times))
        amplitude = (times / times[-1]) ** exponent * decay
    exact = vectors @ (projection[:, None] * amplitude)
    relative_step, errors = [], []
    for steps in (5, 10, 20, 40, 80):
        result = solve_consolidation(depth, MV, K, generation, times, steps_per_decade=steps)
        errors.append(np.abs(result.pore_pressure_Pa[:, kept].T - exact).max())
        relative_step.append(math.log10(times[-1] / (times[0] * 1e-3)) / result.n_steps)
    order = observed_order(relative_step, errors)
    print(
        f"achieved: time order ({load}) {order:.2f}, errors {', '.join(f'{e:.1e}' for e in errors)}"
    )
    assert order == pytest.approx(2.0, abs=0.2)


# ---- conservation -----------------------------------------------------------------------------
def train_column(n_nodes=151):
    """A 35 m two-layer column below the invert loaded by traffic (illustrative values).

    ``n_nodes`` depths plus the repeated layer boundary at 8 m; σ′_v0 = 120 kPa + 8 kPa/m · z;
    q_d/σ_s decaying from 0.3 with depth; power-law generation (a_u, b_u, m_u) = (0.05, 0.15,
    1.5), the lower layer half as susceptible; 200 trains/day × 6 cycles; m_v from C_r.
    """
    depth = np.linspace(0.0, 35.0, n_nodes)
    depth = np.sort(np.concatenate([depth, [8.0, 8.0]]))
    in_lower = np.arange(depth.size) > np.searchsorted(depth, 8.0)
    stress = 1.2e5 + 8e3 * depth
    ratio = 0.3 * np.exp(-depth / 5.0)
    mv = recompression_compressibility(np.where(in_lower, 0.02, 0.05), 1.2, stress)
    k = np.where(in_lower, 5e-9, 1e-9)
    a_u = np.where(in_lower, 0.025, 0.05)

    def generation(t_s):
        cycles = load_cycles(t_s / SECONDS_PER_YEAR, 200.0, np.full(depth.size, 6.0))
        return generated_pore_pressure_power(stress, ratio, cycles, a_u, 0.15, 1.5).pressure_Pa

    return depth, mv, k, generation


YEARS = np.geomspace(1.0 / 365.0, 100.0, 61)


def test_conservation_of_water():
    """d/dt ∫ m_v u dz = ∫ m_v ∂u_g/∂t dz − outflow, in its integrated form: the water stored,
    Σ m_v Δz u, equals the water generated, Σ m_v Δz u_g, less the water expelled through the
    lining and the base, to 1e-12 of the water generated (round-off), at every output time;
    so S_c equals the expelled water. Leaking invert, drained base, two layers."""
    depth, mv, k, generation = train_column()
    result = solve_consolidation(
        depth,
        mv,
        k,
        generation,
        YEARS * SECONDS_PER_YEAR,
        top="leaking",
        bottom="drained",
        lining_permeability_m_per_s=1e-10,
        lining_thickness_m=0.3,
    )
    weight = mv * trapezoid_thickness(depth)
    stored, generated = result.pore_pressure_Pa @ weight, result.generated_Pa @ weight
    expelled = result.outflow_top_m + result.outflow_bottom_m
    imbalance = np.abs(stored - (generated - expelled)) / generated
    print(
        f"achieved: conservation {imbalance.max():.1e}; S_c(100 y) = "
        f"{result.settlement_m[-1] * 1e3:.2f} mm, lining {result.outflow_top_m[-1] * 1e3:.2f} mm"
    )
    assert imbalance.max() <= 1e-12
    assert np.all(result.outflow_top_m > 0.0) and np.all(np.diff(result.outflow_top_m) > 0.0)
    np.testing.assert_allclose(result.settlement_m, expelled, rtol=0, atol=1e-12 * generated.max())


def test_default_steps_on_traffic_loading():
    """The default 20 steps per decade on the traffic case: S_c(t) within 1e-4 of its final
    value against 640 steps per decade, and within 3e-4 of itself at each time from 1 year."""
    depth, mv, k, generation = train_column()
    times = YEARS * SECONDS_PER_YEAR
    default = solve_consolidation(depth, mv, k, generation, times)
    fine = solve_consolidation(depth, mv, k, generation, times, steps_per_decade=640)
    error = np.abs(default.settlement_m - fine.settlement_m)
    late = YEARS >= 1.0
    relative = (error / fine.settlement_m)[late].max()
    print(
        f"achieved: default steps ({default.n_steps}) |ΔS_c|/S_c(100 y) "
        f"{error.max() / fine.settlement_m[-1]:.1e}, relative from 1 y {relative:.1e}"
    )
    assert error.max() <= 1e-4 * fine.settlement_m[-1]
    assert relative <= 3e-4


# ---- generation, compressibility, the column --------------------------------------------------
def test_cycle_count():
    """N = trains/day · 365 · years · cycles per train (docs/model.md §10), (n_years, n_depth)."""
    cycles = load_cycles(np.array([1.0, 2.0]), 100.0, np.array([4.0, 6.0]))
    np.testing.assert_allclose(cycles, [[146000.0, 219000.0], [292000.0, 438000.0]], rtol=1e-15)


def test_power_generation_and_cap():
    """Hand values of σ′_v0 a_u (q_d/σ_s)^m_u N^b_u; the cap 0.9 σ′_v0 and its depths."""
    stress, ratio = np.array([1e5, 2e5]), np.array([0.5, 0.1])
    result = generated_pore_pressure_power(stress, ratio, [0.0, 1e4, 1e8], 0.2, 0.25, 1.0)
    raw = 0.2 * ratio * np.array([0.0, 10.0, 100.0])[:, None]
    np.testing.assert_allclose(result.pressure_Pa, stress * np.minimum(raw, 0.9), rtol=1e-14)
    assert result.capped.tolist() == [True, True]
    assert generated_pore_pressure_power(stress, ratio, [1e4], 0.2, 0.25, 1.0).capped.tolist() == [
        True,
        False,
    ]


def test_hyperbolic_generation():
    """N/(α + βN) → N/α for small N and 1/β for large N, times (q_d/σ_s)^m_u; per-depth
    constants; per-depth N (nt, nd)."""
    stress, ratio = np.array([1e5, 1e5]), np.array([0.4, 0.4])
    cycles = np.array([[1.0, 2.0], [1e12, 2e12]])
    result = generated_pore_pressure_hyperbolic(stress, ratio, cycles, [1e4, 2e4], 2.0, 0.5)
    small = stress * ratio**0.5 * np.array([1.0 / 1e4, 2.0 / 2e4])
    np.testing.assert_allclose(result.pressure_Pa[0], small, rtol=1e-3)
    np.testing.assert_allclose(result.pressure_Pa[1], stress * ratio**0.5 / 2.0, rtol=1e-7)
    assert not result.capped.any()


def test_compressibility_and_consolidation_coefficient():
    """m_v = 0.434 C_r/((1 + e0) σ′_v0) (to 1e-3, and to 1e-6 the secant of
    e = e0 − C_r log10(σ′/σ′_v0) over ±0.01 %); c_v = k/(m_v γ_w) and back (1e-15)."""
    mv = recompression_compressibility(0.05, 1.2, 1e5)
    assert mv == pytest.approx(0.434 * 0.05 / (2.2 * 1e5), rel=1e-3)
    d = 1e-4 * 1e5
    secant = 0.05 * math.log10((1e5 + d) / (1e5 - d)) / (2.2 * 2 * d)
    assert mv == pytest.approx(secant, rel=1e-6)
    cv = consolidation_coefficient(1e-9, mv)
    assert cv == pytest.approx(1e-9 / (mv * 9.81e3), rel=1e-15)
    assert hydraulic_conductivity(cv, mv) == pytest.approx(1e-9, rel=1e-15)


def test_cell_thickness():
    """Increasing depths: half the neighbouring spacings; a repeated depth: Σ f Δz is the
    trapezoidal integral layer by layer (1e-14)."""
    depth = np.array([0.0, 1.0, 3.0, 3.5])
    np.testing.assert_allclose(trapezoid_thickness(depth), [0.5, 1.5, 1.25, 0.25])
    layered = np.array([0.0, 1.0, 2.0, 2.0, 4.0])
    values = np.array([1.0, 2.0, 3.0, 10.0, 20.0])  # a jump at z = 2
    expected = np.trapezoid(values[:3], layered[:3]) + np.trapezoid(values[3:], layered[3:])
    assert trapezoid_thickness(layered) @ values == pytest.approx(expected, rel=1e-14)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"depth_m": [0.0, 2.0, 1.0]}, "non-decreasing"),
        ({"depth_m": [0.0, 1.0, 1.0, 1.0, 2.0]}, "repeat once"),
        ({"depth_m": [0.0, 0.0, 1.0]}, "repeat once"),
        ({"compressibility_per_Pa": -1.0}, "compressibility"),
        ({"hydraulic_conductivity_m_per_s": [1e-9, 1e-9]}, "one value per depth"),
        ({"top": "open"}, "top"),
        ({"bottom": "leaking"}, "bottom"),
        ({"top": "leaking"}, "needs lining"),
        ({"lining_thickness_m": 0.3}, "need top='leaking'"),
        ({"times_s": [2.0, 1.0]}, "times_s"),
        ({"generated_Pa": np.zeros((2, 3))}, "generated_times_s"),
        ({"generated_Pa": np.zeros((2, 3)), "generated_times_s": [1.0, 5.0]}, "start at 0"),
        ({"generated_Pa": lambda t: np.zeros(t.size)}, "must return"),
    ],
)
def test_invalid_input(change, message):
    """Each bad input is refused with a ValueError naming it."""
    arguments = {
        "depth_m": [0.0, 1.0, 2.0],
        "compressibility_per_Pa": MV,
        "hydraulic_conductivity_m_per_s": K,
        "generated_Pa": lambda t: np.ones((t.size, 3)),
        "times_s": [1.0, 2.0],
    } | change
    with pytest.raises(ValueError, match=message):
        solve_consolidation(**arguments)


def test_array_generation_equals_callable_at_its_samples():
    """u_g given as samples (linear in time between them, each sample a step end) and as the
    same piecewise-linear callable: equal to 1e-12."""
    depth = np.linspace(0.0, THICKNESS, 31)
    sample_times = np.array([0.0, 1e5, 1e6, 1e7, 1e8])
    samples = np.outer([0.0, 3e3, 5e3, 6e3, 6.5e3], 1.0 + depth)
    times = np.array([5e5, 1e7, 5e7])
    from_array = solve_consolidation(depth, MV, K, samples, times, generated_times_s=sample_times)

    def piecewise(t):
        return np.array([np.interp(t, sample_times, column) for column in samples.T]).T

    steps_through_samples = np.union1d(times, sample_times[1:-1])
    from_callable = solve_consolidation(depth, MV, K, piecewise, steps_through_samples)
    np.testing.assert_allclose(
        from_array.pore_pressure_Pa,
        from_callable.pore_pressure_Pa[np.isin(steps_through_samples, times)],
        rtol=0,
        atol=1e-12 * samples.max(),
    )
