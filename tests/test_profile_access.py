"""Which profile files a run may read (issue 29's file-read hole), and profiles held by content.

One test per finding of the security walk; each failed before the fix:

- the hidden input ``irregularity.profile_csv`` could be set from a URL argument, a scenario
  file loaded in the dashboard and a what-if session file (pinned runs and the current
  scenario), and the run then opened any path the server could read;
- the error quoted the file's first line on the page;
- messages differed for files that exist and files that do not;
- a special file (``/proc/self/mem``) raised an uncaught OSError while the page was built.

The command line, run by the person who owns the files, still reads a path it is given.
"""

import json
import os
from pathlib import Path

import numpy as np
import pytest

from dashboard.app import Dashboard
from dashboard.whatif import load_session, read_session, save_session
from dashboard.whatif_view import WhatIfPanel
from model import cli
from model.params import DATA_DIR, Scenario
from model.params import measured_profile as mp
from model.pipeline import StageCache, run, stage_keys

SECRET = "s3cr3t-token-do-not-show"
EXAMPLE = DATA_DIR / "example_profile.csv"


@pytest.fixture(scope="module")
def cache():
    return StageCache()


@pytest.fixture
def secret_file(tmp_path):
    """A server file outside any data folder, whose first line must never reach a page."""
    path = tmp_path / "outside" / "secret.txt"
    path.parent.mkdir()
    path.write_text(f"{SECRET}\nx_m,eta_m\n", encoding="utf-8")
    return path


@pytest.fixture
def data_dir(tmp_path, monkeypatch):
    """A configured data folder holding the example profile as ``track.csv``."""
    folder = tmp_path / "data"
    folder.mkdir()
    (folder / "track.csv").write_bytes(EXAMPLE.read_bytes())
    monkeypatch.setenv(mp.DATA_DIR_ENV, str(folder))
    return folder


def _page_text(board: Dashboard) -> str:
    """Everything the page's messages say."""
    alerts = (board.messages.error_alert, board.messages.warning_alert)
    return " ".join(str(a.object) for a in alerts).replace("\\", "")


def _scenario_with(profile: str, cheap=True) -> dict:
    """Scenario data (the cheap scenario's) naming a profile path."""
    scenario = Scenario.preset("single_bogie")
    if cheap:
        scenario.numerics.n_depths = 11
    data = scenario.to_dict()
    data["irregularity"]["profile_csv"] = profile
    return data


# ---- URL arguments -------------------------------------------------------------------------
@pytest.mark.parametrize(
    "profile", ["/proc/self/environ", "../../../../../../etc/passwd", "/etc/passwd"]
)
def test_a_url_argument_cannot_make_the_server_read_a_file(cache, profile):
    board = Dashboard.from_query(
        {"preset": [b"single_bogie"], "irregularity.profile_csv": [profile.encode()]},
        cache=cache,
    )
    assert board.scenario.irregularity.profile_csv is None
    assert board.scenario.irregularity.profile_data is None
    text = _page_text(board)
    assert "not a profile file of this server's data folder" in text
    assert "root:" not in text and "PATH=" not in text


def test_a_url_argument_naming_a_secret_file_never_shows_its_contents(cache, secret_file):
    board = Dashboard.from_query(
        {"preset": [b"single_bogie"], "irregularity.profile_csv": [str(secret_file).encode()]},
        cache=cache,
    )
    board.refresh()  # the run uses the synthetic profile; nothing is read
    assert SECRET not in _page_text(board)
    assert board.runs.results is not None


def test_existing_and_missing_files_outside_the_data_folder_get_the_same_message(
    cache, secret_file, data_dir
):
    missing = secret_file.with_name("missing.txt")
    texts = []
    for path in (secret_file, missing):
        board = Dashboard.from_query(
            {"preset": [b"single_bogie"], "irregularity.profile_csv": [str(path).encode()]},
            cache=cache,
        )
        texts.append(_page_text(board).replace(repr(str(path)), "<name>"))
    assert texts[0] == texts[1]
    # a folder, devices, a missing name inside the folder: the same refusal again
    for name in (str(secret_file.parent), "/dev/null", "/dev/zero", "nothing.csv"):
        with pytest.raises(ValueError) as refused:
            mp.read_profile_in_folder(name, data_dir)
        assert str(refused.value).replace(repr(name), "<name>") in texts[0]


