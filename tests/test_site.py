"""Site profile (docs/model.md §14) and the long-term stage's pore pressure and consolidation (§15).

By hand first (the layered effective stress, the generated pore pressure), then the one-layer
regression of the paper case, the layer boundaries in the depth column, an independent solution
of the consolidation driven by the stage's own generated pore pressure, the warnings, the
calibration of the pore-pressure law, the borehole CSV and bad input. The solver itself is
checked against closed forms in tests/test_consolidation.py.
"""

import math

import numpy as np
import pytest
import scipy.integrate
import scipy.sparse

from model.longterm.calibration import fit_pore_pressure_law, load_triaxial_csv
from model.longterm.column import layered_column, trapezoid_thickness
from model.longterm.geostatic import UNIT_WEIGHT_WATER, vertical_stresses
from model.longterm.settlement import N_YEARS, long_term_settlement
from model.params import DATA_DIR, Layer, Scenario, ScenarioError, Site
from model.params.borehole import load_borehole_csv, parse_borehole_csv
from model.params.site import SECONDS_PER_YEAR
from model.pipeline import run

TOP = 15.0 + 2.85  # axis depth + ring radius of the paper case: the invert below ground (m)


@pytest.fixture(scope="module")
def paper():
    """The paper case after 10 years, default long-term settings (pore pressure on)."""
    scenario = Scenario.paper()
    scenario.longterm.years = 10.0
    return run(scenario, cache=None)


def _scenario(results, **longterm) -> Scenario:
    """A fresh copy of the results' scenario with long-term parameters changed."""
    scenario = results.scenario
    scenario.longterm.param.update(**longterm)
    return scenario


# ---- the static state by hand ------------------------------------------------------------------
def test_two_layer_effective_stress_by_hand():
    """Clay 10 m of 18 kN/m³ over sand of 20 kN/m³, water table 2 m below the surface:
    z = 1 m: σ_v = 18 kPa, u_0 = 0, σ′ = 18 kPa (above the water the unit weight as is);
    z = 5 m: σ_v = 90, u_0 = 9.81 · 3 = 29.43, σ′ = 60.57 kPa;
    z = 10 m: σ_v = 180, u_0 = 78.48, σ′ = 101.52 kPa;
    z = 15 m: σ_v = 180 + 5 · 20 = 280, u_0 = 127.53, σ′ = 152.47 kPa (exact arithmetic)."""
    site = Site(
        layers=[
            Layer(name="clay", thickness=10.0, unit_weight=18e3),
            Layer(name="sand", thickness=50.0, unit_weight=20e3),
        ],
        water_table_depth=2.0,
    )
    total, pore, effective = vertical_stresses([1.0, 5.0, 10.0, 15.0], site)
    np.testing.assert_allclose(total, [18e3, 90e3, 180e3, 280e3], rtol=1e-14)
    np.testing.assert_allclose(pore, [0.0, 29.43e3, 78.48e3, 127.53e3], rtol=1e-14)
    np.testing.assert_allclose(effective, [18e3, 60.57e3, 101.52e3, 152.47e3], rtol=1e-14)
    assert [site.layer_index(z) for z in (9.99, 10.0, 10.01)] == [0, 1, 1]


