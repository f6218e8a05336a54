"""The native FE section (model/fe/native.py): its element kernels against closed forms, and the
whole section against the same model in OpenSees.

The pulses and meshes are those of tests/test_fe_section.py (tests/fe_pulses.py: a Hann pulse
at the invert on a 12 m section), so that the comparison runs in seconds.
"""

from __future__ import annotations

import math
import sys

import numpy as np
import pytest
from fe_pulses import DT_S, PLASTIC_MESH, hann_pulse
from system_requirements import needs_opensees

from model.fe.analysis import run_fe
from model.fe.mesh import FEMesh, section_mesh
from model.fe.native import (
    NO_TANGENT,
    beam_matrices,
    elastic_matrix,
    plastic_forces,
    quad_kinematics,
)
from model.params import Scenario

BULK, SHEAR = 13e6, 2.2e6


def _patch():
    """A small graded mesh and its quads' matrices."""
    grid = section_mesh(2.85, 8.0, 1.0, 3.0)
    return grid, *quad_kinematics(grid)


def _nodal_field(grid, gradient):
    """Nodal displacements of the linear field u = gradient · (x, y) (m)."""
    i, j = np.meshgrid(np.arange(grid.n_rings + 1), np.arange(grid.n_theta + 1), indexing="ij")
    x, y = grid.xy(i.ravel(), j.ravel())
    u = np.empty(2 * x.size)
    u[0::2] = gradient[0][0] * x + gradient[0][1] * y
    u[1::2] = gradient[1][0] * x + gradient[1][1] * y
    return u


def test_quads_strain_a_linear_field_exactly_and_integrate_the_area():
    """u = (a x + b y, c x + d y) gives ε_xx = a, ε_yy = d, γ_xy = b + c at every Gauss point
    (bilinear quads are exact for linear fields), and the Gauss weights (det J) add up to the
    area of the half annulus of straight-sided quads, ½ (R² − a²) n_θ sin Δθ (rounding)."""
    grid, dofs, strain_matrix, weight = _patch()
    u = _nodal_field(grid, ((1e-3, 2e-3), (-5e-4, 3e-3)))
    strain = np.einsum("egia,ea->egi", strain_matrix, u[dofs])
    np.testing.assert_allclose(strain[..., 0], 1e-3, rtol=1e-9)
    np.testing.assert_allclose(strain[..., 1], 3e-3, rtol=1e-9)
    np.testing.assert_allclose(strain[..., 2], 1.5e-3, rtol=1e-9)
    a, radius = grid.radii[0], grid.radii[-1]
    area = 0.5 * (radius**2 - a**2) * grid.n_theta * math.sin(grid.thetas[1])
    assert weight.sum() == pytest.approx(area, rel=1e-12)


def _forces(dofs, strain_matrix, weight, u, yield_stress, tangent=NO_TANGENT):
    """Internal forces of every quad made plastic with ``yield_stress`` (N), from no plastic
    strain; with ``tangent`` ((n, 8, 8)), their tangent stiffness is written there."""
    n = dofs.shape[0]
    force = np.zeros(u.size)
    plastic_forces(u, dofs, strain_matrix, weight, np.full(n, yield_stress), BULK, SHEAR,
                   np.zeros((n, 4, 4)), np.zeros((n, 4, 4)), force, tangent)  # fmt: skip
    return force


def test_plastic_quads_are_elastic_below_yield_and_carry_c_u_in_yielding_simple_shear():
    """Below yield the J2 kernel gives K_elastic u (the plane-strain elasticity matrix). In
    simple shear γ beyond yield the radial return leaves τ = c_u = σ_Y/√3 (von Mises in plane
    strain shear: ‖s‖ = √2 τ = √(2/3) σ_Y) and no normal stress, so the nodal forces are the
    elastic ones scaled by c_u / (G γ); OpenSees' J2Plasticity stops 1e-8 of γ short, hence the
    tolerance."""
    grid, dofs, strain_matrix, weight = _patch()
    d_matrix = elastic_matrix(BULK, SHEAR)
    shear_strain = 2e-3
    u = _nodal_field(grid, ((0.0, shear_strain), (0.0, 0.0)))
    elastic = np.zeros(u.size)
    blocks = np.einsum("egia,ij,egjb,eg->eab", strain_matrix, d_matrix, strain_matrix, weight)
    np.add.at(elastic, dofs, np.einsum("eab,eb->ea", blocks, u[dofs]))
    strong = _forces(dofs, strain_matrix, weight, u, 1e12)
    np.testing.assert_allclose(strong, elastic, rtol=0, atol=1e-9 * np.abs(elastic).max())
    c_u = 0.25 * SHEAR * shear_strain
    weak = _forces(dofs, strain_matrix, weight, u, math.sqrt(3.0) * c_u)
    ratio = c_u / (SHEAR * shear_strain)
    np.testing.assert_allclose(weak, ratio * elastic, rtol=0, atol=1e-7 * np.abs(weak).max())


