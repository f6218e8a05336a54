"""Named sets of strain-law constants from the literature, each with its citation and test
conditions (issue 25 item 2), selectable by name as ``s.longterm.soil_set``.

A set fixes the form of the strain law and its constants (a in %, b, m, and n for Chai &
Miura) for every layer of the site; ``"layers"`` (the default) uses each layer's own constants
(``Layer.soil_class`` or its ``a``, ``b``, ``m``, ``n``). Every set says where its numbers were
read and what is known of the tests behind them; what could not be read is said so, never
filled in. **No pore-pressure-law set for a soft clay could be read** (the searches of issue 25
found the laws' forms and citing papers, not a table of constants that could be read): every
set has ``pore_pressure = None`` and the pore-pressure constants stay each layer's (still the
illustrative defaults of ``model.params.site``). docs/validation.md lists what was searched.
"""

from __future__ import annotations

from dataclasses import dataclass, field

NOT_READ = "not read"
"""What a set says of a fact of its source that could not be read."""

_LI_SELIG = (
    "Li, D. & Selig, E. T. (1996), Cumulative plastic deformation for fine-grained subgrade "
    "soils, Journal of Geotechnical Engineering (ASCE) 122(12), 1006–1013"
)
_CARVAJAL_ROMANA = (
    "Carvajal, E. & Romana, M. (2013), Analysis of the influence of soft soil depth on the "
    "subgrade capacity for flexible pavements, Proc. 18th Int. Conf. Soil Mechanics and "
    "Geotechnical Engineering, Paris, TC 202, p. 1253"
)
_CARVAJAL_ROMANA_PAGE = "https://www.cfms-sols.org/sites/default/files/Actes/Volume2/20140516/"


@dataclass(frozen=True)
class Conditions:
    """What is known of the tests behind a set; :data:`NOT_READ` where the source was not read.

    Attributes
    ----------
    soil : str
        The soil tested (classification, origin).
    confining_stress : str
        Effective confining stress of the tests (kPa as published).
    frequency : str
        Loading frequency (Hz as published).
    drainage : str
        Drained or undrained cyclic loading.
    cycles : str
        Range of the number of cycles N of the tests.
    """

    soil: str
    confining_stress: str = NOT_READ
    frequency: str = NOT_READ
    drainage: str = NOT_READ
    cycles: str = NOT_READ


@dataclass(frozen=True)
class SoilSet:
    """One named set of strain-law constants and where it comes from.

    Attributes
    ----------
    name : str
        The name ``longterm.soil_set`` takes.
    law : {"li_selig", "chai_miura", "monismith"}
        Form of the strain law the constants belong to (``longterm.law``).
    a : float
        Coefficient a, ε_p in %.
    b, m : float
        Exponents of N and of the stress ratio.
    n : float or None
        Exponent of (1 + q_s/q_f) (Chai & Miura only; None for the other laws).
    citation : str
        Author, year, title, journal or proceedings, pages.
    read : str
        Where the constants were actually read (page, table) and how (first or second hand).
    conditions : Conditions
        The test conditions behind the constants.
    pore_pressure : dict or None
        Constants of a pore-pressure law (``a_u``, ``b_u``, ``m_u`` …); None: none was read.
    """

    name: str
    law: str
    a: float
    b: float
    m: float
    n: float | None
    citation: str
    read: str
    conditions: Conditions
    pore_pressure: dict | None = field(default=None)

    def constants(self) -> dict[str, float]:
        """The strain-law constants by layer-property name (a in %; n for Chai & Miura)."""
        values = {"a": self.a, "b": self.b, "m": self.m}
        if self.n is not None:
            values["n"] = self.n
        return values