def test_the_stage_reports_the_layered_static_state(paper):
    """Clay (c_u/σ′ = 0.2) to 25 m over silt (c_u/σ′ = 0.3), water table 3 m: at each reported
    depth σ′_v0 = 17.658 · min(z, 25) + 19 · max(0, z − 25) − 9.81 (z − 3) kPa, the strength
    2 c_u of its layer, the boundary depth (25 m, 7.15 m below the invert) taking the silt."""
    scenario = _scenario(paper)
    scenario.site.param.update(
        layers=[
            Layer(name="clay", thickness=25.0, cu_ratio=0.2),
            Layer(name="silt", thickness=75.0, unit_weight=19e3, cu_ratio=0.3, soil_class="ML"),
        ],
        water_table_depth=3.0,
    )
    lt = long_term_settlement(paper.stress, scenario)
    z = lt.depth_below_ground_m
    by_hand = 17658.0 * np.minimum(z, 25.0) + 19e3 * np.maximum(0.0, z - 25.0) - 9810.0 * (z - 3.0)
    np.testing.assert_allclose(lt.vertical_effective_stress_Pa, by_hand, rtol=1e-12)
    boundary = int(np.flatnonzero(np.isclose(lt.depth_m, 7.15))[0])
    assert lt.layer_boundaries_m.tolist() == pytest.approx([7.15])
    assert lt.layer_index[boundary - 1 : boundary + 2].tolist() == [0, 1, 1]
    ratio = np.where(lt.layer_index == 0, 0.2, 0.3)
    np.testing.assert_allclose(lt.strength_Pa, 2.0 * ratio * by_hand, rtol=1e-12)
    assert np.all(np.diff(lt.depth_m) > 0.0)  # each depth reported once
    assert lt.layer_names == ("clay", "silt")
    assert "clay (soil class CH) a = 1.2 %" in lt.statement
    assert "silt (soil class ML) a = 0.64 %" in lt.statement


# ---- the one-layer regression --------------------------------------------------------------------
def test_one_default_layer_reproduces_the_homogeneous_plastic_settlement(paper):
    """pore_pressure_law = 'none': S = S_p = 1.17 mm after 10 years on the paper case (a pinned
    regression, docs/longterm.md; nothing exact exists), and bit for bit the homogeneous formulas
    of wave 2: σ′_v0 = ρ g z − ρ_w g z (water at the surface), σ_s = 2 · 0.22 σ′_v0,
    N = 200 · 365 · 10 · 12, ε_p = 1.2 (q_d/σ_s)^2.4 N^0.18, S = Σ ε_p/100 Δz."""
    scenario = _scenario(paper, pore_pressure_law="none")
    lt = long_term_settlement(paper.stress, scenario)
    assert round(lt.plastic_settlement_m[-1] * 1e3, 2) == 1.17
    assert lt.plastic_settlement_m[-1] == pytest.approx(1.16581e-3, rel=1e-5)
    np.testing.assert_array_equal(lt.settlement_m, lt.plastic_settlement_m)
    assert np.all(lt.consolidation_settlement_m == 0.0)
    assert np.all(lt.excess_pore_pressure_Pa == 0.0)
    depth = paper.stress.depth_m
    z = TOP + depth
    effective = 1800.0 * 9.81 * z - 1000.0 * 9.81 * z
    strain = 1.2 * (paper.stress.deviator_Pa / (2.0 * 0.22 * effective)) ** 2.4
    strain = strain * (200.0 * 365.0 * 10.0 * 12.0) ** 0.18
    cells = 0.5 * (np.diff(depth, append=depth[-1]) + np.diff(depth, prepend=depth[0]))
    assert lt.plastic_settlement_m[-1] == pytest.approx(strain / 100.0 @ cells, rel=1e-13)


def test_default_settlement_is_plastic_plus_consolidation(paper):
    """With the default (illustrative) pore-pressure constants the plastic part is the same
    number and S = S_p + S_c at every year (exact); S_c > 0 and grows; the summary reports the
    parts; arrays over years and depths are (n_years, n_depth)."""
    lt = paper.longterm
    none = long_term_settlement(paper.stress, _scenario(paper, pore_pressure_law="none"))
    np.testing.assert_array_equal(lt.plastic_settlement_m, none.plastic_settlement_m)
    np.testing.assert_array_equal(
        lt.settlement_m, lt.plastic_settlement_m + lt.consolidation_settlement_m
    )
    assert np.all(np.diff(lt.consolidation_settlement_m) > 0.0)
    n_depth = lt.depth_m.size
    assert lt.generated_pore_pressure_Pa.shape == lt.excess_pore_pressure_Pa.shape
    assert lt.generated_pore_pressure_Pa.shape == (N_YEARS, n_depth)
    for name in ("compressibility_per_Pa", "consolidation_coefficient_m2_per_s", "layer_index"):
        assert getattr(lt, name).shape == (n_depth,), name
    summary = paper.summary()
    assert summary["longterm_settlement_m"] == pytest.approx(
        summary["longterm_plastic_settlement_m"] + summary["longterm_consolidation_settlement_m"],
        rel=1e-15,
    )
    assert "Illustrative defaults, not from a test or a source: a_u, b_u, m_u, m_v, k of soft" in (
        lt.pore_pressure_statement
    )


