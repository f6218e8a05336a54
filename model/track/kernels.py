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
import numpy as np

# Status codes returned by ``advance``
RUNNING = -1
# Reassociation lets LLVM vectorise the sums over wheels and modes; no 'nnan'/'ninf', so the
# divergence checks on non-finite values stay valid.
FAST = {"reassoc", "contract", "nsz", "arcp"}


@numba.njit(cache=True)
def zhai_update(x, v, a, a_prev, dt, phi, psi):
    """Zhai's explicit step of one variable: (x_{n+1}, v_{n+1}) from x_n, v_n, a_n, a_{n−1}."""
    h2 = dt * dt
    return (
        x + (v * dt + (0.5 + psi) * a * h2 - psi * a_prev * h2),
        v + ((1.0 + phi) * a * dt - phi * a_prev * dt),
    )


@numba.njit(cache=True)
def zhai_predict(x, v, a, a_prev, dt, phi, psi):
    """Zhai's explicit update of x, v in place; a_prev takes a_n (a is then recomputed)."""
    for i in range(x.size):
        x[i], v[i] = zhai_update(x[i], v[i], a[i], a_prev[i], dt, phi, psi)
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
    """Vehicle: M ü = f_g − Σ (k aᵀu + c aᵀu̇) a − (contact forces on the wheelsets), per car.

    Summed over the spring–dashpots (each on a relative displacement aᵀu of at most three
    DOFs), which is K u + C u̇ with ~40 % of the dense matrices' multiply–adds.
    """
    inv_mass, gravity_force, wheel_dof = vehicle.inv_mass, vehicle.gravity_force, vehicle.wheel_dof
    spring_dof, spring_lever = vehicle.spring_dof, vehicle.spring_lever
    spring_k, spring_c = vehicle.spring_stiffness, vehicle.spring_damping
    n_cars, n_dof = inv_mass.shape
    n_springs, n_ends = spring_dof.shape
    wheels_per_car = wheel_dof.shape[1]
    for car in range(n_cars):
        base = car * n_dof
        for i in range(n_dof):
            udd[base + i] = gravity_force[car, i]
        for w in range(wheels_per_car):
            udd[base + wheel_dof[car, w]] -= wheel_force[car * wheels_per_car + w]
        for spring in range(n_springs):
            stretch = 0.0
            rate = 0.0
            for end in range(n_ends):
                dof = base + spring_dof[spring, end]
                stretch += spring_lever[spring, end] * u[dof]
                rate += spring_lever[spring, end] * ud[dof]
            force = spring_k[car, spring] * stretch + spring_c[car, spring] * rate
            for end in range(n_ends):
                udd[base + spring_dof[spring, end]] -= force * spring_lever[spring, end]
        for i in range(n_dof):
            udd[base + i] *= inv_mass[car, i]


# Modes per pass of the wheel loops below: eight keep the recurrence's terms in registers and
# halve the loop overhead per mode against four (measured, benchmarks/bench_vehicle_track.py).
MODES_PER_PASS = 8


@numba.njit(cache=True, fastmath=FAST)
def sine_series_at_wheels(coefficients, two_cos, first, prev, cur, total):
    """total_j = Σ_k c_k first_j sin(kθ_j)/sin θ_j, k = 1..N_m, by the Chebyshev recurrence.

    sin((k+1)θ) = 2cosθ sin kθ − sin((k−1)θ), started from ``first`` (the k = 1 term without
    its coefficient, e.g. A sin θ_j, which makes the terms the mode shapes Y_k(x_j)). The inner
    loops run over the wheels, so they vectorise, ``MODES_PER_PASS`` modes per pass; ``prev``
    and ``cur`` are work arrays. The rounding error grows like k ε/sin θ (~1e-13 here: the
    wheels stay ≥ 20 m from the rail ends).
    """
    n_modes, n_wheels = coefficients.size, two_cos.size
    for j in range(n_wheels):
        prev[j] = 0.0
        cur[j] = first[j]
        total[j] = 0.0
    k = 0
    while k + MODES_PER_PASS <= n_modes:
        c0, c1, c2, c3 = (
            coefficients[k],
            coefficients[k + 1],
            coefficients[k + 2],
            coefficients[k + 3],
        )
        c4, c5 = coefficients[k + 4], coefficients[k + 5]
        c6, c7 = coefficients[k + 6], coefficients[k + 7]
        for j in range(n_wheels):
            c = two_cos[j]
            y0 = cur[j]
            y1 = c * y0 - prev[j]
            y2 = c * y1 - y0
            y3 = c * y2 - y1
            y4 = c * y3 - y2
            y5 = c * y4 - y3
            y6 = c * y5 - y4
            y7 = c * y6 - y5
            total[j] += (y0 * c0 + y1 * c1 + y2 * c2 + y3 * c3) + (
                y4 * c4 + y5 * c5 + y6 * c6 + y7 * c7
            )
            prev[j] = y7
            cur[j] = c * y7 - y6
        k += MODES_PER_PASS
    for last in range(k, n_modes):  # the last N_m mod MODES_PER_PASS modes
        ck = coefficients[last]
        for j in range(n_wheels):
            y = cur[j]
            total[j] += y * ck
            cur[j] = two_cos[j] * y - prev[j]
            prev[j] = y


