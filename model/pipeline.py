"""The one place the stages are chained: vehicle–track → invert load → soil response
(displacements and stresses under the invert, one tunnel–soil kernel pass) → long-term
settlement.

``run(scenario)`` returns :class:`Results`. Each stage is cached on exactly the parameters it
depends on, so moving a soil slider reuses the vehicle–track simulation and moving the speed
slider re-runs everything.

Coupling rule (docs/model.md §6): the 3D train loads the 2D tunnel section through the force into
the invert under the monitored block, spread over one block spacing and summed over both rails,
``q(t) = N_RAILS · F_b(t) / L_s`` in N per metre of tunnel.
"""

from __future__ import annotations

import json
import threading
import time
import warnings
from collections import OrderedDict
from collections.abc import Callable
from concurrent.futures import Future
from dataclasses import dataclass, field, fields, is_dataclass
from typing import Any

import numpy as np

from model.longterm.geostatic import check_longterm_inputs
from model.longterm.settlement import LongTermResult, long_term_settlement
from model.params import Scenario
from model.params.measured_profile import profile_digest
from model.run_checks import check_record_padding, invariant_warnings, scenario_warnings
from model.run_cost import SLOW_RUN_SECONDS, RunEstimate, SlowRunWarning, estimate_run
from model.soil.ground_vibration import GroundResponse, ground_summary
from model.soil.halfspace_response import halfspace_response, halfspace_transfer
from model.soil.response import (
    COMPARISON_DEPTH_M,
    SoilResponse,
    padded_load_spectrum,
)
from model.soil.stresses import StressResponse, section_response, section_transfer
from model.spectra import one_sided_psd
from model.track.vehicle_track import (
    VehicleTrackResult,
    check_inputs,
    n_time_steps,
    simulate,
)

N_RAILS = 2  # both rails load the same tunnel section (docs/model.md §6)

# Numerics parameters read by each stage; with WAVENUMBER_NUMERICS they must cover every
# Numerics parameter (checked by the tests), so that no setting is silently left out of a key.
VEHICLE_TRACK_NUMERICS = ("dt", "n_rail_modes", "rail_end_margin", "approach_distance")
LOAD_NUMERICS = ("psd_segment",)
# Numerics of the wavenumber integral of the point-load response
# (model.soil.point_load.point_load_response), which no stage calls (the 2.5D soil stage
# evaluates the kernel at ξ = ω/v): in no key, so a change never forces a recompute.
WAVENUMBER_NUMERICS = ("n_wavenumbers", "max_wavenumber", "wavenumber_tolerance")
# Numerics of the ground-surface results of the half-space model: in the soil key only when
# tunnel.ground is "half_space".
GROUND_NUMERICS = ("ground_max_distance", "n_ground_distances")
SOIL_NUMERICS = (
    "n_harmonics",
    "soil_max_frequency",
    "zero_pad_factor",
    "psd_segment",
    "max_depth",
    "n_depths",
    "kernel_samples_per_cycle",
    *GROUND_NUMERICS,
)

# Tunnel parameters read by the long-term stage only (the static stress state; the full-space
# soil models have no ground surface): in the long-term key, not the soil key, so that changing
# them re-runs the long-term stage alone. A soil model that reads one must take it off this list.
LONGTERM_TUNNEL = ("axis_depth",)

# The soil stage also yields the stresses under the invert (Results.stress): both come from
# one evaluation of the tunnel–soil kernel, so they share a stage and its cache key.
STAGES = ("vehicle_track", "load", "soil", "longterm")


class SimulationError(RuntimeError):
    """The vehicle–track integration went unstable; its warnings say why and what to change."""


Progress = Callable[[str, float], None]
StageDone = Callable[[str, Any], None]


@dataclass(frozen=True)
class LoadResult:
    """2D line load on the tunnel section and its spectrum."""

    t_s: np.ndarray
    """(nt,) time (s)."""
    line_load_N_per_m: np.ndarray
    """(nt,) downward line load on the invert, N per metre of tunnel."""
    f_hz: np.ndarray
    """(nf,) frequencies of the PSD (Hz)."""
    psd: np.ndarray
    """(nf,) one-sided PSD of the line load, (N/m)²/Hz."""


