"""The FE section solved in this package: the OpenSees model of ``model.fe.build``, assembled
with NumPy/SciPy and stepped with a Numba kernel for the plastic soil.

The same model, element by element, as ``model.fe.build`` builds in OpenSees (docs/fe_section.md):

- bilinear quads (2 × 2 Gauss points, plane strain, 1 m thick; OpenSees ``quad``), elastic
  (E, ν) or J2-plastic (K, G, σ_Y = √3 c_u, perfectly plastic: OpenSees ``J2Plasticity`` with
  its radial return, including its γ(1 − 10⁻⁸));
- the soil's lumped mass on the nodes, the lining's elastic beams (lumped mass ρh L/2 on the
  translations), the soil–lining links (LINK_STIFFNESS in series with the PENALTY of the
  ``equalDOF`` ties, as OpenSees' penalty handler assembles them) and the viscous–spring
  boundary (springs and dashpots in the radial and tangential directions, no Rayleigh damping:
  OpenSees' ``zeroLength`` default);
- Rayleigh damping a₀M + a₁K_init on the nodal masses, the quads and the beams;
- the same stages: gravity with the anchor (10 load steps for the plastic law), the lining and
  the boundary measuring from the gravity state, a static equilibrium, then each passage with
  Newmark's average acceleration, the iteration on the tangent of the passage's start,
  factorised once, with the same convergence test (``NormDispOrUnbalance``), and a static
  equilibrium after it; the static stages by Newton's method on J2's consistent tangent.

What differs from OpenSees: the fixed degrees of freedom are removed instead of held by penalty
springs of 10¹⁴ N/m (which let them move by ~10⁻⁹ m under their reactions). Measured against
OpenSees on the tests' meshes: the histories agree to ~10⁻⁷ of the peak
(tests/test_fe_native.py).

Why: a passage of the paper case with Mohr–Coulomb soil spends most of its time in OpenSees'
per-element updates (docs/fe_section.md, Speed); here the elastic elements are one sparse
product and only the plastic ones are integrated point by point.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu

from model.fe.build import (
    DISP_TOLERANCE,
    LINK_STIFFNESS,
    MAX_ITERATIONS,
    PENALTY,
    PLASTIC_GRAVITY_STEPS,
    FEConvergenceError,
    anchor_stiffness,
    boundary_coefficients,
    gravity_loads,
    lining_beam,
    plastic_soil,
)
from model.fe.mesh import GAUSS_POINTS, SectionMesh, body_loads
from model.params import Scenario

STATIC_TOLERANCE = 1e-10
"""Static stages: converged when Newton's displacement correction (m, 2-norm) is below this
(OpenSees' test: 10⁻⁹ m in the gravity stage, 10⁻¹⁰ m in the static equilibrium)."""
NO_TANGENT = np.empty((0, 8, 8))
"""``plastic_forces``' tangent argument when none is wanted."""


# ---- element matrices -------------------------------------------------------------------------
def quad_kinematics(mesh: SectionMesh):
    """Strain–displacement matrices of every quad at its 2 × 2 Gauss points.

    Returns
    -------
    dofs : ndarray of int
        (n_elements, 8) global degrees of freedom (u_x, u_y of the nodes (i, j), (i + 1, j),
        (i + 1, j + 1), (i, j + 1)), elements numbered i · n_θ + j.
    strain_matrix : ndarray
        (n_elements, 4, 3, 8): ε_xx, ε_yy, γ_xy at each Gauss point per unit nodal displacement.
    weight : ndarray
        (n_elements, 4): det J at each Gauss point (m², unit weights, 1 m thick).
    """
    nr, nt = mesh.n_rings, mesh.n_theta
    i, j = np.meshgrid(np.arange(nr), np.arange(nt), indexing="ij")
    corners = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)]
    nodes = np.stack([(a * (nt + 1) + b).ravel() for a, b in corners], axis=1)
    x = np.stack([mesh.xy(a, b)[0].ravel() for a, b in corners], axis=1)
    y = np.stack([mesh.xy(a, b)[1].ravel() for a, b in corners], axis=1)
    dofs = np.stack([2 * nodes, 2 * nodes + 1], axis=2).reshape(-1, 8)
    strain_matrix = np.zeros((nodes.shape[0], 4, 3, 8))
    weight = np.empty((nodes.shape[0], 4))
    signs_s, signs_t = np.array([-1.0, 1.0, 1.0, -1.0]), np.array([-1.0, -1.0, 1.0, 1.0])
    for g, (s, t) in enumerate((s, t) for t in GAUSS_POINTS for s in GAUSS_POINTS):
        dn_ds = 0.25 * signs_s * (1 + signs_t * t)
        dn_dt = 0.25 * signs_t * (1 + signs_s * s)
        j11, j12 = x @ dn_ds, y @ dn_ds
        j21, j22 = x @ dn_dt, y @ dn_dt
        det = j11 * j22 - j12 * j21
        dn_dx = (j22[:, None] * dn_ds - j12[:, None] * dn_dt) / det[:, None]
        dn_dy = (-j21[:, None] * dn_ds + j11[:, None] * dn_dt) / det[:, None]
        strain_matrix[:, g, 0, 0::2] = dn_dx
        strain_matrix[:, g, 1, 1::2] = dn_dy
        strain_matrix[:, g, 2, 0::2] = dn_dy
        strain_matrix[:, g, 2, 1::2] = dn_dx
        weight[:, g] = det
    return dofs, strain_matrix, weight


