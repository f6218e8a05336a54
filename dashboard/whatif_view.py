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
from concurrent.futures import Executor
from functools import partial

import panel as pn
import param

from dashboard.limits import SESSION_JSON_BYTES, refuse_oversized
from dashboard.longterm_checks import SessionLoop
from dashboard.scheduler import EXECUTOR, outcome_of
from dashboard.whatif import (
    CURRENT_LABEL,
    MAX_PINNED,
    Compute,
    PinnedRun,
    WhatIfSession,
    load_session,
    save_session,
)
from dashboard.whatif_report import COMPARISON_CSS, comparison_html, session_report_html
from model.params import Scenario
from model.pipeline import Results, SimulationError, run

Current = Callable[[], tuple[Scenario, Results | None]]


def runs_list_html(runs: list[PinnedRun]) -> str:
    """The pinned runs as one list: each run's plot colour, name, and whether it is shown.

    One HTML element for the whole list, not a row of widgets per run: every widget adds its
    own styled DOM tree, and the browser restyles them all on each repaint of the plots.
    """
    items = "".join(
        f'<li class="whatif-run{"" if run.visible else " whatif-hidden"}">'
        f'<span class="whatif-swatch" style="background: {run.colour}"></span>'
        f"{html.escape(run.name)}{'' if run.visible else ' <em>(hidden)</em>'}</li>"
        for run in runs
    )
    return f'<ul class="whatif-list">{items}</ul>' if runs else ""


