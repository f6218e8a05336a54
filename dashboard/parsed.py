"""What the page reads of a run's :class:`~model.pipeline.Results` more than once, computed
once: the summary once per Results (dropped with it), the scenario once per inputs.

``results.scenario`` parses the scenario's JSON anew on each call (6 ms on the paper case), and
``results.summary()`` parses it too: one run shown read the scenario seven times and its
summary twice (the key numbers, the what-if table). The last few parsed scenarios are kept by
their JSON text, so the results of the same inputs share one.
"""

from __future__ import annotations

import functools
import weakref
from collections.abc import Callable
from typing import TypeVar

from model.params import Scenario
from model.pipeline import Results

Value = TypeVar("Value")

SCENARIOS_KEPT = 8
"""Parsed scenarios kept (the least recently read is dropped first)."""

_VALUES: dict[tuple[str, int], object] = {}
"""Computed values by (what, id of their Results), each dropped with its Results."""


def _once(what: str, results: Results, compute: Callable[[Results], Value]) -> Value:
    """``compute(results)``, computed once per Results under the name ``what``."""
    key = (what, id(results))
    if key not in _VALUES:
        _VALUES[key] = compute(results)
        weakref.finalize(results, _VALUES.pop, key, None)
    return _VALUES[key]


def scenario_of(results: Results) -> Scenario:
    """The scenario of ``results``, to read only (shared by every reader, and by the results of
    the same inputs: the first stages' results drawn early and the whole run's)."""
    return _parsed(results.scenario_json)


@functools.lru_cache(maxsize=SCENARIOS_KEPT)
def _parsed(scenario_json: str) -> Scenario:
    """The scenario of a JSON text, parsed once for all readers."""
    return Scenario.from_json(scenario_json)


def summary_of(results: Results) -> dict[str, float]:
    """:meth:`Results.summary` of ``results``, to read only (shared by every reader)."""
    return _once("summary", results, lambda r: r.summary(scenario_of(r)))
