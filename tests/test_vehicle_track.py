"""Vehicle–track model (docs/model.md §1–6): closed forms first, then convergence, then the paper's
qualitative claims. Most runs use the single bogie (64.8 m rail, 108 modes, ~10 k steps, a few
ms each once compiled); the six-car train is run once per module.
"""

import math

import numba
import numpy as np
import pytest
from scipy.signal import find_peaks

import model.track.irregularity
from model.params import Scenario, ScenarioError
from model.track import assembly, kernels
from model.track import vehicle_track as vt
from model.track.vehicle_track import check_inputs, simulate, stable_time_step

TABLE_1_WHEEL_LOAD = 61.1e3  # N, paper Table 1 (axle 122 kN)


def smooth_single_bogie(speed_kmh=80.0, **numerics) -> Scenario:
    """The paper's single bogie on a smooth rail."""
    scenario = Scenario.preset("single_bogie")
    scenario.irregularity.enabled = False
    scenario.train.speed_kmh = speed_kmh
    scenario.numerics.param.update(**numerics)
    return scenario


def zimmermann_rail_deflection(scenario: Scenario, t_s: np.ndarray) -> np.ndarray:
    """Rail deflection (m) above the monitored block: Winkler beam, static wheel loads superposed.

    w(ξ) = (Pβ/2k) e^{−β|ξ|}(cos β|ξ| + sin β|ξ|), written out here from β and k of the track.
    """
    track, train = scenario.track, scenario.train
    beta, k = track.winkler_beta, track.winkler_modulus
    x_block = 0.5 * scenario.rail_length
    x0 = x_block - scenario.numerics.approach_distance - np.asarray(train.axle_offsets)
    xi = beta * np.abs(x0[:, None] + train.speed * t_s[None, :] - x_block)
    load = scenario.vehicle.static_wheel_load
    return (load * beta / (2 * k) * np.exp(-xi) * (np.cos(xi) + np.sin(xi))).sum(axis=0)


@pytest.fixture(scope="module")
def train_run():
    """Six-car train on a smooth rail at 80 km/h (66.6 k steps)."""
    scenario = Scenario.paper()
    scenario.irregularity.enabled = False
    return scenario, simulate(scenario)


@pytest.fixture(scope="module")
def bogie_run():
    """Single bogie on a smooth rail at 80 km/h."""
    scenario = smooth_single_bogie()
    return scenario, simulate(scenario)


# ---- statics ---------------------------------------------------------------------------------
@pytest.mark.parametrize("single_bogie", [True, False])
def test_static_wheel_loads_are_table_1(single_bogie):
    """Every wheel carries (M_c + 2M_t + 4M_w) g / 8 = 61.14 kN: Table 1's 61.1 kN to its
    printed precision (±0.05 kN); equal to Vehicle.static_wheel_load to rounding (1e-12)."""
    scenario = Scenario.paper()
    scenario.train.single_bogie = single_bogie
    loads = assembly.static_wheel_loads(
        assembly.assemble_vehicle(scenario), assembly.assemble_wheels(scenario, 1.0)
    )
    assert loads.size == scenario.train.n_wheels
    np.testing.assert_allclose(loads, scenario.vehicle.static_wheel_load, rtol=1e-12)
    assert loads[0] == pytest.approx(TABLE_1_WHEEL_LOAD, abs=50.0)


def test_vehicle_mass_and_gravity_are_the_halved_car():
    """One-rail model: the gravity forces of all DOFs add up to half the car's weight per car
    (a quarter car body for the single bogie), exactly."""
    scenario = Scenario.paper()
    veh = scenario.vehicle
    full = assembly.assemble_vehicle(scenario)
    car = veh.car_body_mass + 2 * veh.bogie_mass + 4 * veh.wheelset_mass
    np.testing.assert_allclose(full.gravity_force.sum(axis=1), car * 9.81 / 2, rtol=1e-14)
    scenario.train.single_bogie = True
    bogie = assembly.assemble_vehicle(scenario)
    expected = (veh.car_body_mass / 4 + veh.bogie_mass / 2 + veh.wheelset_mass) * 9.81
    assert bogie.gravity_force.sum() == pytest.approx(expected, rel=1e-14)


