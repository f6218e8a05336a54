"""Property test: any scenario inside the parameters' hard bounds gives a sound result or a
clear refusal (issue 10, "make it stay fixed").

Hypothesis draws one to three parameters of the vehicle–track–soil pipeline, each across its
full hard bounds (log-uniform where the range spans decades, endpoints included), on top of a
cheap base: the single bogie at 100 km/h with coarse soil numerics. Every example must end in
one of two ways:

- finite results that keep the elastic model's invariants: peak downward displacement > 0 at
  the invert and not growing with depth (beyond ``INVARIANT_TOLERANCE`` of the invert peak, the
  flag's own tolerance), non-negative PSDs, and no invariant warning; or
- a ValueError (ScenarioError is one) or SimulationError whose message names a parameter
  (``section.name`` or ``Class.name``).

Examples estimated (model.run_cost) to take longer than ``RUN_BUDGET_S`` are checked only up to
the pre-computation checks, so the test stays under a minute; ``benchmarks/fuzz_scenarios.py``
runs the same property longer, without that budget, and its counts are in docs/validity.md.
"""

from __future__ import annotations

import math
import re
import warnings
from datetime import timedelta

import numpy as np
import param
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from model.params import SECTIONS, Count, Quantity, Scenario
from model.pipeline import SimulationError, run
from model.run_checks import INVARIANT_TOLERANCE
from model.run_cost import SlowRunWarning, estimate_run
from model.track.vehicle_track import check_inputs

RUN_BUDGET_S = 1.0  # estimated seconds above which an example stops after the input checks
PIPELINE_SECTIONS = tuple(s for s in SECTIONS if s != "longterm")  # stages on this branch
CHOICES = ("track.wheel_tread", "irregularity.enabled", "train.single_bogie")


def base_scenario() -> Scenario:
    """Single bogie at 100 km/h, coarse soil numerics: about half a second per run."""
    scenario = Scenario.preset("single_bogie")
    scenario.update(
        {
            "train": {"speed_kmh": 100.0},
            "numerics": {"n_depths": 6, "n_harmonics": 8, "soil_max_frequency": 50.0},
        }
    )
    return scenario


def drawable_parameters() -> dict[str, param.Parameter]:
    """Every numeric parameter of the pipeline's sections, by dotted path."""
    scenario = Scenario()
    return {
        f"{section}.{name}": parameter
        for section in PIPELINE_SECTIONS
        for name, parameter in getattr(scenario, section).param.objects("existing").items()
        if isinstance(parameter, Quantity | Count)
    }


PARAMETERS = drawable_parameters()
# A refusal may name any parameter of any section (a later stage may refuse too).
NAMES = {name for section in SECTIONS for name in getattr(Scenario(), section).param} - {"name"}
NAMED = re.compile(
    r"\b(?:" + "|".join(SECTIONS) + r"|Vehicle|Train|Track|Irregularity|Tunnel|Soil|Numerics|"
    r"LongTerm)\.(" + "|".join(sorted(NAMES)) + r")\b",
    re.IGNORECASE,
)


def _inner_bounds(parameter: param.Parameter) -> tuple[float, float]:
    """Closed interval of allowed values (an excluded end moved one ulp inside)."""
    (low, high), (low_in, high_in) = parameter.bounds, parameter.inclusive_bounds
    low = low if low_in else math.nextafter(low, math.inf)
    high = high if high_in else math.nextafter(high, -math.inf)
    return low, high


def values_within_bounds(parameter: param.Parameter) -> st.SearchStrategy:
    """Values across the hard bounds: endpoints, and log-uniform over decades or uniform."""
    low, high = _inner_bounds(parameter)
    if isinstance(parameter, Count):
        if low > 0 and high / low > 100:
            inner = st.floats(math.log(low), math.log(high)).map(
                lambda x: min(high, max(low, round(math.exp(x))))
            )
        else:
            inner = st.integers(low, high)
        values = st.one_of(st.sampled_from([low, high]), inner)
        return st.one_of(st.none(), values) if parameter.allow_None else values
    if low > 0 and high / low > 100:
        inner = st.floats(math.log(low), math.log(high)).map(
            lambda x: min(high, max(low, math.exp(x)))
        )
    else:
        inner = st.floats(low, high)
    return st.one_of(st.sampled_from([low, high]), inner)


@st.composite
def scenarios(draw, max_changed: int = 3) -> tuple[Scenario, dict]:
    """The base scenario with 1 to ``max_changed`` parameters drawn across their bounds."""
    paths = draw(
        st.lists(st.sampled_from(sorted(PARAMETERS)), min_size=1, max_size=max_changed, unique=True)
    )
    changes = {path: draw(values_within_bounds(PARAMETERS[path])) for path in paths}
    for path in draw(st.lists(st.sampled_from(CHOICES), max_size=1)):
        section, name = path.split(".")
        options = getattr(Scenario(), section).param[name]
        objects = options.objects if hasattr(options, "objects") else [True, False]
        changes[path] = draw(st.sampled_from(list(objects)))
    scenario = base_scenario()
    for path, value in changes.items():
        section, name = path.split(".")
        setattr(getattr(scenario, section), name, value)
    return scenario, changes


def check_property(scenario: Scenario, budget_s: float | None = RUN_BUDGET_S) -> tuple[str, str]:
    """Run the property on one scenario: the outcome ("ok", "refused", "too slow") and, for a
    refusal, the parameter it names.

    Raises AssertionError if the outcome is neither sound results nor a clear refusal.
    """
    try:
        scenario.validate()
        estimate = estimate_run(scenario)
        if budget_s is not None and estimate.total_seconds > budget_s:
            check_inputs(scenario)
            return "too slow", ""
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", SlowRunWarning)
            results = run(scenario)
    except (ValueError, SimulationError) as error:
        named = NAMED.search(str(error))
        assert named, f"refusal names no parameter: {error}"
        return "refused", named.group(0)
    soil, load = results.soil, results.load
    for name, array in [
        ("peak_disp_m", soil.peak_disp_m),
        ("disp_m", soil.disp_m),
        ("interface_psd", soil.interface_psd),
        ("load.psd", load.psd),
        ("block_force_N", results.vehicle_track.block_force_N),
    ]:
        assert np.all(np.isfinite(array)), f"{name} is not finite"
    peak = soil.peak_disp_m
    assert peak[0] > 0.0, f"peak at the invert {peak[0]:g} m is not positive"
    rise = np.diff(peak).max(initial=-np.inf)
    assert rise <= INVARIANT_TOLERANCE * peak[0], f"peak grows with depth by {rise:g} m"
    assert np.all(load.psd >= 0.0) and np.all(soil.interface_psd >= 0.0)
    assert not any("assumptions are broken" in text for text in results.warnings)
    return "ok", ""


@settings(
    max_examples=40,
    deadline=timedelta(seconds=30),
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow],
)
@given(scenarios())
def test_scenarios_within_bounds_give_sound_results_or_clear_refusals(drawn):
    """Tolerances: INVARIANT_TOLERANCE (1e-6 of the invert peak) on the growth with depth, the
    pipeline flag's own; every other check is exact (finite, > 0, ≥ 0)."""
    scenario, changes = drawn
    event(check_property(scenario)[0])
