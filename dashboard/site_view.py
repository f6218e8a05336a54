"""The site profile in the long-term tab: the layer table, its borehole CSV, and the plots of the
settlement's two parts and of the excess pore pressure (docs/model.md §14–15).

Pure plot functions Results → HoloViews (shared with the report): the settlement at the invert
against years as stacked components (plastic S_p, consolidation S_c, their sum S), the excess
pore pressure u against depth at chosen years with the undrained u_g it started from, and the
layer boundaries that every depth plot of the tab draws. :class:`LayerTable` edits the session's
:class:`~model.params.Site` in place (Panel's Tabulator, one row a layer, values in the units the
interface shows), loads a borehole CSV (``model.params.borehole``) and writes one. Units on
screen: mm, kPa, kN/m³, MPa⁻¹, m²/year.
"""

from __future__ import annotations

import html
import io
import math

import holoviews as hv
import numpy as np
import pandas as pd
import panel as pn
import param
from bokeh.models.widgets.tables import HTMLTemplateFormatter

from dashboard.limits import BOREHOLE_CSV_BYTES, refuse_oversized
from dashboard.plots import LEGEND_SPACING_PX, MM, PLOT_OPTIONS, PlotSpec, scenario_of
from model.params import LAYER_PROPERTIES, Layer, Site
from model.params.borehole import borehole_csv, parse_borehole_csv
from model.params.display import LAYER_PATH, display_label, display_unit
from model.params.site import layers_from_records
from model.pipeline import Results

KPA = 1e-3  # Pa → kPa
DEPTH = hv.Dimension("depth", label="Depth below the invert", unit="m")
YEARS = hv.Dimension("years", label="Service time", unit="years")
SETTLEMENT = hv.Dimension("settlement", label="Settlement at the invert", unit="mm")
PORE = hv.Dimension("pore_pressure", label="Excess pore pressure", unit="kPa")
BOUNDARY_STYLE = {"color": "#8c564b", "line_dash": "dashdot", "line_width": 1}
PLASTIC_COLOUR, CONSOLIDATION_COLOUR, TOTAL_COLOUR = "#1f77b4", "#ff7f0e", "#222222"
YEAR_CHOICES = (0.1, 0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0, 200.0)
"""Years the excess pore pressure can be shown at (those within the service time)."""
DEFAULT_YEARS = (1.0, 10.0)
"""Shown by default, with the last year of service."""
_LEGEND = {
    "legend_position": "bottom",
    "legend_cols": 3,
    "legend_opts": {"spacing": LEGEND_SPACING_PX},  # Bokeh's 3 px ran a label into the next line
}


def layer_boundary_lines(results: Results) -> hv.HLines:
    """Horizontal lines at the layer boundaries inside the long-term column (one element, so a
    change of the number of layers redraws the same plot)."""
    depths = np.asarray(results.longterm.layer_boundaries_m)
    label = "layer boundary" if depths.size else ""  # no legend entry without a line
    return hv.HLines(depths, label=label).opts(**BOUNDARY_STYLE)


def _layer_labels(results: Results, x: float) -> hv.Labels:
    """Each layer's name at mid-depth of its part of the column, at abscissa ``x``."""
    lt = results.longterm
    edges = np.concatenate([[lt.depth_m[0]], lt.layer_boundaries_m, [lt.depth_m[-1]]])
    middle = 0.5 * (edges[1:] + edges[:-1])
    names = [lt.layer_names[lt.layer_index[np.searchsorted(lt.depth_m, d)]] for d in middle]
    return hv.Labels((np.full(middle.size, x), middle, names), kdims=["x", DEPTH], vdims=["name"])