def dense_static_track(scenario: Scenario, wheel_x: np.ndarray, loads: np.ndarray):
    """Static rail modal coordinates and block displacements by one dense solve (no transform).

    Unknowns [q (N_m), Z_s (N−1)]: (diag ω² + K_r Φ Φᵀ) q − K_r Φ Z_s = Φ_w p,
    −K_r Φᵀ q + (K_r + K_s) Z_s = 0, with Φ_ki = Y_k(x_i) written out from docs/model.md §2.
    """
    tr = scenario.track
    length = scenario.rail_length
    n = round(length / tr.block_spacing)
    k = np.arange(1, scenario.rail_modes + 1)[:, None]

    def shapes(x):
        return math.sqrt(2 / (tr.rail_mass * length)) * np.sin(k * np.pi * x[None, :] / length)

    phi = shapes(tr.block_spacing * np.arange(1, n))
    omega2 = tr.rail_E * tr.rail_I / tr.rail_mass * (k[:, 0] * np.pi / length) ** 4
    kr, ks = tr.fastener_stiffness, tr.pad_stiffness
    matrix = np.block(
        [[np.diag(omega2) + kr * phi @ phi.T, -kr * phi], [-kr * phi.T, (kr + ks) * np.eye(n - 1)]]
    )
    rhs = np.concatenate([shapes(wheel_x) @ loads, np.zeros(n - 1)])
    solution = np.linalg.solve(matrix, rhs)
    return solution[: k.size], solution[k.size :]


@pytest.mark.parametrize("modes_per_spacing", [1.0, 1.5, 2.05])
def test_static_track_solution_equals_dense_solve(modes_per_spacing):
    """The block-modal static solve (modes folded onto N−1 block modes, O(N_m)) equals a dense
    solve of rail modes and blocks, for N_m = N, 1.5 N and 2.05 N (which includes the modes
    N and 2N that vanish at every block). Both are exact: tolerance 1e-9 of the peak."""
    scenario = smooth_single_bogie()
    n = round(scenario.rail_length / scenario.track.block_spacing)
    scenario.numerics.n_rail_modes = round(modes_per_spacing * n)
    track, wheels = assembly.assemble_track(scenario), assembly.assemble_wheels(scenario, 1.0)
    loads = assembly.static_wheel_loads(assembly.assemble_vehicle(scenario), wheels)
    q, s = assembly.track_equilibrium(track, track.mode_shapes(wheels.x0) @ loads)
    blocks = np.array([track.block_mode_weights(i) @ s for i in range(1, n)])
    q_dense, blocks_dense = dense_static_track(scenario, wheels.x0, loads)
    np.testing.assert_allclose(q, q_dense, atol=1e-9 * np.abs(q_dense).max())
    np.testing.assert_allclose(blocks, blocks_dense, atol=1e-9 * blocks_dense.max())


@pytest.mark.parametrize("modes_per_spacing", [1.0, 2.05])
def test_kernel_track_accelerations_equal_dense_equations(modes_per_spacing):
    """One evaluation of the kernel's accelerations for a random track state and prescribed
    wheel loads, against docs/model.md §2 written with dense matrices in physical block coordinates
    (Φ_ki = Y_k(x_i) by NumPy sines, Z_s = D s with D the orthonormal DST-I). Both exact:
    tolerance 1e-10 of the largest term."""
    scenario = smooth_single_bogie()
    n = round(scenario.rail_length / scenario.track.block_spacing)
    scenario.numerics.n_rail_modes = round(modes_per_spacing * n)
    loads = np.array([61e3, 55e3])
    tr, vehicle = assembly.assemble_track(scenario), assembly.assemble_vehicle(scenario)
    wheels = assembly.assemble_wheels(scenario, 1.0, prescribed_load_N=loads)
    rng = np.random.default_rng(7)
    state = assembly.static_equilibrium(scenario, tr, vehicle, wheels)
    for name in ("q", "qd", "s", "sd"):
        getattr(state, name)[:] = rng.standard_normal(getattr(state, name).size) * 1e-4
    before = {name: getattr(state, name).copy() for name in ("q", "qd", "s", "sd")}
    vt.integrate(tr, vehicle, wheels, state, 0, 1e-4)  # zero steps: accelerations at t = 0 only
    for name, values in before.items():  # the predictor runs with Δt = 0: exactly the identity
        np.testing.assert_array_equal(getattr(state, name), values)

    k = np.arange(1, tr.omega2.size + 1)[:, None]
    x_blocks = scenario.track.block_spacing * np.arange(1, n)
    phi = math.sqrt(2 / (scenario.track.rail_mass * tr.length)) * np.sin(
        k * np.pi * x_blocks[None, :] / tr.length
    )
    dst = math.sqrt(2 / n) * np.sin(np.outer(np.arange(1, n), np.arange(1, n)) * np.pi / n)
    y_wheels = math.sqrt(2 / (scenario.track.rail_mass * tr.length)) * np.sin(
        k * np.pi * wheels.x0[None, :] / tr.length
    )
    z_block, v_block = dst @ state.s, dst @ state.sd
    fastener = tr.fastener_k * (phi.T @ state.q - z_block) + tr.fastener_c * (
        phi.T @ state.qd - v_block
    )
    rail_acc = -tr.omega2 * state.q - phi @ fastener + y_wheels @ loads
    block_acc = (fastener - tr.pad_k * z_block - tr.pad_c * v_block) / tr.block_mass
    np.testing.assert_allclose(state.qdd, rail_acc, atol=1e-10 * np.abs(rail_acc).max())
    np.testing.assert_allclose(dst @ state.sdd, block_acc, atol=1e-10 * np.abs(block_acc).max())


