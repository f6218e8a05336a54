"""One control per model parameter, built from its declaration in :mod:`model.params`.

A control shows and takes its parameter in the parameter's display unit
(:func:`model.params.display_unit`: MPa, MN/m, GPa, …) while the parameter itself stays SI. It
is bound to the parameter object both ways: it follows every change of the parameter (preset,
loaded file, train type) and sets the parameter when the user edits it. Typed text is read by
:func:`dashboard.typed_values.parse_typed` (a decimal comma, a unit of the same kind:
``6000 kPa`` in a box shown in MPa). A refused edit (text that is not a number, a value outside
the hard bounds) changes nothing — not the parameter, not the slider's range: its message is
shown beside the field, which keeps the typed text to correct, and goes to the ``report``
callback; :meth:`ParameterControl.clear_refusal` puts the value in force back.

Why not ``pn.widgets.X.from_param`` / ``pn.Param``: those bind a widget to the SI value (no unit
conversion), and a refused value raises inside the watcher (server log, nothing in the page).
"""

from __future__ import annotations

import html
import math
from collections.abc import Callable

import panel as pn
import param

from dashboard.typed_values import parse_typed
from model.params import display_label, display_range, display_unit, parameter_of

SLIDER_POSITIONS = 200
"""A slider's step gives at least this many positions over the parameter's soft bounds."""

SIGNIFICANT_DIGITS = 12
"""Unit conversions are rounded to this many digits: 6.1 MPa is 6 100 000 Pa, not …99.999."""

Report = Callable[[str, "str | None"], None]
"""``report(path, message)``: a refused edit's message, or None once the parameter accepted one."""

REFUSAL_STYLES = {
    "color": "#82071e",
    "background": "#ffebe9",
    "border": "1px solid #ff818266",
    "border-radius": "6px",
    "padding": "2px 8px",
    "font-size": "12px",
}
"""The message of a refused edit, right under its field."""


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
        self.refusal = pn.pane.HTML(
            "",
            visible=False,
            styles=REFUSAL_STYLES,
            margin=(2, 10, 6, 10),
            sizing_mode="stretch_width",
            css_classes=["param-refusal"],
        )
        """The message of a refused edit, beside the field (hidden while there is none)."""
        if isinstance(p, param.Boolean):
            root = [pn.Row(*root, sizing_mode="stretch_width", margin=0)]
        self._root = pn.Column(
            *root, self.refusal, css_classes=css, sizing_mode="stretch_width", margin=0
        )
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
        """Display value of typed text (:func:`~dashboard.typed_values.parse_typed`)."""
        stripped = text.strip()
        if not stripped and self.parameter.allow_None:
            return None
        whole = isinstance(self.parameter, param.Integer)
        try:
            number = parse_typed(stripped, self.unit)
            if whole and not number.is_integer():
                raise ValueError("is not a whole number")
        except ValueError as error:
            raise ValueError(f"{self.path} = {text.strip()!r} {error}") from None
        return int(number) if whole else number

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
            if not numeric:  # a choice or a switch: the parameter's own reason
                self._refuse(str(error))
                return
            shown = self._with_unit(format_value(value, self.parameter))
            as_typed = (
                "" if typed in (shown, format_value(value, self.parameter)) else f" ({typed})"
            )
            self._refuse(
                f"{self.path} = {shown}{as_typed} is outside the allowed range "
                f"{display_range(self.path)}"
            )
            return
        self._show(self.value)

    def _refuse(self, message: str) -> None:
        """Show a refused edit's message beside the field, which keeps the typed text; the
        parameter and the slider keep the value in force."""
        in_force = (
            "automatic"
            if self.value is None
            else self._with_unit(format_value(self.value, self.parameter))
        )
        self.refusal.param.update(object=html.escape(f"{message}; still {in_force}"), visible=True)
        self._report(self.path, message)

    def _with_unit(self, text: str) -> str:
        """``text`` followed by the display unit (none for plain numbers)."""
        return f"{text} {self.unit}" if self.unit and self.unit != "-" else text

    @property
    def refused(self) -> bool:
        """True while the field shows a refused edit."""
        return self.refusal.visible

    def clear_refusal(self) -> None:
        """Hide the message of a refused edit and show the value in force again."""
        if self.refusal.visible:
            self.refusal.param.update(object="", visible=False)
            self._show(self.value)

    # ---- following the parameter ----------------------------------------------------------
    def _follow(self, event: param.parameterized.Event) -> None:
        self.refusal.param.update(object="", visible=False)  # a new value in force
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
