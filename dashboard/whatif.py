"""What-if sessions: pin runs, compare them side by side, save and load the session.

Panel-free core of the dashboard's what-if tools (the widgets are in ``whatif_view.py``). A
:class:`WhatIfSession` keeps up to :data:`MAX_PINNED` pinned runs, each with its own inputs and
the :class:`~model.pipeline.Results` it had when pinned: pinning never recomputes, and a pinned
run keeps its results whatever the current scenario does later. Each session has its own.

The session file is one JSON object: a format tag, a version, the inputs (never the results) of
every pinned run with its name, visibility and colour, the reference run and, optionally, the
current scenario. Loading it recomputes the results through an injected ``compute`` function,
so the dashboard's stage cache serves what it still holds.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from importlib.resources import files
from pathlib import Path
from typing import Any

import pandas as pd

from dashboard.parsed import summary_of
from model.params import SECTIONS, Scenario
from model.params.measured_profile import admit_profile, data_folder, parse_profile
from model.pipeline import Results, StageCache, run

MAX_PINNED = 8
"""Pinned runs per session: enough for a what-if study, few enough for legible plots."""

CURRENT_LABEL = "Current run"
"""Name of the current (unpinned) run in legends and the comparison table; not a pin name."""

CURRENT_COLOUR = "#000000"
"""The current run is drawn in black, on top of the pinned runs."""

PINNED_COLOURS = (
    "#E69F00",  # orange
    "#56B4E9",  # sky blue
    "#009E73",  # bluish green
    "#0072B2",  # blue
    "#D55E00",  # vermillion
    "#CC79A7",  # reddish purple
    "#999999",  # grey
    "#F0E442",  # yellow: the least legible on white, so the last one used
)
"""Okabe–Ito colour-blind-safe palette (Okabe & Ito 2008, with its grey) without the black of
the current run: one colour per pinned run, in pin order."""

SESSION_FORMAT = "tunnelsettle-whatif-session"
SESSION_VERSION = 1
SAMPLE_SESSION_FILE = Path(str(files("dashboard") / "data" / "sample_session.json"))
"""A session to start from, shipped with the package: the paper case, a stiffer soil and the
2.5D model (``python -m dashboard.export --session sample``, or load it in the dashboard)."""

MAX_NAME_CHANGES = 3  # differences listed in a default name before "+ n more"

Compute = Callable[[Scenario], Results]


# ---- describing inputs ------------------------------------------------------------------------
_PREFIXED_UNITS = ("Pa", "N/m", "N·s/m", "N", "N·m²")
_PREFIXES = ((1e9, "G"), (1e6, "M"), (1e3, "k"))
_LABEL_UNIT = re.compile(r"^(?P<name>.*?)\s*\((?P<unit>[^()]*)\)$")


def _split_label(label: str) -> tuple[str, str]:
    """("Fastener stiffness", "N/m") from "Fastener stiffness (N/m)"; "-" or none gives ""."""
    found = _LABEL_UNIT.match(label)
    if not found:
        return label, ""
    unit = found["unit"]
    return found["name"], "" if unit == "-" else unit


def _display_unit(unit: str, value: float) -> tuple[str, float]:
    """Engineering unit for a force/stress-like SI value (e.g. 4e7 N/m → MN/m) and its factor."""
    if unit in _PREFIXED_UNITS:
        for size, prefix in _PREFIXES:
            if abs(value) >= size:
                return prefix + unit, 1.0 / size
    return unit, 1.0


def _lower_first(text: str) -> str:
    """Lower-case the first letter unless the first word is an acronym ("FRA")."""
    if len(text) > 1 and text[0].isupper() and text[1].islower():
        return text[0].lower() + text[1:]
    return text


def describe_change(path: str, value: Any) -> str:
    """Short human description of one input value, e.g. ``"fastener stiffness 40 MN/m"``.

    The only place where inputs are formatted for names and the comparison table: the
    parameter's label without its unit, then the value in an engineering unit (SI prefixes
    for forces, stiffnesses and moduli; every other value in the unit of its label).

    Parameters
    ----------
    path : str
        Dotted parameter path, ``"section.parameter"`` (e.g. ``"train.speed_kmh"``).
    value : bool, int, float, str, None or list
        The parameter's value in the model's units (SI, km/h for the speed); the site's layers
        as a list of records, named by their layers' names.

    Returns
    -------
    str
    """
    section, _, name = path.partition(".")
    if section not in SECTIONS or name not in Scenario.param[section].class_.param:
        raise KeyError(f"unknown parameter {path!r}")
    label, unit = _split_label(Scenario.param[section].class_.param[name].label or name)
    label = _lower_first(label)
    if value is None:
        return f"{label} automatic"
    if isinstance(value, bool):
        return f"{label}: {'yes' if value else 'no'}"
    if path == "irregularity.profile_data":  # the text itself: too long for a name
        profile = parse_profile(value)
        return f"measured profile ({profile.n_points} points, {profile.digest[:8]})"
    if isinstance(value, list):  # the site's layers, as records
        return f"{label} {', '.join(str(layer.get('name', '?')) for layer in value)}"
    if isinstance(value, int | float):
        unit, factor = _display_unit(unit, value)
        space = "" if unit in ("", "°", "%") else " "
        return f"{label} {value * factor:.4g}{space}{unit}"
    return f"{label} {value}"


def flat_inputs(scenario: Scenario | Mapping[str, Mapping[str, Any]]) -> dict[str, Any]:
    """Every input of a scenario by dotted path, ``{"train.speed_kmh": 80.0, ...}``."""
    data = scenario.to_dict() if isinstance(scenario, Scenario) else scenario
    return {f"{section}.{name}": value for section in data for name, value in data[section].items()}


def changed_paths(scenarios: Sequence[Mapping[str, Any]]) -> list[str]:
    """Dotted paths whose values are not all equal across flat input dicts, in input order."""
    if not scenarios:
        return []
    return [path for path in scenarios[0] if any(s[path] != scenarios[0][path] for s in scenarios)]


def default_name(scenario: Scenario, baseline: Scenario, baseline_name: str = "preset") -> str:
    """Name of a run from what differs from ``baseline``, e.g. ``"speed 60 km/h"``.

    At most :data:`MAX_NAME_CHANGES` differences are listed, then ``"+ n more"``; a scenario
    equal to the baseline is named ``baseline_name``.
    """
    inputs, base = flat_inputs(scenario), flat_inputs(baseline)
    changes = [describe_change(p, v) for p, v in inputs.items() if v != base[p]]
    if not changes:
        return baseline_name
    shown = ", ".join(changes[:MAX_NAME_CHANGES])
    extra = len(changes) - MAX_NAME_CHANGES
    return f"{shown} + {extra} more" if extra > 0 else shown


# ---- the comparison table ---------------------------------------------------------------------
@dataclass(frozen=True)
class ComparedQuantity:
    """One key number of the comparison: a :meth:`Results.summary` key shown in a display unit."""

    summary_key: str
    label: str
    unit: str
    scale: float
    """Display value = scale × SI value."""

    @property
    def column(self) -> str:
        """Column heading: label and unit."""
        return f"{self.label} ({self.unit})"


COMPARED = (
    ComparedQuantity("peak_invert_force_N", "Peak invert load", "kN", 1e-3),
    ComparedQuantity("peak_block_disp_m", "Peak sleeper displacement", "mm", 1e3),
    ComparedQuantity("peak_disp_invert_m", "Peak displacement at the invert", "mm", 1e3),
    ComparedQuantity("peak_disp_11m_m", "Peak displacement 11 m below", "mm", 1e3),
    ComparedQuantity("peak_disp_deepest_m", "Peak displacement at the deepest depth", "mm", 1e3),
    ComparedQuantity("longterm_settlement_m", "Long-term settlement", "mm", 1e3),
    ComparedQuantity("longterm_plastic_settlement_m", "… plastic part", "mm", 1e3),
    ComparedQuantity("longterm_consolidation_settlement_m", "… consolidation part", "mm", 1e3),
    ComparedQuantity("longterm_stress_ratio_max", "Largest q_d/σ_s below the invert", "-", 1.0),
)
"""Key numbers compared, in column order; a quantity absent from every summary is left out
(the long-term settlement exists only once the pipeline computes it). A largest q_d/σ_s at or
above 1 puts the settlement outside the strain laws' range (``Results.summary``)."""