def test_generated_pore_pressure_by_hand(paper):
    """u_g = σ′_v0 a_u (q_d/σ_s)^m_u N^b_u at every reported depth and year (power, the default
    constants 0.05, 0.15, 1.5), and the hyperbolic σ′_v0 (q_d/σ_s)^m_u N/(α + βN) (α = 10⁴,
    β = 1); exact arithmetic to rounding (rel 1e-12)."""
    lt = paper.longterm
    cycles = 200.0 * 365.0 * lt.years[:, None] * lt.cycles_per_train
    ratio, stress = lt.stress_ratio, lt.vertical_effective_stress_Pa
    np.testing.assert_allclose(
        lt.generated_pore_pressure_Pa, stress * 0.05 * ratio**1.5 * cycles**0.15, rtol=1e-12
    )
    hyperbolic = long_term_settlement(
        paper.stress, _scenario(paper, pore_pressure_law="hyperbolic")
    )
    expected = stress * ratio**1.5 * cycles / (1e4 + cycles)
    np.testing.assert_allclose(hyperbolic.generated_pore_pressure_Pa, expected, rtol=1e-12)


# ---- the layer boundaries in the column ---------------------------------------------------------
def test_a_boundary_is_two_rows_and_the_sums_are_taken_layer_by_layer():
    """Grid 0, 1, 2, 3 m; a boundary at 1.5 m: rows 0, 1, 1.5 (upper), 1.5 (lower), 2, 3; the
    values at grid depths are copied, the boundary's interpolated; a property that jumps there
    is integrated exactly layer by layer: f = 1 above, 3 below → 1.5 · 1 + 1.5 · 3 = 6 m."""
    grid = np.array([0.0, 1.0, 2.0, 3.0])
    column = layered_column(grid, [1.5, 10.0], lambda d: int(d >= 1.5))
    assert column.depth_m.tolist() == [0.0, 1.0, 1.5, 1.5, 2.0, 3.0]
    assert column.layer_index.tolist() == [0, 0, 0, 1, 1, 1]
    assert column.reported.tolist() == [True, True, False, True, True, True]
    assert column.interpolate(np.array([0.0, 10.0, 20.0, 30.0])).tolist() == [
        0.0,
        10.0,
        15.0,
        15.0,
        20.0,
        30.0,
    ]
    jump = np.where(column.layer_index == 0, 1.0, 3.0)
    assert trapezoid_thickness(column.depth_m) @ jump == pytest.approx(6.0, rel=1e-15)
    on_grid = layered_column(grid, [2.0, 10.0], lambda d: int(d >= 2.0))
    assert on_grid.depth_m.tolist() == [0.0, 1.0, 2.0, 2.0, 3.0]
    assert on_grid.interpolate(np.arange(4.0)).tolist() == [0.0, 1.0, 2.0, 2.0, 3.0]
    at_base = layered_column(grid, [3.0, 10.0], lambda d: int(d >= 3.0))
    assert at_base.layer_index.tolist() == [0, 0, 0, 0]  # the base's half cell lies above it


def test_plastic_settlement_of_two_layers_is_the_layerwise_trapezoid(paper):
    """S_p of clay over silt equals the trapezoidal integral over each layer's own depths, the
    boundary closing the upper layer with the upper law and opening the lower one with the lower
    law (q_d interpolated linearly there), to rounding (rel 1e-12)."""
    scenario = _scenario(paper, pore_pressure_law="none")
    scenario.site.layers = [
        Layer(name="clay", thickness=25.0),
        Layer(name="silt", thickness=75.0, unit_weight=19e3, soil_class="ML", cu_ratio=0.3),
    ]
    lt = long_term_settlement(paper.stress, scenario)
    depth, deviator = paper.stress.depth_m, paper.stress.deviator_Pa
    boundary = 25.0 - TOP
    total = 0.0
    for rows, (a, b, m), ratio in (
        (depth < boundary, (1.2, 0.18, 2.4), 0.22),
        (depth > boundary, (0.64, 0.10, 1.7), 0.3),
    ):
        d = np.sort(np.concatenate([depth[rows], [boundary]]))
        q = np.interp(d, depth, deviator)
        z = TOP + d
        sigma = 17658.0 * np.minimum(z, 25.0) + 19e3 * np.maximum(z - 25.0, 0.0) - 9810.0 * z
        cycles = 200.0 * 365.0 * 10.0 * 12.0
        total += np.trapezoid(a * (q / (2 * ratio * sigma)) ** m * cycles**b / 100.0, d)
    assert lt.plastic_settlement_m[-1] == pytest.approx(total, rel=1e-12)


