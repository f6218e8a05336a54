"""``tunnelsettle serve`` (also ``python -m dashboard.serve``): the dashboard served from the
installed package, with a light first page.

``panel serve`` needs the path of the app's module; after a plain (not editable) install there is
no ``dashboard/app.py`` under the working directory, so the path is that of the installed
:mod:`dashboard.app`. The server runs in this process (it gets Ctrl-C and signals directly; the
command first starts itself again in it, with :data:`SERVER_ALLOCATOR`; large blocks get
mappings of their own, :func:`~dashboard.memory.map_large_blocks`), with ``--warm`` unless
``--no-warm``; options this command does not know are handed to ``panel serve`` unchanged (e.g.
``--allow-websocket-origin``)::

    tunnelsettle serve                      # http://localhost:5006/app
    tunnelsettle serve --port 5010 --address 0.0.0.0 --allow-websocket-origin host:5010

Two changes to what the browser downloads, against plain ``panel serve``:

- **compression on**: Tornado gzips every HTTP response (the page and the Bokeh/Panel bundles,
  ~3 MB of JavaScript and CSS that compress about 4:1); Panel's CLI has no such option, so it is
  passed to the server here;
- **MathJax only for a formula**: Panel loads Bokeh's 1.8 MB MathJax bundle on any page that
  holds an HTML or Markdown pane, formula or not. :func:`use_light_resources` makes it load the
  bundle only when such a pane's text contains TeX delimiters (Bokeh's own test,
  ``contains_tex_string``). The app calls it when served, so plain ``panel serve
  dashboard/app.py`` drops the bundle too.

Both act on private hooks of Panel 1.x (``panel.io.resources._panel_use_mathjax`` and
``Serve.customize_kwargs``); ``benchmarks/bench_page_weight.py`` measures the result.
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import sys
from pathlib import Path

from dashboard.memory import map_large_blocks

DEFAULT_PORT = 5006  # Panel's
COOKIE_SECRET_ENV = "TUNNELSETTLE_COOKIE_SECRET"
MIN_COOKIE_SECRET_CHARS = 32


def app_path() -> Path:
    """File of the installed :mod:`dashboard.app` (found without importing it)."""
    return Path(importlib.util.find_spec("dashboard.app").origin)


def build_parser(prog: str = "tunnelsettle serve") -> argparse.ArgumentParser:
    """Argument parser of ``tunnelsettle serve`` (unknown options go to ``panel serve``)."""
    parser = argparse.ArgumentParser(
        prog=prog,
        description="Serve the interactive dashboard (panel serve of the installed "
        "dashboard/app.py, responses compressed), then open the address it prints. Other "
        "options are passed to panel serve.",
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
    parser.add_argument(
        "--basic-auth",
        metavar="FILE",
        help="JSON file of user names and passwords (Panel's basic auth); needs the cookie secret "
        f"in the environment variable {COOKIE_SECRET_ENV}",
    )
    return parser


def auth_options(password_file: str | None, environ: dict | None = None) -> list[str]:
    """``panel serve`` options that turn basic authentication on (none without a password file).

    The passwords stay in ``password_file`` and the cookie secret in the environment, so neither
    shows in the process list nor in the repository.

    Raises
    ------
    ValueError
        If the file does not exist or the cookie secret is missing or shorter than
        :data:`MIN_COOKIE_SECRET_CHARS`.
    """
    if password_file is None:
        return []
    environ = os.environ if environ is None else environ
    if not Path(password_file).is_file():
        raise ValueError(f"basic-auth file {password_file!r} does not exist")
    secret = environ.get(COOKIE_SECRET_ENV, "")
    if len(secret) < MIN_COOKIE_SECRET_CHARS:
        raise ValueError(
            f"cookie secret {COOKIE_SECRET_ENV} has {len(secret)} characters; basic auth needs at "
            f"least {MIN_COOKIE_SECRET_CHARS} (e.g. python -c 'import secrets; "
            "print(secrets.token_urlsafe(32))')"
        )
    # "=": a secret from secrets.token_urlsafe may begin with "-", which argparse would take
    # for an option
    return ["--basic-auth", str(password_file), f"--cookie-secret={secret}"]


def serve_command(args: argparse.Namespace, extra: list[str]) -> list[str]:
    """The ``panel serve ...`` command line of ``args`` and the passed-through options."""
    command = ["panel", "serve", str(app_path()), "--port", str(args.port)]
    if args.address:
        command += ["--address", args.address]
    if args.warm:
        command.append("--warm")
    if args.show:
        command.append("--show")
    return command + auth_options(args.basic_auth) + extra


def _html_with_formula(roots) -> bool:
    """True if a Panel HTML model in ``roots`` or below shows TeX (the only reason for MathJax)."""
    from bokeh.embed.util import contains_tex_string
    from panel.models.markup import HTML

    return any(
        isinstance(model, HTML) and isinstance(model.text, str) and contains_tex_string(model.text)
        for root in roots
        for model in root.references()
    )


def use_light_resources() -> None:
    """Make Panel load the MathJax bundle only for a page that shows a formula (idempotent)."""
    from panel.io import resources

    resources._panel_use_mathjax = _html_with_formula


def compress_responses() -> None:
    """Make ``panel serve`` start its server with Tornado's response compression on."""
    from panel.command.serve import Serve

    customize = Serve.customize_kwargs
    if getattr(customize, "compresses", False):
        return

    def compressed(self, args, server_kwargs):
        """Panel's server options with Tornado's response compression on."""
        return {**customize(self, args, server_kwargs), "compress_response": True}

    compressed.compresses = True
    Serve.customize_kwargs = compressed