def elastic_matrix(bulk: float, shear: float) -> np.ndarray:
    """Plane-strain elasticity (σ_xx, σ_yy, τ_xy from ε_xx, ε_yy, γ_xy), Pa."""
    lam = bulk - 2.0 * shear / 3.0
    return np.array([[lam + 2 * shear, lam, 0.0], [lam, lam + 2 * shear, 0.0], [0.0, 0.0, shear]])


def factorise(matrix: sp.spmatrix):
    """SuperLU factors of a symmetric positive definite matrix: symmetric mode (minimum degree
    on A + Aᵀ, no pivoting), half the fill of SciPy's default."""
    return splu(
        matrix.tocsc(),
        permc_spec="MMD_AT_PLUS_A",
        diag_pivot_thresh=0.0,
        options={"SymmetricMode": True},
    )


def _assemble(dofs: np.ndarray, blocks: np.ndarray, size: int) -> sp.csr_matrix:
    """Sparse sum of element blocks (n, k, k) on their degrees of freedom (n, k)."""
    rows = np.repeat(dofs, dofs.shape[1], axis=1).ravel()
    cols = np.tile(dofs, (1, dofs.shape[1])).ravel()
    return sp.csr_matrix((blocks.ravel(), (rows, cols)), shape=(size, size))


def beam_matrices(xy: np.ndarray, area: float, youngs: float, inertia: float):
    """2D elastic beams between consecutive points of ``xy`` (OpenSees ``elasticBeamColumn``
    with a linear transformation): their global stiffness matrices (n, 6, 6; u_x, u_y, θ of
    both ends) and lengths (n,) (m)."""
    dx, dy = np.diff(xy[:, 0]), np.diff(xy[:, 1])
    length = np.hypot(dx, dy)
    c, s = dx / length, dy / length
    ea, ei = youngs * area / length, youngs * inertia / length
    local = np.zeros((length.size, 6, 6))
    for a, b, value in (
        (0, 0, ea), (3, 3, ea), (0, 3, -ea),
        (1, 1, 12 * ei / length**2), (4, 4, 12 * ei / length**2), (1, 4, -12 * ei / length**2),
        (1, 2, 6 * ei / length), (1, 5, 6 * ei / length), (2, 4, -6 * ei / length),
        (4, 5, -6 * ei / length), (2, 2, 4 * ei), (5, 5, 4 * ei), (2, 5, 2 * ei),
    ):  # fmt: skip
        local[:, a, b] = local[:, b, a] = value
    rotation = np.zeros((length.size, 6, 6))
    for k in (0, 3):
        rotation[:, k, k] = rotation[:, k + 1, k + 1] = c
        rotation[:, k, k + 1], rotation[:, k + 1, k] = s, -s
        rotation[:, k + 2, k + 2] = 1.0
    return np.einsum("nji,njk,nkl->nil", rotation, local, rotation), length


