"""The Numba kernels against the plain-NumPy implementation of the same equations
(tests/vehicle_track_numpy.py): two independent codings must give the same histories."""

from __future__ import annotations

import numpy as np
import pytest
from vehicle_track_numpy import integrate_numpy

from model.params import Scenario
from model.track import assembly
from model.track import vehicle_track as vt


@pytest.mark.parametrize(
    ("preset", "n_steps", "modes_per_spacing"),
    [
        ("single_bogie", None, None),
        ("paper", 1500, None),
        ("single_bogie", 2000, 2.05),
        ("single_bogie", 2000, 0.6),
    ],
)
def test_kernels_equal_the_plain_numpy_stepping(preset, n_steps, modes_per_spacing):
    """Single bogie, whole passage (FRA class 6, 80 km/h), and the first 0.15 s of the six-car
    train: the invert force, the rail under the monitored block and every wheel force agree to
    1e-11 of their largest values (measured 2e-14 to 9e-13: rounding, the kernels sum in
    another order). Also 2000 steps of the single bogie with N_m = 2.05 N (rail modes k ≥ N
    folded onto the block modes, modes N and 2N meeting none) and 0.6 N (block modes that no
    rail mode meets), at the estimated stable step."""
    scenario = Scenario.preset(preset)
    dt = scenario.numerics.dt
    if modes_per_spacing is not None:
        n = round(scenario.rail_length / scenario.track.block_spacing)
        scenario.numerics.n_rail_modes = round(modes_per_spacing * n)
        dt = vt.stable_time_step(scenario)
    n_steps = n_steps or vt.n_time_steps(scenario)
    track, vehicle = assembly.assemble_track(scenario), assembly.assemble_vehicle(scenario)
    wheels = assembly.assemble_wheels(scenario, vt.n_time_steps(scenario) * dt)
    state = assembly.static_equilibrium(scenario, track, vehicle, wheels)
    reference = integrate_numpy(track, vehicle, wheels, state, n_steps, dt)
    run = vt.integrate(track, vehicle, wheels, state, n_steps, dt)
    assert run.diverged is None
    for name in ("block_force", "rail_disp", "wheel_force"):
        ours, theirs = getattr(run.outputs, name), reference[name]
        assert ours.shape == theirs.shape
        np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-11 * np.abs(theirs).max())
