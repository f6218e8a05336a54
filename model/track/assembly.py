"""Assembly of the vehicle–track system: the kernel records, and the static start.

The kernels of :mod:`model.track.kernels` take a few named records (typed named tuples, built
once per run). The functions here build them from a scenario, and find the static
equilibrium the integration starts from; :func:`model.track.vehicle_track.simulate` chains them
and the tests use them directly::

    track = assemble_track(scenario)        # TrackSystem: rail modes, blocks, monitored block
    vehicle = assemble_vehicle(scenario)    # VehicleSystem: per-car M⁻¹, K, C, gravity
    wheels = assemble_wheels(scenario, duration_s)  # WheelInputs: positions, speed, G, η grid
    state = static_equilibrium(scenario, track, vehicle, wheels)  # SystemState
    run = integrate(track, vehicle, wheels, state, n_time_steps(scenario), dt)  # Integration

(``integrate`` and ``n_time_steps`` are in :mod:`model.track.vehicle_track`.) Equations and the
block modal form: ``docs/vehicle_track.md``.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from model.params import GRAVITY, Scenario
from model.track import irregularity

# Irregularity sampled for linear interpolation at this spacing (m), or at this many points per
# shortest wavelength λ_min if finer (interpolation error < 5e-4 of the amplitude at λ_min).
PROFILE_GRID_STEP = 0.005
PROFILE_POINTS_PER_WAVELENGTH = 100
# DOFs a vehicle spring–dashpot acts on, at most: a bogie's bounce and pitch and a wheelset
SPRING_ENDS = 3


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
    # The spring–dashpots that K and C sum, Σ k a aᵀ: the local DOFs each acts on and the
    # coefficients of its relative displacement aᵀu (0 in unused slots); the kernel uses these.
    spring_dof: np.ndarray  # (n_springs, 3) local DOF indices
    spring_lever: np.ndarray  # (n_springs, 3) coefficients a_i (1 or −1, or a lever arm in m)
    spring_stiffness: np.ndarray  # (n_cars, n_springs) k (N/m)
    spring_damping: np.ndarray  # (n_cars, n_springs) c (N·s/m)


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
    """Displacements, velocities and accelerations, updated in place.

    q: rail modal coordinates (N_m,), s: block modal coordinates (N−1,), u: vehicle DOFs
    (n_cars · d,), all down + (m, or rad for pitch), from the unloaded track. The track's
    predictor runs in the pass that evaluates its accelerations, so only the vehicle keeps
    its previous accelerations (udd_prev).
    """

    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    s: np.ndarray
    sd: np.ndarray
    sdd: np.ndarray
    u: np.ndarray
    ud: np.ndarray
    udd: np.ndarray
    udd_prev: np.ndarray


class Scratch(NamedTuple):
    """Work arrays of one evaluation of the accelerations (allocated once per run)."""

    modal_load: np.ndarray  # (N_m,) Σ_j p_j Y_k(x_j)
    offset_cos: np.ndarray  # (n_wheels,) cos Δ_j, Δ_j = π(x0_j − x0_0)/L
    offset_sin: np.ndarray  # (n_wheels,) sin Δ_j
    two_cos: np.ndarray  # (n_wheels,) 2cos θ_j, the Chebyshev recurrence's factor
    wheel_first: np.ndarray  # (n_wheels,) its first term
    wheel_prev: np.ndarray  # (n_wheels,) and its two running terms
    wheel_cur: np.ndarray  # (n_wheels,)
    rail_at_wheel: np.ndarray  # (n_wheels,) Z_r(x_j)
    fold_disp: np.ndarray  # (N−1,) rail modes k ≥ N − 1 folded onto block modes (zeros if none)
    fold_vel: np.ndarray  # (N−1,) their velocities, likewise
    wheel_x: np.ndarray  # (n_wheels,) wheel positions (m)
    compression: np.ndarray  # (n_wheels,) δ (m)
    wheel_force: np.ndarray  # (n_wheels,) wheel–rail forces (N)
    monitored: np.ndarray  # (3,) rail and block displacement at the monitored block, block velocity


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
    springs = []  # (dofs, coefficients, k, c)

    def spring(k, c, coefficients):
        """Add a spring–dashpot acting on the relative displacement Σ a_i u_i."""
        a = np.zeros(n_dof)
        for dof, coefficient in coefficients.items():
            a[dof] = coefficient
        stiffness[:] += k * np.outer(a, a)
        damping[:] += c * np.outer(a, a)
        ends = list(coefficients.items()) + [(0, 0.0)] * (SPRING_ENDS - len(coefficients))
        springs.append(([dof for dof, _ in ends], [lever for _, lever in ends], k, c))

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
        spring_dof=np.array([dofs for dofs, _, _, _ in springs], dtype=np.int64),
        spring_lever=np.array([levers for _, levers, _, _ in springs], dtype=float),
        spring_stiffness=np.tile([float(k) for _, _, k, _ in springs], (n_cars, 1)),
        spring_damping=np.tile([float(c) for _, _, _, c in springs], (n_cars, 1)),
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
        s=s,
        sd=sd,
        sdd=np.zeros_like(s),
        u=u,
        ud=ud,
        udd=np.zeros_like(u),
        udd_prev=np.zeros_like(u),
    )