def settlement_components_plot(results: Results, behind=(), over=()) -> hv.Overlay:
    """Settlement at the invert against years of service (log axis), stacked: the plastic part
    S_p, the consolidation part S_c on top of it, and the total S = S_p + S_c; the elements
    ``behind`` drawn behind the total's line (over the parts, which would hide them) and
    ``over`` on top of it (the long-term tab's band and smooth rail,
    :mod:`dashboard.longterm_checks`)."""
    lt = results.longterm
    plastic = lt.plastic_settlement_m * MM
    total = lt.settlement_m * MM
    layers = [
        hv.Area(  # filled between its two values: the first is the one hover shows
            (lt.years, plastic, np.zeros_like(plastic)),
            kdims=[YEARS],
            vdims=[SETTLEMENT, "base"],
            label="plastic S_p",
        ).opts(color=PLASTIC_COLOUR, alpha=0.45, line_alpha=0, framewise=True),
        hv.Area(
            (lt.years, total, plastic),
            kdims=[YEARS],
            vdims=[SETTLEMENT, "base"],
            label="consolidation S_c",
        ).opts(color=CONSOLIDATION_COLOUR, alpha=0.45, line_alpha=0, framewise=True),
        hv.Curve((lt.years, total), kdims=[YEARS], vdims=[SETTLEMENT], label="total S").opts(
            color=TOTAL_COLOUR, line_width=2, framewise=True
        ),
    ]
    final = scenario_of(results).longterm.years
    parts, total_line = layers[:2], layers[2]
    return hv.Overlay([*parts, *behind, total_line, *over]).opts(
        title=f"Train-induced settlement: {total[-1]:.3g} mm after {final:g} years",
        logx=True,
        **_LEGEND,
        **PLOT_OPTIONS,
    )


def shown_years(results: Results, years=DEFAULT_YEARS) -> list[float]:
    """The chosen years within the service time, and its last year, increasing."""
    final = float(results.longterm.years[-1])
    return sorted({*(float(y) for y in years if y < final), final})


def pore_pressure_at(results: Results, year: float) -> np.ndarray:
    """Excess pore pressure u (Pa) against depth after ``year`` years, linear in log time
    between the stage's output years (u is smooth in time)."""
    lt = results.longterm
    log_t, target = np.log(lt.years), math.log(year)
    index = int(np.clip(np.searchsorted(log_t, target) - 1, 0, lt.years.size - 2))
    weight = np.clip((target - log_t[index]) / (log_t[index + 1] - log_t[index]), 0.0, 1.0)
    before, after = lt.excess_pore_pressure_Pa[index], lt.excess_pore_pressure_Pa[index + 1]
    return (1.0 - weight) * before + weight * after


def pore_pressure_depth_plot(results: Results, years=DEFAULT_YEARS) -> hv.Overlay:
    """Excess pore pressure u against depth at the chosen years (and the last), with the
    undrained u_g of the last year it dissipates from, the layers and their boundaries."""
    lt = results.longterm
    chosen = shown_years(results, years)
    curves = [
        hv.Curve(
            (pore_pressure_at(results, year) * KPA, lt.depth_m),
            kdims=[PORE],
            vdims=[DEPTH],
            label=f"u after {year:g} y",
        ).opts(line_width=2, framewise=True)
        for year in chosen
    ]
    generated = lt.generated_pore_pressure_Pa[-1] * KPA
    curves.append(
        hv.Curve(
            (generated, lt.depth_m),
            kdims=[PORE],
            vdims=[DEPTH],
            label=f"u_g after {chosen[-1]:g} y",
        ).opts(color="grey", line_dash="dashed", framewise=True)
    )
    largest = float(max(generated.max(), *(c.dimension_values(0).max() for c in curves)))
    labels = _layer_labels(results, 0.98 * largest if largest > 0 else 1.0).opts(
        text_align="right", text_color=BOUNDARY_STYLE["color"], text_font_size="9pt"
    )
    title = "Excess pore pressure against depth"
    if lt.pore_pressure_law == "none":
        title += " (no pore-pressure law)"
    return hv.Overlay([*curves, layer_boundary_lines(results), labels]).opts(
        title=title, invert_yaxis=True, **_LEGEND, **PLOT_OPTIONS
    )


SITE_PLOTS = (
    PlotSpec("longterm_components", "longterm", settlement_components_plot),
    PlotSpec("longterm_pore_pressure", "longterm", pore_pressure_depth_plot),
)
"""The site plots with the stage they read, in the form of ``dashboard.plots.PLOTS``."""

TABLE_COLUMNS = LAYER_PROPERTIES
"""The layer table's columns: every layer property, in declaration order."""
NUMBER_TEMPLATE = (
    '<%= (value == null || isNaN(value)) ? "–" : Number(Number(value).toPrecision(6)) %>'
)
"""Six significant digits in plain JavaScript notation (1e-9 m/s stays 1e-9, where a fixed
number of decimals showed 0.0), a dash for an optional value left empty (None)."""


