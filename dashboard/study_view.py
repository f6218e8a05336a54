"""The "Study" view: sweep one or two parameters over irregularity seeds on Dask, live.

A self-contained Panel component, :class:`StudyView`, given a callable that returns the current
:class:`~model.params.Scenario` (the dashboard's): choose up to two parameters (labels and
ranges from :mod:`model.params`, in the parameter's display unit: MPa, MN/m, …; the study
itself gets SI values), their ranges and points, the number of seeds; start, watch the
progress, cancel. Results (drawn by :mod:`dashboard.study_plots`): the mean with its 5–95 %
band across seeds against one parameter, or a heat map of the mean over two, for the peak
displacement at the invert and the long-term settlement (when the pipeline reports
``longterm_settlement_m``), and the envelope of the peak-displacement depth profiles; once a
study has rows, its report (:func:`dashboard.study_report.study_report_html`) can be
downloaded. The study runs in its own thread on its own Dask cluster
(:func:`model.study.execution.run_study`), so the served app stays responsive; the page is
updated on the session's event loop (``add_next_tick_callback``).
"""

from __future__ import annotations

import io
import itertools
import threading
import time
from collections.abc import Callable
from functools import partial

import holoviews as hv
import numpy as np
import pandas as pd
import panel as pn
import param
from bokeh.models import PrintfTickFormatter
from holoviews.streams import Pipe

from dashboard.controls import clean_number, slider_step, step_decimals
from dashboard.limits import reserve_local_cluster, whole_number_input
from dashboard.study_plots import display_values, finished_rows, plot_slots
from dashboard.study_report import study_report_html
from model.params import SECTIONS, Scenario, display_label, display_unit, parameter_of
from model.run_cost import estimate_run
from model.study.definition import MAX_RUNS_UNCONFIRMED
from model.study.execution import machine_workers, run_study

NONE = "(none)"
EXCLUDED = {"irregularity.seed"}  # varied through the seeds
REFRESH_S = 1.0  # at most this often the plots are redrawn while rows stream in
REFRESH_LOAD = 0.25  # and the redraws take at most this share of the event loop
MAX_POINTS = 50  # per parameter
MAX_SEEDS = 200


def study_parameters() -> dict[str, str]:
    """Label (in display units) → dotted path of every number parameter with a slider range
    (softbounds)."""
    choices = {}
    for section in SECTIONS:
        cls = Scenario.param[section].class_
        for name, p in cls.param.objects("existing").items():
            path = f"{section}.{name}"
            if (
                isinstance(p, param.Number)
                and not isinstance(p, param.Boolean)
                and p.softbounds is not None
                and path not in EXCLUDED
            ):
                choices[f"{display_label(path)} — {path}"] = path
    return choices


def grid_values(path: str, low: float, high: float, n_points: int) -> list[float | int]:
    """``n_points`` evenly spaced values from ``low`` to ``high``, given in the parameter's
    display unit, returned in SI (distinct whole numbers for an integer parameter)."""
    _, factor = display_unit(path)
    shown = np.linspace(low, high, n_points) if n_points > 1 else np.array([low])
    values = [clean_number(v / factor) for v in shown]
    if isinstance(parameter_of(path), param.Integer):
        return sorted({round(v) for v in values})
    return values


