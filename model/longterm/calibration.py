"""Calibration of the strain and pore-pressure laws from cyclic triaxial tests, and their CSV.

Li & Selig's ε_p = a (q_d/σ_s)^m N^b and the power law of the pore-pressure ratio
r_u = a_u (q_d/σ_s)^m_u N^b_u are both fitted by linear least squares in log space,
log y = log c + m log(q_d/σ_s) + b log N, with standard errors (docs/model.md §10, §15); the
hyperbolic r_u = (q_d/σ_s)^m_u N/(α + βN) by nonlinear least squares on log r_u. A fit whose
constants fall outside the bounds of the layer parameters they would set is refused, with the
reason. The CSV's columns are read by the names in its header, with their units; the shipped
example ``model/data/triaxial_synthetic.csv`` is synthetic and labelled so.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.optimize

from model.params.borehole import csv_lines
from model.params.quantities import _format_range
from model.params.site import Layer

N_LAW_PARAMETERS = 3  # a, b, m
STRESS_UNITS = {"kpa": 1.0, "pa": 1e-3, "mpa": 1e3}  # → kPa
PERCENT_UNITS = {"percent": 1.0, "%": 1.0, "pct": 1.0}
NO_UNIT = {"": 1.0, "-": 1.0}
# quantity → (names the header may use, units accepted with their factor to the stored unit)
TRIAXIAL_COLUMNS = {
    "n_cycles": (("n_cycles", "n", "cycles", "cycle"), NO_UNIT),
    "strain_percent": (("strain", "strain_p", "epsilon_p", "ε_p"), PERCENT_UNITS),
    "deviator_kPa": (("deviator", "q_d", "q"), STRESS_UNITS),
    "strength_kPa": (("strength", "sigma_s", "σ_s", "q_f"), STRESS_UNITS),
    "pore_pressure_kPa": (("pore_pressure", "u", "excess_pore_pressure"), STRESS_UNITS),
    "effective_stress_kPa": (("effective_stress", "sigma_c", "σ′_c", "sigma′_c"), STRESS_UNITS),
    "pore_pressure_ratio": (("pore_pressure_ratio", "r_u"), NO_UNIT),
}
REQUIRED = ("n_cycles", "strain_percent", "deviator_kPa", "strength_kPa")
HEADER_HELP = (
    "n_cycles, strain_percent, deviator_kPa, strength_kPa, and optionally pore_pressure_kPa "
    "with effective_stress_kPa (the test's effective consolidation stress) or "
    "pore_pressure_ratio; units after an underscore, a space or in brackets (kPa, Pa, MPa; "
    "percent or %), columns in any order"
)


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
    pore_pressure_ratio: np.ndarray | None = None
    """(n,) excess pore pressure over the effective consolidation stress r_u, or None."""

    @property
    def stress_ratio(self) -> np.ndarray:
        """(n,) q_d/σ_s."""
        return self.deviator_kPa / self.strength_kPa


def _check_calibration_data(n_cycles, values, stress_ratio, source: str, name="strain_percent"):
    """The three arrays as floats, or ValueError saying what is missing for a fit."""
    arrays = [np.atleast_1d(np.asarray(x, dtype=float)) for x in (n_cycles, values, stress_ratio)]
    if len({x.shape for x in arrays}) != 1 or arrays[0].ndim != 1:
        raise ValueError(
            f"{source}: n_cycles, {name} and stress_ratio must be 1-D arrays of the same "
            f"length, got shapes {[x.shape for x in arrays]}"
        )
    for label, column in zip(("n_cycles", name, "stress_ratio"), arrays, strict=True):
        bad = ~(np.isfinite(column) & (column > 0.0))
        if bad.any():
            raise ValueError(
                f"{source}: {label} must be finite and > 0 (the law is fitted in log space); "
                f"point {int(np.flatnonzero(bad)[0]) + 1} has {float(column[bad][0])!r}"
            )
    count = arrays[0].size
    if count <= N_LAW_PARAMETERS:
        raise ValueError(
            f"{source}: {count} points cannot give the three constants with standard errors: "
            f"at least {N_LAW_PARAMETERS + 1} points are needed (3 parameters + 1 for the error "
            "estimate)"
        )
    if np.ptp(np.log(arrays[2])) == 0.0:
        raise ValueError(
            f"{source}: every point has the same stress ratio q_d/σ_s = {arrays[2][0]:g}, so the "
            "stress exponent is not identifiable: add tests at a second stress level"
        )
    if np.ptp(np.log(arrays[0])) == 0.0:
        raise ValueError(
            f"{source}: every point has the same cycle number N = {arrays[0][0]:g}, so the "
            "cycle exponent is not identifiable: add values read at other cycle numbers"
        )
    return arrays


def _log_linear_fit(cycles, values, ratio) -> tuple[np.ndarray, np.ndarray, float, np.ndarray]:
    """Least squares of log y = c0 + c1 log(ratio) + c2 log N: coefficients, errors, s and
    the coefficients' covariance s² (XᵀX)⁻¹."""
    design = np.column_stack([np.ones_like(cycles), np.log(ratio), np.log(cycles)])
    if _ill_conditioned(design):
        raise ValueError(
            "calibration data: the points cannot determine the three constants (their standard "
            "errors would be undefined): the stress ratios q_d/σ_s or the cycle numbers N barely "
            "differ, or vary together; add tests at a second stress level and values read at "
            "other cycle numbers"
        )
    target = np.log(values)
    coefficients, *_ = np.linalg.lstsq(design, target, rcond=None)
    residual = target - design @ coefficients
    variance = float(residual @ residual) / (cycles.size - N_LAW_PARAMETERS)
    covariance = variance * np.linalg.inv(design.T @ design)
    return coefficients, np.sqrt(np.diag(covariance)), math.sqrt(variance), covariance