def test_kernel_records_have_one_numba_type_across_scenarios():
    """The records reach the kernels as typed named tuples: two scenarios that differ in sizes
    and in values given as Python ints (speed 60, block mass 150), with or without prescribed
    loads, give the same Numba types, so the cached compiled kernels serve both (no
    recompilation per scenario)."""
    first, second = Scenario.paper(), smooth_single_bogie()
    second.train.speed_kmh = 60
    second.track.block_mass = 150
    for assemble in (
        assembly.assemble_track,
        assembly.assemble_vehicle,
        lambda s: assembly.assemble_wheels(s, 1.0),
    ):
        assert numba.typeof(assemble(first)) == numba.typeof(assemble(second))
    assert numba.typeof(assembly.assemble_wheels(second, 1.0)) == numba.typeof(
        assembly.assemble_wheels(second, 1.0, prescribed_load_N=[1000, 2000])
    )


@pytest.mark.parametrize("loads", [[1e3], [1e3, -1.0]])
def test_prescribed_loads_are_checked(loads):
    """One non-negative load per wheel, else ValueError naming the argument."""
    with pytest.raises(ValueError, match=r"prescribed_load_N = .* needs 2 loads ≥ 0 N"):
        assembly.assemble_wheels(smooth_single_bogie(), 1.0, prescribed_load_N=loads)


def test_hertz_law():
    """p = (δ/G)^{3/2} for δ > 0 and 0 otherwise (the wheel has left the rail)."""
    g = Scenario().track.hertz_constant
    load = 61140.825
    assert kernels.hertz_force(g * load ** (2 / 3), g) == pytest.approx(load, rel=1e-13)
    assert kernels.hertz_force(0.0, g) == 0.0
    assert kernels.hertz_force(-1e-6, g) == 0.0


def test_static_start_is_equilibrium_with_hertz_compression():
    """At t = 0 each wheel sits G p^{2/3} (≈ 81 µm, docs/model.md §3) into the rail and the vehicle
    is at rest: its accelerations are below 1e-6 g (the kernel's Chebyshev mode shapes agree
    with NumPy's sines to ~1e-13, i.e. force errors of ~1e-4 N)."""
    scenario = smooth_single_bogie()
    track, vehicle = assembly.assemble_track(scenario), assembly.assemble_vehicle(scenario)
    wheels = assembly.assemble_wheels(scenario, 1.0)
    state = assembly.static_equilibrium(scenario, track, vehicle, wheels)
    loads = assembly.static_wheel_loads(vehicle, wheels)
    rail = track.mode_shapes(wheels.x0).T @ state.q
    compression = state.u[[3, 4]] - rail
    np.testing.assert_allclose(compression, scenario.track.hertz_compression(loads), rtol=1e-12)
    assert compression[0] == pytest.approx(81e-6, abs=0.5e-6)
    out = vt.integrate(track, vehicle, wheels, state, 0, scenario.numerics.dt).outputs
    np.testing.assert_allclose(out.wheel_force[:, 0], loads, rtol=1e-9)
    assert np.max(np.abs(out.wheel_acc[:, 0])) < 1e-5
    assert np.max(np.abs(out.body_acc[:, 0])) < 1e-5


def test_winkler_block_displacement_sums_every_wheel_of_the_train():
    """The windowed sum (each wheel within WINKLER_REACH/β, by the anchored geometric
    recurrence) equals the sum of every wheel's deflection at every time to round-off: 1e-13 of
    the peak (each is 3e-14 of the peak from the sum in extended precision: the positions near
    160 m are rounded to 3e-14 m, which moves βξ by as much)."""
    scenario = Scenario.paper()
    t = np.linspace(0.0, scenario.passage_duration, 20_001)
    track = scenario.track
    dense = zimmermann_rail_deflection(scenario, t) * track.support_stiffness / track.pad_stiffness
    windowed = vt.winkler_block_displacement(scenario, t)
    assert np.max(np.abs(windowed - dense)) < 1e-13 * dense.max()


