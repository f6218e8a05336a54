"""Interactive dashboard: ``panel serve dashboard/app.py --warm``, then open
http://localhost:5006/app.

The wiring layer only: controls come from the parameters (:mod:`dashboard.controls`), presets,
train types and URL overrides from :mod:`model.scenarios`, run scheduling from
:mod:`dashboard.scheduler`, numbers from :func:`model.pipeline.run` and plots from
:mod:`dashboard.plots`. ``--warm`` compiles the kernels when the server starts.

URL query arguments choose the initial scenario: ``?preset=single_bogie`` and any number of
``section.parameter=value`` overrides in SI units, e.g. ``?preset=paper&train.speed_kmh=60``.
"""

from __future__ import annotations

import asyncio
import functools
import html
import io
import logging
import os
import re
from concurrent.futures import Executor, Future
from pathlib import Path

import holoviews as hv
import panel as pn
import param
from holoviews.streams import Pipe

from dashboard import plots
from dashboard.controls import ParameterControl
from dashboard.longterm_view import LONGTERM_PLOTS, CalibrationPanel, law_statement
from dashboard.report import ITEMS_CSS, items_html, report_html
from dashboard.scheduler import EXECUTOR, LatestRun, outcome_of, warm_up, warm_up_run
from dashboard.study_view import StudyView
from dashboard.whatif_view import WhatIfPanel
from model import scenarios
from model.fe_section import FEResult, stored_fe_result
from model.params import SECTIONS, Scenario, ScenarioError
from model.pipeline import STAGES, Results, SimulationError, StageCache, run, stage_keys

log = logging.getLogger(__name__)

PRIMARY = ("train.speed_kmh", "soil.youngs_modulus", "track.fastener_stiffness")
"""Main inputs, shown up front; every other parameter sits in its section's collapsible group."""

SWITCHES = ("tunnel.model",)
"""Model switches shown up front with the presets."""

GROUP_TITLES = {
    "train": "Train",
    "irregularity": "Track irregularity",
    "track": "Track",
    "soil": "Soil",
    "tunnel": "Lining",
    "vehicle": "Vehicle",
    "longterm": "Long-term settlement",
    "numerics": "Numerics",
}
"""Collapsible groups in display order: section → title."""

HIDDEN = {"irregularity.profile_csv"}
"""Not offered as a control: a measured profile is a server-side file; set it in a scenario file."""

ALL_PLOTS = (*plots.PLOTS, *LONGTERM_PLOTS)
"""Every plot of the page: the passage plots, then the long-term ones."""

FE_RESULTS_DIR = Path(os.environ.get("TUNNELSETTLE_FE_RESULTS", "fe_results"))
"""Where ``python -m model fe --out`` results are looked up for the depth plot (relative to the
server's working directory unless absolute)."""

OTHER_MODEL = {"2d": "2.5d", "2.5d": "2d"}
DEPTH_PLOT = "depth_profile"  # the plot that also draws the other model's curve
# The opacity is always stated: the browser keeps a style that a new set of styles leaves out.
PLOT_STYLES = {"flex": "1 1 440px", "opacity": "1"}
# A plot that a run will redraw is dimmed, not covered by Panel's animated loading spinner: the
# spinner's animation cost the browser more than the redraw itself (1.4 s of CPU per change).
STALE_PLOT_STYLES = {**PLOT_STYLES, "opacity": "0.45"}
# The progress bar and status line follow a run at this interval: each refresh is a message to
# the browser and a restyle there, competing with the run for the two cores (at 0.1 s a typed
# speed on the paper case took ~0.3 s longer to show).
PROGRESS_REFRESH_S = 0.25
# The progress bar keeps its place while no run computes, hidden: showing and hiding it changed
# the height above the plots, and the browser laid the whole main area out again twice per run
# (0.3 s of CPU each time on the paper case, once after the results had arrived).
PROGRESS_SHOWN = {"opacity": "1"}
PROGRESS_HIDDEN = {"opacity": "0"}
# The other model's run waits this long after the results are shown, and is skipped if the
# user has changed an input by then: the chosen model's plots come first.
COMPANION_DELAY_S = 0.5
"""The tunnel–soil model drawn faint beside the chosen one on the depth plot."""