def test_a_special_file_is_refused_cleanly_while_the_page_is_built(cache):
    """Before the fix ``/proc/self/mem`` raised OSError out of the stage key, while the page
    was built (show_cached) and every time the inputs changed."""
    board = Dashboard.from_query(
        {"preset": [b"single_bogie"], "irregularity.profile_csv": [b"/proc/self/mem"]},
        cache=cache,
    )
    board.runs.show_cached()
    board.refresh()
    assert "not a profile file" in _page_text(board)


def test_the_stage_key_never_raises_for_an_unreadable_profile_file():
    scenario = Scenario.preset("single_bogie")
    scenario.irregularity.profile_csv = "/proc/self/mem"
    keys = stage_keys(scenario)  # the run itself says why it cannot read the file
    assert '"profile_digest": null' in keys["vehicle_track"]
    with pytest.raises(ValueError, match=r"^/proc/self/mem: cannot read the profile file"):
        run(scenario)


# ---- files loaded in the dashboard ---------------------------------------------------------
def test_a_loaded_scenario_file_cannot_name_a_server_file(cache, secret_file):
    board = Dashboard(scenario=Scenario.preset("single_bogie"), cache=cache)
    before = board.scenario.to_json()
    content = json.dumps(_scenario_with(str(secret_file))).encode()
    board.inputs.load_input.param.update(filename="evil.json", value=content)
    text = _page_text(board)
    assert "Could not load evil.json" in text and "not a profile file" in text
    assert SECRET not in text
    assert board.scenario.to_json() == before


def _session_file(pinned: str | None, current: str | None) -> str:
    """A session file whose pinned run and current scenario name the given paths."""
    base = Scenario.preset("single_bogie")
    base.numerics.n_depths = 11
    data = json.loads(save_session(_empty_session(), current=base))
    data["runs"] = [
        {
            "name": "evil",
            "visible": True,
            "colour": "#E69F00",
            "scenario": _scenario_with(pinned) if pinned else base.to_dict(),
        }
    ]
    data["current"] = _scenario_with(current) if current else base.to_dict()
    return json.dumps(data)


def _empty_session():
    from dashboard.whatif import WhatIfSession

    return WhatIfSession()


@pytest.mark.parametrize("where", ["pinned", "current"])
def test_a_session_file_cannot_name_a_server_file(secret_file, where):
    paths = {"pinned": str(secret_file), "current": None}
    if where == "current":
        paths = {"pinned": None, "current": str(secret_file)}
    text = _session_file(**paths)
    computed = []
    with pytest.raises(ValueError, match="not a profile file") as refused:
        load_session(text, compute=lambda scenario: computed.append(scenario))
    assert SECRET not in str(refused.value)
    assert computed == []  # refused before anything is computed


def test_the_session_panel_reports_the_refusal_without_the_contents(secret_file):
    restored = []
    panel = WhatIfPanel(current=lambda: (Scenario.paper(), None), restore=restored.append)
    content = _session_file(pinned=None, current=str(secret_file)).encode()
    panel.load_input.param.update(filename="evil.json", value=content)
    assert "not a profile file" in panel.message.object and SECRET not in panel.message.object
    assert restored == []


def test_a_scenario_holding_a_path_is_not_computed_by_the_dashboard(cache, secret_file):
    """The last guard: a scenario that reached a session's runs with a path is refused."""
    scenario = Scenario.preset("single_bogie")
    scenario.numerics.n_depths = 11
    scenario.irregularity.profile_csv = str(secret_file)
    board = Dashboard(scenario=scenario, cache=cache)
    board.refresh()
    text = _page_text(board)
    assert "not a profile file" in text and SECRET not in text
    assert board.runs.results is None


