"""The track (rail, fasteners, blocks, wheel contact) and its vertical irregularity."""

from __future__ import annotations

import param

from model.params.measured_profile import parse_profile
from model.params.quantities import Choice, Count, Switch, Text, _q

# Hertz contact constant G = a R^b × 1e-8 m/N^(2/3) (Zhai's empirical fits), by wheel tread type.
HERTZ_FITS = {"conical": (4.57, -0.149), "worn": (3.86, -0.115)}

# FRA vertical-profile roughness parameter A_v in cm²·rad/m for track classes 1–6.
FRA_ROUGHNESS_CM2_RAD_PER_M = {1: 1.2107, 2: 1.0181, 3: 0.6816, 4: 0.5376, 5: 0.2095, 6: 0.0339}


class Track(param.Parameterized):
    """Elastic supporting-block ballastless track, one rail.

    The paper's Table 2 is missing; defaults are typical Chinese-metro values (docs/model.md §2):
    60 kg/m rail, 0.6 m block spacing. Used by ``model.track.assembly.assemble_track`` and
    ``stable_time_step``; the Winkler values by ``winkler_block_displacement``.
    """

    rail_E = _q(
        2.059e11,
        (1.5e11, 2.5e11),
        (1.9e11, 2.2e11),
        "Rail Young's modulus (Pa)",
        "Young's modulus of rail steel, E (assumed, docs/model.md §2), in the modal rail of "
        "model.track.assembly.assemble_track (EI). Bounds 150–250 GPa: rail steels.",
    )
    rail_I = _q(
        3.217e-5,
        (5e-6, 1e-4),
        (1e-5, 6e-5),
        "Rail second moment of area (m⁴)",
        "Vertical-bending second moment of area of the rail, I (60 kg/m rail, assumed), in "
        "model.track.assembly.assemble_track (EI). Bounds 5e-6–1e-4 m⁴: light 30 kg/m rails to "
        "beyond the 75 kg/m rail.",
    )
    rail_mass = _q(
        60.64,
        (20.0, 120.0),
        (40.0, 80.0),
        "Rail mass per length (kg/m)",
        "Mass per metre of the rail, m_r (assumed), in model.track.assembly.assemble_track. "
        "Bounds 20–120 kg/m: light rails to heavy rails with fittings.",
    )
    block_spacing = _q(
        0.6,
        (0.3, 1.5),
        (0.5, 0.75),
        "Block spacing (m)",
        "Distance between supporting blocks, L_s (assumed), in "
        "model.track.assembly.assemble_track, Scenario.rail_length and the line load "
        "model.pipeline.invert_line_load. Bounds 0.3–1.5 m: the discretely supported rail "
        "needs several supports per wheel-load spread; real spacings are 0.5–0.75 m.",
    )
    fastener_stiffness = _q(
        8e7,
        (1e6, 1e10),
        (1e7, 2e8),
        "Fastener stiffness (N/m)",
        "Rail pad / fastener stiffness per block, K_r (assumed), in "
        "model.track.assembly.assemble_track. Bounds 1 MN/m–10 GN/m: the softest resilient "
        "fasteners to a practically rigid pad.",
    )
    fastener_damping = _q(
        5e4,
        (0, 1e6),
        (0.0, 2e5),
        "Fastener damping (N·s/m)",
        "Rail pad / fastener damping per block, C_r (assumed), in "
        "model.track.assembly.assemble_track. Bounds 0–1 MN·s/m: undamped to five times the "
        "stiffest published pads.",
    )
    pad_stiffness = _q(
        4e7,
        (1e6, 1e10),
        (5e6, 1.5e8),
        "Block pad stiffness (N/m)",
        "Block pad + rubber boot stiffness per block, K_s (assumed), in "
        "model.track.assembly.assemble_track; the invert force K_s Z_s + C_s Ż_s. Bounds "
        "1 MN/m–10 GN/m: soft boots to a practically rigid support.",
    )
    pad_damping = _q(
        8e4,
        (0, 1e6),
        (0.0, 3e5),
        "Block pad damping (N·s/m)",
        "Block pad + rubber boot damping per block, C_s (assumed), in "
        "model.track.assembly.assemble_track and the invert force. Bounds 0–1 MN·s/m: undamped to "
        "five times the most damped published boots.",
    )
    block_mass = _q(
        100.0,
        (10.0, 1000.0),
        (50.0, 300.0),
        "Block mass (kg)",
        "Mass of one supporting block on one rail, M_s (assumed), in "
        "model.track.assembly.assemble_track. Bounds 10–1000 kg: a base plate to a floating "
        "slab segment per rail seat.",
    )
    wheel_radius = _q(
        0.42,
        (0.25, 0.6),
        (0.35, 0.5),
        "Wheel radius (m)",
        "Rolling radius of the wheel, R (assumed), in Track.hertz_constant (used by "
        "model.track.kernels.hertz_force). Bounds 0.25–0.6 m: where Zhai's Hertz fits G(R) were "
        "made (wheel diameters 0.5–1.2 m).",
    )

    wheel_tread = Choice(
        default="conical",
        objects=list(HERTZ_FITS),
        label="Wheel tread",
        doc="Tread profile for the Hertz constant G of Track.hertz_constant (the contact law of "
        "model.track.kernels.hertz_force): conical G = 4.57 R^-0.149e-8, worn "
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


class ProfileText(param.String):
    """The CSV text of a measured profile, or None; parsed and checked at assignment
    (:func:`model.params.measured_profile.parse_profile`), so a scenario never holds a bad one."""

    def _validate_value(self, val, allow_None):
        super()._validate_value(val, allow_None)
        if val is not None:
            parse_profile(val, "irregularity.profile_data")


class Irregularity(param.Parameterized):
    """Vertical rail-profile irregularity: US FRA PSD, trigonometric-series synthesis (§2.4).

    Used by ``model.track.irregularity.profile_for`` (called from ``model.track.assembly``).
    """

    enabled = Switch(
        True,
        label="Irregularity on",
        doc="If false, the rail is perfectly smooth (model.track.irregularity.profile_for).",
    )
    track_class = Count(
        6,
        bounds=(1, 6),
        softbounds=(1, 6),
        label="FRA track class",
        doc="US FRA track class 1–6 (A_v of fra_psd in model.track.irregularity); 6 is the best "
        "track and the paper's choice. Bounds: the classes the FRA defines.",
    )
    seed = Count(
        2024,
        bounds=(0, 2**32 - 1),
        softbounds=(0, 9999),
        label="Random seed",
        doc="Seed of the random phases φ_k of model.track.irregularity.synthesize_profile. Bounds: "
        "NumPy's 32-bit seed range.",
    )
    wavelength_min = _q(
        1.0,
        (0.1, 100.0),
        (0.5, 10.0),
        "Shortest wavelength (m)",
        "Lower end λ_min of the synthesised band (docs/model.md §4: 1 m), in "
        "model.track.irregularity.series_wavenumbers; sets the profile grid step λ_min/100 in "
        "model.track.assembly.assemble_wheels. Bounds 0.1–100 m: shorter waves are "
        "corrugation, outside the FRA fit; must be below wavelength_max (Scenario.validate).",
    )
    wavelength_max = _q(
        50.0,
        (0.5, 1000.0),
        (10.0, 120.0),
        "Longest wavelength (m)",
        "Upper end λ_max of the synthesised band (docs/model.md §4: 50 m), in "
        "model.track.irregularity.series_wavenumbers. Bounds 0.5–1000 m: beyond, the waves are "
        "alignment design, not irregularity.",
    )
    n_components = Count(
        2000,
        bounds=(10, 200000),
        softbounds=(200, 10000),
        label="Harmonic components",
        doc="Number of cosines N_k in model.track.irregularity.synthesize_profile. Bounds 10–2e5: "
        "the cost grows as N_k × profile points (see the run-cost guard).",
    )
    profile_csv = Text(
        None,
        allow_None=True,
        label="Measured profile CSV",
        doc="Path of a measured profile file (format of model.params.measured_profile: x in m "
        "from the monitored block, η in m or mm), read by model.track.irregularity.profile_for "
        "and replacing the synthetic profile. A relative path in a scenario file is resolved "
        "against that file's folder (Scenario.from_file). Read as given by the command line and "
        "the Python API only; the dashboard accepts the name of a file in its data folder "
        "($TUNNELSETTLE_DATA_DIR) and reads it into profile_data (measured_profile.admit_profile).",
    )
    profile_data = ProfileText(
        None,
        allow_None=True,
        label="Measured profile (CSV text)",
        doc="A measured profile held by content: the CSV text itself (the format of "
        "model.params.measured_profile, at most MAX_PROFILE_BYTES), as uploaded in the "
        "dashboard or saved in a scenario file, read by model.track.irregularity.profile_for "
        "in place of the synthetic profile. Not together with profile_csv.",
    )
