"""Interactive dashboard: ``panel serve dashboard/app.py``, then open http://localhost:5006/app.

Thin by design: every widget is generated from the parameter objects of :mod:`model.params`
(label, unit, range, default and doc all come from there), every number comes from
:func:`model.pipeline.run` and every plot from :mod:`dashboard.plots`.

URL query arguments choose the initial scenario: ``?preset=single_bogie`` and any number of
``section.parameter=value`` overrides, e.g. ``?preset=paper&train.speed_kmh=60``.
"""

from __future__ import annotations

import asyncio
import html
import io
import json
import logging
import math
import re
from concurrent.futures import ThreadPoolExecutor
from functools import partial

import holoviews as hv
import panel as pn
import param
from holoviews.streams import Pipe

from dashboard import plots
from dashboard.export import ITEMS_CSS, items_html, report_html
from model.params import PRESETS_FILE, SECTIONS, Scenario, ScenarioError, Train
from model.pipeline import (
    STAGES,
    Results,
    SimulationError,
    StageCache,
    run,
    stage_keys,
)

log = logging.getLogger(__name__)

PRIMARY = ("train.speed_kmh", "soil.youngs_modulus", "track.fastener_stiffness")
"""Controls shown up front; every other parameter sits in its section's collapsible group."""

GROUP_TITLES = {
    "train": "Train",
    "irregularity": "Track irregularity",
    "track": "Track",
    "soil": "Soil",
    "tunnel": "Lining",
    "vehicle": "Vehicle",
    "numerics": "Numerics",
    "longterm": "Long-term settlement",
}
"""Collapsible groups in display order: section → title."""

HIDDEN = {"irregularity.profile_csv"}
"""Not offered as a widget: a measured profile is a server-side file; set it in a scenario file."""

TRAIN_TYPES = {"Type A": Train.type_a(), "Type B": Train.type_b()}
TRAIN_GEOMETRY = ("car_length", "bogie_distance", "wheelbase")
CUSTOM = "Custom"
DEFAULT_PRESET = "paper"  # Scenario.paper(): the paper's Nanjing case

STAGE_NAMES = {
    "vehicle_track": "vehicle–track",
    "load": "load",
    "soil": "soil",
    "stress": "stresses",
    "longterm": "long-term settlement",
}
POLL_S = 0.1  # how often the page's progress bar is refreshed while a run computes

# One worker: runs from all sessions queue instead of fighting over two cores.
_EXECUTOR = ThreadPoolExecutor(max_workers=1, thread_name_prefix="pipeline")


def _slider_step(low: float, high: float) -> float:
    """A round step giving at least 200 positions between ``low`` and ``high``."""
    return 10.0 ** math.floor(math.log10((high - low) / 200.0))


def parameter_widget(scenario: Scenario, path: str) -> pn.widgets.Widget:
    """Widget for one parameter (``"section.name"``), from its label, doc, softbounds and value.

    Numbers get an editable slider over their soft bounds whose text box accepts any value
    (the parameter itself refuses what is out of its hard bounds); optional numbers get a text
    box where empty means "automatic". The widget has the CSS class ``param-section-name``.
    """
    section, _, name = path.partition(".")
    obj = getattr(scenario, section)
    p = obj.param[name]
    value = getattr(obj, name)
    if isinstance(p, param.Boolean):
        cls, kwargs = pn.widgets.Checkbox, {}
    elif isinstance(p, param.Selector):
        cls, kwargs = pn.widgets.Select, {"options": list(p.objects)}
    elif isinstance(p, param.Number) and not p.allow_None and p.softbounds is not None:
        low, high = p.softbounds
        kwargs = {"start": min(low, value), "end": max(high, value)}
        if isinstance(p, param.Integer):
            cls, kwargs["step"] = pn.widgets.EditableIntSlider, 1
        else:
            cls, kwargs["step"] = pn.widgets.EditableFloatSlider, _slider_step(low, high)
    else:
        cls = pn.widgets.TextInput
        kwargs = {"placeholder": "automatic" if p.allow_None else ""}
        value = "" if value is None else str(value)
    if "description" in cls.param:  # sliders and checkboxes have no tooltip
        kwargs["description"] = p.doc
    return cls(
        label=p.label,
        value=value,
        sizing_mode="stretch_width",
        css_classes=[f"param-{section}-{name}"],
        **kwargs,
    )


