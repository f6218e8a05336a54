"""Settlement bands: how sure the long-term settlement is, by Monte Carlo on Dask.

Each draw is the base scenario with its irregularity seed taken from a list of seeds (in turn),
the constants of the strain and pore-pressure laws drawn (from a calibration's covariance where
a calibration is in use, else from coefficients of variation) and the layers' properties drawn
from their coefficients of variation. The draws are fixed in this process from
``sampling_seed`` before anything runs, so a band is reproducible whatever the cluster.

The draws of one seed go to one task, which runs the passage (vehicle–track and soil stages)
once and then the long-term stage alone for each draw (``run_in_worker``'s stage cache).

Distributions. A coefficient of variation ``cv`` multiplies the value by a log-normal factor of
mean 1 and that CV (σ² = ln(1 + cv²), μ = −σ²/2): the value stays positive, and a CV of 0 keeps
it exactly. A calibration (:func:`model.longterm.calibration.fit_strain_law`) gives the normal
joint distribution of (ln a, m, b) with its covariance; one draw of it serves every layer that
uses the fitted constants (one test series, one set of constants).
"""

from __future__ import annotations

import json
import math
import re
import warnings
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from model.longterm.statements import SETTLEMENT_COVERS
from model.outputs import write_text_atomic
from model.params import Scenario
from model.study.execution import collect_tasks, run_in_worker, study_client

LAW_CONSTANTS = ("a", "b", "m", "n", "a_u", "b_u", "m_u", "alpha_u", "beta_u")
"""Layer constants of the strain and pore-pressure laws that ``law_cv`` may vary."""
SITE_PROPERTIES = (
    "unit_weight",
    "friction_angle",
    "cu_ratio",
    "undrained_strength",
    "compressibility",
    "recompression_index",
    "void_ratio",
    "permeability",
    "consolidation_coefficient",
)
"""Layer properties that ``site_cv`` may vary."""
CALIBRATED = ("a", "m", "b")  # the order of the fit's covariance: ln a, m, b
MAX_CV = 1.0  # a CV above 1 is not an uncertainty of a measured property but ignorance of it
MAX_DRAWS = 10000
DEFAULT_DRAWS = 200
DEFAULT_SEEDS = 10
QUANTILES = {"p05": 5.0, "p50": 50.0, "p95": 95.0}
"""Band columns and their percentiles (linear interpolation between order statistics)."""
DRAW_COLUMN = "draw_{index:04d}"
_LAYER_KEY = re.compile(r"^site\.layers\[(\d+)\]\.(\w+)$")
_MATCH_RTOL = 1e-9  # a layer uses a calibration when its a, b, m equal the fit's to this


def _check_cvs(cvs: Mapping[str, float], known: tuple[str, ...], label: str) -> dict[str, float]:
    """The CVs as floats, or ValueError naming the entry, its value and the allowed range."""
    if not isinstance(cvs, Mapping):
        raise ValueError(f"{label} must be a mapping of property → CV, not {type(cvs).__name__}")
    checked = {}
    for name, cv in cvs.items():
        if name not in known:
            raise ValueError(
                f"{label}[{name!r}] is not a layer property it may vary; known: {', '.join(known)}"
            )
        try:
            cv = float(cv)
        except (TypeError, ValueError):
            raise ValueError(f"{label}[{name!r}] = {cv!r} is not a number") from None
        if not 0.0 <= cv <= MAX_CV:
            raise ValueError(
                f"{label}[{name!r}] = {cv!r} is outside the allowed range [0, {MAX_CV:g}] "
                "(coefficient of variation, -)"
            )
        checked[name] = cv
    return checked


