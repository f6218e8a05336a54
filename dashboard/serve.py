"""``tunnelsettle serve``: the dashboard served from the installed package.

``panel serve`` needs the path of the app's module; after a plain (not editable) install there is
no ``dashboard/app.py`` under the working directory, so the path is that of the installed
:mod:`dashboard.app`. The server replaces this process (it gets Ctrl-C and signals directly),
with ``--warm`` unless ``--no-warm``; options this command does not know are handed to
``panel serve`` unchanged (e.g. ``--allow-websocket-origin``)::

    tunnelsettle serve                      # http://localhost:5006/app
    tunnelsettle serve --port 5010 --address 0.0.0.0 --allow-websocket-origin host:5010
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import sys
from pathlib import Path

DEFAULT_PORT = 5006  # Panel's


def app_path() -> Path:
    """File of the installed :mod:`dashboard.app` (found without importing it)."""
    return Path(importlib.util.find_spec("dashboard.app").origin)


def build_parser(prog: str = "tunnelsettle serve") -> argparse.ArgumentParser:
    """Argument parser of ``tunnelsettle serve`` (unknown options go to ``panel serve``)."""
    parser = argparse.ArgumentParser(
        prog=prog,
        description="Serve the interactive dashboard (panel serve of the installed "
        "dashboard/app.py), then open the address it prints. Other options are passed to "
        "panel serve.",
    )
    parser.add_argument("--port", type=int, default=DEFAULT_PORT, help="TCP port (default 5006)")
    parser.add_argument("--address", help="address to listen on (default: panel's, localhost only)")
    parser.add_argument(
        "--warm",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="compile the numerical kernels when the server starts (default: yes)",
    )
    parser.add_argument("--show", action="store_true", help="open the page in a browser")
    return parser


def serve_command(args: argparse.Namespace, extra: list[str]) -> list[str]:
    """The ``python -m panel serve ...`` command line of ``args`` and the passed-through options."""
    command = [sys.executable, "-m", "panel", "serve", str(app_path()), "--port", str(args.port)]
    if args.address:
        command += ["--address", args.address]
    if args.warm:
        command.append("--warm")
    if args.show:
        command.append("--show")
    return command + extra


def main(argv: list[str] | None = None, prog: str = "tunnelsettle serve") -> int:
    """Replace this process with the dashboard's server; returns only if it cannot start."""
    args, extra = build_parser(prog).parse_known_args(argv)
    command = serve_command(args, extra)
    print(
        f"dashboard at http://{args.address or 'localhost'}:{args.port}/app: open it once the "
        "server's log says 'Bokeh app running at' (loading the packages takes up to a minute "
        "before that on a busy machine; the first start then compiles the kernels while the "
        "page says so; Ctrl-C stops the server)",
        flush=True,
    )
    os.execv(command[0], command)
    return 1  # pragma: no cover - execv does not return
