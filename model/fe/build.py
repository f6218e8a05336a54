"""The OpenSees model of the section: soil, lining, boundary, the gravity stage and the analyses.

- **Lining.** Elastic beam elements (``elasticBeamColumn``) on the ring radius a, the chords of
  the circle between the soil nodes of the first ring, with the plane-strain modulus
  E/(1 − ν²), area h·1 m, inertia h³/12 and mass ρh per metre: the thin ring of docs/model.md
  §7, with the soil starting at the ring radius, as in the analytical model. Added after the
  gravity stage, tied to the soil nodes by stiff links (see :func:`add_lining`).
- **Absorbing boundary.** Viscous–spring (Kelvin) boundary on the circle r = R: per unit length
  a Lysmer–Kuhlemeyer dashpot ρc₁ normal and ρc₂ tangential, in parallel with springs
  α_N G/R and α_T G/R (α_N = 1, α_T = 1/2; Deeks & Randolph 1994, Liu et al. 2006), which carry
  the static part of the load that pure dashpots would let drift away (a 2D domain on dashpots
  alone moves by ∫q dt / C: ~2 cm per passage here). ``zeroLength`` elements with an elastic
  material that has a damping tangent, oriented radially, lumped at the boundary nodes by
  their tributary arc length.
- **Gravity with K0 first.** The geostatic stress of the level ground above, extended linearly
  over the whole (full-space) mesh: total vertical stress σ_v = ρ g z at depth z = H_t − y
  below the surface (H_t = ``tunnel.axis_depth``), pore pressure u = γ_w (z − z_w), effective
  σ′_v = σ_v − u, horizontal σ_h = K0 σ′_v + u with K0 = 1 − sin φ′ (``longterm``). It is set up
  by the body force ρ g and the tractions of that field on the outer boundary (a linear stress
  field is compatible, so the elastic solution reproduces it exactly away from the tunnel),
  the lining wished in place with its own weight; the tunnel perturbs the field locally.
- **Soil laws.** ``"elastic"``: ``ElasticIsotropic`` (E, ν; the mass is on the nodes, see
  :func:`build_section`). ``"mohr_coulomb"``: the
  undrained (φ_u = 0) Mohr–Coulomb, i.e. Tresca, criterion matched in plane strain by
  Drucker–Prager with zero friction, i.e. von Mises with σ_Y = √3 c_u (OpenSees
  ``J2Plasticity``, perfectly plastic, associated), with the
  undrained strength c_u(z) of docs/model.md §10 (the host layer's ``cu_ratio`` × σ′_v0,
  or its ``undrained_strength``). Why undrained and c_u: a passage lasts seconds, far too short
  for the soft clay to drain; the strength is the one the long-term model uses. Because the
  φ = 0 criterion ignores the mean stress, the plastic model carries the geostatic stress
  minus its in-plane mean (a statically admissible isotropic part removed, body force
  adjusted): the deviator is the K0 one and the out-of-plane stress equals the in-plane mean,
  as in undrained plane strain, where the drained Poisson ratio would otherwise put an
  out-of-plane deviator into the criterion. Only elements within ``FEMesh.plastic_radius`` of
  the axis and below the ground surface are plastic; the others (including the fictitious upper
  part of the full space) stay elastic.
"""

from __future__ import annotations

import numpy as np

from model.fe.inputs import drucker_prager_plane_strain, geostatic, undrained_strength
from model.fe.mesh import SectionMesh, arc_loads, body_loads
from model.params import Scenario