def number_cell() -> HTMLTemplateFormatter:
    """The formatter of a number column, new for each table: a Bokeh model belongs to one page,
    and a formatter shared at module level held every table (and its closed session's whole
    dashboard) through the watcher each Tabulator puts on its formatters."""
    return HTMLTemplateFormatter(template=NUMBER_TEMPLATE)


def column_title(name: str) -> str:
    """A short column title: the symbol of the label with the display unit ("γ (kN/m³)"), or
    the label where it has no symbol ("Thickness (m)"); the full label is the tooltip."""
    label = display_label(LAYER_PATH + name)
    bare, _, unit = label.partition(" (")
    words = bare.split()
    symbol = words[-1]
    if len(words) < 2 or (symbol.isalpha() and symbol.islower() and len(symbol) > 2):
        return label
    return f"{symbol} ({unit}" if unit else symbol


def _tooltip(name: str) -> str:
    """The full label of a column and what the property does (its parameter's doc)."""
    return f"{display_label(LAYER_PATH + name)}. {Layer.param[name].doc or ''}".strip()


def _factor(name: str) -> float:
    """SI → display factor of a layer property."""
    return display_unit(LAYER_PATH + name)[1]


def layers_frame(layers: list[Layer]) -> pd.DataFrame:
    """The layers as a table in display units (None as NaN), one row a layer."""
    rows = []
    for layer in layers:
        row = {}
        for name in TABLE_COLUMNS:
            value = getattr(layer, name)
            if isinstance(value, str):
                row[name] = value
            else:
                row[name] = math.nan if value is None else float(f"{value * _factor(name):.12g}")
        rows.append(row)
    return pd.DataFrame(rows, columns=list(TABLE_COLUMNS))


def cell_value(name: str, shown):
    """A table cell's display value → the layer property's SI value (NaN or blank → None)."""
    if name in ("name", "soil_class"):
        return str(shown).strip()
    if shown is None or (isinstance(shown, str) and not shown.strip()):
        return None
    value = float(shown)
    return None if math.isnan(value) else value / _factor(name)


def _cell_text(value) -> str:
    """A table value as text: strings as they are, numbers to 4 digits, None as a dash."""
    if isinstance(value, str):
        return value
    return "–" if math.isnan(value) else f"{value:.4g}"


def layers_html(site: Site) -> str:
    """HTML table of the site's layers in display units (the report's site section)."""
    frame = layers_frame(site.layers)
    head = "".join(
        f'<th title="{html.escape(display_label(LAYER_PATH + n))}">'
        f"{html.escape(column_title(n))}</th>"
        for n in TABLE_COLUMNS
    )
    body = "".join(
        "<tr>" + "".join(f"<td>{html.escape(_cell_text(v))}</td>" for v in row) + "</tr>"
        for row in frame.itertuples(index=False)
    )
    return (
        f'<table class="layers"><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>'
        f"<p>Water table {site.water_table_depth:g} m below the surface.</p>"
    )


