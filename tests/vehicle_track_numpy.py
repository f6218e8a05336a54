"""The vehicle–track time stepping written the plain-NumPy way: a second implementation.

The same equations as the Numba kernels of ``model/track/kernels.py`` (docs/vehicle_track.md):
rail modes Y_k(x) = A sin(kπx/L) on block modes through the fold ρ(k), σ_k; per-car vehicle
matrices; Hertz contact on the interpolated irregularity; Zhai's explicit method (φ = ψ = 0 on
the first step). Each step is a handful of whole-array expressions: the mode shapes under the
wheels by ``np.sin`` of the (N_m × n_wheels) phase table, the two wheel–mode sums as
matrix–vector products, the vehicle's K u + C u̇ with ``np.einsum``.

It serves two purposes: ``tests/test_vehicle_track_numpy.py`` checks the kernels against it,
and ``benchmarks/bench_vehicle_track.py --ratio`` times the kernels against it on the same job
(the "plain-NumPy baseline" of issue 27). Coupled vehicles only (no prescribed loads), no
contact-loss log, no divergence check.
"""

from __future__ import annotations

import numpy as np

from model.track.assembly import SystemState, TrackSystem, VehicleSystem, WheelInputs


def integrate_numpy(
    track: TrackSystem,
    vehicle: VehicleSystem,
    wheels: WheelInputs,
    state: SystemState,
    n_steps: int,
    dt: float,
    phi: float = 0.5,
    psi: float = 0.5,
) -> dict[str, np.ndarray]:
    """Zhai's method for ``n_steps`` from ``state`` (not modified); recorded histories.

    Returns
    -------
    dict
        ``block_force``, ``block_disp``, ``rail_disp`` (n_steps + 1,) and ``wheel_force``
        (n_wheels, n_steps + 1), as in :class:`model.track.assembly.Outputs` (SI, down +).
    """
    q, qd, s, sd = (a.copy() for a in (state.q, state.qd, state.s, state.sd))
    u, ud = state.u.copy(), state.ud.copy()
    n_cars, n_dof = vehicle.inv_mass.shape
    wheel_dofs = (np.arange(n_cars)[:, None] * n_dof + vehicle.wheel_dof).ravel()
    mode_numbers = np.arange(1, q.size + 1)
    meets = track.fold_index >= 0
    fold_index, fold_sign = track.fold_index[meets], track.fold_sign[meets]
    gain = track.block_gain
    nt = n_steps + 1
    out = {name: np.zeros(nt) for name in ("block_force", "block_disp", "rail_disp")}
    out["wheel_force"] = np.zeros((wheels.x0.size, nt))

    def accelerations(t):
        x = wheels.x0 + wheels.speed * t
        shapes = track.mode_amplitude * np.sin(np.outer(mode_numbers, x) * track.wavenumber_unit)
        compression = u[wheel_dofs] - q @ shapes - wheels.profile(x)
        ratio = np.maximum(compression, 0.0) / wheels.hertz_constant
        force = ratio * np.sqrt(ratio)  # Hertz, zero off the rail
        car_u, car_ud = u.reshape(n_cars, n_dof), ud.reshape(n_cars, n_dof)
        load = vehicle.gravity_force - np.einsum("cij,cj->ci", vehicle.stiffness, car_u)
        load -= np.einsum("cij,cj->ci", vehicle.damping, car_ud)
        load = load.ravel()
        load[wheel_dofs] -= force
        udd = load * vehicle.inv_mass.ravel()
        rail_on_blocks = np.bincount(fold_index, fold_sign * q[meets], minlength=s.size)
        rail_rate_on_blocks = np.bincount(fold_index, fold_sign * qd[meets], minlength=s.size)
        fastener = track.fastener_k * (gain * rail_on_blocks - s) + track.fastener_c * (
            gain * rail_rate_on_blocks - sd
        )
        qdd = shapes @ force - track.omega2 * q
        qdd[meets] -= gain * fold_sign * fastener[fold_index]
        sdd = (fastener - track.pad_k * s - track.pad_c * sd) / track.block_mass
        return qdd, sdd, udd, force

    previous = None  # the accelerations of the step before
    for n in range(nt):
        qdd, sdd, udd, force = accelerations(n * dt)
        out["rail_disp"][n] = track.monitored_rail_shapes @ q
        out["block_disp"][n] = track.monitored_block_weights @ s
        block_rate = track.monitored_block_weights @ sd
        out["block_force"][n] = track.pad_k * out["block_disp"][n] + track.pad_c * block_rate
        out["wheel_force"][:, n] = force
        if n == n_steps:
            break
        step_phi, step_psi = (0.0, 0.0) if previous is None else (phi, psi)
        before = (qdd, sdd, udd) if previous is None else previous
        for x, v, a, a_prev in zip((q, s, u), (qd, sd, ud), (qdd, sdd, udd), before, strict=True):
            x += v * dt + (0.5 + step_psi) * a * dt**2 - step_psi * a_prev * dt**2
            v += (1.0 + step_phi) * a * dt - step_phi * a_prev * dt
        previous = (qdd, sdd, udd)
    return out
