"""Upload and input limits (dashboard/limits.py, issue 29 item 3): an oversized scenario, session or
profile file is refused before it is parsed, with its size and the limit."""

from __future__ import annotations

import pytest

from dashboard import limits, study_view
from dashboard.app import Dashboard
from dashboard.longterm_checks import DASHBOARD_MAX_DRAWS, SettlementBandPanel
from dashboard.longterm_view import CalibrationPanel
from dashboard.site_view import LayerTable
from dashboard.study_view import MAX_POINTS, MAX_SEEDS, StudyView
from dashboard.whatif_view import WhatIfPanel
from model.params import Scenario, Site
from model.pipeline import StageCache
from model.run_cost import estimate_run
from model.study.execution import SCHEDULER_ENV

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


def test_oversized_borehole_and_triaxial_csv_are_refused():
    table = LayerTable(site=Site())
    layers_before = list(table.site.layers)
    table.load_text("0" * (limits.BOREHOLE_CSV_BYTES + 1), "log.csv")
    assert "log.csv is 3.0 MB; the server accepts at most 3.0 MB" in table.message.object
    assert list(table.site.layers) == layers_before
    calibration = CalibrationPanel()
    calibration.load_text("0" * (limits.TRIAXIAL_CSV_BYTES + 1), "cyclic.csv")
    assert "cyclic.csv is 3.0 MB" in calibration.message.object and calibration.fit is None


TRIAXIAL_HEADER = "n_cycles,strain_percent,deviator_kPa,strength_kPa\n"
BINARY = bytes(range(256)) * 64  # holds NUL bytes, as binary files do
HUGE_FIELD = "9" * 200_000  # beyond the CSV reader's field limit (131 072), under 3 MB


@pytest.mark.parametrize(
    "content, message",
    [
        (BINARY, "data.csv: not a CSV text file (it holds NUL characters: binary data)"),
        (
            (TRIAXIAL_HEADER + f"1,{HUGE_FIELD},10,50\n").encode(),
            "data.csv: line 2 cannot be read as CSV (field larger than field limit",
        ),
    ],
)
def test_a_binary_or_huge_field_csv_upload_is_refused_in_one_line(content, message):
    """Python's CSV reader raised csv.Error out of the upload callbacks (issue 29)."""
    table = LayerTable(site=Site())
    layers_before = list(table.site.layers)
    table.upload.param.update(filename="data.csv", value=content)
    assert message in table.message.object and list(table.site.layers) == layers_before
    calibration = CalibrationPanel()
    calibration.file_input.param.update(filename="data.csv", value=content)
    assert message in calibration.message.object and calibration.fit is None


def test_study_counts_beyond_the_inputs_end_are_refused_by_the_server(cheap_scenario, monkeypatch):
    """A value set past an input's ``end`` (as a crafted websocket message sets it) is refused
    naming the input and its range; before, the server built the grid and ran the study."""
    started = []
    monkeypatch.setattr(study_view, "run_study", lambda *args, **kwargs: started.append(args))
    view = StudyView(scenario_source=cheap_scenario, threaded=False)
    for widget, end in ((view.first_points, MAX_POINTS), (view.seeds, MAX_SEEDS)):
        widget.value = end + 1
        refusal = f"{widget.label} = {end + 1} is outside the allowed range [1, {end}]"
        assert view.plan.object == f"Cannot start: {refusal}"
        view.start()
        assert view.status.object == f"**Not started:** {refusal}" and started == []
        widget.value = 1
    band = SettlementBandPanel(threaded=False)
    band.draws.value = DASHBOARD_MAX_DRAWS + 1
    with pytest.raises(ValueError, match=rf"^Draws = {DASHBOARD_MAX_DRAWS + 1} is outside"):
        band.counts()


def test_one_local_cluster_per_server_a_second_study_or_band_is_refused(
    cheap_scenario, monkeypatch
):
    """Each session's study or band started its own LocalCluster (a worker process per core),
    however many ran (issue 29): now one at a time per server; the others are refused, saying
    when to start again, and a shared scheduler is not limited."""
    monkeypatch.delenv(SCHEDULER_ENV, raising=False)
    studies = []

    def study_that_fails(*args, **kwargs):
        studies.append(args)
        raise RuntimeError("no study in this test")

    monkeypatch.setattr(study_view, "run_study", study_that_fails)
    other_session = limits.reserve_local_cluster(None)  # its study computes
    view = StudyView(scenario_source=cheap_scenario, threaded=False)
    view.start()
    assert view.status.object.startswith(
        "**Not started:** this server computes at most 1 study or settlement band at a time"
    )
    assert studies == [] and not view.running
    band = SettlementBandPanel(threaded=False)
    band._results = object()  # results on screen: the band's Start is live
    band.start()
    assert band.status.object.startswith("**Not started:** this server computes at most 1")
    release = limits.reserve_local_cluster("tcp://127.0.0.1:8786")  # a shared scheduler
    release()
    other_session()  # that study ended
    view.start()
    assert len(studies) == 1 and view.status.object == "**Study failed:** no study in this test"
    limits.reserve_local_cluster(None)()  # the view's study gave its cluster back


def test_a_run_estimated_beyond_the_servers_bound_is_refused_with_its_estimate(
    cheap_scenario, monkeypatch
):
    """A URL argument or an uploaded scenario that the run-cost model puts above the bound is
    not computed: the page says why and how to compute it."""
    board = Dashboard(scenario=cheap_scenario(), preset="single_bogie", cache=StageCache())
    seconds = estimate_run(board.scenario).total_seconds
    monkeypatch.setattr(limits, "SERVED_RUN_SECONDS", 0.5 * seconds)
    board.refresh()
    assert board.runs.results is None and board.messages.error_alert.visible
    text = board.messages.error_alert.object.replace("\\", "")
    assert f"estimated to take about {seconds:.0f} s" in text
    assert f"at most {0.5 * seconds:.0f} s" in text and "tunnelsettle run" in text
    monkeypatch.setattr(limits, "SERVED_RUN_SECONDS", 2.0 * seconds)
    board.refresh()
    assert board.runs.results is not None
