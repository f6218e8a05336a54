"""Two checks of the long-term tab's settlement curve: how sure it is, and how much of it the
track irregularity makes.

* :class:`SettlementBandPanel`: on a button (draws cost a passage per seed), the 5–95 % band of
  :func:`model.study.band.settlement_band` (Monte Carlo on Dask, as the study tab runs its
  studies: a thread of its own, the session's scheduler, cancellable, cancelled with a closed
  session), drawn behind the curve with the number of draws that made it.
* :class:`SmoothRailPanel`: on a button, the same scenario with ``irregularity.enabled =
  False``, computed by the session's run function (its stage cache, the shared pool), drawn
  over the curve, with the ratio irregular/smooth after the service time.

Both belong to the results they were computed for: results of other inputs drop them (a band
still running is cancelled) and the panel says so; they are not recomputed by themselves.
:func:`settlement_plot` is the tab's settlement plot with both drawn in.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from concurrent.futures import Executor
from functools import partial

import holoviews as hv
import pandas as pd
import panel as pn
import param

from dashboard.limits import reserve_local_cluster, whole_number_input
from dashboard.plots import MM, scenario_of
from dashboard.scheduler import EXECUTOR, outcome_of
from dashboard.site_view import SETTLEMENT, YEARS, settlement_components_plot
from model.longterm.settlement import long_term_settlement
from model.params import Scenario
from model.pipeline import Results, run
from model.run_cost import estimate_run
from model.study.band import DEFAULT_SEEDS, MAX_CV, band_seeds, settlement_band
from model.study.execution import machine_workers

BAND_COLOUR = "#9467bd"
SMOOTH_COLOUR = "#2ca02c"
DASHBOARD_MAX_DRAWS = 1000  # the command line takes up to model.study.band.MAX_DRAWS
DEFAULT_DASHBOARD_DRAWS = 20
MAX_SEEDS = 50


def counted(n: int, noun: str) -> str:
    """ "1 draw", "3 draws"."""
    return f"{n} {noun}" if n == 1 else f"{n} {noun}s"


def band_label(table: pd.DataFrame) -> str:
    """Legend entry of a band's shaded area, with the number of draws that made it."""
    return f"band of {counted(table.attrs['n_draws'], 'draw')}: p05–p95"


def band_layers(table: pd.DataFrame | None) -> list[hv.Element]:
    """The band's p05–p95 area and its p50 line (mm), or nothing without a band."""
    if table is None or table.empty:
        return []
    n_draws = table.attrs["n_draws"]
    return [
        hv.Area(
            (table["years"], table["p95"] * MM, table["p05"] * MM),
            kdims=[YEARS],
            vdims=[SETTLEMENT, "base"],
            label=band_label(table),
        ).opts(color=BAND_COLOUR, alpha=0.35, line_color=BAND_COLOUR, line_width=1, framewise=True),
        hv.Curve(
            (table["years"], table["p50"] * MM),
            kdims=[YEARS],
            vdims=[SETTLEMENT],
            label=f"p50 of {counted(n_draws, 'draw')}",
        ).opts(color=BAND_COLOUR, line_dash="dashed", line_width=1.5, framewise=True),
    ]


def smooth_rail_layers(smooth: Results | None) -> list[hv.Element]:
    """The smooth rail's settlement (mm), or nothing without it."""
    if smooth is None:
        return []
    lt = smooth.longterm
    return [
        hv.Curve(
            (lt.years, lt.settlement_m * MM),
            kdims=[YEARS],
            vdims=[SETTLEMENT],
            label=f"smooth rail: {lt.settlement_m[-1] * MM:.3g} mm",
        ).opts(color=SMOOTH_COLOUR, line_dash="dotdash", line_width=2, framewise=True)
    ]


def settlement_plot(
    results: Results, band: pd.DataFrame | None = None, smooth: Results | None = None
) -> hv.Overlay:
    """The long-term tab's settlement plot: the stacked parts and total of
    :func:`~dashboard.site_view.settlement_components_plot`, the band behind them and the
    smooth rail's curve over them (each when given)."""
    return settlement_components_plot(
        results, behind=band_layers(band), over=smooth_rail_layers(smooth)
    )