STAGE_NAMES = {"vehicle_track": "vehicle–track", "longterm": "long-term settlement"}
"""Stage names as shown, where they differ from the pipeline's."""

PREPARING = (
    '<span class="preparing">Preparing the model: the numerical kernels are being compiled '
    "(first start of the server only; about a minute)…</span>"
)


def _lazy_card(members: list[pn.viewable.Viewable], **params) -> pn.Card:
    """A collapsed card whose contents are rendered only when it is first opened.

    Rendering every group's ~50 controls up front costs seconds of page load; most sessions
    never open most groups.
    """
    card = pn.Card(collapsed=True, sizing_mode="stretch_width", **params)

    def fill(event):
        if not event.new and not card.objects:
            card.objects = members

    card.param.watch(fill, "collapsed")
    return card


def _markdown_escape(text: str) -> str:
    """Text shown literally inside a Markdown alert."""
    return re.sub(r"([\\`*_{}\[\]<>#|])", r"\\\1", text)


def _note_html(text: str) -> str:
    """Small grey paragraph showing ``text`` literally."""
    return f'<div style="font-size: 12px; color: #57606a">{html.escape(text)}</div>'


def _dynamic(spec: plots.PlotSpec, overlays, companions):
    """DynamicMap callback drawing the Results a Pipe stream carries (its ``data``), with the
    pinned runs (``overlays()``) on the passage plots, and on the depth plot the other
    tunnel–soil model's profile and a stored FE result (``companions()``: a dict of keyword
    arguments)."""

    def callback(data):
        if spec.key == plots.MODEL_COMPARISON_PLOT:
            return spec.draw(data, overlays=overlays(), **companions())
        if spec in plots.PLOTS:
            return spec.draw(data, overlays=overlays())
        return spec.draw(data)

    return callback


def _one_message(*, reindex_once: bool = False):
    """Decorate a page-updating method: its changes reach the browser as one message.

    With ``reindex_once`` the document's models are re-indexed once at the end instead of
    after each change of a model reference (each re-indexing walks every model of the page).
    Only for methods that update existing plots: a plot made while the index is frozen misses
    the page design's Bokeh theme (its title came out small).
    """

    def decorate(method):
        @functools.wraps(method)
        def held(*args, **kwargs):
            with pn.io.hold(freeze=reindex_once):
                return method(*args, **kwargs)

        return held

    return decorate


def _stage_name(stage: str) -> str:
    return STAGE_NAMES.get(stage, stage)