@numba.njit(cache=True, fastmath=FAST)
def modal_loads(two_cos, first, prev, cur, load):
    """load_k = Σ_j first_j sin(kθ_j)/sin θ_j for k = 1..N_m, by the same recurrence.

    With first_j = p_j A sin θ_j this is the modal wheel load Σ_j p_j Y_k(x_j). The sines are
    generated again rather than stored by the first pass: a table of N_m × n_wheels values is
    larger than the level-1 cache, and writing and reading it cost more than the recurrence.
    """
    n_modes, n_wheels = load.size, two_cos.size
    for j in range(n_wheels):
        prev[j] = 0.0
        cur[j] = first[j]
    k = 0
    while k + MODES_PER_PASS <= n_modes:
        a0 = a1 = a2 = a3 = a4 = a5 = a6 = a7 = 0.0
        for j in range(n_wheels):
            c = two_cos[j]
            y0 = cur[j]
            y1 = c * y0 - prev[j]
            y2 = c * y1 - y0
            y3 = c * y2 - y1
            y4 = c * y3 - y2
            y5 = c * y4 - y3
            y6 = c * y5 - y4
            y7 = c * y6 - y5
            a0 += y0
            a1 += y1
            a2 += y2
            a3 += y3
            a4 += y4
            a5 += y5
            a6 += y6
            a7 += y7
            prev[j] = y7
            cur[j] = c * y7 - y6
        load[k] = a0
        load[k + 1] = a1
        load[k + 2] = a2
        load[k + 3] = a3
        load[k + 4] = a4
        load[k + 5] = a5
        load[k + 6] = a6
        load[k + 7] = a7
        k += MODES_PER_PASS
    for last in range(k, n_modes):  # the last N_m mod MODES_PER_PASS modes
        a = 0.0
        for j in range(n_wheels):
            y = cur[j]
            a += y
            cur[j] = two_cos[j] * y - prev[j]
            prev[j] = y
        load[last] = a


@numba.njit(cache=True, fastmath=FAST)
def fastener_force(track, rail_disp, rail_vel, block_disp, block_vel):
    """Fastener force of one block mode, F̂ = K_r (b Q − s) + C_r (b Q̇ − ṡ) (N).

    ``rail_disp``, ``rail_vel``: Q, Q̇, the rail's displacement and velocity folded onto the
    block mode.
    """
    gain = track.block_gain
    return track.fastener_k * (gain * rail_disp - block_disp) + track.fastener_c * (
        gain * rail_vel - block_vel
    )


@numba.njit(cache=True, fastmath=FAST)
def unpaired_rail_modes(track, state, modal_load, fold_disp, fold_vel, step):
    """Rail modes k ≥ N − 1 (N_m ≥ N), before :func:`paired_modes` moves the others.

    Folds their displacements and velocities onto the block modes ρ_k they meet, with sign σ_k
    (``fold_disp``, ``fold_vel``: the sums over these modes only, zero at every block mode none
    of them meets), then sets their accelerations (with the fastener force of block mode ρ_k)
    and takes them to t + Δt with Zhai's predictor (``step`` = (Δt, φ, ψ); Δt = 0 leaves them).

    Returns
    -------
    float
        Their part of the rail displacement at the monitored block, Σ_k Y_k(x_b) q_k.
    """
    q, qd, qdd = state.q, state.qd, state.qdd
    s, sd = state.s, state.sd
    fold_index, fold_sign = track.fold_index, track.fold_sign
    dt, phi, psi = step
    n_paired = min(q.size, s.size)
    for k in range(n_paired, q.size):
        if fold_index[k] >= 0:
            fold_disp[fold_index[k]] = 0.0
            fold_vel[fold_index[k]] = 0.0
    for k in range(n_paired, q.size):
        if fold_index[k] >= 0:
            fold_disp[fold_index[k]] += fold_sign[k] * q[k]
            fold_vel[fold_index[k]] += fold_sign[k] * qd[k]
    z_rail = 0.0
    for k in range(n_paired, q.size):
        rail_acc = modal_load[k] - track.omega2[k] * q[k]
        r = fold_index[k]
        if r >= 0:
            force = fastener_force(track, q[r] + fold_disp[r], qd[r] + fold_vel[r], s[r], sd[r])
            rail_acc -= fold_sign[k] * track.block_gain * force
        z_rail += track.monitored_rail_shapes[k] * q[k]
        q[k], qd[k] = zhai_update(q[k], qd[k], rail_acc, qdd[k], dt, phi, psi)
        qdd[k] = rail_acc
    return z_rail


