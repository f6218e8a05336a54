"""Calibration of Li & Selig's law from cyclic triaxial tests, and reading their CSV files.

Fit a, b, m by linear least squares on log ε_p = log a + m log(q_d/σ_s) + b log N, with
standard errors (docs/model.md §10); the shipped example ``model/data/triaxial_synthetic.csv``
is synthetic and labelled so.
"""

from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

TRIAXIAL_COLUMNS = ("n_cycles", "strain_percent", "deviator_kPa", "strength_kPa")
COMMENT = "#"
N_LAW_PARAMETERS = 3  # a, b, m


@dataclass(frozen=True)
class TriaxialData:
    """Cyclic triaxial test points: one row per (stress level, cycle count)."""

    n_cycles: np.ndarray
    """(n,) cycle number N."""
    strain_percent: np.ndarray
    """(n,) accumulated permanent axial strain (%)."""
    deviator_kPa: np.ndarray
    """(n,) cyclic deviator q_d (kPa)."""
    strength_kPa: np.ndarray
    """(n,) static strength σ_s (kPa)."""
    source: str = "arrays"
    """Where the data came from (file name)."""

    @property
    def stress_ratio(self) -> np.ndarray:
        """(n,) q_d/σ_s."""
        return self.deviator_kPa / self.strength_kPa


def _check_calibration_data(n_cycles, strain_percent, stress_ratio, source: str):
    """The three arrays as floats, or ValueError saying what is missing for a fit."""
    arrays = [
        np.atleast_1d(np.asarray(x, dtype=float)) for x in (n_cycles, strain_percent, stress_ratio)
    ]
    if len({x.shape for x in arrays}) != 1 or arrays[0].ndim != 1:
        raise ValueError(
            f"{source}: n_cycles, strain_percent and stress_ratio must be 1-D arrays of the "
            f"same length, got shapes {[x.shape for x in arrays]}"
        )
    for name, values in zip(("n_cycles", "strain_percent", "stress_ratio"), arrays, strict=True):
        bad = ~(np.isfinite(values) & (values > 0.0))
        if bad.any():
            raise ValueError(
                f"{source}: {name} must be finite and > 0 (the law is fitted in log space); "
                f"point {int(np.flatnonzero(bad)[0]) + 1} has {float(values[bad][0])!r}"
            )
    count = arrays[0].size
    if count <= N_LAW_PARAMETERS:
        raise ValueError(
            f"{source}: {count} points cannot give a, b, m with standard errors: at least "
            f"{N_LAW_PARAMETERS + 1} points are needed (3 parameters + 1 for the error estimate)"
        )
    if np.ptp(np.log(arrays[2])) == 0.0:
        raise ValueError(
            f"{source}: every point has the same stress ratio q_d/σ_s = {arrays[2][0]:g}, so m "
            "is not identifiable: add tests at a second stress level"
        )
    if np.ptp(np.log(arrays[0])) == 0.0:
        raise ValueError(
            f"{source}: every point has the same cycle number N = {arrays[0][0]:g}, so b is "
            "not identifiable: add strains read at other cycle numbers"
        )
    return arrays


