"""Numba kernels of the vehicle–track model (records of plain floats and arrays only).

The track is integrated in the form described in ``docs/vehicle_track.md``: rail modal
coordinates q_k (unit modal mass, k = 1..N_m) and *block modal* coordinates s_r (r = 1..N−1),
the orthonormal DST-I of the block displacements. Because the blocks are identical and uniformly
spaced, the fastener coupling is diagonal between them: rail mode k meets only block mode
ρ(k) = fold(k), with sign σ_k and gain b = 1/√(m_r L_s). One time step costs O(N_m + N) for the
track and O(N_m · n_wheels) for the wheel–rail coupling, with no transform at all.

Vehicle: per car a dense (d × d) stiffness and damping matrix, a diagonal mass, gravity, and the
local indices of its wheelset DOFs. Displacements are positive downward.

The kernels take the named records of :mod:`model.track.assembly` (``TrackSystem``,
``VehicleSystem``, ``WheelInputs``, ``SystemState``, ``Scratch``, ``Outputs``, ``ContactLog``):
typed named tuples, which Numba passes by value as structs of their fields. They only read the
fields by name, so the records are defined with the assembly code and not imported here.
"""

from __future__ import annotations

import math

import numba

# Status codes returned by ``advance``
RUNNING = -1
# Reassociation lets LLVM vectorise the sums over wheels and modes; no 'nnan'/'ninf', so the
# divergence checks on non-finite values stay valid.
FAST = {"reassoc", "contract", "nsz", "arcp"}


@numba.njit(cache=True)
def zhai_predict(x, v, a, a_prev, dt, phi, psi):
    """Zhai's explicit update of x, v in place; a_prev takes a_n (a is then recomputed)."""
    h2 = dt * dt
    for i in range(x.size):
        x[i] += v[i] * dt + (0.5 + psi) * a[i] * h2 - psi * a_prev[i] * h2
        v[i] += (1.0 + phi) * a[i] * dt - phi * a_prev[i] * dt
        a_prev[i] = a[i]


@numba.njit(cache=True)
def hertz_force(compression, hertz_constant):
    """Hertz force p = (δ/G)^{3/2} for δ > 0, 0 when the wheel has left the rail (N)."""
    if compression <= 0.0:
        return 0.0
    ratio = compression / hertz_constant
    return ratio * math.sqrt(ratio)


@numba.njit(cache=True)
def profile_at(eta_grid, grid_start, grid_step, x):
    """Irregularity at x by linear interpolation on the uniform grid (clamped at its ends)."""
    pos = (x - grid_start) / grid_step
    n = eta_grid.size
    if pos <= 0.0:
        return eta_grid[0]
    if pos >= n - 1:
        return eta_grid[n - 1]
    i = int(pos)
    frac = pos - i
    return eta_grid[i] + frac * (eta_grid[i + 1] - eta_grid[i])


@numba.njit(cache=True, fastmath=FAST)
def vehicle_accelerations(u, ud, udd, vehicle, wheel_force):
    """Vehicle: M ü = f_g − K u − C u̇ − (contact forces on the wheelsets), car by car."""
    inv_mass, stiffness, damping = vehicle.inv_mass, vehicle.stiffness, vehicle.damping
    gravity_force, wheel_dof = vehicle.gravity_force, vehicle.wheel_dof
    n_cars, n_dof = inv_mass.shape
    wheels_per_car = wheel_dof.shape[1]
    for car in range(n_cars):
        base = car * n_dof
        for i in range(n_dof):
            force = gravity_force[car, i]
            for m in range(n_dof):
                force -= stiffness[car, i, m] * u[base + m] + damping[car, i, m] * ud[base + m]
            udd[base + i] = force
        for w in range(wheels_per_car):
            udd[base + wheel_dof[car, w]] -= wheel_force[car * wheels_per_car + w]
        for i in range(n_dof):
            udd[base + i] *= inv_mass[car, i]


