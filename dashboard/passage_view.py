"""The "Passage" view: what one train passage does, in key numbers and five plots.

The key numbers of the results on screen, the derived soil quantities (they follow the soil
inputs at once, before any run), the passage plots of :mod:`dashboard.plots` with the pinned
runs of the what-if panel overlaid, and the what-if panel itself. The depth plot also draws the
other tunnel–soil model's profile and a stored FE result, given by the session's runs.
"""

from __future__ import annotations

from collections.abc import Callable

import panel as pn

from dashboard import key_numbers, plots
from dashboard.plot_panes import STALE_PLOT_STYLES, PlotPanes, PlotsView, one_message
from dashboard.report import ITEMS_CSS, items_html
from dashboard.whatif_view import WhatIfPanel
from model.params import Soil
from model.pipeline import Results

# The key numbers are dimmed like the plots while a run computes: the vehicle–track plots show
# the new run before its key numbers do (dashboard.runs.EARLY_STAGES).
SUMMARY_STYLES = {"opacity": "1"}
STALE_SUMMARY_STYLES = {"opacity": STALE_PLOT_STYLES["opacity"]}


class PassageView(PlotsView):
    """Key numbers, soil quantities, the passage plots and the what-if panel of one session.

    Parameters
    ----------
    whatif : WhatIfPanel
        The session's pinned runs: overlaid on the plots, and shown below them.
    companions : callable
        ``companions()``: keyword arguments of the depth plot's other curves (the other
        tunnel–soil model's results and a stored FE result, see
        :func:`dashboard.plots.depth_profile_plot`), asked for each time it is drawn.
    """

    def __init__(self, whatif: WhatIfPanel, companions: Callable[[], dict]) -> None:
        super().__init__()
        self.whatif = whatif
        self._companions = companions
        self.summary = pn.pane.HTML(
            "",
            css_classes=["summary-pane"],
            stylesheets=[ITEMS_CSS],
            styles=SUMMARY_STYLES,
            sizing_mode="stretch_width",
        )
        self.soil_summary = pn.pane.HTML(
            "", css_classes=["soil-pane"], stylesheets=[ITEMS_CSS], sizing_mode="stretch_width"
        )
        self.plots = PlotPanes(plots.PLOTS, self._draw_arguments)
        self._results: Results | None = None
        whatif.param.watch(self._redraw_overlays, "overlays_changed")
        self._layout = pn.Column(
            self.summary,
            self.soil_summary,
            self.plots.flexbox(),
            pn.Card(whatif, title="What-if: pinned runs", sizing_mode="stretch_width"),
            sizing_mode="stretch_width",
            name="Passage",
        )

    def __panel__(self) -> pn.viewable.Viewable:
        return self._layout

    def mark_stale(self, stages: set[str]) -> None:
        """Dim the plots that a computing run will change, and the key numbers (each run
        changes some of them; they follow at its end)."""
        super().mark_stale(stages)
        if stages:
            self.summary.styles = STALE_SUMMARY_STYLES

    def settle(self) -> None:
        """Undim the plots and the key numbers: the run they waited for failed."""
        super().settle()
        self.summary.styles = SUMMARY_STYLES

    def show(self, results: Results, redrawn: set[str]) -> None:
        """The plots of the ``redrawn`` stages, the key numbers and the what-if table follow
        ``results``."""
        self._results = results
        self.plots.show(results, redrawn)
        self.summary.object = items_html(key_numbers.summary_items(results), "summary")
        self.summary.styles = SUMMARY_STYLES
        self.whatif.refresh()

    def update_soil_summary(self, soil: Soil) -> None:
        """Derived soil quantities of ``soil`` (they follow the inputs, before any run)."""
        self.soil_summary.object = items_html(key_numbers.soil_items(soil), "soil")

    def redraw_depth_plot(self) -> None:
        """Draw the depth plot again: its other curves (``companions()``) changed."""
        if self._results is not None:
            self.plots.send(plots.MODEL_COMPARISON_PLOT, self._results)

    def close(self) -> None:
        """Drop the plots and results of a closed session."""
        super().close()
        self._results = None

    def _draw_arguments(self, spec: plots.PlotSpec) -> dict:
        """The pinned runs, and on the depth plot the other model's and the FE curves."""
        arguments = {"overlays": self.whatif.overlays()}
        if spec.key == plots.MODEL_COMPARISON_PLOT:
            arguments.update(self._companions())
        return arguments

    @one_message()
    def _redraw_overlays(self, _event=None) -> None:
        """The pinned runs changed: new passage plots (a plot's set of curves is fixed when
        it is first drawn)."""
        if self._results is not None:
            self.plots.rebuild()
