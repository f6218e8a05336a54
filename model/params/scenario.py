"""One complete set of inputs, :class:`Scenario`: its sections, presets, JSON and dotted paths.

``Scenario.validate`` checks the constraints between parameters before any computation.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import param

from model.params.ground import THIN_RING_MAX_RATIO, Soil, Tunnel
from model.params.longterm import MOVED_TO_LAYERS, LongTerm
from model.params.numerics import Numerics
from model.params.quantities import ScenarioError, _load_presets
from model.params.site import Site, layers_from_records
from model.params.soil_sets import LAYERS, SOIL_SETS
from model.params.track import Irregularity, Track
from model.params.vehicle import Train, Vehicle

SECTIONS = (
    "vehicle",
    "train",
    "track",
    "irregularity",
    "tunnel",
    "soil",
    "numerics",
    "site",
    "longterm",
)

MOVED_PARAMETERS = {
    "longterm.axis_depth": "tunnel.axis_depth",
    "longterm.water_table_depth": "site.water_table_depth",
}
"""Former dotted path → current one, so that scenario files written before a parameter moved to
another section still load (the axis depth moved to the tunnel, where later models of the ground
need it; the water table to the site profile). The strength and strain-law constants that became
properties of each layer are in ``model.params.longterm.MOVED_TO_LAYERS``."""


class Scenario(param.Parameterized):
    """One complete set of inputs: vehicle, train, track, irregularity, tunnel, soil, numerics,
    site profile, long-term settlement."""

    vehicle = param.ClassSelector(class_=Vehicle, instantiate=True)
    train = param.ClassSelector(class_=Train, instantiate=True)
    track = param.ClassSelector(class_=Track, instantiate=True)
    irregularity = param.ClassSelector(class_=Irregularity, instantiate=True)
    tunnel = param.ClassSelector(class_=Tunnel, instantiate=True)
    soil = param.ClassSelector(class_=Soil, instantiate=True)
    numerics = param.ClassSelector(class_=Numerics, instantiate=True)
    site = param.ClassSelector(class_=Site, instantiate=True)
    longterm = param.ClassSelector(class_=LongTerm, instantiate=True)

    def __init__(self, **params):
        classes = {name: self.param[name].class_ for name in SECTIONS}
        for name, cls in classes.items():
            params.setdefault(name, cls())
        super().__init__(**params)

    # ---- presets --------------------------------------------------------------------------
    @staticmethod
    def preset_names() -> list[str]:
        """Names of the presets stored in ``model/data/presets.json``."""
        return list(_load_presets())

    @classmethod
    def preset(cls, name: str) -> Scenario:
        """Scenario of a named preset from ``model/data/presets.json``."""
        presets = _load_presets()
        if name not in presets:
            raise KeyError(f"unknown preset {name!r}; available: {', '.join(presets)}")
        scenario = cls()
        scenario.update(presets[name]["values"])
        return scenario

    @classmethod
    def paper(cls) -> Scenario:
        """The paper's Nanjing case as read by docs/model.md: Type A six cars, 80 km/h, FRA 6."""
        return cls.preset("paper")

    @classmethod
    def paper_soil_lame(cls) -> Scenario:
        """Paper case with the soil of Table 4's Lamé constants (E ≈ 550 MPa, ν ≈ 0.44)."""
        return cls.preset("paper_soil_lame")

    @classmethod
    def paper_soil_wave_speeds(cls) -> Scenario:
        """Paper case with the soil of Table 4's wave speeds c1 = 524, c2 = 190 m/s."""
        return cls.preset("paper_soil_wave_speeds")

    @classmethod
    def paper_2p5d(cls) -> Scenario:
        """The paper's case with the 2.5D moving-load tunnel–soil model."""
        return cls.preset("paper_2p5d")

    @classmethod
    def paper_half_space(cls) -> Scenario:
        """The paper's case, 2.5D, with the tunnel under a free ground surface (half-space)."""
        return cls.preset("paper_half_space")

    @classmethod
    def type_b(cls) -> Scenario:
        """Paper case with a six-car Type B train."""
        return cls.preset("type_b")

    # ---- serialisation --------------------------------------------------------------------
    def to_dict(self) -> dict[str, dict[str, Any]]:
        """All inputs as nested plain values, ``{section: {parameter: value}}``; the site's
        layers are a list of ``{property: value}``, top down."""
        data = {
            section: {name: getattr(obj, name) for name in obj.param if name != "name"}
            for section in SECTIONS
            for obj in [getattr(self, section)]
        }
        data["site"]["layers"] = self.site.records()
        return data

    def to_json(self, indent: int | None = 2) -> str:
        """JSON text of :meth:`to_dict`; floats are written exactly (shortest repr)."""
        return json.dumps(self.to_dict(), indent=indent, allow_nan=False)

    @classmethod
    def from_dict(cls, data: dict[str, dict[str, Any]]) -> Scenario:
        """Scenario from :meth:`to_dict` output (missing values take their defaults).

        A parameter under its former path (``MOVED_PARAMETERS``) is read at its current one.
        """
        scenario = cls()
        scenario.update(_with_moved_parameters(data))
        return scenario

    @classmethod
    def from_json(cls, text: str | bytes) -> Scenario:
        """Scenario from :meth:`to_json` output (str, or UTF-8 bytes; a leading BOM is ignored).

        Raises
        ------
        ValueError
            Malformed JSON (with its line and column), non-UTF-8 bytes, nesting too deep, or
            a bad value (naming the parameter).
        """
        if isinstance(text, bytes):
            try:
                text = text.decode("utf-8-sig")
            except UnicodeDecodeError as error:
                raise ValueError(
                    f"scenario is not UTF-8 text (byte {error.start}: {error.reason})"
                ) from None
        return cls.from_dict(parse_json(text.removeprefix("\ufeff"), "scenario"))

    @classmethod
    def from_file(cls, path: str | Path) -> Scenario:
        """Scenario from a JSON file written by a run or the dashboard's "Save scenario".

        A relative ``irregularity.profile_csv`` is resolved against the file's folder (not the
        working directory), so a scenario and its profile can be moved together.

        Raises
        ------
        ValueError
            The file cannot be read or is not a valid scenario; the message names the file.
        """
        path = Path(path)
        try:
            scenario = cls.from_json(path.read_bytes())
        except OSError as error:
            raise ValueError(f"{path}: cannot read the scenario file ({error.strerror})") from None
        except ValueError as error:
            raise ValueError(f"{path}: {error}") from None
        except KeyError as error:
            raise ValueError(f"{path}: {error.args[0] if error.args else error}") from None
        profile = scenario.irregularity.profile_csv
        if profile and not Path(profile).is_absolute():
            scenario.irregularity.profile_csv = str((path.parent / profile).resolve())
        return scenario

    def copy(self) -> Scenario:
        """Independent deep copy."""
        return type(self).from_dict(self.to_dict())

    def update(self, values: dict[str, dict[str, Any]]) -> None:
        """Set parameters from ``{section: {parameter: value}}``; unknown names are refused.

        All or nothing: if any value is refused, every parameter keeps its previous value.
        """
        self._check_update(values)
        if isinstance(values.get("site", {}).get("layers"), list):
            values = {**values, "site": {**values["site"]}}
            values["site"]["layers"] = layers_from_records(values["site"]["layers"])
        before = {
            section: {name: getattr(getattr(self, section), name) for name in section_values}
            for section, section_values in values.items()
        }
        try:
            for section, section_values in values.items():
                getattr(self, section).param.update(**section_values)
        except Exception:
            for section, old_values in before.items():
                getattr(self, section).param.update(**old_values)
            raise

    def _check_update(self, values) -> None:
        """Refuse an update that is not ``{known section: {known parameter: value}}``."""
        if not isinstance(values, dict):
            raise ValueError(
                f"a scenario must be an object of sections, not {type(values).__name__}"
            )
        for section, section_values in values.items():
            if section in SECTIONS and not isinstance(section_values, dict):
                raise ValueError(
                    f"section {section!r} must be an object of parameters, not "
                    f"{type(section_values).__name__}"
                )
            if section not in SECTIONS:
                raise KeyError(f"unknown section {section!r}; expected one of {SECTIONS}")
            obj = getattr(self, section)
            unknown = (set(section_values) - set(obj.param)) | ({"name"} & set(section_values))
            if unknown:
                raise KeyError(f"unknown parameter(s) {sorted(unknown)} in section {section!r}")

    def set_value(self, path: str, value: Any) -> None:
        """Set one parameter by dotted path, e.g. ``set_value("train.speed_kmh", 60)``.

        A string value is converted to the parameter's type ("none" gives None for optional
        parameters).
        """
        section, name = parameter_path(path)
        obj = getattr(self, section)
        if isinstance(value, str):
            value = _parse_value(obj.param[name], path, value)
        setattr(obj, name, value)

    # ---- derived quantities that need more than one section --------------------------------
    @property
    def car_body_pitch_inertia(self) -> float:
        """Car body pitch inertia (kg·m²): the given value, or M_c·L_car²/12 when None."""
        given = self.vehicle.car_body_pitch_inertia
        if given is not None:
            return given
        return self.vehicle.car_body_mass * self.train.car_length**2 / 12.0

    @property
    def rail_length(self) -> float:
        """Rail length L (m), a whole number of block spacings.

        The leading axle starts ``approach_distance`` before the monitored block at mid-length
        and the trailing axle ends the same distance past it, every axle staying
        ``rail_end_margin`` from both rail ends: L ≥ 2 (margin + approach + axle span).
        """
        n = self.numerics
        needed = 2.0 * (n.rail_end_margin + n.approach_distance + self.train.axle_span)
        n_spacings = math.ceil(needed / self.track.block_spacing - 1e-9)
        n_spacings += n_spacings % 2  # even, so the mid-length point is a block position
        return n_spacings * self.track.block_spacing

    @property
    def rail_modes(self) -> int:
        """Number of rail modes used: the given value, or L/L_s (docs/model.md §2)."""
        if self.numerics.n_rail_modes is not None:
            return self.numerics.n_rail_modes
        return round(self.rail_length / self.track.block_spacing)

    @property
    def passage_duration(self) -> float:
        """Simulated time (s): leading axle from approach to trailing axle past the block."""
        travel = 2.0 * self.numerics.approach_distance + self.train.axle_span
        return travel / self.train.speed

    def validate(self) -> None:
        """Check constraints between parameters; raise :class:`ScenarioError` listing all."""
        problems = []
        irr, tr = self.irregularity, self.train
        if irr.wavelength_min >= irr.wavelength_max:
            problems.append(
                f"irregularity.wavelength_min = {irr.wavelength_min:g} m must be below "
                f"irregularity.wavelength_max = {irr.wavelength_max:g} m"
            )
        if not tr.single_bogie and tr.bogie_distance + tr.wheelbase >= tr.car_length:
            problems.append(
                f"train.bogie_distance + train.wheelbase = {tr.bogie_distance + tr.wheelbase:g} m "
                f"must be shorter than train.car_length = {tr.car_length:g} m"
            )
        if tr.wheelbase >= tr.bogie_distance and not tr.single_bogie:
            problems.append(
                f"train.wheelbase = {tr.wheelbase:g} m must be shorter than "
                f"train.bogie_distance = {tr.bogie_distance:g} m"
            )
        min_modes = math.ceil(0.5 * self.rail_length / self.track.block_spacing)
        if self.rail_modes < min_modes:
            problems.append(
                f"numerics.n_rail_modes = {self.rail_modes} is too few for a "
                f"{self.rail_length:g} m rail: at least 0.5 L/L_s = {min_modes} are needed "
                f"(L/L_s = {2 * min_modes} recommended)"
            )
        tunnel = self.tunnel
        if tunnel.thickness > THIN_RING_MAX_RATIO * tunnel.ring_radius:
            problems.append(
                f"tunnel.thickness = {tunnel.thickness:g} m is more than {THIN_RING_MAX_RATIO:g} "
                f"of the ring radius a = {tunnel.ring_radius:g} m (h/a = "
                f"{tunnel.thickness / tunnel.ring_radius:.3g}): the thin-ring lining model does "
                f"not hold; allowed h ≤ {THIN_RING_MAX_RATIO:g} a"
            )
        cover = tunnel.axis_depth - tunnel.inner_radius - tunnel.thickness
        if cover <= 0.0:
            problems.append(
                f"tunnel.axis_depth = {tunnel.axis_depth:g} m puts the lining (outer "
                f"radius {tunnel.inner_radius + tunnel.thickness:g} m) above the ground surface; "
                "allowed: axis depth > tunnel.inner_radius + tunnel.thickness"
            )
        if tunnel.ground == "half_space" and tunnel.model != "2.5d":
            problems.append(
                "tunnel.ground = 'half_space' needs tunnel.model = '2.5d': in the 2D section (a "
                "line load on the whole tunnel at once) the field the ground surface reflects "
                "is 20–70 % of the direct displacement at the invert at every frequency (axis "
                "15 m deep, 0.05–5 Hz), too strong for the pipe-in-pipe method, which neglects "
                "how the tunnel scatters it (docs/halfspace.md)"
            )
        profile = irr.profile_csv
        if profile and irr.profile_data is not None:
            problems.append(
                "irregularity.profile_csv and irregularity.profile_data are both set: a "
                "measured profile is given by its file or by its text, not both"
            )
        elif irr.enabled and profile and not Path(profile).is_file():
            problems.append(
                f"irregularity.profile_csv = {profile!r} is not a file"
                + ("" if Path(profile).is_absolute() else f" (relative to {Path.cwd()})")
            )
        problems += self._profile_problems()
        lt = self.longterm
        if lt.soil_set != LAYERS and SOIL_SETS[lt.soil_set].law != lt.law:
            problems.append(
                f"longterm.soil_set = {lt.soil_set!r} holds constants of the law "
                f"{SOIL_SETS[lt.soil_set].law!r}, but longterm.law = {lt.law!r}: choose that law "
                "or longterm.soil_set = 'layers' (each layer's own constants)"
            )
        if problems:
            raise ScenarioError("inconsistent scenario:\n  - " + "\n  - ".join(problems))

    @property
    def deepest_depth_below_ground(self) -> float:
        """Depth below the surface of the long-term stage's deepest depth, H_t + a + d_max (m)."""
        return self.tunnel.axis_depth + self.tunnel.ring_radius + self.numerics.max_depth

    def _profile_problems(self) -> list[str]:
        """The site profile must reach the deepest depth and hold the water table."""
        site, problems = self.site, []
        total, deepest = site.bottoms[-1], self.deepest_depth_below_ground
        last = site.layers[-1]
        if total < deepest:
            problems.append(
                f"site.layers reach {total:g} m below the surface, short of the long-term "
                f"stage's deepest depth {deepest:g} m (tunnel.axis_depth {self.tunnel.axis_depth:g}"
                f" m + ring radius {self.tunnel.ring_radius:g} m + numerics.max_depth "
                f"{self.numerics.max_depth:g} m): make the last layer ({last.name!r}, "
                f"site.layers[{len(site.layers) - 1}].thickness = {last.thickness:g} m) at least "
                f"{last.thickness + deepest - total:g} m thick"
            )
        if site.water_table_depth > total:
            problems.append(
                f"site.water_table_depth = {site.water_table_depth:g} m lies below the profile, "
                f"whose layers reach {total:g} m; allowed range [0, {total:g}] m"
            )
        return problems


