"""One control per model parameter, built from its declaration in :mod:`model.params`.

A control shows and takes its parameter in the parameter's display unit
(:func:`model.params.display_unit`: MPa, MN/m, GPa, …) while the parameter itself stays SI. It
is bound to the parameter object both ways: it follows every change of the parameter (preset,
loaded file, train type) and sets the parameter when the user edits it. A refused edit (text
that is not a number, a value outside the hard bounds) changes nothing — not the parameter, not
the slider's range — and its message goes to the ``report`` callback, for the page to show.

Why not ``pn.widgets.X.from_param`` / ``pn.Param``: those bind a widget to the SI value (no unit
conversion), and a refused value raises inside the watcher (server log, nothing in the page).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import panel as pn
import param

from model.params import display_label, display_range, display_unit, parameter_of

SLIDER_POSITIONS = 200
"""A slider's step gives at least this many positions over the parameter's soft bounds."""

SIGNIFICANT_DIGITS = 12
"""Unit conversions are rounded to this many digits: 6.1 MPa is 6 100 000 Pa, not …99.999."""

Report = Callable[[str, "str | None"], None]
"""``report(path, message)``: a refused edit's message, or None once the parameter accepted one."""


def clean_number(value: float) -> float:
    """``value`` rounded to :data:`SIGNIFICANT_DIGITS` (removes binary noise of conversions)."""
    return float(f"{value:.{SIGNIFICANT_DIGITS}g}")


def slider_step(low: float, high: float) -> float:
    """A round step giving at least :data:`SLIDER_POSITIONS` positions from ``low`` to ``high``."""
    return 10.0 ** math.floor(math.log10((high - low) / SLIDER_POSITIONS))


def step_decimals(step: float) -> int:
    """Decimal places of a slider step (0.1 → 1; 1 and above → 0)."""
    return max(0, -round(math.log10(step)))


def format_value(value, parameter: param.Parameter) -> str:
    """Text of a display value: integers exactly, reals to six significant digits."""
    if value is None:
        return ""
    if isinstance(parameter, param.Integer):
        return str(int(value))
    return f"{value:.6g}"


