"""Traffic, static ground state and strain law of the long-term (permanent) settlement."""

from __future__ import annotations

import math

import param

from model.params.quantities import Choice, _q

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

    law = Choice(
        default="li_selig",
        objects=["li_selig", "chai_miura", "monismith"],
        label="Strain law",
        doc="Cyclic strain-accumulation law: Li & Selig (1996) ε_p = a (q_d/σ_s)^m N^b; "
        "Chai & Miura (2002) ε_p = a (q_d/q_f)^m (1 + q_s/q_f)^n N^b; Monismith (1975) "
        "ε_p = A N^b; evaluated in model.longterm.",
    )
    soil_class = Choice(
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
    cycles_per_train = Choice(
        default="bogies",
        objects=["bogies", "rainflow"],
        label="Cycles per train",
        doc="Load cycles per passage in model.longterm: one per bogie, or counted on the deviator "
        "history by rainflow (ASTM E1049), full cycles weighted by their range.",
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