DIFFERENCE = "Δ"
PERCENT = "Δ %"
VALUE = "value"
INPUTS_COLUMN = ("Inputs that differ", "")


@dataclass(frozen=True)
class ComparedRun:
    """One row of the comparison: a run's name, its summary (SI) and its flat inputs."""

    name: str
    summary: Mapping[str, float]
    inputs: Mapping[str, Any]


def comparison_table(runs: Sequence[ComparedRun], reference: str) -> pd.DataFrame:
    """Key numbers of every run, their difference to the reference run and the inputs that differ.

    Parameters
    ----------
    runs : sequence of ComparedRun
        Rows in display order; names must be unique.
    reference : str
        Name of the run the differences are taken to.

    Returns
    -------
    pandas.DataFrame
        Index: run names. Columns (two levels): for each quantity of :data:`COMPARED` present
        in at least one summary, ``(column, "value")`` in its display unit, ``(column, "Δ")``
        = value − reference value in the same unit and ``(column, "Δ %")`` = 100 Δ / |reference
        value| (NaN when the reference value is 0 or missing); then
        :data:`INPUTS_COLUMN`: the inputs that differ between the runs, described by
        :func:`describe_change`. The depth of the deepest value is named in the heading when
        every run has the same one.
    """
    names = [r.name for r in runs]
    if reference not in names:
        raise KeyError(f"unknown reference run {reference!r}; runs: {', '.join(names)}")
    ref = runs[names.index(reference)]
    columns: dict[tuple[str, str], list] = {}
    for quantity in COMPARED:
        if not any(quantity.summary_key in r.summary for r in runs):
            continue
        heading = _heading(quantity, runs)
        ref_value = _display_value(ref.summary, quantity)
        values = [_display_value(r.summary, quantity) for r in runs]
        columns[(heading, VALUE)] = values
        columns[(heading, DIFFERENCE)] = [v - ref_value for v in values]
        columns[(heading, PERCENT)] = [
            100.0 * (v - ref_value) / abs(ref_value) if ref_value else math.nan for v in values
        ]
    differing = changed_paths([r.inputs for r in runs])
    columns[INPUTS_COLUMN] = [
        ", ".join(describe_change(path, r.inputs[path]) for path in differing) for r in runs
    ]
    table = pd.DataFrame(columns, index=pd.Index(names, name="Run"))
    table.columns = pd.MultiIndex.from_tuples(table.columns)
    return table


