"""The paper's elastic–plastic finite-element check of the section, rebuilt on OpenSeesPy
(docs/model.md §12; the study and the results are in docs/fe_section.md).

Model (plane strain, 1 m thick slice, y up, origin on the tunnel axis):

- **Half model.** The section is symmetric about the vertical axis and so is the invert load:
  only x ≥ 0 is meshed, with u_x = 0 (and, on the lining, zero rotation) on the axis, and half
  the line load at the invert.
- **Mesh.** Structured radial–circumferential quads from the ring radius a to the outer radius
  R: n_θ equal angles over the half circle, rings growing geometrically (radial size
  ``radial_aspect`` × the circumferential size r Δθ) until they reach the largest element size
  h, then uniform. Bilinear ``quad`` elements (2×2 Gauss). The largest element edge is h, and h
  must resolve the shortest S wavelength of the load band, λ_min = c₂/f_max, with at least
  ``ELEMENTS_PER_WAVELENGTH`` elements (else the mesh is refused).
- **Lining.** Elastic beam elements (``elasticBeamColumn``) on the ring radius a, the chords of
  the circle between the soil nodes of the first ring, with the plane-strain modulus
  E/(1 − ν²), area h·1 m, inertia h³/12 and mass ρh per metre: the thin ring of docs/model.md
  §7, with the soil starting at the ring radius, as in the analytical model. Added after the
  gravity stage, tied to the soil nodes by stiff links (see ``_add_lining``).
- **Absorbing boundary.** Viscous–spring (Kelvin) boundary on the circle r = R: per unit length
  a Lysmer–Kuhlemeyer dashpot ρc₁ normal and ρc₂ tangential, in parallel with springs
  α_N G/R and α_T G/R (α_N = 1, α_T = 1/2; Deeks & Randolph 1994, Liu et al. 2006), which carry
  the static part of the load that pure dashpots would let drift away (a 2D domain on dashpots
  alone moves by ∫q dt / C: ~2 cm per passage here). ``zeroLength`` elements with an elastic
  material that has a damping tangent, oriented radially, lumped at the boundary nodes by
  their tributary arc length.
- **Gravity with K0 first.** The geostatic stress of the level ground above, extended linearly
  over the whole (full-space) mesh: total vertical stress σ_v = ρ g z at depth z = H_t − y
  below the surface (H_t = ``longterm.axis_depth``), pore pressure u = γ_w (z − z_w), effective
  σ′_v = σ_v − u, horizontal σ_h = K0 σ′_v + u with K0 = 1 − sin φ′ (``longterm``). It is set up
  by the body force ρ g and the tractions of that field on the outer boundary (a linear stress
  field is compatible, so the elastic solution reproduces it exactly away from the tunnel),
  the lining wished in place with its own weight; the tunnel perturbs the field locally.
- **Soil laws.** ``"elastic"``: ``ElasticIsotropic`` (E, ν, ρ). ``"mohr_coulomb"``: the
  undrained (φ_u = 0) Mohr–Coulomb, i.e. Tresca, criterion matched in plane strain by
  Drucker–Prager with zero friction, i.e. von Mises with σ_Y = √3 c_u (OpenSees
  ``J2Plasticity``, perfectly plastic, associated), with the
  undrained strength c_u(z) of docs/model.md §10 (``longterm.cu_ratio`` × σ′_v0, or
  ``longterm.undrained_strength``). Why undrained and c_u: a passage lasts seconds, far too short
  for the soft clay to drain; the strength is the one the long-term model uses. Because the
  φ = 0 criterion ignores the mean stress, the plastic model carries the geostatic stress
  minus its in-plane mean (a statically admissible isotropic part removed, body force
  adjusted): the deviator is the K0 one and the out-of-plane stress equals the in-plane mean,
  as in undrained plane strain, where the drained Poisson ratio would otherwise put an
  out-of-plane deviator into the criterion. Only elements within ``FEMesh.plastic_radius`` of
  the axis and below the ground surface are plastic; the others (including the fictitious upper
  part of the full space) stay elastic.
- **Dynamics.** Newmark average acceleration (γ = 1/2, β = 1/4). Rayleigh damping
  C = a₀M + a₁K_init with ζ = η_G/2 at the two ends of the load band [f_lo, f_hi] (below that
  band the mass term over-damps, between the ends ζ dips below η_G/2). The line load of the
  pipeline (docs/model.md §6) is averaged over each FE step (a box filter that keeps the impulse)
  and applied downward at the invert.
- **Passages.** Each passage is followed by a quiet tail (R/c₂ plus the boundary's relaxation
  time ρc₁R/(α_N G): waves leave, the response decays),
  then a static equilibrium solve with the train gone: for elastic soil it returns exactly to
  the state before the passage, so the displacement left is the permanent (plastic) one. The
  next passage starts from rest.

Displacements are reported downward positive, relative to the state before the first passage,
on the nodes below the invert (depth = r − a, below the ring–soil interface as in
``model.soil.section_2d.invert_receptance``).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from model.params import Scenario

GRAVITY = 9.81  # m/s²
WATER_UNIT_WEIGHT = 9810.0  # γ_w, N/m³
ELEMENTS_PER_WAVELENGTH = 6
"""Fewest bilinear elements per shortest S wavelength of the load band (phase error ≲ 3 %)."""
BAND_ENERGY_LOW, BAND_ENERGY_HIGH = 0.05, 0.99
"""Load band: where the fluctuating (mean-removed) load energy passes 5 % and 99 %."""
STEPS_PER_PERIOD = 20
"""FE time steps per period of f_hi (Newmark period elongation ≈ 0.8 %)."""
SPRING_NORMAL, SPRING_TANGENTIAL = 1.0, 0.5
"""α_N, α_T of the viscous–spring boundary (springs α G / R per unit length)."""
TAIL_BOUNDARY_TIMES = 1.0
"""Quiet tail after each passage, in units of R/c₂ plus the boundary relaxation time."""
SOIL_LAWS = ("elastic", "mohr_coulomb")
UNBALANCE_TOLERANCE = 1e-6
"""Plastic soil: a time step has converged when the unbalanced force (N, 2-norm over the model)
is below this fraction of the peak invert load; one iteration then suffices where the soil
stays elastic (changes the result by < 1e-6 of it, docs/fe_section.md)."""
DISP_TOLERANCE = 1e-9
"""Plastic soil: a time step has also converged when the displacement correction (m, 2-norm)
is below this."""
PENALTY = 1e14
"""Penalty factor of the lining's equalDOF ties (N/m): 100 × LINK_STIFFNESS."""
LINK_STIFFNESS = 1e12
"""Soil–lining link stiffness (N/m per metre): 1e6 × the soil's G, 30 × the lining's EA/length,
so the links stretch by ~1e-8 m under the train load (mm response)."""
FE_EXTRA_MESSAGE = (
    "the FE section needs OpenSeesPy: install the 'fe' extra (pip install \".[fe]\") and, on "
    "Debian/Ubuntu, its BLAS/LAPACK libraries (apt-get install libopenblas0 liblapack3)"
)

