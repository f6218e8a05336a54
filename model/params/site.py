"""The site profile: soil layers from the ground surface down, and the water table (§14).

Each :class:`Layer` holds what the long-term stage reads of the ground it crosses: unit weight
(for σ′_v0), strength and K0, the constants of the strain law, of the pore-pressure law and of
consolidation. :class:`Site` is the list of layers top down and the water table depth.

Sources. The strain-law sets and the strength/K0 defaults are those the long-term stage has
always used (docs/longterm.md, "Assumptions and their sources"). **No soft-clay constant of a
pore-pressure law, compressibility or permeability was found in a source that could be read**
(/work/notes/literature.md §5): the defaults of a_u, b_u, m_u, α_u, β_u, m_v, C_r, e0 and k are
*illustrative*, round values of a plausible order, and every doc below says so; r_u,max = 0.9 is
docs/model.md §15's rule, not a measured value. Replace them by a site's test data.
"""

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
# The long-term stage's year: 365 days, for N = trains per day × 365 × years (docs/model.md §10)
# and for the time of consolidation (docs/longterm.md, "Days per year").
DAYS_PER_YEAR = 365.0
SECONDS_PER_YEAR = DAYS_PER_YEAR * 86400.0
ILLUSTRATIVE = "Illustrative default, not from a source (docs/longterm.md): use the site's data."
PAPER_UNIT_WEIGHT = 1800.0 * 9.81  # N/m³: the paper case's soil density × g (docs/model.md §14)


