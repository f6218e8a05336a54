"""The "Ground vibration" view: ground-surface velocity levels of the half-space model.

Pure plot functions Results → HoloViews (shared with the report) read ``Results.ground``
(docs/halfspace.md): one-third-octave velocity levels against frequency at chosen distances
from the tunnel axis, the overall level against distance, and the dynamic surface trough and
peak velocity against distance, with a criterion level drawn on the level plots. Units an
engineer reads: dB re 1e-9 m/s, Hz, m, mm, mm/s. :class:`GroundView` is the tab: its display
settings (:class:`GroundDisplay`: the criterion, the distances) redraw the plots without a run.
With a full-space ground (no surface) it says how to get the results.
"""

from __future__ import annotations

import holoviews as hv
import numpy as np
import panel as pn
import param

from dashboard.plot_panes import PlotPanes, PlotsView
from dashboard.plots import MM, PLOT_OPTIONS, PlotSpec, scenario_of
from model.pipeline import Results
from model.soil.ground_vibration import LEVEL_FLOOR_DB

LEVEL = hv.Dimension("level", label="Velocity level (dB re 1e-9 m/s)", unit=None)
DISTANCE = hv.Dimension("distance", label="Distance from the tunnel axis", unit="m")
BAND = hv.Dimension("band", label="One-third-octave band centre", unit="Hz")
KMH_PER_M_S = 3.6
LEVEL_SPAN_DB = 100.0  # the level plots show this far below their largest value
BAND_TICKS = (1, 2, 4, 8, 16, 31.5, 63)  # octave-band labels on the log frequency axis (Hz)
CRITERION_COLOUR = "#d62728"
NO_GROUND = (
    "No ground surface in this model: the full-space ground (tunnel.ground = 'full_space') has "
    "none. Choose **Ground: half_space** (with the 2.5D model) for the vibration at the surface."
)
EXCITATION_NOTE = (
    "Excitation: the invert load of the passage, convected with the train (the moving-frame "
    "rule of the 2.5D model, docs/model.md §9): the axles' quasi-static loading, exact on a "
    "smooth rail. {regime} The dynamic wheel–rail forces of the irregularity and of the "
    "sleeper passing, which dominate measured levels above ~10 Hz, are not radiated by this "
    "rule: above a few hertz these levels are a lower bound (docs/halfspace.md)."
)
SUBSONIC = (
    "The train ({speed:.0f} km/h) is slower than the soil's shear waves ({shear:.0f} km/h): "
    "this field does not radiate, so the levels fall steeply above a few hertz and reach the "
    f"reporting floor ({LEVEL_FLOOR_DB:g} dB)."
)
SUPERSONIC = (
    "The train ({speed:.0f} km/h) is faster than the soil's shear waves ({shear:.0f} km/h): "
    "this field radiates (a Mach cone), and the levels stay high far from the tunnel."
)


class GroundDisplay(param.Parameterized):
    """What the Ground vibration plots show; display settings, not model inputs."""

    criterion_db = param.Number(
        100.0,
        bounds=(LEVEL_FLOOR_DB, 200.0),
        label="Criterion (dB re 1e-9 m/s)",
        doc="A limit drawn on the level plots, e.g. a building's vibration criterion in the "
        "same reference (1e-9 m/s; a level re 5e-8 m/s is 34 dB less). The default, 100 dB "
        "(an rms velocity of 0.1 mm/s), is illustrative, not taken from a standard.",
    )
    distances_m = param.List(
        [0.0, 10.0, 20.0, 50.0],
        item_type=float,
        doc="Distances from the tunnel axis (m) whose band levels are drawn: the nearest "
        "computed distances.",
    )


def _nearest(distance_m: np.ndarray, wanted) -> list[int]:
    """Indices of the computed distances nearest to each wanted one, without repeats."""
    return sorted({int(np.argmin(np.abs(distance_m - d))) for d in wanted})


def _level_range(levels: np.ndarray, criterion_db: float | None) -> tuple[float, float]:
    """y-range of a level plot: from LEVEL_SPAN_DB below the top (not below the floor) to 10 dB
    above the top, widened to show the criterion."""
    top = float(np.max(levels))
    if criterion_db is not None:
        top = max(top, criterion_db)
    return max(LEVEL_FLOOR_DB, top - LEVEL_SPAN_DB), top + 10.0


def _criterion(criterion_db: float | None) -> list[hv.HLine]:
    """The criterion line (none if not given)."""
    if criterion_db is None:
        return []
    return [
        hv.HLine(criterion_db, label="criterion").opts(color=CRITERION_COLOUR, line_dash="dashed")
    ]


