"""Writing results safely: every file by a temporary name then ``os.replace``, every output
folder of the command lines checked before any computation and replaced only once the new one
is complete.

A reader therefore finds a result file either whole or absent (never half written, never a
mixture of two runs), and an interrupted ``--force`` leaves the previous folder as it was.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np


def write_atomic(path: str | Path, write: Callable[[Path], object]) -> Path:
    """Write a file by calling ``write`` on a temporary name in the same folder, then rename
    it onto ``path`` (``os.replace``, atomic on one file system).

    Parameters
    ----------
    path : path-like
        The file to (re)place; its folder must exist.
    write : callable(Path)
        Writes the whole file at the path it is given (e.g. ``lambda p: p.write_text(...)``).

    Returns
    -------
    Path
        ``path``. If ``write`` raises (or the process is interrupted), ``path`` is untouched and
        the temporary file is removed.
    """
    path = Path(path)
    handle, temporary = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    os.close(handle)
    temporary = Path(temporary)
    try:
        write(temporary)
        os.replace(temporary, path)
    except BaseException:
        temporary.unlink(missing_ok=True)
        raise
    return path


def write_text_atomic(path: str | Path, text: str) -> Path:
    """:func:`write_atomic` of a UTF-8 text file."""
    return write_atomic(path, lambda temporary: temporary.write_text(text, encoding="utf-8"))


def write_csv_table(path: Path, columns: dict[str, np.ndarray]) -> Path:
    """Columns of equal length as a CSV file (header of their names, 9 significant digits),
    written whole (:func:`write_atomic`)."""
    return write_atomic(
        path,
        lambda temporary: np.savetxt(
            temporary,
            np.column_stack(list(columns.values())),
            delimiter=",",
            header=",".join(columns),
            comments="",
            fmt="%.9g",
        ),
    )


def check_output_folder(out: str | Path, force: bool, option: str = "--out") -> None:
    """Refuse an output folder that cannot take a command's results, before any computation.

    Parameters
    ----------
    out : path-like
        The folder the results are to replace (it need not exist).
    force : bool
        Allow replacing a folder that holds files.
    option : str
        How the messages name the folder.

    Raises
    ------
    ValueError
        ``out`` is a file, holds files and ``force`` is false, or its parent folder cannot be
        created or written (the new folder is assembled beside ``out``).
    """
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise ValueError(f"{option} {out} is a file, not a folder: choose a folder")
    if out.is_dir() and any(out.iterdir()) and not force:
        raise ValueError(
            f"{option} {out} already holds files; choose a new folder or pass --force to replace it"
        )
    parent = out.absolute().parent
    try:
        parent.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory(dir=parent, prefix=f".{out.name}."):
            pass
    except OSError as error:
        raise ValueError(f"{option} {out} cannot be written: {error.strerror or error}") from None


@contextlib.contextmanager
def replacing_folder(out: str | Path) -> Iterator[Path]:
    """A new, empty sibling folder to write results into; on leaving the block without an
    error it replaces ``out`` (the old folder is removed only after the new one is in place),
    on an error or an interrupt it is removed and ``out`` is left as it was.

    Parameters
    ----------
    out : path-like
        The folder to replace (need not exist).

    Yields
    ------
    Path
        The temporary folder (``.<name>.new-*`` beside ``out``).
    """
    out = Path(out)
    parent = out.absolute().parent
    parent.mkdir(parents=True, exist_ok=True)
    new = Path(tempfile.mkdtemp(dir=parent, prefix=f".{out.name}.new-"))
    try:
        yield new
        swap_in(new, out)
    except BaseException:
        shutil.rmtree(new, ignore_errors=True)
        raise


def swap_in(new: Path, out: Path) -> None:
    """Put the complete folder ``new`` in the place of ``out`` (two renames: the old folder is
    set aside, the new one takes its name, the old one is removed)."""
    old = None
    if out.exists():
        old = Path(tempfile.mkdtemp(dir=new.parent, prefix=f".{out.name}.old-"))
        os.replace(out, old / out.name)
    try:
        os.replace(new, out)
    except BaseException:
        if old is not None:  # put the old folder back
            os.replace(old / out.name, out)
        raise
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)