SPRING_NORMAL, SPRING_TANGENTIAL = 1.0, 0.5
"""α_N, α_T of the viscous–spring boundary (springs α G / R per unit length)."""
DISP_TOLERANCE = 1e-9
"""Plastic soil: a time step has also converged when the displacement correction (m, 2-norm)
is below this."""
MAX_ITERATIONS = 100
"""Most iterations of a time step and of the static equilibrium (both engines)."""
PLASTIC_GRAVITY_STEPS = 10
"""Load steps of the gravity stage with plastic soil (one with elastic soil; both engines)."""
PENALTY = 1e14
"""Penalty factor of the lining's equalDOF ties (N/m): 100 × LINK_STIFFNESS."""
LINK_STIFFNESS = 1e12
"""Soil–lining link stiffness (N/m per metre): 1e6 × the soil's G, 30 × the lining's EA/length,
so the links stretch by ~1e-8 m under the train load (mm response)."""
FE_EXTRA_MESSAGE = (
    "the FE section needs OpenSeesPy: install the 'fe' extra (pip install \".[fe]\") and, on "
    "Debian/Ubuntu, its BLAS/LAPACK libraries (apt-get install libopenblas0 liblapack3)"
)


class FEUnavailableError(RuntimeError):
    """OpenSeesPy is not installed or its shared library cannot be loaded."""


class FEConvergenceError(RuntimeError):
    """An OpenSees analysis stage did not converge; the message says where."""


def opensees():
    """The ``openseespy.opensees`` module, or FEUnavailableError with the one-line fix.

    Without its shared libraries (Debian's BLAS/LAPACK) OpenSeesPy's import raises
    ``RuntimeError: Failed to import openseespy on Linux.``, hiding the loader's reason in the
    exception's context: the message gives that reason (e.g. "libopenblas.so.0: cannot open
    shared object file").
    """
    try:
        import openseespy.opensees as ops
    except (ImportError, OSError, RuntimeError) as error:
        raise FEUnavailableError(f"{FE_EXTRA_MESSAGE} ({_root_cause(error)})") from error
    return ops


def fe_unavailable_reason() -> str | None:
    """Why the FE section cannot run here (the message of :func:`opensees`), or None if it can."""
    try:
        opensees()
    except FEUnavailableError as error:
        return str(error)
    return None


def _root_cause(error: BaseException) -> str:
    """The innermost import or loader error behind ``error`` (its message), else ``error``'s."""
    cause = error
    while cause.__cause__ or cause.__context__:
        cause = cause.__cause__ or cause.__context__
    return str(cause) if isinstance(cause, ImportError | OSError) else str(error)


# ---- model building ---------------------------------------------------------------------------
def _next_tag(tags) -> int:
    """A tag above every tag in use."""
    return int(max(tags, default=0)) + 1


def _stress_field(scenario: Scenario, soil_law: str):
    """(σ_xx(y), σ_yy(y)) in OpenSees sign (tension +) and the body force b_y(y) (N/m³)."""
    field_ = geostatic(scenario)
    if soil_law == "elastic":

        def sxx(y):
            return -field_.horizontal(y)

        def syy(y):
            return -field_.vertical(y)

    else:  # deviatoric part: the isotropic in-plane mean removed (module docstring)

        def sxx(y):
            return 0.5 * (field_.vertical(y) - field_.horizontal(y))

        def syy(y):
            return -sxx(y)

    slope = syy(1.0) - syy(0.0)  # linear in y: ∂σ_yy/∂y

    def body(y):
        return -slope * np.ones_like(np.asarray(y, dtype=float))

    return sxx, syy, body


def plastic_soil(scenario: Scenario, mesh: SectionMesh, soil_law: str, plastic_radius: float):
    """Which elements are plastic and their von Mises yield stress σ_Y = √3 c_u (Pa).

    Returns
    -------
    plastic : ndarray of bool
        (n_rings, n_theta): with the Mohr–Coulomb law, the elements whose centroid lies within
        ``plastic_radius`` of the axis and below the ground surface.
    yield_stress : ndarray
        (n_rings, n_theta) σ_Y of the φ = 0 Drucker–Prager match (c_u at least 1 Pa).
    """
    ele_x, ele_y = mesh.centroids()
    plastic = (soil_law == "mohr_coulomb") & (np.hypot(ele_x, ele_y) <= plastic_radius)
    plastic &= ele_y < scenario.tunnel.axis_depth
    strength = np.maximum(undrained_strength(scenario, ele_y), 1.0)
    yield_stress = drucker_prager_plane_strain(strength, 0.0)[0]
    return plastic, yield_stress