@numba.njit(cache=True, fastmath=FAST)
def accelerations(t, state, track, vehicle, wheels, scratch):
    """Accelerations qdd, sdd, udd of the whole system at time t; wheel forces in ``scratch``.

    ``wheels.prescribed_load`` (n_wheels,) replaces the Hertz law when its first entry is ≥ 0:
    the moving-constant-load model, with the vehicle at rest (ü = 0, δ reported as 0). It is
    [-1.0] for the coupled vehicle.
    """
    q, qd, qdd = state.q, state.qd, state.qdd
    s, sd, sdd = state.s, state.sd, state.sdd
    u, ud, udd = state.u, state.ud, state.udd
    omega2, fold_index, fold_sign = track.omega2, track.fold_index, track.fold_sign
    block_gain, mode_amplitude = track.block_gain, track.mode_amplitude
    wavenumber_unit = track.wavenumber_unit
    fastener_k, fastener_c = track.fastener_k, track.fastener_c
    pad_k, pad_c, block_mass = track.pad_k, track.pad_c, track.block_mass
    wheel_x0, speed, prescribed_load = wheels.x0, wheels.speed, wheels.prescribed_load
    sine_table, rail_at_wheel = scratch.sine_table, scratch.rail_at_wheel
    fold_disp, fold_vel = scratch.fold_disp, scratch.fold_vel
    block_mode_force, wheel_x = scratch.block_mode_force, scratch.wheel_x
    compression, wheel_force = scratch.compression, scratch.wheel_force
    n_modes = q.size
    n_wheels = wheel_x0.size
    n_dof = vehicle.inv_mass.shape[1]
    wheel_dof = vehicle.wheel_dof
    wheels_per_car = wheel_dof.shape[1]

    # Mode shapes at the wheels, Y_k(x_j) = A sin(kθ_j), by the Chebyshev recurrence
    # sin((k+1)θ) = 2cosθ sin kθ − sin((k−1)θ); inner loops run over wheels so they vectorise.
    two_cos = scratch.wheel_work[0]
    s_prev = scratch.wheel_work[1]
    s_cur = scratch.wheel_work[2]
    for j in range(n_wheels):
        x = wheel_x0[j] + speed * t
        wheel_x[j] = x
        theta = wavenumber_unit * x
        two_cos[j] = 2.0 * math.cos(theta)
        s_prev[j] = 0.0
        s_cur[j] = mode_amplitude * math.sin(theta)
        rail_at_wheel[j] = 0.0
    k = 0
    while k + 4 <= n_modes:  # four modes per pass: a quarter of the loads and stores
        q0, q1, q2, q3 = q[k], q[k + 1], q[k + 2], q[k + 3]
        for j in range(n_wheels):
            c = two_cos[j]
            y0 = s_cur[j]
            y1 = c * y0 - s_prev[j]
            y2 = c * y1 - y0
            y3 = c * y2 - y1
            sine_table[k, j] = y0
            sine_table[k + 1, j] = y1
            sine_table[k + 2, j] = y2
            sine_table[k + 3, j] = y3
            rail_at_wheel[j] += y0 * q0 + y1 * q1 + y2 * q2 + y3 * q3
            s_prev[j] = y3
            s_cur[j] = c * y3 - y2
        k += 4
    for k in range(4 * (n_modes // 4), n_modes):
        qk = q[k]
        for j in range(n_wheels):
            shape = s_cur[j]
            sine_table[k, j] = shape
            rail_at_wheel[j] += shape * qk
            s_cur[j] = two_cos[j] * shape - s_prev[j]
            s_prev[j] = shape

    if prescribed_load[0] >= 0.0:  # moving constant loads, no vehicle
        for j in range(n_wheels):
            compression[j] = 0.0
            wheel_force[j] = prescribed_load[j]
        for i in range(udd.size):
            udd[i] = 0.0
    else:
        # Wheel–rail contact: δ = Z_w − Z_r(x_w) − η(x_w)
        for j in range(n_wheels):
            car = j // wheels_per_car
            dof = car * n_dof + wheel_dof[car, j % wheels_per_car]
            eta = profile_at(wheels.eta_grid, wheels.eta_start, wheels.eta_step, wheel_x[j])
            compression[j] = u[dof] - rail_at_wheel[j] - eta
            wheel_force[j] = hertz_force(compression[j], wheels.hertz_constant)
        vehicle_accelerations(u, ud, udd, vehicle, wheel_force)

    # Track: rail modes k < N meet block mode k directly (ρ = k, σ = +1); higher modes fold
    n_block_modes = s.size
    n_direct = min(n_modes, n_block_modes)
    for r in range(n_direct):
        fold_disp[r] = q[r]
        fold_vel[r] = qd[r]
    for r in range(n_direct, n_block_modes):
        fold_disp[r] = 0.0
        fold_vel[r] = 0.0
    for k in range(n_direct, n_modes):
        r = fold_index[k]
        if r >= 0:
            fold_disp[r] += fold_sign[k] * q[k]
            fold_vel[r] += fold_sign[k] * qd[k]
    for r in range(n_block_modes):
        force = fastener_k * (block_gain * fold_disp[r] - s[r]) + fastener_c * (
            block_gain * fold_vel[r] - sd[r]
        )
        block_mode_force[r] = force
        sdd[r] = (force - pad_k * s[r] - pad_c * sd[r]) / block_mass
    for k in range(n_modes):
        acc = -omega2[k] * q[k]
        for j in range(n_wheels):
            acc += wheel_force[j] * sine_table[k, j]
        if k < n_direct:
            acc -= block_gain * block_mode_force[k]
        elif fold_index[k] >= 0:
            acc -= fold_sign[k] * block_gain * block_mode_force[fold_index[k]]
        qdd[k] = acc


@numba.njit(cache=True, nogil=True)  # releases the GIL: a served dashboard stays responsive
def advance(
    step_start,
    step_stop,
    dt,
    phi,
    psi,
    divergence_limit,
    state,
    track,
    vehicle,
    wheels,
    scratch,
    outputs,
    contact,
):
    """Advance the system from step ``step_start`` to ``step_stop`` with Zhai's method.

    Step n takes the state at t_n = n·dt to t_{n+1} and writes outputs at index n + 1 (index 0
    holds the initial state). φ = ψ = 0 on step 0. Loss of contact is logged in
    ``contact.events`` (rows: wheel, t_start, x_start, t_end) while ``contact.event_count[0]``
    counts all of them.

    Returns
    -------
    int
        ``RUNNING`` (−1) if all steps were taken, else the index of the first output at which
        the response diverged (non-finite, or a wheel–rail compression beyond
        ``divergence_limit`` m; a gap of any size is a wheel in flight, not divergence);
        outputs from that index on are not valid.
    """
    n_wheels = wheels.x0.size
    compression, wheel_force, wheel_x = scratch.compression, scratch.wheel_force, scratch.wheel_x
    in_contact, open_event = contact.in_contact, contact.open_event
    events, event_count = contact.events, contact.event_count
    event_capacity = events.shape[0]
    block_force = outputs.block_force

    for step in range(step_start, step_stop):
        step_phi = 0.0 if step == 0 else phi
        step_psi = 0.0 if step == 0 else psi
        zhai_predict(state.q, state.qd, state.qdd, state.qdd_prev, dt, step_phi, step_psi)
        zhai_predict(state.s, state.sd, state.sdd, state.sdd_prev, dt, step_phi, step_psi)
        zhai_predict(state.u, state.ud, state.udd, state.udd_prev, dt, step_phi, step_psi)
        out = step + 1
        t = out * dt
        accelerations(t, state, track, vehicle, wheels, scratch)
        record(out, state, track, vehicle, scratch, outputs)

        for j in range(n_wheels):
            delta = compression[j]
            if not delta <= divergence_limit:  # also catches NaN; a gap is a wheel in flight
                return out
            touching = wheel_force[j] > 0.0
            if in_contact[j] and not touching:
                if event_count[0] < event_capacity:
                    events[event_count[0], 0] = j
                    events[event_count[0], 1] = t
                    events[event_count[0], 2] = wheel_x[j]
                    events[event_count[0], 3] = -1.0
                    open_event[j] = event_count[0]
                else:
                    open_event[j] = -1
                event_count[0] += 1
                in_contact[j] = False
            elif touching and not in_contact[j]:
                if open_event[j] >= 0:
                    events[open_event[j], 3] = t
                open_event[j] = -1
                in_contact[j] = True
        if not abs(block_force[out]) < math.inf:
            return out
    return RUNNING


@numba.njit(cache=True, fastmath=FAST)
def record(out, state, track, vehicle, scratch, outputs):
    """Write the monitored quantities of the current state at output index ``out``."""
    q, s, sd, udd = state.q, state.s, state.sd, state.udd
    block_weight, rail_weight = track.monitored_block_weights, track.monitored_rail_shapes
    z_block = 0.0
    v_block = 0.0
    for r in range(s.size):
        z_block += block_weight[r] * s[r]
        v_block += block_weight[r] * sd[r]
    z_rail = 0.0
    for k in range(q.size):
        z_rail += rail_weight[k] * q[k]
    outputs.block_disp[out] = z_block
    outputs.block_force[out] = track.pad_k * z_block + track.pad_c * v_block
    outputs.rail_disp[out] = z_rail
    n_dof = vehicle.inv_mass.shape[1]
    wheel_dof = vehicle.wheel_dof
    wheels_per_car = wheel_dof.shape[1]
    wheel_force = scratch.wheel_force
    for j in range(wheel_force.size):
        car = j // wheels_per_car
        outputs.wheel_force[j, out] = wheel_force[j]
        outputs.wheel_acc[j, out] = udd[car * n_dof + wheel_dof[car, j % wheels_per_car]]
    body_acc = outputs.body_acc
    for car in range(body_acc.shape[0]):
        body_acc[car, out] = udd[car * n_dof + vehicle.body_dof]
