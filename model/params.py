"""Parameter objects of the vehicle–track–tunnel–soil model.

The single source of truth for defaults, physical bounds, slider ranges (``softbounds``), units
(in each ``label``) and derived quantities. Defaults follow docs/model.md: the paper's
Tables 1, 3 and 4 where they are usable, stated assumptions where the paper is silent (its
Table 2 is missing). Every value is SI except ``Train.speed_kmh``.

A bad value is refused at assignment with a message that names the parameter, the value and
the allowed range; constraints between parameters are checked by :meth:`Scenario.validate`
before any computation.
"""

from __future__ import annotations

import json
import math
from importlib.resources import files
from pathlib import Path
from typing import Any

import param
from numpy import bool_ as numpy_bool

GRAVITY = 9.81  # m/s², standard value used for static loads
# Package data (presets, the paper's reported numbers, an example measured profile), shipped
# inside the package so that a plain `pip install` finds it from any working directory.
DATA_DIR = Path(str(files("model") / "data"))
PRESETS_FILE = DATA_DIR / "presets.json"

# Hertz contact constant G = a R^b × 1e-8 m/N^(2/3) (Zhai's empirical fits), by wheel tread type.
HERTZ_FITS = {"conical": (4.57, -0.149), "worn": (3.86, -0.115)}

# FRA vertical-profile roughness parameter A_v in cm²·rad/m for track classes 1–6.
FRA_ROUGHNESS_CM2_RAD_PER_M = {1: 1.2107, 2: 1.0181, 3: 0.6816, 4: 0.5376, 5: 0.2095, 6: 0.0339}


# Thin-ring limit on the lining, h/a (Scenario.validate): thin-ring theory neglects shear
# deformation and the stress variation through the thickness, relative errors of order (h/a)²
# (~4 % at 0.2); tunnel linings have h/a ≈ 0.05–0.15 (the paper's 0.105).
THIN_RING_MAX_RATIO = 0.2


class ScenarioError(ValueError):
    """Raised when parameter values are individually valid but inconsistent with each other."""


def _format_range(bounds, inclusive) -> str:
    low, high = bounds
    left = "[" if inclusive[0] else "("
    right = "]" if inclusive[1] else ")"
    low_s = "-inf" if low is None else f"{low:g}"
    high_s = "inf" if high is None else f"{high:g}"
    right = ")" if high is None else right
    return f"{left}{low_s}, {high_s}{right}"


class _RangeMessage:
    """Mixin: a bounds violation names the parameter, the value, the allowed range and the unit."""

    def _validate_bounds(self, val, bounds, inclusive_bounds):
        try:
            if val is not None and not math.isfinite(val):
                raise ValueError("not finite")
            super()._validate_bounds(val, bounds, inclusive_bounds)
        except ValueError:
            owner = self.owner if isinstance(self.owner, type) else type(self.owner)
            where = f"{owner.__name__}.{self.name}" if self.owner is not None else self.name
            raise ValueError(
                f"{where} = {val!r} is outside the allowed range "
                f"{self._allowed_text(bounds, inclusive_bounds)} ({self.label})"
            ) from None

    def _allowed_text(self, bounds, inclusive_bounds) -> str:
        """The allowed values, as the refusal message states them."""
        return _format_range(bounds, inclusive_bounds)


class _NotBoolean:
    """Mixin: refuse True/False where a number is expected (bool is an int subclass)."""

    def _validate_value(self, val, allow_None):
        if isinstance(val, bool | numpy_bool):
            owner = self.owner if isinstance(self.owner, type) else type(self.owner)
            where = f"{owner.__name__}.{self.name}" if self.owner is not None else self.name
            raise ValueError(f"{where} = {val!r} is a boolean, not a number ({self.label})")
        super()._validate_value(val, allow_None)


class Quantity(_NotBoolean, _RangeMessage, param.Number):
    """A real physical quantity with bounds; NaN, ±inf and booleans are always refused."""


class Count(_NotBoolean, _RangeMessage, param.Integer):
    """An integer quantity with bounds; booleans are refused."""


class CountOrOff(Count):
    """A count within its bounds, or 0, which switches off what the count refines."""

    def _validate_bounds(self, val, bounds, inclusive_bounds):
        """0 always passes; any other value is checked against the bounds."""
        if val != 0:
            super()._validate_bounds(val, bounds, inclusive_bounds)

    def _allowed_text(self, bounds, inclusive_bounds) -> str:
        """The bounds, and 0."""
        return f"{_format_range(bounds, inclusive_bounds)} or 0"


def _q(default, bounds, soft, label, doc, inclusive=(True, True), allow_none=False):
    return Quantity(
        default,
        bounds=bounds,
        softbounds=soft,
        inclusive_bounds=inclusive,
        label=label,
        doc=doc,
        allow_None=allow_none,
    )


class Vehicle(param.Parameterized):
    """Metro car: masses and suspensions of one whole car (paper Table 1).

    The one-rail model halves every mass and inertia; suspension values are per side. All are
    used by ``model.vehicle_track.assemble_vehicle`` (and so by ``stable_time_step``). Hard
    bounds span rail vehicles from a light tram to a loaded heavy-rail car; outside them the
    one-rail linear-suspension model and its explicit time step lose their meaning.
    """

    car_body_mass = _q(
        38500.0,
        (5000.0, 120000.0),
        (20000.0, 60000.0),
        "Car body mass (kg)",
        "Mass of one car body, M_c (paper Table 1), in model.vehicle_track.assemble_vehicle "
        "and Vehicle.static_wheel_load. Bounds 5–120 t: a light tram body to a fully loaded "
        "heavy-rail car body.",
    )
    car_body_pitch_inertia = _q(
        None,
        (1e4, 1e8),
        (5e5, 3e6),
        "Car body pitch inertia (kg·m²)",
        "Pitch inertia of one car body, J_c, in model.vehicle_track.assemble_vehicle. The paper "
        "does not give it; None means M_c·L_car²/12 (uniform slender body, docs/model.md §1). "
        "Bounds 1e4–1e8 kg·m²: M_c L²/12 over the mass and length bounds.",
        allow_none=True,
    )
    bogie_mass = _q(
        2980.0,
        (500.0, 10000.0),
        (1500.0, 5000.0),
        "Bogie frame mass (kg)",
        "Mass of one bogie frame, M_t (paper Table 1), in model.vehicle_track.assemble_vehicle. "
        "Bounds 0.5–10 t: tram to heavy freight bogie frames.",
    )
    bogie_pitch_inertia = _q(
        3605.0,
        (100.0, 50000.0),
        (1000.0, 8000.0),
        "Bogie pitch inertia (kg·m²)",
        "Pitch inertia of one bogie frame, J_t (paper Table 1), in "
        "model.vehicle_track.assemble_vehicle. Bounds 100–5e4 kg·m²: M_t l² over the bogie "
        "masses and wheelbases.",
    )
    wheelset_mass = _q(
        1350.0,
        (300.0, 5000.0),
        (800.0, 2500.0),
        "Wheelset mass (kg)",
        "Mass of one wheelset, M_w (paper Table 1), in model.vehicle_track.assemble_vehicle "
        "and the Hertz term of stable_time_step. Bounds 0.3–5 t: light tram to powered "
        "heavy-haul wheelsets.",
    )
    primary_stiffness = _q(
        2.14e6,
        (1e5, 1e8),
        (5e5, 5e6),
        "Primary suspension stiffness (N/m)",
        "Primary suspension stiffness per axle box, K_pz (paper Table 1), in "
        "model.vehicle_track.assemble_vehicle. Bounds 0.1–100 MN/m: soft rubber springs to a "
        "nearly rigid axle box.",
    )
    primary_damping = _q(
        4.9e4,
        (0, 1e6),
        (0.0, 2e5),
        "Primary suspension damping (N·s/m)",
        "Primary suspension damping per axle box, C_pz (paper Table 1), in "
        "model.vehicle_track.assemble_vehicle. Bounds 0–1 MN·s/m: undamped to ten times the "
        "heaviest hydraulic dampers.",
    )
    secondary_stiffness = _q(
        2.535e6,
        (1e5, 1e8),
        (2e5, 5e6),
        "Secondary suspension stiffness (N/m)",
        "Secondary suspension stiffness per bogie side, K_sz (paper Table 1), in "
        "model.vehicle_track.assemble_vehicle. Bounds 0.1–100 MN/m: air springs to stiff "
        "freight springs.",
    )
    secondary_damping = _q(
        1.96e5,
        (0, 2e6),
        (0.0, 5e5),
        "Secondary suspension damping (N·s/m)",
        "Secondary suspension damping per bogie side, C_sz (paper Table 1), in "
        "model.vehicle_track.assemble_vehicle. Bounds 0–2 MN·s/m: undamped to ten times the "
        "paper's value.",
    )

    @property
    def static_wheel_load(self) -> float:
        """Static load of one wheel on the rail (N): the car's weight over its eight wheels."""
        car_mass = self.car_body_mass + 2 * self.bogie_mass + 4 * self.wheelset_mass
        return car_mass * GRAVITY / 8.0


