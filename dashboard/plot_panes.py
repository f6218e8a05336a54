"""The panes that show a view's plots of a run, and how a run updates them.

Each plot (a :class:`~dashboard.plots.PlotSpec`) sits in a pane inside a box of its own. Its
first results create a DynamicMap on a stream; later ones update the Bokeh figure in place,
which is far cheaper on both ends than replacing the figure: a plot that states its axis
limits (:mod:`dashboard.axes`) and keeps its layers gets its new data and ranges set on the
Bokeh models directly (:meth:`PlotPanes._update`), any other through the stream and HoloViews.
While a run that will change a plot computes, the plot's box is dimmed. :class:`PlotsView` is
the base of the views whose plots show a run; :func:`one_message` sends a method's page changes
to the browser as one message.
"""

from __future__ import annotations

import contextlib
import functools
from collections.abc import Callable, Iterable

import holoviews as hv
import numpy as np
import panel as pn
import param
from holoviews.plotting.plot import GenericOverlayPlot
from holoviews.streams import Pipe

from dashboard import plots
from model.pipeline import Results

# The opacity is always stated: the browser keeps a style that a new set of styles leaves out.
PLOT_STYLES = {"flex": "1 1 440px", "opacity": "1"}
# A plot that a run will redraw is dimmed, not covered by Panel's animated loading spinner: the
# spinner's animation cost the browser more than the redraw itself (1.4 s of CPU per change).
STALE_PLOT_STYLES = {**PLOT_STYLES, "opacity": "0.45"}

DrawArguments = Callable[[plots.PlotSpec], dict]
"""``draw_arguments(spec)``: keyword arguments of ``spec.draw`` besides the results."""


def one_message(*, reindex_once: bool = False):
    """Decorate a page-updating method: its changes reach the browser as one message
    (:func:`message`)."""

    def decorate(method):
        @functools.wraps(method)
        def held(*args, **kwargs):
            with message(reindex_once=reindex_once):
                return method(*args, **kwargs)

        return held

    return decorate


@contextlib.contextmanager
def message(*, reindex_once: bool = False):
    """The page changes made inside reach the browser as one message.

    With ``reindex_once`` the document's models are re-indexed at most once, at the end, and
    only if a model reference changed (:func:`_index_frozen`), instead of after each such
    change (each re-indexing walks every model of the page). Only for updates of existing
    plots: a plot made while the index is frozen misses the page design's Bokeh theme (its
    title came out small).
    """
    frozen = _index_frozen(pn.state.curdoc) if reindex_once else contextlib.nullcontext()
    with frozen, pn.io.hold():
        yield


@contextlib.contextmanager
def _index_frozen(doc):
    """Freeze ``doc``'s model index; at the end re-index it only if the changes need it.

    Bokeh re-indexes its document (every model of the page, ~30 ms here) whenever its
    outermost freeze ends, even after changes of data alone, such as a run's update of the
    plots. What needs a re-indexing is what Bokeh itself reports or relies on: a change of a
    model reference (``Model.trigger`` calls ``invalidate``) and a root added or removed (whose
    re-indexing is left to the end of the freeze). Inside an outer freeze nothing changes.
    """
    models = getattr(doc, "models", None)
    if models is None or models._freeze_count:
        yield
        return
    references_changed = False

    def note_reference_change():
        nonlocal references_changed
        references_changed = True

    roots = doc.roots
    models.invalidate = note_reference_change  # this document's only, while frozen
    models._freeze_count += 1
    try:
        yield
    finally:
        models._freeze_count -= 1
        del models.invalidate
        if references_changed or doc.roots != roots:
            models.recompute()


def _drawing(spec: plots.PlotSpec, draw_arguments: DrawArguments, drawn: dict):
    """DynamicMap callback drawing the Results a Pipe stream carries (its ``data``), with the
    keyword arguments ``draw_arguments(spec)`` gives at the time of drawing; an element drawn
    already for those very Results (``drawn[spec.key]``: ``(results, element)``, see
    :meth:`PlotPanes._update`) is taken instead."""

    def callback(data):
        drawn_for, element = drawn.pop(spec.key, (None, None))
        return element if drawn_for is data else spec.draw(data, **draw_arguments(spec))

    return callback


