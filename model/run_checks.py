"""What a run refuses and what it warns about beyond each stage's own checks: the padded
record's length (before any computation), inputs where the model's simplifications start to
matter, and results that break the elastic model's invariants (docs/validity.md).

:func:`model.pipeline.run` calls them; they compute nothing of the run themselves.
"""

from __future__ import annotations

import math

import numpy as np

from model.params import Scenario, ScenarioError
from model.soil.response import SoilResponse, response_tail

# invariant_warnings: growth of the peak with depth tolerated, relative to the invert peak (the
# FFT's rounding and the tail's truncation leave ripples orders of magnitude below this).
INVARIANT_TOLERANCE = 1e-6


def check_record_padding(scenario: Scenario) -> None:
    """Refuse a padded record too short for the response at the deepest output depth.

    The soil stage's inverse FFT is periodic: a padded record shorter than the passage plus
    the wave-travel tail to ``numerics.max_depth`` (``model.soil.response.response_tail``) wraps
    the deep response onto itself, which lowers the deep peaks (e.g. by half at 35 m for a soft
    soil at 400 km/h) and can make them grow with depth.

    Raises
    ------
    ScenarioError
        Naming numerics.zero_pad_factor and the smallest value that suffices.
    """
    numerics, record = scenario.numerics, scenario.passage_duration
    needed = record + response_tail(numerics.max_depth, scenario.soil.s_wave_speed)
    if numerics.zero_pad_factor * record < needed:
        raise ScenarioError(
            f"numerics.zero_pad_factor = {numerics.zero_pad_factor} pads the {record:.2f} s "
            f"record to less than the passage plus the wave-travel tail to "
            f"numerics.max_depth = {numerics.max_depth:g} m ({needed:.2f} s), which would "
            f"wrap the deep response; allowed: at least {math.ceil(needed / record)} (or a "
            "smaller max_depth)"
        )


def scenario_warnings(scenario: Scenario) -> list[str]:
    """Warnings for inputs where the model's simplifications start to matter (not errors)."""
    warnings = []
    speed, shear_speed = scenario.train.speed, scenario.soil.s_wave_speed
    ratio = f"train speed {speed:.1f} m/s is {speed / shear_speed:.0%} of the soil shear-wave "
    if scenario.tunnel.model == "2.5d" and speed >= shear_speed:
        warnings.append(
            ratio + f"speed {shear_speed:.1f} m/s: the load outruns the shear waves (Mach "
            "cone), the response changes character, radiating energy behind the train and "
            "extending far from the tunnel; computed, but outside the usual metro range"
        )
    elif speed > 0.7 * shear_speed:
        warnings.append(
            ratio
            + f"speed {shear_speed:.1f} m/s: moving-load effects become important; "
            + (
                "the 2.5D model includes them and the response grows as the speed approaches "
                "the shear-wave speed"
                if scenario.tunnel.model == "2.5d"
                else "the 2D plane-strain tunnel model ignores them (use tunnel.model = '2.5d')"
            )
        )
    numerics, beta = scenario.numerics, scenario.track.winkler_beta
    if numerics.approach_distance * beta < 4.0:
        warnings.append(
            f"numerics.approach_distance = {numerics.approach_distance:g} m is shorter than "
            f"4/β = {4.0 / beta:.1f} m: the record starts and ends with the block still "
            "loaded, which cuts the load history and lowers the soil response"
        )
    record = scenario.passage_duration
    segment = numerics.psd_segment
    if record < segment:
        warnings.append(
            f"the passage lasts {record:.2f} s, less than numerics.psd_segment = {segment:g} s: "
            f"the PSDs use the whole record, a frequency resolution of {1 / record:.2f} Hz"
        )
    return warnings


def invariant_warnings(soil: SoilResponse) -> list[str]:
    """Flags for results that break the elastic model's invariants (docs/model.md §8).

    Under a downward load the peak downward displacement is positive and does not grow with
    depth; a violation beyond ``INVARIANT_TOLERANCE`` of the invert peak means the inputs are
    outside what the model represents.
    """
    peak, depth = soil.peak_disp_m, soil.depth_m
    problems = []
    if not peak[0] > 0.0:
        problems.append(f"the peak downward displacement at the invert is {peak[0]:.3g} m, not > 0")
    rise = np.diff(peak) > INVARIANT_TOLERANCE * abs(peak[0])
    if np.any(rise):
        k = int(np.argmax(rise))
        problems.append(
            f"the peak downward displacement grows with depth from {depth[k]:g} m to "
            f"{depth[k + 1]:g} m ({peak[k]:.4g} → {peak[k + 1]:.4g} m)"
        )
    return [
        f"{problem}: the elastic model's assumptions are broken; check soil.youngs_modulus, "
        "soil.shear_loss_factor and numerics.zero_pad_factor"
        for problem in problems
    ]
