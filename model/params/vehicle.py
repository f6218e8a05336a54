"""The vehicle (masses and suspensions of one car) and the train (geometry and speed)."""

from __future__ import annotations

import param

from model.params.quantities import GRAVITY, Count, Switch, _load_presets, _q


class Vehicle(param.Parameterized):
    """Metro car: masses and suspensions of one whole car (paper Table 1).

    The one-rail model halves every mass and inertia; suspension values are per side. All are
    used by ``model.track.assembly.assemble_vehicle`` (and so by ``stable_time_step``). Hard
    bounds span rail vehicles from a light tram to a loaded heavy-rail car; outside them the
    one-rail linear-suspension model and its explicit time step lose their meaning.
    """

    car_body_mass = _q(
        38500.0,
        (5000.0, 120000.0),
        (20000.0, 60000.0),
        "Car body mass (kg)",
        "Mass of one car body, M_c (paper Table 1), in model.track.assembly.assemble_vehicle "
        "and Vehicle.static_wheel_load. Bounds 5–120 t: a light tram body to a fully loaded "
        "heavy-rail car body.",
    )
    car_body_pitch_inertia = _q(
        None,
        (1e4, 1e8),
        (5e5, 3e6),
        "Car body pitch inertia (kg·m²)",
        "Pitch inertia of one car body, J_c, in model.track.assembly.assemble_vehicle. The paper "
        "does not give it; None means M_c·L_car²/12 (uniform slender body, docs/model.md §1). "
        "Bounds 1e4–1e8 kg·m²: M_c L²/12 over the mass and length bounds.",
        allow_none=True,
    )
    bogie_mass = _q(
        2980.0,
        (500.0, 10000.0),
        (1500.0, 5000.0),
        "Bogie frame mass (kg)",
        "Mass of one bogie frame, M_t (paper Table 1), in model.track.assembly.assemble_vehicle. "
        "Bounds 0.5–10 t: tram to heavy freight bogie frames.",
    )
    bogie_pitch_inertia = _q(
        3605.0,
        (100.0, 50000.0),
        (1000.0, 8000.0),
        "Bogie pitch inertia (kg·m²)",
        "Pitch inertia of one bogie frame, J_t (paper Table 1), in "
        "model.track.assembly.assemble_vehicle. Bounds 100–5e4 kg·m²: M_t l² over the bogie "
        "masses and wheelbases.",
    )
    wheelset_mass = _q(
        1350.0,
        (300.0, 5000.0),
        (800.0, 2500.0),
        "Wheelset mass (kg)",
        "Mass of one wheelset, M_w (paper Table 1), in model.track.assembly.assemble_vehicle "
        "and the Hertz term of stable_time_step. Bounds 0.3–5 t: light tram to powered "
        "heavy-haul wheelsets.",
    )
    primary_stiffness = _q(
        2.14e6,
        (1e5, 1e8),
        (5e5, 5e6),
        "Primary suspension stiffness (N/m)",
        "Primary suspension stiffness per axle box, K_pz (paper Table 1), in "
        "model.track.assembly.assemble_vehicle. Bounds 0.1–100 MN/m: soft rubber springs to a "
        "nearly rigid axle box.",
    )
    primary_damping = _q(
        4.9e4,
        (0, 1e6),
        (0.0, 2e5),
        "Primary suspension damping (N·s/m)",
        "Primary suspension damping per axle box, C_pz (paper Table 1), in "
        "model.track.assembly.assemble_vehicle. Bounds 0–1 MN·s/m: undamped to ten times the "
        "heaviest hydraulic dampers.",
    )
    secondary_stiffness = _q(
        2.535e6,
        (1e5, 1e8),
        (2e5, 5e6),
        "Secondary suspension stiffness (N/m)",
        "Secondary suspension stiffness per bogie side, K_sz (paper Table 1), in "
        "model.track.assembly.assemble_vehicle. Bounds 0.1–100 MN/m: air springs to stiff "
        "freight springs.",
    )
    secondary_damping = _q(
        1.96e5,
        (0, 2e6),
        (0.0, 5e5),
        "Secondary suspension damping (N·s/m)",
        "Secondary suspension damping per bogie side, C_sz (paper Table 1), in "
        "model.track.assembly.assemble_vehicle. Bounds 0–2 MN·s/m: undamped to ten times the "
        "paper's value.",
    )

    @property
    def static_wheel_load(self) -> float:
        """Static load of one wheel on the rail (N): the car's weight over its eight wheels."""
        car_mass = self.car_body_mass + 2 * self.bogie_mass + 4 * self.wheelset_mass
        return car_mass * GRAVITY / 8.0


class Train(param.Parameterized):
    """Train geometry and speed. Defaults: Nanjing Lines 1–2 six-car Type A (docs/model.md §1).

    Used by ``Train.axle_offsets`` (wheel positions in model.track.assembly) and
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
        "Train speed v (paper §4.1: 80 km/h), in model.track.assembly (wheel positions) and "
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
        "Train.axle_offsets and model.track.assembly.assemble_vehicle. Bounds 2–50 m; with "
        "Scenario.validate: 2l_c + wheelbase < L_car.",
    )
    wheelbase = _q(
        2.4,
        (1.0, 5.0),
        (1.8, 3.0),
        "Bogie wheelbase (m)",
        "Axle spacing within a bogie, 2l_h (twice the paper's half wheelbase 1.2 m), in "
        "Train.axle_offsets and model.track.assembly.assemble_vehicle. Bounds 1–5 m: real "
        "bogies have 1.6–3.5 m.",
    )

    single_bogie = Switch(
        False,
        label="Single bogie only",
        doc="If true, simulate the paper's Fig. 1 model: half a car body on one bogie with two "
        "wheelsets, instead of the full train (Train.axle_offsets, "
        "model.track.assembly.assemble_vehicle).",
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