def _display_value(summary: Mapping[str, float], quantity: ComparedQuantity) -> float:
    """A summary value in its display unit; NaN when the summary lacks it."""
    value = summary.get(quantity.summary_key)
    return math.nan if value is None else quantity.scale * value


def _heading(quantity: ComparedQuantity, runs: Sequence[ComparedRun]) -> str:
    """Column heading; the deepest value's heading names the depth if all runs share it."""
    if quantity.summary_key == "peak_disp_deepest_m":
        depths = {r.summary.get("deepest_depth_m") for r in runs}
        if len(depths) == 1 and None not in depths:
            return f"Peak displacement {depths.pop():g} m below ({quantity.unit})"
    return quantity.column


# ---- pinned runs and the session --------------------------------------------------------------
@dataclass
class PinnedRun:
    """A run kept for comparison: its name, inputs, results, visibility and plot colour."""

    name: str
    scenario_json: str
    results: Results
    visible: bool = True
    colour: str = PINNED_COLOURS[0]
    summary: dict[str, float] = field(default_factory=dict)
    """:meth:`Results.summary` taken once when pinned (SI units)."""

    @property
    def scenario(self) -> Scenario:
        """An independent copy of the run's inputs."""
        return Scenario.from_json(self.scenario_json)


class WhatIfSession:
    """The pinned runs of one dashboard session and the chosen reference run.

    Parameters
    ----------
    baseline : Scenario, optional
        What default names are taken relative to (default: the ``paper`` preset).
    baseline_name : str
        Name of a run whose inputs equal the baseline.
    """

    def __init__(self, baseline: Scenario | None = None, baseline_name: str = "paper"):
        self.baseline = baseline if baseline is not None else Scenario.paper()
        self.baseline_name = baseline_name
        self.runs: list[PinnedRun] = []
        self._reference: str | None = None

    # ---- pinning ---------------------------------------------------------------------------
    def pin(self, results: Results, name: str | None = None) -> PinnedRun:
        """Keep ``results`` under ``name`` (default: what differs from the baseline).

        The inputs recorded are those that produced the results (``results.scenario_json``).
        Nothing is recomputed. A 9th run and a name already in use are refused (ValueError).
        """
        if len(self.runs) >= MAX_PINNED:
            raise ValueError(
                f"at most {MAX_PINNED} runs can be pinned in a session; remove one first"
            )
        if name is None or not name.strip():
            scenario = Scenario.from_json(results.scenario_json)
            name = self._unique(default_name(scenario, self.baseline, self.baseline_name))
        name = self._check_new_name(name)
        used = {r.colour for r in self.runs}
        colour = next(c for c in PINNED_COLOURS if c not in used)
        pinned = PinnedRun(
            name=name,
            scenario_json=results.scenario_json,
            results=results,
            colour=colour,
            summary=results.summary(),
        )
        self.runs.append(pinned)
        return pinned

    def _unique(self, name: str) -> str:
        """``name``, or ``name (2)``, ``name (3)`` … if it is taken."""
        taken = set(self.names())
        if name not in taken:
            return name
        return next(
            f"{name} ({k})" for k in range(2, MAX_PINNED + 2) if f"{name} ({k})" not in taken
        )

    def _check_new_name(self, name: str) -> str:
        """A stripped, unused name that is not the current run's; ValueError otherwise."""
        name = name.strip()
        if not name:
            raise ValueError("a pinned run needs a name")
        if name == CURRENT_LABEL:
            raise ValueError(f"{CURRENT_LABEL!r} names the current run; choose another name")
        if name in self.names():
            raise ValueError(f"a pinned run is already named {name!r}; choose another name")
        return name

    # ---- managing pinned runs --------------------------------------------------------------
    def names(self) -> list[str]:
        """Names of the pinned runs, in pin order."""
        return [r.name for r in self.runs]

    def get(self, name: str) -> PinnedRun:
        """The pinned run called ``name`` (KeyError if none)."""
        for pinned in self.runs:
            if pinned.name == name:
                return pinned
        raise KeyError(f"no pinned run is named {name!r}")

    def rename(self, name: str, new_name: str) -> None:
        """Rename a pinned run (the reference follows it)."""
        pinned = self.get(name)
        if new_name.strip() == name:
            return
        pinned.name = self._check_new_name(new_name)
        if self._reference == name:
            self._reference = pinned.name

    def set_visible(self, name: str, visible: bool) -> None:
        """Show or hide a pinned run in the plots (it stays in the comparison table)."""
        self.get(name).visible = bool(visible)

    def restore(self, name: str) -> Scenario:
        """The inputs of a pinned run, as a new Scenario to make current."""
        return self.get(name).scenario

    def remove(self, name: str) -> None:
        """Forget a pinned run and its results; its colour becomes free."""
        self.runs.remove(self.get(name))
        if self._reference == name:
            self._reference = None

    def clear(self) -> None:
        """Forget every pinned run (e.g. when the browser session closes)."""
        self.runs.clear()
        self._reference = None

    # ---- reference and comparison ----------------------------------------------------------
    @property
    def reference(self) -> str:
        """Name of the run differences are taken to: the chosen one, else the first pinned run,
        else the current run."""
        if self._reference is not None:
            return self._reference
        return self.runs[0].name if self.runs else CURRENT_LABEL

    @reference.setter
    def reference(self, name: str | None) -> None:
        if name is not None and name != CURRENT_LABEL:
            self.get(name)
        self._reference = name

    def overlays(self) -> list[tuple[str, Results, str]]:
        """``(name, results, colour)`` of every visible pinned run, in pin order (for plots)."""
        return [(r.name, r.results, r.colour) for r in self.runs if r.visible]

    def comparison(self, current: Results | None = None) -> pd.DataFrame:
        """:func:`comparison_table` of every pinned run and, last, the current run if given.

        Without a current run, a current-run reference falls back to the first pinned run.
        """
        # inputs straight from the JSON: no Scenario objects on every refresh of the table
        rows = [
            ComparedRun(r.name, r.summary, flat_inputs(json.loads(r.scenario_json)))
            for r in self.runs
        ]
        if current is not None:
            inputs = flat_inputs(json.loads(current.scenario_json))
            rows.append(ComparedRun(CURRENT_LABEL, summary_of(current), inputs))
        if not rows:
            raise ValueError("nothing to compare: no pinned run and no current run")
        names = [r.name for r in rows]
        reference = self.reference if self.reference in names else names[0]
        return comparison_table(rows, reference)


