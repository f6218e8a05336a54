"""Plots of a study table: pure functions of its rows → HoloViews, shared by the Study view and
the study report (:mod:`dashboard.study_report`).

Per result of :data:`RESULTS` (in mm): the mean with its 5–95 % band across seeds against one
varied parameter, or a heat map of the mean over two; and the envelope of the peak-displacement
depth profiles. Parameters are shown in their display units (MPa, MN/m, …); the table is SI.
"""

from __future__ import annotations

from collections.abc import Callable

import holoviews as hv
import numpy as np
import pandas as pd

from dashboard.controls import clean_number
from dashboard.plots import MM, PLOT_OPTIONS
from model.params import SECTIONS, display_label, display_unit
from model.study.tables import aggregate, profile_depths

RESULTS = {
    "peak_disp_invert_m": "Peak displacement at the invert",
    "longterm_settlement_m": "Long-term settlement at the invert",
}
"""Summary keys drawn against the varied parameters (in mm), when the table has them."""


def display_values(path: str, values) -> np.ndarray:
    """SI values of parameter ``path`` in its display unit (conversion noise rounded off)."""
    _, factor = display_unit(path)
    return np.array([clean_number(v * factor) for v in np.asarray(values, float)])


def _dimension(path: str) -> hv.Dimension:
    """Plot dimension of parameter ``path``, labelled in its display unit."""
    return hv.Dimension(path.replace(".", "_"), label=display_label(path))


def band_plot(bands: pd.DataFrame, path: str, key: str) -> hv.Overlay:
    """Mean (line) and 5–95 % band across seeds of ``key`` (m → mm) against one parameter (in
    its display unit)."""
    x = display_values(path, bands[path])
    order = np.argsort(x)
    x = x[order]
    mean, low, high = (bands[f"{key}_{s}"].to_numpy()[order] * MM for s in ("mean", "p05", "p95"))
    value = hv.Dimension("value_mm", label=RESULTS[key], unit="mm")
    area = hv.Area(
        (x, low, high), kdims=[_dimension(path)], vdims=[value, "high"], label="5–95 % of seeds"
    ).opts(**PLOT_OPTIONS, alpha=0.3, line_width=0)
    curve = hv.Curve((x, mean), kdims=[_dimension(path)], vdims=[value], label="mean")
    return (area * curve.opts(**PLOT_OPTIONS)).opts(title=RESULTS[key])


def heat_map(bands: pd.DataFrame, path_x: str, path_y: str, key: str) -> hv.HeatMap:
    """Mean across seeds of ``key`` (m → mm) over two parameters (in their display units); the
    band in the hover."""
    data = pd.DataFrame(
        {
            "x": display_values(path_x, bands[path_x]),
            "y": display_values(path_y, bands[path_y]),
            "mean": bands[f"{key}_mean"].to_numpy() * MM,
            "p05": bands[f"{key}_p05"].to_numpy() * MM,
            "p95": bands[f"{key}_p95"].to_numpy() * MM,
        }
    )
    kdims = [
        hv.Dimension("x", label=display_label(path_x)),
        hv.Dimension("y", label=display_label(path_y)),
    ]
    vdims = [
        hv.Dimension("mean", label=f"{RESULTS[key]} (mean)", unit="mm"),
        hv.Dimension("p05", label="5 %", unit="mm"),
        hv.Dimension("p95", label="95 %", unit="mm"),
    ]
    options = {k: v for k, v in PLOT_OPTIONS.items() if k != "show_grid"}
    # the title names the quantity: the colour bar's own label stays short enough for the
    # plot's height (the whole dimension label was cut off, unit included)
    return hv.HeatMap(data, kdims=kdims, vdims=vdims).opts(
        **options,
        colorbar=True,
        clabel="Mean (mm)",
        cmap="viridis",
        title=f"{RESULTS[key]}, mean of seeds",
    )


def depth_envelope_plot(table: pd.DataFrame) -> hv.Overlay:
    """Peak displacement against depth: the 5–95 % band and the envelope (max) of every run."""
    found = profile_depths(table)
    depth = np.array([d for d, _ in found])
    peaks = table[[c for _, c in found]].dropna().to_numpy() * MM
    low, high = np.percentile(peaks, [5, 95], axis=0)
    kdims = [hv.Dimension("peak_mm", label="Peak dynamic displacement", unit="mm")]
    vdims = [hv.Dimension("depth", label="Depth below the ring–soil interface", unit="m")]
    band = hv.Polygons(
        [
            {
                "peak_mm": np.concatenate([low, high[::-1]]),
                "depth": np.concatenate([depth, depth[::-1]]),
            }
        ],
        kdims=kdims + vdims,
        label="5–95 % of runs",
    ).opts(**{k: v for k, v in PLOT_OPTIONS.items() if k != "tools"}, alpha=0.3, line_width=0)
    envelope = hv.Curve((peaks.max(axis=0), depth), kdims=kdims, vdims=vdims, label="envelope")
    median = hv.Curve((np.median(peaks, axis=0), depth), kdims=kdims, vdims=vdims, label="median")
    return (band * envelope.opts(**PLOT_OPTIONS) * median.opts(**PLOT_OPTIONS)).opts(
        title="Depth profile across the study", invert_yaxis=True
    )


def plot_slots(table: pd.DataFrame) -> dict[str, Callable[[pd.DataFrame], hv.Element]]:
    """The plots a study table calls for, by name → function of the table: per result, a band
    (one parameter) or heat map (two); then the depth envelope (if the table has the profile)."""
    paths = [c for c in table.columns if "." in c and c.partition(".")[0] in SECTIONS]
    slots = {}
    for key in (k for k in RESULTS if k in table):
        if len(paths) == 1:
            slots[key] = _bands_then(band_plot, paths[0], key=key)
        elif len(paths) == 2:
            slots[key] = _bands_then(heat_map, paths[0], paths[1], key=key)
    if profile_depths(table):
        slots["depth"] = lambda data: depth_envelope_plot(finished_rows(data))
    return slots


def finished_rows(table: pd.DataFrame) -> pd.DataFrame:
    """The rows of a study table whose runs succeeded (a failed run has no results)."""
    return table.dropna(subset=[k for k in RESULTS if k in table])


def _bands_then(draw, *paths: str, key: str):
    """``draw(aggregate(finished rows), *paths, key)`` as a function of the table."""
    return lambda table: draw(aggregate(finished_rows(table)), *paths, key)


def study_plots(table: pd.DataFrame) -> list[hv.Element | hv.Overlay]:
    """Every plot of a study table (see :func:`plot_slots`), drawn now."""
    if finished_rows(table).empty:
        return []
    return [draw(table) for draw in plot_slots(table).values()]
