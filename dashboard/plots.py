"""Pure functions from pipeline :class:`~model.pipeline.Results` to HoloViews elements.

Used by both the dashboard (``app.py``) and the static report (``export.py``), so the two always
show the same thing. Inside the model everything is SI; here values are converted to the units a
reader expects (mm, kN, kN/m) and every axis label states its unit.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import holoviews as hv
import holoviews.plotting.bokeh  # noqa: F401  (registers the Bokeh options used below)
import numpy as np

from model.params import DATA_DIR, Soil
from model.pipeline import Results
from model.settlement import COMPARISON_DEPTH_M

REFERENCE_FILE = DATA_DIR / "paper_reference.json"

# A displayed time history keeps at most this many points: a 6-car passage at Δt = 1e-4 s has
# ~70 000 samples, far more than a plot's pixels; min/max decimation keeps every peak visible.
MAX_DISPLAY_POINTS = 4000

MM, KN = 1e3, 1e-3  # m → mm, N → kN
PLOT_HEIGHT = 300  # px

# Canvas, not HoloViews' default WebGL: a few thousand points draw fast either way, and WebGL
# falls back to slow software rendering in browsers without a GPU (headless, remote desktops).
_COMMON = {
    "responsive": True,
    "height": PLOT_HEIGHT,
    "tools": ["hover"],
    "show_grid": True,
    "backend_opts": {"plot.output_backend": "canvas"},
}
# In the dashboard the same plot is updated with new data and its axes must follow. framewise
# is a normalisation option of each element: set on an Overlay it is ignored (the axes of the
# overlaid plots stayed at the first run's ranges), so every layer carries it.
_FOLLOW_DATA = {"framewise": True}
_LEGEND_OUTSIDE = {
    "legend_position": "bottom",
    "legend_cols": 3,
}  # below the axes, never over the curves


@dataclass(frozen=True)
class PlotSpec:
    """One plot: the pipeline stage its data comes from and the function that draws it."""

    key: str
    stage: str
    draw: Callable[[Results], hv.Element]


def decimate_min_max(
    x: np.ndarray, y: np.ndarray, max_points: int = MAX_DISPLAY_POINTS
) -> tuple[np.ndarray, np.ndarray]:
    """Thin a sampled curve for display, keeping each bin's minimum and maximum in time order.

    Parameters
    ----------
    x, y : ndarray, shape (n,)
        Abscissa (increasing) and ordinate.
    max_points : int
        Upper bound on the number of points returned (at least 4).

    Returns
    -------
    x, y : ndarray
        The same arrays if ``n <= max_points``, else a subset that contains the global
        extremes, the first and the last sample.
    """
    n = y.size
    if n <= max_points:
        return x, y
    n_bins = max(1, (max_points - 2) // 2)
    bin_size = -(-n // n_bins)  # ceil
    padded = np.pad(y, (0, n_bins * bin_size - n), mode="edge").reshape(n_bins, bin_size)
    offsets = np.arange(n_bins) * bin_size
    lows = offsets + np.argmin(padded, axis=1)
    highs = offsets + np.argmax(padded, axis=1)
    keep = np.unique(
        np.concatenate(([0, n - 1], np.minimum(lows, n - 1), np.minimum(highs, n - 1)))
    )
    return x[keep], y[keep]


def _time_curve(t_s, values, label, value_dim, scale):
    """Decimated time-history curve with a labelled value dimension."""
    t, v = decimate_min_max(np.asarray(t_s), np.asarray(values) * scale)
    return hv.Curve(
        (t, v), kdims=[hv.Dimension("t", label="Time", unit="s")], vdims=[value_dim], label=label
    ).opts(**_FOLLOW_DATA)


Runs = Results | Sequence[tuple[str, Results]]
"""One run, or several labelled runs drawn on the same axes (e.g. what-if comparisons)."""


def _labelled(runs: Runs) -> list[tuple[str | None, Results]]:
    """``[(None, results)]`` for one run, else the (label, results) pairs."""
    return [(None, runs)] if isinstance(runs, Results) else list(runs)


def _combine(layers: list[hv.Element], **opts) -> hv.Element:
    """One layer as it is, several as an overlay with the legend below the axes."""
    if len(layers) == 1:
        return layers[0].opts(**opts, **_COMMON)
    return hv.Overlay(layers).opts(**opts, **_LEGEND_OUTSIDE, **_COMMON)


def block_displacement_plot(runs: Runs) -> hv.Overlay:
    """Monitored block (sleeper) displacement against time, with the Winkler-beam curve."""
    disp = hv.Dimension("block_disp", label="Displacement, down +", unit="mm")
    layers = []
    for label, results in _labelled(runs):
        vt = results.vehicle_track
        model = "Vehicle–track model" if label is None else label
        winkler = "Winkler beam (BOEF)" if label is None else f"{label}: Winkler beam"
        layers.append(_time_curve(vt.t_s, vt.block_disp_m, model, disp, MM).opts(line_width=1.5))
        layers.append(
            _time_curve(vt.t_s, vt.winkler_block_disp_m, winkler, disp, MM).opts(
                line_dash="dashed", line_width=1.5
            )
        )
    return _combine(layers, title="Sleeper (block) displacement")


def invert_load_plot(runs: Runs) -> hv.Element:
    """Force into the tunnel invert under the monitored block against time."""
    force = hv.Dimension("block_force", label="Force into the invert per block", unit="kN")
    layers = [
        _time_curve(
            results.vehicle_track.t_s,
            results.vehicle_track.block_force_N,
            "Invert load" if label is None else label,
            force,
            KN,
        )
        for label, results in _labelled(runs)
    ]
    return _combine(layers, title="Invert load")


def _psd_curve(f_hz, psd, value_dim, scale, label, max_frequency_hz):
    """Log-scale PSD curve from 0 to ``max_frequency_hz``; zero bins are left out of the log."""
    f = np.asarray(f_hz)
    p = np.asarray(psd) * scale
    keep = (f > 0) & (f <= max_frequency_hz) & (p > 0)
    return hv.Curve(
        (f[keep], p[keep]),
        kdims=[hv.Dimension("f", label="Frequency", unit="Hz")],
        vdims=[value_dim],
        label=label,
    ).opts(**_FOLLOW_DATA)


def load_psd_plot(runs: Runs) -> hv.Element:
    """One-sided PSD of the line load on the tunnel section."""
    dim = hv.Dimension("load_psd", label="PSD", unit="(kN/m)²/Hz")
    layers = [
        _psd_curve(
            results.load.f_hz,
            results.load.psd,
            dim,
            KN**2,
            "Line load" if label is None else label,
            results.scenario.numerics.soil_max_frequency,
        )
        for label, results in _labelled(runs)
    ]
    return _combine(layers, title="Invert line-load PSD", logy=True)


def interface_psd_plot(runs: Runs) -> hv.Element:
    """One-sided PSD of the displacement at the ring–soil interface under the invert."""
    dim = hv.Dimension("interface_psd", label="PSD", unit="mm²/Hz")
    layers = [
        _psd_curve(
            results.soil.f_hz,
            results.soil.interface_psd,
            dim,
            MM**2,
            "Ring–soil interface" if label is None else label,
            results.scenario.numerics.soil_max_frequency,
        )
        for label, results in _labelled(runs)
    ]
    return _combine(layers, title="Interface displacement PSD", logy=True)


def paper_reference(path: Path = REFERENCE_FILE) -> list[dict]:
    """The paper's reported peak displacements against depth: a list of labelled series (SI)."""
    with path.open(encoding="utf-8") as handle:
        return json.load(handle)["series"]