# ---- the session file -------------------------------------------------------------------------
@dataclass(frozen=True)
class SavedRun:
    """A pinned run as stored in a session file: inputs, name, visibility and colour."""

    name: str
    scenario: Scenario
    visible: bool
    colour: str


@dataclass(frozen=True)
class SessionFile:
    """The validated contents of a session file (no results)."""

    runs: tuple[SavedRun, ...]
    reference: str | None
    current: Scenario | None


def save_session(session: WhatIfSession, current: Scenario | None = None) -> str:
    """JSON text of a session: every pinned run's inputs, name, visibility and colour, the
    reference and, if given, the current scenario (inputs only, SI; results are not stored)."""
    data = {
        "format": SESSION_FORMAT,
        "version": SESSION_VERSION,
        "reference": session._reference,
        "runs": [
            {
                "name": r.name,
                "visible": r.visible,
                "colour": r.colour,
                "scenario": json.loads(r.scenario_json),
            }
            for r in session.runs
        ],
        "current": None if current is None else current.to_dict(),
    }
    return json.dumps(data, indent=2, allow_nan=False)


def read_session(text: str | bytes) -> SessionFile:
    """Parse and check a session file written by :func:`save_session`; nothing is computed.

    Raises
    ------
    ValueError
        Not JSON (or nested too deeply), not a session file (format tag), an unknown version, a
        malformed entry, or a scenario value out of range (naming the run and the parameter).
    """
    if isinstance(text, bytes):
        try:
            text = text.decode("utf-8")
        except UnicodeDecodeError:
            raise ValueError("not a session file: it is not UTF-8 text") from None
    try:
        data = json.loads(text)
    except json.JSONDecodeError as error:
        raise ValueError(f"not a session file: not valid JSON ({error})") from None
    except RecursionError:
        raise ValueError("not a session file: its JSON is nested too deeply") from None
    if not isinstance(data, dict) or data.get("format") != SESSION_FORMAT:
        raise ValueError(
            f"not a session file: the format tag is not {SESSION_FORMAT!r} (a scenario file is "
            'loaded with "Load a scenario file" instead)'
        )
    if data.get("version") != SESSION_VERSION:
        raise ValueError(
            f"session file version {data.get('version')!r} is not supported; this version of "
            f"tunnelsettle reads version {SESSION_VERSION}"
        )
    entries = data.get("runs")
    if not isinstance(entries, list):
        raise ValueError("bad session file: 'runs' must be a list")
    if len(entries) > MAX_PINNED:
        raise ValueError(f"bad session file: {len(entries)} runs, at most {MAX_PINNED} allowed")
    runs = [_saved_run(entry, index) for index, entry in enumerate(entries, start=1)]
    names = [r.name for r in runs]
    duplicates = sorted({n for n in names if names.count(n) > 1})
    if duplicates or CURRENT_LABEL in names:
        raise ValueError(
            f"bad session file: run names must be unique and not {CURRENT_LABEL!r}: "
            f"{', '.join(duplicates or [CURRENT_LABEL])}"
        )
    reference = data.get("reference")
    if reference is not None and reference not in [*names, CURRENT_LABEL]:
        raise ValueError(f"bad session file: reference {reference!r} is not one of the runs")
    current = data.get("current")
    return SessionFile(
        runs=tuple(runs),
        reference=reference,
        current=None if current is None else _scenario(current, "the current scenario"),
    )