# ---- consolidation against an independent solution -----------------------------------------------
def _method_of_lines(lt, scenario, n_nodes=701):
    """u (n_years, n_nodes) and S_c (n_years,) on a uniform grid, integrated by scipy's BDF.

    The same equation, m_v ∂u/∂t = ∂/∂z (k/γ_w ∂u/∂z) + m_v ∂u_g/∂t, discretised independently
    of the stage: its own uniform grid, central differences with the arithmetic mean of k
    (uniform here), an adaptive implicit integrator, and u_g from the stage's reported values
    (linear in depth between reported depths, linear in time between reported years, from 0 at
    t = 0).
    """
    times = np.concatenate([[0.0], lt.years * SECONDS_PER_YEAR])
    z = np.linspace(lt.depth_m[0], lt.depth_m[-1], n_nodes)
    h = z[1] - z[0]
    m_v = np.interp(z, lt.depth_m, lt.compressibility_per_Pa)
    k = np.interp(z, lt.depth_m, lt.hydraulic_conductivity_m_per_s)
    generated = np.vstack([np.zeros(lt.depth_m.size), lt.generated_pore_pressure_Pa])
    generated = np.array([np.interp(z, lt.depth_m, row) for row in generated])
    rate = np.diff(generated, axis=0) / np.diff(times)[:, None]
    face = 0.5 * (k[1:] + k[:-1]) / (UNIT_WEIGHT_WATER * h)
    storage = m_v * h * np.r_[0.5, np.ones(n_nodes - 2), 0.5]
    diagonal = np.r_[face, 0.0] + np.r_[0.0, face]
    lt_params = scenario.longterm
    if lt_params.invert_drainage == "leaking":
        diagonal[0] += lt_params.lining_permeability / (
            UNIT_WEIGHT_WATER * scenario.tunnel.thickness
        )
    stiffness = scipy.sparse.diags([diagonal, -face, -face], [0, 1, -1]).tocsr()
    free = np.ones(n_nodes, bool)
    free[0] = lt_params.invert_drainage != "drained"
    free[-1] = lt_params.base_drainage != "drained"
    stiffness, storage_free = stiffness[free][:, free], storage[free]
    matrix = scipy.sparse.diags(1.0 / storage_free) @ (-stiffness)
    u = np.zeros((lt.years.size, n_nodes))
    state = np.zeros(free.sum())
    for i in range(lt.years.size):  # one interval at a time: the source jumps at the samples
        source = rate[i, free]
        solution = scipy.integrate.solve_ivp(
            lambda t, y, source=source: matrix @ y + source,
            (times[i], times[i + 1]),
            state,
            method="BDF",
            jac=matrix,
            rtol=1e-8,
            atol=1e-8,
        )
        state = solution.y[:, -1]
        u[i, free] = state
    settlement = (generated[1:] - u) @ (m_v * h * np.r_[0.5, np.ones(n_nodes - 2), 0.5])
    return z, u, settlement


