"""The "Long-term settlement" view: pure plot functions Results → HoloViews, a calibration
panel, and :class:`LongTermView`, the tab that shows them with the law's statement.

The plots read ``Results.longterm`` (docs/model.md §10): settlement at the invert against years of
service (log axis), the permanent strain and the stress ratio q_d/σ_s against depth with the
depth that holds 90 % of the settlement, and the fit of a cyclic-triaxial calibration. The
:class:`CalibrationPanel` uploads a triaxial CSV
(``model.longterm.calibration.parse_triaxial_csv``), shows the fit and writes the fitted a, b, m
into a :class:`~model.params.LongTerm` (Li & Selig, soil class "user"). Units on screen: mm, %,
kPa.
"""

from __future__ import annotations

import holoviews as hv
import numpy as np
import panel as pn
import param
from bokeh.models import CustomJSTickFormatter

from dashboard.plot_panes import PlotPanes, PlotsView
from dashboard.plots import MM, PLOT_MIN_WIDTH, PLOT_OPTIONS, PlotSpec, legend_options
from model.longterm.calibration import TriaxialData, fit_strain_law, parse_triaxial_csv
from model.params import LongTerm
from model.pipeline import Results

KPA = 1e-3  # Pa → kPa
DEPTH = hv.Dimension("depth", label="Depth below the invert", unit="m")
FIT_CURVE_POINTS = 50
DEPTH90_LABEL = "90 % of the settlement above"

_FOLLOW_DATA = {"framewise": True}


def compact_ticks() -> CustomJSTickFormatter:
    """Tick labels with at most four significant digits and no trailing zeros (0.0005, not
    the "5.000e-4" of Bokeh's default formatter on small strains); a new model per plot (a
    Bokeh model belongs to one page)."""
    return CustomJSTickFormatter(code="return String(Number(tick.toPrecision(4)));")


def _depth_plot_options() -> dict:
    """Options of a plot against depth: depth down, the x padding that keeps the peak under
    the invert off the plot's edge, compact ticks. (Each layer carries framewise: on an
    Overlay it is ignored, and the axes kept the first run's range.)"""
    return {"invert_yaxis": True, "padding": (0.06, 0.02), "xformatter": compact_ticks()}


def _depth90_line(results: Results, values: np.ndarray, x_dim: hv.Dimension) -> list[hv.Curve]:
    """The depth holding 90 % of the settlement across the range of ``values`` (dimension
    ``x_dim``; a Curve, so that it has a legend entry; nothing when that depth is undefined)."""
    depth90 = results.longterm.depth90_m
    if not np.isfinite(depth90):
        return []
    x = [float(np.nanmin(values)), float(np.nanmax(values))]
    return [
        hv.Curve((x, [depth90, depth90]), kdims=[x_dim], vdims=[DEPTH], label=DEPTH90_LABEL).opts(
            color="grey", line_dash="dotted", line_width=1.5, **_FOLLOW_DATA
        )
    ]


def settlement_time_plot(results: Results) -> hv.Curve:
    """Settlement at the invert against years of service, log time axis."""
    lt = results.longterm
    curve = hv.Curve(
        (lt.years, lt.settlement_m * MM),
        kdims=[hv.Dimension("years", label="Service time", unit="years")],
        vdims=[hv.Dimension("settlement", label="Settlement at the invert", unit="mm")],
        label="Long-term settlement",
    )
    return curve.opts(
        title="Long-term settlement",
        logx=True,
        line_width=2,
        yformatter=compact_ticks(),
        padding=(0, 0.05),
        **PLOT_OPTIONS,
    )


def strain_depth_plot(results: Results) -> hv.Overlay:
    """Permanent strain after the service time against depth, 90 % depth marked."""
    lt = results.longterm
    strain = hv.Dimension("strain", label="Permanent strain ε_p", unit="%")
    curve = hv.Curve(
        (lt.strain_percent, lt.depth_m), kdims=[strain], vdims=[DEPTH], label="ε_p"
    ).opts(line_width=2, **_FOLLOW_DATA)
    layers = [curve, *_depth90_line(results, lt.strain_percent, strain)]
    return hv.Overlay(layers).opts(
        title=f"Permanent strain after {results.scenario.longterm.years:g} years",
        **_depth_plot_options(),
        **legend_options([layer.label for layer in layers]),
        **PLOT_OPTIONS,
    )