def _saved_run(entry: Any, index: int) -> SavedRun:
    """One checked run entry of a session file."""
    if not isinstance(entry, dict):
        raise ValueError(f"bad session file: run {index} is not an object")
    name = entry.get("name")
    if not isinstance(name, str) or not name.strip():
        raise ValueError(f"bad session file: run {index} has no name")
    visible = entry.get("visible", True)
    if not isinstance(visible, bool):
        raise ValueError(f"bad session file: run {name!r}: 'visible' must be true or false")
    colour = entry.get("colour")
    if colour not in PINNED_COLOURS:
        raise ValueError(
            f"bad session file: run {name!r}: colour {colour!r} is not one of {PINNED_COLOURS}"
        )
    return SavedRun(name, _scenario(entry.get("scenario"), f"run {name!r}"), visible, colour)


def _scenario(data: Any, where: str) -> Scenario:
    """Scenario from a session file's inputs; bad values are refused naming ``where``."""
    try:
        scenario = Scenario.from_dict(data)
        admit_profile(scenario, data_folder())  # a path: only inside the data folder
        return scenario
    except (ValueError, KeyError, TypeError) as error:
        message = error.args[0] if isinstance(error, KeyError) and error.args else error
        raise ValueError(f"bad session file: {where}: {message}") from None