class Layer(param.Parameterized):
    """One soil layer of the site profile, with its long-term properties (docs/model.md §14–15).

    Read by ``model.longterm`` at every depth of the long-term column that lies in the layer (a
    depth on a boundary takes the lower layer). Bounds refuse impossible values; the profile as a
    whole is checked by :meth:`model.params.Scenario.validate`.
    """

    name = param.String(
        default="soft clay", constant=False, doc="Name of the layer, as the borehole log has it."
    )
    thickness = _q(
        100.0,
        (0, 1000),
        (0.5, 60.0),
        "Thickness (m)",
        "Thickness of the layer (m). Bounds (0, 1000] m. The default single layer reaches 100 m "
        "below the surface, below the deepest depth of the paper case (52.85 m).",
        (False, True),
    )
    unit_weight = _q(
        PAPER_UNIT_WEIGHT,
        (0, 30000),
        (12000.0, 23000.0),
        "Unit weight γ (N/m³)",
        "Unit weight of the soil, taken as saturated below the water table and used as is above "
        "it (σ_v = Σ γ h); default 1800 kg/m³ × g, the density of s.soil in the paper case. "
        "Bounds (0, 30] kN/m³: soils weigh 12–23 kN/m³.",
        (False, True),
    )
    friction_angle = _q(
        25.0,
        (0, 60),
        (15.0, 40.0),
        "Effective friction angle φ′ (°)",
        "Effective friction angle φ′; sets K0 = 1 − sin φ′ (Jaky, "
        "Layer.earth_pressure_coefficient) for the static deviator q_s. Bounds (0, 60]°: soils "
        "have 15–45°.",
        (False, True),
    )
    cu_ratio = _q(
        0.22,
        (0, 2),
        (0.1, 0.5),
        "Undrained strength ratio c_u/σ′_v0 (-)",
        "Undrained shear strength as a ratio to the vertical effective stress (normally "
        "consolidated clay, Mesri 1975); the static strength is σ_s = q_f = 2c_u. Bounds (0, 2]: "
        "normally consolidated clays 0.2–0.3, heavily overconsolidated ones up to ~1.",
        (False, True),
    )
    undrained_strength = _q(
        None,
        (0, None),
        (10e3, 200e3),
        "Undrained shear strength c_u (Pa)",
        "Undrained shear strength c_u given directly (uniform in the layer); None uses the ratio "
        "to σ′_v0 above. Bounds: any positive strength.",
        (False, True),
        allow_none=True,
    )
    soil_class = Choice(
        default="CH",
        objects=[*LI_SELIG_SOIL_CLASSES, "user"],
        label="Soil class",
        doc="Li & Selig parameter set (a, b, m) for ML, MH, CL, CH soils; 'user' takes the values "
        "of a, b and m below (e.g. from a cyclic-triaxial calibration); via Layer.law_parameters.",
    )
    a = _q(
        1.2,
        (0, 100),
        (0.1, 5.0),
        "Law coefficient a (%)",
        "Coefficient a (or A of Monismith) of the strain law, ε_p in %; used when the soil class "
        "is 'user' or the law is not Li & Selig. Bounds (0, 100] %: a strain beyond 100 % is "
        "failure, not accumulation.",
        (False, True),
    )
    b = _q(
        0.18,
        (0, 1),
        (0.05, 0.4),
        "Cycle exponent b (-)",
        "Exponent b of N in the strain law; used when the soil class is 'user' or the law is not "
        "Li & Selig. Bounds (0, 1): the strain grows with N, but slower than linearly (published "
        "fits 0.1–0.3).",
        (False, False),
    )
    m = _q(
        2.4,
        (0, 10),
        (1.0, 4.0),
        "Stress exponent m (-)",
        "Exponent m of the stress ratio in the strain law; used when the soil class is 'user' or "
        "the law is not Li & Selig. Bounds (0, 10]: published fits 1–4.",
        (False, True),
    )
    n = _q(
        1.0,
        (0, 10),
        (0.0, 3.0),
        "Static-stress exponent n (-)",
        "Exponent n of (1 + q_s/q_f) in Chai & Miura's law (default 1.0). Bounds [0, 10]: "
        "published fits 0–3.",
    )
    a_u = _q(
        0.05,
        (0, 10),
        (0.005, 0.5),
        "Pore-pressure coefficient a_u (-)",
        "Coefficient of the power law r_u = a_u (q_d/σ_s)^m_u N^b_u of the generated pore-pressure "
        "ratio (longterm.pore_pressure_law = 'power'). " + ILLUSTRATIVE + " Bounds (0, 10].",
        (False, True),
    )
    b_u = _q(
        0.15,
        (0, 1),
        (0.02, 0.5),
        "Pore-pressure cycle exponent b_u (-)",
        "Exponent of N in the power law of r_u. " + ILLUSTRATIVE + " Bounds [0, 1): r_u grows "
        "slower than N.",
        (True, False),
    )
    m_u = _q(
        1.5,
        (0, 10),
        (0.5, 4.0),
        "Pore-pressure stress exponent m_u (-)",
        "Exponent of q_d/σ_s in both pore-pressure laws. " + ILLUSTRATIVE + " Bounds [0, 10].",
    )
    alpha_u = _q(
        1e4,
        (0, None),
        (10.0, 1e7),
        "Hyperbolic constant α_u (cycles)",
        "α of the hyperbolic law r_u = (q_d/σ_s)^m_u N/(α + βN) (longterm.pore_pressure_law = "
        "'hyperbolic'): r_u reaches half its limit after α/β cycles. "
        + ILLUSTRATIVE
        + " Bounds (0, inf).",
        (False, True),
    )
    beta_u = _q(
        1.0,
        (0, None),
        (0.1, 10.0),
        "Hyperbolic constant β_u (-)",
        "β of the hyperbolic law: r_u tends to (q_d/σ_s)^m_u/β for N ≫ α/β. "
        + ILLUSTRATIVE
        + " Bounds [0, inf).",
    )
    r_u_max = _q(
        0.9,
        (0, 1),
        (0.3, 1.0),
        "Largest pore-pressure ratio r_u,max (-)",
        "Cap of the generated pore-pressure ratio u_g/σ′_v0 (docs/model.md §15 default 0.9, a "
        "rule, not a measured value); a warning names the depths where it acts. Bounds (0, 1]: "
        "r_u = 1 is zero effective stress.",
        (False, True),
    )
    compressibility = _q(
        1e-7,
        (0, 1e-4),
        (1e-8, 2e-6),
        "Volume compressibility m_v (1/Pa)",
        "Coefficient of volume compressibility m_v for the consolidation strain ε_c = m_v (u_g − "
        "u); None takes the recompression line, m_v = 0.434 C_r/((1 + e0) σ′_v0). Default "
        "0.1 MPa⁻¹ (of the order of soft clay unloaded and reloaded). "
        + ILLUSTRATIVE
        + " Bounds (0, 100] MPa⁻¹.",
        (False, True),
        allow_none=True,
    )
    recompression_index = _q(
        0.05,
        (0, 2),
        (0.005, 0.3),
        "Recompression index C_r (-)",
        "Slope of the recompression line, e against log10 σ′; read only when compressibility is "
        "None. " + ILLUSTRATIVE + " Bounds (0, 2].",
        (False, True),
    )
    void_ratio = _q(
        1.2,
        (0, 10),
        (0.5, 3.0),
        "Initial void ratio e0 (-)",
        "Void ratio at σ′_v0; read only when compressibility is None. "
        + ILLUSTRATIVE
        + " Bounds (0, 10].",
        (False, True),
    )
    permeability = _q(
        1e-9,
        (0, 1e-2),
        (1e-11, 1e-6),
        "Hydraulic conductivity k (m/s)",
        "Vertical hydraulic conductivity k; the flux (k/γ_w) ∂u/∂z is continuous across layer "
        "boundaries and c_v = k/(m_v γ_w). Read when consolidation_coefficient is None. "
        + ILLUSTRATIVE
        + " Bounds (0, 0.01] m/s.",
        (False, True),
    )
    consolidation_coefficient = _q(
        None,
        (0, 1),
        (1e-9, 1e-5),
        "Coefficient of consolidation c_v (m²/s)",
        "Coefficient of consolidation c_v given directly (then k = c_v m_v γ_w); None derives it "
        "from the permeability. Bounds (0, 1] m²/s.",
        (False, True),
        allow_none=True,
    )

    def __init__(self, **params):
        try:
            super().__init__(**params)
        except ValueError as error:  # name the layer: a profile has several
            raise ValueError(f"layer {params.get('name', 'soft clay')!r}: {error}") from None

    @property
    def earth_pressure_coefficient(self) -> float:
        """K0 = 1 − sin φ′ (Jaky)."""
        return 1.0 - math.sin(math.radians(self.friction_angle))

    def law_parameters(self, law: str = "li_selig") -> tuple[float, float, float]:
        """(a, b, m) in force for ``law``: the soil class's set for Li & Selig, else a, b, m."""
        if law == "li_selig" and self.soil_class != "user":
            return LI_SELIG_SOIL_CLASSES[self.soil_class]
        return self.a, self.b, self.m

    def values(self) -> dict:
        """Every property by name, plain values (the layer's entry in a scenario's JSON)."""
        return {name: getattr(self, name) for name in self.param}