def irregularity_ratio(results: Results, smooth: Results) -> float:
    """Settlement with the irregularity over that on a smooth rail after the service time
    (inf when the smooth rail's is 0)."""
    irregular, plain = results.longterm.settlement_m[-1], smooth.longterm.settlement_m[-1]
    return float(irregular / plain) if plain > 0 else float("inf")


def smooth_rail_statement(results: Results, smooth: Results) -> str:
    """Markdown: both settlements after the service time, their ratio and the irregularity's
    share."""
    irregular, plain = results.longterm.settlement_m[-1], smooth.longterm.settlement_m[-1]
    years = results.longterm.years[-1]
    ratio = irregularity_ratio(results, smooth)
    change = f" (the irregularity changes it by {ratio - 1.0:+.1%})" if plain > 0 else ""
    return (
        f"**Irregularity's share:** after {years:g} years {irregular * MM:.3g} mm with the "
        f"irregularity, {plain * MM:.3g} mm on a smooth rail (irregularity.enabled = False, "
        f"the other inputs the same): irregular/smooth = {ratio:.3g}{change}."
    )


def band_statement(table: pd.DataFrame) -> str:
    """Markdown: the band's draws and seeds and its p05, p50, p95 after the service time."""
    final = table.iloc[-1]
    attrs = table.attrs
    failed = attrs["n_requested"] - attrs["n_draws"]
    notes = [f"{counted(failed, 'draw')} failed" if failed and not attrs["cancelled"] else ""]
    notes.append("cancelled: the draws done so far" if attrs["cancelled"] else "")
    note = "".join(f" ({text})" for text in notes if text)
    return (
        f"**Settlement band of {attrs['n_draws']} of {counted(attrs['n_requested'], 'draw')}** "
        f"({counted(len(attrs['seeds']), 'irregularity seed')}){note}: after "
        f"{final['years']:g} years p05 {final['p05'] * MM:.3g} mm, p50 {final['p50'] * MM:.3g} mm, "
        f"p95 {final['p95'] * MM:.3g} mm."
    )


def longterm_stage_seconds(results: Results) -> float:
    """Time of the results' long-term stage (s): as the run measured it, or timed here once
    when the stage came from the cache (milliseconds: docs/longterm.md, Cost)."""
    seconds = results.stage_seconds.get("longterm", 0.0)
    if seconds > 0.0:
        return seconds
    start = time.perf_counter()
    long_term_settlement(results.stress, results.scenario)
    return time.perf_counter() - start


def band_seconds(scenario: Scenario, n_draws: int, n_seeds: int, draw_seconds: float) -> float:
    """Estimated wall time of a band (s): a passage per seed (:func:`model.run_cost.
    estimate_run`) and a long-term stage per draw (``draw_seconds``, measured), shared by the
    machine's workers (one task per seed). Cluster start-up not included."""
    n_tasks = len(band_seeds(scenario, min(n_seeds, n_draws)))
    workers = max(1, min(machine_workers(), n_tasks))
    passage = estimate_run(scenario).total_seconds
    return (n_tasks * passage + n_draws * draw_seconds) / workers


class SessionLoop:
    """Hands a worker thread's outcome to the session's event loop (``add_next_tick_callback``)
    when served, or runs it at once (tests, notebooks); nothing once the session is closed."""

    def __init__(self) -> None:
        self.doc = None
        self.closed = False

    def remember(self) -> None:
        """Note the session's document (call from its event loop, e.g. in a click)."""
        if pn.state.curdoc is not None:
            self.doc = pn.state.curdoc

    def call(self, callback: Callable[[], None]) -> None:
        """Run ``callback`` on the session's loop, or here when not served."""
        if self.closed:
            return
        doc = self.doc
        if doc is not None and doc.session_context is not None:
            doc.add_next_tick_callback(callback)
        else:
            callback()


