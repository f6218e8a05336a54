"""What the page reads of a run's :class:`~model.pipeline.Results` more than once, computed
once per Results and dropped with it.

``results.scenario`` parses the scenario's JSON anew on each call (6 ms on the paper case), and
``results.summary()`` parses it too: one run shown read the scenario seven times and its
summary twice (the key numbers, the what-if table).
"""

from __future__ import annotations

import weakref
from collections.abc import Callable
from typing import TypeVar

from model.params import Scenario
from model.pipeline import Results

Value = TypeVar("Value")

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
    """The scenario of ``results``, to read only (shared by every reader)."""
    return _once("scenario", results, lambda r: r.scenario)


def summary_of(results: Results) -> dict[str, float]:
    """:meth:`Results.summary` of ``results``, to read only (shared by every reader)."""
    return _once("summary", results, Results.summary)
