"""Pure functions from pipeline :class:`~model.pipeline.Results` to HoloViews elements.

Used by both the dashboard (``app.py``) and the static report (``export.py``), so the two always
show the same thing. Inside the model everything is SI; here values are converted to the units a
reader expects (mm, kN, kN/m) and every axis label states its unit.
"""

from __future__ import annotations

import functools
import json
import weakref
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import holoviews as hv
import holoviews.plotting.bokeh  # noqa: F401  (registers the Bokeh options used below)
import numpy as np

from dashboard.axes import axis_limits
from dashboard.legend_swatches import swatches_apart
from dashboard.parsed import scenario_of
from dashboard.whatif import CURRENT_COLOUR, CURRENT_LABEL
from model.fe.store import FEResult
from model.params import DATA_DIR
from model.pipeline import Results

REFERENCE_FILE = DATA_DIR / "paper_reference.json"

# A displayed time history keeps at most this many points: a 6-car passage at Δt = 1e-4 s has
# ~70 000 samples, far more than a plot's pixels; min/max decimation keeps every peak visible.
# 2000 points are a minimum and a maximum in each of ~1000 bins: at most one bin per pixel
# column on a plot up to 1000 px wide, and the time histories (the first two of five plots,
# 440 px basis each) are wider only in a main area over 5000 px; the browser maps and strokes
# half the points of 4000 on each change.
MAX_DISPLAY_POINTS = 2000
# A pinned run's time history is drawn thinner: with 8 pinned runs a plot holds 9 curves.
PINNED_DISPLAY_POINTS = 1000

MM, KN = 1e3, 1e-3  # m → mm, N → kN
PLOT_HEIGHT = 300  # px
PLOT_MIN_WIDTH = 360  # px: narrower, a plot wraps to a row of its own

# Canvas, not HoloViews' default WebGL: a few thousand points draw fast either way, and WebGL
# falls back to slow software rendering in browsers without a GPU (headless, remote desktops).
PLOT_OPTIONS = {
    "responsive": True,
    "height": PLOT_HEIGHT,
    # the same minimum size as the dashboard's plot pane gives the figure: HoloViews would
    # otherwise clear it on the first update, and the browser would lay the whole page out
    # again (1.2 s on the paper case's first change)
    "min_height": PLOT_HEIGHT,
    "min_width": PLOT_MIN_WIDTH,
    "tools": ["hover"],
    "show_grid": True,
    "framewise": True,
    "backend_opts": {"plot.output_backend": "canvas"},
}
"""Options every plot of the dashboard and the report shares."""
# In the dashboard the same plot is updated with new data and its axes must follow. framewise
# is a normalisation option of each element: set on an Overlay it is ignored (the axes of the
# overlaid plots stayed at the first run's ranges), so every layer carries it. With it,
# HoloViews' update of a plot also takes each frame's stated limits (xlim, ylim; without it
# the first frame's stayed): the path of a plot whose layers changed (plot_panes).
_FOLLOW_DATA = {"framewise": True}

LEGEND_LABEL_CHARS = 30
"""A legend entry is cut to this many characters ("…"): the full names are in the list of
pinned runs. Bokeh does not wrap a legend: a wider one widened its figure and the page."""


LEGEND_SPACING_PX = 16
"""Space between a legend's entries (px)."""