@pytest.mark.parametrize(
    "invert, base",
    [
        ("leaking", "drained"),
        pytest.param("sealed", "drained", marks=pytest.mark.slow),
        pytest.param("drained", "sealed", marks=pytest.mark.slow),
    ],
)
def test_consolidation_matches_an_independent_solution_of_the_same_equation(paper, invert, base):
    """The paper case after 10 years: S_c within 1 % of the method-of-lines solution at every
    year from one month on, and u within 1 % of its largest value from one month on (achieved
    0.3–0.6 % and 0.1–0.4 %; the reference's linear-in-time u_g between the reported years is
    most of the difference, which is why the first days are left out: u_g grows as N^0.15,
    steeply at first, and the first interval of the reference spreads it over a day)."""
    scenario = _scenario(paper, invert_drainage=invert, base_drainage=base)
    lt = long_term_settlement(paper.stress, scenario)
    z, u, settlement = _method_of_lines(lt, scenario)
    later = lt.years >= 1.0 / 12.0
    settlement_error = np.abs(lt.consolidation_settlement_m - settlement) / np.abs(settlement)
    u_reference = np.array([np.interp(lt.depth_m, z, row) for row in u])
    u_error = np.abs(lt.excess_pore_pressure_Pa - u_reference).max(axis=1) / np.abs(
        u_reference
    ).max(axis=1)
    print(
        f"achieved ({invert}/{base}): |ΔS_c|/S_c {settlement_error[later].max():.1e}, "
        f"|Δu|/max u {u_error[later].max():.1e}"
    )
    assert settlement_error[later].max() <= 1e-2
    assert u_error[later].max() <= 1e-2


def test_drainage_orders_the_consolidation_settlement(paper):
    """More drainage, more consolidation settlement at every year: drained ≥ leaking ≥ sealed
    invert (the lining conductance between the two limits), and a drained base ≥ a sealed one."""
    settlement = {
        (invert, base): long_term_settlement(
            paper.stress, _scenario(paper, invert_drainage=invert, base_drainage=base)
        ).consolidation_settlement_m
        for invert in ("sealed", "leaking", "drained")
        for base in ("sealed", "drained")
    }
    for base in ("sealed", "drained"):
        assert np.all(settlement[("drained", base)] >= settlement[("leaking", base)])
        assert np.all(settlement[("leaking", base)] >= settlement[("sealed", base)])
    for invert in ("sealed", "leaking", "drained"):
        assert np.all(settlement[(invert, "drained")] >= settlement[(invert, "sealed")])


# ---- warnings -----------------------------------------------------------------------------------
def test_the_cap_on_the_pore_pressure_ratio_is_applied_and_named(paper):
    """a_u = 10: r_u exceeds 0.9 near the invert; u_g there is 0.9 σ′_v0 (exact) and a warning
    names the depth range."""
    scenario = _scenario(paper)
    scenario.site.layers[0].a_u = 10.0
    lt = long_term_settlement(paper.stress, scenario)
    capped = lt.generated_pore_pressure_Pa[-1] == 0.9 * lt.vertical_effective_stress_Pa
    assert capped[0] and not capped[-1]
    assert np.all(lt.generated_pore_pressure_Pa <= 0.9 * lt.vertical_effective_stress_Pa)
    (warning,) = [w for w in lt.warnings if "r_u,max" in w]
    assert f"depths 0–{lt.depth_m[np.flatnonzero(capped)[-1]]:.3g} m below the invert" in warning


def test_a_host_layer_heavier_than_the_soil_model_is_warned_about(paper):
    scenario = _scenario(paper)
    assert not long_term_settlement(paper.stress, scenario).warnings
    scenario.site.layers[0].unit_weight = 20e3  # 13 % above 1800 kg/m³ × g
    (warning,) = long_term_settlement(paper.stress, scenario).warnings
    assert "site.layers[0].unit_weight = 20 kN/m³" in warning and "17.66 kN/m³" in warning


# ---- calibration of the pore-pressure law --------------------------------------------------------
def test_pore_pressure_law_is_calibrated_from_the_fifth_column():
    """The shipped synthetic file (docs/make_triaxial_example.py: a_u = 0.25, b_u = 0.12,
    m_u = 1.2, 5 % noise): the fit recovers each within 3 standard errors."""
    data = load_triaxial_csv(DATA_DIR / "triaxial_synthetic.csv")
    np.testing.assert_allclose(data.pore_pressure_ratio[0], 2.7118 / 75.0, rtol=1e-12)
    fit = fit_pore_pressure_law(data.n_cycles, data.pore_pressure_ratio, data.stress_ratio)
    for name, true in (("a_u", 0.25), ("b_u", 0.12), ("m_u", 1.2)):
        assert abs(fit[name] - true) <= 3.0 * fit[f"{name}_se"], name


