"""Two dashboard sessions of one server, built in-process as ``panel serve`` builds them (one
:class:`Dashboard` per session, one shared stage cache): what one user uploads, pins or studies
is invisible to the other (issue 29, item 2)."""

from __future__ import annotations

import pytest
from test_study_view import _in_process_study

from dashboard import study_view
from dashboard.app import Dashboard
from model.params import DATA_DIR


@pytest.fixture
def sessions(cache, cheap_scenario, monkeypatch):
    """Two sessions on the server's shared stage cache, each with the results of its inputs;
    studies computed in this process."""
    monkeypatch.setattr(study_view, "run_study", _in_process_study)
    boards = []
    for _ in range(2):
        board = Dashboard(scenario=cheap_scenario(), preset="single_bogie", cache=cache)
        board.study.threaded = False
        board.refresh()
        boards.append(board)
    return boards


def test_one_sessions_uploads_pins_and_study_are_invisible_to_another(sessions):
    mine, other = sessions
    other_scenario = other.scenario.to_json()
    profile = (DATA_DIR / "example_profile.csv").read_bytes()
    mine.inputs.profile.upload.param.update(filename="track.csv", value=profile)
    borehole = (DATA_DIR / "borehole_example.csv").read_bytes()
    mine.longterm.layers.upload.param.update(filename="log.csv", value=borehole)
    triaxial = (DATA_DIR / "triaxial_synthetic.csv").read_bytes()
    mine.longterm.calibration.file_input.param.update(filename="cyclic.csv", value=triaxial)
    mine.whatif.name_input.value = "mine"
    mine.whatif.pin_button.clicks += 1
    mine.study.seeds.value = mine.study.first_points.value = 1
    mine.study.start()
    # each upload, the pin and the study took effect in my session ...
    assert mine.scenario.irregularity.profile_data is not None
    assert len(mine.scenario.site.layers) > 1 and mine.longterm.calibration.fit is not None
    assert mine.whatif.session.names() == ["mine"] and len(mine.study.table) == 1
    # ... and nowhere in the other
    assert other.scenario.to_json() == other_scenario
    assert other.longterm.calibration.fit is None and other.longterm.calibration.data is None
    assert other.whatif.session.runs == [] and other.whatif.overlays() == []
    assert other.whatif.run_select.options == [] and other.whatif.runs_list.object == ""
    assert other.study.table is None and other.study.status.object == ""
    assert "mine" not in other.whatif.save_button.callback().getvalue()