def test_quasi_static_passage_matches_static_load_and_winkler_beam():
    """Smooth rail at 20 km/h (wheel passing frequencies ≪ track resonances).

    - Contact force = static wheel load within 0.2 % (measured 0.09 %: the residue is the
      parametric excitation of the discrete supports at v/L_s = 9 Hz).
    - Rail deflection above the monitored block = Zimmermann's Winkler beam with both wheels
      superposed, within 2 % of the peak (measured 1.1 %). Error budget: discrete vs
      continuous support ±0.3 % (static solve with 4N modes: −0.2 % over a block, +0.3 %
      between blocks, βL_s = 0.68), mode truncation at N_m = N −0.6 %, dynamics < 0.3 %.
    - The block follows the Winkler block displacement (K_r/(K_r + K_s) of the rail) likewise.
    - Check values of docs/model.md §2: β = 1.14 1/m, 0.78 mm under one 61.1 kN wheel.
    """
    scenario = smooth_single_bogie(speed_kmh=20.0)
    result = simulate(scenario)
    load = scenario.vehicle.static_wheel_load
    assert np.max(np.abs(result.wheel_force_N / load - 1.0)) < 2e-3
    winkler = zimmermann_rail_deflection(scenario, result.t_s)
    assert np.max(np.abs(result.rail_disp_m - winkler)) < 0.02 * winkler.max()
    assert np.max(np.abs(result.block_disp_m - result.winkler_block_disp_m)) < (
        0.02 * result.winkler_block_disp_m.max()
    )
    track = scenario.track
    assert track.winkler_beta == pytest.approx(1.14, abs=0.005)
    assert load * track.winkler_beta / (2 * track.winkler_modulus) == pytest.approx(
        0.78e-3, abs=0.005e-3
    )
    assert not result.unstable and result.warnings == () and result.contact_loss.size == 0


def test_block_force_is_pad_force_of_block_motion(bogie_run):
    """block_force_N = K_s Z_s + C_s Ż_s (paper eq 39): with Ż_s by central differences of the
    recorded displacement, equal to 0.2 % of the peak (the difference quotient's O(Δt²) error
    on the ~2 ms-scale pulse)."""
    scenario, result = bogie_run
    track = scenario.track
    velocity = np.gradient(result.block_disp_m, result.t_s)
    expected = track.pad_stiffness * result.block_disp_m + track.pad_damping * velocity
    assert np.max(np.abs(result.block_force_N - expected)[1:-1]) < 2e-3 * expected.max()


# ---- moving load on a bare beam ----------------------------------------------------------------
def test_moving_constant_load_on_simply_supported_beam():
    """A constant 1 kN load crossing the bare simply supported rail (no supports, no vehicle)
    at 80 km/h, from the static deflection and its quasi-static rate.

    Exact modal solution, mode by mode: q̈ + ω²q = P Y_k(x0 + vt) gives
    q = P A sin(Ωt + φ)/(ω² − Ω²) + a cos ωt + b sin ωt with Ω = kπv/L, φ = kπx0/L and a, b
    from q(0), q̇(0). The first mode is supercritical (Ω₁/ω₁ = 1.4), so the record holds free
    vibration, not just the static shape. Same 108 modes: the difference is the integration
    error only, O((ω_k Δt)²) weighted by the mode's share; measured 2e-9 of the peak, tolerance
    1e-7.
    """
    scenario = smooth_single_bogie()
    dt = scenario.numerics.dt
    n_steps = vt.n_time_steps(scenario)
    load = 1000.0
    # no supports: the series support stiffness goes with the fastener
    track = assembly.assemble_track(scenario)._replace(
        fastener_k=0.0, fastener_c=0.0, support_k=0.0
    )
    vehicle = assembly.assemble_vehicle(scenario)
    wheels = assembly.assemble_wheels(scenario, n_steps * dt, prescribed_load_N=[load, 0.0])
    state = assembly.static_equilibrium(scenario, track, vehicle, wheels)
    run = vt.integrate(track, vehicle, wheels, state, n_steps, dt)
    assert run.diverged is None

    tr = scenario.track
    length = scenario.rail_length
    k = np.arange(1, scenario.rail_modes + 1)
    amp = math.sqrt(2 / (tr.rail_mass * length))
    omega = np.sqrt(tr.rail_E * tr.rail_I / tr.rail_mass) * (k * np.pi / length) ** 2
    forcing = k * np.pi * scenario.train.speed / length
    phase = k * np.pi * wheels.x0[0] / length
    steady = load * amp / (omega**2 - forcing**2)
    q0 = load * amp * np.sin(phase) / omega**2
    qd0 = scenario.train.speed * load * amp * (k * np.pi / length) * np.cos(phase) / omega**2
    a = q0 - steady * np.sin(phase)
    b = (qd0 - steady * forcing * np.cos(phase)) / omega
    t = dt * np.arange(n_steps + 1)[None, :]
    q = (
        steady[:, None] * np.sin(forcing[:, None] * t + phase[:, None])
        + a[:, None] * np.cos(omega[:, None] * t)
        + b[:, None] * np.sin(omega[:, None] * t)
    )
    midspan = amp * np.sin(k * np.pi / 2) @ q
    assert forcing[0] / omega[0] > 1.2
    np.testing.assert_allclose(run.outputs.rail_disp, midspan, rtol=0, atol=1e-7 * midspan.max())
    np.testing.assert_array_equal(run.outputs.block_disp, 0.0)