class StudyView(pn.viewable.Viewer):
    """Study tab: parameters, ranges, seeds; start, progress, cancel; bands or heat maps.

    Parameters
    ----------
    scenario_source : callable
        Returns the current scenario (the base of a new study).
    scheduler : None, str or distributed.Client
        Where studies run (see :func:`model.study.execution.study_client`); None:
        ``$TUNNELSETTLE_SCHEDULER`` or a LocalCluster per study.
    threaded : bool
        Run the study in its own thread (served app) or in the calling thread (tests).
    """

    scenario_source = param.Callable(doc="Returns the current Scenario.")
    scheduler = param.Parameter(default=None, doc="Dask scheduler address or Client, or None.")
    threaded = param.Boolean(default=True, doc="Run the study in its own thread.")
    running = param.Boolean(default=False, doc="A study is running.")
    table = param.DataFrame(default=None, allow_None=True, doc="Rows of the last study so far.")

    def __init__(self, **params):
        super().__init__(**params)
        self.choices = study_parameters()
        labels = list(self.choices)
        default = next(label for label, path in self.choices.items() if path == "train.speed_kmh")
        self.first = pn.widgets.Select(label="First parameter", options=labels, value=default)
        self.second = pn.widgets.Select(label="Second parameter", options=[NONE, *labels])
        self.first_range = pn.widgets.EditableRangeSlider(
            label="Range", sizing_mode="stretch_width", css_classes=["study-range-first"]
        )
        self.second_range = pn.widgets.EditableRangeSlider(
            label="Range",
            sizing_mode="stretch_width",
            visible=False,
            css_classes=["study-range-second"],
        )
        self.first_points = pn.widgets.IntInput(label="Points", value=5, start=1, end=MAX_POINTS)
        self.second_points = pn.widgets.IntInput(
            label="Points", value=3, start=1, end=MAX_POINTS, visible=False
        )
        self.seeds = pn.widgets.IntInput(
            label="Irregularity seeds", value=10, start=1, end=MAX_SEEDS
        )
        self.start_button = pn.widgets.Button(label="Start study", color="primary")
        self.cancel_button = pn.widgets.Button(label="Cancel", color="warning", disabled=True)
        # shown from the first Start on (an empty bar before it read as a broken widget)
        self.progress = pn.indicators.Progress(
            value=0, max=1, sizing_mode="stretch_width", visible=False
        )
        self.status = pn.pane.Markdown("", sizing_mode="stretch_width")
        self.plan = pn.pane.Markdown("", sizing_mode="stretch_width", css_classes=["study-plan"])
        """How many runs Start will compute and about how long they take."""
        self.report_button = pn.widgets.FileDownload(
            callback=self._report_file,
            filename="study_report.html",
            label="Download study report",
            disabled=True,
            sizing_mode="stretch_width",
            css_classes=["study-report"],
        )
        # beside the controls, or below them in a narrow window (a Row overflowed it)
        self.plots = pn.Column(sizing_mode="stretch_width", styles={"flex": "1 1 400px"})
        self.first.param.watch(partial(self._on_parameter, self.first_range), "value")
        self.second.param.watch(self._on_second, "value")
        self.start_button.on_click(lambda event: self.start())
        self.cancel_button.on_click(lambda event: self.cancel())
        self._on_parameter(self.first_range, None)
        for widget in (self.first, self.second, self.first_points, self.second_points, self.seeds):
            widget.param.watch(lambda event: self.update_plan(), "value")
        self.update_plan()
        self._cancel = threading.Event()
        self._rows: list[dict] = []
        self._lock = threading.Lock()
        self._doc = None
        self._last_refresh = self._refresh_seconds = 0.0
        self._refresh_pending = False
        self._thread: threading.Thread | None = None
        self._pipe = Pipe(data=None)
        self._slot_names: list[str] = []

    def __panel__(self) -> pn.viewable.Viewable:
        controls = pn.Column(
            self.first,
            self.first_range,
            self.first_points,
            self.second,
            self.second_range,
            self.second_points,
            self.seeds,
            self.plan,
            pn.Row(self.start_button, self.cancel_button),
            self.progress,
            self.status,
            self.report_button,
            width=340,
        )
        return pn.FlexBox(controls, self.plots, sizing_mode="stretch_width")

    # ---- inputs ---------------------------------------------------------------------------
    def _on_parameter(self, slider: pn.widgets.EditableRangeSlider, event) -> None:
        """A parameter was chosen: its softbounds become the range and its label the name, both
        in its display unit."""
        select = self.first if slider is self.first_range else self.second
        if select.value == NONE:
            return
        path = self.choices[select.value]
        low, high = display_values(path, parameter_of(path).softbounds)
        step = 1 if isinstance(parameter_of(path), param.Integer) else slider_step(low, high)
        slider.param.update(
            label=display_label(path),
            start=low,
            end=high,
            value=(low, high),
            step=step,
            format=PrintfTickFormatter(format=f"%.{step_decimals(step)}f"),
        )

    def _on_second(self, event) -> None:
        shown = event.new != NONE
        self.second_range.visible = self.second_points.visible = shown
        if shown:
            self._on_parameter(self.second_range, event)

    def vary(self) -> dict[str, list]:
        """Grid of the chosen parameters: path → SI values (the range's ends rounded to the
        slider's step: 56, not 55.99999999999999)."""
        vary = {}
        pairs = [(self.first, self.first_range, self.first_points)]
        if self.second.value != NONE:
            pairs.append((self.second, self.second_range, self.second_points))
        for select, slider, points in pairs:
            path = self.choices[select.value]
            if path in vary:
                raise ValueError(f"{path} is chosen twice: pick two different parameters")
            low, high = (round(end, step_decimals(slider.step)) for end in slider.value)
            vary[path] = grid_values(path, low, high, whole_number_input(points))
        return vary

    def n_runs(self) -> int:
        """Runs of the chosen grid and seeds (ValueError for a grid that cannot be run)."""
        return int(np.prod([len(v) for v in self.vary().values()])) * whole_number_input(self.seeds)

    def update_plan(self) -> None:
        """Say how many runs Start computes and about how long, before it is pressed: the
        mean of :func:`model.run_cost.estimate_run` over the grid's points (a slow train's
        passage lasts longer), shared by the machine's workers."""
        try:
            vary = self.vary()
            n_runs = self.n_runs()
            each = self._mean_run_seconds(vary)
        except (ValueError, TypeError) as error:
            self.plan.object = f"Cannot start: {error}"
            return
        minutes = n_runs * each / machine_workers() / 60.0
        took = f"about {minutes:.0f} min" if minutes >= 1.5 else "about a minute or less"
        too_many = (
            f" — more than {MAX_RUNS_UNCONFIRMED}: use fewer points or seeds"
            if n_runs > MAX_RUNS_UNCONFIRMED
            else ""
        )
        self.plan.object = (
            f"**{n_runs} runs**, {took} on {machine_workers()} workers (estimate){too_many}"
        )

    def _mean_run_seconds(self, vary: dict[str, list]) -> float:
        """Mean estimated time of one run over the grid (at most 100 of its points)."""
        points = list(itertools.product(*vary.values()))
        points = points[:: max(1, len(points) // 100)]
        base = self.scenario_source()
        seconds = []
        for values in points:
            scenario = base.copy()
            for path, value in zip(vary, values, strict=True):
                scenario.set_value(path, value)
            seconds.append(estimate_run(scenario).total_seconds)
        return float(np.mean(seconds))

    # ---- running --------------------------------------------------------------------------
    def start(self) -> None:
        """Start a study of the current scenario (does nothing while one runs)."""
        if self.running:
            return
        try:
            vary = self.vary()
            seeds = self._seed_list()
            n_runs = self.n_runs()
            if n_runs > MAX_RUNS_UNCONFIRMED:
                raise ValueError(
                    f"{n_runs} runs: at most {MAX_RUNS_UNCONFIRMED} from the dashboard; use "
                    "fewer points or seeds (or the command line with --yes)"
                )
            release_cluster = reserve_local_cluster(self.scheduler)
        except ValueError as error:
            self.status.object = f"**Not started:** {error}"
            return
        base = self.scenario_source()
        self._cancel.clear()
        self._rows = []
        self.table = None
        self.plots.objects, self._slot_names = [], []
        self.progress.param.update(value=0, max=n_runs, visible=True)
        self.status.object = f"Starting {n_runs} runs (cluster start-up takes a few seconds)…"
        self.running = True
        self.start_button.disabled, self.cancel_button.disabled = True, False
        self.report_button.disabled = True
        if self._doc is None and pn.state.curdoc is not None and pn.state.curdoc.session_context:
            # a closed browser tab stops its study instead of leaving it to run to the end
            pn.state.curdoc.on_session_destroyed(lambda context: self._cancel.set())
        self._doc = pn.state.curdoc
        work = partial(self._work, base, vary, seeds, release_cluster)
        if self.threaded:
            self._thread = threading.Thread(target=work, name="study", daemon=True)
            self._thread.start()
        else:
            work()

    def cancel(self) -> None:
        """Stop the running study; the finished rows stay."""
        if self.running:
            self._cancel.set()
            self.cancel_button.disabled = True
            self.status.object = "Cancelling: waiting for the runs in progress…"

    def _seed_list(self) -> list[int]:
        """The first ``seeds`` irregularity seeds from the scenario's own."""
        first = self.scenario_source().irregularity.seed
        return list(range(first, first + whole_number_input(self.seeds)))

    def _work(self, base: Scenario, vary: dict, seeds: list[int], release_cluster) -> None:
        """The study (in its own thread when served); gives its cluster back and hands the
        outcome to the page."""
        try:
            outcome = run_study(
                base,
                vary,
                seeds,
                scheduler=self.scheduler,
                depth_profile=True,
                progress=self._on_row,
                cancel=self._cancel,
            )
        except Exception as error:  # shown on the page; the server must not lose the thread
            outcome = error
        finally:
            release_cluster()
        self._on_page(partial(self._finish, outcome))

    def _on_row(self, done: int, total: int, row: dict) -> None:
        """A run came back (study thread): keep it; redraw at most every REFRESH_S, and less
        often when redrawing is slow, so the event loop stays free for the users."""
        with self._lock:
            self._rows.append(row)
            wait = max(REFRESH_S, self._refresh_seconds / REFRESH_LOAD)
            due = time.monotonic() - self._last_refresh > wait and not self._refresh_pending
            if due:
                self._refresh_pending = True
        if due:
            self._on_page(self._refresh)

    def _on_page(self, callback: Callable[[], None]) -> None:
        """Run ``callback`` on the session's event loop when served, else right here."""
        doc = self._doc
        if doc is not None and doc.session_context is not None:
            doc.add_next_tick_callback(callback)
        else:
            callback()

    def _refresh(self) -> None:
        """Progress, status and plots from the rows so far."""
        start = time.monotonic()
        with self._lock:
            rows = list(self._rows)
        if rows:
            table = pd.DataFrame(rows)
            table.attrs["n_runs"] = self.progress.max  # the plots say they are partial
            self.table = table
            self.progress.value = len(rows)
            self.status.object = f"{len(rows)} of {self.progress.max} runs done"
            self._draw(table)
        with self._lock:
            self._refresh_pending = False
            self._last_refresh = time.monotonic()
            self._refresh_seconds = self._last_refresh - start

    def _draw(self, table: pd.DataFrame) -> None:
        """Send the table to the plots; build them only when the set of plots changes (a new
        study), so streaming rows update the figures in place instead of replacing them."""
        if finished_rows(table).empty:
            return
        slots = plot_slots(table)
        if list(slots) == self._slot_names:
            self._pipe.send(table)
            return
        self._pipe = Pipe(data=table)
        self._slot_names = list(slots)
        self.plots.objects = [
            pn.pane.HoloViews(
                hv.DynamicMap(lambda data, draw=draw: draw(data), streams=[self._pipe]),
                sizing_mode="stretch_width",
            )
            for draw in slots.values()
        ]

    def _report_file(self) -> io.BytesIO:
        """The last study's HTML report (built when the button is pressed, not on every row)."""
        return io.BytesIO(study_report_html(self.table).encode("utf-8"))

    def _finish(self, outcome: pd.DataFrame | Exception) -> None:
        """The study ended, finished, cancelled or refused: final table and state."""
        self.running = False
        self.start_button.disabled, self.cancel_button.disabled = False, True
        if isinstance(outcome, Exception):
            message = " ".join(str(outcome).split()) or type(outcome).__name__
            self.status.object = f"**Study failed:** {message}"
            return
        self.table = outcome.reset_index(drop=True)  # keeps attrs: the report's definition
        self.report_button.disabled = outcome.empty
        self.progress.value = len(outcome)
        failed = int((outcome["error"] != "").sum()) if "error" in outcome else 0
        cancelled = outcome.attrs.get("cancelled")
        state = "Cancelled" if cancelled else "Done"
        self.status.object = (
            f"{state}: {len(outcome)} of {outcome.attrs.get('n_runs', len(outcome))} runs"
            + (f", {failed} failed" if failed else "")
            + (" — the plots show this partial result" if cancelled and len(outcome) else "")
        )
        self._draw(self.table)