def _per_layer(site_cv, n_layers: int) -> list[dict[str, float]]:
    """``site_cv`` as one checked dict per layer (a single mapping applies to every layer)."""
    if site_cv is None:
        return [{} for _ in range(n_layers)]
    if isinstance(site_cv, Mapping):
        one = _check_cvs(site_cv, SITE_PROPERTIES, "site_cv")
        return [dict(one) for _ in range(n_layers)]
    site_cv = list(site_cv)
    if len(site_cv) != n_layers:
        raise ValueError(
            f"site_cv has {len(site_cv)} entries but site.layers has {n_layers} layer(s): give "
            "one mapping per layer, top down, or one mapping for all"
        )
    return [
        _check_cvs(cvs, SITE_PROPERTIES, f"site_cv[{index}]") for index, cvs in enumerate(site_cv)
    ]


def band_seeds(scenario: Scenario, seeds) -> list[int]:
    """Irregularity seeds of a band: a count N (the base seed and the N − 1 after it) or a list.

    With the irregularity switched off every seed gives the same passage: one seed is used.
    """
    if seeds is None:
        seeds = DEFAULT_SEEDS
    if isinstance(seeds, int | np.integer) and not isinstance(seeds, bool):
        if seeds < 1:
            raise ValueError(f"seeds = {seeds} is outside the allowed range [1, {MAX_DRAWS}]")
        seeds = range(scenario.irregularity.seed, scenario.irregularity.seed + int(seeds))
    seeds = [int(seed) for seed in seeds]
    if not seeds:
        raise ValueError("seeds is empty: give a count or at least one seed")
    if not scenario.irregularity.enabled:
        return seeds[:1]
    return seeds


def calibrated_layers(scenario: Scenario, calibration: Mapping[str, Any]) -> list[int]:
    """Indices of the layers that use a strain-law calibration (class 'user', its a, b, m).

    Raises
    ------
    ValueError
        The calibration has no covariance, or no layer uses its constants.
    """
    if "covariance" not in calibration:
        raise ValueError("calibration has no 'covariance': pass the dict fit_strain_law returns")
    fitted = np.array([calibration[name] for name in CALIBRATED], dtype=float)
    layers = [
        index
        for index, layer in enumerate(scenario.site.layers)
        if layer.soil_class == "user"
        and np.allclose([getattr(layer, name) for name in CALIBRATED], fitted, rtol=_MATCH_RTOL)
    ]
    if not layers:
        raise ValueError(
            f"calibration: no layer of site.layers uses the fitted a = {fitted[0]:.4g} %, "
            f"b = {fitted[2]:.4g}, m = {fitted[1]:.4g} (soil class 'user' with these values): "
            "apply the fit to the layer(s) first"
        )
    return layers


def calibration_draws(calibration: Mapping[str, Any], n_draws: int, rng) -> np.ndarray:
    """(n_draws, 3) draws of (a, m, b) from the normal law of (ln a, m, b) of a calibration.

    Parameters
    ----------
    calibration : mapping
        :func:`fit_strain_law`'s result: ``a`` (%), ``m``, ``b`` and ``covariance`` (3 × 3, of
        ln a, m, b).
    n_draws : int
        Number of draws.
    rng : numpy.random.Generator
        Source of the draws.
    """
    covariance = np.asarray(calibration["covariance"], dtype=float)
    if covariance.shape != (3, 3) or not np.all(np.isfinite(covariance)):
        raise ValueError(
            f"calibration['covariance'] must be a finite 3 × 3 matrix, got shape {covariance.shape}"
        )
    mean = np.array([math.log(calibration["a"]), calibration["m"], calibration["b"]])
    draws = rng.multivariate_normal(mean, covariance, size=n_draws, method="eigh")
    draws[:, 0] = np.exp(draws[:, 0])
    return draws


def lognormal_factors(cv: float, n_draws: int, rng) -> np.ndarray:
    """(n_draws,) log-normal factors of mean 1 and coefficient of variation ``cv`` (1 at 0)."""
    sigma = math.sqrt(math.log1p(cv * cv))
    return np.exp(sigma * rng.standard_normal(n_draws) - 0.5 * sigma * sigma)


