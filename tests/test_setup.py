"""The README's set-up on a fresh machine (issue 30): the system-package step of the test command,
and the suite skipping, not aborting, where a system package is missing.

``scripts/install_system_packages.sh`` runs here against stand-ins for ``apt-get``,
``apt-cache``, ``dpkg-query``, ``id`` and ``sudo`` that log their calls, on a PATH that holds
nothing else but the few tools the script uses: every branch is checked without touching the
machine's packages.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
SCRIPT = ROOT / "scripts" / "install_system_packages.sh"
PACKAGES = ("chromium", "libopenblas0", "liblapack3")
STUBS = {
    "dpkg-query": 'for p in $STUB_INSTALLED; do [ "$p" = "$3" ] && printf "install ok installed"'
    " && exit 0; done; exit 1",
    "apt-cache": 'for p in $STUB_NO_CANDIDATE; do [ "$p" = "$2" ] && echo "  Candidate: (none)"'
    ' && exit 0; done; echo "  Candidate: 1.0"',
    "apt-get": 'echo "apt-get $*" >> "$STUB_LOG"',
    "id": 'echo "$STUB_UID"',
    "sudo": 'echo "sudo" >> "$STUB_LOG"; exec "$@"',
}
REAL_TOOLS = ("sh", "grep", "env", "sed", "cat")


def _run(tmp_path: Path, *args: str, installed=(), no_candidate=(), uid=1000, stubs=STUBS):
    """Run the script on a PATH of stand-ins; return (exit code, output, logged calls)."""
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir(exist_ok=True)
    for tool in REAL_TOOLS:
        (bin_dir / tool).unlink(missing_ok=True)
        (bin_dir / tool).symlink_to(shutil.which(tool))
    for name, body in stubs.items():
        stub = bin_dir / name
        stub.write_text(f"#!/bin/sh\n{body}\n")
        stub.chmod(0o755)
    log = tmp_path / "calls.log"
    log.write_text("")
    env = {
        "PATH": str(bin_dir),
        "STUB_INSTALLED": " ".join(installed),
        "STUB_NO_CANDIDATE": " ".join(no_candidate),
        "STUB_UID": str(uid),
        "STUB_LOG": str(log),
    }
    done = subprocess.run(
        [shutil.which("sh"), str(SCRIPT), *args], env=env, capture_output=True, text=True
    )
    return done.returncode, done.stdout + done.stderr, log.read_text().splitlines()


def test_nothing_is_done_when_everything_is_installed(tmp_path):
    code, output, calls = _run(tmp_path, installed=PACKAGES)
    assert code == 0 and calls == [] and "are installed" in output


def test_the_missing_packages_are_installed_through_sudo(tmp_path):
    code, output, calls = _run(tmp_path, installed=("chromium",))
    assert code == 0, output
    assert calls == [
        "sudo",
        "apt-get update -qq",
        "sudo",
        "apt-get install -y -qq libopenblas0 liblapack3",
    ]


def test_root_installs_without_sudo(tmp_path):
    code, _, calls = _run(tmp_path, uid=0)
    assert code == 0
    assert calls == [
        "apt-get update -qq",
        "apt-get install -y -qq chromium libopenblas0 liblapack3",
    ]


def test_a_package_without_candidate_is_named_and_the_others_installed(tmp_path):
    """Ubuntu has no deb of Chromium: BLAS/LAPACK are still installed, the browser tests will be
    skipped; --strict (CI) fails instead."""
    code, output, calls = _run(tmp_path, uid=0, no_candidate=("chromium",))
    assert code == 0
    assert calls[-1] == "apt-get install -y -qq libopenblas0 liblapack3"
    assert "no package chromium here" in output and "will be skipped" in output
    code, output, _ = _run(tmp_path, "--strict", uid=0, no_candidate=("chromium",))
    assert code == 1 and "not installed: chromium" in output


@pytest.mark.parametrize(
    ("stubs", "uid", "said"),
    [
        ({k: v for k, v in STUBS.items() if k != "apt-get"}, 1000, "no apt-get here"),
        ({k: v for k, v in STUBS.items() if k != "sudo"}, 1000, "not root and no sudo"),
        ({**STUBS, "apt-get": "exit 100"}, 0, "apt-get update failed"),
    ],
)
def test_where_nothing_can_be_installed_it_says_why_and_the_tests_go_on(tmp_path, stubs, uid, said):
    code, output, _ = _run(tmp_path, stubs=stubs, uid=uid)
    assert code == 0 and said in output and "will be skipped" in output
    code, output, _ = _run(tmp_path, "--strict", stubs=stubs, uid=uid)
    assert code == 1 and said in output


@pytest.mark.slow
def test_the_suite_skips_what_needs_missing_system_packages(tmp_path):
    """A real failed load of OpenSeesPy (a broken libopenblas.so.0 found first on the loader's
    path makes ``import openseespy.opensees`` raise RuntimeError, as on a machine without
    BLAS/LAPACK) and no Chromium: the FE and browser files are skipped with the reason and the
    remedy, the rest runs, and pytest exits 0."""
    broken = tmp_path / "lib"
    broken.mkdir()
    (broken / "libopenblas.so.0").write_bytes(b"")
    env = {
        **os.environ,
        "LD_LIBRARY_PATH": str(broken),
        "TUNNELSETTLE_CHROMIUM": str(tmp_path / "no-chromium"),
    }
    done = subprocess.run(
        [sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-q", "-rs"]
        + ["tests/test_fe_section.py", "tests/test_browser.py", "tests/test_spectra.py"],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
    )
    output = done.stdout + done.stderr
    assert done.returncode == 0, output
    fe_skip = next(line for line in output.splitlines() if "tests/test_fe_section.py" in line)
    assert fe_skip.startswith("SKIPPED [1]") and "libopenblas.so.0" in fe_skip
    assert "no Chromium at" in output and "scripts/install_system_packages.sh" in output
    assert " passed" in output
