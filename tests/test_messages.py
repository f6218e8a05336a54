"""One voice in every refusal of an input (issue 30): a walk over every parameter of every section
with a bad value of each kind, assigned in Python, set from command-line text and read from a
scenario file.

Each message must start with the dotted lower-case path and the value (with the unit of the
parameter's label for a number), state the allowed range or the options, and hold none of
param's own wording ("parameter '", "<class", the class name of the section).
"""

from __future__ import annotations

import math
import re

import param
import pytest

from model.params import SECTIONS, Choice, Count, Quantity, Scenario, Switch, Text
from model.params.quantities import _format_range, number_text, split_label
from model.params.track import ProfileText

RAW_LIBRARY_TEXT = re.compile(r"parameter '|<class|valid options|only takes|must be an integer")


def _parameters():
    """(path, parameter) of every input of a scenario. ``site.layers`` is a list of layers,
    each refusing its own properties as ``site.layers[i].name`` (tests/test_site.py and
    tests/test_site_view.py walk those); a measured profile's text is refused with the reason
    its parsing gives (tests/test_profile_access.py)."""
    for section in SECTIONS:
        for name, p in Scenario.param[section].class_.param.objects("existing").items():
            if name != "name" and not isinstance(p, param.List | ProfileText):
                yield f"{section}.{name}", p


PARAMETERS = dict(_parameters())


def _out_of_range(p: param.Number) -> float | int:
    """A value just outside the bounds (the excluded end itself where one is excluded)."""
    low, high = p.bounds
    if high is not None:
        return high if not p.inclusive_bounds[1] else (high + 1 if high >= 1 else high * 2 + 1)
    return low if not p.inclusive_bounds[0] else low - 1


def _bad_values(p: param.Parameter) -> list:
    """A bad value of every kind for ``p``'s type."""
    if isinstance(p, Count):
        return [_out_of_range(p), 2.5, "x", True, math.nan, [1]] + ([] if p.allow_None else [None])
    if isinstance(p, Quantity):
        values = [_out_of_range(p), "abc", True, math.nan, math.inf, -math.inf, [1.0]]
        return values + ([] if p.allow_None else [None])
    if isinstance(p, Choice):
        return ["not-an-option", 3, None, True]
    if isinstance(p, Switch):
        return ["yes", 3, None, 0.5]
    if isinstance(p, Text):
        return [5, ["a.csv"], True]
    raise AssertionError(f"{type(p).__name__} is not a parameter type of the project")


CASES = [
    pytest.param(path, bad, id=f"{path}={bad!r}")
    for path, p in PARAMETERS.items()
    for bad in _bad_values(p)
]


def _allowed(p: param.Parameter) -> list[str]:
    """Texts the message must hold to state what is allowed."""
    if isinstance(p, Quantity | Count):
        return [_format_range(p.bounds, p.inclusive_bounds, isinstance(p, Count))]
    if isinstance(p, Choice):
        return [repr(option) for option in p.objects]
    if isinstance(p, Switch):
        return ["true or false"]
    return ["text"]


def _value_text(p: param.Parameter, value) -> str:
    """The value as the message must show it."""
    if isinstance(value, int | float) and not isinstance(value, bool):
        unit = split_label(p.label)[1]
        finite = math.isfinite(value)
        return number_text(value) + (f" {unit}" if unit and unit != "-" and finite else "")
    return repr(value)


def _check_voice(message: str, path: str, value_text: str) -> None:
    """The message starts with "path = value", states what is allowed, and is ours alone."""
    p = PARAMETERS[path]
    assert message.startswith(f"{path} = {value_text} "), message
    for allowed in _allowed(p):
        assert allowed in message, message
    assert f"({split_label(p.label)[0]})" in message, message
    assert not RAW_LIBRARY_TEXT.search(message), message
    section_class = type(getattr(Scenario(), path.partition(".")[0])).__name__
    assert f"{section_class}." not in message, message


