"""A study's table: its columns, the bands across seeds, and study folders written and read."""

from __future__ import annotations

import hashlib
import io
import json
import re
from pathlib import Path

import pandas as pd

from model.outputs import write_text_atomic
from model.params import SECTIONS
from model.study.definition import Study

BAND = (0.05, 0.95)
"""Quantiles of the band across seeds (numpy's linear interpolation between order statistics)."""
PROFILE_COLUMN = "profile_peak_disp_{depth:g}m_m"
STUDY_FILES = ("runs.csv", "bands.csv", "study.json")
"""The files of a study folder, as :func:`save_study` writes them."""
SAVED_KEY = "saved"
"""Key of ``study.json`` recording how the study was saved (cancelled, rows, checksum)."""
_PROFILE_RE = re.compile(r"^profile_peak_disp_(.+)m_m$")


# ---- results -------------------------------------------------------------------------------
def input_columns(table: pd.DataFrame) -> list[str]:
    """The varied parameters: columns named by a dotted path ``section.parameter``."""
    return [c for c in table.columns if "." in c and c.partition(".")[0] in SECTIONS]


def output_columns(table: pd.DataFrame) -> list[str]:
    """Numeric result columns (summary numbers and depth profile)."""
    inputs = set(input_columns(table)) | {"seed"}
    return [c for c in table.columns if c not in inputs and pd.api.types.is_numeric_dtype(table[c])]


def profile_depths(table: pd.DataFrame) -> list[tuple[float, str]]:
    """(depth in m, column) of the depth-profile columns, shallowest first."""
    found = [(m, c) for c in table.columns if (m := _PROFILE_RE.match(c))]
    return sorted((float(m.group(1)), c) for m, c in found)


def aggregate(table: pd.DataFrame, band: tuple[float, float] = BAND) -> pd.DataFrame:
    """Mean and band across seeds at each point of a study.

    Parameters
    ----------
    table : pandas.DataFrame
        :func:`run_study` output (failed runs, with NaN results, are left out).
    band : (float, float)
        Lower and upper quantile, default 5 % and 95 %.

    Returns
    -------
    pandas.DataFrame
        One row per point (the varied columns, in study order), ``n_runs`` and for each result
        column ``<column>_mean``, ``<column>_p05``, ``<column>_p95`` (same units).
    """
    inputs, outputs = input_columns(table), output_columns(table)
    low, high = band
    names = {"mean": "mean", "low": f"p{round(100 * low):02d}", "high": f"p{round(100 * high):02d}"}
    groups = table.groupby(inputs, sort=False) if inputs else [((), table)]
    rows = []
    for key, group in groups:
        key = key if isinstance(key, tuple) else (key,)
        values = group[outputs]
        ok = values.notna().all(axis=1)
        row = {**dict(zip(inputs, key, strict=True)), "n_runs": int(ok.sum())}
        stats = {
            "mean": values[ok].mean(),
            "low": values[ok].quantile(low),
            "high": values[ok].quantile(high),
        }
        for column in outputs:
            for stat, series in stats.items():
                row[f"{column}_{names[stat]}"] = float(series[column])
        rows.append(row)
    return pd.DataFrame(rows)