def load_session(
    text: str | bytes,
    compute: Compute | None = None,
    baseline: Scenario | None = None,
    cache: StageCache | None = None,
) -> tuple[WhatIfSession, Scenario | None]:
    """Session from a file written by :func:`save_session`, every run's results recomputed.

    Parameters
    ----------
    text : str or bytes
        The file's contents.
    compute : callable(Scenario) -> Results, optional
        How a run is computed; the dashboard passes one that uses its own stage cache.
        Default: :func:`model.pipeline.run` with ``cache``.
    baseline : Scenario, optional
        Baseline of the new session's default names.
    cache : StageCache, optional
        Stage cache of the default ``compute`` (ignored when ``compute`` is given).

    Returns
    -------
    session : WhatIfSession
    current : Scenario or None
        The current scenario saved with the session, if any.

    Raises
    ------
    ValueError
        A bad or foreign file (see :func:`read_session`), or a run that fails to compute.
    """
    saved = read_session(text)
    compute = compute if compute is not None else (lambda s: run(s, cache=cache))
    session = WhatIfSession(baseline=baseline)
    for entry in saved.runs:
        try:
            results = compute(entry.scenario)
        except (ValueError, KeyError, RuntimeError) as error:
            raise ValueError(f"run {entry.name!r} of the session failed: {error}") from error
        pinned = session.pin(results, entry.name)
        pinned.visible, pinned.colour = entry.visible, entry.colour
    session.reference = saved.reference
    return session, saved.current
