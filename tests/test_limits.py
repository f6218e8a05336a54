"""Upload limits (dashboard/limits.py, issue 29 item 3): an oversized scenario, session or
profile file is refused before it is parsed, with its size and the limit."""

from __future__ import annotations

from dashboard import limits
from dashboard.app import Dashboard
from dashboard.whatif_view import WhatIfPanel
from model.params import Scenario
from model.pipeline import StageCache

OVERSIZED_JSON = b" " * (limits.SESSION_JSON_BYTES + 1)  # valid JSON whitespace, too large


def test_an_oversized_session_file_is_refused_with_its_size():
    restored = []
    panel = WhatIfPanel(current=lambda: (Scenario.paper(), None), restore=restored.append)
    panel.load_input.param.update(filename="big.json", value=OVERSIZED_JSON)
    assert "big.json is 2.0 MB; the server accepts at most 2.0 MB" in panel.message.object
    assert restored == []


def test_an_oversized_scenario_file_and_profile_are_refused():
    board = Dashboard(scenario=Scenario.preset("single_bogie"), cache=StageCache())
    before = board.scenario.to_json()
    board.inputs.load_input.param.update(filename="big.json", value=OVERSIZED_JSON)
    assert "big.json is 2.0 MB" in str(board.messages.error_alert.object)
    board.inputs.profile.load(b"0" * (limits.PROFILE_CSV_BYTES + 1), "track.csv")
    alert = str(board.messages.error_alert.object)
    assert "track.csv is 12.0 MB; the server accepts at most 12.0 MB" in alert
    assert board.scenario.to_json() == before
    assert board.scenario.irregularity.profile_data is None
