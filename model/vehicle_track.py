"""Nonlinear vehicle–track model: the excitation model of the paper (§2, §4.1; docs/model.md §1–6).

Vehicle (one-rail half model): the paper's single bogie (half car body in bounce, bogie bounce
and pitch, two wheelsets) or a train of independent 10-DOF cars. Track: simply supported modal
Euler rail on identical, uniformly spaced blocks (fastener K_r, C_r; block mass M_s; block pad
K_s, C_s onto the rigid invert). Hertz contact with loss of contact, rail irregularity from
:func:`model.irregularity.profile_for`, Zhai's explicit integrator (φ = ψ = ½) from static
equilibrium. Equations, the fast formulation and measured figures: ``docs/vehicle_track.md``.

:func:`simulate` runs a passage. Underneath, the kernels in ``model._vt_kernels`` take a few
named records (typed named tuples, built once per run), which the public assembly functions
build and the tests use directly::

    track = assemble_track(scenario)        # TrackSystem: rail modes, blocks, monitored block
    vehicle = assemble_vehicle(scenario)    # VehicleSystem: per-car M⁻¹, K, C, gravity
    wheels = assemble_wheels(scenario, duration_s)  # WheelInputs: positions, speed, G, η grid
    state = static_equilibrium(scenario, track, vehicle, wheels)  # SystemState
    run = integrate(track, vehicle, wheels, state, n_time_steps(scenario), dt)  # Integration
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from model import _vt_kernels as kernels
from model import irregularity
from model._vt_kernels import hertz_force, zhai_predict
from model.params import GRAVITY, Scenario

__all__ = [
    # running a passage
    "simulate",
    "check_inputs",
    "stable_time_step",
    "zhai_damped_limit",
    "winkler_block_displacement",
    "VehicleTrackResult",
    "CONTACT_EVENT_DTYPE",
    # assembly of the kernel records, statics and time stepping (used by tests and benchmarks)
    "TrackSystem",
    "VehicleSystem",
    "WheelInputs",
    "SystemState",
    "Outputs",
    "Integration",
    "assemble_track",
    "assemble_vehicle",
    "assemble_wheels",
    "wheel_start_positions",
    "static_wheel_loads",
    "vehicle_equilibrium",
    "track_equilibrium",
    "static_equilibrium",
    "n_time_steps",
    "integrate",
    # the two kernels with a closed-form check of their own
    "hertz_force",
    "zhai_predict",
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
# Irregularity sampled for linear interpolation at this spacing (m), or at this many points per
# shortest wavelength λ_min if finer (interpolation error < 5e-4 of the amplitude at λ_min).
PROFILE_GRID_STEP = 0.005
PROFILE_POINTS_PER_WAVELENGTH = 100
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


# ---- kernel records --------------------------------------------------------------------------
# Typed named tuples: Numba passes them to the kernels as structs, by field name, with
# nogil=True and cache=True. Scalars are Python floats and ints, arrays float64 (int64 for
# indices), so one compiled signature serves every scenario.
class TrackSystem(NamedTuple):
    """Modal rail on uniformly spaced identical blocks in the diagonal (block modal) form.

    Built by :func:`assemble_track`. Rail modes Y_k(x) = A sin(kπx/L), k = 1..N_m; blocks at
    i L_s, i = 1..N−1 (N = L/L_s), in block modal coordinates (docs/vehicle_track.md).
    """

    length: float  # L (m)
    n_spacings: int  # N = L / L_s
    omega2: np.ndarray  # (N_m,) ω_k² of the free rail (rad²/s²)
    fold_index: np.ndarray  # (N_m,) block mode ρ(k) − 1 that rail mode k meets, −1 if none
    fold_sign: np.ndarray  # (N_m,) σ_k
    block_gain: float  # b = 1/√(m_r L_s) (1/√kg)
    mode_amplitude: float  # A = √(2/(m_r L)) (1/√kg)
    wavenumber_unit: float  # π/L (1/m)
    fastener_k: float  # K_r (N/m)
    fastener_c: float  # C_r (N·s/m)
    pad_k: float  # K_s (N/m)
    pad_c: float  # C_s (N·s/m)
    block_mass: float  # M_s (kg)
    support_k: float  # K_r K_s/(K_r + K_s), fastener and pad in series (N/m)
    monitored_block: int  # block i (1..N−1) whose invert force is recorded
    monitored_block_weights: np.ndarray  # (N−1,) Z_s,i = Σ_r w_r s_r at the monitored block
    monitored_rail_shapes: np.ndarray  # (N_m,) Y_k at the monitored block

    @property
    def monitored_x(self) -> float:
        """Position of the monitored block (m)."""
        return self.monitored_block * self.length / self.n_spacings

    def mode_shapes(self, x: np.ndarray) -> np.ndarray:
        """Y_k(x) for all modes, shape (N_m, x.size)."""
        k = np.arange(1, self.omega2.size + 1)
        return self.mode_amplitude * np.sin(np.outer(k, x) * self.wavenumber_unit)

    def mode_slopes(self, x: np.ndarray) -> np.ndarray:
        """dY_k/dx at x for all modes, shape (N_m, x.size)."""
        k = np.arange(1, self.omega2.size + 1)
        phase = np.outer(k, x) * self.wavenumber_unit
        return self.mode_amplitude * (k * self.wavenumber_unit)[:, None] * np.cos(phase)

    def block_mode_weights(self, block: int) -> np.ndarray:
        """Z_s,i = Σ_r w_r s_r for block i (1..N−1): w_r = √(2/N) sin(rπi/N)."""
        return _block_mode_weights(self.n_spacings, block)


class VehicleSystem(NamedTuple):
    """Per-car matrices of the linear one-rail vehicle, built by :func:`assemble_vehicle`."""

    inv_mass: np.ndarray  # (n_cars, d) 1/m_i (1/kg or 1/(kg·m²))
    stiffness: np.ndarray  # (n_cars, d, d) (N/m, N or N·m)
    damping: np.ndarray  # (n_cars, d, d)
    gravity_force: np.ndarray  # (n_cars, d) (N)
    wheel_dof: np.ndarray  # (n_cars, wheels per car), local DOF index of each wheelset
    body_dof: int  # local DOF index of the car-body bounce


class WheelInputs(NamedTuple):
    """Wheel motion, contact law and rail irregularity, built by :func:`assemble_wheels`."""

    x0: np.ndarray  # (n_wheels,) positions at t = 0 (m), leading axle first
    speed: float  # v (m/s)
    hertz_constant: float  # G (m/N^(2/3))
    prescribed_load: np.ndarray  # (n_wheels,) loads (N) replacing Hertz contact, or [-1.0]
    eta_grid: np.ndarray  # irregularity η (m) on a uniform grid
    eta_start: float  # rail coordinate of eta_grid[0] (m)
    eta_step: float  # grid step (m)

    def profile(self, x: np.ndarray) -> np.ndarray:
        """η at x, interpolated exactly as in the kernel (m)."""
        grid_x = self.eta_start + self.eta_step * np.arange(self.eta_grid.size)
        return np.interp(x, grid_x, self.eta_grid)


class SystemState(NamedTuple):
    """Displacements, velocities, accelerations and previous accelerations, updated in place.

    q: rail modal coordinates (N_m,), s: block modal coordinates (N−1,), u: vehicle DOFs
    (n_cars · d,), all down + (m, or rad for pitch), from the unloaded track.
    """

    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    qdd_prev: np.ndarray
    s: np.ndarray
    sd: np.ndarray
    sdd: np.ndarray
    sdd_prev: np.ndarray
    u: np.ndarray
    ud: np.ndarray
    udd: np.ndarray
    udd_prev: np.ndarray


class Scratch(NamedTuple):
    """Work arrays of one evaluation of the accelerations (allocated once per run)."""

    sine_table: np.ndarray  # (N_m, n_wheels) Y_k(x_j)
    wheel_work: np.ndarray  # (3, n_wheels) Chebyshev recurrence
    rail_at_wheel: np.ndarray  # (n_wheels,) Z_r(x_j)
    fold_disp: np.ndarray  # (N−1,) rail displacement folded onto block modes
    fold_vel: np.ndarray  # (N−1,)
    block_mode_force: np.ndarray  # (N−1,) fastener force per block mode
    wheel_x: np.ndarray  # (n_wheels,) wheel positions (m)
    compression: np.ndarray  # (n_wheels,) δ (m)
    wheel_force: np.ndarray  # (n_wheels,) wheel–rail forces (N)


class Outputs(NamedTuple):
    """Recorded histories, index 0 = initial state (SI, down +)."""

    block_force: np.ndarray  # (nt,) K_s Z_s + C_s Ż_s under the monitored block
    block_disp: np.ndarray  # (nt,)
    rail_disp: np.ndarray  # (nt,)
    wheel_force: np.ndarray  # (n_wheels, nt)
    wheel_acc: np.ndarray  # (n_wheels, nt)
    body_acc: np.ndarray  # (n_cars, nt)


class ContactLog(NamedTuple):
    """Loss-of-contact bookkeeping of the kernel."""

    in_contact: np.ndarray  # (n_wheels,) bool
    open_event: np.ndarray  # (n_wheels,) row of the wheel's open event, −1 if none
    events: np.ndarray  # (MAX_CONTACT_EVENTS, 4) wheel, t_start, x_start, t_end
    event_count: np.ndarray  # (1,) events so far, including those past the capacity


@dataclass(frozen=True)
class Integration:
    """Result of :func:`integrate`: the recorded outputs and how the run ended."""

    outputs: Outputs
    diverged: int | None  # output index where the response diverged, None if it did not
    events: np.ndarray  # (n, 4) logged contact-loss rows, open ones closed at the end
    n_events: int  # all contact-loss events, including those past the log's capacity


# ---- assembly (public: the tests and benchmarks build the kernel inputs with these) ----------
def _block_mode_weights(n_spacings: int, block: int) -> np.ndarray:
    """w_r = √(2/N) sin(rπi/N), r = 1..N−1, for block i."""
    r = np.arange(1, n_spacings)
    return math.sqrt(2.0 / n_spacings) * np.sin(r * math.pi * block / n_spacings)


def assemble_track(scenario: Scenario) -> TrackSystem:
    """Track record for the scenario's rail length and number of rail modes.

    Parameters
    ----------
    scenario : Scenario
        Uses ``track`` (rail and support values, docs/model.md §2), ``rail_length`` and
        ``rail_modes``.

    Returns
    -------
    TrackSystem
        ω_k² = (EI/m_r)(kπ/L)⁴; the fold of rail mode k onto block mode ρ(k) (k mod 2N folded
        into 1..N−1, sign σ_k); b = 1/√(m_r L_s); the monitored block at mid-rail.
    """
    track = scenario.track
    length = float(scenario.rail_length)
    n_spacings = round(length / track.block_spacing)
    k = np.arange(1, scenario.rail_modes + 1)
    omega2 = track.bending_stiffness / track.rail_mass * (k * math.pi / length) ** 4
    # sin(kπi/N) at the blocks equals σ sin(ρπi/N) with ρ = k mod 2N folded into 1..N−1
    remainder = k % (2 * n_spacings)
    upper = remainder > n_spacings
    fold = np.where(upper, 2 * n_spacings - remainder, remainder)
    coupled = (fold > 0) & (fold < n_spacings)
    mode_amplitude = math.sqrt(2.0 / (track.rail_mass * length))
    wavenumber_unit = math.pi / length
    monitored = n_spacings // 2
    monitored_x = monitored * length / n_spacings
    return TrackSystem(
        length=length,
        n_spacings=n_spacings,
        omega2=omega2,
        fold_index=np.where(coupled, fold - 1, -1).astype(np.int64),
        fold_sign=np.where(coupled, np.where(upper, -1.0, 1.0), 0.0),
        block_gain=1.0 / math.sqrt(track.rail_mass * track.block_spacing),
        mode_amplitude=mode_amplitude,
        wavenumber_unit=wavenumber_unit,
        fastener_k=float(track.fastener_stiffness),
        fastener_c=float(track.fastener_damping),
        pad_k=float(track.pad_stiffness),
        pad_c=float(track.pad_damping),
        block_mass=float(track.block_mass),
        support_k=float(track.support_stiffness),
        monitored_block=monitored,
        monitored_block_weights=_block_mode_weights(n_spacings, monitored),
        monitored_rail_shapes=mode_amplitude * np.sin(k * monitored_x * wavenumber_unit),
    )


def assemble_vehicle(scenario: Scenario) -> VehicleSystem:
    """Per-car mass, stiffness, damping and gravity of the one-rail vehicle model.

    Every mass and inertia is halved (one rail), suspensions are per side (docs/model.md §1).
    The single bogie carries a quarter of the car body in bounce only; a full car has body
    bounce and pitch, two bogies in bounce and pitch and four wheelsets. Longitudinal positions
    grow backwards along the train, so the wheel order follows ``Train.axle_offsets``.

    Parameters
    ----------
    scenario : Scenario
        Uses ``vehicle`` and ``train``.

    Returns
    -------
    VehicleSystem
        DOFs per car, single bogie: body bounce, bogie bounce and pitch, wheelsets 1–2; full
        car: body bounce and pitch, (bogie bounce, pitch) × 2, wheelsets 1–4.
    """
    veh, train = scenario.vehicle, scenario.train
    half_wheelbase = 0.5 * train.wheelbase
    if train.single_bogie:
        masses = [
            veh.car_body_mass / 4,
            veh.bogie_mass / 2,
            veh.bogie_pitch_inertia / 2,
            veh.wheelset_mass / 2,
            veh.wheelset_mass / 2,
        ]
        translational = [True, True, False, True, True]
        body_point = [{0: 1.0}]  # secondary attachment on the body, per bogie
        bogies = [(1, 2)]
        wheels = [3, 4]
    else:
        masses = [
            veh.car_body_mass / 2,
            scenario.car_body_pitch_inertia / 2,
            veh.bogie_mass / 2,
            veh.bogie_pitch_inertia / 2,
            veh.bogie_mass / 2,
            veh.bogie_pitch_inertia / 2,
        ] + [veh.wheelset_mass / 2] * 4
        translational = [True, False, True, False, True, False, True, True, True, True]
        half_bogie_distance = 0.5 * train.bogie_distance
        body_point = [{0: 1.0, 1: -half_bogie_distance}, {0: 1.0, 1: half_bogie_distance}]
        bogies = [(2, 3), (4, 5)]
        wheels = [6, 7, 8, 9]
    n_dof = len(masses)
    stiffness = np.zeros((n_dof, n_dof))
    damping = np.zeros((n_dof, n_dof))

    def spring(k, c, coefficients):
        """Add a spring–dashpot acting on the relative displacement Σ a_i u_i."""
        a = np.zeros(n_dof)
        for dof, coefficient in coefficients.items():
            a[dof] = coefficient
        stiffness[:] += k * np.outer(a, a)
        damping[:] += c * np.outer(a, a)

    for b, (bounce, pitch) in enumerate(bogies):
        spring(veh.secondary_stiffness, veh.secondary_damping, {**body_point[b], bounce: -1.0})
        for w, lever in enumerate((-half_wheelbase, half_wheelbase)):
            spring(
                veh.primary_stiffness,
                veh.primary_damping,
                {bounce: 1.0, pitch: lever, wheels[2 * b + w]: -1.0},
            )
    mass = np.array(masses)
    gravity = np.where(translational, mass * GRAVITY, 0.0)
    n_cars = 1 if train.single_bogie else train.n_cars
    return VehicleSystem(
        inv_mass=np.tile(1.0 / mass, (n_cars, 1)),
        stiffness=np.tile(stiffness, (n_cars, 1, 1)),
        damping=np.tile(damping, (n_cars, 1, 1)),
        gravity_force=np.tile(gravity, (n_cars, 1)),
        wheel_dof=np.tile(np.array(wheels, dtype=np.int64), (n_cars, 1)),
        body_dof=0,
    )


def wheel_start_positions(scenario: Scenario) -> np.ndarray:
    """Wheel positions at t = 0 (m): the leading axle ``approach_distance`` before mid-rail.

    Parameters
    ----------
    scenario : Scenario

    Returns
    -------
    ndarray
        (n_wheels,) rail coordinates (m), leading axle first.
    """
    return (
        0.5 * scenario.rail_length
        - scenario.numerics.approach_distance
        - np.asarray(scenario.train.axle_offsets, dtype=float)
    )


def assemble_wheels(
    scenario: Scenario, duration_s: float, prescribed_load_N: np.ndarray | None = None
) -> WheelInputs:
    """Wheel record for ``scenario``, with the irregularity sampled where the wheels run.

    Profile positions are measured from the monitored block, so the track under it does not
    change when a numerics setting changes the rail length. The profile is sampled every
    ``PROFILE_GRID_STEP`` m, or λ_min/``PROFILE_POINTS_PER_WAVELENGTH`` if finer, for the
    kernel's linear interpolation.

    Parameters
    ----------
    scenario : Scenario
        Uses ``train``, ``track.hertz_constant``, ``irregularity``, ``numerics``.
    duration_s : float
        Time the wheels run (s); the profile covers their travel.
    prescribed_load_N : array_like, optional
        (n_wheels,) constant moving loads (N) that replace the vehicle and the Hertz contact
        (the moving-load model); None for the coupled vehicle.

    Returns
    -------
    WheelInputs
    """
    speed = float(scenario.train.speed)
    x0 = wheel_start_positions(scenario)
    eta_step = min(
        PROFILE_GRID_STEP, scenario.irregularity.wavelength_min / PROFILE_POINTS_PER_WAVELENGTH
    )
    start = x0.min() - eta_step
    n_grid = math.ceil((x0.max() + speed * duration_s - start) / eta_step) + 2
    grid = start + eta_step * np.arange(n_grid)
    if prescribed_load_N is None:
        prescribed = np.array([-1.0])
    else:
        prescribed = np.array(prescribed_load_N, dtype=float)
        if prescribed.shape != x0.shape or np.any(prescribed < 0.0):
            raise ValueError(
                f"prescribed_load_N = {prescribed_load_N!r}: needs {x0.size} loads ≥ 0 N "
                "(one per wheel)"
            )
    return WheelInputs(
        x0=x0,
        speed=speed,
        hertz_constant=float(scenario.track.hertz_constant),
        prescribed_load=prescribed,
        eta_grid=np.ascontiguousarray(
            irregularity.profile_for(scenario.irregularity, grid - 0.5 * scenario.rail_length),
            dtype=float,
        ),
        eta_start=float(start),
        eta_step=float(eta_step),
    )


# ---- statics -----------------------------------------------------------------------------------
def vehicle_equilibrium(
    vehicle: VehicleSystem, wheel_disp: np.ndarray, wheel_vel: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Vehicle equilibrium on wheelsets at given displacements (and quasi-static velocities).

    Parameters
    ----------
    vehicle : VehicleSystem
    wheel_disp, wheel_vel : ndarray
        (n_wheels,) wheelset displacements (m, down +) and velocities (m/s).

    Returns
    -------
    u, ud : ndarray
        Flat DOF displacements and velocities (n_cars · d,).
    wheel_force : ndarray
        (n_wheels,) wheel–rail forces (N); they do not depend on the wheel displacements (the
        vehicle is statically determinate).
    """
    n_cars, n_dof = vehicle.inv_mass.shape
    per_car = vehicle.wheel_dof.shape[1]
    u = np.zeros(n_cars * n_dof)
    v = np.zeros(n_cars * n_dof)
    force = np.zeros(n_cars * per_car)
    for car in range(n_cars):
        wheels = vehicle.wheel_dof[car]
        others = np.setdiff1d(np.arange(n_dof), wheels)
        k = vehicle.stiffness[car]
        u_w = wheel_disp[car * per_car : (car + 1) * per_car]
        v_w = wheel_vel[car * per_car : (car + 1) * per_car]
        k_oo, k_ow = k[np.ix_(others, others)], k[np.ix_(others, wheels)]
        u_o = np.linalg.solve(k_oo, vehicle.gravity_force[car, others] - k_ow @ u_w)
        v_o = np.linalg.solve(k_oo, -k_ow @ v_w)
        base = car * n_dof
        u[base + others], u[base + wheels] = u_o, u_w
        v[base + others], v[base + wheels] = v_o, v_w
        force[car * per_car : (car + 1) * per_car] = (
            vehicle.gravity_force[car, wheels]
            - k[np.ix_(wheels, others)] @ u_o
            - k[np.ix_(wheels, wheels)] @ u_w
        )
    return u, v, force