def _pinned_apart(figure: hv.DynamicMap) -> hv.DynamicMap:
    """``figure`` with its pinned runs' layer, if any, as a static element under the rest.

    HoloViews updates only the subplots of the stream that fired, so a change of the current
    run leaves the pinned layer's subplot alone (its colour mapping and glyph were processed
    again on every change). Each combined frame takes the figure's options (title, legend,
    height) through its id, and its ranges cover both parts. The pinned runs are fixed for
    the life of a plot: a change of them makes a new plot.
    """
    frame = figure[()]
    layers = frame.values() if isinstance(frame, hv.Overlay) else [frame]
    pinned = [layer for layer in layers if isinstance(layer, plots.PinnedRuns)]
    if not pinned:
        return figure
    rest = figure.apply(
        lambda drawn: hv.Overlay([x for x in drawn if not isinstance(x, plots.PinnedRuns)])
    )
    return (pinned[0] * rest).apply(lambda combined: combined.clone(id=figure.last.id))


class ResultsPipe(Pipe):
    """The stream of a plot's Results; :meth:`hold` changes them without drawing."""

    def hold(self, data) -> None:
        """Keep ``data`` as what the plot shows (its figure was updated apart): a later
        evaluation of the DynamicMap draws it, not its last drawn element."""
        self.update(data=data)
        self._on_trigger()  # a new memoization key, as a sent event makes


def _layer_pairs(plot, element: hv.Element) -> list[tuple] | None:
    """The layers of ``element`` paired with the Bokeh sources of the drawn HoloViews
    ``plot`` that show them, as ``(layer, source, columns)``; None unless each layer can be
    shown by setting its subplot's Bokeh source: an overlay drawn as an overlay, the same
    layers in the same order, each of the same type, label and dimensions (a plot's styles
    and legend follow from its layers' labels) and drawn (HoloViews hides the glyph and the
    legend entry of a layer a frame left out, and keeps its subplot). A layer identical to
    the one shown (the pinned runs, the paper's points) is left out."""
    overlay = isinstance(element, hv.Overlay)
    if overlay != isinstance(plot, GenericOverlayPlot):
        return None
    layers = list(element) if overlay else [element]
    subplots = list(plot.subplots.values()) if overlay else [plot]
    if len(layers) != len(subplots):
        return None
    pairs = []
    for layer, subplot in zip(layers, subplots, strict=True):
        renderer = subplot.handles.get("glyph_renderer")
        if renderer is not None and not renderer.visible:
            return None
        shown = subplot.current_frame
        if shown is layer:
            continue
        source = subplot.handles.get("source")
        columns = [dimension.name for dimension in layer.dimensions()]
        if not (
            type(shown) is type(layer)
            and (shown.label, shown.kdims, shown.vdims) == (layer.label, layer.kdims, layer.vdims)
            and source is not None
            and sorted(source.data) == sorted(columns)
        ):
            return None
        pairs.append((layer, source, columns))
    return pairs


def _set_data(pairs: list[tuple]) -> None:
    """Set each layer's data on its Bokeh source (:func:`_layer_pairs`), where it changed
    (the paper's points stay as they are)."""
    for layer, source, columns in pairs:
        data = {name: layer.dimension_values(name) for name in columns}
        if any(not np.array_equal(source.data[name], data[name]) for name in columns):
            source.data = data


def _stated_limits(element: hv.Element) -> dict:
    """The axis limits ``element`` states (``xlim``, ``ylim``: :mod:`dashboard.axes`)."""
    options = hv.Store.lookup_options("bokeh", element, "plot").kwargs
    return {name: options[name] for name in ("xlim", "ylim") if name in options}