class Train(param.Parameterized):
    """Train geometry and speed. Defaults: Nanjing Lines 1–2 six-car Type A (docs/model.md §1).

    Used by ``Train.axle_offsets`` (wheel positions in model.vehicle_track) and
    ``Scenario.passage_duration``.
    """

    n_cars = Count(
        6,
        bounds=(1, 12),
        softbounds=(1, 8),
        label="Number of cars",
        doc="Cars in the train, n_c, in Train.axle_offsets; cars are independent (no coupler "
        "stiffness). Bounds 1–12: metro trains have up to 10 cars.",
    )
    speed_kmh = _q(
        80.0,
        (1.0, 400.0),
        (20.0, 160.0),
        "Speed (km/h)",
        "Train speed v (paper §4.1: 80 km/h), in model.vehicle_track (wheel positions) and "
        "Scenario.passage_duration. Bounds 1–400 km/h: the record lasts ∝ 1/v (a crawl would "
        "need millions of steps) and 400 km/h is the fastest rail service.",
    )
    car_length = _q(
        22.0,
        (5.0, 60.0),
        (15.0, 30.0),
        "Car length (m)",
        "Length of one car over couplers, L_car (22 m for Type A, docs/model.md §1), in "
        "Train.axle_offsets and the default J_c. Bounds 5–60 m: a tram module to an "
        "articulated unit.",
    )
    bogie_distance = _q(
        15.7,
        (2.0, 50.0),
        (8.0, 20.0),
        "Bogie-centre distance (m)",
        "Distance between the two bogie centres of a car, 2l_c (15.7 m for Type A), in "
        "Train.axle_offsets and model.vehicle_track.assemble_vehicle. Bounds 2–50 m; with "
        "Scenario.validate: 2l_c + wheelbase < L_car.",
    )
    wheelbase = _q(
        2.4,
        (1.0, 5.0),
        (1.8, 3.0),
        "Bogie wheelbase (m)",
        "Axle spacing within a bogie, 2l_h (twice the paper's half wheelbase 1.2 m), in "
        "Train.axle_offsets and model.vehicle_track.assemble_vehicle. Bounds 1–5 m: real "
        "bogies have 1.6–3.5 m.",
    )

    single_bogie = param.Boolean(
        False,
        label="Single bogie only",
        doc="If true, simulate the paper's Fig. 1 model: half a car body on one bogie with two "
        "wheelsets, instead of the full train (Train.axle_offsets, "
        "model.vehicle_track.assemble_vehicle).",
    )

    @classmethod
    def type_a(cls, **overrides) -> Train:
        """Nanjing six-car Type A train (the defaults: 22 m cars, 15.7 m bogies, 2.4 m axles)."""
        return cls(**overrides)

    @classmethod
    def type_b(cls, **overrides) -> Train:
        """Six-car Type B train, geometry from the ``type_b`` preset (19 m, 12.6 m, 2.3 m)."""
        return cls(**{**_load_presets()["type_b"]["values"]["train"], **overrides})

    @property
    def speed(self) -> float:
        """Train speed (m/s)."""
        return self.speed_kmh / 3.6

    @property
    def axle_offsets(self) -> list[float]:
        """Distance of every axle behind the leading axle (m), leading axle first."""
        if self.single_bogie:
            return [0.0, self.wheelbase]
        bogie = [0.0, self.wheelbase, self.bogie_distance, self.bogie_distance + self.wheelbase]
        return [car * self.car_length + x for car in range(self.n_cars) for x in bogie]

    @property
    def axle_span(self) -> float:
        """Distance from the leading to the trailing axle (m)."""
        return self.axle_offsets[-1]

    @property
    def n_wheels(self) -> int:
        """Wheels on one rail (= number of axles)."""
        return len(self.axle_offsets)


