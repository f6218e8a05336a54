"""The subcommands of the command lines, and their help, without importing the model.

``python -m model`` and the ``tunnelsettle`` console script list their subcommands from here:
this module needs only the standard library, so ``--help`` answers at once instead of after
the numerical stack (NumPy, SciPy, Numba) has loaded; a subcommand's module is imported only
when it runs.
"""

from __future__ import annotations

import importlib
import importlib.util
import sys
from dataclasses import dataclass


@dataclass(frozen=True)
class Subcommand:
    """A subcommand of the command line: the module whose ``main(argv, prog)`` handles it (and
    returns the exit code), the name of that function, and one line for the help."""

    module: str
    summary: str
    entry: str = "main"

    @property
    def available(self) -> bool:
        """Whether its module is installed (a subcommand may be registered before it exists)."""
        return importlib.util.find_spec(self.module) is not None

    def run(self, argv: list[str], prog: str) -> int:
        """Hand ``argv`` to the subcommand; exit 2, saying so, where it is not available."""
        if not self.available:
            sys.stderr.write(
                f"{prog}: error: not available in this version yet: {self.summary} "
                f"(its module {self.module} is still to come)\n"
            )
            return 2
        return getattr(importlib.import_module(self.module), self.entry)(argv, prog=prog)


MODEL_SUBCOMMANDS = {
    "study": Subcommand("model.study.cli", "parameter sweeps and Monte-Carlo bands on Dask"),
    "fe": Subcommand("model.fe.cli", "the elastic–plastic FE check of the section"),
    "band": Subcommand(
        "model.study.band_cli", "Monte-Carlo band of the long-term settlement (p05, p50, p95)"
    ),
}
"""Subcommands of ``python -m model`` (and of ``tunnelsettle``): each module has
``main(argv, prog)``; one that is not installed is marked in the help and, called, says so."""


def subcommand_help(subcommands: dict[str, Subcommand], program: str) -> str:
    """The help's list of subcommands, one line each; those not installed are marked."""
    width = max(len(name) for name in subcommands)
    lines = [
        f"  {name:<{width}}  {command.summary}"
        + ("" if command.available else " [not available in this version]")
        for name, command in subcommands.items()
    ]
    return f"subcommands ({program} SUBCOMMAND --help for the options of each):\n" + "\n".join(
        lines
    )
