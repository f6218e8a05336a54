"""Command line of the static HTML reports (:mod:`dashboard.report`): one run, a what-if session
or a study, written as one self-contained file that opens offline::

    python -m dashboard.export --preset paper --out report.html
    python -m dashboard.export --scenario scenario.json --set train.speed_kmh=60 --out report.html
    python -m dashboard.export --session whatif_session.json --out report.html
    python -m dashboard.export --session sample --out report.html   # the shipped sample
    python -m dashboard.export --study study/ --out report.html
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from dashboard.report import write_report
from dashboard.study_report import study_report_html
from dashboard.whatif import SAMPLE_SESSION_FILE
from dashboard.whatif_report import write_session_report
from model.cli import add_scenario_arguments, load_scenario
from model.pipeline import SimulationError, run
from model.scenarios import CUSTOM, matching_preset, named_file
from model.study.definition import Study
from model.study.tables import read_study


def build_parser(prog: str = "python -m dashboard.export") -> argparse.ArgumentParser:
    """Argument parser of ``python -m dashboard.export``."""
    parser = argparse.ArgumentParser(
        prog=prog,
        description="Write a self-contained HTML report of a run, a what-if session or a study.",
    )
    add_scenario_arguments(parser)
    parser.add_argument(
        "--session",
        type=Path,
        help="what-if session file saved by the dashboard, or 'sample' for the shipped sample: "
        "report its runs side by side (instead of --scenario and --set)",
    )
    parser.add_argument(
        "--study",
        type=Path,
        help="study folder written by python -m model study --out: report its definition, "
        "plots and bands (instead of --scenario, --set and --session)",
    )
    parser.add_argument("--out", type=Path, required=True, help="HTML file to write")
    return parser


def main(argv: list[str] | None = None, prog: str = "python -m dashboard.export") -> int:
    """Entry point; returns the process exit code (2 for bad input)."""
    parser = build_parser(prog)
    args = parser.parse_args(argv)
    if args.study is not None:
        return _study_main(parser, args)
    if args.session is not None:
        return _session_main(parser, args)
    try:
        scenario = load_scenario(args)
        results = run(scenario, cache=None)
        name = matching_preset(scenario)
        if name == CUSTOM and args.scenario:
            name = args.scenario.name
        write_report(results, args.out, name)
    except (ValueError, KeyError, OSError, SimulationError) as error:
        message = error.args[0] if isinstance(error, KeyError) and error.args else error
        parser.exit(2, f"error: {message}\n")
    for warning in results.warnings:
        print(f"warning: {warning}", file=sys.stderr)
    print(f"report written to {args.out}")
    return 0


def _session_main(parser: argparse.ArgumentParser, args: argparse.Namespace) -> int:
    """``--session``: the report of a saved what-if session."""
    if args.scenario is not None or args.overrides:
        parser.error("--session cannot be combined with --scenario or --set")
    try:
        session = named_file(args.session, SAMPLE_SESSION_FILE)
        try:
            text = session.read_text(encoding="utf-8")
        except OSError as error:
            raise ValueError(
                f"--session {session}: cannot read the session file ({error.strerror})"
            ) from None
        write_session_report(text, args.out)
    except (ValueError, OSError, SimulationError) as error:
        parser.exit(2, f"error: {error}\n")
    print(f"session report written to {args.out}")
    return 0


def _study_main(parser: argparse.ArgumentParser, args: argparse.Namespace) -> int:
    """``--study``: the report of a saved study folder."""
    if args.scenario is not None or args.overrides or args.session is not None:
        parser.error("--study cannot be combined with --scenario, --set or --session")
    try:
        table = read_study(args.study)
        name = matching_preset(Study.from_json(table.attrs["study"]).base)
        if name == CUSTOM:
            name = args.study.resolve().name
        args.out.write_text(study_report_html(table, name), encoding="utf-8")
    except (ValueError, OSError) as error:
        parser.exit(2, f"error: {error}\n")
    print(f"study report written to {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