def define_band(
    scenario: Scenario,
    n_draws: int = DEFAULT_DRAWS,
    seeds=None,
    *,
    law_cv: Mapping[str, float] | None = None,
    site_cv=None,
    calibration: Mapping[str, Any] | None = None,
    sampling_seed: int = 0,
) -> list[dict[str, Any]]:
    """The draws of a band, checked: per draw its ``seed`` and each drawn layer value.

    Parameters are those of :func:`settlement_band`. Returns one dict per draw, ``{"seed":
    int, "site.layers[i].name": value, ...}``; a layer whose strain-law constants are drawn
    while it uses a Li & Selig class gets ``soil_class = "user"`` with the class's values as
    the means.

    Raises
    ------
    ValueError
        A bad count, seed list, CV or calibration, naming it (before anything runs).
    """
    scenario.validate()
    if isinstance(n_draws, bool) or not isinstance(n_draws, int | np.integer):
        raise ValueError(f"n_draws = {n_draws!r} is not a whole number")
    if not 1 <= n_draws <= MAX_DRAWS:
        raise ValueError(f"n_draws = {n_draws} is outside the allowed range [1, {MAX_DRAWS}]")
    seeds = band_seeds(scenario, seeds)
    layers = scenario.site.layers
    law = _check_cvs(law_cv or {}, LAW_CONSTANTS, "law_cv")
    named_set = scenario.longterm.soil_set
    if named_set != "layers" and (law or calibration is not None):
        raise ValueError(
            f"longterm.soil_set = {named_set!r} fixes the strain-law constants of every layer, "
            "so law_cv and calibration would draw constants the run does not use: set "
            "longterm.soil_set = 'layers' to draw them"
        )
    site = _per_layer(site_cv, len(layers))
    for index, (layer, cvs) in enumerate(zip(layers, site, strict=True)):
        for name in cvs:
            if getattr(layer, name) is None:
                raise ValueError(
                    f"site_cv: site.layers[{index}].{name} is None (layer {layer.name!r} uses "
                    "the property it is derived from): vary that one instead"
                )
    calibrated = [] if calibration is None else calibrated_layers(scenario, calibration)
    rng = np.random.default_rng(sampling_seed)
    draws: list[dict[str, Any]] = [{"seed": seeds[index % len(seeds)]} for index in range(n_draws)]
    if calibrated:
        constants = calibration_draws(calibration, n_draws, rng)
        for index in calibrated:
            for column, name in enumerate(CALIBRATED):
                for draw, value in zip(draws, constants[:, column], strict=True):
                    draw[f"site.layers[{index}].{name}"] = float(value)
    for index, (layer, cvs) in enumerate(zip(layers, site, strict=True)):
        law_here = {
            name: cv for name, cv in law.items() if not (index in calibrated and name in CALIBRATED)
        }
        means = dict(zip(("a", "b", "m"), layer.law_parameters(scenario.longterm.law), strict=True))
        for name, cv in {**law_here, **cvs}.items():
            mean = means.get(name, getattr(layer, name))
            factors = lognormal_factors(cv, n_draws, rng)
            for draw, factor in zip(draws, factors, strict=True):
                draw[f"site.layers[{index}].{name}"] = float(mean * factor)
        if layer.soil_class != "user" and set(law_here) & set(means):
            for draw in draws:  # the class's a, b, m become the layer's own, then drawn
                draw[f"site.layers[{index}].soil_class"] = "user"
                for name, value in means.items():
                    draw.setdefault(f"site.layers[{index}].{name}", value)
    return draws


def apply_draw(scenario: Scenario, draw: Mapping[str, Any]) -> Scenario:
    """A copy of ``scenario`` with a draw's seed and layer values set (ValueError if refused)."""
    drawn = scenario.copy()
    drawn.irregularity.seed = int(draw["seed"])
    for key, value in draw.items():
        if key == "seed":
            continue
        match = _LAYER_KEY.match(key)
        if match is None:
            raise ValueError(f"{key!r} is not a drawn input (seed or site.layers[i].property)")
        layer = drawn.site.layers[int(match.group(1))]
        try:
            setattr(layer, match.group(2), value)
        except ValueError as error:
            raise ValueError(f"{key} = {value!r}: {error}") from None
    return drawn