def gravity_loads(scenario: Scenario, mesh: SectionMesh, soil_law: str) -> np.ndarray:
    """(n_rings + 1, n_theta + 1, 2) nodal forces of the gravity stage (N): the body force and
    the geostatic tractions on both arcs (the inner one stands for the soil inside the tunnel)."""
    sxx, syy, body = _stress_field(scenario, soil_law)

    def traction(x, y, normal):
        return np.array([sxx(y) * normal[0], syy(y) * normal[1]])

    forces = np.zeros((mesh.n_rings + 1, mesh.n_theta + 1, 2))
    forces[..., 1] = body_loads(mesh, body)
    forces[0] += arc_loads(mesh, 0, traction)
    forces[-1] += arc_loads(mesh, mesh.n_rings, traction)
    return forces


def anchor_stiffness(scenario: Scenario) -> float:
    """Stiffness of the link holding the bottom axis node during gravity (N/m): 1e3 × E."""
    return 1e3 * scenario.soil.youngs_modulus


def lining_beam(scenario: Scenario):
    """(A (m²), plane-strain E (Pa), I (m⁴), mass per length (kg/m)) of the lining per metre."""
    tunnel = scenario.tunnel
    h = tunnel.thickness
    e_plane = tunnel.youngs_modulus / (1.0 - tunnel.poisson_ratio**2)
    return h, e_plane, h**3 / 12.0, tunnel.density * h


def boundary_coefficients(scenario: Scenario, mesh: SectionMesh):
    """The viscous–spring boundary lumped at the nodes of r = R, one row per node j.

    Returns
    -------
    springs, dashpots : ndarray
        (n_theta + 1, 2): normal and tangential stiffness (N/m) and damping (N s/m).
    radial, tangential : ndarray
        (n_theta + 1, 2) unit vectors of the two directions.
    """
    soil = scenario.soil
    radius = mesh.radii[-1]
    d_theta = mesh.thetas[1] - mesh.thetas[0]
    length = np.full(mesh.n_theta + 1, radius * d_theta)
    length[[0, -1]] *= 0.5
    springs = np.outer(length, [SPRING_NORMAL, SPRING_TANGENTIAL]) * soil.shear_modulus / radius
    dashpots = np.outer(length, [soil.p_wave_speed, soil.s_wave_speed]) * soil.density
    theta = mesh.thetas
    radial = np.column_stack([np.sin(theta), -np.cos(theta)])
    tangential = np.column_stack([np.cos(theta), np.sin(theta)])
    return springs, dashpots, radial, tangential