def _ill_conditioned(design: np.ndarray) -> bool:
    """Whether (XᵀX)⁻¹ of the columns scaled to unit length has no correct digit: the
    condition number of XᵀX, cond(X)², beyond 1/ε of double precision."""
    scaled = design / np.linalg.norm(design, axis=0)
    return bool(np.linalg.cond(scaled) ** 2 * np.finfo(float).eps > 1.0)


def _refuse_implausible(fit: dict[str, float], layer_names: dict[str, str], law: str) -> None:
    """ValueError unless every fitted constant lies within its layer parameter's bounds."""
    for key, name in layer_names.items():
        parameter = Layer.param[name]
        low, high = parameter.bounds
        low_in, high_in = parameter.inclusive_bounds
        value = fit[key]
        below = low is not None and (value < low or (value == low and not low_in))
        above = high is not None and (value > high or (value == high and not high_in))
        if below or above or not math.isfinite(value):
            doc = parameter.doc or ""
            reason = doc[doc.index("Bounds") :].rstrip(".") if "Bounds" in doc else ""
            raise ValueError(
                f"the fit of {law} gives {key} = {value:.3g}, outside the plausible range "
                f"{_format_range(parameter.bounds, parameter.inclusive_bounds)} of the layer's "
                f"{parameter.label} ({reason}); refused: check that the columns hold what "
                "their header names"
            )


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
        ``log_a_se``, ``n_points``, ``residual_std`` (of log ε_p) and ``covariance``, the
        3 × 3 covariance of (log a, m, b) as nested lists (``model.study.band`` draws the
        constants from it).

    Raises
    ------
    ValueError
        Fewer than 4 points, non-positive values, a single stress level or a single N, or
        points that cannot determine the constants (stress ratios or cycle numbers that barely
        differ or vary together); or fitted constants outside the bounds of the layer's
        a (0, 100] %, b (0, 1), m (0, 10] (strains that do not grow with N, swapped columns),
        with the reason.
    """
    cycles, strain, ratio = _check_calibration_data(
        n_cycles, strain_percent, stress_ratio, "calibration data"
    )
    coefficients, errors, residual_std, covariance = _log_linear_fit(cycles, strain, ratio)
    a = float(np.exp(coefficients[0]))
    fit = {
        "a": a,
        "m": float(coefficients[1]),
        "b": float(coefficients[2]),
        "a_se": a * float(errors[0]),
        "log_a_se": float(errors[0]),
        "m_se": float(errors[1]),
        "b_se": float(errors[2]),
        "n_points": int(cycles.size),
        "residual_std": residual_std,
        "covariance": covariance.tolist(),
    }
    _refuse_implausible(fit, {"a": "a", "b": "b", "m": "m"}, "Li & Selig's law")
    return fit


def fit_pore_pressure_law(n_cycles, pore_pressure_ratio, stress_ratio, law: str = "power"):
    """Fit the pore-pressure ratio r_u = u/σ′_c of cyclic tests to a generation law (§15).

    ``"power"``: r_u = a_u (q_d/σ_s)^m_u N^b_u, linear least squares of log r_u as
    :func:`fit_strain_law`. ``"hyperbolic"``: r_u = (q_d/σ_s)^m_u N/(α + βN), nonlinear least
    squares of log r_u over (log α, β, m_u) (``scipy.optimize.least_squares``), standard errors
    from the Jacobian, s² (JᵀJ)⁻¹.

    Parameters
    ----------
    n_cycles : array_like
        Cycle numbers N, > 0.
    pore_pressure_ratio : array_like
        r_u, > 0.
    stress_ratio : array_like
        q_d/σ_s, > 0, at least two distinct values.
    law : {"power", "hyperbolic"}
        Generation law.

    Returns
    -------
    dict
        Power: ``a_u``, ``b_u``, ``m_u`` and their ``*_se``; hyperbolic: ``alpha_u``,
        ``beta_u``, ``m_u`` and their ``*_se``; with ``n_points``, ``residual_std`` (of
        log r_u) and ``law``.

    Raises
    ------
    ValueError
        As :func:`fit_strain_law`, and constants outside the bounds of the layer's a_u, b_u,
        m_u, α_u, β_u.
    """
    cycles, pore, ratio = _check_calibration_data(
        n_cycles, pore_pressure_ratio, stress_ratio, "calibration data", "pore_pressure_ratio"
    )
    if law == "power":
        coefficients, errors, residual_std, _ = _log_linear_fit(cycles, pore, ratio)
        a_u = float(np.exp(coefficients[0]))
        fit = {
            "a_u": a_u,
            "m_u": float(coefficients[1]),
            "b_u": float(coefficients[2]),
            "a_u_se": a_u * float(errors[0]),
            "m_u_se": float(errors[1]),
            "b_u_se": float(errors[2]),
        }
        names = {"a_u": "a_u", "b_u": "b_u", "m_u": "m_u"}
    elif law == "hyperbolic":
        fit, residual_std = _hyperbolic_fit(cycles, pore, ratio)
        names = {"alpha_u": "alpha_u", "beta_u": "beta_u", "m_u": "m_u"}
    else:
        raise ValueError(f"law = {law!r} is not one of power, hyperbolic")
    fit.update(n_points=int(cycles.size), residual_std=residual_std, law=law)
    _refuse_implausible(fit, names, f"the {law} pore-pressure law")
    return fit


def _hyperbolic_fit(cycles, pore, ratio) -> tuple[dict[str, float], float]:
    """(log α, β, m_u) of r_u = ratio^m_u N/(α + βN) by least squares on log r_u."""

    def residual(p):
        alpha, beta, m_u = math.exp(p[0]), p[1], p[2]
        return m_u * np.log(ratio) + np.log(cycles / (alpha + beta * cycles)) - np.log(pore)

    start = [math.log(np.median(cycles)), 1.0, 1.0]
    solution = scipy.optimize.least_squares(
        residual, start, bounds=([-50.0, 0.0, 0.0], [50.0, np.inf, 10.0])
    )
    dof = cycles.size - N_LAW_PARAMETERS
    variance = float(solution.fun @ solution.fun) / dof
    jacobian = solution.jac
    covariance = variance * np.linalg.pinv(jacobian.T @ jacobian)
    errors = np.sqrt(np.diag(covariance))
    alpha = math.exp(solution.x[0])
    fit = {
        "alpha_u": alpha,
        "beta_u": float(solution.x[1]),
        "m_u": float(solution.x[2]),
        "alpha_u_se": alpha * float(errors[0]),
        "beta_u_se": float(errors[1]),
        "m_u_se": float(errors[2]),
    }
    return fit, math.sqrt(variance)


def load_triaxial_csv(path) -> TriaxialData:
    """Read cyclic triaxial results from a CSV file.

    Lines starting with ``#`` are comments (e.g. "SYNTHETIC data"); blank lines are skipped.
    The first other line is the header: it names each column with its unit, and the columns
    are read by those names, in any order (``HEADER_HELP``): cycle number N, accumulated
    permanent strain (%), cyclic deviator q_d and static strength σ_s (kPa, Pa or MPa), and
    optionally the excess pore pressure u with the test's effective consolidation stress σ′_c
    (r_u = u/σ′_c), or r_u itself, to calibrate the pore-pressure law.

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
        Binary content or a line the CSV reader cannot read (:func:`csv_lines`); a header
        that is missing, names an unknown column or lacks a required one or a unit;
        bad rows (with the file name, line numbers and columns); or data from which a, b, m
        cannot be fitted (fewer than 4 points, non-positive values, a single stress level).
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
    lines = csv_lines(text, source)
    if not lines:
        raise ValueError(f"{source}: no header and 0 points; the header names {HEADER_HELP}")
    header_line, header = lines[0]
    columns = _header_columns(header, header_line, source)
    rows, problems = [], []
    for line_number, fields in lines[1:]:
        values, problem = _data_row(fields, columns, line_number)
        if problem:
            problems.append(problem)
        else:
            rows.append(values)
    if problems:
        shown = "; ".join(problems[:5]) + ("; …" if len(problems) > 5 else "")
        raise ValueError(f"{source}: {len(problems)} bad row(s): {shown}")
    data = np.array(rows, dtype=float).reshape(-1, len(columns))
    by_name = {name: data[:, i] * factor for i, (name, factor, _) in enumerate(columns)}
    ratio = by_name.get("pore_pressure_ratio")
    if "pore_pressure_kPa" in by_name:
        ratio = by_name["pore_pressure_kPa"] / by_name["effective_stress_kPa"]
    result = TriaxialData(*(by_name[name] for name in REQUIRED), source, ratio)
    _check_calibration_data(result.n_cycles, result.strain_percent, result.stress_ratio, source)
    return result