# ---- the plastic soil -------------------------------------------------------------------------
@nb.njit(cache=True, nogil=True)
def plastic_forces(
    u, dofs, strain_matrix, weight, yield_stress, bulk, shear, plastic_n, plastic, force, tangent
):
    """Add the plastic quads' internal forces at displacement ``u`` to ``force``.

    J2 plasticity as OpenSees' ``J2Plasticity`` (perfectly plastic, no viscosity): trial
    deviator 2G(e − ε_p,n) from the committed plastic strain; where ‖s‖ exceeds √(2/3) σ_Y,
    radial return with the consistency parameter γ = (‖s‖ − √(2/3) σ_Y)/(2G) × (1 − 10⁻⁸), and
    OpenSees' consistent tangent K 1⊗1 + (2G + c₃) I_dev + (c₂ − c₃) n⊗n, c₂ = −2G,
    c₃ = −4G²γ/‖s‖.

    Parameters
    ----------
    u : ndarray
        Global displacements (m).
    dofs, strain_matrix, weight : ndarray
        (n, 8), (n, 4, 3, 8), (n, 4) of the plastic quads (:func:`quad_kinematics`).
    yield_stress : ndarray
        (n,) σ_Y (Pa).
    bulk, shear : float
        K, G (Pa).
    plastic_n : ndarray
        (n, 4, 4) committed plastic strain (xx, yy, zz, xy tensor components).
    plastic : ndarray
        (n, 4, 4) out: the trial plastic strain of this state.
    force : ndarray
        Global internal forces (N), added to.
    tangent : ndarray
        (n, 8, 8) out: each quad's tangent stiffness (N/m), or an empty (0, 8, 8) array for
        none.

    Returns
    -------
    int
        Gauss points that yield in this state.
    """
    root23 = math.sqrt(2.0 / 3.0)
    ue = np.empty(8)
    d = np.empty((3, 3))
    with_tangent = tangent.shape[0] > 0
    yielding = 0
    for e in range(dofs.shape[0]):
        for a in range(8):
            ue[a] = u[dofs[e, a]]
        if with_tangent:
            tangent[e] = 0.0
        radius = root23 * yield_stress[e]
        for g in range(4):
            exx = eyy = gxy = 0.0
            for a in range(8):
                exx += strain_matrix[e, g, 0, a] * ue[a]
                eyy += strain_matrix[e, g, 1, a] * ue[a]
                gxy += strain_matrix[e, g, 2, a] * ue[a]
            trace = exx + eyy
            dev = (exx - trace / 3.0, eyy - trace / 3.0, -trace / 3.0, 0.5 * gxy)
            s0 = 2.0 * shear * (dev[0] - plastic_n[e, g, 0])
            s1 = 2.0 * shear * (dev[1] - plastic_n[e, g, 1])
            s2 = 2.0 * shear * (dev[2] - plastic_n[e, g, 2])
            s3 = 2.0 * shear * (dev[3] - plastic_n[e, g, 3])
            norm = math.sqrt(s0 * s0 + s1 * s1 + s2 * s2 + 2.0 * s3 * s3)
            phi = norm - radius
            for k in range(4):
                plastic[e, g, k] = plastic_n[e, g, k]
            c2 = c3 = n0 = n1 = n3 = 0.0
            if phi > 0.0:
                yielding += 1
                gamma = phi / (2.0 * shear) * (1.0 - 1e-8)
                n0, n1, n3 = s0 / norm, s1 / norm, s3 / norm
                plastic[e, g, 0] += gamma * n0
                plastic[e, g, 1] += gamma * n1
                plastic[e, g, 2] += gamma * s2 / norm
                plastic[e, g, 3] += gamma * n3
                s0 = 2.0 * shear * (dev[0] - plastic[e, g, 0])
                s1 = 2.0 * shear * (dev[1] - plastic[e, g, 1])
                s3 = 2.0 * shear * (dev[3] - plastic[e, g, 3])
                c2 = -2.0 * shear
                c3 = -4.0 * shear * shear * gamma / norm
            sxx = s0 + bulk * trace
            syy = s1 + bulk * trace
            w = weight[e, g]
            for a in range(8):
                force[dofs[e, a]] += w * (
                    strain_matrix[e, g, 0, a] * sxx
                    + strain_matrix[e, g, 1, a] * syy
                    + strain_matrix[e, g, 2, a] * s3
                )
            if not with_tangent:
                continue
            mu2, coupled = 2.0 * shear + c3, c2 - c3
            d[0, 0] = bulk + mu2 * 2.0 / 3.0 + coupled * n0 * n0
            d[1, 1] = bulk + mu2 * 2.0 / 3.0 + coupled * n1 * n1
            d[0, 1] = d[1, 0] = bulk - mu2 / 3.0 + coupled * n0 * n1
            d[2, 2] = 0.5 * mu2 + coupled * n3 * n3
            d[0, 2] = d[2, 0] = coupled * n0 * n3
            d[1, 2] = d[2, 1] = coupled * n1 * n3
            for a in range(8):
                for i in range(3):
                    bd = 0.0
                    for j in range(3):
                        bd += strain_matrix[e, g, j, a] * d[j, i]
                    bd *= w
                    for b in range(8):
                        tangent[e, a, b] += bd * strain_matrix[e, g, i, b]
    return yielding