def _empty(title: str, overlay: bool = False) -> hv.Curve | hv.Overlay:
    """An empty plot titled to say why it is empty; an Overlay for a plot that draws one when
    it has data (a plot drawn once keeps its type: HoloViews cannot turn a Curve's plot into
    an Overlay's, and the plot stayed empty after a change to the half-space model)."""
    empty = hv.Curve([], kdims=[DISTANCE], vdims=[LEVEL])
    return (hv.Overlay([empty]) if overlay else empty).opts(title=title, **PLOT_OPTIONS)


def band_levels_plot(results: Results, criterion_db=None, distances_m=(0.0, 10.0, 20.0, 50.0)):
    """One-third-octave velocity levels against band centre at the chosen distances."""
    ground = results.ground
    if ground is None:
        return _empty("Band levels: no ground surface (full space)", overlay=True)
    centre = ground.band_nominal_hz
    layers = [
        hv.Curve(
            (centre, ground.velocity_level_dB[:, k]),
            kdims=[BAND],
            vdims=[LEVEL],
            label=f"{ground.distance_m[k]:g} m",
        ).opts(line_width=2, framewise=True)
        * hv.Scatter(
            (centre, ground.velocity_level_dB[:, k]),
            kdims=[BAND],
            vdims=[LEVEL],
            label=f"{ground.distance_m[k]:g} m",
        ).opts(size=5, framewise=True)  # fmt: skip
        for k in _nearest(ground.distance_m, distances_m)
    ]
    chosen = ground.velocity_level_dB[:, _nearest(ground.distance_m, distances_m)]
    return hv.Overlay([*layers, *_criterion(criterion_db)]).opts(
        title="One-third-octave velocity levels at the surface",
        logx=True,
        xticks=[(f, f"{f:g}") for f in BAND_TICKS],
        xlim=(0.8, 100.0),
        ylim=_level_range(chosen, criterion_db),
        legend_position="bottom",
        legend_cols=5,
        **PLOT_OPTIONS,
    )


def overall_level_plot(results: Results, criterion_db=None, distances_m=()):
    """Overall (energetic sum of the bands) velocity level against distance from the axis."""
    ground = results.ground
    if ground is None:
        return _empty("Overall level: no ground surface (full space)", overlay=True)
    low, high = ground.band_nominal_hz[[0, -1]] if ground.band_nominal_hz.size else (0, 0)
    curve = hv.Curve(
        (ground.distance_m, ground.overall_level_dB),
        kdims=[DISTANCE],
        vdims=[LEVEL],
        label=f"overall {low:g}–{high:g} Hz",
    ).opts(line_width=2, framewise=True)
    return hv.Overlay([curve, *_criterion(criterion_db)]).opts(
        title="Overall velocity level against distance",
        ylim=_level_range(ground.overall_level_dB, criterion_db),
        legend_position="bottom",
        **PLOT_OPTIONS,
    )


def surface_trough_plot(results: Results, criterion_db=None, distances_m=()):
    """The dynamic surface trough: peak downward displacement against distance (down +)."""
    ground = results.ground
    if ground is None:
        return _empty("Surface trough: no ground surface (full space)")
    trough = hv.Dimension("trough", label="Peak displacement, down +", unit="mm")
    return (
        hv.Curve((ground.distance_m, ground.peak_disp_m * MM), kdims=[DISTANCE], vdims=[trough])
        .opts(line_width=2, invert_yaxis=True, framewise=True)
        .opts(title="Dynamic surface trough during the passage", **PLOT_OPTIONS)
    )


def peak_velocity_plot(results: Results, criterion_db=None, distances_m=()):
    """Peak vertical surface velocity against distance from the axis."""
    ground = results.ground
    if ground is None:
        return _empty("Peak velocity: no ground surface (full space)")
    speed = hv.Dimension("peak_velocity", label="Peak vertical velocity", unit="mm/s")
    return hv.Curve(
        (ground.distance_m, ground.peak_velocity_m_per_s * MM), kdims=[DISTANCE], vdims=[speed]
    ).opts(line_width=2, title="Peak surface velocity", **PLOT_OPTIONS)


GROUND_PLOTS = (
    PlotSpec("ground_band_levels", "soil", band_levels_plot),
    PlotSpec("ground_overall_level", "soil", overall_level_plot),
    PlotSpec("ground_trough", "soil", surface_trough_plot),
    PlotSpec("ground_peak_velocity", "soil", peak_velocity_plot),
)
"""The ground plots with the stage they read (the soil stage computes ``Results.ground``)."""


