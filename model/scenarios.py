"""Named ways into a scenario: presets, standard train types and text overrides (URL arguments).

Domain helpers shared by the dashboard and any other front end; no GUI code.
"""

from __future__ import annotations

import functools
import json
from collections.abc import Mapping
from pathlib import Path

from model.params import DATA_DIR, PRESETS_FILE, Scenario, Train

DEFAULT_PRESET = "paper"
"""The paper's Nanjing case (:meth:`Scenario.paper`)."""

CUSTOM = "custom"
"""Name given to inputs that match no preset or no standard train type."""

SAMPLE = "sample"
"""The word that names a shipped sample file on the command line (``--scenario sample``,
``--session sample``), unless a file of that name exists."""

SAMPLE_SCENARIO_FILE = DATA_DIR / "sample_scenario.json"
"""A scenario file to start from: the single bogie at 60 km/h on the example measured rail
profile, which it names by a path relative to itself (``example_profile.csv``)."""


def named_file(path: Path, sample: Path) -> Path:
    """``path``, or ``sample`` where ``path`` is the word :data:`SAMPLE` and no such file exists."""
    return sample if str(path) == SAMPLE and not path.exists() else path


TRAIN_TYPES = {"Type A": Train.type_a, "Type B": Train.type_b}
"""Standard Chinese metro cars by name; each builds a :class:`Train` of that geometry."""

TRAIN_GEOMETRY = ("car_length", "bogie_distance", "wheelbase")
"""The train parameters a train type fixes."""


def preset_descriptions() -> dict[str, str]:
    """One-line description of every preset in ``model/data/presets.json``, by name."""
    presets = json.loads(PRESETS_FILE.read_text(encoding="utf-8"))["presets"]
    return {name: entry.get("description", "") for name, entry in presets.items()}


def matching_preset(scenario: Scenario) -> str:
    """Name of the preset whose inputs ``scenario`` has exactly, else :data:`CUSTOM`."""
    current = scenario.to_dict()
    for name, inputs in _preset_inputs().items():
        if inputs == current:
            return name
    return CUSTOM


@functools.cache
def _preset_inputs() -> dict[str, dict]:
    """:meth:`Scenario.to_dict` of every preset, by name, built once per process: the page
    asks which preset the inputs match after every change (7 presets built anew took 6 ms)."""
    return {name: Scenario.preset(name).to_dict() for name in Scenario.preset_names()}


def train_type_of(train: Train) -> str:
    """Name of the standard train type whose geometry ``train`` has, else :data:`CUSTOM`."""
    for name, build in TRAIN_TYPES.items():
        standard = build()
        if all(getattr(train, n) == getattr(standard, n) for n in TRAIN_GEOMETRY):
            return name
    return CUSTOM


def apply_train_type(scenario: Scenario, name: str) -> None:
    """Give ``scenario`` the geometry of the standard train type ``name`` (in place)."""
    if name not in TRAIN_TYPES:
        raise KeyError(f"unknown train type {name!r}; available: {', '.join(TRAIN_TYPES)}")
    standard = TRAIN_TYPES[name]()
    scenario.train.param.update({n: getattr(standard, n) for n in TRAIN_GEOMETRY})


def scenario_from_arguments(arguments: Mapping[str, str]) -> tuple[str, Scenario, list[str]]:
    """Scenario from text arguments: ``preset`` and any ``section.parameter`` overrides (SI).

    Parameters
    ----------
    arguments : mapping of str to str
        E.g. ``{"preset": "single_bogie", "train.speed_kmh": "60"}`` (URL query arguments).
        Names without a dot other than ``preset`` are ignored.

    Returns
    -------
    preset : str
        The preset used (:data:`DEFAULT_PRESET` when none or an unknown one was asked for).
    scenario : Scenario
        The preset with every acceptable override applied.
    problems : list of str
        One message per refused argument (unknown preset, unknown parameter, bad value).
    """
    values = dict(arguments)
    preset = values.pop("preset", DEFAULT_PRESET)
    problems = []
    names = Scenario.preset_names()
    if preset not in names:
        problems.append(f"unknown preset {preset!r}; available: {', '.join(names)}")
        preset = DEFAULT_PRESET
    scenario = Scenario.preset(preset)
    for path, value in values.items():
        if "." not in path:
            continue
        try:
            scenario.set_value(path, value)
        except (KeyError, ValueError) as error:
            problems.append(error_text(error))
    return preset, scenario, problems


def error_text(error: BaseException) -> str:
    """The message of an exception (a KeyError quotes its argument otherwise)."""
    if isinstance(error, KeyError) and error.args:
        return str(error.args[0])
    return str(error) or type(error).__name__