def stress_ratio_depth_plot(results: Results) -> hv.Overlay:
    """Dynamic deviator over static strength q_d/σ_s against depth, 90 % depth marked.

    The laws hold below q_d/σ_s = 1 (a vertical line marks it when the ratio comes near it).
    """
    lt = results.longterm
    ratio = hv.Dimension("stress_ratio", label="q_d/σ_s", unit="-")
    deviator = hv.Dimension("deviator", label="q_d", unit="kPa")
    strength = hv.Dimension("strength", label="σ_s", unit="kPa")
    curve = hv.Curve(
        (lt.stress_ratio, lt.depth_m, lt.deviator_Pa * KPA, lt.strength_Pa * KPA),
        kdims=[ratio],
        vdims=[DEPTH, deviator, strength],
        label="q_d/σ_s",
    ).opts(line_width=2, **_FOLLOW_DATA)
    layers = [curve, *_depth90_line(results, lt.stress_ratio, ratio)]
    if lt.stress_ratio.max() > 0.5:
        depths = [float(lt.depth_m.min()), float(lt.depth_m.max())]
        layers.append(
            hv.Curve(
                ([1.0, 1.0], depths), kdims=[ratio], vdims=[DEPTH], label="failure (laws not valid)"
            ).opts(color="red", **_FOLLOW_DATA)
        )
    return hv.Overlay(layers).opts(
        title="Dynamic deviator over static strength",
        **_depth_plot_options(),
        **legend_options([layer.label for layer in layers]),
        **PLOT_OPTIONS,
    )


def law_statement(results: Results) -> str:
    """Markdown naming the law, parameters and traffic, with the key numbers and warnings."""
    lt = results.longterm
    depth90 = f"{lt.depth90_m:.3g} m" if np.isfinite(lt.depth90_m) else "–"
    lines = [
        f"**Law:** {lt.statement}",
        f"**Settlement at the invert after {results.scenario.longterm.years:g} years:** "
        f"{lt.settlement_m[-1] * MM:.3g} mm; 90 % of it within {depth90} below the invert; "
        f"q_d at the invert {lt.deviator_Pa[0] * KPA:.3g} kPa "
        f"(σ_s = {lt.strength_Pa[0] * KPA:.3g} kPa).",
    ]
    lines += [f"⚠ {warning}" for warning in lt.warnings]
    return "\n\n".join(lines)


def calibration_plot(data: TriaxialData, fit: dict[str, float]) -> hv.Overlay:
    """Triaxial points ε_p against N per stress level, with the fitted law, both log axes."""
    cycles = hv.Dimension("n_cycles", label="Cycles N", unit="-")
    strain = hv.Dimension("strain", label="Permanent strain ε_p", unit="%")
    layers = []
    n_fit = np.geomspace(data.n_cycles.min(), data.n_cycles.max(), FIT_CURVE_POINTS)
    for ratio in np.unique(data.stress_ratio):
        level = data.stress_ratio == ratio
        label = f"q_d/σ_s = {ratio:.3g}"
        layers.append(
            hv.Scatter(
                (data.n_cycles[level], data.strain_percent[level]),
                kdims=[cycles],
                vdims=[strain],
                label=label,
            ).opts(size=7)
        )
        fitted = fit["a"] * ratio ** fit["m"] * n_fit ** fit["b"]
        layers.append(
            hv.Curve((n_fit, fitted), kdims=[cycles], vdims=[strain], label=label).opts(
                line_dash="dashed"
            )
        )
    return hv.Overlay(layers).opts(
        title=f"Calibration ({data.source}): ε_p = a (q_d/σ_s)^m N^b",
        logx=True,
        logy=True,
        **legend_options([layer.label for layer in layers]),  # below: never over the points
        **PLOT_OPTIONS,
    )


def fit_summary(fit: dict[str, float]) -> str:
    """Markdown of the fitted parameters with their standard errors."""
    return (
        f"a = {fit['a']:.4g} ± {fit['a_se']:.2g} %, b = {fit['b']:.4g} ± {fit['b_se']:.2g}, "
        f"m = {fit['m']:.4g} ± {fit['m_se']:.2g} (± one standard error; {fit['n_points']} "
        f"points, residual sd of ln ε_p {fit['residual_std']:.2g})"
    )


def apply_fit(longterm: LongTerm, fit: dict[str, float]) -> None:
    """Use fitted a, b, m: Li & Selig's law with soil class 'user' (one update, one event).

    All or nothing: a fitted value outside its parameter's bounds (e.g. b ≤ 0 from strains that
    do not grow with N) raises ValueError and leaves ``longterm`` unchanged.
    """
    values = {"law": "li_selig", "soil_class": "user", "a": fit["a"], "b": fit["b"], "m": fit["m"]}
    before = {name: getattr(longterm, name) for name in values}
    try:
        longterm.param.update(**values)
    except ValueError:
        longterm.param.update(**before)
        raise


