"""The what-if Panel component driven from Python, as the browser would drive its widgets.

A stand-in for the dashboard supplies ``current()``, ``restore()`` and a counting ``compute()``;
two cheap pipeline runs (differing only in the soil) serve as the runs to pin.
"""

import json
from concurrent.futures import Future

import pytest

from dashboard.whatif import CURRENT_LABEL, MAX_PINNED, PINNED_COLOURS, SESSION_FORMAT
from dashboard.whatif_view import WhatIfPanel
from model.params import Scenario
from model.pipeline import run


class FakeDashboard:
    """What the dashboard gives the component: its current run, restore and compute."""

    def __init__(self, results, cache):
        self.results, self.cache = results, cache
        self.scenario = results.scenario
        self.restored, self.computed = [], []

    def current(self):
        return self.scenario, self.results

    def restore(self, scenario):
        self.restored.append(scenario)
        self.scenario = scenario

    def compute(self, scenario):
        self.computed.append(scenario.to_json())
        return run(scenario, cache=self.cache)

    def panel(self):
        panel = WhatIfPanel(
            current=self.current,
            restore=self.restore,
            compute=self.compute,
            preset=lambda: "single_bogie",
        )
        self.events = []
        panel.param.watch(self.events.append, "overlays_changed")
        return panel


@pytest.fixture
def board(base_results, cache):
    return FakeDashboard(base_results, cache)


def _pin(panel, name=""):
    panel.name_input.value = name
    panel.pin_button.clicks += 1  # what a click in the browser does


def test_pin_names_by_difference_and_never_recomputes(board, stiff_results, monkeypatch):
    def no_run(*args, **kwargs):
        raise AssertionError("pinning must not run the pipeline")

    for module in ("model.pipeline", "dashboard.whatif", "dashboard.whatif_view"):
        monkeypatch.setattr(f"{module}.run", no_run)
    panel = board.panel()
    assert "Pin runs to compare" in panel.table.object
    _pin(panel)
    board.results, board.scenario = stiff_results, stiff_results.scenario  # the user moves on
    panel.refresh()
    _pin(panel, "stiff soil")
    session = panel.session
    # the cheap scenario differs from the single_bogie preset in speed and output depths
    assert session.names() == ["speed 100 km/h, output depths 11", "stiff soil"]
    assert session.runs[0].results is not stiff_results  # the first pin kept its own results
    assert panel.run_select.options == session.names()
    assert panel.run_select.value == "stiff soil"  # the controls act on the last pinned run
    listed = panel.runs_list.object
    assert listed.index("speed 100 km/h") < listed.index("stiff soil")
    assert PINNED_COLOURS[0] in listed and PINNED_COLOURS[1] in listed
    assert len(board.events) == 2 and board.computed == []
    assert panel.name_input.value == ""
    overlays = panel.overlays()
    assert [(n, c) for n, _, c in overlays] == [
        ("speed 100 km/h, output depths 11", PINNED_COLOURS[0]),
        ("stiff soil", PINNED_COLOURS[1]),
    ]
    table = panel.table.object
    assert "stiff soil" in table and CURRENT_LABEL in table and "Peak invert load" in table
    assert panel.reference_select.options == [*session.names(), CURRENT_LABEL]


def test_a_ninth_pin_is_refused_with_a_message(board):
    panel = board.panel()
    for k in range(MAX_PINNED):
        _pin(panel, f"run {k}")
    assert panel.pin_button.disabled
    panel._on_pin()  # even if the click got through
    assert panel.message.visible and f"at most {MAX_PINNED} runs" in panel.message.object
    assert len(panel.session.runs) == MAX_PINNED


def test_a_taken_name_is_refused_and_nothing_is_pinned(board):
    panel = board.panel()
    _pin(panel, "today")
    _pin(panel, "today")
    assert panel.message.visible and "already named" in panel.message.object
    assert panel.session.names() == ["today"] and len(board.events) == 1


def test_pin_before_any_result_gives_a_message():
    panel = WhatIfPanel(current=lambda: (Scenario.paper(), None), restore=lambda s: None)
    panel.pin_button.clicks += 1
    assert panel.message.visible and "no result to pin" in panel.message.object
    assert panel.session.runs == []


def test_rename_hide_restore_remove_from_the_list(board, stiff_results):
    panel = board.panel()
    _pin(panel, "today")
    board.results, board.scenario = stiff_results, stiff_results.scenario
    _pin(panel, "stiff")
    assert panel.run_select.value == "stiff" and panel.rename_input.value == "stiff"
    panel.rename_input.value = "stiff soil"
    assert panel.session.names() == ["today", "stiff soil"]
    assert panel.run_select.value == "stiff soil"
    panel.rename_input.value = "today"  # taken: refused, the old name is shown again
    assert panel.message.visible and panel.rename_input.value == "stiff soil"
    panel.run_select.value = "today"
    assert panel.rename_input.value == "today" and panel.shown_checkbox.value
    panel.shown_checkbox.value = False
    assert [n for n, _, _ in panel.overlays()] == ["stiff soil"]
    assert "today" in panel.table.object  # hidden from the plots, still compared
    assert "(hidden)" in panel.runs_list.object
    panel.restore_button.clicks += 1
    assert board.restored[-1].to_json() == panel.session.get("today").scenario_json
    panel.remove_button.clicks += 1
    assert panel.session.names() == ["stiff soil"] and panel.run_select.options == ["stiff soil"]
    assert panel.run_select.value == "stiff soil" and panel.run_controls.visible
    assert len(board.events) == 2 + 1 + 1 + 1  # pins, rename, hide, remove (restore: none)