class Track(param.Parameterized):
    """Elastic supporting-block ballastless track, one rail.

    The paper's Table 2 is missing; defaults are typical Chinese-metro values (docs/model.md §2):
    60 kg/m rail, 0.6 m block spacing. Used by ``model.vehicle_track.assemble_track`` and
    ``stable_time_step``; the Winkler values by ``winkler_block_displacement``.
    """

    rail_E = _q(
        2.059e11,
        (1.5e11, 2.5e11),
        (1.9e11, 2.2e11),
        "Rail Young's modulus (Pa)",
        "Young's modulus of rail steel, E (assumed, docs/model.md §2), in the modal rail of "
        "model.vehicle_track.assemble_track (EI). Bounds 150–250 GPa: rail steels.",
    )
    rail_I = _q(
        3.217e-5,
        (5e-6, 1e-4),
        (1e-5, 6e-5),
        "Rail second moment of area (m⁴)",
        "Vertical-bending second moment of area of the rail, I (60 kg/m rail, assumed), in "
        "model.vehicle_track.assemble_track (EI). Bounds 5e-6–1e-4 m⁴: light 30 kg/m rails to "
        "beyond the 75 kg/m rail.",
    )
    rail_mass = _q(
        60.64,
        (20.0, 120.0),
        (40.0, 80.0),
        "Rail mass per length (kg/m)",
        "Mass per metre of the rail, m_r (assumed), in model.vehicle_track.assemble_track. "
        "Bounds 20–120 kg/m: light rails to heavy rails with fittings.",
    )
    block_spacing = _q(
        0.6,
        (0.3, 1.5),
        (0.5, 0.75),
        "Block spacing (m)",
        "Distance between supporting blocks, L_s (assumed), in "
        "model.vehicle_track.assemble_track, Scenario.rail_length and the line load "
        "model.pipeline.invert_line_load. Bounds 0.3–1.5 m: the discretely supported rail "
        "needs several supports per wheel-load spread; real spacings are 0.5–0.75 m.",
    )
    fastener_stiffness = _q(
        8e7,
        (1e6, 1e10),
        (1e7, 2e8),
        "Fastener stiffness (N/m)",
        "Rail pad / fastener stiffness per block, K_r (assumed), in "
        "model.vehicle_track.assemble_track. Bounds 1 MN/m–10 GN/m: the softest resilient "
        "fasteners to a practically rigid pad.",
    )
    fastener_damping = _q(
        5e4,
        (0, 1e6),
        (0.0, 2e5),
        "Fastener damping (N·s/m)",
        "Rail pad / fastener damping per block, C_r (assumed), in "
        "model.vehicle_track.assemble_track. Bounds 0–1 MN·s/m: undamped to five times the "
        "stiffest published pads.",
    )
    pad_stiffness = _q(
        4e7,
        (1e6, 1e10),
        (5e6, 1.5e8),
        "Block pad stiffness (N/m)",
        "Block pad + rubber boot stiffness per block, K_s (assumed), in "
        "model.vehicle_track.assemble_track; the invert force K_s Z_s + C_s Ż_s. Bounds "
        "1 MN/m–10 GN/m: soft boots to a practically rigid support.",
    )
    pad_damping = _q(
        8e4,
        (0, 1e6),
        (0.0, 3e5),
        "Block pad damping (N·s/m)",
        "Block pad + rubber boot damping per block, C_s (assumed), in "
        "model.vehicle_track.assemble_track and the invert force. Bounds 0–1 MN·s/m: undamped to "
        "five times the most damped published boots.",
    )
    block_mass = _q(
        100.0,
        (10.0, 1000.0),
        (50.0, 300.0),
        "Block mass (kg)",
        "Mass of one supporting block on one rail, M_s (assumed), in "
        "model.vehicle_track.assemble_track. Bounds 10–1000 kg: a base plate to a floating "
        "slab segment per rail seat.",
    )
    wheel_radius = _q(
        0.42,
        (0.25, 0.6),
        (0.35, 0.5),
        "Wheel radius (m)",
        "Rolling radius of the wheel, R (assumed), in Track.hertz_constant (used by the "
        "model.vehicle_track kernel). Bounds 0.25–0.6 m: where Zhai's Hertz fits G(R) were "
        "made (wheel diameters 0.5–1.2 m).",
    )

    wheel_tread = param.Selector(
        default="conical",
        objects=list(HERTZ_FITS),
        label="Wheel tread",
        doc="Tread profile for the Hertz constant G of Track.hertz_constant (the contact law of "
        "the model.vehicle_track kernel): conical G = 4.57 R^-0.149e-8, worn "
        "G = 3.86 R^-0.115e-8 (paper §2.3, docs/model.md §3).",
    )

    @property
    def hertz_constant(self) -> float:
        """Hertz contact constant G (m/N^(2/3)): p = (δ/G)^(3/2)."""
        a, b = HERTZ_FITS[self.wheel_tread]
        return a * self.wheel_radius**b * 1e-8

    @property
    def bending_stiffness(self) -> float:
        """Rail bending stiffness EI (N·m²)."""
        return self.rail_E * self.rail_I

    @property
    def support_stiffness(self) -> float:
        """Fastener and block pad in series, per block (N/m)."""
        return (
            self.fastener_stiffness
            * self.pad_stiffness
            / (self.fastener_stiffness + self.pad_stiffness)
        )

    @property
    def winkler_modulus(self) -> float:
        """Equivalent continuous foundation modulus k = K_r K_s / ((K_r + K_s) L_s) (N/m²)."""
        return self.support_stiffness / self.block_spacing

    @property
    def winkler_beta(self) -> float:
        """Winkler-beam wavenumber β = (k / 4EI)^(1/4) (1/m)."""
        return (self.winkler_modulus / (4.0 * self.bending_stiffness)) ** 0.25

    def hertz_compression(self, wheel_load: float) -> float:
        """Static Hertz compression δ = G p^(2/3) (m) under a wheel load p (N)."""
        return self.hertz_constant * wheel_load ** (2.0 / 3.0)


class Irregularity(param.Parameterized):
    """Vertical rail-profile irregularity: US FRA PSD, trigonometric-series synthesis (§2.4).

    Used by ``model.irregularity.profile_for`` (called from ``model.vehicle_track``).
    """

    enabled = param.Boolean(
        True,
        label="Irregularity on",
        doc="If false, the rail is perfectly smooth (model.irregularity.profile_for).",
    )
    track_class = Count(
        6,
        bounds=(1, 6),
        softbounds=(1, 6),
        label="FRA track class",
        doc="US FRA track class 1–6 (A_v of fra_psd in model.irregularity); 6 is the best "
        "track and the paper's choice. Bounds: the classes the FRA defines.",
    )
    seed = Count(
        2024,
        bounds=(0, 2**32 - 1),
        softbounds=(0, 9999),
        label="Random seed",
        doc="Seed of the random phases φ_k of model.irregularity.synthesize_profile. Bounds: "
        "NumPy's 32-bit seed range.",
    )
    wavelength_min = _q(
        1.0,
        (0.1, 100.0),
        (0.5, 10.0),
        "Shortest wavelength (m)",
        "Lower end λ_min of the synthesised band (docs/model.md §4: 1 m), in "
        "model.irregularity.series_wavenumbers; sets the profile grid step λ_min/100 in "
        "model.vehicle_track. Bounds 0.1–100 m: shorter waves are corrugation, outside the "
        "FRA fit; must be below wavelength_max (Scenario.validate).",
    )
    wavelength_max = _q(
        50.0,
        (0.5, 1000.0),
        (10.0, 120.0),
        "Longest wavelength (m)",
        "Upper end λ_max of the synthesised band (docs/model.md §4: 50 m), in "
        "model.irregularity.series_wavenumbers. Bounds 0.5–1000 m: beyond, the waves are "
        "alignment design, not irregularity.",
    )
    n_components = Count(
        2000,
        bounds=(10, 200000),
        softbounds=(200, 10000),
        label="Harmonic components",
        doc="Number of cosines N_k in model.irregularity.synthesize_profile. Bounds 10–2e5: "
        "the cost grows as N_k × profile points (see the run-cost guard).",
    )
    profile_csv = param.String(
        None,
        allow_None=True,
        label="Measured profile CSV",
        doc="Path of a measured profile (columns x in m measured from the monitored block, η in "
        "m or mm), read by model.irregularity.load_profile_csv; replaces the synthetic profile "
        "when set. A relative path in a scenario file is resolved against that file's folder "
        "(Scenario.from_file).",
    )


