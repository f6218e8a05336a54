"""Interactive dashboard: ``panel serve dashboard/app.py --warm``, then open
http://localhost:5006/app.

The wiring layer only: it builds one session's page from its parts and connects them. The
sidebar's inputs are :mod:`dashboard.inputs`, the messages above the views
:mod:`dashboard.messages`, the runs with their progress bar and status line
:mod:`dashboard.runs`; the views are :mod:`dashboard.passage_view` (with the what-if panel of
:mod:`dashboard.whatif_view`), :mod:`dashboard.longterm_view`, :mod:`dashboard.ground_view` and
:mod:`dashboard.study_view`;
the report button is :mod:`dashboard.report`'s. ``--warm`` compiles the kernels when the server
starts.

URL query arguments choose the initial scenario: ``?preset=single_bogie`` and any number of
``section.parameter=value`` overrides in SI units, e.g. ``?preset=paper&train.speed_kmh=60``.
"""

from __future__ import annotations

from concurrent.futures import Executor, Future
from functools import partial

import panel as pn
import param

from dashboard.ground_view import GroundView
from dashboard.inputs import InputsPanel
from dashboard.longterm_view import LongTermView
from dashboard.memory import release_links, session_closed
from dashboard.messages import Messages
from dashboard.page import PAGE_CSS, close_drawer_in_narrow_windows
from dashboard.passage_view import PassageView
from dashboard.report import report_button
from dashboard.runs import SessionRuns, admitted
from dashboard.scheduler import EXECUTOR, warm_up, warm_up_run
from dashboard.study_view import StudyView
from dashboard.whatif_view import WhatIfPanel
from model import scenarios
from model.params import Scenario
from model.params.measured_profile import admit_profile, data_folder
from model.pipeline import Results, StageCache, run


