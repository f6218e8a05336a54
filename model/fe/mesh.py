"""Mesh of the FE section: the user's settings and the structured half-annulus.

- **Half model.** The section is symmetric about the vertical axis and so is the invert load:
  only x ≥ 0 is meshed, with u_x = 0 (and, on the lining, zero rotation) on the axis, and half
  the line load at the invert.
- **Mesh.** Structured radial–circumferential quads from the ring radius a to the outer radius
  R: n_θ equal angles over the half circle, rings growing geometrically (radial size
  ``radial_aspect`` × the circumferential size r Δθ) until they reach the largest element size
  h, then uniform. Bilinear ``quad`` elements (2×2 Gauss). The largest element edge is h, and h
  must resolve the shortest S wavelength of the load band, λ_min = c₂/f_max, with at least
  ``ELEMENTS_PER_WAVELENGTH`` elements (else the mesh is refused).

The consistent nodal loads of a linear traction on an arc and of a body force on the quads are
here too (used by the gravity stage of ``model.fe.build``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

ELEMENTS_PER_WAVELENGTH = 6
"""Fewest bilinear elements per shortest S wavelength of the load band (phase error ≲ 3 %)."""
GAUSS_POINTS = np.array([-1.0, 1.0]) / math.sqrt(3.0)
"""The 2-point Gauss rule on [−1, 1] (unit weights) of the bilinear quads, per direction."""
STEPS_PER_PERIOD = 20
"""FE time steps per period of f_hi (Newmark period elongation ≈ 0.8 %)."""

FE_BYTES_PER_ELEMENT = 15e3
"""Peak memory per soil element of the FE section (B), the larger of the two engines': the
native engine's peak ru_maxrss above the start, Mohr–Coulomb law, up to its first time step
(paper scenario, R = 30 m: 163 MB for 12 474 elements of 0.5 m and 571 MB for 49 387 of
0.25 m, 11.6–13 kB each, most of it SuperLU's factors, 29 M entries at 49 387 elements; 181 MB,
14.5 kB each, at 12 474 elements with c_u = 12 kPa, where the gravity stage yields and Newton
refactorises); OpenSees' growth over the same meshes was 9 kB per element (108 and 427 MB)."""
MAX_FE_ELEMENTS = 200_000
"""Most soil elements of an FE section: about 3 GB at :data:`FE_BYTES_PER_ELEMENT` (a 0.15 m
mesh to R = 30 m has 137 122)."""


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

    def __post_init__(self) -> None:
        """Refuse settings that no mesh can have, naming the setting, its value and what is
        allowed (limits that depend on the scenario and the load band are run_fe's)."""
        rules = (
            ("outer_radius", " m", lambda v: v > 0, "a length > 0 m"),
            ("radial_aspect", "", lambda v: v >= 1, "a ratio ≥ 1"),
            ("plastic_radius", " m", lambda v: v >= 0, "a radius ≥ 0 m"),
            ("element_size", " m", lambda v: v > 0, ELEMENT_SIZE_ALLOWED),
            ("steps_per_period", "", lambda v: v >= 4 and v == int(v), "a whole number ≥ 4"),
        )
        for name, unit, holds, allowed in rules:
            value = getattr(self, name)
            if name == "element_size" and value is None:
                continue
            if not (_finite(value) and holds(value)):
                shown = f"{value:g}{unit}" if _finite(value) else repr(value)
                raise ValueError(f"mesh.{name} = {shown} must be {allowed}")


ELEMENT_SIZE_ALLOWED = (
    f"a length > 0 m, or None for the size that resolves the load band "
    f"(λ_min/{ELEMENTS_PER_WAVELENGTH})"
)
"""What ``element_size`` may be, as the refusals of FEMesh and ``python -m model fe`` say it."""


def _finite(value) -> bool:
    """A real number, neither NaN nor infinite."""
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


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
    """Radii and angles of the graded half-annulus mesh (see the module docstring); a mesh of
    more than :data:`MAX_FE_ELEMENTS` elements is refused before it is built."""
    check_mesh_size(ring_radius, outer_radius, element_size)
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


def check_mesh_size(ring_radius: float, outer_radius: float, element_size: float) -> None:
    """Refuse a mesh of more than :data:`MAX_FE_ELEMENTS` elements, from a lower bound of its
    count that needs no mesh: n_θ = πR/h elements around, at least (R − a)/h rings (no radial
    step exceeds h)."""
    with np.errstate(over="ignore"):
        around = np.float64(math.pi) * outer_radius / element_size
        fewest = around * max(outer_radius - ring_radius, element_size) / element_size
    if not fewest <= MAX_FE_ELEMENTS:  # also inf and nan
        with np.errstate(over="ignore"):
            area = np.float64(math.pi) * outer_radius * (outer_radius - ring_radius)
        shortest = math.sqrt(area / MAX_FE_ELEMENTS) if np.isfinite(area) else math.inf
        size = f" ≥ {shortest:.3g} m" if math.isfinite(shortest) else ""
        count = f"at least {fewest:.3g}" if np.isfinite(fewest) else "more than 1e308"
        raise ValueError(
            f"mesh.element_size = {element_size:g} m with mesh.outer_radius = {outer_radius:g} m "
            f"gives {count} elements, more than the {MAX_FE_ELEMENTS} allowed (about "
            f"{MAX_FE_ELEMENTS * FE_BYTES_PER_ELEMENT / 1e9:.1f} GB): take a larger element "
            f"size{size} or a smaller outer radius"
        )


def arc_loads(mesh: SectionMesh, i: int, traction):
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


def body_loads(mesh: SectionMesh, body_force_y):
    """Consistent nodal forces (i, j) of a vertical body force b(y) (N/m³) on bilinear quads:
    Σ N_a b(y) |J| over each quad's 2 × 2 Gauss points."""
    nr, nt = mesh.n_rings, mesh.n_theta
    i, j = np.meshgrid(np.arange(nr), np.arange(nt), indexing="ij")
    corners = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)]
    x = np.stack([mesh.xy(a, b)[0] for a, b in corners], axis=-1)  # (nr, nt, 4)
    y = np.stack([mesh.xy(a, b)[1] for a, b in corners], axis=-1)
    forces = np.zeros((nr + 1, nt + 1))
    for s in GAUSS_POINTS:
        for t in GAUSS_POINTS:
            shape = 0.25 * np.array(
                [(1 - s) * (1 - t), (1 + s) * (1 - t), (1 + s) * (1 + t), (1 - s) * (1 + t)]
            )
            ds = 0.25 * np.array([-(1 - t), (1 - t), (1 + t), -(1 + t)])
            dt = 0.25 * np.array([-(1 - s), -(1 + s), (1 + s), (1 - s)])
            jac = np.abs((x @ ds) * (y @ dt) - (y @ ds) * (x @ dt))
            load = body_force_y(y @ shape) * jac
            for (a, b), n in zip(corners, shape, strict=True):
                np.add.at(forces, (a, b), n * load)
    return forces