def parameter_path(path: str) -> tuple[str, str]:
    """Section and name of the dotted parameter path ``path`` (e.g. ``"train.speed_kmh"``).

    Raises
    ------
    KeyError
        If no parameter has that path; the message names it and lists what exists.
    """
    section, _, name = path.partition(".")
    if section not in SECTIONS or not name:
        raise KeyError(
            f"unknown parameter {path!r}: a parameter is section.parameter, with section one of "
            f"{', '.join(SECTIONS)}"
        )
    names = [n for n in Scenario.param[section].class_.param if n != "name"]
    if name not in names:
        raise KeyError(f"unknown parameter {path!r}; {section} has: {', '.join(names)}")
    return section, name


def _with_moved_parameters(data):
    """``data`` with every parameter of ``MOVED_PARAMETERS`` under its current section, and the
    long-term parameters that became layer properties (``MOVED_TO_LAYERS``) in every layer.

    Raises
    ------
    ValueError
        The former and the current path are both given, with different values.
    """
    if not isinstance(data, dict):
        return data  # refused, with its message, by Scenario.update
    data = {section: dict(v) if isinstance(v, dict) else v for section, v in data.items()}
    _move_to_layers(data)
    for old, new in MOVED_PARAMETERS.items():
        (old_section, old_name), (new_section, new_name) = old.split("."), new.split(".")
        values = data.get(old_section)
        if not isinstance(values, dict) or old_name not in values:
            continue
        value = values.pop(old_name)
        target = data.setdefault(new_section, {})
        if not isinstance(target, dict):
            continue  # refused by Scenario.update
        if target.setdefault(new_name, value) != value:
            raise ValueError(
                f"{old} = {value!r} and {new} = {target[new_name]!r} disagree: {old} is the "
                f"former path of {new}; give only {new}"
            )
    return data