# ---- convergence -----------------------------------------------------------------------------
@pytest.fixture(scope="module")
def convergence_runs():
    """Peak invert force of the single bogie at 80 km/h on the FRA class 6 rail (the paper's
    case) for several (modes per block spacing, Δt)."""
    peaks = {}
    for per_spacing, dt in [(0.5, 1e-4), (1.0, 1e-4), (1.0, 5e-5), (1.5, 5e-5), (2.0, 2.5e-5)]:
        scenario = Scenario.preset("single_bogie")
        n = round(scenario.rail_length / scenario.track.block_spacing)
        scenario.numerics.n_rail_modes = round(per_spacing * n)
        scenario.numerics.dt = dt
        result = simulate(scenario)
        assert not result.unstable
        peaks[per_spacing, dt] = result.block_force_N.max()
    return peaks


def test_halving_the_time_step_changes_the_peak_invert_force_below_1_percent(convergence_runs):
    """Δt = 1e-4 → 5e-5 s at N_m = L/L_s: < 1 % (measured 2e-7)."""
    coarse, fine = convergence_runs[1.0, 1e-4], convergence_runs[1.0, 5e-5]
    assert abs(coarse / fine - 1.0) < 0.01


def test_more_rail_modes_change_the_peak_invert_force_below_1_percent(convergence_runs):
    """N_m = L/L_s against 1.5 and 2 L/L_s (at smaller stable Δt): < 1 % (measured 0.7 %);
    the finer pair agrees to 0.1 % (measured 0.03 %), so 2 L/L_s is converged."""
    default, finer, finest = (
        convergence_runs[1.0, 5e-5],
        convergence_runs[1.5, 5e-5],
        convergence_runs[2.0, 2.5e-5],
    )
    assert abs(default / finest - 1.0) < 0.01
    assert abs(finer / finest - 1.0) < 0.001


def test_paper_mode_rule_underestimates_the_peak_invert_force(convergence_runs):
    """docs/model.md §2: the paper's N_m = 0.5 L/L_s is about 7 % low (measured 7.7 %); asserted
    between 4 and 12 %, which N_m = L/L_s (0.7 %) is not."""
    shortfall = 1.0 - convergence_runs[0.5, 1e-4] / convergence_runs[2.0, 2.5e-5]
    assert 0.04 < shortfall < 0.12


# ---- full train ------------------------------------------------------------------------------
def test_full_train_shows_every_axle_at_its_pass_time(train_run):
    """Smooth rail, six cars at 80 km/h: the invert force has one maximum per axle (24; the
    wheels of a bogie are 2.4 m apart, βa = 2.7, so each makes its own hump), each within
    4 ms (9 cm of travel) of the time the train geometry gives for that axle. The offset has
    two known parts: the neighbouring wheel pulls the quasi-static maximum ±1.2–1.7 ms toward
    the bogie centre, and the pad damping advances the force by about C_s/K_s = 2 ms."""
    scenario, result = train_run
    force = result.block_force_N
    peaks, _ = find_peaks(force, height=0.5 * force.max())
    assert peaks.size == scenario.train.n_wheels == 24
    expected = (
        scenario.numerics.approach_distance + np.asarray(scenario.train.axle_offsets)
    ) / scenario.train.speed
    np.testing.assert_allclose(result.axle_pass_times_s, expected, rtol=1e-12)
    np.testing.assert_allclose(result.t_s[peaks], expected, atol=4e-3)
    assert not result.unstable and result.contact_loss.size == 0


def test_full_train_first_bogie_equals_single_bogie(train_run, bogie_run):
    """Until the second bogie comes near (t ≤ 0.8 s, it is then > 7 m from the block, where
    the Winkler influence is e^{−8} ≈ 3e-4), the full train's invert force equals the single
    bogie's within 0.3 % of the peak (measured 0.1 %: the whole car body pitches, the half body
    of the single bogie does not)."""
    _, train = train_run
    _, bogie = bogie_run
    window = bogie.t_s <= 0.8
    np.testing.assert_allclose(
        train.block_force_N[: bogie.t_s.size][window],
        bogie.block_force_N[window],
        rtol=0,
        atol=3e-3 * bogie.block_force_N.max(),
    )


def test_result_shapes_and_fields(train_run):
    scenario, result = train_run
    nt = result.t_s.size
    assert nt == math.ceil(scenario.passage_duration / scenario.numerics.dt - 1e-9) + 1
    assert result.wheel_force_N.shape == result.wheel_acc_m_s2.shape == (24, nt)
    assert result.car_body_acc_m_s2.shape == (6, nt)
    for name in ("block_force_N", "block_disp_m", "rail_disp_m", "winkler_block_disp_m"):
        assert getattr(result, name).shape == (nt,)
        assert np.all(np.isfinite(getattr(result, name)))
    assert result.monitored_block_x_m == pytest.approx(0.5 * scenario.rail_length)
    assert result.rail_length_m == pytest.approx(316.8) and result.n_rail_modes == 528
    assert result.contact_loss.dtype == vt.CONTACT_EVENT_DTYPE


