"""The README's commands work as written (issue 30), and the docs state ranges as declared.

Every command of the README's ``bash`` blocks is read: the set-up steps must be the two commands
CI runs, and every ``tunnelsettle`` command must parse with its subcommand's own parser, its
scenario (preset, file or sample, with the ``--set`` overrides) must load and validate, and a
session it names must be a valid session file. The cheap ones (up to three paper-case runs) are
also run, in a temporary folder, as a new user would type them. The study (180 runs) and the FE
check (three plastic passages, minutes each) are only parsed: their code is run by their own
tests. The headless Python example runs too.
"""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import pytest

from dashboard import console
from dashboard.console import SUBCOMMANDS
from model.cli import load_scenario
from model.params import SECTIONS, Scenario
from model.params.quantities import _format_range, split_label

ROOT = Path(__file__).resolve().parent.parent
README = (ROOT / "README.md").read_text(encoding="utf-8")
BLOCKS = re.findall(r"```(\w+)\n(.*?)```", README, flags=re.DOTALL)
COMMANDS = [
    command.strip()
    for language, block in BLOCKS
    if language == "bash"
    for line in block.splitlines()
    for command in line.split(" && ")
    if command.strip()
]
TUNNELSETTLE = [shlex.split(c) for c in COMMANDS if c.startswith("tunnelsettle ")]
RUN_FOR_REAL = {"run", "export"}  # seconds each; study and fe are minutes to hours


def test_the_set_up_is_two_commands_and_ci_runs_the_test_command():
    setup = README.split("## Set up", 1)[1].split("\n## ", 1)[0]
    blocks = re.findall(r"```bash\n(.*?)\n```", setup, flags=re.DOTALL)
    assert len(blocks) == 2 and all("\n" not in block for block in blocks)
    serve_line, test_line = blocks
    assert serve_line.startswith("python3 -m venv .venv && . .venv/bin/activate && pip install")
    assert serve_line.endswith("&& tunnelsettle serve")
    assert test_line.startswith("sh scripts/install_system_packages.sh && python3 -m venv .venv")
    assert (ROOT / "scripts" / "install_system_packages.sh").is_file()
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    ci_test_line = ci.split("# --- README test command (keep identical to README.md) ---\n")[1]
    assert test_line.endswith(ci_test_line.strip())  # CI makes the venv itself beforehand
    assert "sh scripts/install_system_packages.sh --strict" in ci


def test_every_subcommand_has_an_example_and_every_example_a_known_subcommand():
    used = {argv[1] for argv in TUNNELSETTLE}
    assert used <= set(SUBCOMMANDS)
    assert {"run", "study", "fe", "export", "serve"} <= used


@pytest.mark.parametrize("argv", TUNNELSETTLE, ids=" ".join)
def test_each_readme_command_parses_and_its_inputs_load(argv):
    """The command line as written is accepted by its own parser; the scenario it describes
    loads and validates; a session it names is a valid session file."""
    import importlib

    name, args = argv[1], argv[2:]
    module = importlib.import_module(SUBCOMMANDS[name].module)
    parser = module.build_parser(f"tunnelsettle {name}")
    if name == "serve":
        parser.parse_known_args(args)
        return
    parsed = parser.parse_args(args)
    if getattr(parsed, "session", None) is not None:
        from dashboard.whatif import SAMPLE_SESSION_FILE, read_session
        from model.scenarios import named_file

        read_session(named_file(parsed.session, SAMPLE_SESSION_FILE).read_bytes())
    elif getattr(parsed, "study", None) is None:
        load_scenario(parsed).validate()


@pytest.mark.slow
@pytest.mark.parametrize(
    "command", [c for c in COMMANDS if shlex.split(c)[:2][-1] in RUN_FOR_REAL], ids=str
)
def test_the_cheap_readme_commands_run_as_written(command, tmp_path, monkeypatch):
    """Run from an empty folder, in this process (tests/test_console.py runs the script)."""
    monkeypatch.chdir(tmp_path)
    argv = shlex.split(command)
    assert console.main(argv[1:]) == 0
    assert (tmp_path / argv[argv.index("--out") + 1]).exists()


@pytest.mark.slow
def test_the_headless_example_runs(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    exec(next(block for language, block in BLOCKS if language == "python"), {})
    assert "mm peak dynamic displacement at the invert" in capsys.readouterr().out
    assert (tmp_path / "report.html").stat().st_size > 0


# ---- ranges stated in the docs ----------------------------------------------------------------
RANGE_IN_DOCS = re.compile(r"`([a-z]+)\.(\w+)` (in|over) ([\[(][^\])]*[\])])(?: ([^\s,;.)]+))?")
""""`train.speed_kmh` in [1, 400] km/h" (the hard bounds) or "… over [20, 160] km/h" (the
softbounds, the sliders' range)."""
DOCUMENTS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def _stated_ranges():
    for document in DOCUMENTS:
        text = " ".join(document.read_text(encoding="utf-8").split())
        for match in RANGE_IN_DOCS.finditer(text):
            yield pytest.param(document.name, *match.groups(), id=match.group(0))


STATED = list(_stated_ranges())


def test_the_docs_state_some_ranges_this_way():
    """docs/studies.md's speed bounds (once "(0, 400]" against the code's [1, 400]) are read."""
    assert any(case.values[0] == "studies.md" for case in STATED)


@pytest.mark.parametrize(("document", "section", "name", "kind", "interval", "unit"), STATED)
def test_a_range_in_the_docs_is_the_declared_one(document, section, name, kind, interval, unit):
    assert section in SECTIONS, document
    p = Scenario.param[section].class_.param[name]
    if kind == "in":
        declared = _format_range(p.bounds, p.inclusive_bounds)
    else:
        declared = _format_range(p.softbounds, (True, True))
    assert interval == declared, f"{document}: {section}.{name} {kind} {interval}"
    label_unit = split_label(p.label)[1]
    assert unit in (None, label_unit) or label_unit in ("", "-"), document