# ---- the data folder -----------------------------------------------------------------------
def test_a_name_in_the_data_folder_is_read_into_the_scenario(cache, data_dir):
    board = Dashboard.from_query(
        {
            "preset": [b"single_bogie"],
            "numerics.n_depths": [b"11"],
            "irregularity.profile_csv": [b"track.csv"],
        },
        cache=cache,
    )
    irregularity = board.scenario.irregularity
    assert irregularity.profile_csv is None  # held by content from here on
    assert irregularity.profile_data == EXAMPLE.read_text(encoding="utf-8")
    board.refresh()
    reference = Scenario.preset("single_bogie")
    reference.numerics.n_depths = 11
    reference.irregularity.profile_csv = str(EXAMPLE)  # the command line's way: by path
    np.testing.assert_array_equal(
        board.runs.results.soil.peak_disp_m, run(reference).soil.peak_disp_m
    )


@pytest.mark.parametrize("escape", ["../outside/secret.txt", "link.csv", "sub/../../outside"])
def test_no_name_leaves_the_data_folder(data_dir, secret_file, escape):
    (data_dir / "link.csv").symlink_to(secret_file)
    with pytest.raises(ValueError, match="not a profile file of this server's data folder"):
        mp.read_profile_in_folder(escape, data_dir)


def test_an_absolute_path_inside_the_data_folder_is_accepted(data_dir):
    text = mp.read_profile_in_folder(str(data_dir / "track.csv"), data_dir)
    assert text == EXAMPLE.read_text(encoding="utf-8")


def test_a_malformed_file_in_the_data_folder_names_the_line_not_its_text(data_dir):
    (data_dir / "bad.csv").write_text(f"x_m,eta_m\n0,{SECRET}\n", encoding="utf-8")
    with pytest.raises(ValueError, match=r"^bad.csv, line 2: the values are not two numbers$"):
        mp.read_profile_in_folder("bad.csv", data_dir)


def test_without_a_data_folder_every_name_is_refused(monkeypatch):
    monkeypatch.delenv(mp.DATA_DIR_ENV, raising=False)
    assert mp.data_folder() is None
    with pytest.raises(ValueError, match=r"\(none is configured\)"):
        mp.read_profile_in_folder("track.csv", None)


# ---- the command line still reads what it is given --------------------------------------------
def test_the_command_line_reads_a_profile_path_it_is_given(tmp_path, capsys):
    out = tmp_path / "out"
    code = cli.main(
        [
            "--preset",
            "single_bogie",
            "--set",
            f"irregularity.profile_csv={EXAMPLE}",
            "--set",
            "numerics.n_depths=11",
            "--out",
            str(out),
            "--quiet",
        ]
    )
    assert code == 0
    assert json.loads((out / "scenario.json").read_text())["irregularity"]["profile_csv"] == str(
        EXAMPLE
    )


def test_the_command_line_refuses_a_special_file_cleanly(tmp_path, capsys):
    with pytest.raises(SystemExit) as exited:
        cli.main(
            [
                "--preset",
                "single_bogie",
                "--set",
                "irregularity.profile_csv=/proc/self/mem",
                "--out",
                str(tmp_path / "out"),
                "--quiet",
            ]
        )
    assert exited.value.code == 2
    assert "/proc/self/mem: cannot read the profile file" in capsys.readouterr().err


def test_a_fifo_is_refused_without_waiting_for_a_writer(tmp_path):
    fifo = tmp_path / "pipe.csv"
    os.mkfifo(fifo)
    with pytest.raises(ValueError, match="not a regular file"):
        mp.read_profile_file(fifo)


def test_profile_errors_never_quote_the_file(tmp_path):
    from model.track.irregularity import load_profile_csv

    for text in (f"{SECRET}\n0,1\n", f"x_m,eta_m\n0,1\n{SECRET},2\n", f"x_m,eta_m\n0,1,{SECRET}\n"):
        path = tmp_path / "p.csv"
        path.write_text(text, encoding="utf-8")
        with pytest.raises(ValueError) as refused:
            load_profile_csv(path)
        assert SECRET not in str(refused.value)