class Dashboard(pn.viewable.Viewer):
    """The dashboard of one browser session: controls, views of the results, export.

    Parameters
    ----------
    scenario : Scenario, optional
        Initial inputs (default: the ``paper`` preset). The dashboard edits this object.
    preset : str, optional
        Name shown in the preset selector.
    cache : StageCache, optional
        Stage cache of the runs (the served app passes one shared by its sessions); a new one
        by default.
    executor : Executor
        Where runs compute (default: the process-wide pool of :mod:`dashboard.scheduler`).
    warm : Future, optional
        The server's warm-up run; while it computes, the page says the model is being prepared.
    threaded : bool
        Compute without blocking the event loop (served app) instead of before returning.
    """

    threaded = param.Boolean(default=False, doc="Run the pipeline without blocking the caller.")

    def __init__(
        self,
        scenario: Scenario | None = None,
        preset: str = scenarios.DEFAULT_PRESET,
        cache: StageCache | None = None,
        executor: Executor = EXECUTOR,
        warm: Future | None = None,
        **params,
    ):
        super().__init__(**params)
        self.scenario = scenario if scenario is not None else Scenario.preset(preset)
        self.base_preset = preset
        """The preset the inputs started from (what-if names say what differs from it)."""
        self.cache = cache if cache is not None else StageCache()
        self.warm = warm
        self.results: Results | None = None
        self.other_model: Results | None = None
        """The same scenario with the other tunnel–soil model, drawn faint on the depth plot."""
        self.fe_result: FEResult | None = None
        """A stored FE result of the current scenario (``python -m model fe``), if any."""
        self.render_counts = dict.fromkeys(STAGES, 0)
        self.runs = LatestRun(self._compute, executor)
        self.companion_runs = LatestRun(self._compute_companion, executor)
        """The other tunnel–soil model's run, computed after the results are on screen."""
        self._companion_wanted: Scenario | None = None
        self._companion_json = ""
        self.comparison_state = "computing"
        """The other model's curve on the depth plot: "computing", "shown" or "unavailable"."""
        self.companion_delay_s = COMPANION_DELAY_S if self.threaded else 0.0
        self._shown_keys: dict[str, str] = {}
        self._progress_state = ("", 0.0)
        self._replacing = False
        self._quiet = False
        self._refused: dict[str, str] = {}

        self.controls = {
            f"{section}.{name}": ParameterControl(obj, f"{section}.{name}", self._on_refusal)
            for section in SECTIONS
            for obj in [getattr(self.scenario, section)]
            for name in obj.param
            if name != "name" and f"{section}.{name}" not in HIDDEN
        }
        for section in SECTIONS:
            obj = getattr(self.scenario, section)
            obj.param.watch(self._on_parameter, [n for n in obj.param if n != "name"])

        self._preset_descriptions = scenarios.preset_descriptions()
        self.preset_select = pn.widgets.Select(
            label="Preset",
            options=[*self._preset_descriptions, scenarios.CUSTOM],
            value=preset,
            description="Named scenario; choosing one replaces every input. Shows "
            f"'{scenarios.CUSTOM}' once an input differs from every preset.",
            sizing_mode="stretch_width",
        )
        self.preset_select.param.watch(self._on_preset, "value")
        self.preset_note = pn.pane.HTML(
            _note_html(self._preset_descriptions.get(preset, "")),
            margin=(0, 10),
            sizing_mode="stretch_width",
        )
        self.train_type = pn.widgets.Select(
            label="Train type",
            options=[*scenarios.TRAIN_TYPES, scenarios.CUSTOM],
            value=scenarios.train_type_of(self.scenario.train),
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
            height=8,  # a thin bar: its place stays reserved while no run computes
            sizing_mode="stretch_width",
            css_classes=["run-progress"],
        )
        # shown and hidden through its box: the bar itself keeps the styles it was built with
        self.progress_box = pn.Column(
            self.progress, styles=PROGRESS_HIDDEN, margin=(6, 0, 0, 0), sizing_mode="stretch_width"
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
                min_width=plots.PLOT_MIN_WIDTH,
                # each plot's axes follow its own data: Panel would otherwise share the ranges
                # of plots drawn in the same layout with the same dimension (both PSDs' "f",
                # on slightly different frequency grids), cutting one of them off
                linked_axes=False,
                css_classes=["plot", f"plot-{spec.key}", f"stage-{spec.stage}"],
            )
            for spec in ALL_PLOTS
        }
        self.plot_cells = {
            key: pn.Column(
                pane,
                styles=PLOT_STYLES,
                min_width=plots.PLOT_MIN_WIDTH,
                sizing_mode="stretch_width",
            )
            for key, pane in self.plot_panes.items()
        }
        """Per plot, the box around its pane (flex item; dimmed while the plot is stale)."""
        self.whatif = WhatIfPanel(
            current=lambda: (self.scenario, self.results),
            restore=self._replace_scenario,
            compute=lambda scenario: run(scenario, cache=self.cache),
            preset=lambda: self.base_preset,
        )
        self.whatif.param.watch(self._redraw_overlays, "overlays_changed")
        self.law_statement = pn.pane.Markdown("", sizing_mode="stretch_width")
        self.calibration = CalibrationPanel(longterm=self.scenario.longterm)
        self.study = StudyView(scenario_source=lambda: self.scenario.copy())
        self.views: dict[str, pn.viewable.Viewable] = {
            "Passage": pn.Column(
                self.summary,
                self.soil_summary,
                pn.FlexBox(
                    *[self.plot_cells[spec.key] for spec in plots.PLOTS],
                    sizing_mode="stretch_width",
                ),
                pn.Card(self.whatif, title="What-if: pinned runs", sizing_mode="stretch_width"),
                sizing_mode="stretch_width",
                name="Passage",
            ),
            "Long-term settlement": pn.Column(
                self.law_statement,
                pn.FlexBox(
                    *[self.plot_cells[spec.key] for spec in LONGTERM_PLOTS],
                    sizing_mode="stretch_width",
                ),
                pn.Card(
                    self.calibration,
                    title="Calibrate the strain law",
                    collapsed=True,
                    sizing_mode="stretch_width",
                ),
                sizing_mode="stretch_width",
                name="Long-term settlement",
            ),
            "Study": self.study,
        }
        """Main-area views by tab title; :meth:`add_view` adds one."""
        self.tabs = pn.Tabs(*self.views.items(), sizing_mode="stretch_width", dynamic=True)

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
        preset, scenario, problems = scenarios.scenario_from_arguments(decoded)
        dashboard = cls(scenario=scenario, preset=preset, **params)
        dashboard._set_quietly(dashboard.preset_select, scenarios.matching_preset(scenario))
        if problems:
            dashboard._show_error("Ignored URL arguments:", problems)
        return dashboard

    # ---- layout ---------------------------------------------------------------------------
    def add_view(self, title: str, view: pn.viewable.Viewable) -> None:
        """Add a tab to the main area (e.g. long-term settlement, studies)."""
        self.views[title] = view
        self.tabs.append((title, view))

    def sidebar(self) -> list[pn.viewable.Viewable]:
        """Sidebar: preset, model switch, train type and main inputs; the rest in groups."""
        up_front = {*PRIMARY, *SWITCHES}
        groups = [
            _lazy_card(
                [
                    control
                    for path, control in self.controls.items()
                    if path.startswith(f"{section}.") and path not in up_front
                ],
                title=title,
                css_classes=[f"group-{section}"],
            )
            for section, title in GROUP_TITLES.items()
        ]
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
            *[self.controls[path] for path in SWITCHES],
            self.train_type,
            *[self.controls[path] for path in PRIMARY],
            *groups,
            files,
            self.report_button,
        ]

    def main(self) -> list[pn.viewable.Viewable]:
        """Main area: run status and messages above the tabs of views."""
        return [
            pn.Column(
                self.progress_box,
                self.status,
                self.error_alert,
                self.warning_alert,
                self.tabs,
                sizing_mode="stretch_width",
            )
        ]

    def __panel__(self) -> pn.viewable.Viewable:
        return pn.Row(
            pn.Column(*self.sidebar(), width=320),
            pn.Column(*self.main(), sizing_mode="stretch_width"),
            sizing_mode="stretch_width",
        )

    def template(self) -> pn.template.BootstrapTemplate:
        """The served page: controls in the sidebar, results in the main area."""
        # Bootstrap rather than Fast: the Fast design fetches a web font from the internet.
        return pn.template.BootstrapTemplate(
            title="tunnelsettle — metro tunnel settlement under passing trains",
            sidebar=self.sidebar(),
            main=self.main(),
            sidebar_width=320,
            header_background="#1f6f8b",
        )

    def close(self) -> None:
        """Drop the results and plots of a closed session (its memory returns at once)."""
        for pane in self.plot_panes.values():
            pane.object = None
        self.plot_streams.clear()
        self.results = self.other_model = self.fe_result = None

    # ---- editing ----------------------------------------------------------------------------
    def _on_parameter(self, *events: param.parameterized.Event) -> None:
        """An input changed (control, train type): follow-up displays, then a new run."""
        if self._replacing:
            return
        self._after_change()

    def _after_change(self) -> None:
        """Derived displays follow the inputs; a run is requested."""
        self._update_soil_summary()
        self._set_quietly(self.preset_select, scenarios.matching_preset(self.scenario))
        self._set_quietly(self.train_type, scenarios.train_type_of(self.scenario.train))
        self.refresh()

    def _on_refusal(self, path: str, message: str | None) -> None:
        """A control refused an edit (message) or accepted one (None)."""
        if message is None:
            if self._refused.pop(path, None) is not None or not self._refused:
                self._clear_error()
            return
        self._refused[path] = message
        self._show_error("Value not accepted:", [message])

    def _on_preset(self, event: param.parameterized.Event) -> None:
        """Replace every input by the chosen preset's."""
        if self._quiet or event.new == scenarios.CUSTOM:
            return
        self.preset_note.object = _note_html(self._preset_descriptions.get(event.new, ""))
        self.base_preset = event.new
        self._replace_scenario(Scenario.preset(event.new))

    def _on_train_type(self, event: param.parameterized.Event) -> None:
        """Apply the geometry of a standard train type."""
        if not self._quiet and event.new != scenarios.CUSTOM:
            scenarios.apply_train_type(self.scenario, event.new)

    def _on_load(self, event: param.parameterized.Event) -> None:
        """Load a scenario file written by "Save scenario"; a bad file gives a clear message."""
        if event.new is None:
            return
        filename = self.load_input.filename or "the file"
        self.load_input.clear()  # so that loading the same file again is a new event
        try:
            scenario = Scenario.from_json(event.new.decode("utf-8"))
        except (ValueError, KeyError, TypeError, AttributeError) as error:
            self._show_error(
                f"Could not load {filename} as a scenario:", [scenarios.error_text(error)]
            )
            return
        self._replace_scenario(scenario)

    def _replace_scenario(self, scenario: Scenario) -> None:
        """Adopt every input of ``scenario`` (controls follow), then one run."""
        self._replacing = True
        try:
            self.scenario.update(scenario.to_dict())
        finally:
            self._replacing = False
        self._refused.clear()
        self._clear_error()
        self._after_change()

    def _set_quietly(self, widget: pn.widgets.Widget, value) -> None:
        """Set a selector without treating it as the user's choice."""
        self._quiet = True
        try:
            widget.value = value
        finally:
            self._quiet = False

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

        A change made while a run computes replaces any change still waiting, so dragging or
        typing never queues stale runs.
        """
        if self.runs.request(self.scenario.copy()):
            self.compute_waiting()

    def compute_waiting(self) -> None:
        """Compute what waits, without requesting a run: the requested runs, then the other
        tunnel–soil model's curve for the depth plot (all there is after
        :meth:`show_cached_results`)."""
        if self.threaded:
            pn.state.execute(self._drain)
        else:
            asyncio.run(self._drain())

    def show_cached_results(self) -> bool:
        """Draw the scenario's results at once, without a run in the pool, when the stage
        cache holds every stage of it (another visitor asked for the same inputs) and the
        kernels are ready. Returns True when it did.

        The served app calls it while it builds a page: the plots are then part of the page
        the browser first receives, instead of replacing their placeholders once it has been
        drawn (each replacement lays the whole page out again in the browser). Only the other
        model's curve is left to compute (:meth:`compute_waiting`).
        """
        if self.warm is not None and not self.warm.done():
            return False
        if not self.cache.holds(stage_keys(self.scenario)):
            return False
        scenario = self.scenario.copy()
        self._finish(scenario, outcome_of(self._compute, scenario))
        return True

    async def _drain(self) -> None:
        """Compute the requested runs, refreshing the progress bar meanwhile, then (unless a
        newer change is computing by then) the other tunnel–soil model's run for the depth
        plot."""
        await self.runs.drain(
            self._start, self._finish, tick=self._show_progress, poll_s=PROGRESS_REFRESH_S
        )
        if self._companion_wanted is None:
            return
        await asyncio.sleep(self.companion_delay_s)  # the page draws the results undisturbed
        if self.runs.busy:  # a newer change: its own drain asks for its comparison
            return
        other, self._companion_wanted = self._companion_wanted, None
        if other is not None and self.companion_runs.request(other):
            await self.companion_runs.drain(lambda scenario: None, self._finish_companion)

    @_one_message()
    def _start(self, scenario: Scenario) -> None:
        """Mark the plots that this run will change as stale."""
        self._progress_state = ("", 0.0)
        self.progress.value = 0
        self.progress_box.styles = PROGRESS_SHOWN
        if self.warm is not None and not self.warm.done():
            self.status.object = PREPARING
        stale = self._stale_stages(scenario)
        for spec in ALL_PLOTS:
            if spec.stage in stale:
                self._mark_stale(spec.key, True)

    def _mark_stale(self, key: str, stale: bool) -> None:
        """Dim a drawn plot that a run will change (undim it when drawn); a plot not drawn yet
        shows the loading spinner until its first results."""
        pane, cell = self.plot_panes[key], self.plot_cells[key]
        if pane.object is None:
            pane.loading = stale
            return
        pane.loading = False
        cell.styles = STALE_PLOT_STYLES if stale else PLOT_STYLES

    @property
    def progress_shown(self) -> bool:
        """True while the progress bar shows a run computing."""
        return self.progress_box.styles == PROGRESS_SHOWN

    def is_stale(self, key: str) -> bool:
        """True while the plot ``key`` waits for a run that will change it."""
        return self.plot_panes[key].loading or self.plot_cells[key].styles == STALE_PLOT_STYLES

    def _stale_stages(self, scenario: Scenario) -> set[str]:
        """Stages whose shown output does not belong to ``scenario``."""
        keys = stage_keys(scenario)
        return {stage for stage in STAGES if self._shown_keys.get(stage) != keys[stage]}

    def _note_progress(self, stage: str, fraction: float) -> None:
        """Pipeline progress callback (runs in a worker thread): just remember it."""
        self._progress_state = (stage, fraction)

    @_one_message()
    def _show_progress(self) -> None:
        """Progress bar and status line from the last progress report."""
        stage, fraction = self._progress_state
        if stage:
            overall = (STAGES.index(stage) + fraction) / len(STAGES)
            self.progress.value = round(100 * overall)
            self.status.object = (
                f'<span class="computing">Computing {_stage_name(stage)}… {fraction:.0%}</span>'
            )

    def _compute(self, scenario: Scenario) -> tuple[Results, FEResult | None]:
        """Run the pipeline with the app's cache (in a worker thread) and look up a stored FE
        result of the scenario."""
        if self.warm is not None:
            self.warm.result()  # the kernels compile once, not once per waiting session
        results = run(scenario, progress=self._note_progress, cache=self.cache)
        return results, stored_fe_result(scenario, FE_RESULTS_DIR)

    def _compute_companion(self, other: Scenario) -> Results | None:
        """The scenario with the other tunnel–soil model (in a worker thread; its vehicle–track
        and load stages come from the cache). A failure only leaves its curve out."""
        try:
            return run(other, cache=self.cache)
        except (ValueError, SimulationError):
            return None

    def _request_companion(self, other: Scenario) -> None:
        """Ask for the other model's run of the scenario ``other`` (unless it is on screen); it
        becomes that run's job, with the other tunnel–soil model."""
        other.tunnel.model = OTHER_MODEL[other.tunnel.model]
        self._companion_json = other.to_json()
        shown = self.other_model
        if shown is not None and shown.scenario_json == self._companion_json:
            self._companion_wanted = None  # nothing older is left to compute
            return
        self.other_model = None  # the previous scenario's curve must not stay on the plot
        self._companion_wanted = other
        self.comparison_state = "computing"

    @_one_message(reindex_once=True)
    def _finish_companion(self, other: Scenario, outcome: Results | None | BaseException):
        """Draw the other model's curve if it still belongs to the results on screen."""
        if isinstance(outcome, BaseException):
            log.error("comparison run failed", exc_info=outcome)
            outcome = None
        if other.to_json() != self._companion_json:  # inputs have changed since it was asked for
            return
        self.other_model = outcome
        self.comparison_state = "unavailable" if outcome is None else "shown"
        stream = self.plot_streams.get(DEPTH_PLOT)
        if stream is not None and outcome is not None:
            stream.send(self.results)
        self.status.object = self._status_html(self.results)

    def _finish(
        self,
        scenario: Scenario,
        outcome: tuple[Results, FEResult | None] | BaseException,
    ) -> None:
        """Show a run's results (redrawing only the plots whose stage changed) or its error, in
        one message; the models are re-indexed once when every plot exists already (see
        :func:`_one_message`)."""
        in_place = len(self.plot_streams) == len(ALL_PLOTS)
        with pn.io.hold(freeze=in_place):
            self._show_outcome(scenario, outcome)

    def _show_outcome(
        self,
        scenario: Scenario,
        outcome: tuple[Results, FEResult | None] | BaseException,
    ) -> None:
        """:meth:`_finish` without the message batching."""
        self.progress_box.styles = PROGRESS_HIDDEN
        if isinstance(outcome, BaseException):
            self._show_failure(outcome)
            return
        results, self.fe_result = outcome
        # ``scenario`` is this run's own copy of the inputs (``results.scenario`` would parse
        # them again): it gives the stage keys, then becomes the other model's job
        redrawn = self._stale_stages(scenario)
        self._shown_keys = stage_keys(scenario)
        self._request_companion(scenario)
        for spec in ALL_PLOTS:
            if spec.stage in redrawn:
                stream = self.plot_streams.get(spec.key)
                if stream is None:
                    # the first results create the plot; later ones update its data in place,
                    # which is far cheaper on both ends than replacing the Bokeh figure
                    self._new_plot(spec, results)
                else:
                    stream.send(results)
            self._mark_stale(spec.key, False)
        for stage in redrawn:
            self.render_counts[stage] += 1
        self.results = results
        self.summary.object = items_html(plots.summary_items(results), "summary")
        self.warning_alert.param.update(
            object="**Warnings**\n\n"
            + "\n".join(f"- {_markdown_escape(w)}" for w in results.warnings),
            visible=bool(results.warnings),
        )
        self.status.object = self._status_html(results)
        self.law_statement.object = law_statement(results)
        self.report_button.disabled = False
        self.whatif.refresh()

    def _new_plot(self, spec: plots.PlotSpec, results: Results) -> None:
        """A new plot of ``results``; its stream then updates it in place."""
        stream = self.plot_streams[spec.key] = Pipe(data=results)
        self.plot_panes[spec.key].object = hv.DynamicMap(
            _dynamic(spec, self.whatif.overlays, self._depth_companions), streams=[stream]
        )

    def _depth_companions(self) -> dict:
        """The other tunnel–soil model's results and the stored FE result, for the depth plot."""
        return {"other_model": self.other_model, "fe_result": self.fe_result}

    @_one_message()
    def _redraw_overlays(self, _event=None) -> None:
        """The pinned runs changed: new passage plots (a plot's set of curves is fixed when
        it is first drawn)."""
        if self.results is not None:
            for spec in plots.PLOTS:
                self._new_plot(spec, self.results)

    def _show_failure(self, error: BaseException) -> None:
        """A failed run: its message in the page, the previous results kept."""
        if isinstance(error, ScenarioError):
            headline = "Inconsistent inputs:"
        else:
            headline = "The computation failed:"
            if not isinstance(error, ValueError | KeyError | SimulationError):
                log.error("pipeline run failed", exc_info=error)
        self._show_error(headline, [scenarios.error_text(error)])
        for key in self.plot_panes:
            self._mark_stale(key, False)
        self.status.object = (
            '<span class="failed">Last run failed; the plots show the previous results.</span>'
            if self.results
            else ""
        )

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
                f'data-renders="{self.render_counts[stage]}" '
                f'data-seconds="{results.stage_seconds.get(stage, 0.0):.4f}">'
                f"{_stage_name(stage)}: {took}</span>"
            )
        other = plots.MODEL_NAMES[OTHER_MODEL[results.scenario.tunnel.model]]
        parts.append(
            f'<span class="comparison-status" data-state="{self.comparison_state}">'
            f"{html.escape(other)} on the depth plot: {self.comparison_state}</span>"
        )
        return '<div class="stages">Last run: ' + " · ".join(parts) + "</div>"

    # ---- files ------------------------------------------------------------------------------
    def _scenario_file(self) -> io.StringIO:
        """Current inputs as a JSON file."""
        return io.StringIO(self.scenario.to_json())

    def _report_file(self) -> io.BytesIO:
        """Static HTML report of the results on screen."""
        name = self.preset_select.value
        return io.BytesIO(report_html(self.results, scenario_name=name).encode("utf-8"))


def serve_session() -> Dashboard:
    """Build the page of one browser session of ``panel serve`` (the server's shared stage
    cache and warm-up; the session's memory is dropped when it closes)."""
    cache = pn.state.as_cached("tunnelsettle-stage-cache", StageCache)
    dashboard = Dashboard.from_query(
        pn.state.session_args, cache=cache, warm=warm_up(warm_up_run), threaded=True
    )
    # once the page is loaded: its own run, or (drawn from the cache) only the comparison curve
    drawn = dashboard.show_cached_results()
    pn.state.onload(dashboard.compute_waiting if drawn else dashboard.refresh)
    pn.state.on_session_destroyed(lambda _context: dashboard.close())
    with pn.io.hold(freeze=True):  # the page's ~20 roots are indexed once, not each
        dashboard.template().servable()
    return dashboard


if pn.state.served:
    pn.extension(notifications=False)
    serve_session()