def fit_strain_law(n_cycles, strain_percent, stress_ratio) -> dict[str, float]:
    """Fit Li & Selig's ε_p = a (q_d/σ_s)^m N^b by linear least squares in log space.

    log ε_p = log a + m log(q_d/σ_s) + b log N (natural logarithms), ordinary least squares;
    standard errors from the residual variance s² = RSS/(n − 3) and (XᵀX)⁻¹; the error of a
    by the delta method, a · se(log a).

    Parameters
    ----------
    n_cycles : array_like
        Cycle numbers N, > 0.
    strain_percent : array_like
        Accumulated permanent strains ε_p (%), > 0.
    stress_ratio : array_like
        q_d/σ_s of each point, > 0, at least two distinct values.

    Returns
    -------
    dict
        ``a`` (%), ``b``, ``m``, their standard errors ``a_se``, ``b_se``, ``m_se``,
        ``log_a_se``, ``n_points`` and ``residual_std`` (of log ε_p).

    Raises
    ------
    ValueError
        Fewer than 4 points, non-positive values, a single stress level or a single N.
    """
    cycles, strain, ratio = _check_calibration_data(
        n_cycles, strain_percent, stress_ratio, "calibration data"
    )
    design = np.column_stack([np.ones_like(cycles), np.log(ratio), np.log(cycles)])
    target = np.log(strain)
    coefficients, *_ = np.linalg.lstsq(design, target, rcond=None)
    residual = target - design @ coefficients
    dof = cycles.size - N_LAW_PARAMETERS
    variance = float(residual @ residual) / dof
    errors = np.sqrt(variance * np.diag(np.linalg.inv(design.T @ design)))
    a = float(np.exp(coefficients[0]))
    return {
        "a": a,
        "m": float(coefficients[1]),
        "b": float(coefficients[2]),
        "a_se": a * float(errors[0]),
        "log_a_se": float(errors[0]),
        "m_se": float(errors[1]),
        "b_se": float(errors[2]),
        "n_points": int(cycles.size),
        "residual_std": math.sqrt(variance),
    }


def load_triaxial_csv(path) -> TriaxialData:
    """Read cyclic triaxial results from a CSV file.

    Lines starting with ``#`` are comments (e.g. "SYNTHETIC data"); blank lines are skipped.
    The first other line may be a header (any names, e.g. ``n_cycles,strain_percent,
    deviator_kPa,strength_kPa``); every data row holds four numbers in that order: cycle
    number N, accumulated permanent strain (%), cyclic deviator q_d and static strength σ_s
    (both kPa, or any one stress unit).

    Parameters
    ----------
    path : str or Path
        The CSV file.

    Returns
    -------
    TriaxialData

    Raises
    ------
    ValueError
        Bad rows (with the file name and line numbers), or data from which a, b, m cannot be
        fitted (fewer than 4 points, non-positive values, a single stress level).
    """
    path = Path(path)
    return parse_triaxial_csv(path.read_text(encoding="utf-8"), path.name)


def parse_triaxial_csv(text: str, source: str = "triaxial data") -> TriaxialData:
    """Cyclic triaxial results from CSV text (format and errors as :func:`load_triaxial_csv`).

    Parameters
    ----------
    text : str
        Contents of the CSV file.
    source : str
        Name used in error messages (e.g. the uploaded file's name).

    Returns
    -------
    TriaxialData
    """
    rows, problems = [], []
    header_allowed = True
    text = text.removeprefix("\ufeff")  # a UTF-8 byte-order mark would hide the first number
    for line_number, fields in enumerate(csv.reader(io.StringIO(text)), start=1):
        if not fields or not "".join(fields).strip() or fields[0].lstrip().startswith(COMMENT):
            continue
        try:
            values = [float(field) for field in fields]
        except ValueError:
            if header_allowed:
                header_allowed = False
                continue
            problems.append(f"line {line_number}: not numbers: {','.join(fields)!r}")
            continue
        header_allowed = False
        if len(values) != len(TRIAXIAL_COLUMNS):
            problems.append(
                f"line {line_number}: {len(values)} values, expected "
                f"{len(TRIAXIAL_COLUMNS)} ({', '.join(TRIAXIAL_COLUMNS)})"
            )
        elif not all(math.isfinite(v) and v > 0.0 for v in values):
            bad = next(
                f"{name} = {v!r}"
                for name, v in zip(TRIAXIAL_COLUMNS, values, strict=True)
                if not (math.isfinite(v) and v > 0.0)
            )
            problems.append(f"line {line_number}: {bad} must be finite and > 0")
        else:
            rows.append(values)
    if problems:
        shown = "; ".join(problems[:5]) + ("; …" if len(problems) > 5 else "")
        raise ValueError(f"{source}: {len(problems)} bad row(s): {shown}")
    data = np.array(rows, dtype=float).reshape(-1, len(TRIAXIAL_COLUMNS))
    result = TriaxialData(*data.T, source=source)
    _check_calibration_data(result.n_cycles, result.strain_percent, result.stress_ratio, source)
    return result
