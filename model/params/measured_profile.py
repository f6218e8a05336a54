"""Measured rail profiles: the CSV format, its checks, and which files may be read.

A measured profile enters a scenario by content, ``Irregularity.profile_data`` (the CSV text,
as uploaded in the dashboard or written in a scenario file), or by path,
``Irregularity.profile_csv``, which only the command line and the Python API read as given:
they act for the person who runs them. A front end that serves other people (the dashboard)
accepts a path only inside its data folder (environment variable ``TUNNELSETTLE_DATA_DIR``) and
reads it into ``profile_data`` when the scenario arrives (:func:`admit_profile`), so no run of
the server opens a file that one of its users named. Refusals of such a path say the same
thing whether a file exists outside that folder or not, and no message quotes a line of a
profile file.

Format (UTF-8, with or without a byte-order mark): lines starting with ``#`` and blank lines
are ignored; the first other line is the header ``x_m,eta_m`` or ``x_m,eta_mm`` (η in mm is
converted to m); then one ``x,η`` pair per line, at least two, x strictly increasing (m,
measured from the monitored block), all values finite. η > 0 is a dip (down positive).
"""

from __future__ import annotations

import functools
import hashlib
import math
import os
import stat
from dataclasses import dataclass
from pathlib import Path

import numpy as np

DATA_DIR_ENV = "TUNNELSETTLE_DATA_DIR"
"""Environment variable naming the folder whose profile files the dashboard may read."""

MAX_PROFILE_BYTES = 2_000_000
"""Largest profile accepted (bytes of CSV, about 100 000 points): a measured section of a few
hundred metres at 5 mm steps is a tenth of it, and every run of a session keeps the text."""

_ETA_UNITS_TO_M = {"eta_m": 1.0, "eta_mm": 1e-3}
_HEADERS = "'x_m,eta_m' or 'x_m,eta_mm'"


@dataclass(frozen=True, eq=False)
class MeasuredProfile:
    """A parsed measured profile: positions and η (read-only arrays) and the text's digest."""

    x_m: np.ndarray
    """Positions (m), strictly increasing, measured from the monitored block."""
    eta_m: np.ndarray
    """Profile (m), positive downward (a dip)."""
    digest: str
    """SHA-256 of the CSV text: what a cache key or a stored result is keyed by."""

    @property
    def n_points(self) -> int:
        """Number of points."""
        return self.x_m.size


class _Fault(ValueError):
    """A malformed profile: the line number (0 for the whole text) and what is wrong."""

    def __init__(self, line: int, reason: str):
        super().__init__(line, reason)
        self.line, self.reason = line, reason

    def message(self, source: str) -> str:
        """The refusal, naming ``source`` and the line, never the line's text."""
        where = f"{source}, line {self.line}" if self.line else source
        return f"{where}: {self.reason}"


class _NotRegularFile(OSError):
    """A path that names a folder, a device, a pipe or a socket, not a file."""


def parse_profile(data: str | bytes, source: str = "irregularity.profile_data") -> MeasuredProfile:
    """Parse the CSV text of a measured profile (format in the module docstring).

    Parameters
    ----------
    data : str or bytes
        The CSV text (bytes are decoded as UTF-8), at most :data:`MAX_PROFILE_BYTES`.
    source : str
        How the messages name the profile (a file name, ``irregularity.profile_data``).

    Returns
    -------
    MeasuredProfile

    Raises
    ------
    ValueError
        Too large, not UTF-8 or malformed; the message names ``source``, the line and the
        fault, and quotes nothing of the text.
    """
    try:
        return _parse_text(_as_text(data))
    except _Fault as fault:
        raise ValueError(fault.message(source)) from None


def profile_text(data: str | bytes, source: str) -> str:
    """The text of a profile (an uploaded file's bytes), checked by :func:`parse_profile`: what
    ``Irregularity.profile_data`` is set to."""
    try:
        text = _as_text(data)
        _parse_text(text)
    except _Fault as fault:
        raise ValueError(fault.message(source)) from None
    return text


