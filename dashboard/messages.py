"""The messages above the views: what went wrong (a refused value, a bad file or URL argument, a
failed run) and the warnings of the results on screen, as alerts that show the text literally
(never a traceback)."""

from __future__ import annotations

import re

import panel as pn


def _markdown_escape(text: str) -> str:
    """Text shown literally inside a Markdown alert."""
    return re.sub(r"([\\`*_{}\[\]<>#|])", r"\\\1", text)


def _bullets(messages: list[str]) -> str:
    """Markdown list of ``messages``, each shown literally."""
    return "\n".join(f"- {_markdown_escape(m)}" for m in messages)


class Messages:
    """The error alert and the warning alert of one page (hidden while they have nothing to
    say)."""

    def __init__(self) -> None:
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

    def show_error(self, headline: str, messages: list[str]) -> None:
        """Show ``headline`` (Markdown) above the ``messages`` (shown literally)."""
        self.error_alert.param.update(
            object=f"**{headline}**\n\n{_bullets(messages)}", visible=True
        )

    def clear_error(self) -> None:
        """Hide the error message."""
        self.error_alert.param.update(object="", visible=False)

    def show_warnings(self, warnings: list[str]) -> None:
        """The warnings of the results on screen (hidden when there are none)."""
        self.warning_alert.param.update(
            object="**Warnings**\n\n" + _bullets(warnings), visible=bool(warnings)
        )