def test_hyperbolic_pore_pressure_law_is_recovered_from_exact_data():
    """r_u = q^1.3 N/(500 + 1.5 N) at two stress levels, no noise: α, β, m_u to 1e-6."""
    ratio, cycles = np.meshgrid([0.3, 0.6], np.geomspace(1.0, 1e5, 15), indexing="ij")
    pore = ratio**1.3 * cycles / (500.0 + 1.5 * cycles)
    fit = fit_pore_pressure_law(cycles.ravel(), pore.ravel(), ratio.ravel(), "hyperbolic")
    assert (fit["alpha_u"], fit["beta_u"], fit["m_u"]) == pytest.approx((500.0, 1.5, 1.3), rel=1e-6)


def test_an_implausible_pore_pressure_fit_is_refused():
    """Pore pressures falling with N give b_u < 0: refused at the fit, with the bounds."""
    ratio, cycles = np.meshgrid([0.3, 0.6], np.geomspace(1.0, 1e4, 5), indexing="ij")
    pore = 0.1 * ratio * cycles**-0.1
    with pytest.raises(ValueError, match=r"b_u = -0\.1, outside the plausible range \[0, 1\)"):
        fit_pore_pressure_law(cycles.ravel(), pore.ravel(), ratio.ravel())


# ---- the borehole CSV ----------------------------------------------------------------------------
def test_the_example_borehole_loads_in_si_units():
    layers = load_borehole_csv(DATA_DIR / "borehole_example.csv")
    assert [layer.name for layer in layers] == [
        "made ground",
        "soft clay",
        "silty clay",
        "stiff clay",
    ]
    soft = layers[1]
    assert (soft.thickness, soft.unit_weight, soft.compressibility) == (20.0, 17700.0, 1e-7)
    assert soft.soil_class == "CH" and soft.a_u == Layer.param["a_u"].default
    assert "ILLUSTRATIVE" in (DATA_DIR / "borehole_example.csv").read_text().splitlines()[0]


def test_borehole_columns_are_read_by_name_and_unit():
    """Any order, units after an underscore, a space or in brackets, SI or display units; an
    empty cell takes the default and 'none' clears an optional property."""
    text = (
        "unit_weight (N/m³),thickness_m,name,consolidation_coefficient [m²/year],"
        "compressibility_1/MPa\n"
        "18000,12,clay,31.536,none\n"
        "19.5e3,88,sand,,0.02\n"
    )
    clay, sand = parse_borehole_csv(text)
    assert (clay.name, clay.thickness, clay.unit_weight) == ("clay", 12.0, 18000.0)
    assert clay.consolidation_coefficient == pytest.approx(1e-6, rel=1e-12)
    assert clay.compressibility is None and sand.compressibility == pytest.approx(2e-8)
    assert sand.consolidation_coefficient is None


@pytest.mark.parametrize(
    "text, message",
    [
        ("name,thickness_m\nclay,5\n", r"b\.csv: the header on line 1 has no column unit_weight"),
        ("name,thickness,unit_weight_kN/m3\n", r"column 2 \('thickness'\): no unit"),
        ("name,thickness_m,unit_weight_kN/m3,colour\n", r"column 4: 'colour' names no layer"),
        ("name,thickness_m,unit_weight_kN/m3\n", r"no layer below the header"),
        (
            "# a comment\nname,thickness_m,unit_weight_kN/m3\nclay,5,18\nsilt,-2,19\n",
            r"line 4 \(layer 'silt'\), column 'thickness_m': -2 is outside .*\(0, 1000\] m",
        ),
        (
            "name,thickness_m,unit_weight_kN/m3\nclay,5,180\n",
            r"line 2 \(layer 'clay'\), column 'unit_weight_kN/m3': 180 is outside .*\(0, 30\] kN",
        ),
        ("name,thickness_m,unit_weight_kN/m3\nclay,five,18\n", r"'five' is not a number"),
        ("name,thickness_m,unit_weight_kN/m3\nclay,5\n", r"line 2: 2 values, expected 3"),
    ],
)
def test_bad_borehole_csvs_are_refused_naming_line_and_column(text, message):
    with pytest.raises(ValueError, match=message):
        parse_borehole_csv(text, "b.csv")