# ---- the paper's qualitative claims ------------------------------------------------------------
@pytest.fixture(scope="module")
def rough_runs():
    """Single bogie on the FRA class 6 rail (same seed) at 40, 80 and 120 km/h."""
    runs = {}
    for speed in (40.0, 80.0, 120.0):
        scenario = Scenario.preset("single_bogie")
        scenario.train.speed_kmh = speed
        runs[speed] = simulate(scenario)
    return runs


def test_faster_means_larger_contact_force_variation(rough_runs):
    """Paper §4.1: 'the faster the speed, the larger the wheel–track contact force'. The
    standard deviation of each wheel's force grows with speed, by > 30 % per step (measured
    40 → 80 km/h: × 2.3–3.0, 80 → 120: × 1.7)."""
    spread = np.array([rough_runs[v].wheel_force_N.std(axis=1) for v in (40.0, 80.0, 120.0)])
    assert np.all(spread[1] > 1.3 * spread[0])
    assert np.all(spread[2] > 1.3 * spread[1])


def test_load_spectrum_is_mostly_below_30_hz(rough_runs):
    """Paper Fig. 7: the invert load's main content is 0–30 Hz at 80 km/h. Of the variance of
    the block force about its mean, > 95 % lies below 30 Hz (measured 99.99 %); of the part the
    irregularity adds (rough minus smooth run), > 90 % (measured 99.99 %: the pads filter the
    wheel force, of which 99 % is below 30 Hz)."""
    rough = rough_runs[80.0]
    smooth = simulate(smooth_single_bogie())

    def fraction_below(signal, f_max):
        power = np.abs(np.fft.rfft(signal - signal.mean())) ** 2
        f = np.fft.rfftfreq(signal.size, rough.dt_s)
        return power[f <= f_max].sum() / power.sum()

    assert fraction_below(rough.block_force_N, 30.0) > 0.95
    assert fraction_below(rough.block_force_N - smooth.block_force_N, 30.0) > 0.90


# ---- loss of contact, instability, input checks ----------------------------------------------
def test_loss_of_contact_is_reported_where_and_when(monkeypatch):
    """A 1 mm deep, 0.5 m long rectangular dip (η > 0) 3 m past the monitored block at 80 km/h:
    the unsprung wheel (675 kg under 61 kN) cannot follow the 1 mm drop, so each wheel leaves
    the rail at the dip's entry edge, at the time its axle gets there (to one step)."""
    scenario = Scenario.preset("single_bogie")
    centre = 0.5 * scenario.rail_length + 3.0  # rail coordinate; profile x is from the block
    monkeypatch.setattr(
        model.track.irregularity,
        "profile_for",
        lambda irregularity, x: np.where(np.abs(x - 3.0) < 0.25, 1e-3, 0.0),
    )
    result = simulate(scenario)
    assert not result.unstable
    for wheel in (0, 1):
        events = result.contact_loss[result.contact_loss["wheel"] == wheel]
        entry = events[np.argmin(np.abs(events["x_m"] - (centre - 0.25)))]
        assert entry["x_m"] == pytest.approx(centre - 0.25, abs=scenario.train.speed * 2e-4)
        x0 = (
            0.5 * scenario.rail_length
            - scenario.numerics.approach_distance
            - scenario.train.axle_offsets[wheel]
        )
        assert entry["t_s"] == pytest.approx((entry["x_m"] - x0) / scenario.train.speed, abs=1e-9)
        assert 0.0 < entry["duration_s"] < 0.01
        lost = (result.t_s >= entry["t_s"]) & (result.t_s < entry["t_s"] + entry["duration_s"])
        np.testing.assert_array_equal(result.wheel_force_N[wheel, lost], 0.0)
    assert any("loss of wheel–rail contact" in w for w in result.warnings)


def test_track_under_the_monitored_block_does_not_depend_on_the_rail_length():
    """Profile positions are measured from the monitored block: a longer approach (a longer
    rail) leaves the irregularity the wheels meet at the block unchanged, so the peak invert
    force moves only by the longer settling of the start (< 0.5 %)."""
    scenario = Scenario.preset("single_bogie")
    peaks = []
    for approach in (10.0, 20.0):
        scenario.numerics.approach_distance = approach
        peaks.append(simulate(scenario).block_force_N.max())
    assert peaks[1] == pytest.approx(peaks[0], rel=5e-3)


