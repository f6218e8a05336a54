"""What the page reads of a run's :class:`~model.pipeline.Results` more than once, computed
once per Results and dropped with it.

``results.scenario`` parses the scenario's JSON anew on each call (6 ms on the paper case), and
``results.summary()`` parses it too: one run shown read the scenario seven times and its
summary twice (the key numbers, the what-if table). A parsed scenario is kept by its JSON text,
so the results of the same inputs share it.
"""

from __future__ import annotations

import threading
import weakref
from collections import OrderedDict
from collections.abc import Callable
from typing import TypeVar

from model.params import Scenario
from model.pipeline import Results

Value = TypeVar("Value")

SCENARIOS_KEPT = 8
"""Parsed scenarios kept, the most recently read first dropped last."""

_VALUES: dict[tuple[str, int], object] = {}
"""Computed values by (what, id of their Results), each dropped with its Results."""
_SCENARIOS: OrderedDict[str, Scenario] = OrderedDict()
"""Parsed scenarios by their JSON text: the first stages' results drawn early and the whole
run's results share one (:meth:`dashboard.runs.SessionRuns._show_early`)."""
_SCENARIOS_LOCK = threading.Lock()


def _once(what: str, results: Results, compute: Callable[[Results], Value]) -> Value:
    """``compute(results)``, computed once per Results under the name ``what``."""
    key = (what, id(results))
    if key not in _VALUES:
        _VALUES[key] = compute(results)
        weakref.finalize(results, _VALUES.pop, key, None)
    return _VALUES[key]


def scenario_of(results: Results) -> Scenario:
    """The scenario of ``results``, to read only (shared by every reader)."""
    text = results.scenario_json
    with _SCENARIOS_LOCK:
        scenario = _SCENARIOS.get(text)
        if scenario is not None:
            _SCENARIOS.move_to_end(text)
            return scenario
    scenario = Scenario.from_json(text)
    with _SCENARIOS_LOCK:
        _SCENARIOS[text] = scenario
        while len(_SCENARIOS) > SCENARIOS_KEPT:
            _SCENARIOS.popitem(last=False)
    return scenario


def summary_of(results: Results) -> dict[str, float]:
    """:meth:`Results.summary` of ``results``, to read only (shared by every reader)."""
    return _once("summary", results, lambda r: r.summary(scenario_of(r)))
