"""Numbers as a person types them into the dashboard: a decimal point or a decimal comma, an
optional exponent, and an optional unit of the parameter's kind (``6000 kPa`` in a box shown in
MPa is 6 MPa).

Refused: digit separators (``1_00``, ``1,000.5``, ``6 000``: docs/validity.md, as ``--set``
does), text that is not a number, and a unit of another kind; the message says which units the
box takes. Panel-free; :mod:`dashboard.controls` shows the messages.
"""

from __future__ import annotations

import math
import re

_NUMBER = re.compile(r"[+-]?(?:\d+(?:[.,]\d*)?|[.,]\d+)(?:[eE][+-]?\d+)?")
# a number, then a unit that starts with a letter or a sign like ° (not a digit: "6 000" and
# "1_00" are numbers with digit separators, not units)
_VALUE_AND_UNIT = re.compile(
    r"^\s*(?P<number>[+-]?[\d.,_]*\d[\d.,_]*(?:[eE][+-]?\d+)?)"
    r"(?:\s*(?P<unit>[^\d\s_.,+-].*?))?\s*$"
)

UNIT_KINDS: dict[str, dict[str, float]] = {
    "pressure": {"Pa": 1.0, "kPa": 1e3, "MPa": 1e6, "GPa": 1e9},
    "stiffness": {"N/m": 1.0, "kN/m": 1e3, "MN/m": 1e6, "GN/m": 1e9},
    "damping": {"N·s/m": 1.0, "kN·s/m": 1e3, "MN·s/m": 1e6},
    "force": {"N": 1.0, "kN": 1e3, "MN": 1e6},
    "mass": {"kg": 1.0, "t": 1e3},
    "rotational inertia": {"kg·m²": 1.0, "t·m²": 1e3},
    "second moment of area": {"m⁴": 1.0, "cm⁴": 1e-8, "mm⁴": 1e-12},
    "length": {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "km": 1e3},
    "time": {"s": 1.0, "ms": 1e-3},
    "speed": {"km/h": 1.0, "m/s": 3.6},
    "frequency": {"Hz": 1.0, "kHz": 1e3},
}
"""Units of one kind each (name → unit → its size in the kind's first unit)."""

SEPARATORS = "digits with one decimal point or comma, no digit separators"


def _key(unit: str) -> str:
    """A unit as typed or declared, compared without case, spaces, product dots or carets
    (``kN.s/m``, ``kNs/m`` and ``kN·s/m`` are the same; ``cm4`` is ``cm⁴``)."""
    plain = unit.translate(str.maketrans("⁴²³", "423", " ·.*^"))
    return plain.lower()


def _kind_of(unit: str) -> str | None:
    """The name of the unit kind holding ``unit`` (None: no other unit converts to it)."""
    return next((name for name, kind in UNIT_KINDS.items() if _key(unit) in map(_key, kind)), None)


def _number(text: str) -> float:
    """A number with a decimal point or a decimal comma; ValueError for anything else."""
    if not _NUMBER.fullmatch(text) or ("," in text and "." in text):
        raise ValueError(text)
    return float(text.replace(",", "."))


def parse_typed(text: str, unit: str) -> float:
    """The value of ``text`` in ``unit``, the unit its box is shown in.

    Parameters
    ----------
    text : str
        As typed: ``"6"``, ``"6,5"``, ``"6.5e3"``, ``"6 MPa"``, ``"6000 kPa"``.
    unit : str
        The box's unit (``"MPa"``; ``""`` or ``"-"`` for a number without unit).

    Returns
    -------
    float
        The value in ``unit``.

    Raises
    ------
    ValueError
        Not a number, a digit separator, or a unit that does not convert to ``unit``; the
        message is the reason alone (the caller names the parameter and the value).
    """
    found = _VALUE_AND_UNIT.match(text)
    if not found:
        detail = f" ({SEPARATORS})" if any(c.isdigit() for c in text) else ""
        raise ValueError(f"is not a number{_in(unit)}{detail}")
    try:
        number = _number(found["number"])
    except ValueError:
        raise ValueError(f"is not a number{_in(unit)} ({SEPARATORS})") from None
    if not math.isfinite(number):
        raise ValueError(f"is not a finite number{_in(unit)}")
    typed_unit = found["unit"] or ""
    if not typed_unit or _key(typed_unit) == _key(unit):
        return number
    kind = _kind_of(unit)
    if kind is None:
        if not unit or unit == "-":
            raise ValueError(f"has a unit ({typed_unit}); this number has none: type it alone")
        raise ValueError(f"has the unit {typed_unit}: type it in {unit}")
    sizes = {_key(name): size for name, size in UNIT_KINDS[kind].items()}
    if _key(typed_unit) not in sizes:
        accepted = ", ".join(UNIT_KINDS[kind])
        raise ValueError(f"has the unit {typed_unit}, not a unit of {kind}: type it in {accepted}")
    return number * sizes[_key(typed_unit)] / sizes[_key(unit)]


def _in(unit: str) -> str:
    """' in MPa' for a box with a unit, '' for a plain number."""
    return f" in {unit}" if unit and unit != "-" else ""