def _lazy_card(members: list[pn.viewable.Viewable], **params) -> pn.Card:
    """A collapsed card whose contents are rendered only when it is first opened.

    Rendering every group's ~50 widgets up front (each editable slider carries a JavaScript
    link) costs seconds of page load; most sessions never open most groups.
    """
    card = pn.Card(collapsed=True, sizing_mode="stretch_width", **params)

    def fill(event):
        if not event.new and not card.objects:
            card.objects = members

    card.param.watch(fill, "collapsed")
    return card


def _dynamic(draw):
    """DynamicMap callback drawing the Results a Pipe stream carries."""

    def callback(data):
        return draw(data)

    return callback


def _widget_value_event(widget: pn.widgets.Widget) -> str:
    """The widget parameter that signals a finished edit (slider release, Enter, blur)."""
    return "value_throttled" if "value_throttled" in widget.param else "value"


def _markdown_escape(text: str) -> str:
    """Text shown literally inside a Markdown alert."""
    return re.sub(r"([\\`*_{}\[\]<>#|])", r"\\\1", text)


def _note_html(text: str) -> str:
    """Small grey paragraph showing ``text`` literally."""
    return f'<div style="font-size: 12px; color: #57606a">{html.escape(text)}</div>'


def _preset_descriptions() -> dict[str, str]:
    """Description of every preset, from ``model/data/presets.json``."""
    presets = json.loads(PRESETS_FILE.read_text(encoding="utf-8"))["presets"]
    return {name: entry.get("description", "") for name, entry in presets.items()}