def legend_options(labels: Sequence[str]) -> dict:
    """Legend below the axes (never over the data), in as many columns (at most 3) as fit
    the narrowest plot (about 7 px per character and 40 px per entry's line and gap), the
    columns :data:`LEGEND_SPACING_PX` apart (Bokeh's default 3 px ran one entry's label into
    the next one's line).

    HoloViews would take a legend placed outside the axes (``legend_position="bottom"``) out
    of the figure and put it back on every update of the plot, and each time the browser laid
    the figure out again; the legend is made inside and moved below the axes once, by
    :func:`_legend_below`.
    """
    longest = max((len(label) for label in labels), default=1)
    columns = int(PLOT_MIN_WIDTH // (7 * longest + 40 + LEGEND_SPACING_PX))
    return {
        "legend_position": LEGEND_PLACE_HOLDER,
        "legend_cols": max(1, min(3, columns)),
        "legend_opts": {"spacing": LEGEND_SPACING_PX},
        "hooks": [_legend_below],
    }


LEGEND_PLACE_HOLDER = "top_left"
"""Where HoloViews makes a legend (inside the axes) before :func:`_legend_below` moves it."""


def _legend_below(plot, element) -> None:
    """HoloViews hook: move the figure's legends below the axes, where they stay (a plot
    updated in place keeps them there: the hook then changes nothing), and draw the entries
    named by a value from swatch renderers (:func:`~dashboard.legend_swatches.swatches_apart`)."""
    figure = plot.state
    for legend in figure.legend:
        if legend not in figure.below:
            figure.center.remove(legend)
            figure.add_layout(legend, "below")
        for item in legend.items:
            swatches_apart(figure, item)


def legend_labels(names: Sequence[str]) -> list[str]:
    """Names cut to :data:`LEGEND_LABEL_CHARS` for a legend, still distinct from each other."""
    labels: list[str] = []
    for name in names:
        label = name if len(name) <= LEGEND_LABEL_CHARS else name[: LEGEND_LABEL_CHARS - 1] + "…"
        base, k = label, 2
        while label in labels:
            label, k = f"{base[: LEGEND_LABEL_CHARS - 6]}… ({k})", k + 1
        labels.append(label)
    return labels


Overlays = Sequence[tuple[str, Results, str]]
"""Pinned runs drawn under the current one: ``(label, results, colour)`` each, bottom first."""

CURRENT_LINE_WIDTH = 2  # thicker than the pinned runs', so the current run stands out on top
PINNED_LINE_WIDTH = 1.5
# The current run keeps one style (black, solid) whether runs are pinned, whichever tunnel–soil
# model is chosen and whether the other model's curve is shown; reference lines and points
# (Winkler beam, the paper's values) are always dark grey, so that every colour names a run.
REFERENCE_COLOUR = "#555555"
REFERENCE_LINE_COLOUR = "#888888"  # dashed, lighter: it often runs over the black current run
OTHER_MODEL_COLOUR = REFERENCE_LINE_COLOUR  # the other tunnel–soil model: faint, behind
FE_COLOUR = "#8c564b"  # a stored FE result of the same scenario


@dataclass(frozen=True)
class PlotSpec:
    """One plot: the pipeline stage its data comes from and the function that draws it."""

    key: str
    stage: str
    draw: Callable[..., hv.Element]
    """``draw(results, overlays=())``: the plot of one run, with pinned runs overlaid."""


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


def _time_curve(t_s, values, label, value_dim, scale, **style):
    """Decimated time-history curve with a labelled value dimension, in ``style``."""
    t, v = decimate_min_max(np.asarray(t_s), np.asarray(values) * scale)
    return hv.Curve(
        (t, v), kdims=[hv.Dimension("t", label="Time", unit="s")], vdims=[value_dim], label=label
    ).opts(**_FOLLOW_DATA, **style)


def run_layers(
    layer: Callable[..., hv.Element],
    results: Results | None,
    label: str,
    overlays: Overlays = (),
) -> list[hv.Element]:
    """One run's layer, or with pinned runs: theirs in their colours, the current one on top.

    Parameters
    ----------
    layer : callable(results, label, **style) -> Curve
        Draws one run's curve (in the line ``style`` given, else its own).
    results : Results or None
        The current run (None: only the pinned runs, e.g. a report of a saved session).
    label : str
        Legend name of the current run when nothing is overlaid.
    overlays : sequence of (label, Results, colour)
        Pinned runs, drawn in this order under the current run, all in one
        :func:`pinned_runs_layer` layer.
    """
    current = []
    if results is not None:
        current = [
            layer(
                results,
                CURRENT_LABEL if overlays else label,
                color=CURRENT_COLOUR,
                line_width=CURRENT_LINE_WIDTH,
            )
        ]
    if not overlays:
        return current
    return [pinned_runs_layer(layer, overlays), *current]


PINNED_RUN = hv.Dimension("run", label="Pinned run")


class PinnedRuns(hv.Contours):
    """The pinned runs of a plot (:func:`pinned_runs_layer`): Contours whose ranges and
    values are computed once.

    The element is built once per set of pinned runs and its data never change, but HoloViews
    ranges every element of a plot on each update and maps the colours of every vertex's run
    name again, and over a Contours it does so path by path through a dataset made per call:
    with 8 pinned runs, most of what pinning added to the server's update of the five plots.
    The ranges stay those of the data (not a fixed ``Dimension.range``, which would override
    the current run's).
    """

    def range(self, dim, data_range=True, dimension_range=True):
        """:meth:`hv.Contours.range`, computed once per dimension and arguments."""
        key = (self.get_dimension(dim, strict=True).name, data_range, dimension_range)
        return self._once("range", key, lambda: super(PinnedRuns, self).range(*key))

    def dimension_values(self, dimension, expanded=True, flat=True):
        """:meth:`hv.Contours.dimension_values`, computed once per dimension and arguments
        (a copy each time: the caller may change it)."""
        key = (self.get_dimension(dimension, strict=True).name, expanded, flat)
        values = self._once("values", key, lambda: super(PinnedRuns, self).dimension_values(*key))
        return values.copy()

    def _once(self, what: str, key: tuple, compute: Callable[[], object]):
        """``compute()``, kept under (``what``, ``key``) for the life of the element."""
        kept = self.__dict__.setdefault("_kept", {})
        if (what, key) not in kept:
            kept[what, key] = compute()
        return kept[what, key]


hv.Store.register({PinnedRuns: hv.Store.registry["bokeh"][hv.Contours]}, "bokeh")

_PINNED_LAYERS: dict[tuple, PinnedRuns] = {}
"""Pinned layers by (layer, (id(results), name, colour) of each run), each dropped as soon as
one of its Results is."""


def pinned_runs_layer(layer: Callable[[Results, str], hv.Curve], overlays: Overlays) -> PinnedRuns:
    """Every pinned run's curve in one element, one line per run in its colour and legend entry.

    One :class:`PinnedRuns` element (one Bokeh renderer), not a Curve per run: on every change
    of the current run the browser repaints each renderer of the plot and restyles it (Bokeh reads
    its CSS on each paint); with 8 pinned runs as 8 curves that cost about 0.5 s per change
    (benchmarks/bench_whatif.py). The element is built once per set of pinned runs (a pinned
    run never changes): the very same element lets a plot updated in place skip re-sending
    its data to the browser.

    Parameters
    ----------
    layer : callable(results, label) -> Curve
        Draws one run's curve.
    overlays : sequence of (label, Results, colour)
        The pinned runs, in drawing order.
    """
    key = (layer.__qualname__, tuple((id(run), name, colour) for name, run, colour in overlays))
    cached = _PINNED_LAYERS.get(key)
    if cached is not None:
        return cached
    labels = legend_labels([name for name, _, _ in overlays])
    curves = [
        _thinned(layer(run, label)) for label, (_, run, _) in zip(labels, overlays, strict=True)
    ]
    x_dim, y_dim = curves[0].kdims[0], curves[0].vdims[0]
    paths = [
        {x_dim.name: c.dimension_values(0), y_dim.name: c.dimension_values(1), "run": label}
        for c, label in zip(curves, labels, strict=True)
    ]
    element = PinnedRuns(paths, kdims=[x_dim, y_dim], vdims=[PINNED_RUN]).opts(
        color="run",
        cmap={label: colour for label, (_, _, colour) in zip(labels, overlays, strict=True)},
        line_width=PINNED_LINE_WIDTH,
        show_legend=True,
        **_FOLLOW_DATA,
    )
    _PINNED_LAYERS[key] = element
    for _, run, _ in overlays:
        weakref.finalize(run, _PINNED_LAYERS.pop, key, None)
    return element


def _thinned(element: hv.Element) -> hv.Element:
    """A pinned run's curve with at most ``PINNED_DISPLAY_POINTS`` points (min/max decimation:
    its peaks stay); the browser redraws every curve of a plot on each change."""
    if not isinstance(element, hv.Curve) or len(element) <= PINNED_DISPLAY_POINTS:
        return element
    x, y = decimate_min_max(
        element.dimension_values(0), element.dimension_values(1), PINNED_DISPLAY_POINTS
    )
    return element.clone((x, y))


CURVE_PADDING = (0.0, 0.1)
"""Axis padding (x, y) of the time histories and PSDs (:func:`~dashboard.axes.axis_limits`):
the time axis ends at the record's ends, the frequency axis at the computed frequencies."""
DEPTH_PADDING = (0.05, 0.05)
"""Axis padding (x, y) of the depth profile: the points at the invert and the deepest depth
stay clear of the frame."""


def _overlaid(
    layers: list[hv.Element], overlays: Overlays, *, logy: bool = False, **opts
) -> hv.Element:
    """The current run's layer alone, or with pinned runs an Overlay with its legend outside;
    its axes cover every layer (:data:`CURVE_PADDING`)."""
    opts.update(axis_limits(layers, CURVE_PADDING, logy=logy), logy=logy)
    if not overlays:
        return layers[0].opts(**opts, **PLOT_OPTIONS)
    return hv.Overlay(layers).opts(**opts, **_with_legend(layers, overlays))


LEGEND_ROW_PX = 36
"""Height of a row of legend entries (a 20 px entry and the spacing)."""
LEGEND_FREE_ROWS = 2
"""Rows of legend entries a plot of :data:`PLOT_HEIGHT` holds; each further row makes the plot
taller by :data:`LEGEND_ROW_PX` (the legend is part of the figure: without that, 8 pinned runs
squeezed the axes of a plot to a strip and cut off the legend's last entries)."""


def _with_legend(layers: list[hv.Element], overlays: Overlays, also: Sequence[str] = ()) -> dict:
    """:data:`PLOT_OPTIONS` and :func:`legend_options` for the labels of ``layers``, of the
    pinned runs and ``also`` (entries that an update in place may add), the plot as much taller
    as its legend needs."""
    labels = [layer.label for layer in layers if not isinstance(layer, PinnedRuns)]
    labels = [*labels, *legend_labels([name for name, _, _ in overlays]), *also]
    legend = legend_options(labels)
    rows = -(-len(labels) // legend["legend_cols"])
    height = PLOT_HEIGHT + LEGEND_ROW_PX * max(0, rows - LEGEND_FREE_ROWS)
    return {**PLOT_OPTIONS, **legend, "height": height, "min_height": height}


BLOCK_DISP = hv.Dimension("block_disp", label="Displacement, down +", unit="mm")


def _block_disp_curve(results: Results, label: str, **style) -> hv.Curve:
    """Simulated block displacement of one run."""
    vt = results.vehicle_track
    return _time_curve(vt.t_s, vt.block_disp_m, label, BLOCK_DISP, MM, **style)


def block_displacement_plot(results: Results | None, *, overlays: Overlays = ()) -> hv.Overlay:
    """Monitored block (sleeper) displacement against time, with the Winkler-beam curve of the
    current run; pinned runs (``overlays``) are drawn under it."""
    layers = run_layers(_block_disp_curve, results, "Vehicle–track model", overlays)
    if results is not None:
        vt = results.vehicle_track
        winkler = _time_curve(
            vt.t_s,
            vt.winkler_block_disp_m,
            "Winkler beam (BOEF)",
            BLOCK_DISP,
            MM,
            color=REFERENCE_LINE_COLOUR,
            line_dash="dashed",
            line_width=2,
        )
        layers.append(winkler)
    return hv.Overlay(layers).opts(
        title="Sleeper (block) displacement",
        **_with_legend(layers, overlays),
        **axis_limits(layers, CURVE_PADDING),
    )


def _invert_load_curve(results: Results, label: str, **style) -> hv.Curve:
    """Force into the invert under the monitored block of one run."""
    force = hv.Dimension("block_force", label="Force into the invert per block", unit="kN")
    vt = results.vehicle_track
    return _time_curve(vt.t_s, vt.block_force_N, label, force, KN, **style)


def invert_load_plot(results: Results | None, *, overlays: Overlays = ()) -> hv.Curve | hv.Overlay:
    """Force into the tunnel invert under the monitored block against time (a Curve; an
    Overlay with pinned runs)."""
    layers = run_layers(_invert_load_curve, results, "Invert load", overlays)
    return _overlaid(layers, overlays, title="Invert load")


PSD_DECADES = 10
"""A PSD's axis spans this many decades below its peak (100 dB): further down lie only the
numerical floor (down to 1e-18 of the peak on the paper case), which left the physics in the
top half of the plot. The curve continues below the axis (cut by it, not removed)."""


def _psd_curve(f_hz, psd, value_dim, scale, label, max_frequency_hz, **style):
    """Log-scale PSD curve from 0 to ``max_frequency_hz`` with its axis :data:`PSD_DECADES`
    deep, in ``style``; zero bins are left out of the log."""
    f = np.asarray(f_hz)
    p = np.asarray(psd) * scale
    keep = (f > 0) & (f <= max_frequency_hz) & (p > 0)
    floor = p[keep].max() * 10.0**-PSD_DECADES if keep.any() else None
    return hv.Curve(
        (f[keep], p[keep]),
        kdims=[hv.Dimension("f", label="Frequency", unit="Hz")],
        vdims=[value_dim.clone(range=(floor, None))],
        label=label,
    ).opts(**_FOLLOW_DATA, **style)


def _load_psd_curve(results: Results, label: str, **style) -> hv.Curve:
    """Line-load PSD of one run up to its soil frequency limit."""
    dim = hv.Dimension("load_psd", label="PSD", unit="(kN/m)²/Hz")
    top = scenario_of(results).numerics.soil_max_frequency
    return _psd_curve(results.load.f_hz, results.load.psd, dim, KN**2, label, top, **style)


def load_psd_plot(results: Results | None, *, overlays: Overlays = ()) -> hv.Curve | hv.Overlay:
    """One-sided PSD of the line load on the tunnel section (an Overlay with pinned runs)."""
    layers = run_layers(_load_psd_curve, results, "Line load", overlays)
    return _overlaid(layers, overlays, title="Invert line-load PSD", logy=True)


def _interface_psd_curve(results: Results, label: str, **style) -> hv.Curve:
    """Interface displacement PSD of one run up to its soil frequency limit."""
    dim = hv.Dimension("interface_psd", label="PSD", unit="mm²/Hz")
    top = scenario_of(results).numerics.soil_max_frequency
    soil = results.soil
    return _psd_curve(soil.f_hz, soil.interface_psd, dim, MM**2, label, top, **style)


def interface_psd_plot(
    results: Results | None, *, overlays: Overlays = ()
) -> hv.Curve | hv.Overlay:
    """One-sided PSD of the displacement at the ring–soil interface under the invert (an
    Overlay with pinned runs)."""
    layers = run_layers(_interface_psd_curve, results, "At the invert", overlays)
    return _overlaid(layers, overlays, title="Interface displacement PSD", logy=True)


def paper_reference(path: Path = REFERENCE_FILE) -> list[dict]:
    """The paper's reported peak displacements against depth: a list of labelled series (SI)."""
    with path.open(encoding="utf-8") as handle:
        return json.load(handle)["series"]


DEPTH = hv.Dimension("depth", label="Depth below the invert", unit="m")
PEAK_DISP = hv.Dimension("peak_disp", label="Peak dynamic displacement", unit="mm")


@functools.cache
def _paper_points() -> tuple[hv.Scatter, ...]:
    """The paper's points of :func:`paper_reference` (fixed data: made once, and a plot
    updated in place finds the same elements and leaves them alone)."""
    markers = ("circle", "triangle", "square", "diamond")
    return tuple(
        hv.Scatter(
            (np.asarray(series["peak_disp_m"]) * MM, series["depth_m"]),
            kdims=[PEAK_DISP],
            vdims=[DEPTH],
            label=series["label"],
        ).opts(color=REFERENCE_COLOUR, marker=marker, size=9, alpha=0.8, **_FOLLOW_DATA)
        for series, marker in zip(paper_reference(), markers, strict=False)
    )


def _depth_curve(results: Results | None, label: str, **style) -> hv.Curve:
    """Peak displacement against depth of one run (empty for ``None``), in ``style``."""
    profile = ([], []) if results is None else (results.soil.peak_disp_m * MM, results.soil.depth_m)
    return hv.Curve(profile, kdims=[PEAK_DISP], vdims=[DEPTH], label=label).opts(
        **{"line_width": 2, **_FOLLOW_DATA, **style}
    )


MODEL_NAMES = {"2d": "2D section", "2.5d": "2.5D moving load"}
"""Legend names of the tunnel–soil models."""

OTHER_MODEL = {"2d": "2.5d", "2.5d": "2d"}
"""The tunnel–soil model drawn faint beside the chosen one on the depth plot."""

MODEL_COMPARISON_PLOT = "depth_profile"
"""The plot that also draws the other tunnel–soil model's profile (``other_model``) and a
stored FE result (``fe_result``)."""

FE_LAW_NAMES = {"elastic": "elastic", "mohr_coulomb": "Mohr–Coulomb"}


def depth_profile_plot(
    results: Results | None,
    *,
    overlays: Overlays = (),
    other_model: Results | None = None,
    other_model_computing: bool = False,
    fe_result: FEResult | None = None,
) -> hv.Overlay:
    """Peak dynamic displacement against depth below the invert, with the paper's points;
    pinned runs (``overlays``) are drawn under the current run, ``other_model`` (the same
    scenario with the other tunnel–soil model) as a faint dashed curve, and a stored FE result
    of the same scenario (``fe_result``, model.fe) as a dotted curve.

    While the other model's run computes (``other_model_computing``, no ``other_model`` yet)
    its curve is drawn empty: the legend keeps its entry, so the curve's arrival changes the
    plot's data and no Bokeh model (no re-indexing of the page, no legend laid out again)."""
    # the current run is named by its model whether the other model's curve is there or not
    model = None if results is None else scenario_of(results).tunnel.model
    current_label = "This model" if model is None else MODEL_NAMES[model]
    other_name = None if model is None else MODEL_NAMES[OTHER_MODEL[model]]
    layers = run_layers(_depth_curve, results, current_label, overlays)
    computing = other_model is None and other_model_computing
    if other_name and (other_model is not None or computing):
        # over the pinned runs, under the current run (the dashboard draws the pinned runs as
        # a layer of their own under the rest)
        layers.insert(
            1 if overlays else 0,
            _depth_curve(
                other_model,
                other_name,
                color=OTHER_MODEL_COLOUR,
                line_dash="dashed",
                line_width=1.5,
                alpha=0.6,
            ),
        )
    if fe_result is not None:
        layers.append(
            hv.Curve(
                (fe_result.peak_disp_m * MM, fe_result.depth_m),
                kdims=[PEAK_DISP],
                vdims=[DEPTH],
                label=f"FE section ({FE_LAW_NAMES[fe_result.soil_law]})",
            ).opts(color=FE_COLOUR, line_dash="dotted", line_width=2, **_FOLLOW_DATA)
        )
    layers += _paper_points()
    # without the other model's curve (its run failed) its legend row stays: the same height
    arriving = [other_name] if other_name and other_model is None and not computing else []
    return hv.Overlay(layers).opts(
        title="Peak dynamic displacement against depth",
        invert_yaxis=True,
        **_with_legend(layers, overlays, also=arriving),
        **axis_limits(layers, DEPTH_PADDING),
    )


PLOTS = (
    PlotSpec("block_displacement", "vehicle_track", block_displacement_plot),
    PlotSpec("invert_load", "vehicle_track", invert_load_plot),
    PlotSpec("load_psd", "load", load_psd_plot),
    PlotSpec("interface_psd", "soil", interface_psd_plot),
    PlotSpec("depth_profile", "soil", depth_profile_plot),
)
"""Every plot of the dashboard and the report, in display order, with the stage it reads."""
