"""What a study is: the base scenario, the varied parameters, the seeds and the sampling.

:func:`define_study` checks the inputs and every scenario of a study before anything is run; a
:class:`Study`'s JSON re-runs it exactly.
"""

from __future__ import annotations

import itertools
import json
import math
from collections.abc import Iterable, Iterator
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np
import param

from model.params import Scenario
from model.params.scenario import parameter_path, parse_json
from model.track.vehicle_track import check_inputs

MAX_RUNS_UNCONFIRMED = 500
"""Largest study run without ``confirm=True`` / ``--yes`` (about 5 min of the paper case on two
cores at ~1.2 s per run)."""
MAX_RUNS = 1_000_000
"""Largest study run at all (its definition alone takes some hundred MB; about a fortnight of
the paper case on two cores)."""
SAMPLINGS = ("grid", "random", "lhs")
STUDY_FORMAT = "tunnelsettle-study/1"


# ---- the study definition ------------------------------------------------------------------
@dataclass
class Study:
    """Everything that defines a study; its JSON re-runs it exactly.

    ``vary`` maps a dotted parameter path to its grid values (``sampling="grid"``) or to its
    ``[low, high]`` range (``"random"``, ``"lhs"``; ``None`` takes the parameter's softbounds).
    """

    base_json: str
    vary: dict[str, Any]
    seeds: list[int]
    sampling: str = "grid"
    n_samples: int | None = None
    sampling_seed: int = 0
    depth_profile: bool = False
    _points: list[dict[str, Any]] = field(default_factory=list, init=False, repr=False)

    @property
    def base(self) -> Scenario:
        """A fresh copy of the base scenario."""
        return Scenario.from_json(self.base_json)

    @property
    def points(self) -> list[dict[str, Any]]:
        """Values of the varied parameters at each point (seeds not included)."""
        if not self._points:
            self._points = _sample_points(self)
        return self._points

    @property
    def n_runs(self) -> int:
        """Points times seeds."""
        return len(self.points) * len(self.seeds)

    def runs(self) -> Iterator[tuple[dict[str, Any], str]]:
        """(inputs row, scenario JSON) of every run, seeds innermost."""
        for point in self.points:
            scenario = self.base
            for path, value in point.items():
                scenario.set_value(path, value)
            for seed in self.seeds:
                scenario.irregularity.seed = seed
                yield {**point, "seed": seed}, scenario.to_json(indent=None)

    def to_json(self) -> str:
        """JSON of the definition (with the base scenario inline)."""
        data = {key: value for key, value in asdict(self).items() if not key.startswith("_")}
        data["base"] = json.loads(data.pop("base_json"))
        return json.dumps({"format": STUDY_FORMAT, **data}, indent=2, allow_nan=False)

    @classmethod
    def from_json(cls, text: str) -> Study:
        """Validated study from :meth:`to_json` output.

        Raises
        ------
        ValueError
            Not JSON, not a study definition (format tag, a missing or mistyped entry), or a
            study that :func:`define_study` refuses; one line, never quoting the text.
        """
        data = parse_json(text, "study definition")
        if not isinstance(data, dict) or data.get("format") != STUDY_FORMAT:
            raise ValueError(f"not a study definition (expected format {STUDY_FORMAT!r})")
        for key, kind, name in (
            ("base", dict, "object"),
            ("vary", dict, "object"),
            ("seeds", list, "array"),
        ):
            if not isinstance(data.get(key), kind):
                raise ValueError(f"study definition: {key!r} must be a JSON {name}")
        try:
            base = Scenario.from_dict(data["base"])
            return define_study(
                base,
                vary=data["vary"],
                seeds=data["seeds"],
                sampling=data.get("sampling", "grid"),
                n_samples=data.get("n_samples"),
                sampling_seed=data.get("sampling_seed", 0),
                depth_profile=data.get("depth_profile", False),
                confirm=True,  # the count is checked when the study is run
            )
        except (TypeError, AttributeError, KeyError, OverflowError) as error:
            raise ValueError(
                f"study definition: an entry has the wrong type or form ({type(error).__name__})"
            ) from None