@numba.njit(cache=True, fastmath=FAST)
def paired_modes(track, state, modal_load, fold_disp, fold_vel, sums, step):
    """Rail mode r and block mode r, r < min(N_m, N − 1) (ρ = r, σ = +1): accelerations,
    monitored sums, and Zhai's predictor over ``step`` = (Δt, φ, ψ) (Δt = 0 leaves the state).

    ``fold_disp``, ``fold_vel``: what the rail modes k ≥ N − 1 add to the rail's displacement and
    velocity on each block mode (:func:`unpaired_rail_modes`). The accelerations a_n replace
    a_{n−1} in qdd and sdd. The loop has no branch, so it vectorises.
    """
    q, qd, qdd = state.q, state.qd, state.qdd
    s, sd, sdd = state.s, state.sd, state.sdd
    omega2, gain = track.omega2, track.block_gain
    pad_k, pad_c = track.pad_k, track.pad_c
    inv_block_mass = 1.0 / track.block_mass
    block_weight, rail_weight = track.monitored_block_weights, track.monitored_rail_shapes
    dt, phi, psi = step
    z_rail = 0.0
    z_block = 0.0
    v_block = 0.0
    for r in range(min(q.size, s.size)):
        rail_disp, rail_vel, block_disp, block_vel = q[r], qd[r], s[r], sd[r]
        force = fastener_force(
            track, rail_disp + fold_disp[r], rail_vel + fold_vel[r], block_disp, block_vel
        )
        rail_acc = modal_load[r] - omega2[r] * rail_disp - gain * force
        block_acc = (force - pad_k * block_disp - pad_c * block_vel) * inv_block_mass
        z_rail += rail_weight[r] * rail_disp
        z_block += block_weight[r] * block_disp
        v_block += block_weight[r] * block_vel
        q[r], qd[r] = zhai_update(rail_disp, rail_vel, rail_acc, qdd[r], dt, phi, psi)
        s[r], sd[r] = zhai_update(block_disp, block_vel, block_acc, sdd[r], dt, phi, psi)
        qdd[r] = rail_acc
        sdd[r] = block_acc
    sums[0] += z_rail
    sums[1] += z_block
    sums[2] += v_block


@numba.njit(cache=True, fastmath=FAST)
def unpaired_block_modes(track, state, sums, step):
    """Block modes r ≥ N_m (N_m < N − 1), which no rail mode meets: accelerations, monitored
    sums and Zhai's predictor."""
    s, sd, sdd = state.s, state.sd, state.sdd
    block_weight = track.monitored_block_weights
    dt, phi, psi = step
    for r in range(min(state.q.size, s.size), s.size):
        block_acc = (
            -(track.fastener_k + track.pad_k) * s[r] - (track.fastener_c + track.pad_c) * sd[r]
        ) / track.block_mass
        sums[1] += block_weight[r] * s[r]
        sums[2] += block_weight[r] * sd[r]
        s[r], sd[r] = zhai_update(s[r], sd[r], block_acc, sdd[r], dt, phi, psi)
        sdd[r] = block_acc