Progress = Callable[[str, float], None]


class FEUnavailableError(RuntimeError):
    """OpenSeesPy is not installed or its shared library cannot be loaded."""


class FEConvergenceError(RuntimeError):
    """An OpenSees analysis stage did not converge; the message says where."""


def opensees():
    """The ``openseespy.opensees`` module, or FEUnavailableError with the one-line fix."""
    try:
        import openseespy.opensees as ops
    except (ImportError, OSError) as error:  # OSError/ImportError: missing BLAS/LAPACK too
        raise FEUnavailableError(f"{FE_EXTRA_MESSAGE} ({error})") from error
    return ops


@dataclass(frozen=True)
class FEMesh:
    """Mesh, boundary and time step of the FE section.

    Parameters
    ----------
    outer_radius : float
        Radius R of the absorbing boundary about the tunnel axis (m), > ring radius.
    element_size : float or None
        Largest element edge h (m); None takes λ_min / ELEMENTS_PER_WAVELENGTH from the load
        band.
    radial_aspect : float
        Radial over circumferential size of the graded rings near the lining (-), ≥ 1.
    plastic_radius : float
        With the Mohr–Coulomb law, elements whose centroid lies within this radius of the axis
        (and below the ground surface) are plastic, the others elastic (m).
    steps_per_period : int
        Time steps per period of the top of the load band, f_high (-), ≥ 4.
    """

    outer_radius: float = 30.0
    element_size: float | None = None
    radial_aspect: float = 3.0
    plastic_radius: float = 12.0
    steps_per_period: int = STEPS_PER_PERIOD


@dataclass(frozen=True)
class LoadBand:
    """Frequency band of a load record and what the FE needs from it."""

    f_low_hz: float
    f_high_hz: float
    shortest_wavelength_m: float
    """c₂ / f_high (m)."""


@dataclass
class FEResult:
    """Result of :func:`run_fe`: displacements below the invert, downward positive."""

    soil_law: str
    passages: int
    depth_m: np.ndarray
    """(nd,) depth below the ring–soil interface of the output nodes (m)."""
    peak_disp_m: np.ndarray
    """(nd,) peak downward displacement during the first passage (m)."""
    residual_disp_m: np.ndarray
    """(nd,) permanent displacement after the last passage, static equilibrium (m)."""
    peak_per_passage_m: np.ndarray
    """(passages, nd) peak displacement during each passage, from the initial state (m)."""
    residual_per_passage_m: np.ndarray
    """(passages, nd) permanent displacement after each passage (m), cumulative."""
    t_s: np.ndarray
    """(nt,) time of the histories (s), all passages with their tails."""
    disp_m: np.ndarray
    """(nd, nt) downward displacement histories (m)."""
    load_N_per_m: np.ndarray
    """(nt,) line load applied at the invert (N/m), after resampling."""
    mesh: dict = field(default_factory=dict)
    """Mesh and numerics: sizes, counts, band, time step, damping, iterations per step."""
    timings_s: dict = field(default_factory=dict)
    """Wall time of each phase (s)."""
    scenario_json: str = ""

    def to_npz(self, path: Path) -> None:
        """Write arrays and metadata to one ``.npz`` file."""
        meta = {
            "soil_law": self.soil_law,
            "passages": self.passages,
            "mesh": self.mesh,
            "timings_s": self.timings_s,
            "scenario_json": self.scenario_json,
        }
        np.savez_compressed(
            path, **{name: getattr(self, name) for name in _ARRAYS}, meta=json.dumps(meta)
        )

    @classmethod
    def from_npz(cls, path: Path) -> FEResult:
        """Read a file written by :meth:`to_npz`."""
        with np.load(path) as data:
            meta = json.loads(str(data["meta"]))
            arrays = {name: data[name] for name in _ARRAYS}
        return cls(**meta, **arrays)


_ARRAYS = (
    "depth_m",
    "peak_disp_m",
    "residual_disp_m",
    "peak_per_passage_m",
    "residual_per_passage_m",
    "t_s",
    "disp_m",
    "load_N_per_m",
)