@dataclass
class Results:
    """Everything one run produces, with the inputs that made it."""

    scenario_json: str
    vehicle_track: VehicleTrackResult
    load: LoadResult
    soil: SoilResponse
    stress: StressResponse
    """Dynamic deviator under the invert, computed by the soil stage."""
    longterm: LongTermResult
    ground: GroundResponse | None = None
    """Ground-surface vibration, computed by the soil stage with tunnel.ground = "half_space";
    None for the full-space models, which have no ground surface."""
    warnings: list[str] = field(default_factory=list)
    stage_seconds: dict[str, float] = field(default_factory=dict)
    """Wall time of each stage in this run; 0.0 for a stage served from the cache."""
    cached_stages: tuple[str, ...] = ()

    @property
    def scenario(self) -> Scenario:
        """The scenario that produced these results."""
        return Scenario.from_json(self.scenario_json)

    def summary(self, scenario: Scenario | None = None) -> dict[str, float]:
        """Key numbers in SI units (N, N/m, m, m/s, Pa); ``longterm_stress_ratio_max``, the
        largest q_d/σ_s of the long-term column, at or above 1 says that the long-term
        settlement is outside the strain laws' range. ``scenario``: :attr:`scenario` already
        parsed, if the caller holds it (parsing takes milliseconds)."""
        vt, soil = self.vehicle_track, self.soil
        scenario = self.scenario if scenario is None else scenario
        depth, peak = soil.depth_m, soil.peak_disp_m
        return {
            "peak_invert_force_N": float(np.max(vt.block_force_N)),
            "peak_line_load_N_per_m": float(np.max(self.load.line_load_N_per_m)),
            "peak_block_disp_m": float(np.max(vt.block_disp_m)),
            "peak_wheel_force_N": float(np.max(vt.wheel_force_N)),
            "min_wheel_force_N": float(np.min(vt.wheel_force_N)),
            "peak_disp_invert_m": float(peak[0]),
            "peak_disp_11m_m": float(np.interp(COMPARISON_DEPTH_M, depth, peak)),
            "peak_disp_deepest_m": float(peak[-1]),
            "deepest_depth_m": float(depth[-1]),
            "soil_p_wave_speed_m_s": scenario.soil.p_wave_speed,
            "soil_s_wave_speed_m_s": scenario.soil.s_wave_speed,
            "soil_lame_lambda_Pa": scenario.soil.lame_lambda,
            "soil_shear_modulus_Pa": scenario.soil.shear_modulus,
            "deviator_invert_Pa": float(self.longterm.deviator_Pa[0]),
            "strength_invert_Pa": float(self.longterm.strength_Pa[0]),
            "longterm_stress_ratio_max": float(np.max(self.longterm.stress_ratio)),
            "longterm_settlement_m": float(self.longterm.settlement_m[-1]),
            "longterm_plastic_settlement_m": float(self.longterm.plastic_settlement_m[-1]),
            "longterm_consolidation_settlement_m": float(
                self.longterm.consolidation_settlement_m[-1]
            ),
            "longterm_generated_pore_pressure_max_Pa": float(
                np.max(self.longterm.generated_pore_pressure_Pa[-1])
            ),
            "longterm_excess_pore_pressure_max_Pa": float(
                np.max(self.longterm.excess_pore_pressure_Pa[-1])
            ),
            "longterm_depth90_m": self.longterm.depth90_m,
            **(ground_summary(self.ground) if self.ground is not None else {}),
        }


# Not a stage of its own (no progress is reported for it): the soil stage's tunnel–soil kernel
# on the record's frequency grid, cached apart from the load so that runs differing only in the
# load (seed, vehicle, track) reuse it. Its entries are large (tens of MB), hence few.
TRANSFER = "soil_transfer"
# Nor is the spectrum of the zero-padded load record: it depends on the load and the record
# grid's numerics, not on the soil, so a soil change reuses it (a small entry).
LOAD_SPECTRUM = "load_spectrum"
# Numerics of the record grid (model.soil.response.padded_load_spectrum).
RECORD_GRID_NUMERICS = ("soil_max_frequency", "zero_pad_factor")


