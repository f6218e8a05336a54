"""Panel component of the what-if tools: pin runs, manage them, compare, save and load.

:class:`WhatIfPanel` is given three callables by the dashboard and knows nothing else of it:
``current()`` returns the current (Scenario, Results or None), ``restore(scenario)`` makes a
scenario current, ``compute(scenario)`` computes a run when a session file is loaded (through the
dashboard's stage cache). Whenever the set of overlaid runs changes (pin, remove, rename,
hide/show, load) it triggers its ``overlays_changed`` event, on which the dashboard redraws its
plots with :meth:`WhatIfPanel.overlays`.
"""

from __future__ import annotations

import html
import io
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial

import panel as pn
import param

from dashboard.export import COMPARISON_CSS, comparison_html, session_report_html
from dashboard.whatif import (
    CURRENT_LABEL,
    MAX_PINNED,
    Compute,
    PinnedRun,
    WhatIfSession,
    load_session,
    save_session,
)
from model.params import Scenario
from model.pipeline import Results, SimulationError, run

Current = Callable[[], tuple[Scenario, Results | None]]


@dataclass(frozen=True)
class RunRow:
    """The controls of one pinned run in the list."""

    name: str
    name_input: pn.widgets.TextInput
    visible: pn.widgets.Checkbox
    restore_button: pn.widgets.Button
    remove_button: pn.widgets.Button
    layout: pn.Row


def _swatch(colour: str) -> pn.pane.HTML:
    """A small square of a run's plot colour."""
    return pn.pane.HTML(
        f'<div style="width: 14px; height: 14px; background: {colour}; border-radius: 3px; '
        'margin-top: 10px"></div>',
        width=20,
        margin=(0, 0, 0, 5),
    )


