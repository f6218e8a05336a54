"""Legend entries drawn from swatch renderers, so that a plot's new data leaves its legend
alone. The HoloViews hook that :func:`dashboard.plots.legend_options` installs calls
:func:`swatches_apart` for every legend entry."""

from __future__ import annotations

import weakref

import numpy as np
from bokeh.core.property.vectorization import Value
from bokeh.models import ColumnDataSource, GlyphRenderer, MultiLine, MultiPolygons, Patches

SWATCH_TAG = "legend-swatch"
"""Tag of a swatch renderer (:func:`swatches_apart`). It also carries HoloViews' ``hv_legend``,
with which HoloViews keeps a legend entry whose renderers are all hidden (it drops the others:
the entry is shown or hidden here, with its own renderers)."""


def swatches_apart(figure, item) -> None:
    """Point a legend entry named by a value (a run, a reference) at hidden copies of its
    renderers without their data, and show the entry while its own renderers are shown.

    BokehJS draws every entry of a legend again, its DOM and a canvas per swatch, when any
    model that its entries reach changes, the data sources of their renderers included: on
    every change of the current run's curves, and with 8 pinned runs 8 more entries in each
    plot (most of what 8 pinned runs added to a change, docs/dashboard.md). A swatch renderer
    changes only with its owner's style, so new data leaves the legends alone. An entry named
    by a field (the pinned runs: one entry per run, coloured from its data) keeps its
    renderer, whose data is fixed for the life of the plot.
    """
    if not isinstance(item.label, Value):
        return
    owners = list(dict.fromkeys(_owner(renderer) for renderer in item.renderers))  # once each
    swatches = [_swatch(figure, owner) for owner in owners]
    if list(item.renderers) != swatches:
        item.renderers = swatches
    shown = any(owner.visible for owner in owners)
    if item.visible != shown:
        item.visible = shown


_SWATCH_OF_OWNER: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
_OWNER_OF_SWATCH: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
"""Swatch → owner; the owner held weakly, so that neither keeps the other alive."""
_MULTI_PATH_GLYPHS = (MultiLine, MultiPolygons, Patches)


def _owner(renderer: GlyphRenderer) -> GlyphRenderer:
    """The renderer of the plot that ``renderer`` is the swatch of, or ``renderer`` itself."""
    owner = _OWNER_OF_SWATCH.get(renderer)
    return renderer if owner is None else owner()


def _swatch(figure, owner: GlyphRenderer) -> GlyphRenderer:
    """The swatch renderer of ``owner`` (added to ``figure`` the first time), its glyph in the
    owner's style: hidden, with one row of NaN (an empty path for the glyphs of many paths) in
    each of the owner's columns, since BokehJS draws no swatch for a renderer without data. The
    swatch takes no colour from data: the entries named by a value have one style each."""
    swatch = _SWATCH_OF_OWNER.get(owner)
    style = owner.glyph.properties_with_values(include_defaults=False)
    if swatch is None:
        row = [np.array([])] if isinstance(owner.glyph, _MULTI_PATH_GLYPHS) else [np.nan]
        swatch = GlyphRenderer(
            data_source=ColumnDataSource({name: list(row) for name in owner.data_source.data}),
            glyph=type(owner.glyph)(**style),
            visible=False,
            tags=["hv_legend", SWATCH_TAG],
        )
        figure.renderers.append(swatch)
        _SWATCH_OF_OWNER[owner] = swatch
        _OWNER_OF_SWATCH[swatch] = weakref.ref(owner)
        return swatch
    shown = swatch.glyph.properties_with_values(include_defaults=False)
    restyled = {name: value for name, value in style.items() if shown.get(name) != value}
    if restyled:  # setting an equal value would still reach the browser, and redraw the legend
        swatch.glyph.update(**restyled)
    return swatch