def _move_to_layers(data: dict) -> None:
    """Give every layer the ``MOVED_TO_LAYERS`` values of a former long-term section (in place).

    Raises
    ------
    ValueError
        A layer sets the same property to another value.
    """
    longterm = data.get("longterm")
    if not isinstance(longterm, dict):
        return
    moved = {name: longterm.pop(name) for name in MOVED_TO_LAYERS if name in longterm}
    site = data.setdefault("site", {})
    if not moved or not isinstance(site, dict):
        return
    records = site.get("layers", [{}])
    if not isinstance(records, list):
        return  # refused by Scenario.update
    site["layers"] = [dict(r) if isinstance(r, dict) else r for r in records]
    for index, record in enumerate(site["layers"]):
        if not isinstance(record, dict):
            continue
        for name, value in moved.items():
            if record.setdefault(name, value) != value:
                raise ValueError(
                    f"longterm.{name} = {value!r} and site.layers[{index}].{name} = "
                    f"{record[name]!r} disagree: longterm.{name} is the former place of the "
                    "layers' property; give only the layers'"
                )


def _parse_value(parameter: param.Parameter, path: str, text: str) -> Any:
    """Convert command-line text to the type of ``parameter``; refuse it in the project's voice
    (:func:`model.params.quantities.refusal`), showing the text as typed."""
    stripped = text.strip()
    if stripped.lower() == "none" and parameter.allow_None:
        return None
    if isinstance(parameter, param.Boolean):
        lowered = stripped.lower()
        if lowered in {"true", "false", "1", "0", "yes", "no"}:
            return lowered in {"true", "1", "yes"}
        raise ValueError(parameter.refusal_text(text, f"is not {parameter.allowed_text()}"))
    if not isinstance(parameter, param.Number):
        return text  # options and texts: the parameter itself refuses what it does not hold
    kind = "a whole number" if isinstance(parameter, param.Integer) else "a number"
    try:
        if "_" in stripped:
            raise ValueError  # int() and float() read "1_0" as 10
        return int(stripped) if isinstance(parameter, param.Integer) else float(stripped)
    except ValueError:
        problem = f"is not {kind}; the allowed range is {parameter.allowed_text()}"
        raise ValueError(parameter.refusal_text(text, problem)) from None


def parse_json(text: str, what: str) -> Any:
    """The value of a JSON text, every failure a one-line ``ValueError`` that names ``what``
    (e.g. "scenario", "study definition") and never quotes the text.

    Raises
    ------
    ValueError
        Not JSON (with the line and column), or nested too deeply for Python's parser.
    """
    try:
        return json.loads(text)
    except json.JSONDecodeError as error:
        raise ValueError(
            f"{what} is not valid JSON ({error.msg} at line {error.lineno} column {error.colno})"
        ) from None
    except RecursionError:
        raise ValueError(f"{what} JSON is nested too deeply to be a {what}") from None