# ---- profiles uploaded through the browser ------------------------------------------------------
def test_an_uploaded_profile_is_held_by_content(cache, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    scenario = Scenario.preset("single_bogie")
    scenario.numerics.n_depths = 11
    board = Dashboard(scenario=scenario, cache=cache)
    other = Dashboard(scenario=Scenario.preset("single_bogie"), cache=cache)
    board.inputs.profile.upload.param.update(filename="track.csv", value=EXAMPLE.read_bytes())
    irregularity = board.scenario.irregularity
    assert irregularity.profile_csv is None and irregularity.profile_data is not None
    assert list(tmp_path.iterdir()) == []  # nothing written on the server
    assert other.scenario.irregularity.profile_data is None  # another session sees nothing
    board.refresh()
    reference = scenario.copy()
    reference.irregularity.profile_data = None
    reference.irregularity.profile_csv = str(EXAMPLE)
    np.testing.assert_array_equal(
        board.runs.results.soil.peak_disp_m, run(reference).soil.peak_disp_m
    )
    assert "measured, 321 points" in board.inputs.profile.note.object
    saved = Scenario.from_json(board.inputs._scenario_file().getvalue())
    assert saved.irregularity.profile_data == irregularity.profile_data  # goes with the file
    board.inputs.profile.use_synthetic()
    assert board.scenario.irregularity.profile_data is None


def test_a_session_file_carries_an_uploaded_profile(base_results):
    scenario = base_results.scenario
    scenario.irregularity.profile_data = EXAMPLE.read_text(encoding="utf-8")
    data = json.loads(save_session(_empty_session(), current=scenario))
    loaded = read_session(json.dumps(data))
    assert loaded.current.irregularity.profile_data == scenario.irregularity.profile_data


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (b"x_m,eta_m\n" + b"0,0\n" * (mp.MAX_PROFILE_BYTES // 4), "MB allowed"),
        (b"x_m,eta_m\n0,0\n1,\xff\n", "not UTF-8"),
        (b"x,eta\n0,0\n1,1\n", "line 1: the header must be"),
    ],
)
def test_a_bad_upload_is_refused_with_a_clear_message(cache, content, message):
    board = Dashboard(scenario=Scenario.preset("single_bogie"), cache=cache)
    board.inputs.profile.upload.param.update(filename="up.csv", value=content)
    assert message in _page_text(board) and "up.csv" in _page_text(board)
    assert board.scenario.irregularity.profile_data is None


def test_profile_text_and_path_together_are_inconsistent():
    scenario = Scenario.preset("single_bogie")
    scenario.irregularity.profile_data = EXAMPLE.read_text(encoding="utf-8")
    scenario.irregularity.profile_csv = str(EXAMPLE)
    with pytest.raises(ValueError, match="both set"):
        scenario.validate()


def test_a_malformed_profile_text_is_refused_at_assignment():
    scenario = Scenario.preset("single_bogie")
    with pytest.raises(ValueError, match=r"^irregularity.profile_data, line 2: "):
        scenario.update({"irregularity": {"profile_data": "x_m,eta_m\n0\n"}})
    assert scenario.irregularity.profile_data is None


def test_the_profile_of_the_cache_key_is_its_digest_not_its_text():
    scenario = Scenario.preset("single_bogie")
    scenario.irregularity.profile_data = EXAMPLE.read_text(encoding="utf-8")
    key = stage_keys(scenario)["vehicle_track"]
    assert (
        "x_m,eta" not in key and mp.parse_profile(scenario.irregularity.profile_data).digest in key
    )
    edited = scenario.copy()
    edited.irregularity.profile_data = scenario.irregularity.profile_data.replace("1", "2", 1)
    assert stage_keys(edited)["vehicle_track"] != key


def test_a_relative_data_folder_is_resolved(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv(mp.DATA_DIR_ENV, "data")
    assert mp.data_folder() == Path(tmp_path / "data").resolve()
