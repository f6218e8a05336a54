"""Nonlinear vehicle–track model: the excitation model of the paper (§2, §4.1; docs/model.md §1–6).

Vehicle (one-rail half model): the paper's single bogie (half car body in bounce, bogie bounce
and pitch, two wheelsets) or a train of independent 10-DOF cars. Track: simply supported modal
Euler rail on identical, uniformly spaced blocks (fastener K_r, C_r; block mass M_s; block pad
K_s, C_s onto the rigid invert). Hertz contact with loss of contact, rail irregularity from
:func:`model.track.irregularity.profile_for`, Zhai's explicit integrator (φ = ψ = ½) from static
equilibrium. Equations, the fast formulation and measured figures: ``docs/vehicle_track.md``.

:func:`simulate` runs a passage: it checks the inputs (:func:`check_inputs`, with the explicit
stability limit :func:`stable_time_step`), builds the kernel records and the static start with
:mod:`model.track.assembly`, and steps Zhai's scheme with the kernels of
:mod:`model.track.kernels` (:func:`integrate`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from model.params import Scenario
from model.track import kernels
from model.track.assembly import (
    ContactLog,
    Outputs,
    Scratch,
    SystemState,
    TrackSystem,
    VehicleSystem,
    WheelInputs,
    assemble_track,
    assemble_vehicle,
    assemble_wheels,
    static_equilibrium,
    static_wheel_loads,
    wheel_start_positions,
)

__all__ = [
    "simulate",
    "check_inputs",
    "stable_time_step",
    "zhai_damped_limit",
    "winkler_block_displacement",
    "n_time_steps",
    "integrate",
    "Integration",
    "VehicleTrackResult",
    "CONTACT_EVENT_DTYPE",
    "ZHAI_PHI",
    "ZHAI_PSI",
]

ZHAI_PHI = 0.5
ZHAI_PSI = 0.5
# stable_time_step: Hertz stiffness linearised at this multiple of the static wheel load (the
# dynamic load rarely exceeds it), and this factor on the resulting limit.
HERTZ_OVERLOAD = 2.0
STABILITY_SAFETY = 0.9
# A wheel–rail compression beyond this (m) means the integration has diverged: the static
# compression is ~0.08 mm and 10 mm would take 80 MN. (A gap of any size is a wheel in flight,
# which the model follows and reports as loss of contact.)
DIVERGENCE_COMPRESSION = 0.01
MAX_OUTPUT_VALUES = 50_000_000  # 400 MB of float64 output
MAX_CONTACT_EVENTS = 10_000
PROGRESS_CALLS = 40
# winkler_block_displacement: β|ξ| beyond which a wheel's deflection, e^{−β|ξ|}(cos + sin), is
# below 1e-17 of its peak (round-off of the sum)
WINKLER_REACH = 40.0

CONTACT_EVENT_DTYPE = np.dtype(
    [("wheel", np.int64), ("t_s", float), ("x_m", float), ("duration_s", float)]
)


@dataclass(frozen=True)
class VehicleTrackResult:
    """Time histories of one passage (SI; displacements down +, from the unloaded track).

    Arrays over time have ``nt`` samples at ``t_s``; wheels are ordered from the leading axle.
    """

    t_s: np.ndarray
    block_force_N: np.ndarray  # K_s Z_s + C_s Ż_s under the monitored block, static part included
    block_disp_m: np.ndarray  # monitored block
    rail_disp_m: np.ndarray  # rail above the monitored block
    wheel_force_N: np.ndarray  # (n_wheels, nt) wheel–rail contact forces
    wheel_acc_m_s2: np.ndarray  # (n_wheels, nt) wheelset accelerations
    car_body_acc_m_s2: np.ndarray  # (n_bodies, nt) car-body bounce accelerations
    axle_pass_times_s: np.ndarray  # (n_wheels,) when each axle is over the monitored block
    winkler_block_disp_m: np.ndarray  # quasi-static Winkler beam (BOEF), static wheel loads
    monitored_block_x_m: float
    contact_loss: np.ndarray  # CONTACT_EVENT_DTYPE records: wheel, t_s, x_m, duration_s
    unstable: bool
    warnings: tuple[str, ...] = ()  # a tuple: the stage cache shares this result
    static_wheel_load_N: float = 0.0
    dt_s: float = 0.0
    stable_dt_s: float = 0.0
    n_rail_modes: int = 0
    rail_length_m: float = 0.0
    speed_m_s: float = 0.0


@dataclass(frozen=True)
class Integration:
    """Result of :func:`integrate`: the recorded outputs and how the run ended."""

    outputs: Outputs
    diverged: int | None  # output index where the response diverged, None if it did not
    events: np.ndarray  # (n, 4) logged contact-loss rows, open ones closed at the end
    n_events: int  # all contact-loss events, including those past the log's capacity


# ---- time stepping -------------------------------------------------------------------------------
def integrate(
    track: TrackSystem,
    vehicle: VehicleSystem,
    wheels: WheelInputs,
    state: SystemState,
    n_steps: int,
    dt: float,
    progress: Callable[[float], None] | None = None,
) -> Integration:
    """Run the kernel for ``n_steps`` from ``state`` (modified in place).

    The accelerations at t = 0 are evaluated first (``n_steps = 0`` does only that). The kernel
    then runs in at most ``PROGRESS_CALLS`` chunks so ``progress`` can be told the fraction
    done.

    Parameters
    ----------
    track, vehicle, wheels : TrackSystem, VehicleSystem, WheelInputs
    state : SystemState
        Initial state, e.g. from :func:`static_equilibrium`; holds the final state on return.
    n_steps : int
        Time steps of Zhai's method (φ = ψ = ½).
    dt : float
        Time step (s).
    progress : callable(fraction), optional

    Returns
    -------
    Integration
        Outputs at n_steps + 1 instants (index 0 = initial state) and how the run ended.
    """
    n_wheels = wheels.x0.size
    n_modes, n_block_modes = track.omega2.size, track.n_spacings - 1
    nt = n_steps + 1
    # The histories of many channels are stored time-major (the transposed views keep the
    # (channel, time) shape): a step writes one contiguous row, not one value per channel
    # rows a megabyte apart, each on its own memory page.
    outputs = Outputs(
        block_force=np.zeros(nt),
        block_disp=np.zeros(nt),
        rail_disp=np.zeros(nt),
        wheel_force=np.zeros((nt, n_wheels)).T,
        wheel_acc=np.zeros((nt, n_wheels)).T,
        body_acc=np.zeros((nt, vehicle.inv_mass.shape[0])).T,
    )
    offset = track.wavenumber_unit * (wheels.x0 - wheels.x0[0])
    scratch = Scratch(
        modal_load=np.empty(n_modes),
        offset_cos=np.cos(offset),
        offset_sin=np.sin(offset),
        two_cos=np.empty(n_wheels),
        wheel_first=np.empty(n_wheels),
        wheel_prev=np.empty(n_wheels),
        wheel_cur=np.empty(n_wheels),
        rail_at_wheel=np.empty(n_wheels),
        fold_disp=np.zeros(n_block_modes),
        fold_vel=np.zeros(n_block_modes),
        wheel_x=np.empty(n_wheels),
        compression=np.empty(n_wheels),
        wheel_force=np.empty(n_wheels),
        monitored=np.empty(3),
    )
    contact = ContactLog(  # a wheel off the rail at t = 0 opens an event there
        in_contact=np.ones(n_wheels, dtype=bool),
        open_event=np.full(n_wheels, -1, dtype=np.int64),
        events=np.zeros((MAX_CONTACT_EVENTS, 4)),
        event_count=np.zeros(1, dtype=np.int64),
    )
    diverged = None
    chunk = max(1, math.ceil(nt / PROGRESS_CALLS))
    for start in range(0, nt, chunk):
        stop = min(start + chunk, nt)
        status = kernels.advance(
            start,
            stop,
            n_steps,
            dt,
            ZHAI_PHI,
            ZHAI_PSI,
            DIVERGENCE_COMPRESSION,
            state,
            track,
            vehicle,
            wheels,
            scratch,
            outputs,
            contact,
        )
        if status != kernels.RUNNING:
            diverged = int(status)
            break
        if not all(np.all(np.isfinite(a)) for a in (state.q, state.s, state.u)):
            diverged = stop  # a mode the outputs do not see has blown up
            break
        if progress is not None:
            progress(stop / nt)
    n_events = int(contact.event_count[0])
    events = contact.events[: min(n_events, MAX_CONTACT_EVENTS)]
    still_open = events[:, 3] < 0.0
    events[still_open, 3] = (diverged if diverged is not None else n_steps) * dt
    return Integration(outputs=outputs, diverged=diverged, events=events, n_events=n_events)


# ---- public API -----------------------------------------------------------------------------
def zhai_damped_limit(omega: float, gamma: float) -> float:
    """Largest stable Δt of Zhai's method (φ = ψ = ½) for ẍ + γẋ + ω²x = 0 (s).

    Δt_max = 2/(γ + √(ω² + γ²)), i.e. ωΔt < 2(√(1 + 4ζ²) − 2ζ) with γ = 2ζω: 2/ω undamped,
    1/γ without stiffness. Stable for every Δt below it, unstable above (verified against the
    amplification matrix in the tests). Decreasing in both ω and γ.
    """
    return 2.0 / (gamma + math.sqrt(omega * omega + gamma * gamma))


def _largest_eigenvalue_2x2(a: float, b: float, d: float) -> float:
    """Largest eigenvalue of the symmetric matrix [[a, b], [b, d]]."""
    return 0.5 * (a + d) + math.hypot(0.5 * (a - d), b)


def stable_time_step(scenario: Scenario) -> float:
    """Explicit stability limit of the linearised model, with a safety factor (s).

    Every eigenvalue z of Zhai's scheme for M ẍ + C ẋ + K x = 0 (symmetric, M > 0) solves the
    scalar scheme for ẍ + γẋ + ω²x = 0 with the Rayleigh quotients γ = x*Cx/x*Mx ≤ γ_max and
    ω² = x*Kx/x*Mx ≤ ω²_max of its eigenvector. :func:`zhai_damped_limit` decreases in both, so
    Δt ≤ zhai_damped_limit(ω_max, γ_max) is stable. Upper bounds (Weyl's inequality, all in
    mass-normalised coordinates):

    - ω²_max ≤ max(track, vehicle) + Hertz. Track: highest rail mode (EI/m_r)(N_m π/L)⁴ plus
      the largest eigenvalue of the fastener/pad coupling of one block mode with the n_f rail
      modes folded onto it, [[n_f K_r b², −√n_f K_r b/√M_s], [·, (K_r + K_s)/M_s]],
      b = 1/√(m_r L_s). Vehicle: exact, per car. Hertz: k_H times the largest eigenvalue of the
      Gram matrix of the wheels' contact vectors (Σ_k Y_k(x_i) Y_k(x_j) + δ_ij/m_w).
    - γ_max ≤ max(track coupling with C_r, C_s; vehicle), likewise.

    k_H = (3/2) p^{1/3}/G is linearised at ``HERTZ_OVERLOAD`` (2) times the static wheel load;
    the result is multiplied by ``STABILITY_SAFETY`` (0.9) for harder contact and the motion of
    the wheels.

    Parameters
    ----------
    scenario : Scenario

    Returns
    -------
    float
        Largest recommended Δt (s).
    """
    track = scenario.track
    system = assemble_track(scenario)
    vehicle = assemble_vehicle(scenario)
    shared = np.bincount(system.fold_index[system.fold_index >= 0]).max(initial=1)
    gain = math.sqrt(shared) * system.block_gain

    def track_coupling(fastener, pad):
        return _largest_eigenvalue_2x2(
            fastener * gain**2,
            -fastener * gain / math.sqrt(track.block_mass),
            (fastener + pad) / track.block_mass,
        )

    scale = np.sqrt(vehicle.inv_mass[0])
    vehicle_k = np.linalg.eigvalsh(scale[:, None] * vehicle.stiffness[0] * scale).max()
    vehicle_c = np.linalg.eigvalsh(scale[:, None] * vehicle.damping[0] * scale).max()
    load = HERTZ_OVERLOAD * scenario.vehicle.static_wheel_load
    k_hertz = 1.5 * load ** (1.0 / 3.0) / track.hertz_constant
    shapes = system.mode_shapes(wheel_start_positions(scenario))
    wheel_inv_mass = vehicle.inv_mass[:, vehicle.wheel_dof[0]].ravel()
    gram = shapes.T @ shapes + np.diag(wheel_inv_mass)
    omega2 = (
        max(
            system.omega2[-1] + track_coupling(track.fastener_stiffness, track.pad_stiffness),
            vehicle_k,
        )
        + k_hertz * np.linalg.eigvalsh(gram).max()
    )
    gamma = max(track_coupling(track.fastener_damping, track.pad_damping), vehicle_c)
    return STABILITY_SAFETY * zhai_damped_limit(math.sqrt(omega2), gamma)


def _stiffest_part(scenario: Scenario) -> str:
    """The part of the model with the highest rate (ω, or damping γ), naming its parameters."""
    track, vehicle = scenario.track, assemble_vehicle(scenario)
    scale = np.sqrt(vehicle.inv_mass[0])
    wheel_mass = 0.5 * scenario.vehicle.wheelset_mass
    hertz = 1.5 * (HERTZ_OVERLOAD * scenario.vehicle.static_wheel_load) ** (1.0 / 3.0)
    rates_squared = {
        f"the highest of {scenario.rail_modes} rail modes (numerics.n_rail_modes, track.rail_E, "
        "track.rail_I, track.rail_mass)": assemble_track(scenario).omega2[-1],
        "the block on its fastener and pad (track.fastener_stiffness, track.pad_stiffness, "
        "track.block_mass)": (track.fastener_stiffness + track.pad_stiffness) / track.block_mass,
        "the block's damping (track.fastener_damping, track.pad_damping, track.block_mass)": (
            (track.fastener_damping + track.pad_damping) / track.block_mass
        )
        ** 2,
        "the vehicle's suspension (vehicle.*_stiffness, vehicle.*_mass)": np.linalg.eigvalsh(
            scale[:, None] * vehicle.stiffness[0] * scale
        ).max(),
        "the vehicle's dampers (vehicle.*_damping, vehicle.*_mass)": np.linalg.eigvalsh(
            scale[:, None] * vehicle.damping[0] * scale
        ).max()
        ** 2,
        "the wheel–rail contact (vehicle.wheelset_mass, track.wheel_radius)": hertz
        / track.hertz_constant
        / wheel_mass,
    }
    part = max(rates_squared, key=rates_squared.get)
    return f"{part}, rate ≈ {math.sqrt(rates_squared[part]):.4g} 1/s"


def n_time_steps(scenario: Scenario) -> int:
    """Time steps covering the passage at ``numerics.dt``.

    A ratio passage_duration/Δt within rounding (1e-6) of a whole number is that number,
    otherwise it is rounded up.

    Parameters
    ----------
    scenario : Scenario

    Returns
    -------
    int
    """
    ratio = scenario.passage_duration / scenario.numerics.dt
    nearest = round(ratio)
    return nearest if abs(ratio - nearest) < 1e-6 * max(1.0, ratio) else math.ceil(ratio)


def check_inputs(scenario: Scenario) -> float:
    """Refuse inputs the simulation cannot handle, before any computation.

    Calls ``scenario.validate()`` (which also refuses too few rail modes, N_m < L/(2L_s)), then
    checks the time step against :func:`stable_time_step` and the size of the output. Speed and
    rail end margin need no check here: their parameter bounds refuse a zero speed and a margin
    under 20 m, and ``Scenario.rail_length`` honours the margin by construction.

    Returns
    -------
    float
        The stability limit :func:`stable_time_step` (s), so callers need not compute it again.

    Raises
    ------
    ValueError
        With a message naming the parameter, its value and the allowed range.
    """
    scenario.validate()
    numerics, train = scenario.numerics, scenario.train
    limit = stable_time_step(scenario)
    if numerics.dt > limit:
        raise ValueError(
            f"numerics.dt = {numerics.dt:g} s is above the explicit stability limit of this "
            f"scenario, set by {_stiffest_part(scenario)}; allowed range (0, {limit:.4g}] s: "
            "lower the time step or change the parameters of that part"
        )
    n_channels = 3 + 2 * train.n_wheels + (1 if train.single_bogie else train.n_cars)
    n_values = (n_time_steps(scenario) + 1) * n_channels
    if n_values > MAX_OUTPUT_VALUES:
        raise ValueError(
            f"numerics.dt = {numerics.dt:g} s gives {n_time_steps(scenario)} time steps for a "
            f"{scenario.passage_duration:.3g} s passage, {n_values:.3g} output values in all; "
            f"allowed up to {MAX_OUTPUT_VALUES:.3g}: raise the time step or the speed"
        )
    return limit


def winkler_block_displacement(scenario: Scenario, t_s: np.ndarray) -> np.ndarray:
    """Quasi-static block displacement on a Winkler beam (BOEF) under the passing train (m).

    Zimmermann: w(ξ) = (Pβ/2k) e^{−β|ξ|}(cos β|ξ| + sin β|ξ|) per static wheel load P,
    k = K_r K_s/((K_r + K_s) L_s), superposed over the wheels at their positions at ``t_s``; the
    block, in series under the fastener, moves K_r/(K_r + K_s) = k L_s/K_s of the rail deflection.

    Each wheel is summed over β|ξ| < ``WINKLER_REACH`` only, where the deflection exceeds
    e^{−40} of its peak, by :func:`model.track.kernels.winkler_shape_sum`.

    Parameters
    ----------
    scenario : Scenario
    t_s : ndarray
        Uniformly spaced increasing times (s) from the start of the passage, 1-D.

    Returns
    -------
    ndarray
        Block displacement (m, down +), same shape as ``t_s``.

    Raises
    ------
    ValueError
        If ``t_s`` is not uniformly spaced.
    """
    track, train = scenario.track, scenario.train
    beta, modulus = track.winkler_beta, track.winkler_modulus
    t = np.asarray(t_s, dtype=float)
    step = float(t[1] - t[0]) if t.size > 1 else 1.0
    if t.size > 2 and np.max(np.abs(np.diff(t) - step)) > 1e-9 * abs(step):
        raise ValueError("t_s must be uniformly spaced (the passage's output times)")
    pass_times = (0.5 * scenario.rail_length - wheel_start_positions(scenario)) / train.speed
    rail = kernels.winkler_shape_sum(
        float(t[0]) if t.size else 0.0, step, t.size, pass_times, beta * train.speed, WINKLER_REACH
    )
    rail *= scenario.vehicle.static_wheel_load * beta / (2.0 * modulus)
    return rail * track.support_stiffness / track.pad_stiffness  # Z_s = F/K_s, F = k L_s w


def simulate(
    scenario: Scenario, progress: Callable[[float], None] | None = None
) -> VehicleTrackResult:
    """Passage of the train (or single bogie) over the monitored block at mid-rail.

    The leading axle starts ``numerics.approach_distance`` before the monitored block and the
    run ends when the trailing axle is the same distance past it (``scenario.passage_duration``),
    from static equilibrium, at ``numerics.dt``.

    If the response diverges (it should not once :func:`check_inputs` has passed), the run
    stops there: the result is flagged ``unstable``, its arrays end at the last valid sample and
    ``warnings`` says why. Callers must check ``unstable`` before using the record.

    Parameters
    ----------
    scenario : Scenario
        All inputs; checked by :func:`check_inputs` first.
    progress : callable(fraction), optional
        Called with the fraction done (0–1) about 40 times.

    Returns
    -------
    VehicleTrackResult

    Raises
    ------
    ValueError
        From :func:`check_inputs`.
    """
    stable_dt = check_inputs(scenario)
    dt = scenario.numerics.dt
    n_steps = n_time_steps(scenario)
    track, vehicle = assemble_track(scenario), assemble_vehicle(scenario)
    wheels = assemble_wheels(scenario, n_steps * dt)
    state = static_equilibrium(scenario, track, vehicle, wheels)
    run = integrate(track, vehicle, wheels, state, n_steps, dt, progress)
    nt = n_steps + 1 if run.diverged is None else run.diverged
    t = dt * np.arange(nt)
    offsets = np.asarray(scenario.train.axle_offsets, dtype=float)
    warnings = []
    if run.diverged is not None:
        warnings.append(_divergence_message(scenario, nt * dt, stable_dt))
    events = _contact_events(run.events)
    if run.n_events:
        warnings.append(_contact_loss_message(events, run.n_events))
    return VehicleTrackResult(
        t_s=t,
        block_force_N=run.outputs.block_force[:nt],
        block_disp_m=run.outputs.block_disp[:nt],
        rail_disp_m=run.outputs.rail_disp[:nt],
        wheel_force_N=run.outputs.wheel_force[:, :nt],
        wheel_acc_m_s2=run.outputs.wheel_acc[:, :nt],
        car_body_acc_m_s2=run.outputs.body_acc[:, :nt],
        axle_pass_times_s=(scenario.numerics.approach_distance + offsets) / wheels.speed,
        winkler_block_disp_m=winkler_block_displacement(scenario, t),
        monitored_block_x_m=track.monitored_x,
        contact_loss=events,
        unstable=run.diverged is not None,
        warnings=tuple(warnings),
        static_wheel_load_N=float(static_wheel_loads(vehicle, wheels)[0]),
        dt_s=dt,
        stable_dt_s=stable_dt,
        n_rail_modes=track.omega2.size,
        rail_length_m=track.length,
        speed_m_s=wheels.speed,
    )


def _divergence_message(scenario: Scenario, t_stop: float, stable_dt: float) -> str:
    """Why the integration stopped at ``t_stop`` and what to change: the time step only where
    it exceeds the estimated limit, else the wheel–rail forces beyond what the limit assumes."""
    dt = scenario.numerics.dt
    stopped = (
        f"the integration diverged at t = {t_stop:.4g} s (a wheel–rail compression passed "
        f"{DIVERGENCE_COMPRESSION * 1e3:g} mm or became non-finite) and was stopped; the record "
        "ends there"
    )
    if dt > stable_dt:
        return (
            f"{stopped}: numerics.dt = {dt:g} s is above the estimated stability limit "
            f"{stable_dt:.3g} s; use a smaller numerics.dt"
        )
    overload = HERTZ_OVERLOAD * scenario.vehicle.static_wheel_load
    below = (
        f"{stopped}: numerics.dt = {dt:g} s is already below the estimated stability limit "
        f"{stable_dt:.3g} s, which holds for wheel–rail forces up to {HERTZ_OVERLOAD:g} × the "
        f"static wheel load ({overload / 1e3:.0f} kN); "
    )
    irregularity = scenario.irregularity
    if not irregularity.enabled:
        return (
            below + "on a smooth rail, forces far beyond that point to an unusual combination of "
            "vehicle and track parameters: a smaller numerics.dt may carry the run through"
        )
    if irregularity.profile_csv:
        source = (
            f"the amplitudes of the measured profile irregularity.profile_csv = "
            f"{irregularity.profile_csv!r} (and the unit in its header, eta_m or eta_mm)"
        )
    else:
        source = "irregularity.track_class and irregularity.wavelength_min"
    return (
        below + f"forces far beyond that come from an implausible rail irregularity: check {source}"
    )


def _contact_events(rows: np.ndarray) -> np.ndarray:
    """Kernel event rows (wheel, t_start, x_start, t_end) as CONTACT_EVENT_DTYPE records."""
    events = np.zeros(rows.shape[0], dtype=CONTACT_EVENT_DTYPE)
    events["wheel"] = rows[:, 0].astype(np.int64)
    events["t_s"] = rows[:, 1]
    events["x_m"] = rows[:, 2]
    events["duration_s"] = rows[:, 3] - rows[:, 1]
    return events


def _contact_loss_message(events: np.ndarray, n_events: int) -> str:
    """Human-readable summary of loss-of-contact events."""
    shown = "; ".join(
        f"wheel {e['wheel']} at t = {e['t_s']:.4f} s, x = {e['x_m']:.2f} m for "
        f"{e['duration_s'] * 1e3:.2f} ms"
        for e in events[:5]
    )
    more = f" (and {n_events - 5} more)" if n_events > 5 else ""
    return f"loss of wheel–rail contact, {n_events} event(s): {shown}{more}"
