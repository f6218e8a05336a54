"""The "Long-term settlement" view: pure plot functions Results → HoloViews, a calibration
panel, and :class:`LongTermView`, the tab that shows them with the laws' statements.

The plots read ``Results.longterm`` (docs/model.md §10, §14, §15): settlement at the invert
against years of service as its plastic and consolidation parts (log axis,
:mod:`dashboard.site_view`), the permanent strain and the stress ratio q_d/σ_s against depth with
the depth that holds 90 % of the settlement and the layer boundaries, the excess pore pressure
against depth, and the fit of a cyclic-triaxial calibration. The :class:`CalibrationPanel`
uploads a triaxial CSV (``model.longterm.calibration.parse_triaxial_csv``), shows the fits and
writes the fitted a, b, m (Li & Selig, soil class "user") and, with a pore-pressure column,
a_u, b_u, m_u (the power law) into a chosen layer of the :class:`~model.params.Site`. Units on
screen: mm, %, kPa.
"""

from __future__ import annotations

import holoviews as hv
import numpy as np
import panel as pn
import param
from bokeh.models import CustomJSTickFormatter

from dashboard.limits import TRIAXIAL_CSV_BYTES, refuse_oversized
from dashboard.longterm_checks import SettlementBandPanel, SmoothRailPanel, settlement_plot
from dashboard.plot_panes import PlotPanes, PlotsView
from dashboard.plots import (
    MM,
    PLOT_MIN_WIDTH,
    PLOT_OPTIONS,
    PlotSpec,
    legend_options,
    scenario_of,
)
from dashboard.site_view import (
    DEFAULT_YEARS,
    SITE_PLOTS,
    YEAR_CHOICES,
    LayerTable,
    layer_boundary_lines,
)
from model.longterm.calibration import (
    TriaxialData,
    fit_pore_pressure_law,
    fit_strain_law,
    parse_triaxial_csv,
)
from model.longterm.statements import OUTSIDE_LAW_RANGE, SETTLEMENT_COVERS
from model.params import Layer, LongTerm, Site
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


