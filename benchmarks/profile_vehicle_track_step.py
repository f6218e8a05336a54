"""Per-step profile of the six-car passage (paper preset): each kernel of the step timed alone.

Run: ``python benchmarks/profile_vehicle_track_step.py``. Times, best of 20 batches of 2 000
calls (short batches, so that other jobs on the machine rarely interrupt the best one), the two
wheel loops (``sine_series_at_wheels``, ``modal_loads``) on the paper's 528 modes and 24 wheels,
the track's mode loops (``unpaired_rail_modes``, ``paired_modes``, ``unpaired_block_modes``;
Δt = 0, which leaves the state as it is at the full cost of the predictor),
``vehicle_accelerations`` and the whole ``accelerations`` (Δt = 0). Compare with the time per
step of ``bench_vehicle_track.py``; the difference is the vehicle's predictor, ``record`` and
the contact bookkeeping of ``advance``.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numba
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from model.params import Scenario  # noqa: E402
from model.track import assembly  # noqa: E402
from model.track import kernels as K  # noqa: E402
from model.track import vehicle_track as vt  # noqa: E402
from model.track.assembly import Scratch  # noqa: E402

NO_STEP = (0.0, 0.0, 0.0)


@numba.njit
def _series(n, c, two_cos, first, prev, cur, total):
    for _ in range(n):
        K.sine_series_at_wheels(c, two_cos, first, prev, cur, total)


@numba.njit
def _loads(n, two_cos, first, prev, cur, load):
    for _ in range(n):
        K.modal_loads(two_cos, first, prev, cur, load)


@numba.njit
def _modes(n, track, st, sc):
    for _ in range(n):
        K.unpaired_rail_modes(track, st, sc.modal_load, sc.fold_disp, sc.fold_vel, NO_STEP)
        K.paired_modes(track, st, sc.modal_load, sc.fold_disp, sc.fold_vel, sc.monitored, NO_STEP)
        K.unpaired_block_modes(track, st, sc.monitored, NO_STEP)


@numba.njit
def _vehicle(n, st, veh, sc):
    for _ in range(n):
        K.vehicle_accelerations(st.u, st.ud, st.udd, veh, sc.wheel_force)


@numba.njit
def _accelerations(n, track, st, veh, wh, sc):
    for _ in range(n):
        K.accelerations(0.3, st, track, veh, wh, sc, NO_STEP)


def main() -> None:
    s = Scenario.preset("paper")
    dt, n_steps = s.numerics.dt, vt.n_time_steps(s)
    track, veh = assembly.assemble_track(s), assembly.assemble_vehicle(s)
    wh = assembly.assemble_wheels(s, n_steps * dt)
    st = assembly.static_equilibrium(s, track, veh, wh)
    nw, nm, nb = wh.x0.size, track.omega2.size, track.n_spacings - 1
    off = track.wavenumber_unit * (wh.x0 - wh.x0[0])
    sc = Scratch(
        modal_load=np.zeros(nm),
        offset_cos=np.cos(off),
        offset_sin=np.sin(off),
        two_cos=np.empty(nw),
        wheel_first=np.empty(nw),
        wheel_prev=np.empty(nw),
        wheel_cur=np.empty(nw),
        rail_at_wheel=np.empty(nw),
        fold_disp=np.zeros(nb),
        fold_vel=np.zeros(nb),
        wheel_x=np.empty(nw),
        compression=np.empty(nw),
        wheel_force=np.empty(nw),
        monitored=np.zeros(3),
    )
    rng = np.random.default_rng(0)
    theta = rng.uniform(0.3, 2.8, nw)
    two_cos, first, coeff = 2 * np.cos(theta), np.sin(theta), rng.standard_normal(nm)
    prev, cur, total, load = np.zeros(nw), np.zeros(nw), np.zeros(nw), np.zeros(nm)
    cases = (
        ("sine_series_at_wheels", _series, (coeff, two_cos, first, prev, cur, total)),
        ("modal_loads", _loads, (two_cos, first, prev, cur, load)),
        ("track mode loops (dt = 0)", _modes, (track, st, sc)),
        ("vehicle_accelerations", _vehicle, (st, veh, sc)),
        ("accelerations, all of it (dt = 0)", _accelerations, (track, st, veh, wh, sc)),
    )
    n = 2000
    print(f"{nm} modes, {nw} wheels, {nb} block modes; best of 20 × {n} calls")
    for name, function, args in cases:
        function(5, *args)
        best = np.inf
        for _ in range(20):
            start = time.perf_counter()
            function(n, *args)
            best = min(best, time.perf_counter() - start)
        print(f"  {name}: {best / n * 1e6:.2f} µs per call")


if __name__ == "__main__":
    main()