class Tunnel(param.Parameterized):
    """Concrete lining as a thin elastic ring in plane strain (paper Table 3, corrected).

    Used by ``model.tunnel_soil`` (ring constants a, m, K, D of ``_ring_constants``). Besides the
    bounds, ``Scenario.validate`` requires a thin ring, h/a ≤ ``THIN_RING_MAX_RATIO``.
    """

    inner_radius = _q(
        2.7,
        (1.0, 10.0),
        (2.0, 4.0),
        "Lining inner radius (m)",
        "Inner radius of the lining (paper Table 3); a = inner radius + h/2 in "
        "model.tunnel_soil._ring_constants. Bounds 1–10 m: a small service tunnel to a large "
        "two-track tunnel.",
    )
    thickness = _q(
        0.30,
        (0.05, 1.5),
        (0.2, 0.6),
        "Lining thickness (m)",
        "Lining thickness h (the paper's '30 m' is a typo for 0.30 m, docs/model.md §7), in "
        "model.tunnel_soil._ring_constants (m = ρh, K, D). Bounds 0.05–1.5 m; with "
        "Scenario.validate the thin-ring limit h/a ≤ 0.2.",
    )
    youngs_modulus = _q(
        3.45e10,
        (1e9, 2.5e11),
        (1e10, 5e10),
        "Lining Young's modulus (Pa)",
        "Young's modulus E_t of the lining (paper Table 3), in K = E_t h/(1 − ν_t²) and D of "
        "model.tunnel_soil._ring_constants. Bounds 1–250 GPa: jointed masonry or cracked "
        "concrete to a steel lining.",
    )
    poisson_ratio = _q(
        0.17,
        (0.0, 0.45),
        (0.1, 0.3),
        "Lining Poisson's ratio (-)",
        "Poisson's ratio ν_t of the lining (paper Table 3), in K and D of "
        "model.tunnel_soil._ring_constants. Bounds 0–0.45: lining materials (concrete 0.15–0.2, "
        "steel 0.3).",
    )
    density = _q(
        2450.0,
        (1000.0, 8000.0),
        (2000.0, 2800.0),
        "Lining density (kg/m³)",
        "Density ρ_t of the lining (paper Table 3), in the ring mass m = ρ_t h of "
        "model.tunnel_soil._ring_constants. Bounds 1000–8000 kg/m³: lightweight concrete to "
        "steel.",
    )

    model = param.Selector(
        default="2d",
        objects=["2d", "2.5d"],
        label="Tunnel–soil model",
        doc="'2d': the paper's plane-strain section (ring in soil), the load of one block spread "
        "over one block spacing on the whole tunnel at once; '2.5d': the lining as a cylindrical "
        "shell infinite along the tunnel, loaded by the moving train (kernel at ξ = ω/v). "
        "Dispatched by the soil stage of model.pipeline.run.",
    )

    @property
    def ring_radius(self) -> float:
        """Radius of the ring's middle surface a = inner radius + h/2 (m)."""
        return self.inner_radius + 0.5 * self.thickness

    @property
    def extensional_stiffness(self) -> float:
        """Plane-strain membrane stiffness K = Eh/(1 − ν²) (N/m)."""
        return self.youngs_modulus * self.thickness / (1.0 - self.poisson_ratio**2)

    @property
    def bending_stiffness(self) -> float:
        """Plane-strain bending stiffness D = Eh³/(12(1 − ν²)) (N·m)."""
        return self.extensional_stiffness * self.thickness**2 / 12.0


class Soil(param.Parameterized):
    """Homogeneous, isotropic, hysteretically damped elastic full-space (paper Table 4).

    Primary inputs are E, ν, ρ and the loss factors; wave speeds and Lamé constants are derived.
    The default E = 6 MPa, ν = 0.3 is the only reading of the self-inconsistent Table 4 that
    reproduces the paper's millimetre magnitudes (docs/model.md §7); the others are presets. Used by
    ``model.tunnel_soil._soil_constants`` (μ*, λ*, ρ) and, for the record tail,
    ``model.settlement.soil_response``.
    """

    youngs_modulus = _q(
        6e6,
        (1e6, 1e11),
        (1e6, 1e8),
        "Soil Young's modulus (Pa)",
        "Young's modulus E_s of the soil (paper Table 4), in μ, λ of "
        "model.tunnel_soil._soil_constants. Bounds 1 MPa–100 GPa: a very soft clay to sound "
        "rock. Below ~1 MPa the small-strain elastic model is meaningless (a passing train "
        "would fail such ground) and its displacement profile stops decreasing with depth.",
    )
    poisson_ratio = _q(
        0.3,
        (0.0, 0.49),
        (0.1, 0.49),
        "Soil Poisson's ratio (-)",
        "Poisson's ratio ν_s of the soil (paper Table 4), in λ = 2νμ/(1 − 2ν) of "
        "model.tunnel_soil._soil_constants. Bounds 0–0.49: at 0.5 the P-wave speed is "
        "infinite (incompressible soil).",
    )
    density = _q(
        1800.0,
        (1000.0, 3000.0),
        (1400.0, 2200.0),
        "Soil density (kg/m³)",
        "Soil density ρ_s (assumed typical of Nanjing soft clay; not in Table 4), in "
        "model.tunnel_soil._soil_constants and the wave speeds. Bounds 1000–3000 kg/m³: "
        "organic soils to dense rock.",
    )
    shear_loss_factor = _q(
        0.06,
        (0.0, 0.4),
        (0.0, 0.3),
        "Shear loss factor η_G (-)",
        "Hysteretic shear loss factor η_G: μ* = μ(1 + iη_G) in "
        "model.tunnel_soil._soil_constants (paper Table 4). Bounds 0–0.4: a damping ratio "
        "η/2 up to 20 %; more is not small-strain behaviour, and the non-causal response of "
        "hysteretic damping grows with η.",
    )
    bulk_loss_factor = _q(
        0.0,
        (0.0, 0.4),
        (0.0, 0.3),
        "Bulk loss factor η_K (-)",
        "Hysteretic bulk loss factor η_K: K* = K(1 + iη_K) in "
        "model.tunnel_soil._soil_constants (paper Table 4). Bounds 0–0.4 as η_G.",
    )

    @classmethod
    def from_lame(
        cls, lame_lambda: float, shear_modulus: float, density: float, **overrides
    ) -> Soil:
        """Soil from its Lamé constants λ, μ (Pa) and density (kg/m³)."""
        youngs = (
            shear_modulus * (3 * lame_lambda + 2 * shear_modulus) / (lame_lambda + shear_modulus)
        )
        poisson = lame_lambda / (2 * (lame_lambda + shear_modulus))
        return cls(youngs_modulus=youngs, poisson_ratio=poisson, density=density, **overrides)

    @classmethod
    def from_wave_speeds(
        cls, p_wave_speed: float, s_wave_speed: float, density: float, **overrides
    ) -> Soil:
        """Soil from its P- and S-wave speeds c1, c2 (m/s) and density (kg/m³)."""
        shear = density * s_wave_speed**2
        lame_lambda = density * p_wave_speed**2 - 2 * shear
        return cls.from_lame(lame_lambda, shear, density, **overrides)

    @property
    def shear_modulus(self) -> float:
        """Lamé μ = E / (2(1 + ν)) (Pa)."""
        return self.youngs_modulus / (2.0 * (1.0 + self.poisson_ratio))

    @property
    def lame_lambda(self) -> float:
        """Lamé λ = 2νμ / (1 − 2ν) (Pa)."""
        return 2.0 * self.poisson_ratio * self.shear_modulus / (1.0 - 2.0 * self.poisson_ratio)

    @property
    def bulk_modulus(self) -> float:
        """Bulk modulus K = λ + 2μ/3 (Pa)."""
        return self.lame_lambda + 2.0 * self.shear_modulus / 3.0

    @property
    def p_wave_speed(self) -> float:
        """Compression wave speed c1 = √((λ + 2μ)/ρ) (m/s), undamped."""
        return math.sqrt((self.lame_lambda + 2.0 * self.shear_modulus) / self.density)

    @property
    def s_wave_speed(self) -> float:
        """Shear wave speed c2 = √(μ/ρ) (m/s), undamped."""
        return math.sqrt(self.shear_modulus / self.density)