class SettlementBandPanel(pn.viewable.Viewer):
    """Start, watch and cancel a settlement band of the results on screen.

    Parameters
    ----------
    changed : callable
        Called (no arguments) when the band to draw changes: a new one, or none.
    scheduler : None, str or distributed.Client
        Where bands run (as the study tab's: ``$TUNNELSETTLE_SCHEDULER`` or a LocalCluster per
        band by default).
    threaded : bool
        Run the band in its own thread (served app) or in the calling thread (tests).
    """

    scheduler = param.Parameter(default=None, doc="Dask scheduler address or Client, or None.")
    threaded = param.Boolean(default=True, doc="Run the band in its own thread.")
    running = param.Boolean(default=False, doc="A band is running.")
    table = param.DataFrame(default=None, allow_None=True, doc="The band drawn, if any.")

    def __init__(self, changed: Callable[[], None] = lambda: None, **params) -> None:
        super().__init__(**params)
        self._changed = changed
        self.draws = pn.widgets.IntInput(
            label="Draws",
            width=150,
            value=DEFAULT_DASHBOARD_DRAWS,
            start=1,
            end=DASHBOARD_MAX_DRAWS,
            css_classes=["band-draws"],
        )
        self.seeds = pn.widgets.IntInput(
            label="Irregularity seeds", value=min(DEFAULT_SEEDS, DEFAULT_DASHBOARD_DRAWS), start=1,
            end=MAX_SEEDS, width=150, css_classes=["band-seeds"],
        )  # fmt: skip
        self.cv_a = pn.widgets.FloatInput(
            label="CV of the strain-law coefficient a (-)", value=0.0, start=0.0, end=MAX_CV,
            step=0.05, css_classes=["band-cv"],
        )  # fmt: skip
        self.plan = pn.pane.Markdown("", sizing_mode="stretch_width", css_classes=["band-plan"])
        """How many draws Start computes and about how long they take."""
        self.start_button = pn.widgets.Button(
            label="Start band", color="primary", css_classes=["band-start"]
        )
        self.cancel_button = pn.widgets.Button(
            label="Cancel", color="warning", disabled=True, css_classes=["band-cancel"]
        )
        self.progress = pn.indicators.Progress(
            value=0, max=1, sizing_mode="stretch_width", visible=False
        )
        self.status = pn.pane.Markdown("", sizing_mode="stretch_width", css_classes=["band-status"])
        self._results: Results | None = None
        self._draw_seconds: float | None = None
        self._base_json = ""
        self._cancel = threading.Event()
        self._loop = SessionLoop()
        self.start_button.on_click(lambda event: self.start())
        self.cancel_button.on_click(lambda event: self.cancel())
        for widget in (self.draws, self.seeds, self.cv_a):
            widget.param.watch(lambda event: self.update_plan(), "value")
        self.update_plan()

    def __panel__(self) -> pn.viewable.Viewable:
        return pn.Column(
            "#### Settlement band (Monte Carlo)",
            pn.Row(self.draws, self.seeds),
            self.cv_a,
            self.plan,
            pn.Row(self.start_button, self.cancel_button),
            self.progress,
            self.status,
            styles={"flex": "1 1 360px"},
        )

    def law_cv(self) -> dict[str, float] | None:
        """The CVs of the law constants drawn (none at 0)."""
        return {"a": float(self.cv_a.value)} if self.cv_a.value else None

    def counts(self) -> tuple[int, int]:
        """The draws and seeds asked for (ValueError for an empty box or a value beyond it)."""
        return whole_number_input(self.draws), whole_number_input(self.seeds)

    def update_plan(self) -> None:
        """Say how many draws Start computes and about how long, before it is pressed."""
        if self._results is None:
            self.plan.object = "A band needs results on screen first."
            return
        scenario = scenario_of(self._results)
        try:
            n_draws, n_seeds = self.counts()
            if self._draw_seconds is None:
                self._draw_seconds = longterm_stage_seconds(self._results)
            seconds = band_seconds(scenario, n_draws, n_seeds, self._draw_seconds)
            passages = len(band_seeds(scenario, min(n_seeds, n_draws)))
        except ValueError as error:
            self.plan.object = f"Cannot start: {error}"
            return
        took = (
            f"about {seconds / 60:.0f} min"
            if seconds >= 90
            else (f"about {seconds:.0f} s" if seconds >= 1 else "under a second")
        )
        repeat = (
            f"; without a CV only {passages} distinct curves (a draw repeats its seed's)"
            if self.law_cv() is None and n_draws > passages
            else ""
        )
        self.plan.object = (
            f"**{counted(n_draws, 'draw')}** over {counted(passages, 'passage')}: {took} on "
            f"{min(machine_workers(), passages)} workers (estimate; plus a few seconds of "
            f"cluster start-up){repeat}"
        )

    def results_changed(self, results: Results) -> bool:
        """New results on screen: a band of other inputs is dropped (cancelled if running).
        Returns True when a drawn band was dropped (the caller redraws; ``changed`` is not
        called)."""
        new_inputs = results.scenario_json != self._results_json()
        self._results = results
        measured = results.stage_seconds.get("longterm", 0.0)
        if measured > 0.0:  # else the last measured time stands (the stage came from the cache)
            self._draw_seconds = measured
        dropped = False
        if results.scenario_json != self._base_json:
            if self.running:
                self._stop("**Band cancelled:** the inputs changed while it ran.")
            elif self.table is not None:
                n_draws = self.table.attrs["n_draws"]
                self.table, dropped = None, True
                self.status.object = (
                    f"**Band of {counted(n_draws, 'draw')} dropped:** the inputs changed since "
                    "it was computed; press Start for a band of the new inputs."
                )
        if new_inputs:
            self.update_plan()
        return dropped

    def _results_json(self) -> str:
        return "" if self._results is None else self._results.scenario_json

    def start(self) -> None:
        """Start a band of the results on screen (nothing while one runs)."""
        if self.running or self._results is None:
            return
        try:
            n_draws, n_seeds = self.counts()
            release_cluster = reserve_local_cluster(self.scheduler)
        except ValueError as error:
            self.status.object = f"**Not started:** {error}"
            return
        base, self._base_json = self._results.scenario, self._results.scenario_json
        tasks = len(band_seeds(base, min(n_seeds, n_draws)))
        self._cancel.clear()
        if self.table is not None:
            self.table = None
            self._changed()
        self.progress.param.update(value=0, max=tasks, visible=True)
        self.status.object = (
            f"Starting {counted(n_draws, 'draw')} (cluster start-up takes a few seconds)…"
        )
        self.running = True
        self.start_button.disabled, self.cancel_button.disabled = True, False
        self._loop.remember()
        work = partial(
            self._work,
            base,
            self._base_json,
            n_draws,
            n_seeds,
            self.law_cv(),
            self._cancel,
            release_cluster,
        )
        if self.threaded:
            threading.Thread(target=work, name="settlement-band", daemon=True).start()
        else:
            work()

    def cancel(self) -> None:
        """Stop the running band; the draws done are drawn."""
        if self.running:
            self._cancel.set()
            self.cancel_button.disabled = True
            self.status.object = "Cancelling: waiting for the draws in progress…"

    def close(self) -> None:
        """A closed session: stop the band, touch the page no more."""
        self._cancel.set()
        self._loop.closed = True

    def _stop(self, message: str) -> None:
        """Cancel the running band, whose outcome will not be drawn; say why."""
        self._cancel.set()
        self._base_json = ""
        self.cancel_button.disabled = True
        self.status.object = message

    def _work(
        self,
        base: Scenario,
        base_json: str,
        n_draws: int,
        n_seeds: int,
        law_cv,
        cancel,
        release_cluster,
    ):
        """The band (in its own thread when served); gives its cluster back and hands the
        outcome to the page."""
        try:
            outcome = settlement_band(
                base,
                n_draws,
                seeds=n_seeds,
                scheduler=self.scheduler,
                law_cv=law_cv,
                progress=lambda done, total, row: self._loop.call(partial(self._tick, done)),
                cancel=cancel,
            )
        except Exception as error:  # shown on the page; the server must not lose the thread
            outcome = error
        finally:
            release_cluster()
        self._loop.call(partial(self._finish, base_json, outcome))

    def _tick(self, done: int) -> None:
        if self.running and self._base_json:
            self.progress.value = done
            self.status.object = f"{done} of {self.progress.max} seeds done"

    def _finish(self, base_json: str, outcome: pd.DataFrame | Exception) -> None:
        """The band ended: drawn if it still belongs to the results on screen."""
        self.running = False
        self.start_button.disabled, self.cancel_button.disabled = False, True
        if isinstance(outcome, Exception):
            message = " ".join(str(outcome).split()) or type(outcome).__name__
            self.status.object = f"**Band failed:** {message}"
            return
        if base_json != self._results_json() or base_json != self._base_json:
            return  # the inputs changed meanwhile: said when it was cancelled
        self.progress.value = len(outcome.attrs["seeds"]) if not outcome.empty else 0
        if outcome.empty:
            self.status.object = "**Band cancelled** before a draw finished."
            return
        self.table = outcome
        self.status.object = band_statement(outcome)
        self._changed()


