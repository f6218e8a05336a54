"""Memory and time of a run, estimated from the scenario before anything is allocated.

:func:`estimate_run` counts the large arrays of each stage exactly as the stages size them and
prices the work with a cost model fitted to the project's benchmarks:

- vehicle–track time stepping, µs per step ≈ 0.73 + 1.94e-3 N_m + 1.85e-4 N_m n_w + 0.218 n_w
  (N_m rail modes, n_w wheels): least-squares fit to the nine cases of the cost-per-step table
  of docs/vehicle_track.md (``benchmarks/bench_vehicle_track.py``), within ±15 % of each;
- irregularity synthesis, 0.36 ns per profile point and series component (six-car grid of
  55 k points × 2000 components in 0.04 s, docs/vehicle_track.md);
- soil stage, 9.2 ns per frequency × depth × (harmonics + 17): the 0.23 s of the paper's soil
  stage (5330 frequencies × 71 depths × 33 harmonics, docs/tunnel_soil.md), about half of it
  in the two K₀/K₁ evaluations per frequency and depth, which cost as much as 16 harmonics.

These figures are best-of timings on the 2-core development machine at a quiet moment; other
processes slow a run down in proportion, so the times are multiplied by
:func:`machine_load_factor`, max(1, load average / cores). ``benchmarks/bench_run_cost.py``
prints the estimate next to measured runs (docs/validity.md). The estimate is used to refuse a
run that cannot fit in memory and to warn before one that would take more than
``SLOW_RUN_SECONDS``.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

import scipy.fft

from model.params import Scenario
from model.soil.response import decimation_factor, response_tail

SLOW_RUN_SECONDS = 30.0
# Refuse a run whose arrays need more than this fraction of the memory available now.
MEMORY_FRACTION = 0.5
FALLBACK_AVAILABLE_BYTES = 4e9  # where the OS does not report available memory
STEP_SECONDS = (0.73e-6, 1.94e-9, 1.85e-10, 0.218e-6)  # 1, N_m, N_m n_w, n_w
SYNTHESIS_SECONDS = 0.36e-9  # per profile point and component
SOIL_SECONDS = 9.2e-9  # per frequency, depth and (harmonic + BESSEL_HARMONICS)
BESSEL_HARMONICS = 17
# Stress stage (model.soil.stresses.stress_response): six stress components, each with its transfer
# function and spectrum (n_freq × n_depths, complex) and its history (n_depths × n_out), the
# deviator history, and the inverse FFT's padded arrays as in the soil stage (a tracemalloc peak
# of 12 MB against 16 MB counted this way, cheap scenario with 71 depths). Its time is about
# twice the soil stage's: paper case 4.6 s against 2.35 s (2D) and 4.1 s against 1.4 s (2.5D),
# measured in one run each with other jobs on the 2-core machine.
STRESS_COMPONENTS = 6
STRESS_TIME_RATIO = 2.0
# The 2.5D stress field carries more than the 2D one: its soil stage's tracemalloc peak exceeds
# the 2D stage's by 101 B per frequency and depth (paper case: 38.9 MB at 71 depths, 109.9 MB at
# 201, 5401 frequencies, the same with 64 harmonics), counted as this many complex fields.
MOVING_LOAD_FIELDS = 7
# Reading a measured profile (model.params.measured_profile.parse_profile): tracemalloc peak of
# 136 B per line for profiles of 20 000 and 120 000 lines (text, the lists of floats, the
# arrays), rounded up. A profile file's lines are bounded by its size over the shortest line
# "0,0\n" (4 bytes), its size being all the estimate reads of it.
PROFILE_BYTES_PER_LINE = 140
SHORTEST_PROFILE_LINE = 4
FLOAT_BYTES, COMPLEX_BYTES = 8, 16


class SlowRunWarning(UserWarning):
    """A run is estimated to take longer than ``SLOW_RUN_SECONDS``."""


@dataclass(frozen=True)
class RunEstimate:
    """Estimated peak memory (bytes) and wall time (s) of each stage of one run."""

    memory_bytes: dict[str, float]
    seconds: dict[str, float]
    blame: dict[str, str]
    """Per stage, the parameters that drive its size, for messages."""

    @property
    def total_seconds(self) -> float:
        """Estimated wall time of the whole run (s)."""
        return sum(self.seconds.values())

    @property
    def peak_memory_bytes(self) -> float:
        """Peak memory of the run (bytes): the stages run one after the other, but each keeps
        its results while the next one computes, and the soil stage computes the displacements
        and the stresses together (a tracemalloc peak of 201 MB against 224 MB counted, paper
        case; ``benchmarks/bench_run_memory.py``)."""
        return sum(self.memory_bytes.values())

    def slow_message(self) -> str:
        """Warning text naming the stage and parameters that make the run slow."""
        stage = max(self.seconds, key=self.seconds.get)
        return (
            f"this run is estimated to take about {self.total_seconds:.0f} s "
            f"({stage} stage {self.seconds[stage]:.0f} s; driven by {self.blame[stage]})"
        )


def machine_load_factor() -> float:
    """Slow-down from other processes: max(1, one-minute load average / CPU count)."""
    try:
        return max(1.0, os.getloadavg()[0] / (os.cpu_count() or 1))
    except (OSError, AttributeError):
        return 1.0


def available_memory_bytes() -> float:
    """Physical memory available now (bytes), or ``FALLBACK_AVAILABLE_BYTES``."""
    try:
        return float(os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        return FALLBACK_AVAILABLE_BYTES


def estimate_run(scenario: Scenario, available_bytes: float | None = None) -> RunEstimate:
    """Memory and time of each stage of ``run(scenario)``, refusing what cannot fit.

    Parameters
    ----------
    scenario : Scenario
        Inputs, individually within their bounds (cross-parameter rules need not hold yet).
    available_bytes : float, optional
        Memory available (bytes); default: what the OS reports now.

    Returns
    -------
    RunEstimate

    Raises
    ------
    ValueError
        If a stage needs more than ``MEMORY_FRACTION`` of the available memory; the message
        names the stage, the size and the parameters to change.
    """
    train, numerics = scenario.train, scenario.numerics
    modes, wheels = scenario.rail_modes, train.n_wheels
    n_steps = math.ceil(scenario.passage_duration / numerics.dt)
    n_channels = 3 + 2 * wheels + (1 if train.single_bogie else train.n_cars)
    travel = scenario.passage_duration * train.speed + train.axle_span
    eta_step = min(0.005, scenario.irregularity.wavelength_min / 100.0)
    n_profile = math.ceil(travel / eta_step)
    synthesis = 0.0
    if scenario.irregularity.enabled and not scenario.irregularity.profile_csv:
        synthesis = SYNTHESIS_SECONDS * n_profile * scenario.irregularity.n_components
    c0, c_modes, c_coupling, c_wheels = STEP_SECONDS
    step_seconds = c0 + c_modes * modes + c_coupling * modes * wheels + c_wheels * wheels
    vt_memory = PROFILE_BYTES_PER_LINE * measured_profile_lines(scenario.irregularity) + (
        FLOAT_BYTES
        * (
            (n_steps + 1) * (n_channels + 2)  # outputs, time and Winkler reference
            + n_profile
            + 4 * modes * wheels  # scratch and mode shapes at the wheels
            + 12 * modes
        )
    )

    n_record = n_steps + 1
    step = decimation_factor(numerics.dt, numerics.soil_max_frequency)
    n_out_pad = scipy.fft.next_fast_len(
        math.ceil(numerics.zero_pad_factor * n_record / step), real=True
    )
    n_pad = step * n_out_pad
    n_freq = min(
        math.floor(numerics.soil_max_frequency * n_pad * numerics.dt) + 1, n_out_pad // 2 + 1
    )
    depths = numerics.n_depths
    soil_memory = (
        (FLOAT_BYTES + COMPLEX_BYTES) * n_pad  # padded load and its transform
        + 3 * COMPLEX_BYTES * n_freq * depths  # receptance and kernel fields
        + (COMPLEX_BYTES + 2 * FLOAT_BYTES) * depths * n_out_pad  # spectra and histories
    )
    dt_out = step * numerics.dt
    tail = response_tail(numerics.max_depth, scenario.soil.s_wave_speed)
    n_out = min(n_out_pad, math.ceil((n_record * numerics.dt + tail) / dt_out))
    fields = 2 * STRESS_COMPONENTS + MOVING_LOAD_FIELDS * (scenario.tunnel.model == "2.5d")
    stress_memory = (
        fields * COMPLEX_BYTES * n_freq * depths  # transfers and spectra
        + (STRESS_COMPONENTS + 1) * FLOAT_BYTES * depths * n_out  # histories and deviator
        + (COMPLEX_BYTES / 2 + FLOAT_BYTES) * depths * n_out_pad  # one inverse FFT
    )
    soil_seconds = SOIL_SECONDS * n_freq * depths * (numerics.n_harmonics + BESSEL_HARMONICS)
    load = machine_load_factor()
    estimate = RunEstimate(
        memory_bytes={"vehicle_track": vt_memory, "soil": soil_memory, "stress": stress_memory},
        seconds={
            "vehicle_track": load * (n_steps * step_seconds + synthesis),
            "soil": load * soil_seconds,
            "stress": load * STRESS_TIME_RATIO * soil_seconds,
        },
        blame={
            "vehicle_track": (
                f"{n_steps} time steps (numerics.dt, train.speed_kmh, "
                f"numerics.approach_distance) × {modes} rail modes (numerics.n_rail_modes, "
                f"track.block_spacing, numerics.rail_end_margin) × {wheels} wheels"
                + (
                    f"; profile {n_profile} points × {scenario.irregularity.n_components} "
                    "components (irregularity.n_components, irregularity.wavelength_min)"
                    if synthesis
                    else ""
                )
            ),
            "soil": (
                f"{n_freq} frequencies (numerics.soil_max_frequency, numerics.zero_pad_factor) "
                f"× {depths} depths (numerics.n_depths) × {numerics.n_harmonics} harmonics "
                f"(numerics.n_harmonics), FFT of {n_pad} samples"
            ),
            "stress": (
                f"{STRESS_COMPONENTS} stress components × {n_freq} frequencies "
                f"(numerics.soil_max_frequency, numerics.zero_pad_factor) × {depths} depths "
                f"(numerics.n_depths) × {numerics.n_harmonics} harmonics (numerics.n_harmonics)"
            ),
        },
    )
    limit = MEMORY_FRACTION * (
        available_memory_bytes() if available_bytes is None else available_bytes
    )
    needed = 0.0
    for stage, bytes_ in estimate.memory_bytes.items():
        needed += bytes_  # a stage's arrays come on top of the results before it
        if needed > limit:
            raise ValueError(
                f"the {stage} stage would need about {needed / 1e9:.3g} GB with the results "
                f"before it, more than the {limit / 1e9:.3g} GB allowed "
                f"({MEMORY_FRACTION:.0%} of the memory available): "
                f"{estimate.blame[stage]}; reduce one of these"
            )
    return estimate


def measured_profile_lines(irregularity) -> int:
    """Lines of the measured profile (0 without one): counted in its text, or bounded by its
    file's size (the file is not read)."""
    if irregularity.profile_data is not None:
        data = irregularity.profile_data
        return data.count("\n" if isinstance(data, str) else b"\n") + 1
    if irregularity.profile_csv:
        try:
            return os.stat(irregularity.profile_csv).st_size // SHORTEST_PROFILE_LINE + 1
        except OSError:  # the run says why it cannot read it
            return 0
    return 0