class ParameterControl(pn.viewable.Viewer):
    """The control of one parameter: a text box in display units, with a slider for bounded
    numbers; a select box for choices; a checkbox for switches.

    Parameters
    ----------
    owner : param.Parameterized
        The scenario section holding the parameter (e.g. ``scenario.soil``).
    path : str
        ``"section.name"``; the control's root has the CSS class ``param-section-name``.
    report : callable
        ``report(path, message)``, see :data:`Report`.
    """

    def __init__(self, owner: param.Parameterized, path: str, report: Report) -> None:
        super().__init__()
        self.owner, self.path, self._report = owner, path, report
        self.name_in_owner = path.partition(".")[2]
        self.parameter = parameter_of(path)
        self.unit, self.factor = display_unit(path)
        self.label = display_label(path)
        self.tooltip = f"{self.label}. {self.parameter.doc or ''}".strip()
        self._following = False  # True while the control shows a new parameter value
        p, value = self.parameter, self.value
        self.text: pn.widgets.TextInput | None = None
        self.slider: pn.widgets.Widget | None = None
        css = [f"param-{path.replace('.', '-')}"]
        if isinstance(p, param.Boolean):
            self.widget = pn.widgets.Checkbox(label=self.label, value=value, margin=(8, 5))
            self.widget.param.watch(self._on_choice, "value")
            root = [self.widget, pn.widgets.TooltipIcon(value=self.tooltip, margin=(8, 0))]
        elif isinstance(p, param.Selector):
            self.widget = pn.widgets.Select(
                label=self.label,
                options=list(p.objects),
                value=value,
                description=self.tooltip,
                sizing_mode="stretch_width",
            )
            self.widget.param.watch(self._on_choice, "value")
            root = [self.widget]
        else:
            self.text = self.widget = pn.widgets.TextInput(
                label=self.label,
                value=format_value(value, p),
                placeholder="automatic" if p.allow_None else "",
                description=self.tooltip,
                sizing_mode="stretch_width",
                margin=(5, 10, 0, 10),
            )
            self.text.param.watch(self._on_text, "value")
            root = [self.text]
            if p.softbounds is not None and not p.allow_None:
                self.slider = self._make_slider(value)
                self.slider.param.watch(self._on_slide, "value_throttled")
                root.append(self.slider)
        self._root = pn.Column(*root, css_classes=css, sizing_mode="stretch_width", margin=0)
        if isinstance(p, param.Boolean):
            self._root = pn.Row(*root, css_classes=css, sizing_mode="stretch_width", margin=0)
        owner.param.watch(self._follow, self.name_in_owner)

    # ---- values in display units --------------------------------------------------------------
    @property
    def value(self):
        """The parameter's current value in display units (None for "automatic")."""
        si = getattr(self.owner, self.name_in_owner)
        if si is None or self.factor == 1.0 or not isinstance(si, float | int):
            return si
        return clean_number(si * self.factor)

    def _make_slider(self, value) -> pn.widgets.Widget:
        """Slider over the soft bounds (widened to the current value), in display units."""
        integer = isinstance(self.parameter, param.Integer)
        low, high = self.parameter.softbounds
        if not integer:
            low, high = clean_number(low * self.factor), clean_number(high * self.factor)
        cls = pn.widgets.IntSlider if integer else pn.widgets.FloatSlider
        step = 1 if integer else slider_step(low, high)
        return cls(
            start=min(low, value),
            end=max(high, value),
            step=step,
            value=value,
            show_value=False,
            sizing_mode="stretch_width",
            margin=(0, 18, 8, 18),
        )

    # ---- user edits -----------------------------------------------------------------------
    def enter(self, text: str) -> None:
        """Take typed text, as if entered in the text box."""
        self.text.value = text

    def slide(self, value) -> None:
        """Take a slider position (display units), as if the slider were released there."""
        with param.edit_constant(self.slider):
            self.slider.param.update(value=value, value_throttled=value)

    def _on_text(self, event: param.parameterized.Event) -> None:
        if self._following:
            return
        try:
            value = self._parse(event.new)
        except ValueError as error:
            self._refuse(str(error))
            return
        self._set(value, typed=event.new.strip())

    def _on_slide(self, event: param.parameterized.Event) -> None:
        if self._following or event.new is None:
            return
        value = event.new
        if not isinstance(self.parameter, param.Integer):
            value = round(value, step_decimals(self.slider.step))  # 56, not 55.99999999999999
        self._set(value, typed=format_value(value, self.parameter))

    def _on_choice(self, event: param.parameterized.Event) -> None:
        if not self._following:
            self._set(event.new, typed=str(event.new))

    def _parse(self, text: str):
        """Display value of typed text; an optional trailing display unit is accepted."""
        stripped = text.strip()
        if not stripped and self.parameter.allow_None:
            return None
        if self.unit and stripped.endswith(self.unit):
            stripped = stripped[: -len(self.unit)].strip()
        kind = "whole number" if isinstance(self.parameter, param.Integer) else "number"
        try:
            number = float(stripped)
        except ValueError:
            number = math.nan
        if math.isnan(number) or (kind == "whole number" and not number.is_integer()):
            unit = f" in {self.unit}" if self.unit and self.unit != "-" else ""
            raise ValueError(f"{self.path} = {text!r} is not a {kind}{unit} ({self.label})")
        return int(number) if kind == "whole number" else number

    def _set(self, value, typed: str) -> None:
        """Set the parameter from a display value; refuse it with a message in display units."""
        si = value
        # A slider may send a whole number as an int: it is still in display units.
        numeric = isinstance(value, int | float) and not isinstance(value, bool)
        if numeric and self.factor != 1.0:
            si = clean_number(value / self.factor)
        self._report(self.path, None)  # before the update: the run it starts may report
        try:
            self.owner.param.update({self.name_in_owner: si})
        except ValueError as error:
            message = str(error)
            if self.factor != 1.0:
                message = (
                    f"{self.path} = {typed} {self.unit} is outside the allowed range "
                    f"{display_range(self.path)} ({self.label})"
                )
            self._refuse(message)
            return
        self._show(self.value)

    def _refuse(self, message: str) -> None:
        """Report a refused edit and show the value still in force (slider range untouched)."""
        self._report(self.path, message)
        self._show(self.value)

    # ---- following the parameter ----------------------------------------------------------
    def _follow(self, event: param.parameterized.Event) -> None:
        self._show(self.value)

    def _show(self, value) -> None:
        """Show ``value`` (display units) without treating it as an edit."""
        self._following = True
        try:
            if self.text is None:
                self.widget.value = value
                return
            self.text.value = format_value(value, self.parameter)
            if self.slider is not None:
                self.slider.param.update(
                    start=min(self.slider.start, value), end=max(self.slider.end, value)
                )
                with param.edit_constant(self.slider):
                    self.slider.param.update(value=value, value_throttled=value)
        finally:
            self._following = False

    def __panel__(self) -> pn.viewable.Viewable:
        return self._root
