"""The site's layer table and its plots without a browser: edits reach the scenario's site as
one checked profile, refusals say why beside the table and change nothing, a borehole CSV loads
and saves, and the report carries the layers."""

import holoviews as hv
import numpy as np
import pandas as pd
import pytest

from dashboard import site_view
from dashboard.report import build_report
from model.params import DATA_DIR, Layer, Site
from model.params.borehole import parse_borehole_csv
from model.pipeline import run


class Edit:
    """What Tabulator's on_edit callback receives."""

    def __init__(self, row, column, value):
        self.row, self.column, self.value = row, column, value


@pytest.fixture
def table():
    return site_view.LayerTable(site=Site())


def test_the_table_shows_the_layers_in_display_units(table):
    frame = table.table.value
    assert list(frame.columns) == list(site_view.TABLE_COLUMNS)
    row = frame.iloc[0]
    assert row["unit_weight"] == pytest.approx(17.658)  # kN/m³
    assert row["compressibility"] == pytest.approx(0.1)  # 1/MPa
    assert np.isnan(row["undrained_strength"]) and row["soil_class"] == "CH"
    assert site_view.column_title("unit_weight") == "γ (kN/m³)"
    assert site_view.column_title("thickness") == "Thickness (m)"


def test_an_edit_in_display_units_reaches_the_site(table):
    """18.5 kN/m³ typed is 18 500 N/m³ on the layer; the site's layers are replaced (one
    event for the scenario's watchers), and the table shows the new value."""
    events = []
    table.site.param.watch(events.append, "layers")
    table._on_edit(Edit(0, "unit_weight", 18.5))
    assert table.site.layers[0].unit_weight == pytest.approx(18500.0)
    assert len(events) == 1 and table.table.value.iloc[0]["unit_weight"] == pytest.approx(18.5)
    table._on_edit(Edit(0, "compressibility", None))  # cleared: m_v from C_r, e0
    assert table.site.layers[0].compressibility is None


@pytest.mark.parametrize(
    "column, value, message",
    [
        ("thickness", -3.0, r"site\.layers\[0\]\.thickness = -3 m is outside"),
        ("unit_weight", None, r"needs a value"),
        ("r_u_max", 1.5, r"site\.layers\[0\]\.r_u_max = 1\.5 is outside"),
        ("cu_ratio", "abc", r"'abc' is not a number"),
    ],
)
def test_a_refused_edit_changes_nothing_and_says_why(table, column, value, message):
    before = table.site.records()
    table._on_edit(Edit(0, column, value))
    assert table.site.records() == before
    assert "Not accepted" in table.message.object
    assert pd.Series([table.message.object]).str.contains(message).all()
    assert table.table.value.iloc[0][column] == pytest.approx(
        site_view.layers_frame(table.site.layers).iloc[0][column], nan_ok=True
    )


def test_layers_are_added_removed_loaded_and_saved(table):
    table.add_layer()
    assert [layer.name for layer in table.site.layers] == ["soft clay", "layer 2"]
    table.table.selection = [0]
    table.remove_selected()
    assert [layer.name for layer in table.site.layers] == ["layer 2"]
    table.remove_selected()  # nothing selected, and one layer stays
    assert len(table.site.layers) == 1 and "at least one layer" in table.message.object
    text = (DATA_DIR / "borehole_example.csv").read_text()
    table.upload.filename = "borehole_example.csv"
    table.upload.value = text.encode()
    assert len(table.site.layers) == 4 and "Loaded 4 layers" in table.message.object
    assert list(table.table.value["name"]) == [layer.name for layer in table.site.layers]
    saved = table.download.callback().getvalue()
    assert [layer.values() for layer in parse_borehole_csv(saved)] == table.site.records()
    table.load_text("name,thickness_m\nclay,5\n", "bad.csv")
    assert "Refused" in table.message.object and "unit_weight" in table.message.object
    assert len(table.site.layers) == 4


def test_the_table_follows_a_site_changed_elsewhere(table):
    table.site.layers = [Layer(name="clay", thickness=30.0), Layer(name="sand")]
    assert list(table.table.value["name"]) == ["clay", "sand"]


def test_plots_and_report_of_a_layered_site(cheap_scenario):
    """Two layers: the boundary drawn on the depth plots, the layer names on the pore-pressure
    plot, and the layer table in the report, in display units."""
    scenario = cheap_scenario()
    scenario.site.layers = [
        Layer(name="clay", thickness=22.0),
        Layer(name="sand", unit_weight=19e3),
    ]
    results = run(scenario, cache=None)
    lt = results.longterm
    assert lt.layer_boundaries_m.tolist() == pytest.approx([22.0 - 17.85])
    lines = site_view.layer_boundary_lines(results)
    np.testing.assert_allclose(lines.dimension_values(0), lt.layer_boundaries_m)
    assert lines.label == "layer boundary"
    overlay = site_view.pore_pressure_depth_plot(results)
    (names,) = [element for element in overlay if isinstance(element, hv.Labels)]
    assert list(names.dimension_values("name")) == ["clay", "sand"]
    hv.render(overlay, backend="bokeh")
    html = site_view.layers_html(scenario.site)
    assert '<th title="Unit weight γ (kN/m³)">γ (kN/m³)</th>' in html
    assert "<td>clay</td>" in html and "<td>19</td>" in html  # 19 000 N/m³ shown in kN/m³
    report = build_report(results)
    assert any("report-layers" in (o.css_classes or []) for o in report.objects)