class Dashboard(pn.viewable.Viewer):
    """The dashboard of one browser session: inputs, runs, views of the results, export.

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
        self.cache = cache if cache is not None else StageCache()
        self.messages = Messages()
        self.inputs = InputsPanel(self.scenario, preset, self.messages, self._after_change)
        self.runs = SessionRuns(
            self.scenario,
            messages=self.messages,
            cache=self.cache,
            executor=executor,
            warm=warm,
            threaded=self.threaded,
        )
        self.whatif = WhatIfPanel(
            current=lambda: (self.scenario, self.runs.results),
            restore=self.inputs.replace_scenario,
            compute=self.compute,
            preset=lambda: self.inputs.base_preset,
            threaded=self.threaded,
            executor=executor,
        )
        self.passage = PassageView(self.whatif, companions=self.runs.depth_companions)
        self.longterm = LongTermView(
            self.scenario.longterm, self.scenario.site, compute=self.compute, threaded=self.threaded
        )
        self.ground = GroundView()
        self.runs.views = (self.passage, self.longterm, self.ground)
        self.study = StudyView(scenario_source=lambda: admitted(self.scenario.copy()))
        self.report_button = report_button(
            results=lambda: self.runs.results,
            scenario_name=lambda: self.inputs.preset_select.value,
            other_model=lambda: self.runs.other_model,
        )
        self.runs.param.watch(self._on_results, "results")
        self.runs.param.watch(self._on_other_model, "other_model")
        self.views: dict[str, pn.viewable.Viewable] = {
            "Passage": self.passage,
            "Long-term settlement": self.longterm,
            "Ground vibration": self.ground,
            "Study": self.study,
        }
        """Main-area views by tab title; :meth:`add_view` adds one."""
        self.tabs = pn.Tabs(*self.views.items(), sizing_mode="stretch_width", dynamic=True)
        self.passage.update_soil_summary(self.scenario.soil)

    @classmethod
    def from_query(cls, args: dict[str, list[bytes]], **params) -> Dashboard:
        """Dashboard for URL query arguments (``preset`` and ``section.parameter`` overrides).

        A bad argument is reported in the page, not raised.
        """
        decoded = {key: values[-1].decode("utf-8", "replace") for key, values in args.items()}
        preset, scenario, problems = scenarios.scenario_from_arguments(decoded)
        try:  # a profile path from a URL is read only inside the data folder
            admit_profile(scenario, data_folder())
        except ValueError as error:
            scenario.irregularity.profile_csv = None
            problems.append(str(error))
        dashboard = cls(scenario=scenario, preset=preset, **params)
        dashboard.inputs.show_matching()
        if problems:
            dashboard.messages.show_error("Ignored URL arguments:", problems)
        return dashboard

    # ---- layout ---------------------------------------------------------------------------
    def add_view(self, title: str, view: pn.viewable.Viewable) -> None:
        """Add a tab to the main area (e.g. long-term settlement, studies)."""
        self.views[title] = view
        self.tabs.append((title, view))

    def sidebar(self) -> list[pn.viewable.Viewable]:
        """Sidebar: the inputs, then the report button."""
        return [*self.inputs.sidebar(), self.report_button]

    def main(self) -> list[pn.viewable.Viewable]:
        """Main area: run progress, status and messages above the tabs of views, each a root
        of its own in the page. The tabs inside a Column with these lost their long-term plots'
        layout (titles, tick labels, axis positions) each time the calibration drew its first
        plot: the browser test of an upload checks it."""
        return [
            self.runs.progress_box,
            self.runs.status,
            self.messages.error_alert,
            self.messages.warning_alert,
            self.tabs,
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
            raw_css=[PAGE_CSS],  # the sidebar is a drawer in a narrow window
        )

    # ---- connections ------------------------------------------------------------------------
    def compute(self, scenario: Scenario) -> Results:
        """One run outside the session's run queue (what-if loads, the smooth rail), with the
        session's stage cache."""
        return run(admitted(scenario), cache=self.cache)

    def refresh(self) -> None:
        """Bring the results up to date with the scenario (see :meth:`SessionRuns.refresh`)."""
        self.runs.refresh()

    def close(self) -> None:
        """Drop the results and plots of a closed session (its memory returns at once), and
        its widgets' entries in Panel's link registry (which would keep them for ever)."""
        self.passage.close()
        self.longterm.close()
        self.ground.close()
        self.runs.close()
        release_links(pn.Column(*self.main()))  # the sidebar's inputs register none

    def _after_change(self) -> None:
        """An input changed: a run is requested (it starts computing at once), and the soil
        quantities follow."""
        self.refresh()
        self.passage.update_soil_summary(self.scenario.soil)

    def _on_results(self, event: param.parameterized.Event) -> None:
        """The report can be downloaded once there are results."""
        self.report_button.disabled = event.new is None

    def _on_other_model(self, event: param.parameterized.Event) -> None:
        """The other tunnel–soil model's run ended: the depth plot draws its curve, or drops
        the empty one that held its place if the run failed."""
        if event.new is not None or self.runs.comparison_state == "unavailable":
            self.passage.redraw_depth_plot()


def serve_session() -> Dashboard:
    """Build the page of one browser session of ``panel serve`` (the server's shared stage
    cache and warm-up; the session's memory is dropped when it closes)."""
    cache = pn.state.as_cached("tunnelsettle-stage-cache", StageCache)
    dashboard = Dashboard.from_query(
        pn.state.session_args, cache=cache, warm=warm_up(warm_up_run), threaded=True
    )
    # once the page is loaded: its own run, or (drawn from the cache) only the comparison curve
    drawn = dashboard.runs.show_cached()
    pn.state.onload(dashboard.runs.compute_waiting if drawn else dashboard.refresh)
    pn.state.on_session_destroyed(partial(session_closed, dashboard.close))
    close_drawer_in_narrow_windows(pn.state.curdoc)
    with pn.io.hold(freeze=True):  # the page's ~20 roots are indexed once, not each
        dashboard.template().servable()
    return dashboard


if pn.state.served and __name__ != "dashboard.app":  # this file, run by panel serve
    # The page is built by the imported module, not by this copy of the script: Bokeh runs the
    # script anew for each session and clears its globals when the session is destroyed, so
    # the session's close would find no names (and each session would define its own classes).
    from dashboard import app
    from dashboard.serve import use_light_resources

    use_light_resources()  # no MathJax bundle unless a formula is shown
    pn.extension("tabulator", notifications=False)  # the long-term tab's layer table
    app.serve_session()