# ---- the section ------------------------------------------------------------------------------
class NativeSection:
    """The FE section of ``model.fe.build`` as matrices, with its stages as methods.

    Degrees of freedom: u_x, u_y of the soil nodes (node i · (n_θ + 1) + j), then u_x, u_y, θ of
    the lining's beam nodes j = 0 … n_θ. Displacements are total, from the undeformed mesh.

    Parameters
    ----------
    scenario : Scenario
        Soil, tunnel and ground (as ``model.fe.build``).
    mesh : SectionMesh
        The half-annulus mesh.
    soil_law : {"elastic", "mohr_coulomb"}
    plastic_radius : float
        Plastic elements within this radius of the axis (m).
    """

    def __init__(self, scenario: Scenario, mesh: SectionMesh, soil_law: str, plastic_radius: float):
        self.scenario, self.mesh, self.soil_law = scenario, mesh, soil_law
        nt = mesh.n_theta
        self.n_soil = 2 * (mesh.n_rings + 1) * (nt + 1)
        self.size = self.n_soil + 3 * (nt + 1)
        self.mass = np.zeros(self.size)
        self.fixed = np.zeros(self.size, dtype=bool)
        self._soil(plastic_radius)
        self._lining()
        self._boundary()
        self.free = np.flatnonzero(~self.fixed)
        self.gravity_free = self.free[self.free < self.n_soil]
        self.u = np.zeros(self.size)
        self.attached_at = np.zeros(self.size)
        self.anchor = 0.0
        self._static_factors = {}

    def _soil(self, plastic_radius: float) -> None:
        """The quads (elastic stiffness, plastic ones' kinematics), the nodal masses, the
        gravity loads, the anchor's degree of freedom and the symmetry conditions (u_x = 0 on
        the axis)."""
        soil, mesh, nt = self.scenario.soil, self.mesh, self.mesh.n_theta
        dofs, strain_matrix, weight = quad_kinematics(mesh)
        plastic, yield_stress = plastic_soil(self.scenario, mesh, self.soil_law, plastic_radius)
        plastic = plastic.ravel()
        self.n_elements, self.n_plastic = plastic.size, int(plastic.sum())
        self.bulk, self.shear = soil.bulk_modulus, soil.shear_modulus
        elasticity = elastic_matrix(self.bulk, self.shear)

        def stiffness(keep):
            blocks = np.einsum("egia,ij,egjb,eg->eab", strain_matrix[keep], elasticity,
                               strain_matrix[keep], weight[keep])  # fmt: skip
            return _assemble(dofs[keep], blocks, self.size)

        self.elastic_soil, self.plastic_initial = stiffness(~plastic), stiffness(plastic)
        self.plastic_dofs = dofs[plastic]
        self.plastic_b = np.ascontiguousarray(strain_matrix[plastic])
        self.plastic_w = np.ascontiguousarray(weight[plastic])
        self.plastic_yield = np.ascontiguousarray(yield_stress.ravel()[plastic])
        self.plastic_n = np.zeros((self.n_plastic, 4, 4))
        self.plastic_trial = np.zeros((self.n_plastic, 4, 4))
        self.mass[: self.n_soil] = np.repeat(body_loads(mesh, lambda y: soil.density).ravel(), 2)
        self.gravity_force = np.zeros(self.size)
        self.gravity_force[: self.n_soil] = gravity_loads(
            self.scenario, mesh, self.soil_law
        ).ravel()
        self.anchor_dof = 2 * (mesh.n_rings * (nt + 1)) + 1
        on_axis = np.isin(np.arange(self.n_soil // 2) % (nt + 1), (0, nt))
        self.fixed[0 : self.n_soil : 2] = on_axis

    def _lining(self) -> None:
        """The beams on the ring, their lumped masses, zero rotation on the axis, and the links
        to the ring's soil nodes (the link in series with the tie's penalty)."""
        nt = self.mesh.n_theta
        area, youngs, inertia, mass_per_length = lining_beam(self.scenario)
        ring = np.column_stack(self.mesh.xy(0, np.arange(nt + 1)))
        beam_k, length = beam_matrices(ring, area, youngs, inertia)
        beam_dofs = self.n_soil + 3 * np.arange(nt)[:, None] + np.arange(6)[None, :]
        self.beams = _assemble(beam_dofs, beam_k, self.size)
        node_mass = np.zeros(nt + 1)
        node_mass[:-1] += 0.5 * mass_per_length * length
        node_mass[1:] += 0.5 * mass_per_length * length
        beam_nodes = self.n_soil + 3 * np.arange(nt + 1)
        self.mass[beam_nodes] += node_mass
        self.mass[beam_nodes + 1] += node_mass
        self.fixed[beam_nodes[[0, -1]] + 2] = True
        link = LINK_STIFFNESS * PENALTY / (LINK_STIFFNESS + PENALTY)
        soil_ring = 2 * np.arange(nt + 1)[:, None] + np.arange(2)[None, :]
        pairs = np.stack([soil_ring, beam_nodes[:, None] + np.arange(2)[None, :]], axis=2)
        spring = link * np.array([[1.0, -1.0], [-1.0, 1.0]])
        self.links = _assemble(pairs.reshape(-1, 2), np.tile(spring, (pairs.size // 2, 1, 1)),
                               self.size)  # fmt: skip

    def _boundary(self) -> None:
        """Springs and dashpots at the nodes of r = R, to fixed points; the springs, the links
        and the beams make up what is attached after gravity (:attr:`attached`)."""
        mesh, nt = self.mesh, self.mesh.n_theta
        springs, dashpots, radial, tangential = boundary_coefficients(self.scenario, mesh)
        outer = 2 * (mesh.n_rings * (nt + 1) + np.arange(nt + 1))[:, None] + np.arange(2)
        directions = np.stack([radial, tangential], axis=1)  # (nt + 1, 2 directions, 2)
        spring_k = np.einsum("jd,jda,jdb->jab", springs, directions, directions)
        dashpot_c = np.einsum("jd,jda,jdb->jab", dashpots, directions, directions)
        self.boundary_c = _assemble(outer, dashpot_c, self.size)
        self.attached = (self.links + _assemble(outer, spring_k, self.size)).tocsr()

    # ---- forces -------------------------------------------------------------------------------
    def internal_force(
        self, u: np.ndarray, with_lining: bool = True, tangent: np.ndarray | None = None
    ) -> np.ndarray:
        """Internal forces at ``u`` (N).

        The plastic points' trial state is left in ``plastic_trial`` and the number of those
        that yield in ``yielding``; with ``tangent`` ((n_plastic, 8, 8)), the plastic quads'
        tangent stiffness at ``u`` is written there.
        """
        force = self.elastic_soil @ u
        if with_lining:
            force += self.beams @ u + self.attached @ (u - self.attached_at)
        else:
            force[self.anchor_dof] += self.anchor * u[self.anchor_dof]
        self.yielding = 0
        if self.n_plastic:
            self.yielding = plastic_forces(
                u, self.plastic_dofs, self.plastic_b, self.plastic_w, self.plastic_yield,
                self.bulk, self.shear, self.plastic_n, self.plastic_trial, force,
                NO_TANGENT if tangent is None else tangent,
            )  # fmt: skip
        return force

    def _stiffness(self, with_lining: bool, plastic: sp.spmatrix) -> sp.csr_matrix:
        """The section's stiffness with the plastic quads' part ``plastic``: the soil and the
        anchor during gravity, the soil, the lining and the boundary after it."""
        matrix = self.elastic_soil + plastic
        if with_lining:
            return (matrix + self.beams + self.attached).tocsr()
        anchor = ([self.anchor], ([self.anchor_dof], [self.anchor_dof]))
        return (matrix + sp.csr_matrix(anchor, shape=matrix.shape)).tocsr()

    def _tangent(self, tangents: np.ndarray) -> sp.csr_matrix:
        """The plastic quads' tangent stiffness (:meth:`internal_force` with ``tangent``)."""
        return _assemble(self.plastic_dofs, tangents, self.size)

    def _static_solve(self, load: np.ndarray, with_lining: bool) -> None:
        """Equilibrium under ``load`` from the current state (velocities zero) by Newton's
        method on the consistent tangent, as OpenSees' static stages; while no point yields
        the tangent is the initial stiffness, factorised once per configuration. Commits the
        plastic state."""
        free = self.free if with_lining else self.gravity_free
        tangents = np.empty((self.n_plastic, 8, 8))
        for _ in range(MAX_ITERATIONS):
            residual = load - self.internal_force(self.u, with_lining, tangents)
            if self.yielding:
                lu = None  # memory: one factorisation alive at a time
                self._static_factors.pop(with_lining, None)
                matrix = self._stiffness(with_lining, self._tangent(tangents))
                lu = factorise(matrix[free][:, free])
            else:
                if with_lining not in self._static_factors:
                    matrix = self._stiffness(with_lining, self.plastic_initial)
                    self._static_factors[with_lining] = factorise(matrix[free][:, free])
                lu = self._static_factors[with_lining]
            correction = lu.solve(residual[free])
            self.u[free] += correction
            if np.linalg.norm(correction) < STATIC_TOLERANCE:
                break
        else:
            stage = "static equilibrium" if with_lining else "gravity stage"
            raise FEConvergenceError(
                f"the {stage} did not converge in {MAX_ITERATIONS} Newton iterations"
                + ("" if with_lining else " (soil too weak for its K0 state?)")
            )
        self.internal_force(self.u, with_lining)
        self.plastic_n[:] = self.plastic_trial

    def _gravity(self) -> None:
        """The gravity stage: soil only, held vertically at the bottom axis node by the anchor,
        the geostatic loads in one step (elastic) or ``PLASTIC_GRAVITY_STEPS`` (plastic)."""
        self.anchor = anchor_stiffness(self.scenario)
        steps = 1 if self.soil_law == "elastic" else PLASTIC_GRAVITY_STEPS
        for step in range(1, steps + 1):
            self._static_solve(self.gravity_force * step / steps, with_lining=False)

    # ---- the stages, as run_fe calls them ------------------------------------------------------
    def prepare(self) -> None:
        """Gravity, then the anchor removed, the lining and the boundary added (measuring from
        the gravity state) and the section brought to rest in equilibrium."""
        self._gravity()
        self._static_factors.clear()  # the anchored soil's factors: not needed again
        self.attached_at = self.u.copy()
        self.anchor = 0.0
        self._static_solve(self.gravity_force, with_lining=True)

    def set_history(self, history: np.ndarray, dt: float) -> None:
        """The line load (N/m) of every time step to come, sampled at ``dt`` (s): step k loads
        the invert with half of ``history[k]`` (zero beyond its end), as OpenSees' ``Path``."""
        self.history = np.append(np.asarray(history, dtype=float), 0.0)
        self.dt, self.step_index = dt, 0

    def begin_passage(self, a0: float, a1: float, unbalance_N: float) -> None:
        """Start Newmark's average acceleration (γ = ½, β = ¼) from rest, with Rayleigh
        damping a₀M + a₁K_init and the iteration's unbalance tolerance (N): the effective
        stiffness is factorised once for the passage."""
        dt = self.dt
        self._static_factors.clear()  # memory: one set of factors at a time (refactorised after)
        initial = self.elastic_soil + self.plastic_initial + self.beams
        self.damping = (a1 * initial + self.boundary_c + sp.diags(a0 * self.mass)).tocsr()
        # the iteration matrix: the tangent at the passage's start (where the soil has just
        # yielded, OpenSees' J2 state lies 1e-8 outside the surface: its elastoplastic tangent)
        tangents = np.empty((self.n_plastic, 8, 8))
        self.internal_force(self.u, True, tangents)
        tangent = self._stiffness(True, self._tangent(tangents))
        effective = tangent + (2.0 / dt) * self.damping + sp.diags(4.0 / dt**2 * self.mass)
        self.lu = factorise(effective.tocsr()[self.free][:, self.free])
        self.velocity = np.zeros(self.size)
        self.acceleration = np.zeros(self.size)
        self.unbalance_N = unbalance_N

    def step(self) -> int:
        """Advance one time step; returns the iterations taken.

        Elastic law: one solve on the factorised effective stiffness (exact). Plastic law:
        iterations on that matrix (the passage's first tangent) until the displacement
        correction is
        below DISP_TOLERANCE or the unbalanced force below the passage's tolerance (2-norms),
        as OpenSees' ``ModifiedNewton`` with ``NormDispOrUnbalance``; FEConvergenceError after
        MAX_ITERATIONS.
        """
        dt, free = self.dt, self.free
        self.step_index += 1
        load = self.gravity_force.copy()
        load[1] -= 0.5 * self.history[min(self.step_index, self.history.size - 1)]
        self.velocity, self.acceleration = (
            -self.velocity,
            -4.0 / dt * self.velocity - self.acceleration,
        )
        residual = self._unbalance(load)
        for iteration in range(1, MAX_ITERATIONS + 1):
            correction = self.lu.solve(residual[free])
            self.u[free] += correction
            self.velocity[free] += 2.0 / dt * correction
            self.acceleration[free] += 4.0 / dt**2 * correction
            if self.n_plastic == 0:
                return 1
            residual = self._unbalance(load)
            if (
                np.linalg.norm(correction) < DISP_TOLERANCE
                or np.linalg.norm(residual[free]) < self.unbalance_N
            ):
                self.plastic_n[:] = self.plastic_trial
                return iteration
        raise FEConvergenceError(f"no convergence in {MAX_ITERATIONS} iterations")

    def _unbalance(self, load: np.ndarray) -> np.ndarray:
        """External minus internal, damping and inertia forces (N)."""
        return (
            load
            - self.internal_force(self.u)
            - self.damping @ self.velocity
            - self.mass * self.acceleration
        )

    def end_passage(self) -> None:
        """Static equilibrium at rest with the train gone (the quiet tail carries no load)."""
        self._static_solve(self.gravity_force, with_lining=True)

    def invert_column_disp(self) -> np.ndarray:
        """Vertical displacement (m, up +) of the soil nodes below the invert, ring by ring."""
        nt = self.mesh.n_theta
        return self.u[2 * (nt + 1) * np.arange(self.mesh.n_rings + 1) + 1].copy()

    def close(self) -> None:
        """Nothing to release (OpenSees' counterpart wipes its domain)."""