def test_unstable_run_is_stopped_flagged_and_explained(monkeypatch):
    """Δt = 2.5e-4 s (ω_max Δt ≈ 2.3 for the highest rail mode) with the input check bypassed:
    the run stops as soon as the response diverges, is flagged, says why, and returns only
    finite samples."""
    scenario = smooth_single_bogie(dt=2.5e-4)
    monkeypatch.setattr(vt, "stable_time_step", lambda s: 1.0)
    result = simulate(scenario)
    assert result.unstable
    assert result.t_s.size < vt.n_time_steps(scenario) // 2
    assert any("diverged" in w and "numerics.dt" in w for w in result.warnings)
    for array in (result.block_force_N, result.wheel_force_N, result.rail_disp_m):
        assert np.all(np.isfinite(array))


def test_a_divergence_below_the_time_step_limit_blames_the_irregularity_not_the_step(tmp_path):
    """An absurd measured profile (±1 m every 0.1 m) diverges at the first step although
    numerics.dt = 1e-4 s is below the estimated limit: the message says the step is already
    below it and points at the profile's amplitudes, never advises a smaller step, and reads as
    one sentence with the pipeline's other warnings (no ".;")."""
    from model.pipeline import SimulationError, run

    x = np.arange(-160.0, 160.05, 0.1)
    eta = np.where(np.arange(x.size) % 2 == 0, 1.0, -1.0)
    profile = tmp_path / "absurd.csv"
    np.savetxt(profile, np.column_stack([x, eta]), delimiter=",", header="x_m,eta_m", comments="")
    scenario = Scenario.preset("single_bogie")
    scenario.irregularity.profile_csv = str(profile)
    assert scenario.numerics.dt < stable_time_step(scenario)
    with pytest.raises(SimulationError) as info:
        run(scenario, cache=None)
    message = str(info.value)
    assert "is already below the estimated stability limit" in message
    assert f"irregularity.profile_csv = {str(profile)!r}" in message
    assert "smaller numerics.dt" not in message and ".;" not in message


@pytest.mark.parametrize(
    ("enabled", "limit", "advice"),
    [
        (True, 1.0, "check irregularity.track_class and irregularity.wavelength_min"),
        (False, 1.0, "on a smooth rail, forces far beyond that point to an unusual combination"),
        (True, 1e-5, "is above the estimated stability limit 1e-05 s; use a smaller numerics.dt"),
    ],
)
def test_the_divergence_advice_follows_the_cause(enabled, limit, advice):
    """A smaller step is advised only where the step exceeds the estimated limit."""
    scenario = smooth_single_bogie()
    scenario.irregularity.enabled = enabled
    message = vt._divergence_message(scenario, 0.5, limit)
    assert message.startswith("the integration diverged at t = 0.5 s")
    assert advice in message and not message.endswith(".")


@pytest.mark.parametrize("per_spacing", [1.0, pytest.param(1.5, marks=pytest.mark.slow)])
def test_stability_estimate_is_safe_but_not_wasteful(per_spacing):
    """stable_time_step against the exact stability of the linearised system (rail modes,
    blocks, vehicle, Hertz springs at the static load): the spectral radius of the Zhai
    amplification matrix is ≤ 1 at the estimate (safe) and > 1 at twice it (not wasteful by
    more than 2×). Measured by bisection: the estimate is 0.71 of the true limit at N_m = N and
    0.78 at N_m = 1.5 N. A 2 m approach shortens the rail to 49.2 m (82 spacings) to keep the
    dense eigenvalue problems small."""
    scenario = smooth_single_bogie(approach_distance=2.0)
    n = round(scenario.rail_length / scenario.track.block_spacing)
    scenario.numerics.n_rail_modes = round(per_spacing * n)
    spectral_radius = zhai_spectral_radius_of_linearised_system(scenario)
    estimate = stable_time_step(scenario)
    assert spectral_radius(estimate) <= 1.0 + 1e-9
    assert spectral_radius(2.0 * estimate) > 1.0 + 1e-6


def test_runs_at_the_estimated_limit_stay_stable_across_the_parameter_ranges():
    """16 scenarios with every vehicle and track parameter drawn uniformly from its slider range
    (softbounds), speed 20–160 km/h, FRA class 3–6, N_m from 0.6 to 2.2 L/L_s, each run at
    Δt = stable_time_step: none diverges. (A wider sweep during development, 360 runs including
    six-car trains and classes 1–2, found none either.)"""
    rng = np.random.default_rng(2024)
    for _ in range(16):
        scenario = Scenario.preset("single_bogie")
        for section in (scenario.vehicle, scenario.track):
            for name, parameter in section.param.objects("existing").items():
                value = getattr(section, name)
                if isinstance(value, float) and parameter.softbounds is not None:
                    setattr(section, name, float(rng.uniform(*parameter.softbounds)))
        scenario.train.speed_kmh = float(rng.uniform(20.0, 160.0))
        scenario.irregularity.track_class = int(rng.integers(3, 7))
        n = round(scenario.rail_length / scenario.track.block_spacing)
        scenario.numerics.n_rail_modes = max(math.ceil(0.5 * n), round(rng.uniform(0.6, 2.2) * n))
        scenario.numerics.dt = stable_time_step(scenario)
        result = simulate(scenario)
        assert not result.unstable, scenario.to_json()