# ---- inputs ---------------------------------------------------------------------------------
def load_band(line_load_N_per_m, dt_s: float, s_wave_speed: float) -> LoadBand:
    """Band of a load record: where its fluctuating energy passes 5 % and 99 %.

    Parameters
    ----------
    line_load_N_per_m : array_like
        Load history (N/m), sampled at ``dt_s``.
    dt_s : float
        Sampling interval (s), > 0.
    s_wave_speed : float
        Soil S-wave speed c₂ (m/s), > 0.

    Returns
    -------
    LoadBand
    """
    q = np.asarray(line_load_N_per_m, dtype=float)
    # no zero padding: after removing the mean it would add a step at the record's end
    energy = np.abs(np.fft.rfft(q - q.mean())) ** 2
    if q.size < 4 or not np.any(energy > 0):
        raise ValueError("the load history must have at least 4 samples and vary in time")
    f_hz = np.fft.rfftfreq(q.size, dt_s)
    cumulative = np.cumsum(energy) / energy.sum()
    f_low = float(f_hz[np.searchsorted(cumulative, BAND_ENERGY_LOW)])
    f_high = float(f_hz[np.searchsorted(cumulative, BAND_ENERGY_HIGH)])
    f_low = max(f_low, f_hz[1])
    f_high = max(f_high, 2.0 * f_low)
    return LoadBand(f_low, f_high, s_wave_speed / f_high)


def rayleigh_coefficients(loss_factor: float, f_low_hz: float, f_high_hz: float):
    """(a₀, a₁) of C = a₀M + a₁K with damping ratio η/2 at f_low and f_high.

    Parameters
    ----------
    loss_factor : float
        Hysteretic loss factor η_G (-), ≥ 0.
    f_low_hz, f_high_hz : float
        Matching frequencies (Hz), 0 < f_low < f_high.

    Returns
    -------
    tuple of float
        a₀ (1/s), a₁ (s).
    """
    w1, w2 = 2 * math.pi * f_low_hz, 2 * math.pi * f_high_hz
    zeta = 0.5 * loss_factor
    return 2 * zeta * w1 * w2 / (w1 + w2), 2 * zeta / (w1 + w2)


def drucker_prager_plane_strain(cohesion_Pa: float, friction_angle_deg: float):
    """OpenSees Drucker–Prager (σ_Y, ρ) matching Mohr–Coulomb (c, φ) in plane strain.

    Plane-strain match with associated flow: √J₂ = k − α I₁, α = tan φ / √(9 + 12 tan²φ),
    k = 3c / √(9 + 12 tan²φ); OpenSees writes ‖s‖ + ρ I₁ ≤ √(2/3) σ_Y, so ρ = √2 α and
    σ_Y = √3 k. For φ = 0 (undrained, Tresca) σ_Y = √3 c_u and ρ = 0.

    Parameters
    ----------
    cohesion_Pa : float
        c (Pa), ≥ 0.
    friction_angle_deg : float
        φ (degrees), 0 ≤ φ < 90.

    Returns
    -------
    tuple of float
        σ_Y (Pa), ρ (-).
    """
    tan_phi = math.tan(math.radians(friction_angle_deg))
    root = math.sqrt(9.0 + 12.0 * tan_phi**2)
    return math.sqrt(3.0) * 3.0 * cohesion_Pa / root, math.sqrt(2.0) * tan_phi / root


def resample_load(line_load_N_per_m, dt_s: float, dt_fe_s: float):
    """Average the load over each FE step of k·dt (k = round(dt_fe/dt)); returns (q, k·dt)."""
    q = np.asarray(line_load_N_per_m, dtype=float)
    k = max(1, math.floor(dt_fe_s / dt_s + 1e-9))
    n = q.size // k
    return q[: n * k].reshape(n, k).mean(axis=1), k * dt_s


# ---- geostatic stress -------------------------------------------------------------------------
@dataclass(frozen=True)
class Geostatic:
    """Linear geostatic stress field about the tunnel axis (compression positive, Pa)."""

    axis_depth: float
    unit_weight: float
    water_table_depth: float
    k0: float

    def depth(self, y):
        """Depth below the ground surface z = H_t − y (m)."""
        return self.axis_depth - np.asarray(y, dtype=float)

    def pore_pressure(self, y):
        """u = γ_w (z − z_w), extended linearly (Pa)."""
        return WATER_UNIT_WEIGHT * (self.depth(y) - self.water_table_depth)

    def vertical(self, y):
        """Total vertical stress σ_v = ρ g z (Pa)."""
        return self.unit_weight * self.depth(y)

    def effective_vertical(self, y):
        """σ′_v = σ_v − u (Pa)."""
        return self.vertical(y) - self.pore_pressure(y)

    def horizontal(self, y):
        """Total horizontal stress σ_h = K0 σ′_v + u (Pa)."""
        return self.k0 * self.effective_vertical(y) + self.pore_pressure(y)


def geostatic(scenario: Scenario) -> Geostatic:
    """The geostatic field of the scenario's long-term ground parameters (docs/model.md §10)."""
    lt = scenario.longterm
    return Geostatic(
        axis_depth=lt.axis_depth,
        unit_weight=scenario.soil.density * GRAVITY,
        water_table_depth=lt.water_table_depth,
        k0=lt.earth_pressure_coefficient,
    )


def undrained_strength(scenario: Scenario, y) -> np.ndarray:
    """c_u at height y above the axis (Pa): given, or cu_ratio · σ′_v0 (docs/model.md §10)."""
    lt = scenario.longterm
    if lt.undrained_strength is not None:
        return np.full(np.shape(y), float(lt.undrained_strength))
    return lt.cu_ratio * geostatic(scenario).effective_vertical(y)