class Numerics(param.Parameterized):
    """Discretisation and output settings of every stage.

    Besides these bounds, ``model.run_cost.estimate_run`` refuses a run whose arrays would not
    fit in memory and warns of one estimated to take long, naming the parameter to change.
    """

    dt = _q(
        1e-4,
        (1e-6, 1e-3),
        (2e-5, 2e-4),
        "Time step Δt (s)",
        "Time step Δt of Zhai's explicit integrator (paper default 1e-4 s), in "
        "model.vehicle_track.simulate; must be below stable_time_step (check_inputs). Bounds "
        "1 µs–1 ms: finer steps only cost time, coarser ones are never stable for a rail on "
        "blocks.",
    )
    n_rail_modes = Count(
        None,
        bounds=(1, 20000),
        softbounds=(50, 2000),
        allow_None=True,
        label="Rail modes",
        doc="Modes N_m of the simply supported rail, in model.vehicle_track.assemble_track; "
        "None means L/L_s (shortest modal half-wavelength = block spacing, docs/model.md §2). "
        "Bounds 1–20000; Scenario.validate requires N_m ≥ L/(2L_s).",
    )
    rail_end_margin = _q(
        20.0,
        (20.0, 500.0),
        (20.0, 60.0),
        "Rail end margin (m)",
        "Minimum distance from any axle to a rail end during the run (docs/model.md §2: "
        "≥ 20 m), in Scenario.rail_length. Bounds 20–500 m: beyond, the rail only adds modes.",
    )
    approach_distance = _q(
        10.0,
        (1.0, 500.0),
        (5.0, 40.0),
        "Approach distance (m)",
        "Distance of the leading axle before the monitored block at the start, and of the "
        "trailing axle past it at the end, in Scenario.rail_length and passage_duration. "
        "Bounds 1–500 m: the response decays within a few 1/β (~4 m).",
    )
    n_harmonics = Count(
        32,
        bounds=(1, 1024),
        softbounds=(4, 128),
        label="Ring harmonics",
        doc="Circumferential harmonics n = 0..N_n summed in model.tunnel_soil.invert_receptance "
        "(called from model.settlement.soil_response). Bounds 1–1024: the ring's bending makes "
        "the terms fall as n⁻⁴ (32 converge to 1e-3, tests); more only cost time.",
    )
    soil_max_frequency = _q(
        100.0,
        (5.0, 1000.0),
        (30.0, 300.0),
        "Soil model frequency limit (Hz)",
        "Highest frequency f_max passed to the tunnel–soil model in "
        "model.settlement.soil_response; the load has negligible content above (paper Fig. 7: "
        "0–30 Hz). Bounds 5–1000 Hz: below 5 Hz the wheel-passage pulses are cut, above "
        "1 kHz the 2D section model has no meaning.",
    )
    zero_pad_factor = Count(
        8,
        bounds=(1, 256),
        softbounds=(1, 32),
        label="Zero-padding factor",
        doc="Record length used for the soil FFT, as a multiple of the passage duration, in "
        "model.settlement.soil_response (convergence of the peak is shown in tests). Bounds "
        "1–256; a run also refuses a padded record shorter than the passage plus the wave tail "
        "to max_depth (model.pipeline.check_record_padding), which would wrap the deep response.",
    )
    psd_segment = _q(
        4.0,
        (0.1, 100.0),
        (1.0, 10.0),
        "PSD segment length (s)",
        "Welch segment length T_seg for the one-sided PSDs (frequency resolution 1/T_seg), in "
        "model.spectra.one_sided_psd (load and soil stages); a shorter record is analysed "
        "whole. Bounds 0.1–100 s: resolutions from 10 Hz to 0.01 Hz.",
    )
    max_depth = _q(
        35.0,
        (11.0, 200.0),
        (11.0, 60.0),
        "Deepest output depth (m)",
        "Depth below the invert down to which model.settlement.soil_response reports the "
        "displacement (paper Fig. 11 and conclusions: 35 m). Bounds 11–200 m: 11 m is the "
        "paper's comparison depth, which the summary always reports; a full-space model of the "
        "ground says nothing deeper than 200 m.",
    )
    n_depths = Count(
        71,
        bounds=(2, 2000),
        softbounds=(11, 201),
        label="Output depths",
        doc="Number of equally spaced depths from the invert to the deepest one, in "
        "model.settlement.soil_response. Bounds 2–2000: a profile needs two points; memory grows "
        "as depths × padded samples (run-cost guard).",
    )
    n_wavenumbers = Count(
        384,
        bounds=(16, 100000),
        softbounds=(128, 4096),
        label="Wavenumber points",
        doc="Points of the base grid of the wavenumber integral of the 2.5D point-load response "
        "(model.tunnel_soil_3d.point_load_response): uniform in asinh(ξ/ξ_c) on [0, max "
        "wavenumber], plus refinements at the P and S wavenumbers ω/c.",
    )
    max_wavenumber = _q(
        20.0,
        (0, 1000),
        (5.0, 100.0),
        "Largest wavenumber (rad/m)",
        "Upper limit ξ_max of the wavenumber integral of the 2.5D point-load response "
        "(model.tunnel_soil_3d.point_load_response); the tail beyond is estimated and must be "
        "below the wavenumber tolerance. Bounds up to 1000 rad/m: wavelengths down to 6 mm, "
        "far below the lining thickness where the thin-shell model ends.",
        (False, True),
    )
    wavenumber_tolerance = _q(
        1e-3,
        (0, 1),
        (1e-5, 1e-2),
        "Wavenumber integral tolerance (-)",
        "Largest estimated error of the 2.5D wavenumber integral "
        "(model.tunnel_soil_3d.point_load_response), relative to the largest response at the "
        "same frequency and depth; a larger estimate raises an error naming the numerics "
        "parameter to raise.",
        (False, True),
    )
    kernel_samples_per_cycle = CountOrOff(
        12,
        bounds=(6, 1024),
        softbounds=(6, 32),
        label="Kernel samples per cycle",
        doc="Frequency sampling of the tunnel–soil kernel on the soil stage's record grid, in "
        "model.settlement.record_grid_transfer: the kernel is evaluated at frequencies at most "
        "c_s/(N r) apart, N this count, r = a + max_depth the distance from the tunnel axis to "
        "the deepest output point (the outgoing S wave there turns through one cycle every "
        "c_s/r Hz), and interpolated in between (6-point Lagrange); below N such steps (near "
        "0 Hz, where the 2D kernel grows like ln f) at every frequency of the grid. 0 evaluates "
        "it at every frequency. Bounds 6–1024 or 0: with fewer than 6 samples per cycle the "
        "interpolation errs by up to 1 % of the transfer functions (docs/tunnel_soil.md); 12 "
        "keeps the error below 1e-4.",
    )


# Li & Selig (1996) parameter sets (a in %, b, m) by soil class (docs/model.md §10).
LI_SELIG_SOIL_CLASSES = {
    "ML": (0.64, 0.10, 1.7),
    "MH": (0.84, 0.13, 2.0),
    "CL": (1.1, 0.16, 2.0),
    "CH": (1.2, 0.18, 2.4),
}


