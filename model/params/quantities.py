"""Parameter types, the messages that refuse a bad value, and the package data files.

Every input of a scenario is one of the project's parameter types: :class:`Quantity` (a real
physical quantity), :class:`Count` (a whole number), :class:`CountOrOff` (a count, or 0 to switch
a refinement off), :class:`Choice` (one of a list of options), :class:`Switch` (true or false)
and :class:`Text`. Each refuses a bad value in one voice (:func:`refusal`): the dotted lower-case
path of the input, the value with its unit, what is wrong and what is allowed, e.g.
``train.speed_kmh = -5 km/h is outside the allowed range [1, 400] km/h (Speed)``; NaN, infinity
and booleans are never numbers. :class:`ScenarioError` is raised for values that are valid one
by one but inconsistent with each other (:meth:`model.params.Scenario.validate`).
"""

from __future__ import annotations

import json
import math
from importlib.resources import files
from pathlib import Path
from typing import Any

import param
from numpy import bool_ as numpy_bool
from numpy import floating as numpy_floating
from numpy import integer as numpy_integer

GRAVITY = 9.81  # m/s², standard value used for static loads
# Package data (presets, the paper's reported numbers, an example measured profile), shipped
# inside the package so that a plain `pip install` finds it from any working directory.
DATA_DIR = Path(str(files("model") / "data"))
PRESETS_FILE = DATA_DIR / "presets.json"


def _load_presets() -> dict[str, dict[str, Any]]:
    """The presets of ``model/data/presets.json``, by name."""
    with PRESETS_FILE.open(encoding="utf-8") as handle:
        return json.load(handle)["presets"]


class ScenarioError(ValueError):
    """Raised when parameter values are individually valid but inconsistent with each other."""


# ---- the project's voice ------------------------------------------------------------------
def split_label(label: str) -> tuple[str, str]:
    """("Soil Young's modulus", "Pa") from "Soil Young's modulus (Pa)"; no unit gives ""."""
    bare, sep, unit = label.rstrip().rpartition(" (")
    return (bare, unit[:-1]) if sep and unit.endswith(")") else (label, "")


def parameter_path(parameter: param.Parameter) -> str:
    """Dotted lower-case path of a section's parameter, e.g. ``"train.speed_kmh"``.

    The section is the owning class's name in lower case (``LongTerm`` → ``longterm``), which is
    the scenario's attribute for it (tests/test_params.py checks every section).
    """
    owner = parameter.owner
    if owner is None:
        return parameter.name or "value"
    cls = owner if isinstance(owner, type) else type(owner)
    return f"{cls.__name__.lower()}.{parameter.name}"


def number_text(value: float) -> str:
    """A number as a person writes it: 60 for 60.0, 0.668, 5e-324, nan."""
    if isinstance(value, int | numpy_integer):
        return str(int(value))
    value = float(value)
    if math.isfinite(value) and value.is_integer() and abs(value) < 1e15:
        return str(int(value))
    return repr(value)


_REAL_TYPES = (int, float, numpy_integer, numpy_floating)


def _bound_text(bound, integer: bool) -> str:
    """One end of a range: :g for reals (1e+06), exact for whole numbers (4294967295)."""
    return f"{int(bound)}" if integer else f"{bound:g}"


def _format_range(bounds, inclusive, integer: bool = False) -> str:
    """Interval text of bounds, e.g. "[1, 400]", "(0, inf)"."""
    low, high = bounds
    left = "[" if inclusive[0] and low is not None else "("
    right = "]" if inclusive[1] and high is not None else ")"
    low_s = "-inf" if low is None else _bound_text(low, integer)
    high_s = "inf" if high is None else _bound_text(high, integer)
    return f"{left}{low_s}, {high_s}{right}"


def _with_unit(text: str, unit: str) -> str:
    """``text`` followed by the unit, unless there is none ("" or "-")."""
    return f"{text} {unit}" if unit and unit != "-" else text


def refusal(path: str, value_text: str, problem: str, label: str) -> str:
    """The one sentence that refuses an input, e.g.
    ``train.speed_kmh = -5 km/h is outside the allowed range [1, 400] km/h (Speed)``.

    Parameters
    ----------
    path : str
        Dotted lower-case path of the input.
    value_text : str
        The value as the user gave it, with its unit where it is a number.
    problem : str
        What is wrong and what is allowed, e.g. "is not a number; the allowed range is …".
    label : str
        The input's label without its unit.
    """
    return f"{path} = {value_text} {problem} ({label})"