ALLOCATOR_ENV = "PYTHONMALLOC"
SERVER_ALLOCATOR = "malloc"
"""Python's allocator in the server process: the C library's ``malloc`` for every object, not
Python's own small-object allocator. After a burst of sessions, the few objects made during it
that live on keep Python's 1 MiB arenas from going back to the system; with ``malloc`` the
trimmed heap (:mod:`dashboard.memory`) goes back page by page. ``deploy/smoke-test`` measured a
second burst of 20 sessions growing the server by +2, +39 and +59 MB with Python's allocator
and by +1 and +3 MB with ``malloc`` (docs/deploy.md); the pipeline's run times did not change."""


def reexec_with_server_allocator(argv: list[str], environ=None, execute=os.execve) -> None:
    """Start this command again, in this process, with :data:`SERVER_ALLOCATOR` (Python picks
    its allocator at start, so it cannot change afterwards). Nothing happens where
    ``PYTHONMALLOC`` is already set (the user's choice, or this re-execution) or off POSIX.

    ``-P`` keeps the working directory off ``sys.path``: started from another checkout, the
    command still serves the installed package, not that folder's ``dashboard``."""
    environ = os.environ if environ is None else environ
    if environ.get(ALLOCATOR_ENV) or os.name != "posix":
        return
    execute(
        sys.executable,
        [sys.executable, "-P", "-m", "dashboard.serve", *argv],
        {**environ, ALLOCATOR_ENV: SERVER_ALLOCATOR},
    )


def main(argv: list[str] | None = None, prog: str = "tunnelsettle serve") -> int:
    """Run the dashboard's server in this process until it stops; returns its exit code."""
    argv = sys.argv[1:] if argv is None else list(argv)
    parser = build_parser(prog)
    args, extra = parser.parse_known_args(argv)
    try:
        command = serve_command(args, extra)
    except ValueError as error:
        parser.error(str(error))
    reexec_with_server_allocator(argv)
    print(
        f"dashboard at http://{args.address or 'localhost'}:{args.port}/app: open it once the "
        "server's log says 'Bokeh app running at' (loading the packages takes up to a minute "
        "before that on a busy machine; the first start then compiles the kernels while the "
        "page says so; Ctrl-C stops the server)",
        flush=True,
    )
    from panel.command import main as panel_main

    map_large_blocks()
    use_light_resources()
    compress_responses()
    sys.argv = command
    panel_main()
    return 0


if __name__ == "__main__":
    sys.exit(main(prog="python -m dashboard.serve"))
