"""Deployment options of ``tunnelsettle serve``: basic auth with a cookie secret from the
environment, refused with a message when either is missing."""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys

import pytest
from panel.command.serve import Serve

from dashboard import serve

SECRET = "s" * serve.MIN_COOKIE_SECRET_CHARS


def _command(argv, environ, monkeypatch):
    monkeypatch.setattr(serve.os, "environ", environ)
    args, extra = serve.build_parser().parse_known_args(argv)
    return serve.serve_command(args, extra)


def test_auth_on_with_file_and_secret(tmp_path, monkeypatch):
    users = tmp_path / "users.json"
    users.write_text(json.dumps({"engineer": "a long password"}))
    command = _command(["--basic-auth", str(users)], {serve.COOKIE_SECRET_ENV: SECRET}, monkeypatch)
    assert command[command.index("--basic-auth") + 1] == str(users)
    assert f"--cookie-secret={SECRET}" in command


def test_a_secret_beginning_with_a_dash_reaches_panel_serve(tmp_path, monkeypatch):
    """secrets.token_urlsafe gives such a secret about one time in 64."""
    users = tmp_path / "users.json"
    users.write_text("{}")
    secret = "-" + SECRET
    command = _command(["--basic-auth", str(users)], {serve.COOKIE_SECRET_ENV: secret}, monkeypatch)
    parser = argparse.ArgumentParser()
    Serve(parser=parser.add_subparsers().add_parser("serve"))
    assert parser.parse_args(command[1:]).cookie_secret == secret


def test_auth_off_without_file(monkeypatch):
    assert "--basic-auth" not in _command([], {}, monkeypatch)


@pytest.mark.parametrize("secret", ["", "short"])
def test_missing_or_short_secret_refused(tmp_path, monkeypatch, secret):
    users = tmp_path / "users.json"
    users.write_text("{}")
    with pytest.raises(ValueError, match=serve.COOKIE_SECRET_ENV):
        _command(["--basic-auth", str(users)], {serve.COOKIE_SECRET_ENV: secret}, monkeypatch)


def test_missing_password_file_refused(tmp_path, monkeypatch):
    with pytest.raises(ValueError, match="does not exist"):
        _command(["--basic-auth", str(tmp_path / "no.json")], {}, monkeypatch)


def test_serve_starts_again_with_the_c_allocator_unless_an_allocator_is_chosen():
    calls = []
    argv = ["--port", "5010", "--allow-websocket-origin", "h:5010"]
    serve.reexec_with_server_allocator(argv, {"HOME": "/h"}, lambda *call: calls.append(call))
    assert calls == [
        (
            sys.executable,
            [sys.executable, "-P", "-m", "dashboard.serve", *argv],
            {"HOME": "/h", "PYTHONMALLOC": "malloc"},
        )
    ]
    calls.clear()  # the started again process, or a user's own choice: no second start
    for chosen in ("malloc", "pymalloc"):
        serve.reexec_with_server_allocator(argv, {"PYTHONMALLOC": chosen}, calls.append)
    assert calls == []


def test_serve_started_again_ignores_a_dashboard_package_in_the_working_directory(tmp_path):
    shadow = tmp_path / "dashboard"
    shadow.mkdir()
    (shadow / "__init__.py").write_text("")
    (shadow / "serve.py").write_text("print('the working directory was served')")

    def execute(executable, args, environ):
        done = subprocess.run(args, env=environ, cwd=tmp_path, capture_output=True, text=True)
        outputs.append(done.stdout + done.stderr)

    outputs = []
    environ = {k: v for k, v in os.environ.items() if k != "PYTHONMALLOC"}
    serve.reexec_with_server_allocator(["--help"], environ, execute)
    assert "usage: " in outputs[0]
    assert "working directory" not in outputs[0]


def test_serve_refuses_bad_options_before_starting_again(tmp_path, monkeypatch):
    monkeypatch.setattr(serve.os, "environ", {})
    started = []
    monkeypatch.setattr(serve, "reexec_with_server_allocator", started.append)
    with pytest.raises(SystemExit):
        serve.main(["--basic-auth", str(tmp_path / "no.json")])
    assert started == []


def test_served_process_maps_large_blocks_before_the_server_starts(monkeypatch):
    import panel.command

    steps = []
    monkeypatch.setattr(serve, "reexec_with_server_allocator", lambda argv: steps.append("reexec"))
    monkeypatch.setattr(serve, "map_large_blocks", lambda: steps.append("map"))
    monkeypatch.setattr(serve, "use_light_resources", lambda: None)
    monkeypatch.setattr(serve, "compress_responses", lambda: None)
    monkeypatch.setattr(panel.command, "main", lambda: steps.append(list(sys.argv)))
    monkeypatch.setattr(sys, "argv", ["tunnelsettle"])
    assert serve.main(["--no-warm"]) == 0
    assert steps[:2] == ["reexec", "map"]
    assert steps[2][:2] == ["panel", "serve"]
