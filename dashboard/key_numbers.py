"""A run's key numbers and the soil's derived quantities, in the units a reader expects.

Shown above the dashboard's plots and in the report (:func:`~dashboard.report.items_html`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dashboard.parsed import summary_of
from dashboard.plots import KN, MM
from model.params import Soil
from model.pipeline import Results


@dataclass(frozen=True)
class SummaryItem:
    """One key number: a stable key, a label, the value in display units and the unit."""

    key: str
    label: str
    value: float
    unit: str

    @property
    def text(self) -> str:
        """Value with three significant digits and its unit."""
        return f"{significant(self.value)} {self.unit}"


def significant(value: float, digits: int = 3) -> str:
    """``value`` to ``digits`` significant digits, trailing zeros kept (0.497, 7.90, 19.9),
    whole numbers of more digits in full (1234), never in exponent form below 1e6."""
    if not np.isfinite(value) or value == 0 or abs(value) >= 1e6 or abs(value) < 1e-4:
        return f"{value:.{digits}g}"
    if abs(value) >= 10 ** (digits - 1):
        return f"{value:.0f}"
    return f"{value:#.{digits}g}"


def summary_items(results: Results) -> list[SummaryItem]:
    """Key numbers of a run in display units, from :meth:`Results.summary`."""
    s = summary_of(results)
    deepest = s["deepest_depth_m"]
    return [
        SummaryItem(
            "peak_invert_force", "Peak invert load (one block)", s["peak_invert_force_N"] * KN, "kN"
        ),
        SummaryItem(
            "peak_line_load",
            "Peak line load on the section",
            s["peak_line_load_N_per_m"] * KN,
            "kN/m",
        ),
        SummaryItem(
            "peak_block_disp", "Peak sleeper displacement", s["peak_block_disp_m"] * MM, "mm"
        ),
        SummaryItem(
            "peak_disp_invert",
            "Peak dynamic displacement at the invert",
            s["peak_disp_invert_m"] * MM,
            "mm",
        ),
        SummaryItem("peak_disp_11m", "… 11 m below the invert", s["peak_disp_11m_m"] * MM, "mm"),
        SummaryItem(
            "peak_disp_deepest",
            f"… {deepest:g} m below the invert",
            s["peak_disp_deepest_m"] * MM,
            "mm",
        ),
        SummaryItem(
            "min_wheel_force", "Lowest wheel–rail force", s["min_wheel_force_N"] * KN, "kN"
        ),
    ]


def soil_items(soil: Soil) -> list[SummaryItem]:
    """Derived soil quantities c1, c2, λ, μ of a soil, in display units (m/s, MPa)."""
    return [
        SummaryItem("soil_p_wave_speed", "P-wave speed c1", soil.p_wave_speed, "m/s"),
        SummaryItem("soil_s_wave_speed", "S-wave speed c2", soil.s_wave_speed, "m/s"),
        SummaryItem("soil_lame_lambda", "Lamé λ", soil.lame_lambda * 1e-6, "MPa"),
        SummaryItem("soil_shear_modulus", "Shear modulus μ", soil.shear_modulus * 1e-6, "MPa"),
    ]