class WhatIfPanel(pn.viewable.Viewer):
    """Pinned runs of one dashboard session, their comparison table and the session file.

    Parameters
    ----------
    current : callable() -> (Scenario, Results or None)
        The current inputs and the results on screen (None before the first run).
    restore : callable(Scenario)
        Make a scenario the current one (the dashboard re-runs it).
    compute : callable(Scenario) -> Results, optional
        Computes the runs of a loaded session file; default :func:`model.pipeline.run` without a
        cache. The dashboard passes one that uses its stage cache.
    preset : callable() -> str, optional
        Name of the preset default names are taken relative to (default ``"paper"``).
    """

    overlays_changed = param.Event(
        doc="Triggered when the overlaid runs, their names or colours change."
    )

    def __init__(
        self,
        current: Current,
        restore: Callable[[Scenario], None],
        compute: Compute | None = None,
        preset: Callable[[], str] | None = None,
        **params,
    ):
        super().__init__(**params)
        self._current = current
        self._restore = restore
        self._compute = compute if compute is not None else partial(run, cache=None)
        self._preset = preset if preset is not None else (lambda: "paper")
        self.session = WhatIfSession()
        self.rows: list[RunRow] = []

        self.name_input = pn.widgets.TextInput(
            placeholder="Name (default: what differs from the preset)",
            sizing_mode="stretch_width",
            css_classes=["whatif-name"],
        )
        self.pin_button = pn.widgets.Button(
            label="Pin current run",
            color="primary",
            sizing_mode="stretch_width",
            css_classes=["whatif-pin"],
        )
        self.pin_button.on_click(self._on_pin)
        self.message = pn.pane.HTML(
            "",
            visible=False,
            styles={
                "color": "#82071e",
                "background": "#ffebe9",
                "border": "1px solid #ff818266",
                "border-radius": "6px",
                "padding": "0 8px",
            },
            sizing_mode="stretch_width",
            css_classes=["whatif-message"],
        )
        self.runs_column = pn.Column(sizing_mode="stretch_width", css_classes=["whatif-runs"])
        self.reference_select = pn.widgets.Select(
            label="Differences to",
            options=[CURRENT_LABEL],
            value=CURRENT_LABEL,
            sizing_mode="stretch_width",
            css_classes=["whatif-reference"],
        )
        self.reference_select.param.watch(self._on_reference, "value")
        self.table = pn.pane.HTML(
            "",
            stylesheets=[COMPARISON_CSS],
            styles={"overflow-x": "auto"},  # a wide table scrolls instead of overflowing
            sizing_mode="stretch_width",
            css_classes=["whatif-table"],
        )
        self.save_button = pn.widgets.FileDownload(
            callback=self._session_file,
            filename="whatif_session.json",
            label="Save session",
            sizing_mode="stretch_width",
            css_classes=["whatif-save"],
        )
        self.load_input = pn.widgets.FileInput(
            accept=".json", multiple=False, sizing_mode="stretch_width", css_classes=["whatif-load"]
        )
        self.load_input.param.watch(self._on_load, "value")
        self.report_button = pn.widgets.FileDownload(
            callback=self._report_file,
            filename="whatif_report.html",
            label="Download session report",
            sizing_mode="stretch_width",
            css_classes=["whatif-report"],
        )
        if pn.state.curdoc is not None and pn.state.curdoc.session_context is not None:
            pn.state.on_session_destroyed(self._release)
        self._rebuild()

    # ---- layout ---------------------------------------------------------------------------
    def controls(self) -> pn.Column:
        """Pin, the list of pinned runs and the session file (fits a sidebar)."""
        return pn.Column(
            pn.Row(self.name_input, self.pin_button, sizing_mode="stretch_width"),
            self.message,
            self.runs_column,
            pn.Row(self.save_button, self.report_button, sizing_mode="stretch_width"),
            pn.Row(
                pn.pane.Markdown("Load a session file:", width=150),
                self.load_input,
                sizing_mode="stretch_width",
            ),
            sizing_mode="stretch_width",
        )

    def comparison(self) -> pn.Column:
        """Reference selector and comparison table (wide: for the main area)."""
        return pn.Column(self.reference_select, self.table, sizing_mode="stretch_width")

    def __panel__(self) -> pn.viewable.Viewable:
        return pn.Column(self.controls(), self.comparison(), sizing_mode="stretch_width")

    # ---- what the dashboard calls ---------------------------------------------------------
    def overlays(self) -> list[tuple[str, Results, str]]:
        """``(name, results, colour)`` of the visible pinned runs, for the plots."""
        return self.session.overlays()

    def refresh(self) -> None:
        """Update the comparison table's current row (call when a run has finished)."""
        _, results = self._current()
        if not self.session.runs:
            self.table.object = (
                '<p class="whatif-hint">Pin runs to compare them with the current one '
                f"(up to {MAX_PINNED}).</p>"
            )
            return
        self.table.object = comparison_html(self.session.comparison(results))

    # ---- callbacks --------------------------------------------------------------------------
    def _on_pin(self, _event=None) -> None:
        """Pin the results on screen under the typed name (or the default one)."""
        _, results = self._current()
        if results is None:
            self._show_message("There is no result to pin yet.")
            return
        preset = self._preset()
        self.session.baseline, self.session.baseline_name = Scenario.preset(preset), preset
        try:
            self.session.pin(results, self.name_input.value or None)
        except ValueError as error:
            self._show_message(str(error))
            return
        self.name_input.value = ""
        self._changed()

    def _on_rename(self, pinned: PinnedRun, event: param.parameterized.Event) -> None:
        """Rename a run; a refused name is reported and the old one shown again."""
        if event.new == pinned.name:
            return
        try:
            self.session.rename(pinned.name, event.new)
        except ValueError as error:
            self._show_message(str(error))
            event.obj.value = pinned.name
            return
        self._changed()

    def _on_visible(self, pinned: PinnedRun, event: param.parameterized.Event) -> None:
        """Show or hide a run in the plots."""
        self.session.set_visible(pinned.name, event.new)
        self._changed()

    def _on_restore(self, pinned: PinnedRun, _event=None) -> None:
        """Make a pinned run's inputs the current scenario."""
        self._clear_message()
        self._restore(self.session.restore(pinned.name))

    def _on_remove(self, pinned: PinnedRun, _event=None) -> None:
        """Forget a pinned run."""
        self.session.remove(pinned.name)
        self._changed()

    def _on_reference(self, event: param.parameterized.Event) -> None:
        """Take the differences to another run."""
        if event.new is not None and event.new != self.session.reference:
            self.session.reference = event.new
            self.refresh()

    def _on_load(self, event: param.parameterized.Event) -> None:
        """Replace the session by a saved one (its runs recomputed); refuse bad files clearly."""
        if event.new is None:
            return
        filename = self.load_input.filename or "the file"
        self.load_input.clear()  # so that loading the same file again is a new event
        try:
            session, current = load_session(event.new, compute=self._compute)
        except (ValueError, SimulationError) as error:
            self._show_message(f"Could not load {filename} as a session: {error}")
            return
        self.session.clear()
        self.session = session
        if current is not None:
            self._restore(current)
        self._changed()

    def _release(self, session_context) -> None:
        """The browser session closed: let go of every pinned result."""
        self.session.clear()
        self.rows = []
        self.runs_column.objects = []

    # ---- files --------------------------------------------------------------------------------
    def _session_file(self) -> io.StringIO:
        """The session (pinned inputs, names, visibility, reference, current inputs) as JSON."""
        scenario, _ = self._current()
        return io.StringIO(save_session(self.session, current=scenario))

    def _report_file(self) -> io.BytesIO:
        """Static HTML report of the session: comparison table and overlaid plots."""
        _, results = self._current()
        return io.BytesIO(session_report_html(self.session, results).encode("utf-8"))

    # ---- state ----------------------------------------------------------------------------
    def _changed(self) -> None:
        """After any change of the pinned runs: list, reference, table, and tell the app."""
        self._clear_message()
        self._rebuild()
        self.param.trigger("overlays_changed")

    def _rebuild(self) -> None:
        """Rebuild the list of runs, the reference options and the table."""
        self.rows = [self._row(pinned) for pinned in self.session.runs]
        self.runs_column.objects = [row.layout for row in self.rows]
        self.reference_select.param.update(
            options=[*self.session.names(), CURRENT_LABEL], value=self.session.reference
        )
        self.pin_button.disabled = len(self.session.runs) >= MAX_PINNED
        self.save_button.disabled = self.report_button.disabled = not self.session.runs
        self.refresh()

    def _row(self, pinned: PinnedRun) -> RunRow:
        """Controls of one pinned run: colour, name, shown, restore, remove."""
        name_input = pn.widgets.TextInput(value=pinned.name, sizing_mode="stretch_width")
        name_input.param.watch(partial(self._on_rename, pinned), "value")
        visible = pn.widgets.Checkbox(label="shown", value=pinned.visible, width=65)
        visible.param.watch(partial(self._on_visible, pinned), "value")
        restore = pn.widgets.Button(label="Restore", width=70)
        restore.on_click(partial(self._on_restore, pinned))
        remove = pn.widgets.Button(label="✕", width=35, description="Remove this run")
        remove.on_click(partial(self._on_remove, pinned))
        layout = pn.Row(
            _swatch(pinned.colour),
            name_input,
            visible,
            restore,
            remove,
            sizing_mode="stretch_width",
            css_classes=["whatif-run"],
        )
        return RunRow(pinned.name, name_input, visible, restore, remove, layout)

    def _show_message(self, text: str) -> None:
        """Show a problem in the component (never a traceback)."""
        self.message.param.update(object=html.escape(text), visible=True)

    def _clear_message(self) -> None:
        """Hide the message."""
        self.message.param.update(object="", visible=False)