class LayerTable(pn.viewable.Viewer):
    """The site's layers, editable in place, with a borehole CSV to load and one to save.

    An edit is checked as a whole profile (``model.params.site.layers_from_records``) before it
    replaces ``site.layers``; a refused one leaves the layers as they were and says why below
    the table.

    Parameters
    ----------
    site : Site
        The session's site profile; edited in place (``site.layers`` is replaced, so watchers
        of the scenario see one change per edit).
    """

    site = param.ClassSelector(class_=Site, doc="The session's site profile.")

    def __init__(self, **params):
        params.setdefault("site", Site())
        super().__init__(**params)
        editors = {name: {"type": "number"} for name in TABLE_COLUMNS}
        editors["name"] = {"type": "input"}
        editors["soil_class"] = {"type": "list", "values": list(Layer.param["soil_class"].objects)}
        self.table = pn.widgets.Tabulator(
            layers_frame(self.site.layers),
            titles={name: column_title(name) for name in TABLE_COLUMNS},
            header_tooltips={name: _tooltip(name) for name in TABLE_COLUMNS},
            sortable=False,  # the rows are the profile top down: never reordered on screen
            editors=editors,
            formatters={
                name: number_cell() for name in TABLE_COLUMNS if name not in ("name", "soil_class")
            },
            show_index=False,
            frozen_columns=["name"],
            selectable=1,
            layout="fit_data_table",
            sizing_mode="stretch_width",
            css_classes=["layer-table"],
        )
        self.table.on_edit(self._on_edit)
        self.message = pn.pane.Markdown("", css_classes=["layer-message"], margin=(0, 10))
        self.add_button = pn.widgets.Button(label="Add a layer below", width=160)
        self.remove_button = pn.widgets.Button(label="Remove the selected layer", width=200)
        self.add_button.on_click(lambda event: self.add_layer())
        self.remove_button.on_click(lambda event: self.remove_selected())
        self.upload = pn.widgets.FileInput(accept=".csv,.txt", css_classes=["borehole-upload"])
        self.upload.param.watch(self._on_upload, "value")
        self.download = pn.widgets.FileDownload(
            callback=lambda: io.StringIO(borehole_csv(self.site.layers)),
            filename="borehole.csv",
            label="Save the layers as a borehole CSV",
            width=260,
        )
        self.site.param.watch(lambda event: self.refresh(), "layers")

    def refresh(self) -> None:
        """The table shows the site's layers (after a preset, a loaded file, an edit)."""
        self.table.value = layers_frame(self.site.layers)

    def set_records(self, records: list[dict], done: str) -> None:
        """Replace the layers by ``records`` (SI), or say why not (the layers stay)."""
        try:
            layers = layers_from_records(records)
        except (ValueError, KeyError) as error:
            self.message.object = f"**Not accepted:** {html.escape(str(error))}"
            self.refresh()
            return
        self.message.object = done
        self.site.layers = layers

    def add_layer(self) -> None:
        """A copy of the deepest layer below it, named after its position."""
        records = self.site.records()
        records.append({**records[-1], "name": f"layer {len(records) + 1}"})
        self.set_records(records, f"Added layer {len(records)} below the others.")

    def remove_selected(self) -> None:
        """Remove the selected layer (one layer always stays)."""
        selected = self.table.selection
        records = self.site.records()
        if not selected or len(records) == 1:
            self.message.object = "Select a row first; the profile keeps at least one layer."
            return
        removed = records.pop(selected[0])
        self.table.selection = []
        self.set_records(records, f"Removed layer {removed['name']!r}.")

    def load_text(self, text: str, source: str) -> None:
        """Layers from the text of a borehole CSV, or the reason it was refused."""
        try:
            refuse_oversized(text, source, BOREHOLE_CSV_BYTES)
            layers = parse_borehole_csv(text, source)
        except ValueError as error:
            self.message.object = f"**Refused:** {html.escape(str(error))}"
            return
        self.message.object = f"Loaded {len(layers)} layers from {html.escape(source)}."
        self.site.layers = layers

    def _on_edit(self, event) -> None:
        """Tabulator edit: the whole profile with the new cell, checked, or refused."""
        records = self.site.records()
        name = event.column
        try:
            value = cell_value(name, event.value)
        except (TypeError, ValueError):
            self.message.object = f"**Not accepted:** {event.value!r} is not a number"
            self.refresh()
            return
        if value is None and not Layer.param[name].allow_None:
            label = display_label(LAYER_PATH + name)
            self.message.object = f"**Not accepted:** {label} needs a value"
            self.refresh()
            return
        records[event.row][name] = value
        self.set_records(records, "")

    def _on_upload(self, event) -> None:
        """FileInput callback: decode the bytes and load them."""
        if event.new:
            text = event.new.decode("utf-8", errors="replace")
            self.load_text(text, self.upload.filename or "upload.csv")

    def __panel__(self):
        return pn.Column(
            pn.pane.Markdown(
                "One row a layer, top down from the ground surface; values in the units of the "
                "column titles (hover a title for its meaning). a, b, m are read with soil class "
                "'user' (else the class's set, named in the law above); C_r and e0 when m_v is "
                "empty; k when c_v is empty. The pore-pressure and consolidation constants "
                "default to **illustrative** values, not from a source: replace them with the "
                "site's test data.",
                margin=(0, 10),
            ),
            self.table,
            self.message,
            pn.Row(self.add_button, self.remove_button, self.download),
            pn.Row(pn.pane.Markdown("Load a borehole CSV:", margin=(5, 10)), self.upload),
            sizing_mode="stretch_width",
        )