RUNS_LIST_CSS = """
ul.whatif-list { list-style: none; margin: 4px 0; padding: 0; }
ul.whatif-list li { display: flex; align-items: center; gap: 6px; padding: 2px 0; }
.whatif-swatch { width: 14px; height: 14px; border-radius: 3px; flex: none; }
li.whatif-hidden { color: #6e7781; }
"""


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
    threaded : bool
        Compute a loaded session's runs in ``executor`` (served app), not in the calling
        thread (tests): up to :data:`MAX_PINNED` runs would hold the session's event loop.
    executor : Executor
        Where a loaded session's runs compute (default: the shared :data:`EXECUTOR`).
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
        threaded: bool = False,
        executor: Executor = EXECUTOR,
        **params,
    ):
        super().__init__(**params)
        self._current = current
        self._restore = restore
        self._compute = compute if compute is not None else partial(run, cache=None)
        self._preset = preset if preset is not None else (lambda: "paper")
        self._threaded, self._executor = threaded, executor
        self._loop = SessionLoop()
        self.session = WhatIfSession()

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
        self.runs_list = pn.pane.HTML(
            "",
            stylesheets=[RUNS_LIST_CSS],
            sizing_mode="stretch_width",
            css_classes=["whatif-runs"],
        )
        # one set of controls acts on the run chosen here (a fixed number of widgets)
        self.run_select = pn.widgets.Select(
            label="Pinned run",
            options=[],
            sizing_mode="stretch_width",
            css_classes=["whatif-chosen"],
        )
        self.run_select.param.watch(self._on_choose, "value")
        self.rename_input = pn.widgets.TextInput(
            label="Name", sizing_mode="stretch_width", css_classes=["whatif-rename"]
        )
        self.rename_input.param.watch(self._on_rename, "value")
        self.shown_checkbox = pn.widgets.Checkbox(
            label="shown in the plots", value=True, css_classes=["whatif-shown"]
        )
        self.shown_checkbox.param.watch(self._on_visible, "value")
        self.restore_button = pn.widgets.Button(
            label="Restore as current",
            description="Make this run's inputs the current ones",
            css_classes=["whatif-restore"],
        )
        self.restore_button.on_click(self._on_restore)
        self.remove_button = pn.widgets.Button(
            label="Remove", description="Forget this pinned run", css_classes=["whatif-remove"]
        )
        self.remove_button.on_click(self._on_remove)
        self.run_controls = pn.Column(
            pn.Row(self.run_select, self.rename_input, sizing_mode="stretch_width"),
            pn.Row(
                self.shown_checkbox,
                self.restore_button,
                self.remove_button,
                sizing_mode="stretch_width",
            ),
            visible=False,
            sizing_mode="stretch_width",
        )
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
            self.runs_list,
            self.run_controls,
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
        self._changed(chosen=self.session.names()[-1])  # the controls act on the new run

    def _chosen(self) -> PinnedRun | None:
        """The pinned run the controls act on."""
        name = self.run_select.value
        return self.session.get(name) if name in self.session.names() else None

    def _on_choose(self, _event=None) -> None:
        """Show the chosen run's name and visibility in the controls."""
        chosen = self._chosen()
        if chosen is not None:
            self.rename_input.value = chosen.name
            self.shown_checkbox.value = chosen.visible

    def _on_rename(self, event: param.parameterized.Event) -> None:
        """Rename the chosen run; a refused name is reported and the old one shown again."""
        chosen = self._chosen()
        if chosen is None or event.new == chosen.name:
            return
        try:
            self.session.rename(chosen.name, event.new)
        except ValueError as error:
            self._show_message(str(error))
            self.rename_input.value = chosen.name
            return
        self._changed(chosen=event.new)

    def _on_visible(self, event: param.parameterized.Event) -> None:
        """Show or hide the chosen run in the plots."""
        chosen = self._chosen()
        if chosen is None or event.new == chosen.visible:
            return
        self.session.set_visible(chosen.name, event.new)
        self._changed()

    def _on_restore(self, _event=None) -> None:
        """Make the chosen run's inputs the current scenario."""
        chosen = self._chosen()
        if chosen is not None:
            self._clear_message()
            self._restore(self.session.restore(chosen.name))

    def _on_remove(self, _event=None) -> None:
        """Forget the chosen run."""
        chosen = self._chosen()
        if chosen is not None:
            self.session.remove(chosen.name)
            self._changed()

    def _on_reference(self, event: param.parameterized.Event) -> None:
        """Take the differences to another run."""
        if event.new is not None and event.new != self.session.reference:
            self.session.reference = event.new
            self.refresh()

    def _on_load(self, event: param.parameterized.Event) -> None:
        """Replace the session by a saved one, its runs recomputed in the executor when
        threaded; refuse bad files clearly."""
        if event.new is None:
            return
        filename = self.load_input.filename or "the file"
        self.load_input.clear()  # so that loading the same file again is a new event
        try:
            refuse_oversized(event.new, filename, SESSION_JSON_BYTES)
        except ValueError as error:
            self._show_message(f"Could not load {filename} as a session: {error}")
            return
        finish = partial(self._finish_load, filename)
        load = partial(load_session, compute=self._compute)
        if not self._threaded:
            finish(outcome_of(load, event.new))
            return
        self.load_input.disabled = True  # one load at a time
        self._loop.remember()
        future = self._executor.submit(outcome_of, load, event.new)
        future.add_done_callback(lambda done: self._loop.call(partial(finish, done.result())))

    def _finish_load(self, filename: str, outcome) -> None:
        """Show a loaded session, or why it was refused."""
        self.load_input.disabled = False
        if isinstance(outcome, (ValueError, SimulationError)):
            self._show_message(f"Could not load {filename} as a session: {outcome}")
            return
        if isinstance(outcome, BaseException):
            raise outcome
        session, current = outcome
        self.session.clear()
        self.session = session
        if current is not None:
            self._restore(current)
        self._changed()

    def _release(self, session_context) -> None:
        """The browser session closed: let go of every pinned result (and of a session still
        loading)."""
        self._loop.closed = True
        self.session.clear()
        # the page's models may be gone already: the widgets let go without updating them
        with param.discard_events(self.runs_list), param.discard_events(self.run_select):
            self.runs_list.object = ""
            self.run_select.param.update(options=[], value=None)

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
    def _changed(self, chosen: str | None = None) -> None:
        """After any change of the pinned runs: list, reference, table, and tell the app."""
        self._clear_message()
        self._rebuild(chosen)
        self.param.trigger("overlays_changed")

    def _rebuild(self, chosen: str | None = None) -> None:
        """Rebuild the list of runs, the controls, the reference options and the table.

        ``chosen`` is the run the controls act on next (default: the one chosen before if it
        is still pinned, else the last one).
        """
        names = self.session.names()
        if chosen not in names:
            chosen = self.run_select.value if self.run_select.value in names else None
        if chosen is None and names:
            chosen = names[-1]
        self.runs_list.object = runs_list_html(self.session.runs)
        self.run_select.param.update(options=names, value=chosen)
        self._on_choose()
        self.run_controls.visible = bool(names)
        self.reference_select.param.update(
            options=[*names, CURRENT_LABEL], value=self.session.reference
        )
        self.pin_button.disabled = len(self.session.runs) >= MAX_PINNED
        self.save_button.disabled = self.report_button.disabled = not self.session.runs
        self.refresh()

    def _show_message(self, text: str) -> None:
        """Show a problem in the component (never a traceback)."""
        self.message.param.update(object=html.escape(text), visible=True)

    def _clear_message(self) -> None:
        """Hide the message."""
        self.message.param.update(object="", visible=False)