class LongTerm(param.Parameterized):
    """Permanent settlement accumulated over years of traffic (docs/model.md §10).

    Static stress state of the ground around the tunnel, traffic, and the empirical cyclic
    strain-accumulation law ε_p(q_d, N) (ε_p in %, stresses in the law as ratios). Every
    parameter is read by ``model.longterm`` (the pipeline's "longterm" stage).
    """

    law = param.Selector(
        default="li_selig",
        objects=["li_selig", "chai_miura", "monismith"],
        label="Strain law",
        doc="Cyclic strain-accumulation law: Li & Selig (1996) ε_p = a (q_d/σ_s)^m N^b; "
        "Chai & Miura (2002) ε_p = a (q_d/q_f)^m (1 + q_s/q_f)^n N^b; Monismith (1975) "
        "ε_p = A N^b; evaluated in model.longterm.",
    )
    soil_class = param.Selector(
        default="CH",
        objects=[*LI_SELIG_SOIL_CLASSES, "user"],
        label="Soil class",
        doc="Li & Selig parameter set (a, b, m) for ML, MH, CL, CH soils; 'user' takes the values "
        "of a, b and m below (e.g. from a cyclic-triaxial calibration); via "
        "LongTerm.law_parameters.",
    )
    a = _q(
        1.2,
        (0, 100),
        (0.1, 5.0),
        "Law coefficient a (%)",
        "Coefficient a (or A of Monismith) of the strain law, ε_p in %; used (via "
        "LongTerm.law_parameters) when the soil class is 'user' or the law is not Li & Selig. "
        "Bounds (0, 100] %: a strain beyond 100 % is failure, not accumulation.",
        (False, True),
    )
    b = _q(
        0.18,
        (0, 1),
        (0.05, 0.4),
        "Cycle exponent b (-)",
        "Exponent b of N in the strain law; used (via LongTerm.law_parameters) when the soil "
        "class is 'user' or the law is not Li & Selig. Bounds (0, 1): the strain grows with N, "
        "but slower than linearly (published fits 0.1–0.3).",
        (False, False),
    )
    m = _q(
        2.4,
        (0, 10),
        (1.0, 4.0),
        "Stress exponent m (-)",
        "Exponent m of the stress ratio in the strain law; used (via LongTerm.law_parameters) "
        "when the soil class is 'user' or the law is not Li & Selig. Bounds (0, 10]: published "
        "fits 1–4.",
        (False, True),
    )
    n = _q(
        1.0,
        (0, 10),
        (0.0, 3.0),
        "Static-stress exponent n (-)",
        "Exponent n of (1 + q_s/q_f) in Chai & Miura's law in model.longterm (default 1.0). "
        "Bounds [0, 10]: published fits 0–3.",
    )
    trains_per_day = _q(
        200.0,
        (0, 5000),
        (10.0, 600.0),
        "Trains per day (-)",
        "Passages of the train over the section per day, both directions, n_d; with the cycles "
        "per train it gives N(t) in model.longterm. Bounds (0, 5000]: more is a train every 20 s "
        "around the clock.",
        (False, True),
    )
    years = _q(
        20.0,
        (0, 200),
        (1.0, 100.0),
        "Years of service (yr)",
        "Service time t at which model.longterm reports the final settlement; the "
        "settlement-time curve runs from one day of traffic to this time. Bounds (0, 200] yr: "
        "design lives are 100 yr.",
        (False, True),
    )
    cycles_per_train = param.Selector(
        default="bogies",
        objects=["bogies", "rainflow"],
        label="Cycles per train",
        doc="Load cycles per passage in model.longterm: one per bogie, or counted on the deviator "
        "history by rainflow (ASTM E1049), full cycles weighted by their range.",
    )
    axis_depth = _q(
        15.0,
        (0, 200),
        (8.0, 40.0),
        "Tunnel axis depth (m)",
        "Depth of the tunnel axis below the ground surface, H_t, for the static stress state in "
        "model.longterm; the paper gives none, 15 m is assumed. Bounds (0, 200] m; "
        "Scenario.validate requires the lining below the ground surface.",
        (False, True),
    )
    water_table_depth = _q(
        0.0,
        (0, 200),
        (0.0, 10.0),
        "Water table depth (m)",
        "Depth of the water table below the ground surface, z_w, for σ′_v0 in model.longterm "
        "(soil above it is taken as dry at the same density). Bounds [0, 200] m (0: at the "
        "surface).",
    )
    friction_angle = _q(
        25.0,
        (0, 60),
        (15.0, 40.0),
        "Effective friction angle φ′ (°)",
        "Effective friction angle φ′; sets K0 = 1 − sin φ′ (Jaky, "
        "LongTerm.earth_pressure_coefficient) for the static stress state in model.longterm. "
        "Bounds (0, 60]°: soils have 15–45°.",
        (False, True),
    )
    cu_ratio = _q(
        0.22,
        (0, 2),
        (0.1, 0.5),
        "Undrained strength ratio c_u/σ′_v0 (-)",
        "Undrained shear strength as a ratio to the vertical effective stress (normally "
        "consolidated clay); the static strength in model.longterm is σ_s = q_f = 2c_u. Bounds "
        "(0, 2]: normally consolidated clays 0.2–0.3, heavily overconsolidated ones up to ~1.",
        (False, True),
    )
    undrained_strength = _q(
        None,
        (0, None),
        (10e3, 200e3),
        "Undrained shear strength c_u (Pa)",
        "Undrained shear strength c_u given directly (uniform with depth) to model.longterm; "
        "None uses the ratio to σ′_v0 above. Bounds: any positive strength.",
        (False, True),
        allow_none=True,
    )

    @property
    def earth_pressure_coefficient(self) -> float:
        """K0 = 1 − sin φ′ (Jaky)."""
        return 1.0 - math.sin(math.radians(self.friction_angle))

    def law_parameters(self) -> tuple[float, float, float]:
        """(a, b, m) in force: the soil class's set for Li & Selig, else the user values."""
        if self.law == "li_selig" and self.soil_class != "user":
            return LI_SELIG_SOIL_CLASSES[self.soil_class]
        return self.a, self.b, self.m


SECTIONS = (
    "vehicle",
    "train",
    "track",
    "irregularity",
    "tunnel",
    "soil",
    "numerics",
    "longterm",
)