# ---- mesh -------------------------------------------------------------------------------------
@dataclass(frozen=True)
class SectionMesh:
    """Structured half-annulus mesh: node (i, j) at radius radii[i], angle thetas[j] from the
    invert (x = r sin θ, y = −r cos θ)."""

    radii: np.ndarray
    thetas: np.ndarray

    @property
    def n_rings(self) -> int:
        """Number of element rings."""
        return self.radii.size - 1

    @property
    def n_theta(self) -> int:
        """Number of elements around the half circle."""
        return self.thetas.size - 1

    def node_tag(self, i, j):
        """OpenSees tag of soil node (i, j)."""
        return 1 + i * (self.n_theta + 1) + j

    def xy(self, i, j):
        """Coordinates of node (i, j) (m)."""
        r, t = self.radii[i], self.thetas[j]
        return r * np.sin(t), -r * np.cos(t)

    def centroids(self):
        """(x, y) of the element centroids (m), each (n_rings, n_theta)."""
        r = 0.5 * (self.radii[:-1] + self.radii[1:])[:, None]
        t = 0.5 * (self.thetas[:-1] + self.thetas[1:])[None, :]
        half = 0.5 * (self.thetas[1] - self.thetas[0])
        r = r * math.cos(half)  # mean of the four corners
        return r * np.sin(t), -r * np.cos(t)

    @property
    def largest_edge(self) -> float:
        """Longest element edge (m): the outer arc or the longest radial step."""
        arc = self.radii[-1] * 2.0 * math.sin(0.5 * (self.thetas[1] - self.thetas[0]))
        return float(max(arc, np.diff(self.radii).max()))


def section_mesh(ring_radius: float, outer_radius: float, element_size: float, aspect: float):
    """Radii and angles of the graded half-annulus mesh (see the module docstring)."""
    n_theta = max(4, math.ceil(math.pi * outer_radius / element_size))
    d_theta = math.pi / n_theta
    radii = [ring_radius]
    while radii[-1] < outer_radius - 1e-9:
        radii.append(radii[-1] + min(aspect * radii[-1] * d_theta, element_size))
    radii = np.array(radii)
    # stretch the graded steps so the last ring lands on R
    steps = np.diff(radii) * (outer_radius - ring_radius) / (radii[-1] - ring_radius)
    if steps.size > 1 and steps[-1] < 0.5 * steps[-2]:
        steps = np.diff(radii)[:-1] * (outer_radius - ring_radius) / (radii[-2] - ring_radius)
    radii = ring_radius + np.concatenate(([0.0], np.cumsum(steps)))
    return SectionMesh(radii=radii, thetas=np.linspace(0.0, math.pi, n_theta + 1))


def _arc_loads(mesh: SectionMesh, i: int, traction):
    """Consistent nodal forces (j → (fx, fy)) of a linear traction on the arc of ring i."""
    sign = 1.0 if i == mesh.n_rings else -1.0  # outward normal of the soil: +e_r or −e_r
    forces = np.zeros((mesh.n_theta + 1, 2))
    for j in range(mesh.n_theta):
        (x1, y1), (x2, y2) = mesh.xy(i, j), mesh.xy(i, j + 1)
        length = math.hypot(x2 - x1, y2 - y1)
        normal = sign * np.array([y2 - y1, -(x2 - x1)]) / length
        t1, t2 = traction(x1, y1, normal), traction(x2, y2, normal)
        forces[j] += length * (2 * t1 + t2) / 6
        forces[j + 1] += length * (t1 + 2 * t2) / 6
    return forces


def _body_loads(mesh: SectionMesh, body_force_y):
    """Consistent nodal forces (i, j) of a vertical body force b(y) (N/m³) on bilinear quads."""
    forces = np.zeros((mesh.n_rings + 1, mesh.n_theta + 1))
    gauss = np.array([-1.0, 1.0]) / math.sqrt(3.0)
    for i in range(mesh.n_rings):
        for j in range(mesh.n_theta):
            corners = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)]
            xy = np.array([mesh.xy(a, b) for a, b in corners])
            for s in gauss:
                for t in gauss:
                    shape = 0.25 * np.array(
                        [(1 - s) * (1 - t), (1 + s) * (1 - t), (1 + s) * (1 + t), (1 - s) * (1 + t)]
                    )
                    ds = 0.25 * np.array([-(1 - t), (1 - t), (1 + t), -(1 + t)])
                    dt = 0.25 * np.array([-(1 - s), -(1 + s), (1 + s), (1 - s)])
                    jac = abs((ds @ xy[:, 0]) * (dt @ xy[:, 1]) - (ds @ xy[:, 1]) * (dt @ xy[:, 0]))
                    b = body_force_y(shape @ xy[:, 1])
                    for (a, c), n in zip(corners, shape, strict=True):
                        forces[a, c] += n * b * jac
    return forces


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


def _build(ops, scenario: Scenario, mesh: SectionMesh, soil_law: str, plastic_radius: float):
    """Soil nodes, materials, quads and the symmetry conditions; returns bookkeeping."""
    soil = scenario.soil
    ops.wipe()
    ops.model("basic", "-ndm", 2, "-ndf", 2)
    nr, nt = mesh.n_rings, mesh.n_theta
    for i in range(nr + 1):
        for j in range(nt + 1):
            ops.node(int(mesh.node_tag(i, j)), *map(float, mesh.xy(i, j)))
    for i in range(nr + 1):
        ops.fix(int(mesh.node_tag(i, 0)), 1, 0)
        ops.fix(int(mesh.node_tag(i, nt)), 1, 0)

    shear, bulk = soil.shear_modulus, soil.bulk_modulus
    rho = soil.density
    n_elements = nr * nt
    ele_x, ele_y = mesh.centroids()
    ops.nDMaterial("ElasticIsotropic", 1, soil.youngs_modulus, soil.poisson_ratio, rho)
    plastic = (soil_law == "mohr_coulomb") & (np.hypot(ele_x, ele_y) <= plastic_radius)
    plastic &= ele_y < scenario.longterm.axis_depth
    strength = undrained_strength(scenario, ele_y)
    for i in range(nr):
        for j in range(nt):
            tag = 1 + i * nt + j
            mat = 1
            if plastic[i, j]:
                mat = 1 + tag
                sigma_y, rho_dp = drucker_prager_plane_strain(max(strength[i, j], 1.0), 0.0)
                ops.nDMaterial("J2Plasticity", mat, bulk, shear, sigma_y, sigma_y, 0.0, 0.0)
            nodes = [
                mesh.node_tag(a, b) for a, b in [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)]
            ]
            ops.element("quad", tag, *map(int, nodes), 1.0, "PlaneStrain", mat, 0.0, rho, 0.0, 0.0)

    return {"n_elements": n_elements, "n_plastic": int(plastic.sum())}