# ---- bad profiles -------------------------------------------------------------------------------
def test_a_negative_thickness_is_refused_naming_the_layer():
    with pytest.raises(ValueError, match=r"layer 'silt': layer\.thickness = -1 m is outside"):
        Layer(name="silt", thickness=-1.0)
    data = {"site": {"layers": [{"name": "clay"}, {"name": "silt", "thickness": -1.0}]}}
    with pytest.raises(ValueError, match=r"site\.layers\[1\]\.thickness = -1 m .*layer 'silt'"):
        Scenario.from_dict(data)
    with pytest.raises(KeyError, match=r"unknown layer property.*'colour'.*site\.layers\[0\]"):
        Scenario.from_dict({"site": {"layers": [{"name": "clay", "colour": "grey"}]}})


def test_a_profile_short_of_the_deepest_depth_is_refused_naming_the_last_layer():
    """Layers reaching 40 m; the column ends 15 + 2.85 + 35 = 52.85 m below the surface."""
    scenario = Scenario.paper()
    scenario.site.layers = [Layer(name="clay", thickness=25.0), Layer(name="silt", thickness=15.0)]
    with pytest.raises(
        ScenarioError,
        match=r"site\.layers reach 40 m .* deepest depth 52\.85 m .*\('silt', "
        r"site\.layers\[1\]\.thickness = 15 m\) at least 27\.85 m thick",
    ):
        run(scenario, cache=None)


def test_a_water_table_below_the_profile_is_refused():
    scenario = Scenario.paper()
    scenario.site.water_table_depth = 150.0
    with pytest.raises(ScenarioError, match=r"site\.water_table_depth = 150 m lies below"):
        scenario.validate()


# ---- scenario files -----------------------------------------------------------------------------
def test_layers_go_through_json_and_old_files_load_into_the_layers():
    """A two-layer site round-trips through JSON; a wave-2 file's long-term strength, law
    constants and water table go to every layer and to the site."""
    scenario = Scenario.paper()
    scenario.site.layers = [Layer(name="clay", thickness=20.0), Layer(name="sand", cu_ratio=0.4)]
    again = Scenario.from_json(scenario.to_json())
    assert again.to_dict() == scenario.to_dict()
    assert (
        again.site.layers[1].cu_ratio == 0.4 and again.site.layers[1] is not scenario.site.layers[1]
    )
    old = Scenario.from_dict(
        {"longterm": {"cu_ratio": 0.3, "soil_class": "CL", "water_table_depth": 2.0, "years": 5}}
    )
    (layer,) = old.site.layers
    assert (layer.cu_ratio, layer.soil_class, old.site.water_table_depth) == (0.3, "CL", 2.0)
    assert old.longterm.years == 5


def test_consolidation_constants_per_depth(paper):
    """m_v from C_r and e0 where m_v is not given: 0.434 C_r/((1 + e0) σ′_v0) (exact form
    C_r/((1 + e0) σ′_v0 ln 10)); c_v = k/(m_v γ_w), or k = c_v m_v γ_w from a given c_v."""
    scenario = _scenario(paper)
    scenario.site.layers[0].param.update(compressibility=None, consolidation_coefficient=2e-6)
    lt = long_term_settlement(paper.stress, scenario)
    m_v = 0.05 / (2.2 * lt.vertical_effective_stress_Pa * math.log(10.0))
    np.testing.assert_allclose(lt.compressibility_per_Pa, m_v, rtol=1e-14)
    np.testing.assert_allclose(lt.consolidation_coefficient_m2_per_s, 2e-6, rtol=1e-14)
    np.testing.assert_allclose(lt.hydraulic_conductivity_m_per_s, 2e-6 * m_v * 9810.0, rtol=1e-14)