def track_equilibrium(track: TrackSystem, modal_load: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Static rail modal coordinates q and block modal coordinates s under modal loads.

    Solves ω_k² q_k + σ_k b F̂_ρ = P_k, F̂_ρ = K_r (b Σ σ_k q_k − s_ρ) = K_s s_ρ exactly, one
    block mode at a time (O(N_m)); the same linear map turns modal load *rates* into the
    quasi-static velocities.

    Parameters
    ----------
    track : TrackSystem
    modal_load : ndarray
        (N_m,) modal loads P_k = Σ_j p_j Y_k(x_j) (N/√kg).

    Returns
    -------
    q, s : ndarray
        (N_m,) and (N−1,) modal coordinates.
    """
    coupled = track.fold_index >= 0
    index = track.fold_index[coupled]
    sign = track.fold_sign[coupled]
    w2 = track.omega2[coupled]
    n_block_modes = track.n_spacings - 1
    free_disp = np.bincount(index, sign * modal_load[coupled] / w2, n_block_modes)
    compliance = np.bincount(index, 1.0 / w2, n_block_modes)
    b = track.block_gain
    block_force = track.support_k * b * free_disp / (1.0 + track.support_k * b * b * compliance)
    q = modal_load / track.omega2
    q[coupled] -= sign * b * block_force[index] / w2
    return q, block_force / track.pad_k


def static_wheel_loads(vehicle: VehicleSystem, wheels: WheelInputs) -> np.ndarray:
    """Wheel–rail forces at equilibrium (N): the prescribed loads or the vehicle's weight."""
    if wheels.prescribed_load[0] >= 0.0:
        return wheels.prescribed_load.copy()
    n_wheels = wheels.x0.size
    return vehicle_equilibrium(vehicle, np.zeros(n_wheels), np.zeros(n_wheels))[2]


def static_equilibrium(
    scenario: Scenario, track: TrackSystem, vehicle: VehicleSystem, wheels: WheelInputs
) -> SystemState:
    """Static equilibrium under the wheel loads, with the quasi-static rates of steady motion.

    Displacements: track under the static wheel loads, wheels at rail + η + Hertz compression
    G p^{2/3} (``scenario.track.hertz_compression``), vehicle in equilibrium on them.
    Velocities: the time derivative of that solution as the loads move at the train speed, so
    a smooth-rail run starts without a drop or a jolt. Accelerations are zero until
    :func:`integrate` evaluates them.

    Parameters
    ----------
    scenario : Scenario
        Its ``track`` gives the Hertz compression.
    track, vehicle, wheels : TrackSystem, VehicleSystem, WheelInputs
        From the ``assemble_*`` functions.

    Returns
    -------
    SystemState
    """
    x0 = wheels.x0
    loads = static_wheel_loads(vehicle, wheels)
    shapes = track.mode_shapes(x0)
    slopes = track.mode_slopes(x0)
    q, s = track_equilibrium(track, shapes @ loads)
    qd, sd = track_equilibrium(track, wheels.speed * (slopes @ loads))
    eta = wheels.profile(x0)
    half = 0.5 * wheels.eta_step
    eta_slope = (wheels.profile(x0 + half) - wheels.profile(x0 - half)) / wheels.eta_step
    wheel_disp = shapes.T @ q + eta + scenario.track.hertz_compression(loads)
    wheel_vel = wheels.speed * (slopes.T @ q + eta_slope) + shapes.T @ qd
    u, ud, _ = vehicle_equilibrium(vehicle, wheel_disp, wheel_vel)
    return SystemState(
        q=q,
        qd=qd,
        qdd=np.zeros_like(q),
        qdd_prev=np.zeros_like(q),
        s=s,
        sd=sd,
        sdd=np.zeros_like(s),
        sdd_prev=np.zeros_like(s),
        u=u,
        ud=ud,
        udd=np.zeros_like(u),
        udd_prev=np.zeros_like(u),
    )


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
    outputs = Outputs(
        block_force=np.zeros(nt),
        block_disp=np.zeros(nt),
        rail_disp=np.zeros(nt),
        wheel_force=np.zeros((n_wheels, nt)),
        wheel_acc=np.zeros((n_wheels, nt)),
        body_acc=np.zeros((vehicle.inv_mass.shape[0], nt)),
    )
    scratch = Scratch(
        sine_table=np.empty((n_modes, n_wheels)),
        wheel_work=np.empty((3, n_wheels)),
        rail_at_wheel=np.empty(n_wheels),
        fold_disp=np.empty(n_block_modes),
        fold_vel=np.empty(n_block_modes),
        block_mode_force=np.empty(n_block_modes),
        wheel_x=np.empty(n_wheels),
        compression=np.empty(n_wheels),
        wheel_force=np.empty(n_wheels),
    )
    kernels.accelerations(0.0, state, track, vehicle, wheels, scratch)
    kernels.record(0, state, track, vehicle, scratch, outputs)
    in_contact = scratch.wheel_force > 0.0
    contact = ContactLog(
        in_contact=in_contact,
        open_event=np.full(n_wheels, -1, dtype=np.int64),
        events=np.zeros((MAX_CONTACT_EVENTS, 4)),
        event_count=np.zeros(1, dtype=np.int64),
    )
    for j in np.flatnonzero(~in_contact):  # already off the rail at t = 0
        contact.events[contact.event_count[0]] = (j, 0.0, wheels.x0[j], -1.0)
        contact.open_event[j] = contact.event_count[0]
        contact.event_count[0] += 1
    diverged = None
    chunk = max(1, math.ceil(n_steps / PROGRESS_CALLS))
    for start in range(0, n_steps, chunk):
        stop = min(start + chunk, n_steps)
        status = kernels.advance(
            start,
            stop,
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
            progress(stop / n_steps)
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

    Each wheel is summed over |ξ| < ``WINKLER_REACH``/β only, where the deflection exceeds
    e^{−40} of its peak.

    Parameters
    ----------
    scenario : Scenario
    t_s : ndarray
        Increasing times (s) from the start of the passage, 1-D.

    Returns
    -------
    ndarray
        Block displacement (m, down +), same shape as ``t_s``.
    """
    track, train = scenario.track, scenario.train
    beta, modulus = track.winkler_beta, track.winkler_modulus
    x_mon = 0.5 * scenario.rail_length
    t = np.asarray(t_s, dtype=float)
    rail = np.zeros(t.shape)
    reach = WINKLER_REACH / beta
    for x0 in wheel_start_positions(scenario):  # each wheel only where it deflects the block
        lo, hi = np.searchsorted(
            t, [(x_mon - x0 - reach) / train.speed, (x_mon - x0 + reach) / train.speed]
        )
        xi = np.abs(x0 + train.speed * t[lo:hi] - x_mon) * beta
        rail[lo:hi] += np.exp(-xi) * (np.cos(xi) + np.sin(xi))
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
        warnings.append(
            f"the integration diverged at t = {nt * dt:.4g} s (a wheel–rail compression passed "
            f"{DIVERGENCE_COMPRESSION * 1e3:g} mm or became non-finite) and was stopped; the "
            f"record ends there. The time step {dt:g} s is too large for this scenario: use a "
            f"smaller numerics.dt (estimated limit {stable_dt:.3g} s)."
        )
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