class Dashboard(pn.viewable.Viewer):
    """The dashboard of one browser session: controls, plots, key numbers and export.

    Parameters
    ----------
    scenario : Scenario, optional
        Initial inputs (default: the ``paper`` preset).
    preset : str, optional
        Name shown in the preset selector.
    threaded : bool
        Compute off the event loop (served app) instead of in the calling thread (tests).
    cache : StageCache, optional
        Stage cache shared by runs, so only the stages a change touches re-run (default: a
        new one owned by this dashboard).
    """

    threaded = param.Boolean(default=False, doc="Run the pipeline in a worker thread.")

    def __init__(
        self,
        scenario: Scenario | None = None,
        preset: str = DEFAULT_PRESET,
        cache: StageCache | None = None,
        **params,
    ):
        super().__init__(**params)
        self.scenario = scenario if scenario is not None else Scenario.preset(preset)
        self.cache = cache if cache is not None else StageCache()
        self.results: Results | None = None
        self.render_counts = dict.fromkeys(STAGES, 0)
        self._shown_keys: dict[str, str] = {}
        self._running = False
        self._pending = False
        self._syncing = False
        self._progress_state = ("", 0.0)

        self.widgets = {
            f"{section}.{name}": parameter_widget(self.scenario, f"{section}.{name}")
            for section in SECTIONS
            for name in getattr(self.scenario, section).param
            if name != "name" and f"{section}.{name}" not in HIDDEN
        }
        for path, widget in self.widgets.items():
            widget.param.watch(partial(self._on_edit, path), _widget_value_event(widget))

        descriptions = _preset_descriptions()
        self.preset_select = pn.widgets.Select(
            label="Preset",
            options=list(descriptions),
            value=preset,
            description="Named scenario; choosing one replaces every input.",
            sizing_mode="stretch_width",
        )
        self.preset_select.param.watch(self._on_preset, "value")
        self._preset_descriptions = descriptions
        self.preset_note = pn.pane.HTML(
            _note_html(descriptions.get(preset, "")), margin=(0, 10), sizing_mode="stretch_width"
        )
        self.train_type = pn.widgets.Select(
            label="Train type",
            options=[*TRAIN_TYPES, CUSTOM],
            value=self._train_type(),
            description="Car length, bogie-centre distance and wheelbase of a standard "
            "Chinese metro car.",
            sizing_mode="stretch_width",
        )
        self.train_type.param.watch(self._on_train_type, "value")

        self.error_alert = pn.pane.Alert(
            "",
            alert_type="danger",
            visible=False,
            css_classes=["error-alert"],
            sizing_mode="stretch_width",
        )
        self.warning_alert = pn.pane.Alert(
            "",
            alert_type="warning",
            visible=False,
            css_classes=["warning-alert"],
            sizing_mode="stretch_width",
        )
        self.progress = pn.indicators.Progress(
            value=0,
            max=100,
            active=False,
            visible=False,
            sizing_mode="stretch_width",
            css_classes=["run-progress"],
        )
        self.status = pn.pane.HTML("", css_classes=["run-status"], sizing_mode="stretch_width")
        self.summary = pn.pane.HTML(
            "", css_classes=["summary-pane"], stylesheets=[ITEMS_CSS], sizing_mode="stretch_width"
        )
        self.soil_summary = pn.pane.HTML(
            "", css_classes=["soil-pane"], stylesheets=[ITEMS_CSS], sizing_mode="stretch_width"
        )
        self.plot_streams: dict[str, Pipe] = {}
        """Per plot, the stream holding the Results it shows (sent only when its stage changed)."""
        self.plot_panes = {
            spec.key: pn.pane.HoloViews(
                None,
                sizing_mode="stretch_width",
                loading=True,
                min_height=plots.PLOT_HEIGHT,
                css_classes=["plot", f"plot-{spec.key}", f"stage-{spec.stage}"],
            )
            for spec in plots.PLOTS
        }

        self.save_button = pn.widgets.FileDownload(
            callback=self._scenario_file,
            filename="scenario.json",
            label="Save scenario",
            sizing_mode="stretch_width",
        )
        self.load_input = pn.widgets.FileInput(
            accept=".json", multiple=False, sizing_mode="stretch_width"
        )
        self.load_input.param.watch(self._on_load, "value")
        self.report_button = pn.widgets.FileDownload(
            callback=self._report_file,
            filename="tunnelsettle_report.html",
            label="Download HTML report",
            disabled=True,
            sizing_mode="stretch_width",
            css_classes=["report-button"],
        )
        self._update_soil_summary()

    # ---- construction from a browser session ----------------------------------------------
    @classmethod
    def from_query(cls, args: dict[str, list[bytes]], **params) -> Dashboard:
        """Dashboard for URL query arguments (``preset`` and ``section.parameter`` overrides).

        A bad argument is reported in the page, not raised.
        """
        decoded = {key: values[-1].decode("utf-8", "replace") for key, values in args.items()}
        names = Scenario.preset_names()
        preset = decoded.pop("preset", DEFAULT_PRESET)
        problems = []
        if preset not in names:
            problems.append(f"unknown preset {preset!r}; available: {', '.join(names)}")
            preset = DEFAULT_PRESET
        scenario = Scenario.preset(preset)
        for path, value in decoded.items():
            if "." not in path:
                continue
            try:
                scenario.set_value(path, value)
            except (KeyError, ValueError) as error:
                problems.append(_error_text(error))
        dashboard = cls(scenario=scenario, preset=preset, **params)
        if problems:
            dashboard._show_error("Ignored URL arguments:", problems)
        return dashboard

    # ---- layout ---------------------------------------------------------------------------
    def sidebar(self) -> list[pn.viewable.Viewable]:
        """Sidebar contents: preset, primary controls, collapsible groups, files."""
        groups = []
        for section, title in GROUP_TITLES.items():
            members = [
                widget
                for path, widget in self.widgets.items()
                if path.startswith(f"{section}.") and path not in PRIMARY
            ]
            if section == "train":
                members.insert(0, self.train_type)
            groups.append(_lazy_card(members, title=title, css_classes=[f"group-{section}"]))
        files = pn.Card(
            self.save_button,
            pn.pane.Markdown("Load a scenario file:", margin=(0, 5)),
            self.load_input,
            title="Scenario file",
            collapsed=True,
            sizing_mode="stretch_width",
        )
        return [
            self.preset_select,
            self.preset_note,
            *[self.widgets[path] for path in PRIMARY],
            *groups,
            files,
            self.report_button,
        ]

    def main(self) -> list[pn.viewable.Viewable]:
        """Main-area contents: run status, messages, key numbers, plots."""
        plots_grid = pn.GridBox(*self.plot_panes.values(), ncols=2, sizing_mode="stretch_width")
        return [
            pn.Column(
                self.progress,
                self.status,
                self.error_alert,
                self.warning_alert,
                self.summary,
                self.soil_summary,
                plots_grid,
                sizing_mode="stretch_width",
            )
        ]

    def __panel__(self) -> pn.viewable.Viewable:
        return pn.Row(
            pn.Column(*self.sidebar(), width=340),
            pn.Column(*self.main()),
            sizing_mode="stretch_width",
        )

    def template(self) -> pn.template.BootstrapTemplate:
        """The served page: controls in the sidebar, results in the main area."""
        # Bootstrap rather than Fast: the Fast design fetches a web font from the internet.
        return pn.template.BootstrapTemplate(
            title="tunnelsettle — metro tunnel settlement under passing trains",
            sidebar=self.sidebar(),
            main=self.main(),
            sidebar_width=380,
            header_background="#1f6f8b",
        )

    # ---- editing ----------------------------------------------------------------------------
    def _on_edit(self, path: str, event: param.parameterized.Event) -> None:
        """A control changed: set the parameter (refusing bad values clearly) and re-run."""
        if self._syncing:
            return
        value = event.new
        if isinstance(value, str) and not value.strip():
            value = "none"  # an emptied optional field means "automatic"
        try:
            self.scenario.set_value(path, value)
        except (KeyError, ValueError) as error:
            self._show_error("Value not accepted:", [_error_text(error)])
            self._sync_widgets()
            return
        self._clear_error()
        if path.startswith("soil."):
            self._update_soil_summary()
        if path.startswith("train."):
            self._set_quietly(self.train_type, self._train_type())
        self.refresh()

    def _on_preset(self, event: param.parameterized.Event) -> None:
        """Replace every input by the chosen preset's."""
        if self._syncing:
            return
        self.preset_note.object = _note_html(self._preset_descriptions.get(event.new, ""))
        self._replace_scenario(Scenario.preset(event.new))

    def _on_train_type(self, event: param.parameterized.Event) -> None:
        """Apply the geometry of a standard train type."""
        if self._syncing or event.new == CUSTOM:
            return
        train = TRAIN_TYPES[event.new]
        self.scenario.train.param.update({name: getattr(train, name) for name in TRAIN_GEOMETRY})
        self._sync_widgets()
        self.refresh()

    def _on_load(self, event: param.parameterized.Event) -> None:
        """Load a scenario file written by "Save scenario"; a bad file gives a clear message."""
        if event.new is None:
            return
        filename = self.load_input.filename or "the file"
        self.load_input.clear()  # so that loading the same file again is a new event
        try:
            scenario = Scenario.from_json(event.new.decode("utf-8"))
        except (ValueError, KeyError, TypeError, AttributeError) as error:
            self._show_error(f"Could not load {filename} as a scenario:", [_error_text(error)])
            return
        self._replace_scenario(scenario)

    def _replace_scenario(self, scenario: Scenario) -> None:
        """Adopt a whole new scenario: widgets follow, then re-run."""
        self.scenario = scenario
        self._clear_error()
        self._sync_widgets()
        self._update_soil_summary()
        self.refresh()

    def _train_type(self) -> str:
        """Name of the standard train whose geometry the scenario has, or "Custom"."""
        train = self.scenario.train
        for label, standard in TRAIN_TYPES.items():
            if all(getattr(train, n) == getattr(standard, n) for n in TRAIN_GEOMETRY):
                return label
        return CUSTOM

    def _set_quietly(self, widget: pn.widgets.Widget, value) -> None:
        """Set a widget without triggering the edit callbacks."""
        self._syncing = True
        try:
            if "value_throttled" in widget.param:
                # keep value_throttled in step too, so re-entering the same value is an event
                with param.edit_constant(widget):
                    widget.param.update(value=value, value_throttled=value)
            else:
                widget.value = value
        finally:
            self._syncing = False

    def _sync_widgets(self) -> None:
        """Make every widget show the scenario's current values."""
        for path, widget in self.widgets.items():
            section, _, name = path.partition(".")
            value = getattr(getattr(self.scenario, section), name)
            if isinstance(widget, pn.widgets.TextInput):
                value = "" if value is None else str(value)
            elif hasattr(widget, "start"):
                widget.param.update(start=min(widget.start, value), end=max(widget.end, value))
            self._set_quietly(widget, value)
        self._set_quietly(self.train_type, self._train_type())

    # ---- messages ---------------------------------------------------------------------------
    def _show_error(self, headline: str, messages: list[str]) -> None:
        """Show a clear message in the page (never a traceback)."""
        lines = "\n".join(f"- {_markdown_escape(m)}" for m in messages)
        self.error_alert.param.update(object=f"**{headline}**\n\n{lines}", visible=True)

    def _clear_error(self) -> None:
        """Hide the error message."""
        self.error_alert.param.update(object="", visible=False)

    def _update_soil_summary(self) -> None:
        """Derived soil quantities follow the soil inputs at once, before any run."""
        self.soil_summary.object = items_html(plots.soil_items(self.scenario.soil), "soil")

    # ---- running ----------------------------------------------------------------------------
    def refresh(self) -> None:
        """Bring the results up to date with the scenario.

        Changes made while a run computes are coalesced into one further run, so dragging or
        typing never queues duplicate runs.
        """
        if self._running:
            self._pending = True
            return
        self._running = True
        if self.threaded:
            pn.state.execute(self._run_in_worker)
            return
        try:
            self._finish(self._compute(self.scenario.copy(), self._note_progress))
        finally:
            self._running = False

    async def _run_in_worker(self) -> None:
        """Run the pipeline in the worker thread, refreshing the progress bar meanwhile."""
        loop = asyncio.get_running_loop()
        try:
            while True:
                self._pending = False
                scenario = self.scenario.copy()
                self._start(scenario)
                future = loop.run_in_executor(
                    _EXECUTOR, partial(self._compute, scenario, self._note_progress)
                )
                while not future.done():
                    await asyncio.wait([future], timeout=POLL_S)
                    self._show_progress()
                self._finish(future.result())
                if not self._pending:
                    break
        finally:
            self._running = False

    def _start(self, scenario: Scenario) -> None:
        """Mark the plots that this run will change as loading."""
        self._progress_state = ("", 0.0)
        self.progress.param.update(value=0, visible=True, active=True)
        stale = self._stale_stages(scenario)
        for spec in plots.PLOTS:
            if spec.stage in stale:
                self.plot_panes[spec.key].loading = True

    def _stale_stages(self, scenario: Scenario) -> set[str]:
        """Stages whose shown output does not belong to ``scenario``."""
        keys = stage_keys(scenario)
        return {stage for stage in STAGES if self._shown_keys.get(stage) != keys[stage]}

    def _note_progress(self, stage: str, fraction: float) -> None:
        """Pipeline progress callback (may run in the worker thread): just remember it."""
        self._progress_state = (stage, fraction)

    def _show_progress(self) -> None:
        """Progress bar and status line from the last progress report."""
        stage, fraction = self._progress_state
        if stage:
            overall = (STAGES.index(stage) + fraction) / len(STAGES)
            self.progress.value = round(100 * overall)
            self.status.object = (
                f'<span class="computing">Computing {STAGE_NAMES[stage]}… {fraction:.0%}</span>'
            )

    def _compute(self, scenario: Scenario, progress) -> Results | Exception:
        """Run the pipeline; a failure is returned (to be shown), not raised."""
        try:
            return run(scenario, progress=progress, cache=self.cache)
        except (ValueError, KeyError, SimulationError) as error:  # ScenarioError: ValueError
            return error
        except Exception as error:  # shown in the page; the traceback goes to the server log
            log.exception("pipeline run failed")
            return error

    def _finish(self, outcome: Results | Exception) -> None:
        """Show a run's results (redrawing only the plots whose stage changed) or its error."""
        self.progress.param.update(visible=False, active=False)
        if isinstance(outcome, Exception):
            headline = (
                "Inconsistent inputs:"
                if isinstance(outcome, ScenarioError)
                else "The computation failed:"
            )
            self._show_error(headline, [_error_text(outcome)])
            for pane in self.plot_panes.values():
                pane.loading = False
            self.status.object = (
                '<span class="failed">Last run failed; the plots show the previous results.</span>'
                if self.results
                else ""
            )
            return
        results = outcome
        redrawn = self._stale_stages(results.scenario)
        for spec in plots.PLOTS:
            pane = self.plot_panes[spec.key]
            if spec.stage in redrawn:
                stream = self.plot_streams.get(spec.key)
                if stream is None:
                    # the first results create the plot; later ones update its data in place,
                    # which is far cheaper on both ends than replacing the Bokeh figure
                    stream = self.plot_streams[spec.key] = Pipe(data=results)
                    pane.object = hv.DynamicMap(_dynamic(spec.draw), streams=[stream])
                else:
                    stream.send(results)
            pane.loading = False
        for stage in redrawn:
            self.render_counts[stage] += 1
        self._shown_keys = stage_keys(results.scenario)
        self.results = results
        self.summary.object = items_html(plots.summary_items(results), "summary")
        self.warning_alert.param.update(
            object="**Warnings**\n\n"
            + "\n".join(f"- {_markdown_escape(w)}" for w in results.warnings),
            visible=bool(results.warnings),
        )
        self.status.object = self._status_html(results)
        self.report_button.disabled = False

    def _status_html(self, results: Results) -> str:
        """Which stages re-ran and how long they took; render counters for the browser tests."""
        parts = []
        for stage in STAGES:
            took = (
                "cached"
                if stage in results.cached_stages
                else f"{results.stage_seconds.get(stage, 0.0):.2f} s"
            )
            parts.append(
                f'<span class="stage-status" data-stage="{stage}" '
                f'data-renders="{self.render_counts[stage]}">'
                f"{STAGE_NAMES[stage]}: {took}</span>"
            )
        return '<div class="stages">Last run: ' + " · ".join(parts) + "</div>"

    # ---- files ------------------------------------------------------------------------------
    def _scenario_file(self) -> io.StringIO:
        """Current inputs as a JSON file."""
        return io.StringIO(self.scenario.to_json())

    def _report_file(self) -> io.BytesIO:
        """Static HTML report of the results on screen."""
        return io.BytesIO(report_html(self.results).encode("utf-8"))


def _error_text(error: BaseException) -> str:
    """The message of an exception (KeyError quotes its argument otherwise)."""
    if isinstance(error, KeyError) and error.args:
        return str(error.args[0])
    return str(error) or type(error).__name__


if pn.state.served:
    pn.extension(notifications=False)
    _dashboard = Dashboard.from_query(pn.state.session_args, threaded=True)
    pn.state.onload(_dashboard.refresh)
    _dashboard.template().servable()
