"""A borehole log as a CSV file: one row a layer, top down, read into :class:`Layer` objects.

The header names each column by a layer property (``Layer`` parameter name) and its unit, after
an underscore, a space or in brackets: ``thickness_m``, ``unit_weight (kN/m³)``,
``compressibility [1/MPa]``, ``friction_angle_deg``; a property without a unit (``cu_ratio``,
``soil_class``, ``name``) is named alone. Each property takes the SI unit of its label or the
unit the interface shows it in (``model.params.display``). ``name``, ``thickness`` and
``unit_weight`` are required; an empty cell, or a missing column, takes the layer default, and
``none`` clears an optional property (e.g. ``compressibility``: then m_v comes from C_r, e0).
Lines starting with ``#`` are comments. Every refusal names the line and the column.
"""

from __future__ import annotations

import csv
import io
from pathlib import Path

from model.params.display import LAYER_PATH, display_unit
from model.params.quantities import _format_range, split_label
from model.params.site import LAYER_PROPERTIES, Layer, layers_from_records

REQUIRED = ("name", "thickness", "unit_weight")
COMMENT = "#"
UNIT_SPELLINGS = {"²": "2", "³": "3", "⁻¹": "-1", "·": "", " ": "", "degrees": "°", "deg": "°"}


def _normal(unit: str) -> str:
    """A unit spelled one way: kN/m³ = kn/m3, 1/MPa = 1/mpa, ° = deg (no layer property has
    two units that differ only in case)."""
    text = unit.strip().lower()
    for spelling, plain in UNIT_SPELLINGS.items():
        text = text.replace(spelling, plain)
    return text


def units_of(name: str) -> dict[str, float]:
    """Units a layer property may be given in → factor that turns a value in it into SI."""
    parameter = Layer.param[name]
    si_unit = split_label(parameter.label or name)[1]
    units = {_normal(si_unit): 1.0}
    shown, factor = display_unit(LAYER_PATH + name)
    units[_normal(shown)] = 1.0 / factor
    if si_unit in ("", "-"):
        units.update({"": 1.0, "-": 1.0})
    return units


def _column(text: str, position: int, line: int, source: str) -> tuple[str, float, str]:
    """(property, factor to SI, unit as written) of a header cell."""
    cell = text.strip().replace("[", "(").replace("]", ")")
    candidates = []
    if cell.endswith(")") and "(" in cell:
        name, _, unit = cell[:-1].rpartition("(")
        candidates.append((name.strip(), unit))
    for separator in (" ", "_"):
        head, _, tail = cell.partition(separator)
        while tail:  # every split point: "unit_weight_kN/m3" → ("unit_weight", "kN/m3")
            candidates.append((head, tail))
            more, _, tail = tail.partition(separator)
            head = f"{head}{separator}{more}"
    candidates.append((cell, ""))
    for name, unit in candidates:
        key = name.strip().lower()
        if key in LAYER_PROPERTIES and _normal(unit) in units_of(key):
            return key, units_of(key)[_normal(unit)], unit.strip()
    for name, unit in sorted(candidates, key=lambda c: -len(c[0])):
        key = name.strip().lower()
        if key in LAYER_PROPERTIES:
            allowed = " or ".join(repr(u) for u in units_of(key) if u not in ("", "-")) or "none"
            raise ValueError(
                f"{source}: line {line}, column {position} ({text!r}): "
                f"{'no unit' if not unit else f'unit {unit!r}'} for the layer's {key}; "
                f"give it in {allowed}"
            )
    raise ValueError(
        f"{source}: line {line}, column {position}: {text!r} names no layer property; known: "
        f"{', '.join(LAYER_PROPERTIES)} (each with its unit, e.g. thickness_m)"
    )


def csv_lines(text: str, source: str) -> list[tuple[int, list[str]]]:
    """(line number, fields) of every line of CSV text that is neither blank nor a comment.

    Parameters
    ----------
    text : str
        Contents of the file; a UTF-8 byte-order mark is dropped.
    source : str
        Name used in error messages (e.g. the uploaded file's name).

    Raises
    ------
    ValueError
        Binary content (NUL characters) or a line Python's CSV reader cannot read (a field
        longer than its limit, a stray carriage return), naming the line.
    """
    if "\x00" in text:
        raise ValueError(f"{source}: not a CSV text file (it holds NUL characters: binary data)")
    reader = csv.reader(io.StringIO(text.removeprefix("\ufeff")))
    lines = []
    try:
        for fields in reader:
            if fields and "".join(fields).strip() and not fields[0].lstrip().startswith(COMMENT):
                lines.append((reader.line_num, fields))
    except csv.Error as error:
        reason = str(error).split(" - ")[0]  # drop the reader's hint about file modes
        raise ValueError(
            f"{source}: line {reader.line_num} cannot be read as CSV ({reason}); save the data "
            "as a plain-text CSV file"
        ) from None
    return lines