@numba.njit(cache=True, fastmath=FAST)
def accelerations(t, state, track, vehicle, wheels, scratch, step):
    """Accelerations of the whole system at time t, then the track's predictor step.

    Sets qdd, sdd, udd (udd's previous values move to udd_prev when the vehicle is
    advanced), the wheel forces and compressions in ``scratch`` and the monitored rail and
    block displacements and block velocity in ``scratch.monitored``. With ``step`` =
    (Δt, φ, ψ), Zhai's predictor then takes the rail and block modal coordinates to t + Δt in
    the same pass over the modes (Δt = 0 leaves them: the update is then exactly zero; the
    vehicle's predictor is :func:`zhai_predict`).

    ``wheels.prescribed_load`` (n_wheels,) replaces the Hertz law when its first entry is ≥ 0:
    the moving-constant-load model, with the vehicle at rest (ü = 0, δ reported as 0). It is
    [-1.0] for the coupled vehicle.
    """
    q = state.q
    u, ud, udd = state.u, state.ud, state.udd
    wheel_x0, speed, prescribed_load = wheels.x0, wheels.speed, wheels.prescribed_load
    rail_at_wheel, modal_load = scratch.rail_at_wheel, scratch.modal_load
    wheel_x, compression, wheel_force = scratch.wheel_x, scratch.compression, scratch.wheel_force
    two_cos, first = scratch.two_cos, scratch.wheel_first
    prev, cur = scratch.wheel_prev, scratch.wheel_cur
    offset_cos, offset_sin = scratch.offset_cos, scratch.offset_sin
    n_wheels = wheel_x0.size
    n_dof = vehicle.inv_mass.shape[1]
    wheel_dof = vehicle.wheel_dof
    wheels_per_car = wheel_dof.shape[1]

    # Rail under the wheels, Z_r(x_j) = Σ_k q_k Y_k(x_j), Y_k(x) = A sin(kθ), θ = πx/L. Every
    # wheel moves at the same speed, so θ_j = θ_0 + Δ_j with fixed offsets Δ_j: two
    # trigonometric calls per step, cos and sin of θ_j by the addition formula.
    theta = track.wavenumber_unit * (wheel_x0[0] + speed * t)
    cos_lead, sin_lead = math.cos(theta), math.sin(theta)
    for j in range(n_wheels):
        wheel_x[j] = wheel_x0[j] + speed * t
        two_cos[j] = 2.0 * (cos_lead * offset_cos[j] - sin_lead * offset_sin[j])
        first[j] = track.mode_amplitude * (sin_lead * offset_cos[j] + cos_lead * offset_sin[j])
    sine_series_at_wheels(q, two_cos, first, prev, cur, rail_at_wheel)

    if prescribed_load[0] >= 0.0:  # moving constant loads, no vehicle
        for j in range(n_wheels):
            compression[j] = 0.0
            wheel_force[j] = prescribed_load[j]
        for i in range(udd.size):
            udd[i] = 0.0
    else:
        # Wheel–rail contact: δ = Z_w − Z_r(x_w) − η(x_w)
        for car in range(wheel_dof.shape[0]):  # nested loops: no integer division per wheel
            for w in range(wheels_per_car):
                j = car * wheels_per_car + w
                eta = profile_at(wheels.eta_grid, wheels.eta_start, wheels.eta_step, wheel_x[j])
                compression[j] = u[car * n_dof + wheel_dof[car, w]] - rail_at_wheel[j] - eta
                wheel_force[j] = hertz_force(compression[j], wheels.hertz_constant)
        vehicle_accelerations(u, ud, udd, vehicle, wheel_force)

    # Modal wheel loads Σ_j p_j Y_k(x_j)
    for j in range(n_wheels):
        first[j] *= wheel_force[j]
    modal_loads(two_cos, first, prev, cur, modal_load)

    # Track: rail mode k < N meets block mode k alone; modes k ≥ N fold onto the block modes
    # (none with the default N_m = N). Every acceleration uses the state at t, so the unpaired
    # rail modes are folded and advanced first.
    monitored = scratch.monitored
    monitored[:] = 0.0
    z_unpaired = unpaired_rail_modes(
        track, state, modal_load, scratch.fold_disp, scratch.fold_vel, step
    )
    paired_modes(track, state, modal_load, scratch.fold_disp, scratch.fold_vel, monitored, step)
    monitored[0] += z_unpaired
    unpaired_block_modes(track, state, monitored, step)


