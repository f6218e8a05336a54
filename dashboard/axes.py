"""The axis limits of the passage plots, computed from the data they draw.

Each passage plot states its limits (``xlim``, ``ylim``) instead of leaving them to HoloViews:
a run's update of the plot then sets the Bokeh ranges to the limits of the new data by the
rule of its first drawing (:meth:`~dashboard.plot_panes.PlotPanes._update` sets the figure's
data and ranges in place, without HoloViews), and the rule is one an engineer can read: the
data's extent over every layer, widened by a fraction of its span (in decades on a log
axis).
"""

from __future__ import annotations

from collections.abc import Sequence

import holoviews as hv
import numpy as np


def padded_range(
    low: float, high: float, padding: float, *, log: bool = False, floor: float | None = None
) -> tuple[float, float] | None:
    """The extent ``low``–``high`` of some data widened by ``padding`` × its span at each end.

    Parameters
    ----------
    low, high : float
        The data's smallest and largest values (on a log axis ``low`` > 0); not finite: no
        data.
    padding : float
        Fraction of the span added at each end (0: the axis ends at the data).
    log : bool
        The span and its padding are taken in decades (log10).
    floor : float, optional
        The axis's lowest value, whatever the data (a log axis's depth below the peak): the
        lower end is ``floor`` and only the upper end is padded (by ``padding`` × the span from
        ``floor`` to ``high``).

    Returns
    -------
    (low, high) or None
        None without data (or with all of it below ``floor``). A single value ``v`` gets
        ±10 % of ``v`` (±0.5 for 0), as HoloViews widens an empty span.
    """
    if floor is not None:
        low = floor
    if not (np.isfinite(low) and np.isfinite(high)) or low > high or (log and low <= 0):
        return None
    if high == low:
        spread = abs(low * 0.1) if low else 0.5
        return float(low - spread), float(high + spread)
    if log:
        low, high = np.log10(low), np.log10(high)
    pad = padding * (high - low)
    low, high = (low if floor is not None else low - pad), high + pad
    if log:
        low, high = 10.0**low, 10.0**high
    return float(low), float(high)


def axis_limits(
    layers: Sequence[hv.Element], padding: tuple[float, float], *, logy: bool = False
) -> dict:
    """``xlim`` and ``ylim`` options covering every layer's data (the first dimension along
    x, the second along y), padded per axis by ``padding`` (x, y) with :func:`padded_range`.

    A layer's y dimension with a lower ``range`` bound (a PSD's depth below its peak) sets the
    lowest y: the smallest such bound of all layers. Non-finite values count for nothing, nor
    do values ≤ 0 on a log axis. An axis without any data gets no limit (HoloViews' own
    ranging then applies).
    """
    bounds = [layer.get_dimension(1).range[0] for layer in layers]
    floors = [bound for bound in bounds if bound is not None and np.isfinite(bound)]
    limits = {}
    for name, index, pad, log, floor in (
        ("xlim", 0, padding[0], False, None),
        ("ylim", 1, padding[1], logy, min(floors) if floors else None),
    ):
        values = np.concatenate(
            [np.empty(0)]
            + [np.asarray(layer.dimension_values(index), dtype=float) for layer in layers]
        )
        values = values[np.isfinite(values) & ((values > 0) if log else True)]
        if values.size:
            axis = padded_range(values.min(), values.max(), pad, log=log, floor=floor)
            if axis is not None:
                limits[name] = axis
    return limits
