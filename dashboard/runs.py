"""The runs of one session and what the page says while they compute.

:class:`SessionRuns` brings the results up to date with the session's scenario: a change
requests a run (:class:`~dashboard.scheduler.LatestRun`: one computing, the newest request
waiting), computed in the shared pool with the server's stage cache; meanwhile the plots it
will change are dimmed and a progress bar and status line follow it. The plots of its first
stages (the vehicle–track and load plots) are drawn as soon as those stages are done, while the
soil stage computes; the rest of its results go to the views that show them (the passage and
long-term views, :class:`ResultsView`) in one message to the browser when it ends. Once they are
on screen, the same scenario with the other tunnel–soil model is run for the depth plot's faint
comparison curve.
"""

from __future__ import annotations

import asyncio
import html
import logging
import os
from collections.abc import Callable, Sequence
from concurrent.futures import Executor, Future, ThreadPoolExecutor
from pathlib import Path
from typing import Protocol

import panel as pn
import param

from dashboard import plots
from dashboard.limits import refuse_long_run
from dashboard.memory import release_soon
from dashboard.messages import Messages
from dashboard.plot_panes import message, one_message
from dashboard.scheduler import EXECUTOR, LatestRun, outcome_of
from model import scenarios
from model.fe.store import FEResult, stored_fe_result
from model.params import Scenario, ScenarioError
from model.params.measured_profile import admit_profile, data_folder
from model.pipeline import STAGES, Results, SimulationError, StageCache, run, stage_keys

log = logging.getLogger(__name__)

FE_RESULTS_DIR = Path(os.environ.get("TUNNELSETTLE_FE_RESULTS", "fe_results"))
"""Where ``python -m model fe --out`` results are looked up for the depth plot (relative to the
server's working directory unless absolute)."""

OTHER_MODEL = plots.OTHER_MODEL
"""Per tunnel–soil model, the other one (drawn faint beside it on the depth plot)."""

# The other model's run waits this long after the results are shown, and is skipped if the
# user has changed an input by then: the chosen model's plots come first.
COMPANION_DELAY_S = 0.5
# The progress bar and status line follow a run at this interval: each refresh is a message to
# the browser and a restyle there, competing with the run for the two cores (at 0.1 s a typed
# speed on the paper case took ~0.3 s longer to show).
PROGRESS_REFRESH_S = 0.25
# The progress bar keeps its place while no run computes, hidden: showing and hiding it changed
# the height above the plots, and the browser laid the whole main area out again twice per run
# (0.3 s of CPU each time on the paper case, once after the results had arrived).
PROGRESS_SHOWN = {"opacity": "1"}
PROGRESS_HIDDEN = {"opacity": "0"}

EARLY_STAGES = ("vehicle_track", "load")
"""Stages whose plots are drawn as soon as they are done, before the run ends: the browser
draws them while the server computes the soil stage (on a typed speed of the paper case they
show 0.2–0.3 s before the rest, and the last plot 0.05–0.1 s sooner, docs/dashboard.md)."""

STAGE_NAMES = {"vehicle_track": "vehicle–track", "longterm": "long-term settlement"}
"""Stage names as shown, where they differ from the pipeline's."""

PREPARING = (
    '<span class="preparing">Preparing the model: the numerical kernels are being compiled '
    "(first start of the server only; about a minute)…</span>"
)

Outcome = tuple[Results, FEResult | None]
"""A run's outcome: its results and the stored FE result of its scenario, if any."""


class ResultsView(Protocol):
    """What shows a run's results (:class:`~dashboard.passage_view.PassageView`,
    :class:`~dashboard.longterm_view.LongTermView`; all but ``show`` from
    :class:`~dashboard.plot_panes.PlotsView`)."""

    @property
    def drawn(self) -> bool:
        """True once every plot of the view exists."""

    def mark_stale(self, stages: set[str]) -> None:
        """A run computing will change the outputs of ``stages``."""

    def show_stages(self, results: Results, stages: set[str]) -> None:
        """Draw the plots of ``stages`` only, from ``results`` (which may hold only their
        outputs)."""

    def show(self, results: Results, redrawn: set[str]) -> None:
        """Show ``results``; only the outputs of the ``redrawn`` stages changed."""

    def settle(self) -> None:
        """The run that was awaited failed: keep showing the previous results."""


