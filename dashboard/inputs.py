"""The sidebar's inputs of one session: preset, tunnel–soil model switch, train type, a control
per parameter (the main ones up front, the rest in collapsible groups) and the scenario file.

They edit the session's :class:`~model.params.Scenario` in place; controls come from the
parameters (:mod:`dashboard.controls`), presets and train types from :mod:`model.scenarios`, the
measured-profile upload from :mod:`dashboard.profile_input`. A profile path in a loaded
scenario file is read only inside the server's data folder
(:func:`model.params.measured_profile.admit_profile`).
A refused value is reported beside its field until the next accepted change; a bad file in
the page's messages (:mod:`dashboard.messages`).
"""

from __future__ import annotations

import html
import io
from collections.abc import Callable

import panel as pn
import param

from dashboard.controls import ParameterControl
from dashboard.limits import SESSION_JSON_BYTES, refuse_oversized
from dashboard.messages import Messages
from dashboard.profile_input import ProfileInput
from model import scenarios
from model.params import SECTIONS, Scenario
from model.params.measured_profile import admit_profile, data_folder

PRIMARY = ("train.speed_kmh", "soil.youngs_modulus", "track.fastener_stiffness")
"""Main inputs, shown up front; every other parameter sits in its section's collapsible group."""

SWITCHES = ("tunnel.model", "tunnel.ground")
"""Model switches shown up front with the presets."""

GROUP_TITLES = {
    "train": "Train",
    "irregularity": "Track irregularity",
    "track": "Track",
    "soil": "Soil",
    "tunnel": "Lining",
    "vehicle": "Vehicle",
    "site": "Site profile",
    "longterm": "Long-term settlement",
    "numerics": "Numerics",
}
"""Collapsible groups in display order: section → title."""

HIDDEN = {"irregularity.profile_csv", "irregularity.profile_data", "site.layers"}
"""Not offered as a control: a measured profile is uploaded (:mod:`dashboard.profile_input`);
the site's layers are edited in the long-term tab's layer table (:mod:`dashboard.site_view`)."""


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


def _note_html(text: str) -> str:
    """Small grey paragraph showing ``text`` literally."""
    return f'<div style="font-size: 12px; color: #57606a">{html.escape(text)}</div>'


class InputsPanel:
    """The inputs of one session, bound to its scenario both ways.

    Parameters
    ----------
    scenario : Scenario
        The session's inputs; edited in place.
    preset : str
        Name shown in the preset selector.
    messages : Messages
        Where refused values and bad scenario files are reported.
    on_change : callable
        ``on_change()``: called after an input changed (once when a whole scenario is replaced).
    """

    def __init__(
        self, scenario: Scenario, preset: str, messages: Messages, on_change: Callable[[], None]
    ) -> None:
        self.scenario = scenario
        self.base_preset = preset
        """The preset the inputs started from (what-if names say what differs from it)."""
        self.messages = messages
        self._on_change = on_change
        self._replacing = False
        self._quiet = False

        self.controls = {
            f"{section}.{name}": ParameterControl(obj, f"{section}.{name}", self._on_refusal)
            for section in SECTIONS
            for obj in [getattr(scenario, section)]
            for name in obj.param
            if name != "name" and f"{section}.{name}" not in HIDDEN
        }
        for section in SECTIONS:
            obj = getattr(scenario, section)
            obj.param.watch(self._on_parameter, [n for n in obj.param if n != "name"])

        self.profile = ProfileInput(scenario.irregularity, messages)
        """The measured-profile upload, in the track irregularity group."""

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
            self._preset_note(preset),
            margin=(0, 10),
            sizing_mode="stretch_width",
            css_classes=["preset-note"],
        )
        self.train_type = pn.widgets.Select(
            label="Train type",
            options=[*scenarios.TRAIN_TYPES, scenarios.CUSTOM],
            value=scenarios.train_type_of(scenario.train),
            description="Car length, bogie-centre distance and wheelbase of a standard "
            "Chinese metro car.",
            sizing_mode="stretch_width",
        )
        self.train_type.param.watch(self._on_train_type, "value")
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

    def sidebar(self) -> list[pn.viewable.Viewable]:
        """Preset, model switch, train type and main inputs; the rest in groups; the file."""
        up_front = {*PRIMARY, *SWITCHES}
        groups = [
            _lazy_card(
                [
                    control
                    for path, control in self.controls.items()
                    if path.startswith(f"{section}.") and path not in up_front
                ]
                + (self.profile.widgets() if section == "irregularity" else []),
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
        ]

    def show_matching(self) -> None:
        """The preset and train type selectors name what the inputs match ('custom' if
        nothing), without treating it as the user's choice."""
        self._set_quietly(self.preset_select, scenarios.matching_preset(self.scenario))
        self._set_quietly(self.train_type, scenarios.train_type_of(self.scenario.train))

    def replace_scenario(self, scenario: Scenario) -> None:
        """Adopt every input of ``scenario`` (controls follow), then one change."""
        self._replacing = True
        try:
            self.scenario.update(scenario.to_dict())
        finally:
            self._replacing = False
        self._clear_refusals()
        self.messages.clear_error()
        self._after_change()

    def _on_parameter(self, *events: param.parameterized.Event) -> None:
        """An input changed (control, train type): the selectors follow, then the change."""
        if self._replacing:
            return
        self._after_change()

    def _after_change(self) -> None:
        """The change is passed on (its run starts first); the selectors follow the inputs."""
        self._on_change()
        self.show_matching()

    def _on_refusal(self, path: str, message: str | None) -> None:
        """A control refused an edit (its message is beside it) or took one (None): the
        messages of earlier refusals go, their fields show the values in force again."""
        if message is None:
            self._clear_refusals()

    def _clear_refusals(self) -> None:
        """Hide every refused edit's message."""
        for control in self.controls.values():
            control.clear_refusal()

    def _preset_note(self, preset: str) -> str:
        """The preset's description; for custom inputs, which preset they started from."""
        if preset == scenarios.CUSTOM:
            return _note_html(
                f"Custom inputs: some differ from every preset (started from {self.base_preset})."
            )
        return _note_html(self._preset_descriptions.get(preset, ""))

    def _on_preset(self, event: param.parameterized.Event) -> None:
        """Replace every input by the chosen preset's."""
        if event.new != scenarios.CUSTOM and not self._quiet:
            self.base_preset = event.new
        note = self._preset_note(event.new)  # it follows quiet changes too
        if note != self.preset_note.object:  # each update of the pane re-indexes the page
            self.preset_note.object = note
        if self._quiet or event.new == scenarios.CUSTOM:
            return
        self.replace_scenario(Scenario.preset(event.new))

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
            refuse_oversized(event.new, filename, SESSION_JSON_BYTES)
            scenario = Scenario.from_json(event.new)
            admit_profile(scenario, data_folder())  # a path: only inside the data folder
        except (ValueError, KeyError, TypeError, AttributeError) as error:
            self.messages.show_error(
                f"Could not load {filename} as a scenario:", [scenarios.error_text(error)]
            )
            return
        self.replace_scenario(scenario)

    def _set_quietly(self, widget: pn.widgets.Widget, value) -> None:
        """Set a selector without treating it as the user's choice."""
        self._quiet = True
        try:
            widget.value = value
        finally:
            self._quiet = False

    def _scenario_file(self) -> io.StringIO:
        """Current inputs as a JSON file."""
        return io.StringIO(self.scenario.to_json())
