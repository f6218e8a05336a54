"""The ``tunnelsettle`` console script: every command line of the project under one name.

``tunnelsettle SUBCOMMAND ...``: ``run`` (one scenario, :mod:`model.cli`), the model's
subcommands (``study``, ``fe``, ``band``: :data:`model.commands.MODEL_SUBCOMMANDS`), ``export``
(HTML reports, :mod:`dashboard.export`) and ``serve`` (the dashboard, :mod:`dashboard.serve`). Each
module is imported only when its subcommand runs, so ``tunnelsettle --help`` loads nothing but
the standard library and ``tunnelsettle run`` no GUI package.
"""

from __future__ import annotations

import sys
from importlib.metadata import PackageNotFoundError, version

from model.commands import MODEL_SUBCOMMANDS, Subcommand, subcommand_help

PROGRAM = "tunnelsettle"

SUBCOMMANDS = {
    "run": Subcommand("model.cli", "one run of a scenario: results as CSV and JSON", "run_main"),
    **MODEL_SUBCOMMANDS,
    "export": Subcommand(
        "dashboard.export", "a self-contained HTML report of a run, a what-if session or a study"
    ),
    "serve": Subcommand("dashboard.serve", "the interactive dashboard, in the browser"),
}
"""Subcommand → the module (and function) that handles it."""


def help_text() -> str:
    """``tunnelsettle --help``."""
    return (
        f"usage: {PROGRAM} SUBCOMMAND [options]\n\n"
        "Metro-tunnel vibration and settlement in soft soil: train → track → tunnel → soil → "
        "long-term settlement.\n\n"
        f"{subcommand_help(SUBCOMMANDS, PROGRAM)}\n\n"
        f"e.g. {PROGRAM} run --preset paper --out results/\n"
        f"     {PROGRAM} serve   (then open http://localhost:5006/app)\n"
    )


def _version() -> str:
    """The installed distribution's version."""
    try:
        return version("tunnelsettle")
    except PackageNotFoundError:  # run from a source tree that was never installed
        return "unknown (not installed)"


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``tunnelsettle``; returns the exit code (2 for a bad command line)."""
    argv = sys.argv[1:] if argv is None else list(argv)
    if not argv or argv[0] in ("-h", "--help"):
        print(help_text(), end="", file=sys.stdout if argv else sys.stderr)
        return 0 if argv else 2
    if argv[0] == "--version":
        print(f"{PROGRAM} {_version()}")
        return 0
    name = argv[0]
    if name not in SUBCOMMANDS:
        sys.stderr.write(
            f"{PROGRAM}: error: unknown subcommand {name!r}; choose one of "
            f"{', '.join(SUBCOMMANDS)} ({PROGRAM} --help)\n"
        )
        return 2
    return SUBCOMMANDS[name].run(argv[1:], prog=f"{PROGRAM} {name}")


if __name__ == "__main__":
    sys.exit(main())
