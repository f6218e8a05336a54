"""What some tests need from the system beyond pip, and the reason given when they are skipped.

Two kinds of tests need Debian or Ubuntu packages (``scripts/install_system_packages.sh``, the
first step of the README's test command, installs them):

- the browser tests: Debian's Chromium at ``/usr/bin/chromium`` (another build can be named by
  ``TUNNELSETTLE_CHROMIUM``; Playwright never downloads a browser here);
- the FE tests: OpenSeesPy, whose shared library loads BLAS/LAPACK (``libopenblas0``,
  ``liblapack3``). Without them ``import openseespy.opensees`` raises ``RuntimeError``, which
  ``pytest.importorskip`` does not catch: collection would abort the whole suite.

Without them those tests are skipped, naming what is missing and how to get it.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

INSTALL_HINT = (
    "to run them, on Debian/Ubuntu: sh scripts/install_system_packages.sh "
    "(or: sudo apt-get install -y chromium libopenblas0 liblapack3)"
)
CHROMIUM = Path(os.environ.get("TUNNELSETTLE_CHROMIUM", "/usr/bin/chromium"))


def chromium_missing() -> str | None:
    """Why the browser tests cannot run here, or None."""
    if CHROMIUM.is_file() and os.access(CHROMIUM, os.X_OK):
        return None
    return f"no Chromium at {CHROMIUM} (Debian's chromium package); {INSTALL_HINT}"


def opensees_missing() -> str | None:
    """Why the FE tests cannot run here (OpenSeesPy or its libraries missing), or None."""
    from model.fe.build import fe_unavailable_reason

    reason = fe_unavailable_reason()
    return None if reason is None else f"{reason}; {INSTALL_HINT}"


needs_opensees = pytest.mark.skipif(opensees_missing() is not None, reason=opensees_missing() or "")
"""Mark of the tests that run OpenSeesPy (the ``opensees`` engine of the FE section): skipped,
with the reason, where it or its libraries are missing."""

needs_chromium = pytest.mark.skipif(chromium_missing() is not None, reason=chromium_missing() or "")
"""Mark of the tests that drive Chromium: skipped, with the reason, where it is missing."""
