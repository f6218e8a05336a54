"""Parameter types, the messages that refuse a bad value, and the package data files.

:class:`Quantity` (a real physical quantity), :class:`Count` (a whole number) and
:class:`CountOrOff` (a count, or 0 to switch a refinement off) refuse NaN, infinity and booleans
and name the parameter, the value, the allowed range and the unit when a value is out of bounds.
:class:`ScenarioError` is raised for values that are valid one by one but inconsistent with each
other (:meth:`model.params.Scenario.validate`).
"""

from __future__ import annotations

import json
import math
from importlib.resources import files
from pathlib import Path
from typing import Any

import param
from numpy import bool_ as numpy_bool

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


def _format_range(bounds, inclusive) -> str:
    low, high = bounds
    left = "[" if inclusive[0] else "("
    right = "]" if inclusive[1] else ")"
    low_s = "-inf" if low is None else f"{low:g}"
    high_s = "inf" if high is None else f"{high:g}"
    right = ")" if high is None else right
    return f"{left}{low_s}, {high_s}{right}"


class _RangeMessage:
    """Mixin: a bounds violation names the parameter, the value, the allowed range and the unit."""

    def _validate_bounds(self, val, bounds, inclusive_bounds):
        try:
            if val is not None and not math.isfinite(val):
                raise ValueError("not finite")
            super()._validate_bounds(val, bounds, inclusive_bounds)
        except ValueError:
            owner = self.owner if isinstance(self.owner, type) else type(self.owner)
            where = f"{owner.__name__}.{self.name}" if self.owner is not None else self.name
            raise ValueError(
                f"{where} = {val!r} is outside the allowed range "
                f"{self._allowed_text(bounds, inclusive_bounds)} ({self.label})"
            ) from None

    def _allowed_text(self, bounds, inclusive_bounds) -> str:
        """The allowed values, as the refusal message states them."""
        return _format_range(bounds, inclusive_bounds)


class _NotBoolean:
    """Mixin: refuse True/False where a number is expected (bool is an int subclass)."""

    def _validate_value(self, val, allow_None):
        if isinstance(val, bool | numpy_bool):
            owner = self.owner if isinstance(self.owner, type) else type(self.owner)
            where = f"{owner.__name__}.{self.name}" if self.owner is not None else self.name
            raise ValueError(f"{where} = {val!r} is a boolean, not a number ({self.label})")
        super()._validate_value(val, allow_None)


class Quantity(_NotBoolean, _RangeMessage, param.Number):
    """A real physical quantity with bounds; NaN, ±inf and booleans are always refused."""


class Count(_NotBoolean, _RangeMessage, param.Integer):
    """An integer quantity with bounds; booleans are refused."""


class CountOrOff(Count):
    """A count within its bounds, or 0, which switches off what the count refines."""

    def _validate_bounds(self, val, bounds, inclusive_bounds):
        """0 always passes; any other value is checked against the bounds."""
        if val != 0:
            super()._validate_bounds(val, bounds, inclusive_bounds)

    def _allowed_text(self, bounds, inclusive_bounds) -> str:
        """The bounds, and 0."""
        return f"{_format_range(bounds, inclusive_bounds)} or 0"


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
