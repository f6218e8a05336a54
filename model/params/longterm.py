"""Traffic, laws and drainage of the long-term settlement (the ground itself is ``s.site``)."""

from __future__ import annotations

import param

from model.params.quantities import Choice, _q
from model.params.site import ILLUSTRATIVE
from model.params.soil_sets import LAYERS, SOIL_SETS, soil_set_names

# ``s.longterm`` parameters of wave 2 that are now properties of each layer (``s.site.layers``):
# a scenario file that still has them in its long-term section gives them to every layer.
MOVED_TO_LAYERS = (
    "soil_class",
    "a",
    "b",
    "m",
    "n",
    "friction_angle",
    "cu_ratio",
    "undrained_strength",
)


class LongTerm(param.Parameterized):
    """Settlement accumulated over years of traffic (docs/model.md §10, §15).

    Traffic, the form of the cyclic strain-accumulation law ε_p(q_d, N) (its constants are each
    layer's, ``s.site.layers``), the form of the pore-pressure generation law and the drainage
    of the column below the invert. Every parameter is read by ``model.longterm`` (the
    pipeline's "longterm" stage).
    """

    law = Choice(
        default="li_selig",
        objects=["li_selig", "chai_miura", "monismith"],
        label="Strain law",
        doc="Cyclic strain-accumulation law: Li & Selig (1996) ε_p = a (q_d/σ_s)^m N^b; "
        "Chai & Miura (2002) ε_p = a (q_d/q_f)^m (1 + q_s/q_f)^n N^b; Monismith (1975) "
        "ε_p = A N^b; evaluated in model.longterm.",
    )
    soil_set = Choice(
        default=LAYERS,
        objects=soil_set_names(),
        label="Soil parameter set",
        doc="Strain-law constants for every layer from a named set of the literature "
        "(model.params.soil_sets: each with its citation and test conditions), or 'layers': "
        "each layer's own constants (soil class or a, b, m, n). Choosing a set also sets the "
        "law to the set's, and choosing another law returns to 'layers'; read in "
        "model.longterm (settlement, statements).",
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
    pore_pressure_law = Choice(
        default="power",
        objects=["power", "hyperbolic", "none"],
        label="Pore-pressure law",
        doc="Generated (undrained) excess pore pressure u_g = σ′_v0 r_u(N), with each layer's "
        "constants: power r_u = a_u (q_d/σ_s)^m_u N^b_u, hyperbolic r_u = (q_d/σ_s)^m_u "
        "N/(α + βN), capped at r_u,max; its dissipation while traffic goes on gives the "
        "consolidation settlement in model.longterm.consolidation. 'none': no pore pressure, "
        "the settlement is the plastic part alone (wave 2's model).",
    )
    invert_drainage = Choice(
        default="sealed",
        objects=["sealed", "drained", "leaking"],
        label="Drainage at the invert",
        doc="Top of the consolidating column in model.longterm.consolidation, at the lining: "
        "'sealed' (no flow, ∂u/∂z = 0: a "
        "watertight lining), 'drained' (u = 0: free drainage into the tunnel), 'leaking' "
        "(flow through the lining, k_s ∂u/∂z = (k_l/t_l) u, with longterm.lining_permeability "
        "and the lining thickness tunnel.thickness).",
    )
    base_drainage = Choice(
        default="drained",
        objects=["drained", "sealed"],
        label="Drainage at the base",
        doc="Bottom of the consolidating column in model.longterm.consolidation (the deepest "
        "depth, numerics.max_depth below the invert): 'drained' (u = 0) or 'sealed' "
        "(∂u/∂z = 0).",
    )
    lining_permeability = _q(
        1e-11,
        (0, 1e-3),
        (1e-13, 1e-8),
        "Lining permeability k_l (m/s)",
        "Hydraulic conductivity of the lining (joints included) for invert_drainage = 'leaking' "
        "in model.longterm.consolidation; the lining conducts k_l/t_l with t_l = "
        "tunnel.thickness. " + ILLUSTRATIVE + " Bounds [0, 1e-3] m/s.",
    )

    @param.depends("soil_set", watch=True, on_init=True)
    def _law_of_the_set(self):
        """A named set belongs to one law: choosing it chooses that law."""
        if self.soil_set != LAYERS:
            self.law = SOIL_SETS[self.soil_set].law

    @param.depends("law", watch=True)
    def _set_of_the_law(self):
        """Another law than the named set's leaves the set: back to each layer's constants."""
        if self.soil_set != LAYERS and SOIL_SETS[self.soil_set].law != self.law:
            self.soil_set = LAYERS
