"""Load cycles: how many cycles one passage is, and how many the traffic gives over the years.

Cycles per train are the number of bogies, or the rainflow count (ASTM E1049) of the deviator
q(t, d) at each depth with each cycle weighted by its range over q_d, Σ count · range / q_d (one
full cycle from 0 to q_d counts 1). N = trains per day × 365 × years × cycles per train
(docs/model.md §10).
"""

from __future__ import annotations

import numpy as np
import rainflow

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
    E1049, the ``rainflow`` package): k pulses from zero to the same peak count k, small
    ripples count in proportion to their size. 0 for a history that never exceeds 0.
    The history is taken to start and end at zero (no train before the passage, none after):
    a record that begins or ends with the train still loading the soil (the 2.5D model's
    long-range field) would otherwise count one passage as less than one cycle.

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
    slope = np.sign(np.diff(series))
    nonflat = np.flatnonzero(slope)
    turning = nonflat[1:][slope[nonflat[1:]] != slope[nonflat[:-1]]]
    points = series[np.concatenate([[0], turning, [series.size - 1]])]
    return sum(rng * count for rng, _, count, _, _ in rainflow.extract_cycles(points)) / peak
