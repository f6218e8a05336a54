"""The inputs of every stage: param classes, one per section of a scenario.

The single source of truth for defaults, physical bounds, slider ranges (``softbounds``), units
(in each ``label``) and derived quantities. Defaults follow docs/model.md: the paper's
Tables 1, 3 and 4 where they are usable, stated assumptions where the paper is silent (its
Table 2 is missing). Every value is SI except ``Train.speed_kmh``.

A bad value is refused at assignment with a message that names the parameter, the value and
the allowed range; constraints between parameters are checked by :meth:`Scenario.validate`
before any computation.

Modules, in the order of the chain:

- ``quantities``: the parameter types (:class:`Quantity`, :class:`Count`, :class:`CountOrOff`,
  :class:`Choice`, :class:`Switch`, :class:`Text`), the one voice of their refusals
  (:func:`refusal`), :class:`ScenarioError`, g and the package data files;
- ``vehicle``: :class:`Vehicle` (one car's masses and suspensions), :class:`Train`;
- ``track``: :class:`Track` (rail, fasteners, blocks, wheel contact), :class:`Irregularity`;
- ``measured_profile``: a measured rail profile's CSV format and checks, and which profile
  files a run may read (any for the command line, only the data folder's for a server);
- ``ground``: :class:`Tunnel` (the lining), :class:`Soil`;
- ``numerics``: :class:`Numerics`, the discretisation of every stage;
- ``site``: :class:`Site` (the soil layers top down and the water table), :class:`Layer`;
- ``borehole``: a borehole log as a CSV file, read into layers by its header's names and units;
- ``soil_sets``: named strain-law sets of the literature (``SOIL_SETS``, :class:`SoilSet`), each
  with its citation and test conditions, chosen by ``longterm.soil_set``;
- ``longterm``: :class:`LongTerm`, traffic, laws and drainage of the long-term settlement;
- ``scenario``: :class:`Scenario` (all sections), ``SECTIONS``, presets, JSON, dotted paths;
- ``display``: units, labels and ranges as the interface shows them.

Everything is re-exported here: ``from model.params import Scenario``.
"""

from model.params.display import (
    DISPLAY_UNITS,
    display_label,
    display_range,
    display_unit,
    parameter_of,
)
from model.params.ground import THIN_RING_MAX_RATIO, Soil, Tunnel
from model.params.longterm import LongTerm
from model.params.numerics import Numerics
from model.params.quantities import (
    DATA_DIR,
    GRAVITY,
    PRESETS_FILE,
    Choice,
    Count,
    CountOrOff,
    Quantity,
    ScenarioError,
    Switch,
    Text,
    refusal,
)
from model.params.scenario import SECTIONS, Scenario
from model.params.site import LAYER_PROPERTIES, LI_SELIG_SOIL_CLASSES, Layer, Site
from model.params.soil_sets import SOIL_SETS, SoilSet
from model.params.track import FRA_ROUGHNESS_CM2_RAD_PER_M, HERTZ_FITS, Irregularity, Track
from model.params.vehicle import Train, Vehicle

__all__ = [
    "DATA_DIR",
    "DISPLAY_UNITS",
    "FRA_ROUGHNESS_CM2_RAD_PER_M",
    "GRAVITY",
    "HERTZ_FITS",
    "LAYER_PROPERTIES",
    "LI_SELIG_SOIL_CLASSES",
    "PRESETS_FILE",
    "SECTIONS",
    "SOIL_SETS",
    "THIN_RING_MAX_RATIO",
    "Choice",
    "Count",
    "CountOrOff",
    "Irregularity",
    "Layer",
    "LongTerm",
    "Numerics",
    "Quantity",
    "Scenario",
    "ScenarioError",
    "Site",
    "SoilSet",
    "Soil",
    "Switch",
    "Text",
    "Track",
    "Train",
    "Tunnel",
    "Vehicle",
    "display_label",
    "display_range",
    "display_unit",
    "parameter_of",
    "refusal",
]