def build_section(ops, scenario: Scenario, mesh: SectionMesh, soil_law: str, plastic_radius: float):
    """Soil nodes, materials, quads and the symmetry conditions; returns bookkeeping.

    The soil's mass sits on the nodes: the quad's own lumped mass (ρ N_a |J| at its 2 × 2 Gauss
    points), so that the quads carry none and OpenSees does not rebuild their mass matrices
    twice per residual (inertia and Rayleigh a₀M); the same matrix, the same results to
    rounding (docs/fe_section.md, Speed)."""
    soil = scenario.soil
    ops.wipe()
    ops.model("basic", "-ndm", 2, "-ndf", 2)
    nr, nt = mesh.n_rings, mesh.n_theta
    nodal_mass = body_loads(mesh, lambda y: soil.density)
    for i in range(nr + 1):
        for j in range(nt + 1):
            tag = int(mesh.node_tag(i, j))
            ops.node(tag, *map(float, mesh.xy(i, j)))
            ops.mass(tag, float(nodal_mass[i, j]), float(nodal_mass[i, j]))
    for i in range(nr + 1):
        ops.fix(int(mesh.node_tag(i, 0)), 1, 0)
        ops.fix(int(mesh.node_tag(i, nt)), 1, 0)

    shear, bulk = soil.shear_modulus, soil.bulk_modulus
    n_elements = nr * nt
    ops.nDMaterial("ElasticIsotropic", 1, soil.youngs_modulus, soil.poisson_ratio, 0.0)
    plastic, yield_stress = plastic_soil(scenario, mesh, soil_law, plastic_radius)
    for i in range(nr):
        for j in range(nt):
            tag = 1 + i * nt + j
            mat = 1
            if plastic[i, j]:
                mat = 1 + tag
                sigma_y = float(yield_stress[i, j])
                ops.nDMaterial("J2Plasticity", mat, bulk, shear, sigma_y, sigma_y, 0.0, 0.0)
            nodes = [
                mesh.node_tag(a, b) for a, b in [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)]
            ]
            ops.element("quad", tag, *map(int, nodes), 1.0, "PlaneStrain", mat, 0.0, 0.0, 0.0, 0.0)

    return {"n_elements": n_elements, "n_plastic": int(plastic.sum())}


def add_lining(ops, scenario: Scenario, mesh: SectionMesh) -> None:
    """Lining beams on the first ring, added stress-free in the stressed ground.

    The beam nodes are new, at rest on the undeformed circle, and tied to the soil nodes by
    stiff links (``zeroLength``, LINK_STIFFNESS per direction) that measure from the moment they
    are added: the gravity displacement of the soil (up to ~1 m with E = 6 MPa: the strain of the
    whole geostatic state) neither loads nor distorts the ring."""
    nt = mesh.n_theta
    ops.model("basic", "-ndm", 2, "-ndf", 3)
    beam_base = _next_tag(ops.getNodeTags())
    ele_base = _next_tag(ops.getEleTags())
    link_material = 1  # the other uniaxial materials take tags derived from element tags (> 1)
    ops.uniaxialMaterial("Elastic", link_material, LINK_STIFFNESS)
    for j in range(nt + 1):
        ops.node(beam_base + j, *map(float, mesh.xy(0, j)))
    ops.fix(beam_base, 0, 0, 1)
    ops.fix(beam_base + nt, 0, 0, 1)
    ops.geomTransf("Linear", 1)
    area, e_plane, inertia, mass = lining_beam(scenario)
    for j in range(nt):
        ops.element(
            "elasticBeamColumn", ele_base + j, beam_base + j, beam_base + j + 1,
            area, e_plane, inertia, 1, "-mass", mass,
        )  # fmt: skip
    # zeroLength needs the same dofs at both ends: link the soil to 2-dof twins of the beam nodes
    ops.model("basic", "-ndm", 2, "-ndf", 2)
    twin_base = beam_base + nt + 1
    for j in range(nt + 1):
        ops.node(twin_base + j, *map(float, mesh.xy(0, j)))
        ops.equalDOF(twin_base + j, beam_base + j, 1, 2)
        ops.element(
            "zeroLength", ele_base + nt + j, int(mesh.node_tag(0, j)), twin_base + j,
            "-mat", link_material, link_material, "-dir", 1, 2,
        )  # fmt: skip