def admitted(scenario: Scenario) -> Scenario:
    """``scenario``, holding its measured profile by content and estimated to compute within
    the server's bound: the last guard before the server computes (every way in admits
    already), so no run here opens a file a user named or holds a worker for many minutes.

    Raises
    ------
    ValueError
        A profile file outside the data folder, or a run estimated to take longer than
        :data:`dashboard.limits.SERVED_RUN_SECONDS`.
    """
    admit_profile(scenario, data_folder())
    refuse_long_run(scenario)
    return scenario


def _stage_name(stage: str) -> str:
    """A pipeline stage's name as shown."""
    return STAGE_NAMES.get(stage, stage)


def _during(stage: str) -> str:
    """Where a cancelled run stopped, for :meth:`LatestRun.stop_if_cancelled`."""
    return f"the {_stage_name(stage)} stage"


class SessionRuns(param.Parameterized):
    """The runs of one session: scheduling, progress, outcome, the other model's run.

    Parameters
    ----------
    scenario : Scenario
        The session's inputs (each run computes a copy).
    messages : Messages
        Where a failed run and the results' warnings are reported.
    cache : StageCache
        Stage cache of the runs (the served app passes one shared by its sessions).
    executor : Executor
        Where runs compute (default: the process-wide pool of :mod:`dashboard.scheduler`).
    warm : Future, optional
        The server's warm-up run; while it computes, the page says the model is being prepared.
    threaded : bool
        Compute without blocking the event loop (served app) instead of before returning.
    """

    results = param.ClassSelector(
        class_=Results, default=None, allow_None=True, doc="The results on screen."
    )
    other_model = param.ClassSelector(
        class_=Results,
        default=None,
        allow_None=True,
        doc="The same scenario with the other tunnel–soil model, drawn faint on the depth plot.",
    )

    def __init__(
        self,
        scenario: Scenario,
        messages: Messages,
        cache: StageCache,
        executor: Executor = EXECUTOR,
        warm: Future | None = None,
        threaded: bool = False,
    ) -> None:
        super().__init__()
        self.scenario, self.messages = scenario, messages
        self.views: Sequence[ResultsView] = ()
        """Where the results are shown; the page sets them once its views exist."""
        self.cache, self.warm, self.threaded = cache, warm, threaded
        self.fe_result: FEResult | None = None
        """A stored FE result of the current scenario (``python -m model fe``), if any."""
        self.render_counts = dict.fromkeys(STAGES, 0)
        self.latest = LatestRun(self._compute, executor)
        """The runs of the chosen model: one computing, the newest request waiting."""
        self.companion = LatestRun(self._compute_companion, executor)
        """The other tunnel–soil model's run, computed after the results are on screen."""
        self._companion_wanted: Scenario | None = None
        self._companion_json = ""
        self.comparison_state = "computing"
        """The other model's curve on the depth plot: "computing", "shown" or "unavailable"."""
        self.companion_delay_s = COMPANION_DELAY_S if threaded else 0.0
        self._shown_keys: dict[str, str] = {}
        self._drawn_early: dict[str, str | None] = {}
        """Stages of the computing run drawn before it ended, with the keys shown before."""
        self._progress_state = ("", 0.0)

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

    # ---- what the page calls ----------------------------------------------------------------
    def refresh(self) -> None:
        """Bring the results up to date with the scenario.

        A change made while a run computes replaces any change still waiting, so dragging or
        typing never queues stale runs.
        """
        if self.latest.request(self.scenario.copy()):
            self.compute_waiting()

    def compute_waiting(self) -> None:
        """Compute what waits, without requesting a run: the requested runs, then the other
        tunnel–soil model's curve for the depth plot (all there is after
        :meth:`show_cached`)."""
        if self.threaded:
            pn.state.execute(self._drain)
        else:
            _run_to_end(self._drain())

    def show_cached(self) -> bool:
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

    @property
    def progress_shown(self) -> bool:
        """True while the progress bar shows a run computing."""
        return self.progress_box.styles == PROGRESS_SHOWN

    def depth_companions(self) -> dict:
        """The other tunnel–soil model's results and the stored FE result, for the depth plot."""
        return {
            "other_model": self.other_model,
            "other_model_computing": self.comparison_state == "computing",
            "fe_result": self.fe_result,
        }

    def close(self) -> None:
        """Drop the results of a closed session (telling no watcher: the page is gone) and
        its runs still waiting, the other model's curve included."""
        self.latest.cancel()
        self.companion.cancel()
        self._companion_wanted = None
        with param.discard_events(self):
            self.results = self.other_model = None
        self.fe_result = None

    # ---- computing ----------------------------------------------------------------------------
    async def _drain(self) -> None:
        """Compute the requested runs, refreshing the progress bar meanwhile, then (unless a
        newer change is computing by then) the other tunnel–soil model's run for the depth
        plot. If the session closed meanwhile, the memory goes back once its runs stopped."""
        try:
            await self.latest.drain(
                self._start,
                self._finish,
                tick=self._show_progress,
                poll_s=PROGRESS_REFRESH_S,
                posted=self._show_early,
            )
            if self._companion_wanted is None:
                return
            await asyncio.sleep(self.companion_delay_s)  # the page draws the results undisturbed
            if self.latest.busy:  # a newer change: its own drain asks for its comparison
                return
            other, self._companion_wanted = self._companion_wanted, None
            if other is not None and self.companion.request(other):
                await self.companion.drain(lambda scenario: None, self._finish_companion)
        finally:
            if self.latest.cancelled:
                release_soon(asyncio.get_running_loop().call_later)

    def _compute(self, scenario: Scenario) -> Outcome:
        """Run the pipeline with the session's cache (in a worker thread) and look up a stored
        FE result of the scenario."""
        if self.warm is not None:
            self.warm.result()  # the kernels compile once, not once per waiting session
        results = run(
            admitted(scenario),
            progress=self._note_progress,
            cache=self.cache,
            on_stage=self._post_early_stages(scenario),
        )
        return results, stored_fe_result(scenario, FE_RESULTS_DIR)

    def _post_early_stages(self, scenario: Scenario) -> Callable[[str, object], None]:
        """The run's ``on_stage``: once the :data:`EARLY_STAGES` are done, their outputs go
        to the page (:meth:`LatestRun.post`) as results holding only them."""
        outputs: dict[str, object] = {}

        def done(stage: str, output: object) -> None:
            outputs[stage] = output
            if stage == EARLY_STAGES[-1]:
                self.latest.post(
                    Results(
                        scenario_json=scenario.to_json(),
                        vehicle_track=outputs["vehicle_track"],
                        load=outputs["load"],
                        soil=None,
                        stress=None,
                        longterm=None,
                    )
                )

        return done

    def _compute_companion(self, other: Scenario) -> Results | None:
        """The scenario with the other tunnel–soil model (in a worker thread; its vehicle–track
        and load stages come from the cache). A failure only leaves its curve out; a closed
        session stops it at its next progress report
        (:class:`~dashboard.scheduler.RunCancelled`)."""
        try:
            return run(
                admitted(other),
                progress=lambda stage, _: self.companion.stop_if_cancelled(_during(stage)),
                cache=self.cache,
            )
        except (ValueError, SimulationError):
            return None

    def _stale_stages(self, scenario: Scenario) -> set[str]:
        """Stages whose shown output does not belong to ``scenario``."""
        keys = stage_keys(scenario)
        return {stage for stage in STAGES if self._shown_keys.get(stage) != keys[stage]}

    # ---- a run on the page --------------------------------------------------------------------
    @one_message()
    def _start(self, scenario: Scenario) -> None:
        """Show the progress bar; mark the outputs that this run will change as stale."""
        self._progress_state = ("", 0.0)
        self.progress.value = 0
        self.progress_box.styles = PROGRESS_SHOWN
        if self.warm is not None and not self.warm.done():
            self.status.object = PREPARING
        stale = self._stale_stages(scenario)
        for view in self.views:
            view.mark_stale(stale)

    def _show_early(self, scenario: Scenario, early: Results) -> None:
        """Draw the plots of the :data:`EARLY_STAGES` that changed from ``early`` (the run of
        ``scenario``, still computing), once every plot exists; the first run's plots are
        all drawn at its end. A change that leaves them alone (a soil change) sends nothing."""
        if self.results is None or not all(view.drawn for view in self.views):
            return
        keys = stage_keys(scenario)
        stages = {stage for stage in EARLY_STAGES if self._shown_keys.get(stage) != keys[stage]}
        if not stages:
            return
        for stage in stages:
            self._drawn_early[stage] = self._shown_keys.get(stage)
            self._shown_keys[stage] = keys[stage]
            self.render_counts[stage] += 1
        self._draw_early(early, stages)

    @one_message(reindex_once=True)
    def _draw_early(self, early: Results, stages: set[str]) -> None:
        """:meth:`_show_early`'s plots, and the status line brought to the stage computing."""
        for view in self.views:
            view.show_stages(early, stages)
        self._show_progress()

    def _note_progress(self, stage: str, fraction: float) -> None:
        """Pipeline progress callback (runs in a worker thread): remember it, or stop the run
        if the session has closed (at the next report: between stages and between chunks of
        the vehicle–track integration).

        Raises
        ------
        RunCancelled
            The session has closed.
        """
        self.latest.stop_if_cancelled(_during(stage))
        self._progress_state = (stage, fraction)

    @one_message()
    def _show_progress(self) -> None:
        """Progress bar and status line from the last progress report."""
        stage, fraction = self._progress_state
        if stage:
            overall = (STAGES.index(stage) + fraction) / len(STAGES)
            self.progress.value = round(100 * overall)
            self.status.object = (
                f'<span class="computing">Computing {_stage_name(stage)}… {fraction:.0%}</span>'
            )

    def _finish(self, scenario: Scenario, outcome: Outcome | BaseException) -> None:
        """Show a run's results (redrawing only the outputs whose stage changed) or its error,
        in one message; the models are re-indexed at most once when every plot exists already
        (see :func:`~dashboard.plot_panes.message`)."""
        in_place = all(view.drawn for view in self.views)
        with message(reindex_once=in_place):
            self._show_outcome(scenario, outcome)

    def _show_outcome(self, scenario: Scenario, outcome: Outcome | BaseException) -> None:
        """:meth:`_finish` without the message batching."""
        self.progress_box.styles = PROGRESS_HIDDEN
        if isinstance(outcome, BaseException):
            self._show_failure(outcome)
            return
        self._drawn_early.clear()
        results, self.fe_result = outcome
        # ``scenario`` is this run's own copy of the inputs (``results.scenario`` would parse
        # them again): it gives the stage keys, then becomes the other model's job
        redrawn = self._stale_stages(scenario)
        self._shown_keys = stage_keys(scenario)
        self._request_companion(scenario)
        self.results = results  # before the views: the what-if table reads the results on screen
        for view in self.views:
            view.show(results, redrawn)
        for stage in redrawn:
            self.render_counts[stage] += 1
        self.messages.show_warnings(results.warnings)
        self.status.object = self._status_html(results)

    def _show_failure(self, error: BaseException) -> None:
        """A failed run: its message in the page, the previous results kept."""
        if isinstance(error, ScenarioError):
            headline = "Inconsistent inputs:"
        else:
            headline = "The computation failed:"
            if not isinstance(error, ValueError | KeyError | SimulationError):
                log.error("pipeline run failed", exc_info=error)
        self.messages.show_error(headline, [scenarios.error_text(error)])
        if self._drawn_early:  # those plots show the previous results again
            self._shown_keys.update(self._drawn_early)
            for view in self.views:
                view.show_stages(self.results, set(self._drawn_early))
            self._drawn_early.clear()
        for view in self.views:
            view.settle()
        self.status.object = (
            '<span class="failed">Last run failed; the plots show the previous results.</span>'
            if self.results
            else ""
        )

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

    @one_message(reindex_once=True)
    def _finish_companion(self, other: Scenario, outcome: Results | None | BaseException):
        """Draw the other model's curve if it still belongs to the results on screen."""
        if isinstance(outcome, BaseException):
            log.error("comparison run failed", exc_info=outcome)
            outcome = None
        if other.to_json() != self._companion_json:  # inputs have changed since it was asked for
            return
        self.comparison_state = "unavailable" if outcome is None else "shown"
        self.other_model = outcome  # a new curve: the depth plot is drawn again
        if outcome is None:  # without the empty curve that held the curve's place
            self.param.trigger("other_model")
        self.status.object = self._status_html(self.results)

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
        other = plots.MODEL_NAMES[OTHER_MODEL[plots.scenario_of(results).tunnel.model]]
        parts.append(
            f'<span class="comparison-status" data-state="{self.comparison_state}">'
            f"{html.escape(other)} on the depth plot: {self.comparison_state}</span>"
        )
        return '<div class="stages">Last run: ' + " · ".join(parts) + "</div>"


def _run_to_end(coroutine) -> None:
    """Run ``coroutine`` to its end before returning; where this thread already runs an event
    loop (a Jupyter kernel's), on a loop of its own in a helper thread."""
    try:
        asyncio.get_running_loop()
    except RuntimeError:
        asyncio.run(coroutine)
        return
    with ThreadPoolExecutor(max_workers=1) as helper:
        helper.submit(asyncio.run, coroutine).result()
