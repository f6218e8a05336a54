"""Upload of a measured rail profile, held by content in the session's scenario.

The uploaded CSV's text becomes ``irregularity.profile_data`` (the format of
:mod:`model.params.measured_profile`): nothing is written on the server and no path is kept,
so the profile goes wherever the scenario goes (its runs, a saved scenario or session file, a
study's workers) and one session's upload is invisible to every other session. A file over
:data:`~model.params.measured_profile.MAX_PROFILE_BYTES` or a malformed one is refused in the
page's messages, naming the line and the fault.
"""

from __future__ import annotations

import html

import panel as pn
import param

from dashboard.limits import PROFILE_CSV_BYTES, refuse_oversized
from dashboard.messages import Messages
from model.params import Irregularity
from model.params.measured_profile import parse_profile, profile_text


def _note_html(irregularity: Irregularity) -> str:
    """Which profile the runs use: the uploaded one (points, range) or the synthetic FRA one."""
    if irregularity.profile_data is None:
        text = "Profile: synthetic (FRA PSD). Upload a measured one (CSV: x_m,eta_m or eta_mm):"
    else:
        profile = parse_profile(irregularity.profile_data)
        text = (
            f"Profile: measured, {profile.n_points} points from x = {profile.x_m[0]:g} to "
            f"{profile.x_m[-1]:g} m."
        )
    return f'<div class="profile-note" style="font-size: 12px">{html.escape(text)}</div>'


class ProfileInput:
    """The measured-profile upload of one session, bound to its scenario's irregularity.

    Parameters
    ----------
    irregularity : Irregularity
        The session's irregularity settings; edited in place.
    messages : Messages
        Where a refused file is reported.
    """

    def __init__(self, irregularity: Irregularity, messages: Messages) -> None:
        self.irregularity, self.messages = irregularity, messages
        self.note = pn.pane.HTML(_note_html(irregularity), sizing_mode="stretch_width")
        self.upload = pn.widgets.FileInput(
            accept=".csv,.txt",
            multiple=False,
            sizing_mode="stretch_width",
            css_classes=["profile-upload"],
        )
        self.upload.param.watch(self._on_upload, "value")
        self.synthetic_button = pn.widgets.Button(
            label="Use the synthetic profile",
            disabled=irregularity.profile_data is None,
            sizing_mode="stretch_width",
            css_classes=["profile-synthetic"],
        )
        self.synthetic_button.on_click(lambda _event: self.use_synthetic())
        irregularity.param.watch(self._follow, "profile_data")

    def widgets(self) -> list[pn.viewable.Viewable]:
        """The note, the upload and the button back to the synthetic profile."""
        return [self.note, self.upload, self.synthetic_button]

    def load(self, data: bytes, filename: str) -> None:
        """Use the profile in ``data`` (an uploaded file's bytes), or say why not."""
        try:
            refuse_oversized(data, filename, PROFILE_CSV_BYTES)
            text = profile_text(data, filename)  # the messages name the file
        except ValueError as error:
            self.messages.show_error("Measured profile not used:", [str(error)])
            return
        self.messages.clear_error()
        self.irregularity.param.update(profile_csv=None, profile_data=text)

    def use_synthetic(self) -> None:
        """Go back to the synthetic FRA profile."""
        self.irregularity.param.update(profile_csv=None, profile_data=None)

    def _on_upload(self, event: param.parameterized.Event) -> None:
        if event.new is None:
            return
        filename = self.upload.filename or "the file"
        self.upload.clear()  # so that uploading the same file again is a new event
        self.load(event.new, filename)

    def _follow(self, _event: param.parameterized.Event) -> None:
        """The note and the button follow the scenario (an upload, a loaded scenario file)."""
        self.note.object = _note_html(self.irregularity)
        self.synthetic_button.disabled = self.irregularity.profile_data is None