def apply_gravity(ops, scenario, mesh, soil_law):
    """Static gravity stage: body force and the geostatic tractions on both arcs (the inner one
    stands for the soil inside the tunnel); returns the link element holding the bottom node."""
    forces = gravity_loads(scenario, mesh, soil_law)
    ops.timeSeries("Linear", 1)
    ops.pattern("Plain", 1, 1)
    for i in range(mesh.n_rings + 1):
        for j in range(mesh.n_theta + 1):
            ops.load(int(mesh.node_tag(i, j)), *map(float, forces[i, j]))
    # hold the bottom axis node vertically by a stiff link to a fixed node: the loads balance,
    # so it carries only the discretisation's imbalance, and it is removed after gravity
    anchor = _next_tag(ops.getEleTags())
    ghost = _next_tag(ops.getNodeTags())
    ops.node(ghost, *ops.nodeCoord(int(mesh.node_tag(mesh.n_rings, 0))))
    ops.fix(ghost, 1, 1)
    ops.uniaxialMaterial("Elastic", anchor, anchor_stiffness(scenario))
    ops.element("zeroLength", anchor, ghost, int(mesh.node_tag(mesh.n_rings, 0)), "-mat", anchor,
                "-dir", 2)  # fmt: skip
    ops.constraints("Penalty", PENALTY, PENALTY)
    ops.numberer("RCM")
    ops.system("UmfPack")
    ops.test("NormDispIncr", 1e-9, 50)
    ops.algorithm("Newton")
    n_steps = 1 if soil_law == "elastic" else PLASTIC_GRAVITY_STEPS
    ops.integrator("LoadControl", 1.0 / n_steps)
    ops.analysis("Static")
    if ops.analyze(n_steps) != 0:
        raise FEConvergenceError(
            "the gravity stage did not converge (soil too weak for its K0 state?)"
        )
    ops.loadConst("-time", 0.0)
    return anchor


def add_boundary(ops, scenario, mesh):
    """Viscous–spring boundary on r = R.

    Added after gravity: OpenSees' zeroLength measures its deformation from the node
    displacements at the time it is added, so the springs start unloaded."""
    springs, dashpots, radial, tangential = boundary_coefficients(scenario, mesh)
    i = mesh.n_rings
    ghost_base = _next_tag(ops.getNodeTags())
    ele_base = _next_tag(ops.getEleTags())
    for j in range(mesh.n_theta + 1):
        node = int(mesh.node_tag(i, j))
        x, y = mesh.xy(i, j)
        ghost = int(ghost_base + j)
        ops.node(ghost, float(x), float(y))
        ops.fix(ghost, 1, 1)
        normal_mat, tangential_mat = 2 * (ele_base + j), 2 * (ele_base + j) + 1
        for mat, k in ((normal_mat, 0), (tangential_mat, 1)):
            ops.uniaxialMaterial("Elastic", mat, float(springs[j, k]), float(dashpots[j, k]))
        ops.element(
            "zeroLength", int(ele_base + j), ghost, node, "-mat", normal_mat, tangential_mat,
            "-dir", 1, 2, "-orient", *radial[j], 0.0, *tangential[j], 0.0,
        )  # fmt: skip


def static_equilibrium(ops):
    """Static solve with the current loads, from rest (the boundary dashpots read the nodal
    velocities, so these are zeroed first)."""
    for node in ops.getNodeTags():
        for dof in range(1, len(ops.nodeDisp(node)) + 1):
            ops.setNodeVel(node, dof, 0.0, "-commit")
            ops.setNodeAccel(node, dof, 0.0, "-commit")
    ops.wipeAnalysis()
    ops.constraints("Penalty", PENALTY, PENALTY)
    ops.numberer("RCM")
    ops.system("UmfPack")
    ops.test("NormDispIncr", 1e-10, MAX_ITERATIONS)
    ops.algorithm("Newton")
    ops.integrator("LoadControl", 0.0)
    ops.analysis("Static")
    if ops.analyze(1) != 0:
        raise FEConvergenceError("the static equilibrium after a passage did not converge")