def test_reference_selector_changes_the_differences(board, stiff_results):
    panel = board.panel()
    _pin(panel, "today")
    board.results, board.scenario = stiff_results, stiff_results.scenario
    panel.refresh()
    assert panel.reference_select.value == "today"
    by_today = panel.table.object
    panel.reference_select.value = CURRENT_LABEL
    assert panel.session.reference == CURRENT_LABEL
    assert panel.table.object != by_today
    expected = panel.session.comparison(stiff_results)
    assert expected.loc[CURRENT_LABEL].filter(like="Δ").abs().max() == 0.0


def test_session_save_and_load_round_trip(board, stiff_results, cache, base_results):
    panel = board.panel()
    _pin(panel, "today")
    board.results, board.scenario = stiff_results, stiff_results.scenario
    _pin(panel, "stiff soil")
    panel.run_select.value = "today"
    panel.shown_checkbox.value = False
    panel.reference_select.value = "stiff soil"
    saved = panel.save_button.callback().getvalue()
    assert json.loads(saved)["format"] == SESSION_FORMAT

    other = FakeDashboard(base_results, cache)  # a fresh page: nothing pinned, another current
    fresh = other.panel()
    fresh.load_input.param.update(filename="s.json", value=saved.encode("utf-8"))
    assert not fresh.message.visible
    assert other.computed == [base_results.scenario_json, stiff_results.scenario_json]
    assert other.restored[-1].to_json() == stiff_results.scenario_json  # the saved current
    assert fresh.session.names() == ["today", "stiff soil"]
    assert [run.visible for run in fresh.session.runs] == [False, True]
    assert fresh.runs_list.object == panel.runs_list.object
    assert fresh.reference_select.value == "stiff soil"
    other.results = stiff_results  # the dashboard re-ran the restored scenario
    fresh.refresh()
    assert fresh.table.object == panel.table.object  # the same table
    assert len(other.events) == 1


class HeldExecutor:
    """An executor that holds every job until the test runs it."""

    def __init__(self):
        self.jobs = []

    def submit(self, function, *args):
        future = Future()
        self.jobs.append((future, function, args))
        return future

    def run_all(self):
        while self.jobs:
            future, function, args = self.jobs.pop(0)
            future.set_result(function(*args))


def test_a_loaded_sessions_runs_compute_in_the_executor_not_the_event_loop(
    board, stiff_results, cache, base_results
):
    """Up to 8 runs of a loaded session were computed inside the load callback, holding the
    session's event loop (issue 29): served, they go to the executor like other runs."""
    panel = board.panel()
    _pin(panel, "today")
    saved = panel.save_button.callback().getvalue().encode("utf-8")
    other, executor = FakeDashboard(base_results, cache), HeldExecutor()
    fresh = WhatIfPanel(
        current=other.current,
        restore=other.restore,
        compute=other.compute,
        threaded=True,
        executor=executor,
    )
    fresh.load_input.param.update(filename="s.json", value=saved)
    assert other.computed == [] and fresh.session.runs == [] and len(executor.jobs) == 1
    assert fresh.load_input.disabled
    executor.run_all()  # not served: the outcome is shown at once
    assert other.computed == [base_results.scenario_json]
    assert fresh.session.names() == ["today"] and not fresh.load_input.disabled
    closed = WhatIfPanel(
        current=other.current, restore=other.restore, threaded=True, executor=executor
    )
    closed.load_input.param.update(filename="s.json", value=saved)
    closed._release(None)  # the tab was closed while its session loaded
    executor.run_all()
    assert closed.session.runs == []


@pytest.mark.parametrize(
    "content, message",
    [
        (b"{not json", "not valid JSON"),
        (Scenario.paper().to_json().encode(), "format tag"),
        (json.dumps({"format": SESSION_FORMAT, "version": 7}).encode(), "version 7"),
    ],
)
def test_a_bad_session_file_is_refused_and_changes_nothing(board, content, message):
    panel = board.panel()
    _pin(panel, "today")
    panel.load_input.param.update(filename="bad.json", value=content)
    assert panel.message.visible
    assert "Could not load bad.json as a session" in panel.message.object
    assert message in panel.message.object
    assert panel.session.names() == ["today"] and board.computed == [] and board.restored == []


def test_report_download_holds_the_table_and_the_overlays(board, stiff_results):
    panel = board.panel()
    assert panel.report_button.disabled and panel.save_button.disabled
    _pin(panel, "today")
    board.results = stiff_results
    report = panel.report_button.callback().getvalue().decode("utf-8")
    assert report.startswith("<!DOCTYPE html>")
    assert "what-if session" in report and "today" in report and CURRENT_LABEL in report


def test_two_panels_share_nothing_and_closing_releases_the_runs(board, base_results, cache):
    first = board.panel()
    second = FakeDashboard(base_results, cache).panel()
    _pin(first, "mine")
    assert second.session.runs == [] and second.overlays() == []
    assert first.session is not second.session
    first._release(None)  # what the server calls when the browser session closes
    assert first.session.runs == [] and first.runs_list.object == ""
    assert first.run_select.options == []