def zhai_spectral_radius_of_linearised_system(scenario: Scenario):
    """Function Δt → spectral radius of the Zhai amplification matrix of the linearised model
    (dense, written out from the equations of docs/model.md §1–3; state x_n, v_n, a_{n−1})."""
    track, vehicle = assembly.assemble_track(scenario), assembly.assemble_vehicle(scenario)
    n_modes, n_blocks = track.omega2.size, track.n_spacings - 1
    n_dof = vehicle.inv_mass.shape[1]
    size = n_modes + n_blocks + n_dof
    stiffness, damping, mass = np.zeros((size, size)), np.zeros((size, size)), np.ones(size)
    phi = track.mode_shapes(track.length / track.n_spacings * np.arange(1, n_blocks + 1))
    coupling = np.block([[phi @ phi.T, -phi], [-phi.T, np.eye(n_blocks)]])
    rail_blocks = slice(0, n_modes + n_blocks)
    stiffness[rail_blocks, rail_blocks] = track.fastener_k * coupling
    damping[rail_blocks, rail_blocks] = track.fastener_c * coupling
    stiffness[:n_modes, :n_modes] += np.diag(track.omega2)
    blocks = np.arange(n_modes, n_modes + n_blocks)
    stiffness[blocks, blocks] += track.pad_k
    damping[blocks, blocks] += track.pad_c
    mass[blocks] = track.block_mass
    car = slice(n_modes + n_blocks, size)
    stiffness[car, car] += vehicle.stiffness[0]
    damping[car, car] += vehicle.damping[0]
    mass[car] = 1.0 / vehicle.inv_mass[0]
    load = scenario.vehicle.static_wheel_load
    k_hertz = 1.5 * load ** (1 / 3) / scenario.track.hertz_constant
    shapes = track.mode_shapes(assembly.wheel_start_positions(scenario))
    for j, dof in enumerate(vehicle.wheel_dof[0]):
        a = np.zeros(size)
        a[n_modes + n_blocks + dof] = 1.0
        a[:n_modes] = -shapes[:, j]
        stiffness += k_hertz * np.outer(a, a)
    acc_x, acc_v = -stiffness / mass[:, None], -damping / mass[:, None]
    eye, zero = np.eye(size), np.zeros((size, size))

    def spectral_radius(h):
        amplification = np.block(
            [
                [eye + h * h * acc_x, h * eye + h * h * acc_v, -0.5 * h * h * eye],
                [1.5 * h * acc_x, eye + 1.5 * h * acc_v, -0.5 * h * eye],
                [acc_x, acc_v, zero],
            ]
        )
        return np.max(np.abs(np.linalg.eigvals(amplification)))

    return spectral_radius


def test_check_inputs_refuses_a_time_step_above_the_stability_limit():
    scenario = smooth_single_bogie(dt=2e-4)
    with pytest.raises(
        ValueError,
        match=r"numerics\.dt = 0\.0002 s is above the explicit "
        r"stability limit.*allowed range \(0, 0\.0001319",
    ):
        check_inputs(scenario)


def test_check_inputs_refuses_too_few_modes():
    scenario = smooth_single_bogie(n_rail_modes=50)
    with pytest.raises(ScenarioError, match=r"numerics\.n_rail_modes = 50 is too few"):
        check_inputs(scenario)


def test_rail_too_short_is_refused_where_it_enters():
    """A rail end margin under docs/model.md's 20 m is refused by the parameter's bounds, and the
    derived rail always honours the margin."""
    scenario = smooth_single_bogie()
    with pytest.raises(
        ValueError,
        match=r"^numerics\.rail_end_margin = 5 m is outside the allowed range \[20, 500\] m",
    ):
        scenario.numerics.rail_end_margin = 5.0
    span = scenario.train.axle_span + scenario.numerics.approach_distance
    assert 0.5 * scenario.rail_length - span >= 20.0


def test_speed_must_be_positive():
    """Speed ≤ 0 is refused where it enters (the parameter's bounds), naming the range."""
    scenario = smooth_single_bogie()
    for bad in (0.0, -10.0):
        with pytest.raises(ValueError, match=r"speed_kmh = .* outside the allowed range"):
            scenario.train.speed_kmh = bad


def test_check_inputs_refuses_an_output_too_large():
    scenario = Scenario.paper()
    scenario.numerics.dt = 1e-6
    with pytest.raises(ValueError, match=r"numerics\.dt = 1e-06 s gives 6664500 time steps"):
        check_inputs(scenario)


def test_progress_is_reported_in_a_few_dozen_monotone_calls():
    calls = []
    simulate(smooth_single_bogie(), progress=calls.append)
    assert 10 <= len(calls) <= 41
    assert calls == sorted(calls) and calls[-1] == 1.0