def _li_selig(soil_class: str, a: float, b: float, m: float, read: str) -> SoilSet:
    return SoilSet(
        name=f"li_selig_{soil_class}",
        law="li_selig",
        a=a,
        b=b,
        m=m,
        n=None,
        citation=_LI_SELIG,
        read=read,
        conditions=Conditions(
            soil=f"fine-grained subgrade soil of USCS class {soil_class} (the tests behind the "
            "class values not read)"
        ),
    )


_SECOND_HAND = (
    "second hand: the value set of docs/model.md §10 (the project's specification); Li & Selig's "
    "1996 table itself could not be read"
)

SOIL_SETS: dict[str, SoilSet] = {
    s.name: s
    for s in (
        _li_selig("ML", 0.64, 0.10, 1.7, _SECOND_HAND),
        _li_selig("MH", 0.84, 0.13, 2.0, _SECOND_HAND),
        _li_selig("CL", 1.1, 0.16, 2.0, _SECOND_HAND),
        _li_selig(
            "CH",
            1.2,
            0.18,
            2.4,
            _SECOND_HAND + "; the same a = 1.2, b = 0.18, m = 2.4 read as 'suggested by Li and "
            "Selig (1996)' for a soft soil in Carvajal & Romana (2013), p. 1253 ("
            + _CARVAJAL_ROMANA_PAGE
            + "assets/basic-html/page380.html)",
        ),
        SoilSet(
            name="chai_miura_CH",
            law="chai_miura",
            a=1.2,
            b=0.18,
            m=2.4,
            n=1.0,
            citation=_CARVAJAL_ROMANA,
            read="p. 1253, the text on their Eq. 6 (the law with a, m, n and b, which they "
            "attribute to Chai and Miura, cited there as 2000): 'a = 1.2; b = 0.18; m = 2.4; "
            "n = 1', values 'suggested by Li and Selig (1996)', read at "
            + _CARVAJAL_ROMANA_PAGE
            + "assets/basic-html/page380.html (the proceedings named from that site's pages "
            "and the TC 202 header; the title from the paper's first page on scribd.com)",
            conditions=Conditions(
                soil="soft soil subgrade under a flexible pavement (an application, not a test: "
                "the constants are Li & Selig's CH values with n = 1, assumed by the authors)",
                confining_stress="not stated (no test)",
                frequency="not stated (haversine traffic load cycles in the abstract)",
                drainage="not stated",
                cycles="the page applies it to N = 100 and to a larger N whose value was cut off",
            ),
        ),
    )
}
"""The library, by name."""

LAYERS = "layers"
"""``longterm.soil_set`` value that uses each layer's own strain-law constants."""


def soil_set_names() -> list[str]:
    """The options of ``longterm.soil_set``: ``"layers"`` first, then the sets by name."""
    return [LAYERS, *SOIL_SETS]


def get_soil_set(name: str) -> SoilSet:
    """The set called ``name``.

    Raises
    ------
    ValueError
        An unknown name, in the project's voice (naming the parameter, the value and the
        options).
    """
    if name not in SOIL_SETS:
        options = ", ".join(repr(option) for option in SOIL_SETS)
        raise ValueError(
            f"longterm.soil_set = {name!r} is not one of the options {options} (Soil parameter set)"
        )
    return SOIL_SETS[name]


def strain_law_constants(soil_set: str, law: str, layer) -> dict[str, float]:
    """The strain-law constants in force in ``layer``: a, b, m and n (n only read by Chai & Miura).

    Parameters
    ----------
    soil_set : str
        ``longterm.soil_set``: ``"layers"`` or a set's name.
    law : str
        ``longterm.law``.
    layer : model.params.Layer
        The layer; its constants when ``soil_set`` is ``"layers"``.
    """
    if soil_set == LAYERS:
        a, b, m = layer.law_parameters(law)
        return {"a": a, "b": b, "m": m, "n": layer.n}
    chosen = get_soil_set(soil_set)
    n = layer.n if chosen.n is None else chosen.n
    return {"a": chosen.a, "b": chosen.b, "m": chosen.m, "n": n}