class _ProjectVoice:
    """Mixin: a refused value raises ValueError(:func:`refusal`), never param's own text.

    Subclasses say what is wrong with a value (``_problem``, None if nothing) and what is
    allowed (``allowed_text``); param's checks stay behind them as a safety net.
    """

    def _validate(self, val):
        problem = None if callable(val) else self._problem(val)
        if problem is None:
            try:
                super()._validate(val)
                return
            except ValueError:
                problem = f"is not allowed; allowed: {self.allowed_text()}"
        raise ValueError(self.refusal_text(val, problem)) from None

    def _problem(self, val) -> str | None:
        """What is wrong with ``val`` (a phrase starting with a verb), or None."""
        raise NotImplementedError

    def allowed_text(self) -> str:
        """The allowed values, as a refusal states them (e.g. "[1, 400] km/h or None")."""
        raise NotImplementedError

    def unit(self) -> str:
        """Unit of the label ("" when there is none)."""
        return split_label(self.label or "")[1]

    def value_text(self, val) -> str:
        """``val`` as the refusal shows it: numbers with their unit, anything else by repr."""
        if isinstance(val, _REAL_TYPES) and not isinstance(val, bool | numpy_bool):
            text = number_text(val)
            return _with_unit(text, self.unit()) if math.isfinite(val) else text
        text = repr(val)
        return text if len(text) <= 60 else f"{text[:57]}..."

    def refusal_text(self, val, problem: str) -> str:
        """The refusal of ``val`` (given as typed: pass a string to show it quoted)."""
        label = split_label(self.label or "")[0] or self.name
        return refusal(parameter_path(self), self.value_text(val), problem, label)


class _NumberVoice(_ProjectVoice):
    """Mixin of the numeric types: refuse booleans, non-numbers, NaN, ±inf and out-of-bounds
    values, stating the range in the label's unit."""

    whole_numbers = False

    def _range_text(self) -> str:
        """The bounds as an interval in the label's unit."""
        bounds = self.bounds or (None, None)
        interval = _format_range(bounds, self.inclusive_bounds, self.whole_numbers)
        return _with_unit(interval, self.unit())

    def allowed_text(self) -> str:
        return self._range_text() + (" or None" if self.allow_None else "")

    def _kind_problem(self, val) -> str | None:
        """What makes ``val`` no number of this kind, or None."""
        kind = "a whole number" if self.whole_numbers else "a number"
        if isinstance(val, bool | numpy_bool):
            return f"is a boolean, not {kind}"
        allowed = (int, numpy_integer) if self.whole_numbers else _REAL_TYPES
        if not isinstance(val, allowed):
            return f"is not {kind}"
        if not math.isfinite(val):
            return "is not a finite number"
        return None

    def _problem(self, val) -> str | None:
        if val is None and self.allow_None:
            return None
        kind = self._kind_problem(val)
        if kind is not None:
            return f"{kind}; the allowed range is {self.allowed_text()}"
        if not self._within_bounds(val):
            return f"is outside the allowed range {self.allowed_text()}"
        return None

    def _within_bounds(self, val) -> bool:
        """``val`` lies within the bounds (inclusive where declared so)."""
        low, high = self.bounds or (None, None)
        low_in, high_in = self.inclusive_bounds
        above = low is None or (val >= low if low_in else val > low)
        below = high is None or (val <= high if high_in else val < high)
        return above and below


class Quantity(_NumberVoice, param.Number):
    """A real physical quantity with bounds; NaN, ±inf and booleans are always refused."""


class Count(_NumberVoice, param.Integer):
    """A whole number with bounds; booleans and reals (even 2.0) are refused."""

    whole_numbers = True


class CountOrOff(Count):
    """A count within its bounds, or 0, which switches off what the count refines."""

    def _within_bounds(self, val) -> bool:
        """0 always passes; any other value is checked against the bounds."""
        return val == 0 or super()._within_bounds(val)

    def _validate_bounds(self, val, bounds, inclusive_bounds):
        """0 passes param's own check too."""
        if val != 0:
            super()._validate_bounds(val, bounds, inclusive_bounds)

    def allowed_text(self) -> str:
        return f"{self._range_text()} or 0"


class Choice(_ProjectVoice, param.Selector):
    """One of a list of options (strings)."""

    def allowed_text(self) -> str:
        return ", ".join(repr(option) for option in self.objects)

    def _problem(self, val) -> str | None:
        if val in self.objects or (val is None and self.allow_None):
            return None
        return f"is not one of the options {self.allowed_text()}"


class Switch(_ProjectVoice, param.Boolean):
    """True or false."""

    def allowed_text(self) -> str:
        return "true or false" + (" or None" if self.allow_None else "")

    def _problem(self, val) -> str | None:
        if isinstance(val, bool) or (val is None and self.allow_None):
            return None
        return f"is not {self.allowed_text()}"


class Text(_ProjectVoice, param.String):
    """A text, e.g. a file path; None where allowed."""

    def allowed_text(self) -> str:
        return "text" + (" or None" if self.allow_None else "")

    def _problem(self, val) -> str | None:
        if isinstance(val, str) or (val is None and self.allow_None):
            return None
        return f"is not text; allowed: {self.allowed_text()}"


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