def ground_statement(results: Results, criterion_db: float | None = None) -> str:
    """Markdown of the ground results' key numbers, the criterion's reach and the caveats."""
    ground = results.ground
    if ground is None:
        return NO_GROUND
    far, axis_depth = ground.distance_m[-1], scenario_of(results).tunnel.axis_depth
    lines = [
        f"**Ground surface, tunnel axis {axis_depth:g} m deep:** overall "
        f"velocity level {ground.overall_level_dB[0]:.1f} dB above the axis, "
        f"{ground.overall_level_dB[-1]:.1f} dB at {far:g} m (re 1e-9 m/s, averaged over the "
        f"{ground.averaging_s:.2f} s passage); peak velocity "
        f"{ground.peak_velocity_m_per_s[0] * MM:.3g} mm/s above the axis; dynamic trough "
        f"{ground.peak_disp_m[0] * MM:.3g} mm above the axis, "
        f"{ground.peak_disp_m[-1] * MM:.3g} mm at {far:g} m.",
    ]
    if criterion_db is not None:
        above = ground.distance_m[ground.overall_level_dB > criterion_db]
        reach = (
            f"exceeded from the axis out to {above.max():g} m"
            if above.size
            else "not exceeded at any distance"
        )
        lines.append(f"**Criterion {criterion_db:g} dB:** {reach} (overall level).")
    lines.append(
        f"**Free surface:** it changes the peak invert displacement by "
        f"{ground.free_surface_effect:+.0%} from the full-space value (pipe-in-pipe: the "
        "tunnel does not scatter the reflected waves, docs/halfspace.md)."
    )
    scenario = scenario_of(results)
    speed, shear = scenario.train.speed, scenario.soil.s_wave_speed
    regime = (SUBSONIC if speed < shear else SUPERSONIC).format(
        speed=speed * KMH_PER_M_S, shear=shear * KMH_PER_M_S
    )
    lines.append(EXCITATION_NOTE.format(regime=regime))
    return "\n\n".join(lines)


class GroundView(PlotsView):
    """The Ground vibration tab of one session: key numbers, four plots, display settings."""

    def __init__(self) -> None:
        super().__init__()
        self.display = GroundDisplay()
        criterion = self.display.param.criterion_db
        self.criterion_input = pn.widgets.FloatInput(
            label=criterion.label,
            value=criterion.default,
            start=criterion.bounds[0],
            end=criterion.bounds[1],
            step=1.0,
            description=criterion.doc,
            width=220,
            css_classes=["ground-criterion"],
        )
        self.distance_select = pn.widgets.MultiChoice(
            label="Band levels at distances (m)",
            options=[],
            value=[],
            width=420,
            css_classes=["ground-distances"],
        )
        self.statement = pn.pane.Markdown(
            NO_GROUND, sizing_mode="stretch_width", css_classes=["ground-statement"]
        )
        self.plots = PlotPanes(GROUND_PLOTS, lambda spec: self._settings())
        self._results: Results | None = None
        self._following = False  # True while show() sets the choices (no redraw then)
        self.criterion_input.param.watch(self._on_criterion, "value")
        self.distance_select.param.watch(self._on_distances, "value")
        self._settings_row = pn.Row(self.criterion_input, self.distance_select, visible=False)
        self._plots_box = self.plots.flexbox()
        self._plots_box.visible = False
        self._layout = pn.Column(
            self.statement,
            self._settings_row,
            self._plots_box,
            sizing_mode="stretch_width",
            name="Ground vibration",
        )

    def __panel__(self) -> pn.viewable.Viewable:
        return self._layout

    def _settings(self) -> dict:
        """The plots' keyword arguments: criterion and distances."""
        return {"criterion_db": self.display.criterion_db, "distances_m": self.display.distances_m}

    def show(self, results: Results, redrawn: set[str]) -> None:
        """The plots of the ``redrawn`` stages, the key numbers and the choices follow
        ``results``."""
        self._results = results
        ground = results.ground
        if ground is not None:
            options = [f"{d:g}" for d in ground.distance_m]
            chosen = [options[k] for k in _nearest(ground.distance_m, self.display.distances_m)]
            self._following = True
            try:
                self.distance_select.param.update(options=options, value=chosen)
            finally:
                self._following = False
        # a full-space ground has no surface: only the statement says so
        self._settings_row.visible = self._plots_box.visible = ground is not None
        self.plots.show(results, redrawn)
        self.statement.object = ground_statement(results, self.display.criterion_db)

    def close(self) -> None:
        """Drop the plots and results of a closed session."""
        super().close()
        self._results = None

    def _redraw(self) -> None:
        """The display settings changed: the plots and the statement follow, without a run."""
        if self._results is None or self._following:
            return
        for spec in GROUND_PLOTS:
            self.plots.send(spec.key, self._results)
        self.statement.object = ground_statement(self._results, self.display.criterion_db)

    def _on_criterion(self, event) -> None:
        """A criterion typed: within the bounds (the input enforces them), redraw."""
        if event.new is None:
            return
        self.display.criterion_db = float(event.new)
        self._redraw()

    def _on_distances(self, event) -> None:
        """Distances chosen: redraw the band levels (at least one distance is kept)."""
        if not event.new:
            return
        self.display.distances_m = [float(v) for v in event.new]
        self._redraw()
