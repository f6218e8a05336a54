"""Plots of a study table: pure functions of its rows → HoloViews, shared by the Study view and
the study report (:mod:`dashboard.study_report`).

Per result of :data:`RESULTS` (in mm): the mean with its band across seeds against one varied
parameter (5–95 % from :data:`MIN_SEEDS_FOR_PERCENTILES` seeds on, the whole range of fewer),
or a heat map of the mean over two; and the envelope of the peak-displacement depth profiles.
Parameters are shown in their display units (MPa, MN/m, …); the table is SI. The plots of a
cancelled study's rows say in their titles that they are partial.
"""

from __future__ import annotations

from collections.abc import Callable

import holoviews as hv
import numpy as np
import pandas as pd

from dashboard.controls import clean_number
from dashboard.plots import MM, PLOT_OPTIONS, legend_options
from model.params import SECTIONS, display_label, display_unit
from model.study.tables import aggregate, profile_depths

RESULTS = {
    "peak_disp_invert_m": "Peak displacement at the invert",
    "longterm_settlement_m": "Long-term settlement at the invert",
}
"""Summary keys drawn against the varied parameters (in mm), when the table has them."""

MIN_SEEDS_FOR_PERCENTILES = 20
"""Fewer seeds than this at a point and the band is their whole range (min–max): the 5 % and
95 % quantiles of fewer than 20 values are only interpolated between the extreme ones."""

_LEGEND = legend_options(["min–max of 19 seeds", "mean"])
"""Legends below the plot: over it they covered the bands and the envelope."""


def display_values(path: str, values) -> np.ndarray:
    """SI values of parameter ``path`` in its display unit (conversion noise rounded off)."""
    _, factor = display_unit(path)
    return np.array([clean_number(v * factor) for v in np.asarray(values, float)])


def _dimension(path: str) -> hv.Dimension:
    """Plot dimension of parameter ``path``, labelled in its display unit."""
    return hv.Dimension(path.replace(".", "_"), label=display_label(path))


def study_bands(rows: pd.DataFrame) -> pd.DataFrame:
    """:func:`model.study.tables.aggregate` of a study's finished rows (mean, 5 % and 95 %)
    with the minimum and maximum across seeds (columns ``<result>_p00``, ``<result>_p100``)."""
    bands = aggregate(rows)
    extremes = aggregate(rows, band=(0.0, 1.0))
    for column in extremes.columns:
        if column.endswith(("_p00", "_p100")):
            bands[column] = extremes[column].to_numpy()
    return bands


def band_statistics(bands: pd.DataFrame) -> tuple[str, str, str]:
    """Column suffixes of a band's low and high ends and its legend label for the seeds at
    each point (``n_runs`` of :func:`model.study.tables.aggregate` with ``band=(0, 1)``)."""
    fewest, most = int(bands["n_runs"].min()), int(bands["n_runs"].max())
    if fewest >= MIN_SEEDS_FOR_PERCENTILES:
        return "p05", "p95", "5–95 % of seeds"
    seeds = f"{fewest}" if fewest == most else f"{fewest}–{most}"
    return "p00", "p100", f"min–max of {seeds} seeds"


def band_plot(bands: pd.DataFrame, path: str, key: str, title: str | None = None) -> hv.Overlay:
    """Mean (line and markers) and band across seeds (:func:`band_statistics`) of ``key``
    (m → mm) against one parameter (in its display unit); ``bands`` from
    :func:`study_bands`; no band where every point has one seed."""
    x = display_values(path, bands[path])
    order = np.argsort(x)
    x = x[order]
    low_column, high_column, band_label = band_statistics(bands)
    mean, low, high = (
        bands[f"{key}_{s}"].to_numpy()[order] * MM for s in ("mean", low_column, high_column)
    )
    value = hv.Dimension("value_mm", label=RESULTS[key], unit="mm")
    layers = []
    if bands["n_runs"].max() > 1:
        layers.append(
            hv.Area(
                (x, low, high), kdims=[_dimension(path)], vdims=[value, "high"], label=band_label
            ).opts(**PLOT_OPTIONS, alpha=0.3, line_width=0)
        )
    curve = hv.Curve((x, mean), kdims=[_dimension(path)], vdims=[value], label="mean")
    points = hv.Scatter((x, mean), kdims=[_dimension(path)], vdims=[value], label="mean")
    layers += [curve.opts(**PLOT_OPTIONS), points.opts(size=7, **PLOT_OPTIONS)]
    return hv.Overlay(layers).opts(title=title or RESULTS[key], **_LEGEND, padding=0.05)