def depth_profile_plot(runs: Runs, reference: list[dict] | None = None) -> hv.Overlay:
    """Peak dynamic displacement against depth below the invert, with the paper's points."""
    reference = paper_reference() if reference is None else reference
    depth = hv.Dimension("depth", label="Depth below the invert", unit="m")
    peak = hv.Dimension("peak_disp", label="Peak dynamic displacement", unit="mm")
    layers = [
        hv.Curve(
            (results.soil.peak_disp_m * MM, results.soil.depth_m),
            kdims=[peak],
            vdims=[depth],
            label="This model" if label is None else label,
        ).opts(line_width=2, **_FOLLOW_DATA)
        for label, results in _labelled(runs)
    ]
    markers = ("circle", "triangle", "square", "diamond")
    for series, marker in zip(reference, markers, strict=False):
        points = hv.Scatter(
            (np.asarray(series["peak_disp_m"]) * MM, series["depth_m"]),
            kdims=[peak],
            vdims=[depth],
            label=series["label"],
        )
        layers.append(points.opts(marker=marker, size=10, **_FOLLOW_DATA))
    return hv.Overlay(layers).opts(
        title="Peak dynamic displacement against depth",
        invert_yaxis=True,
        padding=0.05,
        **_LEGEND_OUTSIDE,
        **_COMMON,
    )