class StageCache:
    """Small thread-safe LRU cache per stage, keyed on the JSON of the parameters it reads.

    Values are stored read-only (see :func:`run`), so a caller cannot change what a later run
    is served. Threads that ask :meth:`fetch` for a value another thread is computing wait for
    it instead of computing it again (ten sessions opening the same page compute it once).
    The caller owns the cache: :func:`run` uses one only when it is passed.

    Parameters
    ----------
    size : int
        Entries kept per stage.
    transfer_size : int
        Entries kept of the soil stage's tunnel–soil transfer functions (``TRANSFER``).
    """

    def __init__(self, size: int = 4, transfer_size: int = 2):
        self.size, self.transfer_size = size, transfer_size
        self._lock = threading.Lock()
        names = (*STAGES, TRANSFER, LOAD_SPECTRUM)
        self._entries: dict[str, OrderedDict[str, Any]] = {s: OrderedDict() for s in names}
        self._computing: dict[tuple[str, str], Future] = {}
        self.hits = dict.fromkeys(names, 0)
        self.misses = dict.fromkeys(names, 0)

    def get(self, stage: str, key: str):
        """Cached value or None; counts the hit or miss."""
        with self._lock:
            return self._lookup(stage, key)

    def _lookup(self, stage: str, key: str):
        """:meth:`get` with the lock held."""
        entries = self._entries[stage]
        if key in entries:
            entries.move_to_end(key)
            self.hits[stage] += 1
            return entries[key]
        self.misses[stage] += 1
        return None

    def _store(self, stage: str, key: str, value) -> None:
        """Store a value (lock held), evicting the least recently used beyond the stage's
        size."""
        limit = self.transfer_size if stage == TRANSFER else self.size
        entries = self._entries[stage]
        entries[key] = value
        entries.move_to_end(key)
        while len(entries) > limit:
            entries.popitem(last=False)

    def holds(self, keys: dict[str, str]) -> bool:
        """True when the value of every stage for ``keys`` (:func:`stage_keys` of a scenario)
        is stored, so that a run of that scenario returns at once (nothing counted)."""
        with self._lock:
            return all(keys[stage] in self._entries[stage] for stage in STAGES)

    def fetch(self, stage: str, key: str, compute: Callable[[], Any]) -> tuple[Any, bool]:
        """The cached value, or the one another thread is computing, or ``compute()`` stored.

        Returns
        -------
        (value, served)
            ``served`` is False when this call computed the value. An exception of the
            computing thread is raised in the threads that waited for it too.
        """
        with self._lock:
            pending = self._computing.get((stage, key))
            owner = pending is None
            if owner:
                value = self._lookup(stage, key)
                if value is not None:
                    return value, True
                pending = self._computing[(stage, key)] = Future()
            else:  # computing in another thread: a hit, once it is done
                self.hits[stage] += 1
        if not owner:
            return pending.result(), True
        try:
            value = compute()
        except BaseException as error:
            with self._lock:
                del self._computing[(stage, key)]
            pending.set_exception(error)
            raise
        with self._lock:
            self._store(stage, key, value)
            del self._computing[(stage, key)]
        pending.set_result(value)
        return value, False

    def clear(self) -> None:
        """Forget every entry and reset the counters (computations under way finish)."""
        with self._lock:
            for entries in self._entries.values():
                entries.clear()
            for counter in (self.hits, self.misses):
                counter.update(dict.fromkeys(counter, 0))


def stage_keys(scenario: Scenario) -> dict[str, str]:
    """Cache key of each stage: the JSON of everything it depends on, upstream included."""
    data = scenario.to_dict()
    numerics = data["numerics"]

    def pick(names):
        return {name: numerics[name] for name in names}

    vehicle_track = {
        section: data[section] for section in ("vehicle", "train", "track", "irregularity")
    }
    # a measured profile counts by its content (an edited file is not served from the cache,
    # whatever its stat), and a profile's text enters the key as its digest (remembered)
    vehicle_track["irregularity"] = {
        **data["irregularity"],
        "profile_data": None,
        "profile_digest": profile_digest(scenario.irregularity),
    }
    vehicle_track["numerics"] = pick(VEHICLE_TRACK_NUMERICS)
    load = {"upstream": vehicle_track, "numerics": pick(LOAD_NUMERICS)}
    moving_load = scenario.tunnel.model == "2.5d"
    half_space = scenario.tunnel.ground == "half_space"
    soil = {
        "upstream": load,
        "tunnel": {  # includes tunnel.model and tunnel.ground
            name: value
            for name, value in data["tunnel"].items()
            if half_space or name not in LONGTERM_TUNNEL
        },
        "soil": data["soil"],
        "numerics": pick(
            name for name in SOIL_NUMERICS if half_space or name not in GROUND_NUMERICS
        ),
    }
    if moving_load:  # the 2.5D kernel is evaluated at ξ = ω/v
        soil["speed_kmh"] = data["train"]["speed_kmh"]
    longterm = {
        "upstream": soil,
        "longterm": data["longterm"],
        "site": data["site"],
        "tunnel": {name: data["tunnel"][name] for name in LONGTERM_TUNNEL},
    }
    # the transfer functions: the soil stage's inputs but the load, whose record's length and
    # step (which set the frequency grid) run() appends
    transfer = {name: value for name, value in soil.items() if name != "upstream"}
    spectrum = {"upstream": load, "numerics": pick(RECORD_GRID_NUMERICS)}
    return {
        name: json.dumps(value, sort_keys=True)
        for name, value in zip(
            (*STAGES, TRANSFER, LOAD_SPECTRUM),
            (vehicle_track, load, soil, longterm, transfer, spectrum),
            strict=True,
        )
    }