@pytest.mark.parametrize(("path", "bad"), CASES)
def test_an_assigned_bad_value_is_refused_in_the_project_s_voice(path, bad):
    scenario = Scenario()
    section, _, name = path.partition(".")
    with pytest.raises(ValueError) as info:
        setattr(getattr(scenario, section), name, bad)
    _check_voice(str(info.value), path, _value_text(PARAMETERS[path], bad))


@pytest.mark.parametrize(("path", "bad"), CASES)
def test_a_bad_value_in_a_scenario_file_is_refused_in_the_same_voice(path, bad):
    """JSON has no NaN or lists-as-numbers problem of its own: the dict is what json.loads gives."""
    section, _, name = path.partition(".")
    with pytest.raises(ValueError) as info:
        Scenario.from_dict({section: {name: bad}})
    _check_voice(str(info.value), path, _value_text(PARAMETERS[path], bad))


def _bad_texts(p: param.Parameter) -> list[str]:
    """Bad command-line texts (``--set path=text``) for ``p``'s type."""
    if isinstance(p, Quantity | Count):
        texts = [number_text(_out_of_range(p)), "abc", "1_0", "nan", ""]
        return texts + (["2.5"] if isinstance(p, Count) else [])
    if isinstance(p, Choice):
        return ["not-an-option", "3"]
    if isinstance(p, Switch):
        return ["maybe", "2"]
    return []  # any text is a text


TEXT_CASES = [
    pytest.param(path, text, id=f"{path}={text}")
    for path, p in PARAMETERS.items()
    for text in _bad_texts(p)
]


@pytest.mark.parametrize(("path", "text"), TEXT_CASES)
def test_bad_command_line_text_is_refused_showing_what_was_typed(path, text):
    p = PARAMETERS[path]
    with pytest.raises(ValueError) as info:
        Scenario().set_value(path, text)
    _check_voice(str(info.value), path, _typed_value_text(p, text))


def _typed_value_text(p: param.Parameter, text: str) -> str:
    """How a refusal shows typed text: a number that parses is refused for its range (shown
    as a number with its unit); any other text is quoted as typed."""
    if isinstance(p, Quantity | Count) and "_" not in text:
        try:
            return _value_text(p, int(text) if isinstance(p, Count) else float(text))
        except ValueError:
            pass
    return repr(text)


def test_every_section_s_class_name_is_its_path_in_lower_case():
    """parameter_path names a section by its class in lower case: that must be the scenario's
    attribute, or the messages would name a path that does not exist."""
    scenario = Scenario()
    for section in SECTIONS:
        assert type(getattr(scenario, section)).__name__.lower() == section


@pytest.mark.parametrize(
    ("path", "value", "message"),
    [
        ("train.speed_kmh", -5.0, "train.speed_kmh = -5 km/h is outside the allowed range "
         "[1, 400] km/h (Speed)"),
        ("soil.youngs_modulus", 0, "soil.youngs_modulus = 0 Pa is outside the allowed range "
         "[1e+06, 1e+11] Pa (Soil Young's modulus)"),
        ("train.speed_kmh", "fast", "train.speed_kmh = 'fast' is not a number; the allowed "
         "range is [1, 400] km/h (Speed)"),
        ("tunnel.model", "3d", "tunnel.model = '3d' is not one of the options '2d', '2.5d' "
         "(Tunnel–soil model)"),
        ("train.n_cars", 2.5, "train.n_cars = 2.5 is not a whole number; the allowed range is "
         "[1, 12] (Number of cars)"),
        ("train.single_bogie", "yes", "train.single_bogie = 'yes' is not true or false "
         "(Single bogie only)"),
    ],
)  # fmt: skip
def test_the_issue_s_examples_read_as_one_voice(path, value, message):
    section, _, name = path.partition(".")
    with pytest.raises(ValueError) as info:
        setattr(getattr(Scenario(), section), name, value)
    assert str(info.value) == message
