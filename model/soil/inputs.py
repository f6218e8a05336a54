"""What the tunnel–soil kernels take from the scenario, checked: shared by every soil model.

The lining's ring constants (a, m, K, D) and the soil's complex moduli (μ*, λ*, ρ), refused with
the parameter named when outside the bounds ``model.params`` declares or not finite; the checks
of the array arguments (frequencies, depths, harmonics); and the Fourier coefficients of a unit
line load at the invert, c_0 = 1/(2πa), c_n = 1/(πa) (docs/model.md §7). Used by the 2D section
(``model.soil.section_2d``), the 2.5D model (``model.soil.moving_load_2p5d``) and its point
load (``model.soil.point_load``).
"""

from __future__ import annotations

import cmath
import math

import numpy as np

from model.params import Soil, Tunnel


def _checked_values(obj, section_class: type, names: tuple[str, ...]) -> None:
    """Refuse values of ``obj`` outside the bounds that ``model.params`` declares for them.

    The parameter classes are the only table of bounds: a Tunnel or Soil object was checked on
    assignment against its own declared parameters (a subclass may widen them on purpose, e.g.
    for an idealised limit in a test); any other object is checked against the declarations of
    ``section_class``, with the same message.
    """
    if isinstance(obj, section_class):
        return
    for name in names:
        section_class.param[name]._validate(getattr(obj, name))


def _finite_constants(section: str, obj, names: tuple[str, ...], compute) -> tuple:
    """Result of ``compute()``, refused (naming the inputs) if a constant is not finite."""
    try:
        constants = compute()
    except ArithmeticError:
        constants = (math.nan,)
    if not all(cmath.isfinite(value) for value in constants):
        values = ", ".join(f"{section}.{name} = {getattr(obj, name)!r}" for name in names)
        raise ValueError(f"{values} give non-finite model constants; check these inputs")
    return constants


RING_INPUTS = ("inner_radius", "thickness", "youngs_modulus", "poisson_ratio", "density")
SOIL_INPUTS = (
    "youngs_modulus",
    "poisson_ratio",
    "density",
    "shear_loss_factor",
    "bulk_loss_factor",
)


def ring_constants(tunnel) -> tuple[float, float, float, float]:
    """(a, m, K, D) of the lining ring, after checking its parameters."""
    _checked_values(tunnel, Tunnel, RING_INPUTS)
    return _finite_constants(
        "tunnel",
        tunnel,
        RING_INPUTS,
        lambda: (
            tunnel.ring_radius,
            tunnel.density * tunnel.thickness,
            tunnel.extensional_stiffness,
            tunnel.bending_stiffness,
        ),
    )


def soil_constants(soil) -> tuple[complex, complex, float]:
    """(μ*, λ*, ρ) of the hysteretically damped soil, after checking its parameters."""
    _checked_values(soil, Soil, SOIL_INPUTS)

    def moduli():
        shear = soil.shear_modulus * (1.0 + 1j * soil.shear_loss_factor)
        bulk = soil.bulk_modulus * (1.0 + 1j * soil.bulk_loss_factor)
        return shear, bulk - 2.0 * shear / 3.0, soil.density

    return _finite_constants("soil", soil, SOIL_INPUTS, moduli)


def as_1d(values, name: str, unit: str) -> np.ndarray:
    """Float array of at most one dimension, refusing NaN and infinity."""
    array = np.atleast_1d(np.asarray(values, dtype=float))
    if array.ndim != 1:
        raise ValueError(f"{name} must be a scalar or a 1-D array, got shape {array.shape}")
    if not np.all(np.isfinite(array)):
        raise ValueError(
            f"{name} contains {float(array[~np.isfinite(array)][0])!r}; finite values "
            f"in {unit} are required"
        )
    return array


def check_harmonics(n_harmonics) -> int:
    """n_harmonics as an int ≥ 0."""
    if (
        isinstance(n_harmonics, bool)
        or not isinstance(n_harmonics, int | np.integer)
        or (n_harmonics < 0)
    ):
        raise ValueError(f"n_harmonics = {n_harmonics!r} must be an integer ≥ 0")
    return int(n_harmonics)


def checked_depths(depth_m) -> np.ndarray:
    """Depths d ≥ 0 below the ring–soil interface (m), as a finite 1-D array."""
    depth = as_1d(depth_m, "depth_m", "m")
    if np.any(depth < 0.0):
        bad = float(depth[depth < 0.0][0])
        raise ValueError(
            f"depth_m = {bad!r} is inside the lining: depths are measured from "
            f"the ring–soil interface and must be ≥ 0 m"
        )
    return depth


def invert_load_coefficients(ring_radius: float, n_harmonics: int) -> np.ndarray:
    """Fourier coefficients of a unit downward line load at the invert (1/m).

    q_r(θ) = δ(aθ) = Σ_n c_n cos nθ per unit arc length with c_0 = 1/(2πa), c_n = 1/(πa).

    Parameters
    ----------
    ring_radius : float
        Ring radius a (m).
    n_harmonics : int
        Highest harmonic N; coefficients for n = 0..N.

    Returns
    -------
    ndarray
        (N + 1,) coefficients in 1/m (radial traction in Pa per N/m of line load).
    """
    coefficients = np.full(check_harmonics(n_harmonics) + 1, 1.0 / (np.pi * ring_radius))
    coefficients[0] *= 0.5
    return coefficients