def _header_columns(header, line_number: int, source: str) -> list[tuple[str, float, str]]:
    """(quantity, factor to its stored unit, the header's text) of each column, checked."""
    columns, seen = [], {}
    for position, cell in enumerate(header, start=1):
        text = cell.strip()
        try:
            float(text)
        except ValueError:
            pass
        else:
            raise ValueError(
                f"{source}: line {line_number} holds numbers, not a header: the first line "
                f"that is not a comment must name the columns ({HEADER_HELP})"
            )
        quantity, factor = _column_of(text, position, line_number, source)
        if quantity in seen:
            raise ValueError(
                f"{source}: line {line_number}: columns {seen[quantity]!r} and {text!r} both "
                f"give {quantity}"
            )
        seen[quantity] = text
        columns.append((quantity, factor, text))
    missing = [name for name in REQUIRED if name not in seen]
    if missing:
        raise ValueError(
            f"{source}: the header on line {line_number} has no column {', '.join(missing)} "
            f"(it names {', '.join(repr(c) for c in header)}; expected {HEADER_HELP})"
        )
    pressure, stress = "pore_pressure_kPa" in seen, "effective_stress_kPa" in seen
    if pressure != stress:
        given, needed = (
            ("pore_pressure_kPa", "effective_stress_kPa")
            if pressure
            else ("effective_stress_kPa", "pore_pressure_kPa")
        )
        raise ValueError(
            f"{source}: the header on line {line_number} has {given} but no {needed}: "
            "r_u = u/σ′_c needs both the excess pore pressure and the test's effective "
            "consolidation stress (or give pore_pressure_ratio)"
        )
    if pressure and "pore_pressure_ratio" in seen:
        raise ValueError(
            f"{source}: the header on line {line_number} gives both pore_pressure_kPa and "
            "pore_pressure_ratio: give one"
        )
    return columns