def define_study(
    base: Scenario,
    vary: dict[str, Any],
    seeds: Iterable[int] | None = None,
    sampling: str = "grid",
    n_samples: int | None = None,
    sampling_seed: int = 0,
    depth_profile: bool = False,
    confirm: bool = False,
) -> Study:
    """Check a study's inputs and every one of its scenarios, before anything is computed.

    Parameters
    ----------
    base : Scenario
        Scenario that every run starts from.
    vary : dict
        Dotted parameter path (``"train.speed_kmh"``, SI units except km/h) → grid values for
        ``sampling="grid"``; → ``(low, high)`` or ``None`` (the parameter's softbounds, its
        realistic slider range) for ``"random"`` and ``"lhs"``.
    seeds : iterable of int, optional
        Irregularity seeds, one run per seed at each point; default the base scenario's seed.
    sampling : {"grid", "random", "lhs"}
        Full grid, independent uniform samples, or a Latin hypercube (each range cut into
        ``n_samples`` equal strata, one sample per stratum and parameter).
    n_samples : int, optional
        Number of points for ``"random"`` and ``"lhs"``.
    sampling_seed : int
        Seed of the random / Latin-hypercube points (not of the irregularity).
    depth_profile : bool
        Also return the peak displacement at every depth (see :func:`run_summary`).
    confirm : bool
        Required for more than :data:`MAX_RUNS_UNCONFIRMED` runs.

    Raises
    ------
    ValueError
        Unknown parameter, value or range outside the parameter's bounds, empty grid, no
        seeds, too many runs without ``confirm``, inconsistent scenario: one line naming the
        parameter and the allowed range.
    """
    if sampling not in SAMPLINGS:
        raise ValueError(f"sampling = {sampling!r} is not one of {', '.join(SAMPLINGS)}")
    if not isinstance(vary, dict):
        raise ValueError("vary must map parameter paths to values")
    seeds = [base.irregularity.seed] if seeds is None else list(seeds)
    if not seeds:
        raise ValueError("seeds is empty: give at least one irregularity seed")
    check_run_count(len(seeds), confirm)
    probe = base.copy()
    for seed in seeds:
        _set(probe, "irregularity.seed", seed)
    seeds = [int(seed) for seed in seeds]
    if len(set(seeds)) != len(seeds):
        raise ValueError(f"seeds {seeds} repeat a seed: each run would be computed twice")
    if sampling == "grid":
        if n_samples is not None:
            raise ValueError("n_samples is for random or lhs sampling, not for a grid")
        vary = {
            path: [spec] if isinstance(spec, str) or not isinstance(spec, Iterable) else list(spec)
            for path, spec in vary.items()
        }
        n_points = math.prod(len(values) for values in vary.values())
    else:
        if not vary:
            raise ValueError(f"{sampling} sampling needs at least one parameter to vary")
        if n_samples is None or int(n_samples) != n_samples or n_samples < 1:
            raise ValueError(f"n_samples = {n_samples!r} must be a whole number ≥ 1")
        n_samples = n_points = int(n_samples)
    check_run_count(n_points * len(seeds), confirm)  # before any point is built
    checked: dict[str, Any] = {}
    for path, spec in vary.items():
        if path == "irregularity.seed":
            raise ValueError("irregularity.seed is varied through seeds, not vary")
        parameter = _parameter(path)
        if sampling == "grid":
            if not spec:
                raise ValueError(f"{path}: no values given, the grid is empty")
            checked[path] = [_set(probe, path, value) for value in spec]
        else:
            checked[path] = _sampling_range(probe, path, parameter, spec)
    study = Study(
        base_json=base.to_json(),
        vary=checked,
        seeds=seeds,
        sampling=sampling,
        n_samples=n_samples,
        sampling_seed=int(sampling_seed),
        depth_profile=bool(depth_profile),
    )
    for point in study.points:  # the seed changes no constraint, so one check per point
        scenario = study.base
        for path, value in point.items():
            scenario.set_value(path, value)
        try:
            check_inputs(scenario)
        except ValueError as error:
            where = ", ".join(f"{path} = {value!r}" for path, value in point.items())
            message = " ".join(str(error).split())
            raise ValueError(f"at {where or 'the base scenario'}: {message}") from None
    return study