def invert_line_load(block_force_N: np.ndarray, block_spacing_m: float) -> np.ndarray:
    """Line load on the 2D section (N/m) from the force into the invert under one block (N)."""
    return N_RAILS * block_force_N / block_spacing_m


def run(
    scenario: Scenario,
    progress: Progress | None = None,
    cache: StageCache | None = None,
    on_stage: StageDone | None = None,
) -> Results:
    """Run every stage (or every stage that ``cache`` cannot serve).

    Every array in the returned results is read-only (``flags.writeable`` is False), also
    those served from a cache: copy an array before changing it.

    Parameters
    ----------
    scenario : Scenario
        All inputs; validated before any computation.
    progress : callable(stage, fraction), optional
        Told the stage name (one of ``STAGES``) and the fraction done
        of that stage, 0 to 1, so a user interface can show a progress bar.
    cache : StageCache or None
        Stage cache owned by the caller (e.g. the dashboard); ``None`` (the default) computes
        everything afresh.
    on_stage : callable(stage, output), optional
        Told each stage's name and output once it is ready (computed or served), in the
        computing thread, before the next stage starts: the vehicle–track result, the load,
        the soil stage's ``(soil, stress, ground)`` and the long-term result, as
        :class:`Results` holds them. A user interface may show a stage's outputs before the
        run ends.

    Returns
    -------
    Results

    Raises
    ------
    ValueError
        Bad or inconsistent inputs, or a run that would not fit in memory (before any
        computation; the message names the parameter).
    SimulationError
        The explicit integration diverged (its message names the limit on ``numerics.dt``).

    Warns
    -----
    SlowRunWarning
        Before computing, if the run is estimated to take longer than ``SLOW_RUN_SECONDS``.
    """
    estimate = _admitted(scenario)
    if estimate.total_seconds > SLOW_RUN_SECONDS:
        warnings.warn(estimate.slow_message(), SlowRunWarning, stacklevel=2)
    report = progress or (lambda stage, fraction: None)
    done = on_stage or (lambda stage, output: None)
    keys = stage_keys(scenario)
    seconds: dict[str, float] = {}
    cached: list[str] = []

    def stage(name, compute, accept=lambda value: None):
        """The output of stage ``name`` (served or ``compute()``d), once ``accept(output)``
        has not raised."""
        report(name, 0.0)
        start = time.perf_counter()
        if cache is None:
            value, served = _read_only(compute()), False
        else:
            value, served = cache.fetch(name, keys[name], lambda: _read_only(compute()))
        seconds[name] = 0.0 if served else time.perf_counter() - start
        if served:
            cached.append(name)
        report(name, 1.0)
        accept(value)
        done(name, value)
        return value

    vt = stage(
        "vehicle_track",
        lambda: simulate(scenario, progress=lambda f: report("vehicle_track", f)),
        accept=_stable,
    )
    load = stage("load", lambda: _load_stage(vt, scenario))

    # the half-space model adds the ground-surface results (docs/halfspace.md)
    respond = (
        halfspace_response
        if scenario.tunnel.ground == "half_space"
        else lambda *args: (*section_response(*args), None)
    )

    def soil_stage():
        q, dt = load.line_load_N_per_m, _time_step(load.t_s)
        if cache is None:
            return respond(q, dt, scenario)
        transfer = _fetch_transfer(scenario, cache, keys, q.size, dt)
        spectrum, _ = cache.fetch(
            LOAD_SPECTRUM,
            keys[LOAD_SPECTRUM],
            lambda: _read_only(padded_load_spectrum(q, dt, scenario.numerics)),
        )
        return respond(q, dt, scenario, transfer, spectrum)

    soil, stress, ground = stage("soil", soil_stage)
    longterm = stage("longterm", lambda: long_term_settlement(stress, scenario))
    run_warnings = (
        list(vt.warnings)
        + scenario_warnings(scenario)
        + invariant_warnings(soil)
        + list(longterm.warnings)
    )
    return Results(
        scenario_json=scenario.to_json(),
        vehicle_track=vt,
        load=load,
        soil=soil,
        stress=stress,
        longterm=longterm,
        ground=ground,
        warnings=run_warnings,
        stage_seconds=seconds,
        cached_stages=tuple(cached),
    )