def _column_of(text: str, position: int, line_number: int, source: str) -> tuple[str, float]:
    """The quantity a header cell names and the factor of its unit."""
    cell = text.lower().replace("[", "(").replace("]", ")")
    candidates = []
    if cell.endswith(")") and "(" in cell:
        name, _, unit = cell[:-1].rpartition("(")
        candidates.append((name.strip(), unit.strip()))
    for separator in ("_", " "):
        name, _, unit = cell.rpartition(separator)
        if name:
            candidates.append((name.strip(), unit.strip()))
    candidates.append((cell, ""))
    for quantity, (names, units) in TRIAXIAL_COLUMNS.items():
        for name, unit in candidates:
            if name in names and unit in units:
                return quantity, units[unit]
    candidates.sort(key=lambda candidate: -len(candidate[0]))  # "q_d" before "q" with unit "d"
    for quantity, (names, units) in TRIAXIAL_COLUMNS.items():
        for name, unit in candidates:
            if name in names:
                allowed = ", ".join(u for u in units if u) or "none"
                raise ValueError(
                    f"{source}: line {line_number}, column {position} ({text!r}): "
                    f"{'no unit' if not unit else f'unit {unit!r}'} for {quantity}; "
                    f"units: {allowed}"
                )
    raise ValueError(
        f"{source}: line {line_number}, column {position}: {text!r} is not a known column; "
        f"the header names {HEADER_HELP}"
    )


def _data_row(fields, columns, line_number: int) -> tuple[list[float], str | None]:
    """The numbers of a data row, or the problem with it (naming the line and the column)."""
    if len(fields) != len(columns):
        names = ", ".join(text for _, _, text in columns)
        return [], f"line {line_number}: {len(fields)} values, expected {len(columns)} ({names})"
    values = []
    for field, (_, _, text) in zip(fields, columns, strict=True):
        try:
            value = float(field)
        except ValueError:
            return [], f"line {line_number}: {text} = {field.strip()!r} is not a number"
        if not math.isfinite(value) or value <= 0.0:
            return [], f"line {line_number}: {text} = {value!r} must be finite and > 0"
        values.append(value)
    return values, None