def transient_analysis(ops, soil_law, a0, a1, unbalance_N):
    """Newmark average acceleration with Rayleigh damping.

    Elastic soil: one factorisation, no iterations. Plastic soil: modified Newton on the
    tangent of the passage's first step, factorised once (with the mass term 4M/Δt² in it, it
    needs about as many iterations as Krylov–Newton refactorised every step:
    docs/fe_section.md); a step has converged when the unbalanced force is below
    ``unbalance_N`` or the displacement correction below DISP_TOLERANCE. The system is solved
    by SuperLU on the RCM numbering, whose back-substitutions cost less than the profile
    solver's (docs/fe_section.md, Speed)."""
    ops.wipeAnalysis()
    ops.constraints("Penalty", PENALTY, PENALTY)
    ops.numberer("RCM")
    ops.system("SparseGeneral")
    ops.rayleigh(a0, 0.0, a1, 0.0)
    if soil_law == "elastic":
        ops.algorithm("Linear", "-factorOnce")
    else:
        ops.test("NormDispOrUnbalance", DISP_TOLERANCE, unbalance_N, MAX_ITERATIONS, 0)
        ops.algorithm("ModifiedNewton", "-factoronce")
    ops.integrator("Newmark", 0.5, 0.25)
    ops.analysis("Transient")


class OpenSeesSection:
    """The section built in OpenSees, with the stages ``run_fe`` calls (the same methods as
    ``model.fe.native.NativeSection``).

    Parameters
    ----------
    scenario : Scenario
    mesh : SectionMesh
    soil_law : {"elastic", "mohr_coulomb"}
    plastic_radius : float
        Plastic elements within this radius of the axis (m).
    """

    def __init__(self, scenario: Scenario, mesh: SectionMesh, soil_law: str, plastic_radius: float):
        self.ops = opensees()
        self.scenario, self.mesh, self.soil_law = scenario, mesh, soil_law
        book = build_section(self.ops, scenario, mesh, soil_law, plastic_radius)
        self.n_elements, self.n_plastic = book["n_elements"], book["n_plastic"]

    def prepare(self) -> None:
        """Gravity, then the anchor removed, the lining and the boundary added and the section
        brought to rest in equilibrium."""
        ops = self.ops
        anchor = apply_gravity(ops, self.scenario, self.mesh, self.soil_law)
        ops.remove("element", anchor)
        add_lining(ops, self.scenario, self.mesh)
        add_boundary(ops, self.scenario, self.mesh)
        static_equilibrium(ops)

    def set_history(self, history: np.ndarray, dt: float) -> None:
        """The line load (N/m) of the time steps to come, at ``dt`` (s): a ``Path`` series,
        half of it downward at the invert."""
        self.dt, self.steps = dt, 0
        self.ops.timeSeries("Path", 3, "-dt", dt, "-values", *np.asarray(history).tolist(), 0.0)
        self.ops.pattern("Plain", 3, 3)
        self.ops.load(int(self.mesh.node_tag(0, 0)), 0.0, -0.5)

    def begin_passage(self, a0: float, a1: float, unbalance_N: float) -> None:
        """The transient analysis of :func:`transient_analysis`."""
        transient_analysis(self.ops, self.soil_law, a0, a1, unbalance_N)

    def step(self) -> int:
        """One time step; the iterations taken (FEConvergenceError if it fails)."""
        if self.ops.analyze(1, self.dt) != 0:
            raise FEConvergenceError("OpenSees' analysis failed")
        self.steps += 1
        return max(self.ops.testIter(), 1)  # the linear algorithm solves once, reports 0

    def end_passage(self) -> None:
        """Static equilibrium between two samples of the quiet tail (no train load)."""
        end = self.steps * self.dt
        self.ops.setTime(end - 1.5 * self.dt)
        static_equilibrium(self.ops)
        self.ops.setTime(end)

    def invert_column_disp(self) -> np.ndarray:
        """Vertical displacement (m, up +) of the soil nodes below the invert, ring by ring."""
        nodes = self.mesh.node_tag(np.arange(self.mesh.n_rings + 1), 0)
        return np.array([self.ops.nodeDisp(int(n), 2) for n in nodes])

    def close(self) -> None:
        """Wipe the OpenSees domain."""
        self.ops.wipe()