@numba.njit(cache=True, nogil=True)  # releases the GIL: a served dashboard stays responsive
def advance(
    out_start,
    out_stop,
    n_steps,
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
    """Outputs ``out_start`` … ``out_stop`` − 1 of a run of ``n_steps`` steps of Zhai's method.

    At output n the accelerations at t_n = n·dt are evaluated and recorded, then (n < n_steps)
    Zhai's predictor takes the state to t_{n+1}, with φ = ψ = 0 from n = 0; output 0 is the
    initial state. Loss of contact is logged in ``contact.events`` (rows: wheel, t_start,
    x_start, t_end; ``contact.in_contact`` starts True, so a wheel off the rail at t = 0 opens
    an event at 0) while ``contact.event_count[0]`` counts all of them.

    Returns
    -------
    int
        ``RUNNING`` (−1) if all outputs were computed, else the index of the first output at
        which the response diverged (non-finite, or a wheel–rail compression beyond
        ``divergence_limit`` m; a gap of any size is a wheel in flight, not divergence);
        outputs from that index on are not valid.
    """
    n_wheels = wheels.x0.size
    compression, wheel_force, wheel_x = scratch.compression, scratch.wheel_force, scratch.wheel_x
    in_contact, open_event = contact.in_contact, contact.open_event
    events, event_count = contact.events, contact.event_count
    event_capacity = events.shape[0]
    block_force = outputs.block_force

    for out in range(out_start, out_stop):
        t = out * dt
        step_dt = dt if out < n_steps else 0.0
        step_phi = 0.0 if out == 0 else phi
        step_psi = 0.0 if out == 0 else psi
        accelerations(t, state, track, vehicle, wheels, scratch, (step_dt, step_phi, step_psi))
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
        if step_dt > 0.0:
            zhai_predict(state.u, state.ud, state.udd, state.udd_prev, dt, step_phi, step_psi)
    return RUNNING


@numba.njit(cache=True, fastmath=FAST)
def record(out, state, track, vehicle, scratch, outputs):
    """Write the monitored quantities at output index ``out`` (after :func:`accelerations`)."""
    udd, monitored = state.udd, scratch.monitored
    outputs.rail_disp[out] = monitored[0]
    outputs.block_disp[out] = monitored[1]
    outputs.block_force[out] = track.pad_k * monitored[1] + track.pad_c * monitored[2]
    n_dof = vehicle.inv_mass.shape[1]
    wheel_dof = vehicle.wheel_dof
    wheels_per_car = wheel_dof.shape[1]
    wheel_force = scratch.wheel_force
    for car in range(wheel_dof.shape[0]):
        for w in range(wheels_per_car):
            j = car * wheels_per_car + w
            outputs.wheel_force[j, out] = wheel_force[j]
            outputs.wheel_acc[j, out] = udd[car * n_dof + wheel_dof[car, w]]
    body_acc = outputs.body_acc
    for car in range(body_acc.shape[0]):
        body_acc[car, out] = udd[car * n_dof + vehicle.body_dof]


# winkler_shape_sum: samples between exact evaluations of e^{−ξ}(cos ξ + sin ξ); in between a
# complex multiplication per sample, whose rounding (~1e-16 each) stays below 1e-14 of the peak.
WINKLER_ANCHOR_SAMPLES = 32


@numba.njit(cache=True, nogil=True)
def winkler_shape_sum(t_start, t_step, n_samples, pass_times, decay_rate, reach):
    """Σ_j e^{−ξ_j}(cos ξ_j + sin ξ_j), ξ_j = decay_rate·|t − t_j|, at t = t_start + n·t_step.

    Each pass time t_j contributes where ξ_j < ``reach``. On either side of t_j the samples of
    e^{(−1+i)ξ} form a geometric sequence (ratio e^{(−1+i)·decay_rate·t_step}), whose real plus
    imaginary part is the term; it is evaluated exactly every ``WINKLER_ANCHOR_SAMPLES``.
    """
    out = np.zeros(n_samples)
    a = decay_rate * t_step
    ratio = complex(math.exp(-a) * math.cos(a), math.exp(-a) * math.sin(a))
    for t_pass in pass_times:
        centre = (t_pass - t_start) / t_step
        for direction in (1, -1):
            n = math.ceil(centre) if direction > 0 else math.ceil(centre) - 1
            count = 0
            term = 0j
            while 0 <= n < n_samples:
                xi = a * abs(n - centre)
                if xi >= reach:
                    break
                if count % WINKLER_ANCHOR_SAMPLES == 0:
                    decay = math.exp(-xi)
                    term = complex(decay * math.cos(xi), decay * math.sin(xi))
                out[n] += term.real + term.imag
                term *= ratio
                count += 1
                n += direction
    return out