def save_study(table: pd.DataFrame, folder: Path) -> list[Path]:
    """Write ``runs.csv`` (one row per run), ``bands.csv`` (:func:`aggregate`) and ``study.json``
    (the definition, and under ``"saved"`` whether the study was cancelled, its rows and the
    SHA-256 of ``runs.csv``, which :func:`read_study` checks); each file written whole
    (:func:`model.outputs.write_atomic`).

    Floats are written in their shortest exact form, so ``pandas.read_csv`` gives back the
    same numbers bit for bit.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    runs_text = table.to_csv(lineterminator="\n")
    definition = json.loads(table.attrs["study"])
    definition[SAVED_KEY] = {
        "cancelled": bool(table.attrs["cancelled"]),
        "n_rows": len(table),
        "runs_sha256": hashlib.sha256(runs_text.encode("utf-8")).hexdigest(),
    }
    texts = (runs_text, aggregate(table).to_csv(index=False), json.dumps(definition, indent=2))
    return [
        write_text_atomic(folder / name, text if name != "study.json" else text + "\n")
        for name, text in zip(STUDY_FILES, texts, strict=True)
    ]


def load_study(path: Path) -> Study:
    """The :class:`Study` of a ``study.json`` written by :func:`save_study`."""
    try:
        text = Path(path).read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise ValueError(f"{path} is not a study definition: it is not UTF-8 text") from None
    try:
        return Study.from_json(text)
    except ValueError as error:
        raise ValueError(f"{path}: {error}") from None


def read_study(folder: Path) -> pd.DataFrame:
    """The table of a study folder written by :func:`save_study`, as :func:`run_study` gave it.

    Parameters
    ----------
    folder : path
        Holds ``runs.csv`` and ``study.json``.

    Returns
    -------
    pandas.DataFrame
        The rows of ``runs.csv`` (the same numbers bit for bit), ``attrs`` ``study``,
        ``n_runs`` and ``cancelled`` (as saved; for a folder saved without that record, True
        when it holds fewer rows than the study has runs).

    Raises
    ------
    ValueError
        A file is missing, ``study.json`` is not a study definition, or ``runs.csv`` does not
        match it (its checksum, its run numbers or its input columns): one line, never quoting
        the files.
    """
    folder = Path(folder)
    runs, definition = folder / "runs.csv", folder / "study.json"
    for path in (runs, definition):
        if not path.is_file():
            raise ValueError(
                f"{path} not found: {folder} is not a folder written by save_study or "
                "python -m model study --out"
            )
    study = load_study(definition)
    saved = json.loads(definition.read_text(encoding="utf-8")).get(SAVED_KEY)
    data = runs.read_bytes()
    if isinstance(saved, dict) and saved.get("runs_sha256") != hashlib.sha256(data).hexdigest():
        raise ValueError(
            f"{runs} does not match {definition} (its SHA-256 differs from the one saved with "
            "the study): the file was changed or cut short after the study was written"
        )
    try:
        table = pd.read_csv(io.BytesIO(data), index_col="run")
    except (ValueError, pd.errors.ParserError, UnicodeDecodeError) as error:
        raise ValueError(f"{runs} is not a study's runs table ({type(error).__name__})") from None
    _check_runs(table, study, runs)
    if "error" in table:
        table["error"] = table["error"].fillna("")
    cancelled = saved["cancelled"] if isinstance(saved, dict) else len(table) < study.n_runs
    table.attrs.update(study=study.to_json(), n_runs=study.n_runs, cancelled=bool(cancelled))
    return table


def _check_runs(table: pd.DataFrame, study: Study, path: Path) -> None:
    """Refuse a runs table that is not the study's: run numbers outside [0, n_runs) or repeated,
    or input columns (varied parameters, seed) other than the study's at those runs."""
    index = table.index
    if not (pd.api.types.is_integer_dtype(index) and index.is_unique):
        raise ValueError(f"{path}: the run numbers must be distinct whole numbers")
    if len(index) and not (index.min() >= 0 and index.max() < study.n_runs):
        raise ValueError(
            f"{path}: run numbers must lie in the allowed range [0, {study.n_runs - 1}] "
            f"(the study has {study.n_runs} runs)"
        )
    n_seeds = len(study.seeds)
    for column in [*study.vary, "seed"]:
        if column not in table:
            raise ValueError(f"{path}: the column {column} of the study's inputs is missing")
        if column == "seed":
            expected = [study.seeds[run % n_seeds] for run in index]
        else:
            expected = [study.points[run // n_seeds][column] for run in index]
        # as text: the numbers are read back exactly, so their repr is the study's
        if list(table[column].astype(str)) != [str(value) for value in expected]:
            raise ValueError(f"{path}: the values of {column} are not the study's at its runs")