def seed_draws_task(scenario_json: str, draws: list[dict[str, Any]]) -> dict[str, Any]:
    """The task of a band: every draw of one seed, the passage computed once.

    Returns
    -------
    dict
        ``years`` (n_years,) or None if every draw failed; ``settlement_m``, one (n_years,)
        array per draw or None where it failed; ``errors``, one message per draw ("" if it ran).
    """
    from model.pipeline import SimulationError

    base = Scenario.from_json(scenario_json)
    years, settlement, errors = None, [], []
    for draw in draws:
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # the slow-run estimate; the band reports errors
                longterm = run_in_worker(apply_draw(base, draw)).longterm
        except (ValueError, KeyError, SimulationError) as error:
            settlement.append(None)
            errors.append(f"{type(error).__name__}: {' '.join(str(error).split())}")
            continue
        years = np.array(longterm.years)
        settlement.append(np.array(longterm.settlement_m))
        errors.append("")
    return {"years": years, "settlement_m": settlement, "errors": errors}


def settlement_band(
    scenario: Scenario,
    n_draws: int = DEFAULT_DRAWS,
    seeds=None,
    scheduler=None,
    *,
    law_cv: Mapping[str, float] | None = None,
    site_cv=None,
    calibration: Mapping[str, Any] | None = None,
    sampling_seed: int = 0,
    progress=None,
    cancel=None,
    n_workers: int | None = None,
) -> pd.DataFrame:
    """5–50–95 % band of the long-term settlement at the invert against service time.

    Parameters
    ----------
    scenario : Scenario
        The base scenario (its long-term settlement ``res.longterm.settlement_m`` is the
        quantity drawn).
    n_draws : int
        Number of draws, 1 to 10 000 (default 200).
    seeds : int or iterable of int, optional
        Irregularity seeds, used in turn by the draws: a count N (the base scenario's seed and
        the N − 1 after it; default 10) or the seeds themselves. One seed when the irregularity
        is off.
    scheduler : None, str or distributed.Client
        As in :func:`model.study.execution.run_study`.
    law_cv : mapping, optional
        Coefficient of variation (−, 0 to 1) of law constants of every layer, by name: ``a``,
        ``b``, ``m``, ``n`` (strain law), ``a_u``, ``b_u``, ``m_u``, ``alpha_u``, ``beta_u``
        (pore pressure); drawn independently per layer.
    site_cv : mapping or list of mappings, optional
        Coefficient of variation of layer properties (``unit_weight``, ``friction_angle``,
        ``cu_ratio``, ``undrained_strength``, ``compressibility``, ``recompression_index``,
        ``void_ratio``, ``permeability``, ``consolidation_coefficient``): one mapping for every
        layer, or one per layer, top down.
    calibration : mapping, optional
        :func:`model.longterm.calibration.fit_strain_law`'s result, in use on the layers whose
        class is 'user' with its a, b, m: those layers' a, b, m are drawn from its covariance
        (one draw for them all), and ``law_cv`` of a, b, m no longer applies to them.
    sampling_seed : int
        Seed of the draws of constants and properties (not of the irregularity).
    progress : callable(done, total, row), optional
        Told as each seed's draws come back.
    cancel : threading.Event, optional
        Stops the band; the draws done are returned, ``attrs["cancelled"]`` True.
    n_workers : int, optional
        Workers of the LocalCluster (default: the machine's cores).

    Returns
    -------
    pandas.DataFrame
        One row per time of the settlement curve: ``years`` (yr), ``p05``, ``p50``, ``p95``,
        ``mean`` (m, over the draws that ran) and one column per draw, ``draw_0000`` … (m; empty
        where the draw failed). ``attrs``: ``n_draws`` (draws that ran), ``n_requested``,
        ``errors`` ({draw: message}), ``draws`` (each draw's seed and drawn values), ``seeds``,
        ``sampling_seed``, ``law_cv``, ``site_cv``, ``calibrated_layers``, ``cancelled``,
        ``scenario`` (the base's JSON) and ``settlement_covers`` (what the settlement covers).

    Raises
    ------
    ValueError
        Bad inputs (before anything runs), or every draw failed (the first message).
    """
    draws = define_band(
        scenario,
        n_draws,
        seeds,
        law_cv=law_cv,
        site_cv=site_cv,
        calibration=calibration,
        sampling_seed=sampling_seed,
    )
    scenario_json = scenario.to_json(indent=None)
    by_seed: dict[int, list[int]] = {}
    for index, draw in enumerate(draws):
        by_seed.setdefault(draw["seed"], []).append(index)
    tasks = [
        ({"seed": seed}, seed_draws_task, (scenario_json, [draws[i] for i in indices]))
        for seed, indices in by_seed.items()
    ]
    with study_client(scheduler, n_workers) as client:
        rows, cancelled = collect_tasks(client, tasks, progress, cancel)
    settlement: list[np.ndarray | None] = [None] * n_draws
    errors: dict[int, str] = {}
    years = None
    for task, indices in enumerate(by_seed.values()):
        row = rows.get(task)
        for position, index in enumerate(indices):
            if row is None:
                continue
            if "error" in row:  # the task itself failed
                errors[index] = row["error"]
                continue
            if row["errors"][position]:
                errors[index] = row["errors"][position]
            else:
                settlement[index] = row["settlement_m"][position]
                years = row["years"]
    ran = [index for index, values in enumerate(settlement) if values is not None]
    if not ran and not cancelled:
        first = min(errors)
        raise ValueError(f"every draw of the band failed; draw {first}: {errors[first]}")
    table = _band_table(years, settlement, ran)
    table.attrs.update(
        n_draws=len(ran),
        n_requested=n_draws,
        errors=errors,
        draws=draws,
        seeds=list(by_seed),
        sampling_seed=sampling_seed,
        law_cv=dict(law_cv or {}),
        site_cv=site_cv if site_cv is None or isinstance(site_cv, Mapping) else list(site_cv),
        calibrated_layers=[] if calibration is None else calibrated_layers(scenario, calibration),
        cancelled=cancelled,
        scenario=scenario_json,
        settlement_covers=SETTLEMENT_COVERS,
    )
    return table