def _as_text(data: str | bytes) -> str:
    """The profile as text, refused when too large or not UTF-8."""
    if isinstance(data, bytes):
        if len(data) > MAX_PROFILE_BYTES:
            raise _Fault(0, _too_large(len(data)))
        try:
            return data.decode("utf-8-sig")
        except UnicodeDecodeError as error:
            raise _Fault(
                0,
                f"not UTF-8 text (byte {error.start}: {error.reason}); save the profile as "
                "UTF-8 or plain ASCII",
            ) from None
    if not isinstance(data, str):
        raise _Fault(0, f"a profile is CSV text, not {type(data).__name__}")
    if len(data) > MAX_PROFILE_BYTES:  # characters: at least as many bytes
        raise _Fault(0, _too_large(len(data)))
    return data.removeprefix("\ufeff")


def _too_large(size: int) -> str:
    """Refusal of a profile of ``size`` bytes."""
    return (
        f"{size / 1e6:.3g} MB is larger than the {MAX_PROFILE_BYTES / 1e6:g} MB allowed for a "
        "measured profile; keep the section the train passes over, or sample it more coarsely"
    )


@functools.lru_cache(maxsize=16)
def _parse_text(text: str) -> MeasuredProfile:
    """:func:`parse_profile` of a text, remembered: a scenario is copied on every change of
    the dashboard, and each copy checks its profile again (faults raise, uncached)."""
    to_m = None
    x_values: list[float] = []
    eta_values: list[float] = []
    for number, raw in enumerate(text.splitlines(), start=1):
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        fields = [field.strip() for field in line.split(",")]
        if to_m is None:
            if len(fields) != 2 or fields[0] != "x_m" or fields[1] not in _ETA_UNITS_TO_M:
                raise _Fault(number, f"the header must be {_HEADERS}")
            to_m = _ETA_UNITS_TO_M[fields[1]]
            continue
        if len(fields) != 2:
            raise _Fault(number, f"expected 2 comma-separated values, found {len(fields)}")
        try:
            x, eta = float(fields[0]), float(fields[1])
        except ValueError:
            raise _Fault(number, "the values are not two numbers") from None
        if not (math.isfinite(x) and math.isfinite(eta)):
            raise _Fault(number, "a value is not finite")
        if x_values and x <= x_values[-1]:
            raise _Fault(number, "x does not exceed the x of the line before; x must increase")
        x_values.append(x)
        eta_values.append(eta * to_m)
    if to_m is None:
        raise _Fault(0, f"no header line {_HEADERS} found")
    if len(x_values) < 2:
        raise _Fault(0, f"{len(x_values)} data line(s); at least 2 are needed")
    eta = np.array(eta_values)
    x = np.array(x_values)
    for array in (x, eta):
        array.flags.writeable = False
    return MeasuredProfile(x, eta, hashlib.sha256(text.encode("utf-8")).hexdigest())


def profile_digest(irregularity) -> str | None:
    """SHA-256 of an Irregularity's measured profile: of its text (remembered, not hashed again
    on every call), else of its file's bytes; None without a measured profile, or for a file
    that cannot be read (its run then says why)."""
    if irregularity.profile_data is not None:
        return _parse_text(_as_text(irregularity.profile_data)).digest
    if not irregularity.profile_csv:
        return None
    try:
        return hashlib.sha256(
            _read_regular_file(Path(irregularity.profile_csv), follow_links=True)
        ).hexdigest()
    except (OSError, ValueError):
        return None


# ---- reading files ---------------------------------------------------------------------------
def read_profile_file(path: str | Path) -> str:
    """The text of a profile file named by the person running the program (command line,
    Python API): any readable regular file.

    Raises
    ------
    ValueError
        Not a regular file (a folder, a device, a pipe), larger than :data:`MAX_PROFILE_BYTES`,
        unreadable or malformed (see :func:`parse_profile`); the message names ``path``.
    """
    path = Path(path)
    try:
        data = _read_regular_file(path, follow_links=True)
    except _NotRegularFile:
        raise ValueError(f"{path}: not a regular file (a profile is a CSV file)") from None
    except _Fault as fault:
        raise ValueError(fault.message(str(path))) from None
    except OSError as error:
        reason = error.strerror or type(error).__name__
        raise ValueError(f"{path}: cannot read the profile file ({reason})") from None
    try:
        return _as_text(data)
    except _Fault as fault:
        raise ValueError(fault.message(str(path))) from None