def _set_ranges(plot, limits: dict) -> None:
    """Set the figure's axis ranges to ``limits`` (:func:`_stated_limits`), as HoloViews'
    update of a plot whose layers follow their data (``framewise``) sets them."""
    for axis, name, inverted in (("x_range", "xlim", False), ("y_range", "ylim", True)):
        if name in limits:
            start, end = limits[name]
            if inverted and plot.invert_yaxis:
                start, end = end, start
            plot.handles[axis].update(start=start, end=end, reset_start=start, reset_end=end)


class PlotPanes:
    """The plots of one view, each in a pane that a run updates in place.

    Parameters
    ----------
    specs : iterable of PlotSpec
        The plots, in display order.
    draw_arguments : callable, optional
        ``draw_arguments(spec)``: keyword arguments of ``spec.draw`` besides the results (e.g.
        the pinned runs), asked for each time the plot is drawn; none by default.
    """

    def __init__(
        self, specs: Iterable[plots.PlotSpec], draw_arguments: DrawArguments | None = None
    ) -> None:
        self.specs = tuple(specs)
        self._draw_arguments = draw_arguments or (lambda spec: {})
        self.panes = {
            spec.key: pn.pane.HoloViews(
                None,
                sizing_mode="stretch_width",
                loading=True,
                min_height=plots.PLOT_HEIGHT,
                min_width=plots.PLOT_MIN_WIDTH,
                # each plot's axes follow its own data: Panel would otherwise share the ranges
                # of plots drawn in the same layout with the same dimension (both PSDs' "f",
                # on slightly different frequency grids), cutting one of them off
                linked_axes=False,
                css_classes=["plot", f"plot-{spec.key}", f"stage-{spec.stage}"],
            )
            for spec in self.specs
        }
        self.cells = {
            key: pn.Column(
                pane,
                styles=PLOT_STYLES,
                min_width=plots.PLOT_MIN_WIDTH,
                sizing_mode="stretch_width",
            )
            for key, pane in self.panes.items()
        }
        """Per plot, the box around its pane (flex item; dimmed while the plot is stale)."""
        self.streams: dict[str, ResultsPipe] = {}
        """Per plot, the stream holding the Results it shows (sent only when its stage changed)."""
        self._drawn: dict[str, tuple[Results, hv.Element]] = {}
        """Per plot, the Results its stream is about to send and the element drawn of them."""

    def flexbox(self) -> pn.FlexBox:
        """The plots' boxes in one row that wraps in a narrow window."""
        return pn.FlexBox(*self.cells.values(), sizing_mode="stretch_width")

    @property
    def drawn(self) -> bool:
        """True once every plot exists (later results update them in place)."""
        return len(self.streams) == len(self.specs)

    def is_stale(self, key: str) -> bool:
        """True while the plot ``key`` waits for a run that will change it."""
        return self.panes[key].loading or self.cells[key].styles == STALE_PLOT_STYLES

    def mark_stale(self, stages: set[str]) -> None:
        """Dim the plots of ``stages``: a run computing will change them."""
        for spec in self.specs:
            if spec.stage in stages:
                self._set_stale(spec.key, True)

    def show(self, results: Results, redrawn: set[str]) -> None:
        """Draw ``results`` in the plots of the ``redrawn`` stages; undim every plot."""
        self.show_stages(results, redrawn)
        self.settle()

    def show_stages(self, results: Results, stages: set[str]) -> None:
        """Draw ``results`` in the plots of ``stages`` (it may hold only their outputs) and
        undim them; the other plots are left as they are."""
        for spec in self.specs:
            if spec.stage in stages:
                if spec.key in self.streams:
                    self._update(spec, results)
                else:
                    self._new_plot(spec, results)
                self._set_stale(spec.key, False)

    def settle(self) -> None:
        """Undim every plot (the run they waited for failed: they keep what they show)."""
        for key in self.panes:
            self._set_stale(key, False)

    def rebuild(self) -> None:
        """New plots in place of the drawn ones, each of the results it shows (the set of
        curves a plot draws is fixed when it is made: a change of that set needs a new
        plot)."""
        for spec in self.specs:
            stream = self.streams.get(spec.key)
            if stream is not None:
                self._new_plot(spec, stream.data)

    def redraw(self, key: str, results: Results) -> None:
        """A new plot ``key`` of ``results`` in place of the drawn one (its set of curves
        changed), if it is drawn."""
        for spec in self.specs:
            if spec.key == key and key in self.streams:
                self._new_plot(spec, results)

    def send(self, key: str, results: Results) -> None:
        """Draw the plot ``key`` again, of ``results`` (if it exists)."""
        for spec in self.specs:
            if spec.key == key and key in self.streams:
                self._update(spec, results)

    def close(self) -> None:
        """Drop the plots of a closed session, without a word to its page: its models may be
        gone already (the session's other clean-ups run in no set order), and a pane told of
        a new object would update them (a failing callback in the server log)."""
        for pane in self.panes.values():
            with param.discard_events(pane):
                pane.object = None
        self.streams.clear()
        self._drawn.clear()

    def _new_plot(self, spec: plots.PlotSpec, results: Results) -> None:
        """A new plot of ``results``; its stream then updates it in place."""
        self._drawn.pop(spec.key, None)  # drawn with what the plot showed before
        stream = self.streams[spec.key] = ResultsPipe(data=results)
        self.panes[spec.key].object = _pinned_apart(
            hv.DynamicMap(_drawing(spec, self._draw_arguments, self._drawn), streams=[stream])
        )

    def _update(self, spec: plots.PlotSpec, results: Results) -> None:
        """Draw ``results`` in the existing plot of ``spec``: its data and axis ranges set on
        its Bokeh models directly where the new element states both axis limits and
        :func:`_layer_pairs` finds the layers shown, else through its stream (HoloViews draws
        it again and updates the figure)."""
        stream = self.streams[spec.key]
        figures = [plot for plot, _ in self.panes[spec.key]._plots.values()]
        if not figures:  # not on a page yet (a tab not opened): HoloViews draws it when shown
            stream.send(results)
            return
        element = spec.draw(results, **self._draw_arguments(spec))
        limits = _stated_limits(element)
        # without both limits the ranges would need HoloViews' ranging of the data
        pairs = [_layer_pairs(plot, element) for plot in figures] if len(limits) == 2 else None
        if pairs is not None and None not in pairs:
            for plot, found in zip(figures, pairs, strict=True):
                _set_data(found)
                _set_ranges(plot, limits)
            stream.hold(results)
        else:
            self._drawn[spec.key] = (results, element)  # HoloViews' callback takes it
            stream.send(results)

    def _set_stale(self, key: str, stale: bool) -> None:
        """Dim a drawn plot that a run will change (undim it when drawn); a plot not drawn yet
        shows the loading spinner until its first results."""
        pane, cell = self.panes[key], self.cells[key]
        if pane.object is None:
            pane.loading = stale
            return
        styles = STALE_PLOT_STYLES if stale else PLOT_STYLES
        # set only what changes: a setting to the same value still costs param's checks
        if pane.loading:
            pane.loading = False
        if cell.styles != styles:
            cell.styles = styles


class PlotsView(pn.viewable.Viewer):
    """Base of a view whose :attr:`plots` (a :class:`PlotPanes`, set by the subclass) show the
    session's runs: what :class:`~dashboard.runs.SessionRuns` asks of a view's plots."""

    plots: PlotPanes

    @property
    def drawn(self) -> bool:
        """True once every plot exists."""
        return self.plots.drawn

    def mark_stale(self, stages: set[str]) -> None:
        """Dim the plots that a computing run will change."""
        self.plots.mark_stale(stages)

    def settle(self) -> None:
        """Undim the plots: the run they waited for failed."""
        self.plots.settle()

    def show_stages(self, results: Results, stages: set[str]) -> None:
        """Draw the plots of ``stages`` only, from ``results`` (which may hold only their
        outputs: a run still computing its later stages)."""
        self.plots.show_stages(results, stages)

    def close(self) -> None:
        """Drop the plots of a closed session."""
        self.plots.close()