class Scenario(param.Parameterized):
    """One complete set of inputs: vehicle, train, track, irregularity, tunnel, soil, numerics,
    long-term settlement."""

    vehicle = param.ClassSelector(class_=Vehicle, instantiate=True)
    train = param.ClassSelector(class_=Train, instantiate=True)
    track = param.ClassSelector(class_=Track, instantiate=True)
    irregularity = param.ClassSelector(class_=Irregularity, instantiate=True)
    tunnel = param.ClassSelector(class_=Tunnel, instantiate=True)
    soil = param.ClassSelector(class_=Soil, instantiate=True)
    numerics = param.ClassSelector(class_=Numerics, instantiate=True)
    longterm = param.ClassSelector(class_=LongTerm, instantiate=True)

    def __init__(self, **params):
        classes = {name: self.param[name].class_ for name in SECTIONS}
        for name, cls in classes.items():
            params.setdefault(name, cls())
        super().__init__(**params)

    # ---- presets --------------------------------------------------------------------------
    @staticmethod
    def preset_names() -> list[str]:
        """Names of the presets stored in ``model/data/presets.json``."""
        return list(_load_presets())

    @classmethod
    def preset(cls, name: str) -> Scenario:
        """Scenario of a named preset from ``model/data/presets.json``."""
        presets = _load_presets()
        if name not in presets:
            raise KeyError(f"unknown preset {name!r}; available: {', '.join(presets)}")
        scenario = cls()
        scenario.update(presets[name]["values"])
        return scenario

    @classmethod
    def paper(cls) -> Scenario:
        """The paper's Nanjing case as read by docs/model.md: Type A six cars, 80 km/h, FRA 6."""
        return cls.preset("paper")

    @classmethod
    def paper_soil_lame(cls) -> Scenario:
        """Paper case with the soil of Table 4's Lamé constants (E ≈ 550 MPa, ν ≈ 0.44)."""
        return cls.preset("paper_soil_lame")

    @classmethod
    def paper_soil_wave_speeds(cls) -> Scenario:
        """Paper case with the soil of Table 4's wave speeds c1 = 524, c2 = 190 m/s."""
        return cls.preset("paper_soil_wave_speeds")

    @classmethod
    def paper_2p5d(cls) -> Scenario:
        """The paper's case with the 2.5D moving-load tunnel–soil model."""
        return cls.preset("paper_2p5d")

    @classmethod
    def type_b(cls) -> Scenario:
        """Paper case with a six-car Type B train."""
        return cls.preset("type_b")

    # ---- serialisation --------------------------------------------------------------------
    def to_dict(self) -> dict[str, dict[str, Any]]:
        """All inputs as nested plain values, ``{section: {parameter: value}}``."""
        return {
            section: {name: getattr(obj, name) for name in obj.param if name != "name"}
            for section in SECTIONS
            for obj in [getattr(self, section)]
        }

    def to_json(self, indent: int | None = 2) -> str:
        """JSON text of :meth:`to_dict`; floats are written exactly (shortest repr)."""
        return json.dumps(self.to_dict(), indent=indent, allow_nan=False)

    @classmethod
    def from_dict(cls, data: dict[str, dict[str, Any]]) -> Scenario:
        """Scenario from :meth:`to_dict` output (missing values take their defaults)."""
        scenario = cls()
        scenario.update(data)
        return scenario

    @classmethod
    def from_json(cls, text: str | bytes) -> Scenario:
        """Scenario from :meth:`to_json` output (str, or UTF-8 bytes; a leading BOM is ignored).

        Raises
        ------
        ValueError
            Malformed JSON (with its line and column), non-UTF-8 bytes, nesting too deep, or
            a bad value (naming the parameter).
        """
        if isinstance(text, bytes):
            try:
                text = text.decode("utf-8-sig")
            except UnicodeDecodeError as error:
                raise ValueError(
                    f"scenario is not UTF-8 text (byte {error.start}: {error.reason})"
                ) from None
        try:
            data = json.loads(text.removeprefix("\ufeff"))
        except RecursionError:
            raise ValueError("scenario JSON is nested too deeply to be a scenario") from None
        return cls.from_dict(data)

    @classmethod
    def from_file(cls, path: str | Path) -> Scenario:
        """Scenario from a JSON file written by a run or the dashboard's "Save scenario".

        A relative ``irregularity.profile_csv`` is resolved against the file's folder (not the
        working directory), so a scenario and its profile can be moved together.

        Raises
        ------
        ValueError
            The file cannot be read or is not a valid scenario; the message names the file.
        """
        path = Path(path)
        try:
            scenario = cls.from_json(path.read_bytes())
        except OSError as error:
            raise ValueError(f"{path}: cannot read the scenario file ({error.strerror})") from None
        except ValueError as error:
            raise ValueError(f"{path}: {error}") from None
        except KeyError as error:
            raise ValueError(f"{path}: {error.args[0] if error.args else error}") from None
        profile = scenario.irregularity.profile_csv
        if profile and not Path(profile).is_absolute():
            scenario.irregularity.profile_csv = str((path.parent / profile).resolve())
        return scenario

    def copy(self) -> Scenario:
        """Independent deep copy."""
        return type(self).from_dict(self.to_dict())

    def update(self, values: dict[str, dict[str, Any]]) -> None:
        """Set parameters from ``{section: {parameter: value}}``; unknown names are refused.

        All or nothing: if any value is refused, every parameter keeps its previous value.
        """
        self._check_update(values)
        before = {
            section: {name: getattr(getattr(self, section), name) for name in section_values}
            for section, section_values in values.items()
        }
        try:
            for section, section_values in values.items():
                getattr(self, section).param.update(**section_values)
        except Exception:
            for section, old_values in before.items():
                getattr(self, section).param.update(**old_values)
            raise

    def _check_update(self, values) -> None:
        """Refuse an update that is not ``{known section: {known parameter: value}}``."""
        if not isinstance(values, dict):
            raise ValueError(
                f"a scenario must be an object of sections, not {type(values).__name__}"
            )
        for section, section_values in values.items():
            if section in SECTIONS and not isinstance(section_values, dict):
                raise ValueError(
                    f"section {section!r} must be an object of parameters, not "
                    f"{type(section_values).__name__}"
                )
            if section not in SECTIONS:
                raise KeyError(f"unknown section {section!r}; expected one of {SECTIONS}")
            obj = getattr(self, section)
            unknown = (set(section_values) - set(obj.param)) | ({"name"} & set(section_values))
            if unknown:
                raise KeyError(f"unknown parameter(s) {sorted(unknown)} in section {section!r}")

    def set_value(self, path: str, value: Any) -> None:
        """Set one parameter by dotted path, e.g. ``set_value("train.speed_kmh", 60)``.

        A string value is converted to the parameter's type ("none" gives None for optional
        parameters).
        """
        section, _, name = path.partition(".")
        if section not in SECTIONS or not name:
            raise KeyError(
                f"{path!r} is not of the form section.parameter with section in {SECTIONS}"
            )
        obj = getattr(self, section)
        if name not in obj.param or name == "name":
            raise KeyError(
                f"unknown parameter {name!r} in section {section!r}; available: "
                f"{', '.join(n for n in obj.param if n != 'name')}"
            )
        if isinstance(value, str):
            value = _parse_value(obj.param[name], path, value)
        setattr(obj, name, value)

    # ---- derived quantities that need more than one section --------------------------------
    @property
    def car_body_pitch_inertia(self) -> float:
        """Car body pitch inertia (kg·m²): the given value, or M_c·L_car²/12 when None."""
        given = self.vehicle.car_body_pitch_inertia
        if given is not None:
            return given
        return self.vehicle.car_body_mass * self.train.car_length**2 / 12.0

    @property
    def rail_length(self) -> float:
        """Rail length L (m), a whole number of block spacings.

        The leading axle starts ``approach_distance`` before the monitored block at mid-length
        and the trailing axle ends the same distance past it, every axle staying
        ``rail_end_margin`` from both rail ends: L ≥ 2 (margin + approach + axle span).
        """
        n = self.numerics
        needed = 2.0 * (n.rail_end_margin + n.approach_distance + self.train.axle_span)
        n_spacings = math.ceil(needed / self.track.block_spacing - 1e-9)
        n_spacings += n_spacings % 2  # even, so the mid-length point is a block position
        return n_spacings * self.track.block_spacing

    @property
    def rail_modes(self) -> int:
        """Number of rail modes used: the given value, or L/L_s (docs/model.md §2)."""
        if self.numerics.n_rail_modes is not None:
            return self.numerics.n_rail_modes
        return round(self.rail_length / self.track.block_spacing)

    @property
    def passage_duration(self) -> float:
        """Simulated time (s): leading axle from approach to trailing axle past the block."""
        travel = 2.0 * self.numerics.approach_distance + self.train.axle_span
        return travel / self.train.speed

    def validate(self) -> None:
        """Check constraints between parameters; raise :class:`ScenarioError` listing all."""
        problems = []
        irr, tr = self.irregularity, self.train
        if irr.wavelength_min >= irr.wavelength_max:
            problems.append(
                f"irregularity.wavelength_min = {irr.wavelength_min:g} m must be below "
                f"irregularity.wavelength_max = {irr.wavelength_max:g} m"
            )
        if not tr.single_bogie and tr.bogie_distance + tr.wheelbase >= tr.car_length:
            problems.append(
                f"train.bogie_distance + train.wheelbase = {tr.bogie_distance + tr.wheelbase:g} m "
                f"must be shorter than train.car_length = {tr.car_length:g} m"
            )
        if tr.wheelbase >= tr.bogie_distance and not tr.single_bogie:
            problems.append(
                f"train.wheelbase = {tr.wheelbase:g} m must be shorter than "
                f"train.bogie_distance = {tr.bogie_distance:g} m"
            )
        min_modes = math.ceil(0.5 * self.rail_length / self.track.block_spacing)
        if self.rail_modes < min_modes:
            problems.append(
                f"numerics.n_rail_modes = {self.rail_modes} is too few for a "
                f"{self.rail_length:g} m rail: at least 0.5 L/L_s = {min_modes} are needed "
                f"(L/L_s = {2 * min_modes} recommended)"
            )
        tunnel = self.tunnel
        if tunnel.thickness > THIN_RING_MAX_RATIO * tunnel.ring_radius:
            problems.append(
                f"tunnel.thickness = {tunnel.thickness:g} m is more than {THIN_RING_MAX_RATIO:g} "
                f"of the ring radius a = {tunnel.ring_radius:g} m (h/a = "
                f"{tunnel.thickness / tunnel.ring_radius:.3g}): the thin-ring lining model does "
                f"not hold; allowed h ≤ {THIN_RING_MAX_RATIO:g} a"
            )
        cover = self.longterm.axis_depth - tunnel.inner_radius - tunnel.thickness
        if cover <= 0.0:
            problems.append(
                f"longterm.axis_depth = {self.longterm.axis_depth:g} m puts the lining (outer "
                f"radius {tunnel.inner_radius + tunnel.thickness:g} m) above the ground surface; "
                "allowed: axis depth > tunnel.inner_radius + tunnel.thickness"
            )
        profile = irr.profile_csv
        if irr.enabled and profile and not Path(profile).is_file():
            problems.append(
                f"irregularity.profile_csv = {profile!r} is not a file"
                + ("" if Path(profile).is_absolute() else f" (relative to {Path.cwd()})")
            )
        if problems:
            raise ScenarioError("inconsistent scenario:\n  - " + "\n  - ".join(problems))


