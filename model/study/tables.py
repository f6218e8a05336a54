"""A study's table: its columns, the bands across seeds, and study folders written and read."""

from __future__ import annotations

import re
from pathlib import Path

import pandas as pd

from model.params import SECTIONS
from model.study.definition import Study

BAND = (0.05, 0.95)
"""Quantiles of the band across seeds (numpy's linear interpolation between order statistics)."""
PROFILE_COLUMN = "profile_peak_disp_{depth:g}m_m"
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
    """Write ``runs.csv`` (one row per run), ``bands.csv`` (:func:`aggregate`) and ``study.json``.

    Floats are written in their shortest exact form, so ``pandas.read_csv`` gives back the
    same numbers bit for bit.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    paths = [folder / "runs.csv", folder / "bands.csv", folder / "study.json"]
    table.to_csv(paths[0])
    aggregate(table).to_csv(paths[1], index=False)
    paths[2].write_text(table.attrs["study"] + "\n", encoding="utf-8")
    return paths


def load_study(path: Path) -> Study:
    """The :class:`Study` of a ``study.json`` written by :func:`save_study`."""
    return Study.from_json(Path(path).read_text(encoding="utf-8"))


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
        ``n_runs`` and ``cancelled`` (True when the folder holds fewer rows than the study has
        runs).

    Raises
    ------
    ValueError
        A file is missing, or ``study.json`` is not a study definition (one line).
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
    table = pd.read_csv(runs, index_col="run")
    if "error" in table:
        table["error"] = table["error"].fillna("")
    table.attrs.update(
        study=study.to_json(), n_runs=study.n_runs, cancelled=len(table) < study.n_runs
    )
    return table