LAYER_PROPERTIES = tuple(Layer.param)
"""The properties of a layer, ``name`` first, in declaration order."""


class Site(param.Parameterized):
    """The ground the long-term stage reads: layers top down from the surface, and the water.

    σ_v(z) = Σ γ_i h_i down to z, u_0 = γ_w max(0, z − z_w), σ′_v0 = σ_v − u_0 (docs/model.md
    §14). The dynamic stresses are still those of the homogeneous ``s.soil`` (§7/§9), which
    should represent the ground around the tunnel.
    """

    layers = param.List(
        default=[Layer()],  # each Site makes its own (__init__)
        item_type=Layer,
        bounds=(1, None),
        label="Layers",
        doc="Soil layers top down from the ground surface (Layer objects), read by "
        "model.longterm (model.longterm.geostatic for σ′_v0, the laws and the consolidation at "
        "each depth of the column); the deepest layer must reach below the deepest depth of the "
        "long-term stage. Default: one layer equal to the paper case's soil.",
    )
    water_table_depth = _q(
        0.0,
        (0, 200),
        (0.0, 10.0),
        "Water table depth (m)",
        "Depth of the water table below the ground surface, z_w, for u_0 and σ′_v0 in "
        "model.longterm.geostatic (above it the unit weight is used as is). Bounds [0, 200] m "
        "(0: at the surface); it must lie within the profile.",
    )

    def __init__(self, **params):
        params.setdefault("layers", [Layer()])
        super().__init__(**params)

    @property
    def bottoms(self) -> list[float]:
        """Depth below the surface of the bottom of each layer (m)."""
        depth, bottoms = 0.0, []
        for layer in self.layers:
            depth += layer.thickness
            bottoms.append(depth)
        return bottoms

    def layer_index(self, depth_below_ground: float) -> int:
        """Index of the layer holding a depth below the surface; a boundary takes the lower one.

        Depths below the profile get the last layer (the profile check refuses them first).
        """
        for index, bottom in enumerate(self.bottoms):
            if depth_below_ground < bottom:
                return index
        return len(self.layers) - 1

    def records(self) -> list[dict]:
        """The layers as plain dicts (:meth:`Layer.values`), top down."""
        return [layer.values() for layer in self.layers]


def layers_from_records(records) -> list[Layer]:
    """Layer objects from ``{property: value}`` dicts (or layers), top down.

    Raises
    ------
    ValueError, KeyError
        Not a list of objects, an unknown property or a refused value, naming the layer as
        ``site.layers[i]``.
    """
    if not isinstance(records, list):
        raise ValueError(f"site.layers must be a list of layers, not {type(records).__name__}")
    layers = []
    for index, record in enumerate(records):
        where = f"site.layers[{index}]"
        if isinstance(record, Layer):
            layers.append(record)
            continue
        if not isinstance(record, dict):
            raise ValueError(f"{where} must be an object of layer properties")
        unknown = set(record) - set(LAYER_PROPERTIES)
        if unknown:
            raise KeyError(
                f"unknown layer property(ies) {sorted(unknown)} in {where}; known: "
                f"{', '.join(LAYER_PROPERTIES)}"
            )
        name = record.get("name", Layer.param["name"].default)
        try:
            layers.append(Layer(**record))
        except (ValueError, TypeError) as error:
            text = str(error).removeprefix(f"layer {name!r}: ").replace("layer.", f"{where}.", 1)
            raise ValueError(f"{text}, layer {name!r}") from None
    return layers
