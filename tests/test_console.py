"""The ``tunnelsettle`` console script and ``python -m model`` (issue 30): every subcommand listed
and reached, ``band`` registered for the module to come, ``serve`` pointing at the installed app,
the shipped samples named by ``sample``, and a refused FE mesh setting that says why."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import pytest

from dashboard import console, serve
from model import commands
from model.params import Scenario
from model.scenarios import SAMPLE_SCENARIO_FILE, named_file

ROOT = Path(__file__).resolve().parent.parent
ALL_SUBCOMMANDS = ("run", "study", "fe", "band", "export", "serve")


def test_tunnelsettle_help_lists_every_subcommand(capsys):
    assert console.main(["--help"]) == 0
    out = capsys.readouterr().out
    for name in ALL_SUBCOMMANDS:
        assert f"\n  {name} " in out, name
    assert tuple(console.SUBCOMMANDS) == ALL_SUBCOMMANDS


def test_the_installed_script_runs(tmp_path):
    """The console script of this environment, from another folder."""
    script = Path(sys.executable).parent / "tunnelsettle"
    done = subprocess.run(
        [str(script), "--help"], cwd=tmp_path, capture_output=True, text=True, check=True
    )
    assert all(f"\n  {name} " in done.stdout for name in ALL_SUBCOMMANDS)


def test_help_answers_without_loading_the_numerical_stack():
    """``tunnelsettle --help`` imports the standard library only, not NumPy, Numba or Panel."""
    probe = (
        "import sys; from dashboard import console; console.help_text(); "
        "print(sorted({'numpy', 'numba', 'scipy', 'panel'} & set(sys.modules)))"
    )
    done = subprocess.run(
        [sys.executable, "-c", probe], cwd=ROOT, capture_output=True, text=True, check=True
    )
    assert done.stdout.strip() == "[]"


def test_python_m_model_help_lists_its_subcommands():
    done = subprocess.run(
        [sys.executable, "-m", "model", "--help"], capture_output=True, text=True, check=True
    )
    for name in ("study", "fe", "band"):
        assert f"\n  {name} " in done.stdout, name
    assert "--preset" in done.stdout  # and the single run's own options


def test_the_console_script_is_declared_in_pyproject():
    text = (ROOT / "pyproject.toml").read_text(encoding="utf-8")
    assert 'tunnelsettle = "dashboard.console:main"' in text


@pytest.mark.parametrize("name", list(ALL_SUBCOMMANDS))
def test_each_subcommand_reaches_its_own_parser_under_its_name(name, capsys):
    with pytest.raises(SystemExit) as info:
        console.main([name, "--help"])
    assert info.value.code == 0
    assert capsys.readouterr().out.startswith(f"usage: tunnelsettle {name}")


def test_no_or_an_unknown_subcommand_is_refused_with_the_list(capsys):
    assert console.main([]) == 2
    assert "run" in capsys.readouterr().err
    assert console.main(["simulate"]) == 2
    err = capsys.readouterr().err
    assert "unknown subcommand 'simulate'" in err and "serve" in err


def test_band_is_registered_with_its_command_line_module():
    """The settlement band (issue 25) plugs in as model.study.band_cli with main(argv, prog)."""
    band = commands.MODEL_SUBCOMMANDS["band"]
    assert console.SUBCOMMANDS["band"] is band and band.module == "model.study.band_cli"
    assert band.available


def test_a_registered_module_gets_the_arguments_and_the_program_name(monkeypatch):
    """What the band module will receive: the remaining arguments and its program name."""
    seen = []
    fake = type(sys)("fake_band")
    fake.main = lambda argv, prog: seen.append((argv, prog)) or 0
    monkeypatch.setitem(sys.modules, "fake_band", fake)
    monkeypatch.setattr(importlib.util, "find_spec", lambda name: name == "fake_band" or None)
    monkeypatch.setitem(console.SUBCOMMANDS, "band", commands.Subcommand("fake_band", "band"))
    assert console.main(["band", "--seeds", "20"]) == 0
    assert seen == [(["--seeds", "20"], "tunnelsettle band")]


def test_serve_runs_panel_on_the_installed_app_with_warm_port_address_and_extras():
    app = serve.app_path()
    assert app == Path(importlib.util.find_spec("dashboard.app").origin) and app.is_file()
    args, extra = serve.build_parser().parse_known_args(
        ["--port", "5010", "--address", "0.0.0.0", "--allow-websocket-origin", "h:5010"]
    )
    command = serve.serve_command(args, extra)
    assert command[:3] == ["panel", "serve", str(app)]
    assert command[3:] == [
        "--port",
        "5010",
        "--address",
        "0.0.0.0",
        "--warm",
        "--allow-websocket-origin",
        "h:5010",
    ]
    args, extra = serve.build_parser().parse_known_args(["--no-warm"])
    assert "--warm" not in serve.serve_command(args, extra)


def test_sample_names_the_shipped_files_unless_such_a_file_exists(tmp_path, monkeypatch):
    from dashboard.whatif import SAMPLE_SESSION_FILE, read_session

    assert named_file(Path("sample"), SAMPLE_SCENARIO_FILE) == SAMPLE_SCENARIO_FILE
    monkeypatch.chdir(tmp_path)
    (tmp_path / "sample").write_text("{}")
    assert named_file(Path("sample"), SAMPLE_SCENARIO_FILE) == Path("sample")
    scenario = Scenario.from_file(SAMPLE_SCENARIO_FILE)
    scenario.validate()  # its profile, named relative to the file, is found
    assert Path(scenario.irregularity.profile_csv).is_file()
    session = read_session(SAMPLE_SESSION_FILE.read_text(encoding="utf-8"))
    assert [run.name for run in session.runs] == ["paper", "soil E = 12 MPa", "2.5D moving load"]


@pytest.mark.parametrize(
    ("argument", "value"),
    [("--element-size", "0"), ("--element-size", "-1"), ("--outer-radius", "nan")],
)
def test_fe_refuses_an_impossible_mesh_setting_before_running_saying_why(argument, value, capsys):
    from model.fe.cli import main

    with pytest.raises(SystemExit) as info:
        main([argument, value, "--out", "unused"], prog="tunnelsettle fe")
    assert info.value.code == 2
    err = capsys.readouterr().err.splitlines()[-1]
    assert err.startswith(f"tunnelsettle fe: error: argument {argument}: '{value}'")
    assert "a length > 0 m" in err and "needs elements" not in err


def test_a_missing_session_file_is_refused_naming_it(tmp_path, capsys):
    """``export --session`` of a file that is not there: the option and the file, no errno text."""
    missing = tmp_path / "nosuch.json"
    with pytest.raises(SystemExit) as exit_info:
        console.main(["export", "--session", str(missing), "--out", str(tmp_path / "r.html")])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert f"--session {missing}: cannot read the session file (No such file" in err
    assert "Errno" not in err


def test_an_unknown_parameter_path_is_named_in_one_voice():
    """--set, the study's --vary and the URL name an unknown path the same way."""
    scenario = Scenario.paper()
    for path, expected in (
        ("train.speed", "unknown parameter 'train.speed'; train has: n_cars, speed_kmh"),
        ("trian.speed_kmh", "unknown parameter 'trian.speed_kmh': a parameter is section."),
        ("speed_kmh", "unknown parameter 'speed_kmh': a parameter is section.parameter"),
    ):
        with pytest.raises(KeyError) as error:
            scenario.set_value(path, "60")
        assert error.value.args[0].startswith(expected)