class SmoothRailPanel(pn.viewable.Viewer):
    """One click: the results on screen again on a smooth rail, and the irregularity's share.

    Parameters
    ----------
    changed : callable
        Called (no arguments) when the smooth rail's results to draw change.
    compute : callable(Scenario) -> Results, optional
        How the run is computed (the dashboard passes its own, with its stage cache: the
        vehicle–track stage runs again, the others only where they follow it).
    executor : Executor
        Where the run computes when threaded (the shared pool of :mod:`dashboard.scheduler`).
    threaded : bool
        Compute without blocking the event loop (served app) instead of before returning.
    """

    threaded = param.Boolean(default=True, doc="Compute in the executor, not the caller.")
    smooth = param.ClassSelector(
        class_=Results, default=None, allow_None=True, doc="The smooth rail's results drawn."
    )

    def __init__(
        self,
        changed: Callable[[], None] = lambda: None,
        compute: Callable[[Scenario], Results] | None = None,
        executor: Executor = EXECUTOR,
        **params,
    ) -> None:
        super().__init__(**params)
        self._changed = changed
        self._compute = compute if compute is not None else partial(run, cache=None)
        self._executor = executor
        self.button = pn.widgets.Button(
            label="Compare with a smooth rail", color="primary", css_classes=["smooth-rail"]
        )
        self.status = pn.pane.Markdown(
            "The same inputs with irregularity.enabled = False: how much of the settlement the "
            "track irregularity makes.",
            sizing_mode="stretch_width",
            css_classes=["smooth-rail-status"],
        )
        self._results: Results | None = None
        self._base_json = ""
        self._loop = SessionLoop()
        self.button.on_click(lambda event: self.start())

    def __panel__(self) -> pn.viewable.Viewable:
        return pn.Column(
            "#### Irregularity's share", self.button, self.status, styles={"flex": "1 1 300px"}
        )

    def statement(self) -> str:
        """The irregularity's share for the tab's statement, or "" without a smooth run."""
        if self.smooth is None or self._results is None:
            return ""
        return smooth_rail_statement(self._results, self.smooth)

    def results_changed(self, results: Results) -> bool:
        """New results on screen: the smooth rail of other inputs is dropped, not recomputed.
        Returns True when a drawn curve was dropped (the caller redraws; ``changed`` is not
        called)."""
        self._results = results
        if results.scenario_json == self._base_json:
            return False
        if self.smooth is not None or self._base_json:
            self.status.object = (
                "**Smooth rail dropped:** the inputs changed; press the button to compare again."
            )
        self._base_json = ""
        dropped, self.smooth = self.smooth is not None, None
        return dropped

    def start(self) -> None:
        """Run the results on screen on a smooth rail (the irregularity switched off)."""
        if self._results is None:
            return
        scenario = self._results.scenario
        if not scenario.irregularity.enabled:
            self.status.object = "The rail is smooth already (irregularity.enabled = False)."
            return
        scenario.irregularity.enabled = False
        self._base_json = self._results.scenario_json
        self.button.disabled = True
        self.status.object = "Computing the smooth rail…"
        self._loop.remember()
        finish = partial(self._finish, self._base_json)
        if not self.threaded:
            finish(outcome_of(self._compute, scenario))
            return
        future = self._executor.submit(outcome_of, self._compute, scenario)
        future.add_done_callback(lambda done: self._loop.call(partial(finish, done.result())))

    def close(self) -> None:
        """A closed session: touch the page no more."""
        self._loop.closed = True

    def _finish(self, base_json: str, outcome: Results | BaseException) -> None:
        """Draw the smooth rail if it still belongs to the results on screen."""
        self.button.disabled = False
        if base_json != self._base_json or self._results is None:
            return  # the inputs changed meanwhile: said when they did
        if isinstance(outcome, BaseException):
            message = " ".join(str(outcome).split()) or type(outcome).__name__
            self.status.object = f"**Smooth rail failed:** {message}"
            return
        self.smooth = outcome
        self.status.object = smooth_rail_statement(self._results, outcome)
        self._changed()