def heat_map(
    bands: pd.DataFrame, path_x: str, path_y: str, key: str, title: str | None = None
) -> hv.HeatMap:
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
        title=title or f"{RESULTS[key]}, mean of seeds",
    )


def depth_envelope_plot(table: pd.DataFrame, title: str | None = None) -> hv.Overlay:
    """Peak displacement against depth: the band across runs (5–95 %, or min–max of fewer
    than :data:`MIN_SEEDS_FOR_PERCENTILES` runs) and the envelope (max) of every run."""
    found = profile_depths(table)
    depth = np.array([d for d, _ in found])
    peaks = table[[c for _, c in found]].dropna().to_numpy() * MM
    few = len(peaks) < MIN_SEEDS_FOR_PERCENTILES
    low, high = np.percentile(peaks, [0, 100] if few else [5, 95], axis=0)
    band_label = f"min–max of {len(peaks)} runs" if few else "5–95 % of runs"
    kdims = [hv.Dimension("peak_mm", label="Peak dynamic displacement", unit="mm")]
    vdims = [hv.Dimension("depth", label="Depth below the invert", unit="m")]
    band = hv.Polygons(
        [
            {
                "peak_mm": np.concatenate([low, high[::-1]]),
                "depth": np.concatenate([depth, depth[::-1]]),
            }
        ],
        kdims=kdims + vdims,
        label=band_label,
    ).opts(**{k: v for k, v in PLOT_OPTIONS.items() if k != "tools"}, alpha=0.3, line_width=0)
    envelope = hv.Curve((peaks.max(axis=0), depth), kdims=kdims, vdims=vdims, label="envelope")
    median = hv.Curve((np.median(peaks, axis=0), depth), kdims=kdims, vdims=vdims, label="median")
    return (band * envelope.opts(**PLOT_OPTIONS) * median.opts(**PLOT_OPTIONS)).opts(
        title=title or "Depth profile across the study", invert_yaxis=True, **_LEGEND
    )


def partial_note(table: pd.DataFrame) -> str:
    """ " (partial: 37 of 200 runs)" for the rows of a study that is not finished (cancelled,
    or still running), else ""."""
    n_runs = table.attrs.get("n_runs")
    if n_runs is None or (len(table) >= n_runs and not table.attrs.get("cancelled")):
        return ""
    return f" (partial: {len(table)} of {n_runs} runs)"


def plot_slots(table: pd.DataFrame) -> dict[str, Callable[[pd.DataFrame], hv.Element]]:
    """The plots a study table calls for, by name → function of the table: per result, a band
    (one parameter) or heat map (two); then the depth envelope (if the table has the profile).
    Their titles say when the table's study is partial (:func:`partial_note`)."""
    paths = [c for c in table.columns if "." in c and c.partition(".")[0] in SECTIONS]
    slots = {}
    for key in (k for k in RESULTS if k in table):
        if len(paths) == 1:
            slots[key] = _bands_then(band_plot, paths[0], key=key)
        elif len(paths) == 2:
            slots[key] = _bands_then(heat_map, paths[0], paths[1], key=key)
    if profile_depths(table):
        slots["depth"] = lambda data: depth_envelope_plot(
            finished_rows(data), "Depth profile across the study" + partial_note(data)
        )
    return slots


def finished_rows(table: pd.DataFrame) -> pd.DataFrame:
    """The rows of a study table whose runs succeeded (a failed run has no results)."""
    return table.dropna(subset=[k for k in RESULTS if k in table])


def _bands_then(draw, *paths: str, key: str):
    """``draw(bands of the finished rows, *paths, key, title)`` as a function of the table:
    the 5–95 % columns and the min–max ones (p00, p100)."""

    def drawn(table: pd.DataFrame):
        bands = study_bands(finished_rows(table))
        title = {"heat_map": f"{RESULTS[key]}, mean of seeds"}.get(draw.__name__, RESULTS[key])
        return draw(bands, *paths, key, title + partial_note(table))

    return drawn


def study_plots(table: pd.DataFrame) -> list[hv.Element | hv.Overlay]:
    """Every plot of a study table (see :func:`plot_slots`), drawn now."""
    if finished_rows(table).empty:
        return []
    return [draw(table) for draw in plot_slots(table).values()]