def data_folder() -> Path | None:
    """The folder named by ``$TUNNELSETTLE_DATA_DIR`` (resolved), or None when it is not set."""
    folder = os.environ.get(DATA_DIR_ENV, "").strip()
    return Path(folder).resolve() if folder else None


def read_profile_in_folder(name: str, folder: Path | None) -> str:
    """The checked text (:func:`profile_text`) of the profile file ``name`` inside ``folder``,
    for names given by users of a server.

    ``name`` is relative to ``folder`` (an absolute path is accepted only if it lies inside).
    A path that leaves the folder (``..``, a symbolic link, an absolute path elsewhere), a
    missing file, a folder, a device or a pipe all get the same refusal, which names what was
    given but says nothing about the server's files; with no folder (None) every name is
    refused.

    Raises
    ------
    ValueError
        As above, or the file is too large or malformed (named by ``name``).
    """
    refusal = ValueError(
        f"irregularity.profile_csv = {name!r} is not a profile file of this server's data "
        f"folder{'' if folder else ' (none is configured)'}: upload the profile instead"
        + (", or give the name of a file in the data folder" if folder else "")
    )
    if folder is None or not isinstance(name, str) or not name.strip():
        raise refusal
    try:
        root = folder.resolve()
        candidate = (root / name).resolve()
        if not candidate.is_relative_to(root):
            raise refusal
        data = _read_regular_file(candidate, follow_links=False)
    except _Fault as fault:
        raise ValueError(fault.message(name)) from None
    except (OSError, ValueError, RuntimeError):  # missing, not a file, unreadable, NUL, loop
        raise refusal from None
    return profile_text(data, name)


def _read_regular_file(path: Path, follow_links: bool) -> bytes:
    """The bytes of a regular file, at most :data:`MAX_PROFILE_BYTES` + 1 of them.

    Opened without blocking (a named pipe would wait for a writer) and checked on the open
    descriptor, so what is read is what was checked. Raises :class:`_NotRegularFile` for
    anything but a regular file, ``_Fault`` when too large, OSError when unreadable (e.g.
    ``/proc/self/mem``).
    """
    flags = os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0)
    if not follow_links:
        flags |= getattr(os, "O_NOFOLLOW", 0)
    descriptor = os.open(path, flags)
    with os.fdopen(descriptor, "rb") as handle:
        info = os.fstat(handle.fileno())
        if not stat.S_ISREG(info.st_mode):
            raise _NotRegularFile(str(path))
        data = handle.read(MAX_PROFILE_BYTES + 1)
    if len(data) > MAX_PROFILE_BYTES:
        raise _Fault(0, _too_large(max(len(data), info.st_size)))
    return data


def admit_profile(scenario, folder: Path | None) -> None:
    """Make a scenario that came from a user of a server hold its profile by content.

    A path in ``irregularity.profile_csv`` is read with :func:`read_profile_in_folder` into
    ``irregularity.profile_data`` and cleared; without a path nothing changes. Call it where a
    scenario enters a server (URL arguments, a loaded scenario or session file) and before it
    is computed there.

    Parameters
    ----------
    scenario : Scenario
        Changed in place.
    folder : Path or None
        The data folder (:func:`data_folder`); None refuses every path.

    Raises
    ------
    ValueError
        The path is refused (see :func:`read_profile_in_folder`); the scenario is unchanged.
    """
    name = scenario.irregularity.profile_csv
    if not name:
        return
    text = read_profile_in_folder(name, folder)
    scenario.irregularity.param.update(profile_csv=None, profile_data=text)