def _band_table(years, settlement: list, ran: list[int]) -> pd.DataFrame:
    """Percentiles over the draws that ran, then every draw's curve (NaN where it failed)."""
    if not ran:
        return pd.DataFrame(columns=["years", *QUANTILES, "mean"])
    curves = np.array([settlement[index] for index in ran])
    columns = {"years": years}
    for name, percent in QUANTILES.items():
        columns[name] = np.percentile(curves, percent, axis=0)
    columns["mean"] = curves.mean(axis=0)
    nan = np.full(len(years), np.nan)
    for index, values in enumerate(settlement):
        columns[DRAW_COLUMN.format(index=index)] = nan if values is None else values
    return pd.DataFrame(columns)


# ---- files and the command line ------------------------------------------------------------
def save_band(table: pd.DataFrame, out: str | Path) -> list[Path]:
    """Write ``band.csv`` (the table, floats exact) and ``band.json`` (its definition), each
    whole (:func:`model.outputs.write_atomic`)."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    definition = {key: value for key, value in table.attrs.items() if key != "scenario"}
    definition["errors"] = {str(key): value for key, value in definition["errors"].items()}
    definition["scenario"] = json.loads(table.attrs["scenario"])
    return [
        write_text_atomic(out / "band.csv", table.to_csv(index=False, float_format="%r")),
        write_text_atomic(
            out / "band.json", json.dumps(definition, indent=1, allow_nan=False) + "\n"
        ),
    ]