LONGTERM_PLOTS = (
    PlotSpec("longterm_settlement", "longterm", settlement_time_plot),
    PlotSpec("longterm_strain", "longterm", strain_depth_plot),
    PlotSpec("longterm_stress_ratio", "longterm", stress_ratio_depth_plot),
)
"""The long-term plots with the stage they read, in the form of ``dashboard.plots.PLOTS``."""


class CalibrationPanel(pn.viewable.Viewer):
    """Upload a cyclic-triaxial CSV, see the fit, and apply a, b, m to a LongTerm object."""

    longterm = param.ClassSelector(class_=LongTerm, doc="Parameters that receive the fit.")
    data = param.ClassSelector(class_=TriaxialData, allow_None=True, doc="Last good upload.")
    fit = param.Dict(default=None, allow_None=True, doc="Fit of the last good upload.")

    def __init__(self, **params):
        params.setdefault("longterm", LongTerm())
        super().__init__(**params)
        self.file_input = pn.widgets.FileInput(accept=".csv,.txt")
        self.apply_button = pn.widgets.Button(
            label="Use fitted a, b, m (Li & Selig, user)", color="primary", disabled=True
        )
        self.message = pn.pane.Markdown(
            "Columns: N, strain (%), q_d (kPa), σ_s (kPa); lines starting with # are comments."
        )
        # axes not linked: Panel would link this plot's strain axis to the strain plot's of
        # the same page (same dimension), and redrew the long-term plots without their
        # titles, tick labels and axis positions on each upload
        self.plot = pn.pane.HoloViews(
            None,
            sizing_mode="stretch_width",
            linked_axes=False,
            min_height=PLOT_OPTIONS["height"],
            min_width=PLOT_MIN_WIDTH,
            css_classes=["plot", "plot-calibration"],
        )
        self.file_input.param.watch(self._on_upload, "value")
        self.apply_button.on_click(lambda event: self.apply())

    def load_text(self, text: str, source: str) -> None:
        """Parse and fit CSV text; show the fit, or the reason it was refused."""
        try:
            data = parse_triaxial_csv(text, source)
            fit = fit_strain_law(data.n_cycles, data.strain_percent, data.stress_ratio)
        except ValueError as error:
            self.param.update(data=None, fit=None)
            self.message.object = f"**Refused:** {error}"
            self.plot.object = None
            self.apply_button.disabled = True
            return
        self.param.update(data=data, fit=fit)
        self.message.object = f"**Fit of {source}:** {fit_summary(fit)}"
        self.plot.object = calibration_plot(data, fit)
        self.apply_button.disabled = False

    def apply(self) -> None:
        """Write the current fit into ``longterm``."""
        if self.fit is None:
            return
        try:
            apply_fit(self.longterm, self.fit)
        except ValueError as error:
            self.message.object += f"\n\n**Not applied:** {error}"
            return
        self.message.object += f"\n\nApplied to the long-term settlement: {fit_summary(self.fit)}"

    def _on_upload(self, event) -> None:
        """FileInput callback: decode the bytes and load them."""
        if event.new:
            text = event.new.decode("utf-8", errors="replace")
            self.load_text(text, self.file_input.filename or "upload.csv")

    def __panel__(self):
        return pn.Column(
            "#### Calibration from a cyclic triaxial test",
            self.file_input,
            self.message,
            self.apply_button,
            self.plot,
        )


class LongTermView(PlotsView):
    """The long-term tab of one session: the law that produced the numbers, the long-term
    plots of the results on screen, and the calibration of the strain law.

    Parameters
    ----------
    longterm : LongTerm
        The session's long-term parameters; the calibration writes its fit into them.
    """

    def __init__(self, longterm: LongTerm) -> None:
        super().__init__()
        self.law_statement = pn.pane.Markdown("", sizing_mode="stretch_width")
        self.calibration = CalibrationPanel(longterm=longterm)
        self.plots = PlotPanes(LONGTERM_PLOTS)
        self._layout = pn.Column(
            self.law_statement,
            self.plots.flexbox(),
            pn.Card(
                self.calibration,
                title="Calibrate the strain law",
                collapsed=True,
                sizing_mode="stretch_width",
            ),
            sizing_mode="stretch_width",
            name="Long-term settlement",
        )

    def __panel__(self) -> pn.viewable.Viewable:
        return self._layout

    def show(self, results: Results, redrawn: set[str]) -> None:
        """The plots of the ``redrawn`` stages and the law's statement follow ``results``."""
        self.plots.show(results, redrawn)
        self.law_statement.object = law_statement(results)