def parse_borehole_csv(text: str, source: str = "borehole") -> list[Layer]:
    """Layers from the text of a borehole CSV (format in the module docstring).

    Parameters
    ----------
    text : str
        Contents of the file.
    source : str
        Name used in error messages (e.g. the uploaded file's name).

    Returns
    -------
    list of Layer
        Top down.

    Raises
    ------
    ValueError
        Binary content or a line the CSV reader cannot read (:func:`csv_lines`); no header, an
        unknown column or unit, a required column missing, no layer, a cell that is not a
        number, or a value outside its bounds; each naming the line and the column.
    """
    lines = csv_lines(text, source)
    if not lines:
        raise ValueError(f"{source}: no header and no layer")
    header_line, header = lines[0]
    columns = [_column(cell, i, header_line, source) for i, cell in enumerate(header, start=1)]
    names = [name for name, _, _ in columns]
    missing = [name for name in REQUIRED if name not in names]
    if missing:
        raise ValueError(
            f"{source}: the header on line {header_line} has no column {', '.join(missing)} "
            f"(required: {', '.join(REQUIRED)}, with units, e.g. thickness_m, unit_weight_kN/m³)"
        )
    repeated = sorted({name for name in names if names.count(name) > 1})
    if repeated:
        raise ValueError(f"{source}: line {header_line}: {', '.join(repeated)} given twice")
    if len(lines) == 1:
        raise ValueError(f"{source}: no layer below the header on line {header_line}")
    layers = []
    for line, fields in lines[1:]:
        record = _record(fields, columns, header, line, source)
        try:
            layers += layers_from_records([record])
        except (ValueError, KeyError) as error:
            raise ValueError(f"{source}: line {line}: {error}") from None
    return layers


def _record(fields, columns, header, line: int, source: str) -> dict:
    """The layer properties of one data row, in SI units."""
    if len(fields) != len(columns):
        raise ValueError(
            f"{source}: line {line}: {len(fields)} values, expected {len(columns)} "
            f"({', '.join(header)})"
        )
    record = {}
    layer = dict(zip([name for name, _, _ in columns], fields, strict=True))["name"].strip()
    for field, (name, factor, unit), label in zip(fields, columns, header, strict=True):
        value = field.strip()
        where = f"{source}: line {line} (layer {layer!r}), column {label.strip()!r}"
        if not value:
            continue  # the layer default
        parameter = Layer.param[name]
        if name == "soil_class" and value not in parameter.objects:
            raise ValueError(f"{where}: {value!r} is not one of {', '.join(parameter.objects)}")
        if name in ("name", "soil_class"):
            record[name] = value
        elif value.lower() == "none" and parameter.allow_None:
            record[name] = None
        else:
            try:
                number = float(value)
            except ValueError:
                raise ValueError(f"{where}: {value!r} is not a number") from None
            _check_bounds(parameter, number, factor, unit, where)
            record[name] = float(f"{number * factor:.12g}")  # no binary noise of the unit
    return record


def _check_bounds(parameter, value: float, factor: float, unit: str, where: str) -> None:
    """ValueError, in the column's unit, for a value outside the parameter's bounds."""
    low, high = parameter.bounds or (None, None)
    low_in, high_in = parameter.inclusive_bounds
    si = value * factor
    below = low is not None and (si < low or (si == low and not low_in))
    above = high is not None and (si > high or (si == high and not high_in))
    if below or above or si != si:
        shown = tuple(None if b is None else float(f"{b / factor:.12g}") for b in (low, high))
        bare = split_label(parameter.label or "")[0]
        raise ValueError(
            f"{where}: {value:g} is outside the allowed range "
            f"{_format_range(shown, parameter.inclusive_bounds)}{' ' + unit if unit else ''} "
            f"({bare})"
        )


def load_borehole_csv(path) -> list[Layer]:
    """Layers from a borehole CSV file (:func:`parse_borehole_csv`), named in errors."""
    path = Path(path)
    return parse_borehole_csv(path.read_text(encoding="utf-8"), path.name)


def borehole_csv(layers: list[Layer]) -> str:
    """The text of a borehole CSV of ``layers``, every property in its display unit (the file
    :func:`parse_borehole_csv` reads back to the same layers, to 12 significant digits)."""
    header, factors = [], []
    for name in LAYER_PROPERTIES:
        unit, factor = display_unit(LAYER_PATH + name)
        header.append(f"{name}_{unit}" if unit and unit != "-" else name)
        factors.append(factor)
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(header)
    for layer in layers:
        row = []
        for name, factor in zip(LAYER_PROPERTIES, factors, strict=True):
            value = getattr(layer, name)
            if value is None:
                row.append("none")
            elif isinstance(value, str):
                row.append(value)
            else:
                row.append(f"{value * factor:.12g}")
        writer.writerow(row)
    return buffer.getvalue()
