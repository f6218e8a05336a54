"""Load cycles: how many cycles one passage is, and how many the traffic gives over the years.

Cycles per train are the number of bogies, or the rainflow count (ASTM E1049) of the deviator
q(t, d) at each depth with each cycle weighted by its range over q_d, Σ count · range / q_d (one
full cycle from 0 to q_d counts 1). N = trains per day × 365 × years × cycles per train
(docs/model.md §10).
"""

from __future__ import annotations

import numba
import numpy as np

from model.params.site import DAYS_PER_YEAR

__all__ = ["DAYS_PER_YEAR", "cycles_per_train", "load_cycles", "n_bogies", "range_weighted_cycles"]


def n_bogies(train) -> int:
    """Bogies in the train (two axles each)."""
    return train.n_wheels // 2


def cycles_per_train(stress, scenario) -> np.ndarray:
    """Load cycles per passage at each depth (``longterm.cycles_per_train``).

    Parameters
    ----------
    stress : model.soil.stresses.StressResponse
        The soil stage's deviator under the invert (its rainflow counts).
    scenario : model.params.Scenario
        Uses longterm.cycles_per_train and train (number of bogies).

    Returns
    -------
    ndarray
        (nd,) cycles per train.
    """
    if scenario.longterm.cycles_per_train == "bogies":
        return np.full(stress.depth_m.size, float(n_bogies(scenario.train)))
    return stress.rainflow_cycles


def load_cycles(years, trains_per_day: float, per_train) -> np.ndarray:
    """N = trains per day × 365 × years × cycles per train, (n_years, n_depth)."""
    return trains_per_day * DAYS_PER_YEAR * years[:, None] * per_train


def range_weighted_cycles(history) -> float:
    """Rainflow count of a load history, each cycle weighted by its range over the peak.

    Σ count_i · range_i / max(history), with count 1 for full and ½ for half cycles (ASTM
    E1049, the algorithm of the ``rainflow`` package's ``extract_cycles``, which
    :func:`rainflow_weighted_sum` follows step for step; tests compare the two): k pulses from
    zero to the same peak count k, small ripples count in proportion to their size. 0 for a
    history that never exceeds 0. The history is taken to start and end at zero (no train
    before the passage, none after): a record that begins or ends with the train still loading
    the soil (the 2.5D model's long-range field) would otherwise count one passage as less than
    one cycle.

    Parameters
    ----------
    history : array_like
        1-D load history (e.g. the deviator q(t), Pa), ≥ 0.

    Returns
    -------
    float
        Equivalent number of cycles.
    """
    series = np.concatenate([[0.0], np.asarray(history, dtype=float), [0.0]])
    peak = float(series.max())
    if peak <= 0.0:
        return 0.0
    return rainflow_weighted_sum(turning_points(series)) / peak


@numba.njit(cache=True, nogil=True)
def turning_points(series):
    """The first and last values of a 1-D series and every value where its slope changes sign
    (flat stretches skipped)."""
    out = np.empty(series.size)
    out[0] = series[0]
    count = 1
    previous = 0.0
    for i in range(series.size - 1):
        slope = np.sign(series[i + 1] - series[i])
        if slope == 0.0:
            continue
        if previous != 0.0 and slope != previous:
            out[count] = series[i]
            count += 1
        previous = slope
    out[count] = series[series.size - 1]
    return out[: count + 1]


@numba.njit(cache=True, nogil=True)
def rainflow_weighted_sum(points):
    """Σ count · range over the rainflow cycles of a series (ASTM E1049 §5.4.4), in the order
    and arithmetic of ``rainflow.extract_cycles`` (its reversals first, then the three-point
    rule with a half cycle for a range that holds the starting point)."""
    n = points.size
    if n < 2:
        return 0.0
    # the package's reversals(): the first value, each interior sign change, the last value
    reversal = np.empty(n)
    reversal[0] = points[0]
    m = 1
    x = points[1]
    d_last = x - points[0]
    for k in range(2, n):
        x_next = points[k]
        if x_next == x:
            continue
        d_next = x_next - x
        if d_last * d_next < 0.0:
            reversal[m] = x
            m += 1
        x = x_next
        d_last = d_next
    if n > 2:
        reversal[m] = points[n - 1]
        m += 1
    stack = np.empty(m)  # the package's deque: stack[head:top]
    head = 0
    top = 0
    total = 0.0
    for k in range(m):
        stack[top] = reversal[k]
        top += 1
        while top - head >= 3:
            x1, x2, x3 = stack[top - 3], stack[top - 2], stack[top - 1]
            if abs(x3 - x2) < abs(x2 - x1):
                break
            if top - head == 3:  # the range holds the starting point: half a cycle
                total += abs(stack[head] - stack[head + 1]) * 0.5
                head += 1
            else:
                total += abs(x1 - x2) * 1.0
                stack[top - 3] = x3
                top -= 2
    while top - head > 1:
        total += abs(stack[head] - stack[head + 1]) * 0.5
        head += 1
    return total