PLOTS = (
    PlotSpec("block_displacement", "vehicle_track", block_displacement_plot),
    PlotSpec("invert_load", "vehicle_track", invert_load_plot),
    PlotSpec("load_psd", "load", load_psd_plot),
    PlotSpec("interface_psd", "soil", interface_psd_plot),
    PlotSpec("depth_profile", "soil", depth_profile_plot),
)
"""Every plot of the dashboard and the report, in display order, with the stage it reads."""


@dataclass(frozen=True)
class SummaryItem:
    """One key number: a stable key, a label, the value in display units and the unit."""

    key: str
    label: str
    value: float
    unit: str

    @property
    def text(self) -> str:
        """Value with four significant digits and its unit."""
        return f"{self.value:.4g} {self.unit}"


def summary_items(results: Results) -> list[SummaryItem]:
    """Key numbers of a run in display units, from :meth:`Results.summary`."""
    s = results.summary()
    deepest = s["deepest_depth_m"]
    return [
        SummaryItem(
            "peak_invert_force", "Peak invert load (one block)", s["peak_invert_force_N"] * KN, "kN"
        ),
        SummaryItem(
            "peak_line_load",
            "Peak line load on the section",
            s["peak_line_load_N_per_m"] * KN,
            "kN/m",
        ),
        SummaryItem(
            "peak_block_disp", "Peak sleeper displacement", s["peak_block_disp_m"] * MM, "mm"
        ),
        SummaryItem(
            "peak_disp_invert",
            "Peak dynamic displacement at the invert",
            s["peak_disp_invert_m"] * MM,
            "mm",
        ),
        SummaryItem(
            "peak_disp_11m",
            f"… {COMPARISON_DEPTH_M:g} m below the invert",
            s["peak_disp_11m_m"] * MM,
            "mm",
        ),
        SummaryItem(
            "peak_disp_deepest",
            f"… {deepest:g} m below the invert",
            s["peak_disp_deepest_m"] * MM,
            "mm",
        ),
        SummaryItem(
            "min_wheel_force", "Lowest wheel–rail force", s["min_wheel_force_N"] * KN, "kN"
        ),
    ]


def soil_items(soil: Soil) -> list[SummaryItem]:
    """Derived soil quantities c1, c2, λ, μ of a soil, in display units (m/s, MPa)."""
    return [
        SummaryItem("soil_p_wave_speed", "P-wave speed c1", soil.p_wave_speed, "m/s"),
        SummaryItem("soil_s_wave_speed", "S-wave speed c2", soil.s_wave_speed, "m/s"),
        SummaryItem("soil_lame_lambda", "Lamé λ", soil.lame_lambda * 1e-6, "MPa"),
        SummaryItem("soil_shear_modulus", "Shear modulus μ", soil.shear_modulus * 1e-6, "MPa"),
    ]