@pytest.mark.parametrize("yield_stress", [1e12, 2e3], ids=["elastic", "yielding"])
def test_the_tangent_of_the_plastic_quads_is_the_derivative_of_their_forces(yield_stress):
    """OpenSees' consistent tangent of the J2 return (used by the static stages and as the
    passage's iteration matrix) is the derivative of the nodal forces: a central difference
    of the forces along a random direction, at a strain state that yields everywhere with
    σ_Y = 2 kPa, agrees with the tangent times that direction to 1e-6 of it (the difference's
    own error is ~1e-9 there; the return's γ(1 − 1e-8) leaves ~1e-8)."""
    grid, dofs, strain_matrix, weight = _patch()
    u = _nodal_field(grid, ((1e-3, 2e-3), (-5e-4, 3e-3)))
    direction = np.random.default_rng(1).standard_normal(u.size) * 1e-6
    tangents = np.empty((dofs.shape[0], 8, 8))
    _forces(dofs, strain_matrix, weight, u, yield_stress, tangents)
    product = np.zeros(u.size)
    np.add.at(product, dofs, np.einsum("eab,eb->ea", tangents, direction[dofs]))
    step = 1e-3
    difference = (
        _forces(dofs, strain_matrix, weight, u + step * direction, yield_stress)
        - _forces(dofs, strain_matrix, weight, u - step * direction, yield_stress)
    ) / (2 * step)
    np.testing.assert_allclose(difference, product, rtol=0, atol=1e-6 * np.abs(product).max())


def test_beams_carry_no_force_in_a_rigid_motion_and_match_the_cantilever():
    """The lining's beam matrices: a rigid rotation of a chain of chords produces no forces, and
    one element clamped at its first node deflects P L³ / (3 E I) under a tip load P."""
    angles = np.linspace(0.0, math.pi, 9)
    xy = np.column_stack([3.0 * np.sin(angles), -3.0 * np.cos(angles)])
    stiffness, length = beam_matrices(xy, 0.3, 3e10, 0.3**3 / 12)
    rotation = 1e-3
    for k in range(len(length)):
        motion = np.concatenate([[-rotation * y, rotation * x, rotation] for x, y in xy[k : k + 2]])
        scale = np.abs(stiffness[k]).max() * np.abs(motion).max()
        np.testing.assert_allclose(stiffness[k] @ motion, 0.0, atol=1e-9 * scale)
    inertia, youngs, span = 0.3**3 / 12, 3e10, 2.0
    single, _ = beam_matrices(np.array([[0.0, 0.0], [span, 0.0]]), 0.3, youngs, inertia)
    tip = np.linalg.solve(single[0][3:, 3:], [0.0, 1e3, 0.0])
    assert tip[1] == pytest.approx(1e3 * span**3 / (3 * youngs * inertia), rel=1e-12)


CASES = {
    "elastic": ("elastic", None),
    "mohr_coulomb": ("mohr_coulomb", None),
    "mohr_coulomb, c_u 5 kPa": ("mohr_coulomb", 5e3),
}
"""Soil law and undrained strength (Pa; None: the paper's c_u = cu_ratio σ′_v0)."""


@pytest.fixture(scope="module")
def both_engines():
    """Two passages of the 100 kN/m pulse on PLASTIC_MESH for each case, on each engine."""
    results = {}
    for case, (law, strength) in CASES.items():
        scenario = Scenario.paper()
        scenario.site.layers[0].undrained_strength = strength
        for engine in ("native", "opensees"):
            results[case, engine] = run_fe(
                scenario,
                law,
                passages=2,
                mesh=PLASTIC_MESH,
                load=(hann_pulse(100e3), DT_S),
                engine=engine,
            )
    return results


@needs_opensees
@pytest.mark.parametrize("case", list(CASES))
def test_the_native_section_is_the_opensees_section(both_engines, case):
    """The same model solved here and by OpenSees: every displacement history below the invert
    and the permanent displacement after each passage agree to 1e-6 of the invert peak
    (measured 1.4e-7, and 2.4e-7 for the weak soil, which yields already in the gravity stage:
    OpenSees holds the fixed degrees of freedom by penalty springs of 1e14 N/m, the native
    section removes them), with the same iterations per step within 10 % (measured 0.2 % and
    6 %: the iterations stop at a tolerance, where the rounding differs)."""
    native, reference = both_engines[case, "native"], both_engines[case, "opensees"]
    scale = reference.peak_disp_m[0]
    np.testing.assert_allclose(native.disp_m, reference.disp_m, rtol=0, atol=1e-6 * scale)
    np.testing.assert_allclose(
        native.residual_per_passage_m, reference.residual_per_passage_m, rtol=0, atol=1e-6 * scale
    )
    assert native.mesh["n_plastic_elements"] == reference.mesh["n_plastic_elements"]
    assert native.mesh["iterations_per_step"] == pytest.approx(
        reference.mesh["iterations_per_step"], rel=0.1
    )
    if CASES[case][0] == "mohr_coulomb":  # the comparison means something: the soil yields
        assert native.residual_per_passage_m[1, 0] > native.residual_per_passage_m[0, 0] > 1e-4


def test_the_native_section_runs_without_openseespy(monkeypatch):
    """OpenSeesPy is not needed by the default engine: with its import blocked, an elastic pulse
    runs and reports the native engine."""
    monkeypatch.setitem(sys.modules, "openseespy.opensees", None)
    result = run_fe(Scenario.paper(), "elastic", mesh=FEMesh(outer_radius=8.0),
                    load=(hann_pulse(), DT_S))  # fmt: skip
    assert result.mesh["engine"] == "native" and result.peak_disp_m[0] > 0


def test_an_unknown_engine_is_refused():
    """The engine is named in the refusal, with the engines there are."""
    with pytest.raises(
        ValueError, match=r"engine = 'abaqus' must be one of \('native', 'opensees'\)"
    ):
        run_fe(Scenario.paper(), load=(hann_pulse(), DT_S), engine="abaqus")