def _parse_value(parameter: param.Parameter, path: str, text: str) -> Any:
    """Convert command-line text to the type of ``parameter``; refuse with a clear message."""
    if text.strip().lower() == "none" and parameter.allow_None:
        return None
    try:
        if isinstance(parameter, param.Boolean):
            lowered = text.strip().lower()
            if lowered not in {"true", "false", "1", "0", "yes", "no"}:
                raise ValueError
            return lowered in {"true", "1", "yes"}
        if isinstance(parameter, param.Number) and "_" in text:
            raise ValueError  # int() and float() read "1_0" as 10
        if isinstance(parameter, param.Integer):
            return int(text)
        if isinstance(parameter, param.Number):
            return float(text)
    except ValueError:
        kind = (
            "true/false"
            if isinstance(parameter, param.Boolean)
            else "whole number"
            if isinstance(parameter, param.Integer)
            else "number"
        )
        raise ValueError(f"{path} = {text!r} is not a {kind} ({parameter.label})") from None
    return text


def _load_presets() -> dict[str, dict[str, Any]]:
    with PRESETS_FILE.open(encoding="utf-8") as handle:
        return json.load(handle)["presets"]


# ---- display units (the interface only; everything above and the JSON stay SI) -------------
DISPLAY_UNITS: dict[str, tuple[str, float]] = {
    "vehicle.car_body_mass": ("t", 1e-3),
    "vehicle.car_body_pitch_inertia": ("t·m²", 1e-3),
    "vehicle.primary_stiffness": ("MN/m", 1e-6),
    "vehicle.primary_damping": ("kN·s/m", 1e-3),
    "vehicle.secondary_stiffness": ("MN/m", 1e-6),
    "vehicle.secondary_damping": ("kN·s/m", 1e-3),
    "track.rail_E": ("GPa", 1e-9),
    "track.rail_I": ("cm⁴", 1e8),
    "track.fastener_stiffness": ("MN/m", 1e-6),
    "track.fastener_damping": ("kN·s/m", 1e-3),
    "track.pad_stiffness": ("MN/m", 1e-6),
    "track.pad_damping": ("kN·s/m", 1e-3),
    "tunnel.youngs_modulus": ("GPa", 1e-9),
    "soil.youngs_modulus": ("MPa", 1e-6),
    "numerics.dt": ("ms", 1e3),
    "longterm.undrained_strength": ("kPa", 1e-3),
}
"""Unit in which a person reads and types a parameter, and the factor SI value → display value.

Parameters not listed are shown in the SI unit of their label."""


def _split_label(label: str) -> tuple[str, str]:
    """("Soil Young's modulus", "Pa") from "Soil Young's modulus (Pa)"; no unit gives ""."""
    bare, sep, unit = label.rstrip().rpartition(" (")
    return (bare, unit[:-1]) if sep and unit.endswith(")") else (label, "")


def parameter_of(path: str) -> param.Parameter:
    """The parameter declaration of a dotted path, e.g. ``"soil.youngs_modulus"``."""
    section, _, name = path.partition(".")
    if section not in SECTIONS or name not in Scenario.param[section].class_.param:
        raise KeyError(f"unknown parameter {path!r}")
    return Scenario.param[section].class_.param[name]


def display_unit(path: str) -> tuple[str, float]:
    """(unit, factor) in which ``path`` is shown: display value = factor × SI value."""
    if path in DISPLAY_UNITS:
        return DISPLAY_UNITS[path]
    return _split_label(parameter_of(path).label or path)[1], 1.0


def display_label(path: str) -> str:
    """The parameter's label with its display unit in place of the SI unit."""
    bare = _split_label(parameter_of(path).label or path)[0]
    unit, _ = display_unit(path)
    return f"{bare} ({unit})" if unit and unit != "-" else bare


def display_range(path: str) -> str:
    """Allowed (hard) range of ``path`` in its display unit, e.g. "(0, inf) MPa"."""
    p = parameter_of(path)
    unit, factor = display_unit(path)
    bounds = tuple(None if b is None else b * factor for b in p.bounds or (None, None))
    text = _format_range(bounds, p.inclusive_bounds)
    return f"{text} {unit}" if unit and unit != "-" else text