def prefetch_transfer(scenario: Scenario, cache: StageCache) -> None:
    """Compute the soil stage's tunnel–soil transfer functions of ``scenario`` into ``cache``
    (or find them there), without the vehicle–track stage.

    They depend on the inputs alone: the load record's grid, ``n_time_steps + 1`` samples at
    ``numerics.dt``, is known before the passage is simulated. A process about to fork workers
    that will run the scenario (a study's LocalCluster) computes them once, on all its cores,
    instead of every worker computing them in its first run; a run of the scenario with that
    cache then finds them (or waits for the thread computing them).

    Raises
    ------
    ValueError
        Inputs that :func:`run` refuses, a run too large for the memory among them (nothing
        is computed).
    """
    _admitted(scenario)
    keys = stage_keys(scenario)
    _fetch_transfer(scenario, cache, keys, n_time_steps(scenario) + 1, scenario.numerics.dt)


def _admitted(scenario: Scenario) -> RunEstimate:
    """The run's estimate, once every check before computing has passed: inputs, the padded
    record, memory (``estimate_run``), the vehicle–track and the long-term stages' own.

    Raises
    ------
    ValueError
        The first check refused; the message names the parameter.
    """
    scenario.validate()
    check_record_padding(scenario)
    estimate = estimate_run(scenario)
    check_inputs(scenario)
    check_longterm_inputs(scenario)
    return estimate


def _fetch_transfer(scenario: Scenario, cache: StageCache, keys: dict, n_samples: int, dt_s: float):
    """The transfer functions of ``scenario`` on the grid of a load record of ``n_samples``
    samples at ``dt_s`` (s), served by ``cache`` or computed into it."""
    transfer_of = halfspace_transfer if scenario.tunnel.ground == "half_space" else section_transfer
    transfer, _ = cache.fetch(
        TRANSFER,
        f"{keys[TRANSFER]} record {n_samples} × {dt_s!r} s",
        lambda: _read_only(transfer_of(np.zeros(n_samples), dt_s, scenario)),
    )
    return transfer


def _stable(vt: VehicleTrackResult) -> None:
    """Raise :class:`SimulationError` if the vehicle–track integration went unstable."""
    if vt.unstable:
        raise SimulationError(
            "the vehicle–track simulation went unstable: " + "; ".join(vt.warnings)
        )


def _read_only(stage_result):
    """The stage result (a dataclass, an array, or a tuple of them and None) with every array
    in it, nested dataclasses included, made read-only."""
    if stage_result is None:
        return None
    if isinstance(stage_result, np.ndarray):
        stage_result.flags.writeable = False
        return stage_result
    if isinstance(stage_result, tuple):
        for part in stage_result:
            _read_only(part)
        return stage_result
    for item in fields(stage_result):
        value = getattr(stage_result, item.name)
        if isinstance(value, np.ndarray):
            value.flags.writeable = False
        elif is_dataclass(value):
            _read_only(value)
    return stage_result


def _load_stage(vt: VehicleTrackResult, scenario: Scenario) -> LoadResult:
    """Line load from the monitored block force, and its one-sided PSD."""
    q = invert_line_load(vt.block_force_N, scenario.track.block_spacing)
    f_hz, psd = one_sided_psd(q, _time_step(vt.t_s), scenario.numerics.psd_segment)
    return LoadResult(t_s=vt.t_s, line_load_N_per_m=q, f_hz=f_hz, psd=psd)


def _time_step(t_s: np.ndarray) -> float:
    """Uniform sampling interval of a time vector (s)."""
    return float(t_s[1] - t_s[0])