def _parameter(path: str) -> param.Parameter:
    """The parameter at a dotted path, or a one-line error listing what exists."""
    try:
        section, name = parameter_path(path)
    except KeyError as error:
        raise ValueError(error.args[0]) from None
    return Scenario.param[section].class_.param[name]


def _set(scenario: Scenario, path: str, value: Any) -> Any:
    """Set ``value`` (text, number, numpy scalar) at ``path``; return it as the parameter's type."""
    parameter = _parameter(path)
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(parameter, param.Integer) and isinstance(value, float) and value.is_integer():
        value = int(value)
    elif _is_quantity(parameter) and isinstance(value, int) and not isinstance(value, bool):
        value = float(value)  # 60 and 60.0 must give the same scenario JSON
    try:
        scenario.set_value(path, value)
    except KeyError as error:
        raise ValueError(error.args[0]) from None
    section, _, name = path.partition(".")
    return getattr(getattr(scenario, section), name)


def _is_quantity(parameter: param.Parameter) -> bool:
    """A real-valued number parameter (not an integer or a flag)."""
    return isinstance(parameter, param.Number) and not isinstance(
        parameter, param.Integer | param.Boolean
    )


def _sampling_range(probe: Scenario, path: str, parameter, spec) -> list[float]:
    """[low, high] of a sampled parameter: the given range, or its softbounds."""
    if not isinstance(parameter, param.Number):
        raise ValueError(f"{path} is not a number and can only be varied on a grid")
    if spec is None:
        low, high = parameter.get_soft_bounds()
        if low is None or high is None:
            raise ValueError(f"{path} has no finite softbounds: give its range as low:high")
    else:
        try:
            low, high = spec
        except (TypeError, ValueError):
            raise ValueError(f"{path}: a sampling range is (low, high), not {spec!r}") from None
    low, high = _set(probe, path, low), _set(probe, path, high)
    if not low < high:
        raise ValueError(f"{path}: the range [{low:g}, {high:g}] is empty (low must be < high)")
    return [low, high]


def _sample_points(study: Study) -> list[dict[str, Any]]:
    """The points of a study: the grid's product, or the random / Latin-hypercube draws."""
    paths = list(study.vary)
    if study.sampling == "grid":
        return [
            dict(zip(paths, values, strict=True))
            for values in itertools.product(*study.vary.values())
        ]
    rng = np.random.default_rng(study.sampling_seed)
    n, d = study.n_samples, len(paths)
    if study.sampling == "random":
        unit = rng.random((n, d))
    else:  # one sample in each of n equal strata per parameter, strata paired at random
        unit = (np.argsort(rng.random((d, n)), axis=1).T + rng.random((n, d))) / n
    points = []
    for row in unit:
        point = {}
        for path, fraction in zip(paths, row, strict=True):
            low, high = study.vary[path]
            value = low + fraction * (high - low)
            point[path] = round(value) if isinstance(_parameter(path), param.Integer) else value
        points.append(point)
    return points


def check_run_count(n_runs: int, confirm: bool) -> None:
    """Refuse more than :data:`MAX_RUNS_UNCONFIRMED` runs unless confirmed, and more than
    :data:`MAX_RUNS` in any case."""
    if n_runs > MAX_RUNS:
        raise ValueError(
            f"the study has {n_runs} runs, more than the {MAX_RUNS} allowed: vary fewer "
            "values or seeds"
        )
    if n_runs > MAX_RUNS_UNCONFIRMED and not confirm:
        raise ValueError(
            f"the study has {n_runs} runs, more than {MAX_RUNS_UNCONFIRMED} without "
            "confirmation: confirm it (--yes on the command line)"
        )