def _add_lining(ops, scenario: Scenario, mesh: SectionMesh) -> None:
    """Lining beams on the first ring, added stress-free in the stressed ground.

    The beam nodes are new, at rest on the undeformed circle, and tied to the soil nodes by
    stiff links (``zeroLength``, LINK_STIFFNESS per direction) that measure from the moment they
    are added: the gravity displacement of the soil (up to ~1 m with E = 6 MPa: the strain of the
    whole geostatic state) neither loads nor distorts the ring."""
    tunnel = scenario.tunnel
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
    h = tunnel.thickness
    e_plane = tunnel.youngs_modulus / (1.0 - tunnel.poisson_ratio**2)
    for j in range(nt):
        ops.element(
            "elasticBeamColumn", ele_base + j, beam_base + j, beam_base + j + 1,
            h, e_plane, h**3 / 12.0, 1, "-mass", tunnel.density * h,
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


def _apply_gravity(ops, scenario, mesh, soil_law):
    """Static gravity stage: body force and the geostatic tractions on both arcs (the inner one
    stands for the soil inside the tunnel); returns the link element holding the bottom node."""
    sxx, syy, body = _stress_field(scenario, soil_law)

    def traction(x, y, normal):
        return np.array([sxx(y) * normal[0], syy(y) * normal[1]])

    forces = np.zeros((mesh.n_rings + 1, mesh.n_theta + 1, 2))
    forces[..., 1] = _body_loads(mesh, body)
    forces[0] += _arc_loads(mesh, 0, traction)
    forces[-1] += _arc_loads(mesh, mesh.n_rings, traction)
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
    stiffness = 1e3 * scenario.soil.youngs_modulus
    ops.uniaxialMaterial("Elastic", anchor, stiffness)
    ops.element("zeroLength", anchor, ghost, int(mesh.node_tag(mesh.n_rings, 0)), "-mat", anchor,
                "-dir", 2)  # fmt: skip
    ops.constraints("Penalty", PENALTY, PENALTY)
    ops.numberer("RCM")
    ops.system("UmfPack")
    ops.test("NormDispIncr", 1e-9, 50)
    ops.algorithm("Newton")
    n_steps = 1 if soil_law == "elastic" else 10
    ops.integrator("LoadControl", 1.0 / n_steps)
    ops.analysis("Static")
    if ops.analyze(n_steps) != 0:
        raise FEConvergenceError(
            "the gravity stage did not converge (soil too weak for its K0 state?)"
        )
    ops.loadConst("-time", 0.0)
    return anchor


def _add_boundary(ops, scenario, mesh):
    """Viscous–spring boundary on r = R.

    Added after gravity: OpenSees' zeroLength measures its deformation from the node
    displacements at the time it is added, so the springs start unloaded."""
    soil = scenario.soil
    radius = mesh.radii[-1]
    i = mesh.n_rings
    d_theta = mesh.thetas[1] - mesh.thetas[0]
    ghost_base = _next_tag(ops.getNodeTags())
    ele_base = _next_tag(ops.getEleTags())
    for j in range(mesh.n_theta + 1):
        node = int(mesh.node_tag(i, j))
        length = radius * d_theta * (0.5 if j in (0, mesh.n_theta) else 1.0)
        x, y = mesh.xy(i, j)
        ghost = int(ghost_base + j)
        ops.node(ghost, float(x), float(y))
        ops.fix(ghost, 1, 1)
        normal_mat, tangential_mat = 2 * (ele_base + j), 2 * (ele_base + j) + 1
        ops.uniaxialMaterial(
            "Elastic", normal_mat, SPRING_NORMAL * soil.shear_modulus / radius * length,
            soil.density * soil.p_wave_speed * length,
        )  # fmt: skip
        ops.uniaxialMaterial(
            "Elastic", tangential_mat, SPRING_TANGENTIAL * soil.shear_modulus / radius * length,
            soil.density * soil.s_wave_speed * length,
        )  # fmt: skip
        theta = mesh.thetas[j]
        radial = (math.sin(theta), -math.cos(theta), 0.0)
        tangential = (math.cos(theta), math.sin(theta), 0.0)
        ops.element(
            "zeroLength", int(ele_base + j), ghost, node, "-mat", normal_mat, tangential_mat,
            "-dir", 1, 2, "-orient", *radial, *tangential,
        )  # fmt: skip


def _static_equilibrium(ops):
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
    ops.test("NormDispIncr", 1e-10, 100)
    ops.algorithm("Newton")
    ops.integrator("LoadControl", 0.0)
    ops.analysis("Static")
    if ops.analyze(1) != 0:
        raise FEConvergenceError("the static equilibrium after a passage did not converge")


def _transient(ops, soil_law, a0, a1, unbalance_N):
    """Newmark average acceleration with Rayleigh damping.

    Elastic soil: one factorisation, no iterations. Plastic soil: modified Newton on the
    tangent of the passage's first step, factorised once (with the mass term 4M/Δt² in it, it
    needs about as many iterations as Krylov–Newton refactorised every step:
    docs/fe_section.md); a step has converged when the unbalanced force is below
    ``unbalance_N`` or the displacement correction below DISP_TOLERANCE."""
    ops.wipeAnalysis()
    ops.constraints("Penalty", PENALTY, PENALTY)
    ops.numberer("RCM")
    ops.system("ProfileSPD")
    ops.rayleigh(a0, 0.0, a1, 0.0)
    if soil_law == "elastic":
        ops.algorithm("Linear", "-factorOnce")
    else:
        ops.test("NormDispOrUnbalance", DISP_TOLERANCE, unbalance_N, 100, 0)
        ops.algorithm("ModifiedNewton", "-factoronce")
    ops.integrator("Newmark", 0.5, 0.25)
    ops.analysis("Transient")


# ---- public entry points ----------------------------------------------------------------------
def _check_mesh(mesh: FEMesh, ring_radius: float, band: LoadBand) -> float:
    """Largest element size to use (m); ValueError naming the numbers when too coarse."""
    if not mesh.outer_radius > ring_radius + 1.0:
        raise ValueError(
            f"mesh.outer_radius = {mesh.outer_radius:g} m must exceed the ring radius "
            f"{ring_radius:g} m by more than 1 m"
        )
    if mesh.steps_per_period < 4:
        raise ValueError(f"mesh.steps_per_period = {mesh.steps_per_period} must be ≥ 4")
    if mesh.radial_aspect < 1.0:
        raise ValueError(f"mesh.radial_aspect = {mesh.radial_aspect:g} must be ≥ 1")
    limit = band.shortest_wavelength_m / ELEMENTS_PER_WAVELENGTH
    size = limit if mesh.element_size is None else mesh.element_size
    if not 0 < size <= limit * (1 + 1e-9):
        raise ValueError(
            f"mesh.element_size = {size:g} m cannot resolve the shortest wavelength of the load "
            f"band: c₂/f_high = {band.shortest_wavelength_m:.3g} m at f_high = "
            f"{band.f_high_hz:.3g} Hz needs elements ≤ {limit:.3g} m "
            f"({ELEMENTS_PER_WAVELENGTH} per wavelength)"
        )
    return size


def run_fe(
    scenario: Scenario,
    soil_law: str = "elastic",
    passages: int = 1,
    mesh: FEMesh | None = None,
    progress: Progress | None = None,
    load: tuple[np.ndarray, float] | None = None,
) -> FEResult:
    """Run the OpenSeesPy plane-strain section under the line-load history at the invert.

    Parameters
    ----------
    scenario : Scenario
        Tunnel, soil (E, ν, ρ, η_G) and the long-term ground parameters (axis depth, water
        table, φ′ for K0, c_u); the load comes from ``model.pipeline.run(scenario)``.
    soil_law : {"elastic", "mohr_coulomb"}
        Soil model (module docstring).
    passages : int
        Passages in a row, ≥ 1.
    mesh : FEMesh, optional
        Mesh and boundary; default ``FEMesh()``.
    progress : callable(stage, fraction), optional
        Told "load", "gravity" and "dynamic" with the fraction done, 0 to 1.
    load : (ndarray, float), optional
        A line-load history (N/m) and its sampling interval (s) to use instead of the
        pipeline's.

    Returns
    -------
    FEResult

    Raises
    ------
    ValueError
        Unknown law, bad passages, or a mesh that cannot resolve the load band.
    FEUnavailableError
        OpenSeesPy missing or its shared library not loadable.
    """
    if soil_law not in SOIL_LAWS:
        raise ValueError(f"soil_law = {soil_law!r} must be one of {SOIL_LAWS}")
    if not (isinstance(passages, int) and 1 <= passages <= 100):
        raise ValueError(f"passages = {passages!r} must be an integer in [1, 100]")
    mesh = mesh or FEMesh()
    report = progress or (lambda stage, fraction: None)
    ops = opensees()
    timings = {}
    start = time.perf_counter()
    report("load", 0.0)
    if load is None:
        from model.pipeline import STAGES, run

        def pipeline_progress(stage: str, fraction: float) -> None:
            report("load", (STAGES.index(stage) + fraction) / len(STAGES))

        results = run(scenario, progress=pipeline_progress, cache=None)
        q_raw, dt_raw = results.load.line_load_N_per_m, float(results.load.t_s[1])
    else:
        q_raw, dt_raw = np.asarray(load[0], dtype=float), float(load[1])
    soil, tunnel = scenario.soil, scenario.tunnel
    band = load_band(q_raw, dt_raw, soil.s_wave_speed)
    size = _check_mesh(mesh, tunnel.ring_radius, band)
    q, dt = resample_load(q_raw, dt_raw, 1.0 / (mesh.steps_per_period * band.f_high_hz))
    timings["load"] = time.perf_counter() - start
    report("load", 1.0)

    start = time.perf_counter()
    report("gravity", 0.0)
    grid = section_mesh(tunnel.ring_radius, mesh.outer_radius, size, mesh.radial_aspect)
    book = _build(ops, scenario, grid, soil_law, mesh.plastic_radius)
    anchor = _apply_gravity(ops, scenario, grid, soil_law)
    ops.remove("element", anchor)
    _add_lining(ops, scenario, grid)
    _add_boundary(ops, scenario, grid)
    _static_equilibrium(ops)
    timings["gravity"] = time.perf_counter() - start
    report("gravity", 1.0)

    # one passage = load record + quiet tail; the boundary relaxes in ~ρ c₁ R / (α_N G)
    relax = soil.p_wave_speed * mesh.outer_radius / (SPRING_NORMAL * soil.s_wave_speed**2)
    n_tail = max(
        3, math.ceil(TAIL_BOUNDARY_TIMES * (mesh.outer_radius / soil.s_wave_speed + relax) / dt)
    )
    n_passage = q.size + n_tail
    history = np.concatenate([np.concatenate([q, np.zeros(n_tail)])] * passages)
    a0, a1 = rayleigh_coefficients(soil.shear_loss_factor, band.f_low_hz, band.f_high_hz)
    ops.timeSeries("Path", 3, "-dt", dt, "-values", *history.tolist(), 0.0)
    ops.pattern("Plain", 3, 3)
    ops.load(int(grid.node_tag(0, 0)), 0.0, -0.5)  # half the line load on the half model

    depth_nodes = [int(grid.node_tag(i, 0)) for i in range(grid.n_rings + 1)]
    reference = np.array([ops.nodeDisp(n, 2) for n in depth_nodes])
    disp = np.zeros((len(depth_nodes), history.size + 1))
    residual = np.zeros((passages, len(depth_nodes)))
    start = time.perf_counter()
    step = iterations = 0
    report("dynamic", 0.0)
    for passage in range(passages):
        _transient(ops, soil_law, a0, a1, UNBALANCE_TOLERANCE * 0.5 * np.abs(history).max())
        for _ in range(n_passage):
            if ops.analyze(1, dt) != 0:
                raise FEConvergenceError(
                    f"the dynamic analysis did not converge at t = {(step + 1) * dt:.3f} s"
                )
            step += 1
            iterations += max(ops.testIter(), 1)  # the linear algorithm solves once, reports 0
            disp[:, step] = reference - np.array([ops.nodeDisp(n, 2) for n in depth_nodes])
            if step % 50 == 0:
                report("dynamic", step / history.size)
        end = (passage + 1) * n_passage * dt
        ops.setTime(end - 1.5 * dt)  # between two samples of the quiet tail: no train load
        _static_equilibrium(ops)
        ops.setTime(end)
        residual[passage] = reference - np.array([ops.nodeDisp(n, 2) for n in depth_nodes])
    timings["dynamic"] = time.perf_counter() - start
    report("dynamic", 1.0)
    peaks = np.array(
        [disp[:, 1 + p * n_passage : 1 + (p + 1) * n_passage].max(axis=1) for p in range(passages)]
    )
    info = {
        "outer_radius_m": float(grid.radii[-1]),
        "element_size_m": float(size),
        "largest_edge_m": grid.largest_edge,
        "n_theta": grid.n_theta,
        "n_rings": grid.n_rings,
        "n_elements": book["n_elements"],
        "n_plastic_elements": book["n_plastic"],
        "n_nodes": (grid.n_rings + 1) * (grid.n_theta + 1),
        "band_hz": [band.f_low_hz, band.f_high_hz],
        "shortest_wavelength_m": band.shortest_wavelength_m,
        "dt_s": dt,
        "steps_per_passage": n_passage,
        "iterations_per_step": iterations / step,
        "rayleigh_a0_per_s": a0,
        "rayleigh_a1_s": a1,
    }
    ops.wipe()
    return FEResult(
        soil_law=soil_law,
        passages=passages,
        depth_m=grid.radii - grid.radii[0],
        peak_disp_m=peaks[0],
        residual_disp_m=residual[-1],
        peak_per_passage_m=peaks,
        residual_per_passage_m=residual,
        t_s=np.arange(history.size + 1) * dt,
        disp_m=disp,
        load_N_per_m=np.concatenate([[0.0], history]),
        mesh=info,
        timings_s=timings,
        scenario_json=scenario.to_json(),
    )


def gravity_state(scenario: Scenario, soil_law: str = "elastic", mesh: FEMesh | None = None):
    """Element stresses after the gravity stage (before the lining and the boundary).

    Parameters
    ----------
    scenario : Scenario
        Soil and long-term ground parameters.
    soil_law : {"elastic", "mohr_coulomb"}
        Soil model; the plastic one carries the deviatoric part of the field.
    mesh : FEMesh, optional
        Mesh; ``element_size`` must be given.

    Returns
    -------
    x_m, y_m : ndarray
        (n_rings, n_theta) element centroids (m), y up from the tunnel axis.
    stress_Pa : ndarray
        (n_rings, n_theta, 3) element-average σ_xx, σ_yy, τ_xy (Pa, tension positive).
    """
    mesh = mesh or FEMesh()
    if mesh.element_size is None:
        raise ValueError("gravity_state needs mesh.element_size (there is no load band)")
    ops = opensees()
    grid = section_mesh(
        scenario.tunnel.ring_radius, mesh.outer_radius, mesh.element_size, mesh.radial_aspect
    )
    _build(ops, scenario, grid, soil_law, mesh.plastic_radius)
    _apply_gravity(ops, scenario, grid, soil_law)
    stress = _element_stress(ops, grid)
    ops.wipe()
    return (*grid.centroids(), stress)


def _element_stress(ops, mesh: SectionMesh) -> np.ndarray:
    """(n_rings, n_theta, 3) element-average σ_xx, σ_yy, τ_xy (Pa, tension +)."""
    out = np.empty((mesh.n_rings, mesh.n_theta, 3))
    for i in range(mesh.n_rings):
        for j in range(mesh.n_theta):
            s = np.asarray(ops.eleResponse(1 + i * mesh.n_theta + j, "stresses"))
            out[i, j] = s.reshape(4, -1)[:, :3].mean(axis=0)
    return out


def analytical_profile(scenario: Scenario, line_load_N_per_m, dt_s: float, depth_m):
    """Peak downward displacement of the analytical 2D model (docs/model.md §7–8) at given depths.

    ``model.soil.response.soil_response`` on the same load history, its depth grid reaching the
    deepest requested depth; interpolated (linearly) to ``depth_m``.

    Parameters
    ----------
    scenario : Scenario
        Tunnel, soil and numerics (n_harmonics, soil_max_frequency, zero_pad_factor).
    line_load_N_per_m : array_like
        Line-load history (N/m) sampled at ``dt_s`` (s).
    dt_s : float
        Sampling interval (s).
    depth_m : array_like
        Depths below the ring–soil interface (m), ≥ 0.

    Returns
    -------
    ndarray
        Peak downward displacement (m) at each depth.
    """
    from model.soil.response import soil_response

    depth = np.asarray(depth_m, dtype=float)
    numerics = scenario.copy().numerics
    numerics.max_depth = max(11.0, float(depth.max()))  # the parameter's lower bound
    numerics.n_depths = max(2, math.ceil(numerics.max_depth / 0.25) + 1)
    response = soil_response(line_load_N_per_m, dt_s, scenario.tunnel, scenario.soil, numerics)
    return np.interp(depth, response.depth_m, response.peak_disp_m)


# ---- stored results ---------------------------------------------------------------------------
def scenario_key(scenario: Scenario) -> str:
    """Hash of the scenario's JSON (16 hex digits): the key of stored FE results."""
    return hashlib.sha256(scenario.to_json(indent=None).encode("utf-8")).hexdigest()[:16]


def result_path(scenario: Scenario, folder, soil_law: str) -> Path:
    """File of the stored FE result of a scenario and soil law in ``folder``."""
    return Path(folder) / f"fe_{scenario_key(scenario)}_{soil_law}.npz"


def save_fe_result(result: FEResult, folder) -> Path:
    """Store a result under its scenario's key; returns the file written.

    Parameters
    ----------
    result : FEResult
        A result of :func:`run_fe`.
    folder : path-like
        Folder (created if missing).

    Returns
    -------
    Path
    """
    path = result_path(Scenario.from_json(result.scenario_json), folder, result.soil_law)
    path.parent.mkdir(parents=True, exist_ok=True)
    result.to_npz(path)
    return path


def stored_fe_result(scenario: Scenario, folder, soil_law: str | None = None) -> FEResult | None:
    """The stored FE result for this exact scenario, or None.

    Parameters
    ----------
    scenario : Scenario
        The scenario; any parameter change gives another key.
    folder : path-like
        Folder of stored results (missing: None).
    soil_law : {"elastic", "mohr_coulomb"} or None
        Law wanted; None takes Mohr–Coulomb if stored, else elastic.

    Returns
    -------
    FEResult or None
    """
    for law in (soil_law,) if soil_law else ("mohr_coulomb", "elastic"):
        path = result_path(scenario, folder, law)
        if path.is_file():
            return FEResult.from_npz(path)
    return None


# ---- command line -----------------------------------------------------------------------------
FE_STAGES = ("load", "gravity", "dynamic")


def build_parser() -> argparse.ArgumentParser:
    """Argument parser of ``python -m model fe``."""
    from model.__main__ import add_scenario_arguments

    parser = argparse.ArgumentParser(
        prog="python -m model fe",
        description="Run the OpenSeesPy plane-strain section (docs/model.md §12) and store its "
        "depth profile of peak and permanent displacement.",
    )
    add_scenario_arguments(parser)
    parser.add_argument("--law", choices=SOIL_LAWS, default="mohr_coulomb", help="soil law")
    parser.add_argument("--passages", type=int, default=1, help="passages in a row (default 1)")
    parser.add_argument(
        "--outer-radius", type=float, default=FEMesh.outer_radius, help="boundary radius R (m)"
    )
    parser.add_argument(
        "--element-size", type=float, default=None, help="largest element edge (m); default "
        "from the load band",
    )  # fmt: skip
    parser.add_argument("--out", type=Path, required=True, help="output folder (created)")
    parser.add_argument("--quiet", action="store_true", help="no progress bar or summary")
    return parser


def write_fe_outputs(result: FEResult, out: Path) -> list[Path]:
    """Stored result (npz, keyed by the scenario), depth-profile CSV and summary JSON."""
    stored = save_fe_result(result, out)
    columns = {"depth_m": result.depth_m, "peak_disp_m": result.peak_disp_m}
    for p, row in enumerate(result.residual_per_passage_m, start=1):
        columns[f"residual_after_passage_{p}_m"] = row
    profile = out / f"fe_depth_profile_{result.soil_law}.csv"
    np.savetxt(
        profile,
        np.column_stack(list(columns.values())),
        delimiter=",",
        header=",".join(columns),
        comments="",
        fmt="%.9g",
    )
    summary = out / f"fe_summary_{result.soil_law}.json"
    content = {
        "soil_law": result.soil_law,
        "passages": result.passages,
        "peak_disp_invert_m": float(result.peak_disp_m[0]),
        "residual_disp_invert_m": float(result.residual_disp_m[0]),
        "mesh": result.mesh,
        "timings_s": result.timings_s,
    }
    summary.write_text(json.dumps(content, indent=2) + "\n", encoding="utf-8")
    return [stored, profile, summary]


def main(argv: list[str] | None = None) -> int:
    """``python -m model fe``: returns the exit code (2 for bad input or an unavailable FE)."""
    from model.__main__ import TerminalProgress, load_scenario
    from model.pipeline import SimulationError

    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        scenario = load_scenario(args)
        mesh = FEMesh(outer_radius=args.outer_radius, element_size=args.element_size)
        progress = None if args.quiet else TerminalProgress(stages=FE_STAGES)
        try:
            result = run_fe(scenario, args.law, args.passages, mesh, progress=progress)
        finally:
            if progress is not None:
                progress.close()
    except (
        ValueError,
        KeyError,
        OSError,
        FEUnavailableError,
        FEConvergenceError,
        SimulationError,
    ) as error:
        message = error.args[0] if isinstance(error, KeyError) and error.args else error
        parser.exit(2, f"error: {message}\n")
    paths = write_fe_outputs(result, args.out)
    if not args.quiet:
        residual = ", ".join(f"{r * 1e3:.3f}" for r in result.residual_per_passage_m[:, 0])
        print(
            f"{result.soil_law}: peak displacement at the invert "
            f"{result.peak_disp_m[0] * 1e3:.2f} mm, permanent after each passage {residual} mm; "
            f"{result.mesh['n_elements']} elements, {sum(result.timings_s.values()):.0f} s; "
            f"{len(paths)} files in {args.out}"
        )
    return 0