def strain_depth_plot(results: Results) -> hv.Overlay:
    """Permanent strain after the service time against depth, 90 % depth marked."""
    lt = results.longterm
    strain = hv.Dimension("strain", label="Permanent strain ε_p", unit="%")
    curve = hv.Curve(
        (lt.strain_percent, lt.depth_m), kdims=[strain], vdims=[DEPTH], label="ε_p"
    ).opts(line_width=2, **_FOLLOW_DATA)
    layers = [curve, *_depth90_line(results, lt.strain_percent, strain)]
    layers.append(layer_boundary_lines(results))
    return hv.Overlay(layers).opts(
        title=f"Permanent strain after {scenario_of(results).longterm.years:g} years",
        **_depth_plot_options(),
        **legend_options([layer.label for layer in layers if layer.label]),
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
    layers.append(layer_boundary_lines(results))
    return hv.Overlay(layers).opts(
        title="Dynamic deviator over static strength",
        **_depth_plot_options(),
        **legend_options([layer.label for layer in layers if layer.label]),
        **PLOT_OPTIONS,
    )


def law_statement(results: Results) -> str:
    """Markdown naming the laws, parameters and traffic, with the key numbers and warnings."""
    lt = results.longterm
    depth90 = f"{lt.depth90_m:.3g} m" if np.isfinite(lt.depth90_m) else "–"
    lines = [
        f"**What it covers:** {SETTLEMENT_COVERS}.",
        f"**Law:** {lt.statement}",
        f"**{lt.pore_pressure_statement.partition(':')[0]}:**"
        f"{lt.pore_pressure_statement.partition(':')[2]}",
        f"**Settlement at the invert after {scenario_of(results).longterm.years:g} years"
        f"{f' ({OUTSIDE_LAW_RANGE})' if lt.outside_law_range else ''}:** "
        f"{lt.settlement_m[-1] * MM:.3g} mm = {lt.plastic_settlement_m[-1] * MM:.3g} mm plastic "
        f"+ {lt.consolidation_settlement_m[-1] * MM:.3g} mm consolidation; 90 % of it within "
        f"{depth90} below the invert; q_d at the invert {lt.deviator_Pa[0] * KPA:.3g} kPa "
        f"(σ_s = {lt.strength_Pa[0] * KPA:.3g} kPa); largest excess pore pressure "
        f"{lt.excess_pore_pressure_Pa[-1].max() * KPA:.3g} kPa (generated "
        f"{lt.generated_pore_pressure_Pa[-1].max() * KPA:.3g} kPa).",
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
    """Markdown of the fitted strain-law parameters with their standard errors."""
    return (
        f"a = {fit['a']:.4g} ± {fit['a_se']:.2g} %, b = {fit['b']:.4g} ± {fit['b_se']:.2g}, "
        f"m = {fit['m']:.4g} ± {fit['m_se']:.2g} (± one standard error; {fit['n_points']} "
        f"points, residual sd of ln ε_p {fit['residual_std']:.2g})"
    )


def pore_fit_summary(fit: dict[str, float]) -> str:
    """Markdown of the fitted power law of the pore-pressure ratio, with standard errors."""
    return (
        f"a_u = {fit['a_u']:.4g} ± {fit['a_u_se']:.2g}, b_u = {fit['b_u']:.4g} ± "
        f"{fit['b_u_se']:.2g}, m_u = {fit['m_u']:.4g} ± {fit['m_u_se']:.2g} (residual sd of "
        f"ln r_u {fit['residual_std']:.2g})"
    )


def _update_all_or_nothing(updates: list[tuple[param.Parameterized, dict]]) -> None:
    """Set every object's values, or none of them (one event per object)."""
    before = [(obj, {name: getattr(obj, name) for name in values}) for obj, values in updates]
    try:
        for obj, values in updates:
            obj.param.update(**values)
    except ValueError:
        for obj, values in before:
            obj.param.update(**values)
        raise


def apply_fit(longterm: LongTerm, layer: Layer, fit: dict[str, float]) -> None:
    """Use fitted a, b, m in ``layer``: Li & Selig's law, soil class 'user', and each layer's
    own constants (``longterm.soil_set = 'layers'``, else a named set would hide the fit).

    All or nothing: a value outside its parameter's bounds raises ValueError and leaves both
    objects unchanged.
    """
    _update_all_or_nothing(
        [
            (layer, {"soil_class": "user", "a": fit["a"], "b": fit["b"], "m": fit["m"]}),
            (longterm, {"soil_set": "layers", "law": "li_selig"}),
        ]
    )


def apply_pore_fit(longterm: LongTerm, layer: Layer, fit: dict[str, float]) -> None:
    """Use fitted a_u, b_u, m_u in ``layer`` and the power law of the pore pressure (all or
    nothing, as :func:`apply_fit`)."""
    _update_all_or_nothing(
        [
            (layer, {name: fit[name] for name in ("a_u", "b_u", "m_u")}),
            (longterm, {"pore_pressure_law": "power"}),
        ]
    )


LONGTERM_PLOTS = (
    PlotSpec("longterm_settlement", "longterm", settlement_plot),
    PlotSpec("longterm_strain", "longterm", strain_depth_plot),
    PlotSpec("longterm_stress_ratio", "longterm", stress_ratio_depth_plot),
    *SITE_PLOTS[1:],
)
"""The long-term plots with the stage they read, in the form of ``dashboard.plots.PLOTS``."""
PORE_PRESSURE_PLOT = "longterm_pore_pressure"
"""The plot drawn at the years the view's year choice gives."""
SETTLEMENT_PLOT = "longterm_settlement"
"""The plot that draws the settlement band and the smooth rail's curve when there are."""


class CalibrationPanel(pn.viewable.Viewer):
    """Upload a cyclic-triaxial CSV, see the fits, and apply them to a layer of the site."""

    site = param.ClassSelector(class_=Site, doc="The site whose layer receives the fit.")
    longterm = param.ClassSelector(class_=LongTerm, doc="Receives the laws of the fits.")
    data = param.ClassSelector(class_=TriaxialData, allow_None=True, doc="Last good upload.")
    fit = param.Dict(default=None, allow_None=True, doc="Strain-law fit of the last upload.")
    pore_fit = param.Dict(default=None, allow_None=True, doc="Pore-pressure fit, if any.")

    def __init__(self, **params):
        params.setdefault("site", Site())
        params.setdefault("longterm", LongTerm())
        super().__init__(**params)
        self.file_input = pn.widgets.FileInput(accept=".csv,.txt")
        self.layer_select = pn.widgets.Select(label="Layer that receives the fit", width=260)
        self._follow_layers()
        self.site.param.watch(lambda event: self._follow_layers(), "layers")
        self.apply_button = pn.widgets.Button(
            label="Use fitted a, b, m (Li & Selig, user)", color="primary", disabled=True
        )
        self.apply_pore_button = pn.widgets.Button(
            label="Use fitted a_u, b_u, m_u (power law)", color="primary", disabled=True
        )
        self.message = pn.pane.Markdown(
            "The header names the columns with their units, in any order: n_cycles, "
            "strain_percent, deviator_kPa, strength_kPa, and optionally pore_pressure_kPa with "
            "effective_stress_kPa (or pore_pressure_ratio); lines starting with # are comments."
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
        self.apply_pore_button.on_click(lambda event: self.apply_pore())

    @property
    def layer(self) -> Layer:
        """The chosen layer."""
        return self.site.layers[self.layer_select.value or 0]

    def _follow_layers(self) -> None:
        """The layer choice lists the site's layers (the first if the chosen one is gone)."""
        options = {f"{i + 1}: {layer.name}": i for i, layer in enumerate(self.site.layers)}
        value = self.layer_select.value if self.layer_select.value in options.values() else 0
        self.layer_select.param.update(options=options, value=value)

    def load_text(self, text: str, source: str) -> None:
        """Parse and fit CSV text; show the fits, or the reason they were refused."""
        pore_fit = None
        try:
            refuse_oversized(text, source, TRIAXIAL_CSV_BYTES)
            data = parse_triaxial_csv(text, source)
            fit = fit_strain_law(data.n_cycles, data.strain_percent, data.stress_ratio)
            if data.pore_pressure_ratio is not None:
                pore_fit = fit_pore_pressure_law(
                    data.n_cycles, data.pore_pressure_ratio, data.stress_ratio
                )
        except ValueError as error:
            self.param.update(data=None, fit=None, pore_fit=None)
            self.message.object = f"**Refused:** {error}"
            self.plot.object = None
            self.apply_button.disabled = self.apply_pore_button.disabled = True
            return
        self.param.update(data=data, fit=fit, pore_fit=pore_fit)
        self.message.object = f"**Fit of {source}:** {fit_summary(fit)}"
        if pore_fit is not None:
            self.message.object += f"\n\n**Pore pressure:** {pore_fit_summary(pore_fit)}"
        self.plot.object = calibration_plot(data, fit)
        self.apply_button.disabled = False
        self.apply_pore_button.disabled = pore_fit is None

    def apply(self) -> None:
        """Write the strain-law fit into the chosen layer."""
        if self.fit is None:
            return
        self._apply(apply_fit, self.fit, fit_summary)

    def apply_pore(self) -> None:
        """Write the pore-pressure fit into the chosen layer."""
        if self.pore_fit is None:
            return
        self._apply(apply_pore_fit, self.pore_fit, pore_fit_summary)

    def _apply(self, apply, fit, summary) -> None:
        """Apply a fit to the chosen layer and say so (or why not)."""
        layer = self.layer
        try:
            apply(self.longterm, layer, fit)
        except ValueError as error:
            self.message.object += f"\n\n**Not applied:** {error}"
            return
        self.message.object += f"\n\nApplied to layer {layer.name!r}: {summary(fit)}"

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
            self.layer_select,
            pn.Row(self.apply_button, self.apply_pore_button),
            self.plot,
        )


class LongTermView(PlotsView):
    """The long-term tab of one session: the laws that produced the numbers, the site's layer
    table, the long-term plots of the results on screen, and the calibration of the laws.

    Parameters
    ----------
    longterm : LongTerm
        The session's long-term parameters; the calibration sets the laws of its fits.
    site : Site
        The session's site profile; the layer table edits it, the calibration writes its fits
        into one of its layers.
    compute : callable(Scenario) -> Results, optional
        How the smooth-rail run is computed (the dashboard passes its run with its stage
        cache); a run without a cache by default.
    scheduler : None, str or distributed.Client
        Where settlement bands run (see :func:`model.study.execution.study_client`).
    threaded : bool
        Compute bands and smooth-rail runs without blocking the caller (served app).
    """

    def __init__(
        self,
        longterm: LongTerm,
        site: Site,
        compute=None,
        scheduler=None,
        threaded: bool = False,
    ) -> None:
        super().__init__()
        self.law_statement = pn.pane.Markdown(
            "", sizing_mode="stretch_width", css_classes=["longterm-statement"]
        )
        self.band = SettlementBandPanel(
            changed=self._on_checks, scheduler=scheduler, threaded=threaded
        )
        self.smooth_rail = SmoothRailPanel(
            changed=self._on_checks, compute=compute, threaded=threaded
        )
        self.layers = LayerTable(site=site)
        self.calibration = CalibrationPanel(site=site, longterm=longterm)
        self.years = pn.widgets.MultiChoice(
            label="Excess pore pressure shown after (years; and the last year)",
            options=list(YEAR_CHOICES),
            value=list(DEFAULT_YEARS),
            sizing_mode="stretch_width",
        )
        self.plots = PlotPanes(LONGTERM_PLOTS, draw_arguments=self._draw_arguments)
        self._results: Results | None = None
        self.years.param.watch(self._on_years, "value")
        self._layout = pn.Column(
            self.law_statement,
            pn.Card(
                self.layers,
                title="Site profile: layers",
                collapsed=False,
                sizing_mode="stretch_width",
                css_classes=["site-layers"],
            ),
            self.plots.flexbox(),
            pn.Card(
                pn.FlexBox(self.band, self.smooth_rail, sizing_mode="stretch_width"),
                title="How sure, and the irregularity's share: settlement band, smooth rail",
                collapsed=False,
                sizing_mode="stretch_width",
                css_classes=["longterm-checks"],
            ),
            self.years,
            pn.Card(
                self.calibration,
                title="Calibrate the strain and pore-pressure laws",
                collapsed=True,
                sizing_mode="stretch_width",
            ),
            sizing_mode="stretch_width",
            name="Long-term settlement",
        )

    def __panel__(self) -> pn.viewable.Viewable:
        return self._layout

    def _draw_arguments(self, spec: PlotSpec) -> dict:
        """The chosen years for the pore-pressure plot, the band and the smooth rail for the
        settlement plot; nothing for the others."""
        if spec.key == SETTLEMENT_PLOT:
            return {"band": self.band.table, "smooth": self.smooth_rail.smooth}
        return {"years": tuple(self.years.value)} if spec.key == PORE_PRESSURE_PLOT else {}

    def _on_checks(self) -> None:
        """A band or smooth-rail run arrived or went: a new settlement plot (its set of curves
        changed) and statement."""
        if self._results is not None:
            self.plots.redraw(SETTLEMENT_PLOT, self._results)
            self.law_statement.object = self._statement(self._results)

    def _statement(self, results: Results) -> str:
        """The laws' statement, with the irregularity's share once the smooth rail ran."""
        share = self.smooth_rail.statement()
        return law_statement(results) + (f"\n\n{share}" if share else "")

    def _on_years(self, event) -> None:
        """Another choice of years: a new pore-pressure plot (its set of curves changed)."""
        if self._results is not None:
            self.plots.redraw(PORE_PRESSURE_PLOT, self._results)

    def show(self, results: Results, redrawn: set[str]) -> None:
        """The plots of the ``redrawn`` stages and the laws' statement follow ``results``; a
        band or smooth rail of other inputs is dropped (and the settlement plot drawn anew)."""
        self._results = results
        dropped = self.band.results_changed(results)
        dropped = self.smooth_rail.results_changed(results) or dropped
        self.plots.show(results, redrawn)
        if dropped:
            self.plots.redraw(SETTLEMENT_PLOT, results)
        self.law_statement.object = self._statement(results)

    def close(self) -> None:
        """A closed session: its band stops, its plots are dropped."""
        self.band.close()
        self.smooth_rail.close()
        super().close()
