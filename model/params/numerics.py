"""Discretisation and output settings of every stage."""

from __future__ import annotations

import param

from model.params.quantities import Count, CountOrOff, _q


class Numerics(param.Parameterized):
    """Discretisation and output settings of every stage.

    Besides these bounds, ``model.run_cost.estimate_run`` refuses a run whose arrays would not
    fit in memory and warns of one estimated to take long, naming the parameter to change.
    """

    dt = _q(
        1e-4,
        (1e-6, 1e-3),
        (2e-5, 2e-4),
        "Time step Δt (s)",
        "Time step Δt of Zhai's explicit integrator (paper default 1e-4 s), in "
        "model.track.vehicle_track.simulate; must be below stable_time_step (check_inputs). Bounds "
        "1 µs–1 ms: finer steps only cost time, coarser ones are never stable for a rail on "
        "blocks.",
    )
    n_rail_modes = Count(
        None,
        bounds=(1, 20000),
        softbounds=(50, 2000),
        allow_None=True,
        label="Rail modes",
        doc="Modes N_m of the simply supported rail, in model.track.assembly.assemble_track; "
        "None means L/L_s (shortest modal half-wavelength = block spacing, docs/model.md §2). "
        "Bounds 1–20000; Scenario.validate requires N_m ≥ L/(2L_s).",
    )
    rail_end_margin = _q(
        20.0,
        (20.0, 500.0),
        (20.0, 60.0),
        "Rail end margin (m)",
        "Minimum distance from any axle to a rail end during the run (docs/model.md §2: "
        "≥ 20 m), in Scenario.rail_length. Bounds 20–500 m: beyond, the rail only adds modes.",
    )
    approach_distance = _q(
        10.0,
        (1.0, 500.0),
        (5.0, 40.0),
        "Approach distance (m)",
        "Distance of the leading axle before the monitored block at the start, and of the "
        "trailing axle past it at the end, in Scenario.rail_length and passage_duration. "
        "Bounds 1–500 m: the response decays within a few 1/β (~4 m).",
    )
    n_harmonics = Count(
        32,
        bounds=(1, 1024),
        softbounds=(4, 128),
        label="Ring harmonics",
        doc="Circumferential harmonics n = 0..N_n summed in "
        "model.soil.section_2d.invert_receptance (called from model.soil.response.soil_response). "
        "Bounds 1–1024: the ring's bending makes the terms fall as n⁻⁴ (32 converge to 1e-3, "
        "tests); more only cost time.",
    )
    soil_max_frequency = _q(
        100.0,
        (5.0, 1000.0),
        (30.0, 300.0),
        "Soil model frequency limit (Hz)",
        "Highest frequency f_max passed to the tunnel–soil model in "
        "model.soil.response.soil_response; the load has negligible content above (paper Fig. 7: "
        "0–30 Hz). Bounds 5–1000 Hz: below 5 Hz the wheel-passage pulses are cut, above "
        "1 kHz the 2D section model has no meaning.",
    )
    zero_pad_factor = Count(
        8,
        bounds=(1, 256),
        softbounds=(1, 32),
        label="Zero-padding factor",
        doc="Record length used for the soil FFT, as a multiple of the passage duration, in "
        "model.soil.response.soil_response (convergence of the peak is shown in tests). Bounds "
        "1–256; a run also refuses a padded record shorter than the passage plus the wave tail "
        "to max_depth (model.run_checks.check_record_padding), which would wrap the deep response.",
    )
    psd_segment = _q(
        4.0,
        (0.1, 100.0),
        (1.0, 10.0),
        "PSD segment length (s)",
        "Welch segment length T_seg for the one-sided PSDs (frequency resolution 1/T_seg), in "
        "model.spectra.one_sided_psd (load and soil stages); a shorter record is analysed "
        "whole. Bounds 0.1–100 s: resolutions from 10 Hz to 0.01 Hz.",
    )
    max_depth = _q(
        35.0,
        (11.0, 200.0),
        (11.0, 60.0),
        "Deepest output depth (m)",
        "Depth below the invert down to which model.soil.response.soil_response reports the "
        "displacement (paper Fig. 11 and conclusions: 35 m). Bounds 11–200 m: 11 m is the "
        "paper's comparison depth, which the summary always reports; a full-space model of the "
        "ground says nothing deeper than 200 m.",
    )
    n_depths = Count(
        71,
        bounds=(2, 2000),
        softbounds=(11, 201),
        label="Output depths",
        doc="Number of equally spaced depths from the invert to the deepest one, in "
        "model.soil.response.soil_response. Bounds 2–2000: a profile needs two points; memory "
        "grows as depths × padded samples (run-cost guard).",
    )
    n_wavenumbers = Count(
        384,
        bounds=(16, 100000),
        softbounds=(128, 4096),
        label="Wavenumber points",
        doc="Points of the base grid of the wavenumber integral of the 2.5D point-load response "
        "(model.soil.point_load.point_load_response): uniform in asinh(ξ/ξ_c) on [0, max "
        "wavenumber], plus refinements at the P and S wavenumbers ω/c.",
    )
    max_wavenumber = _q(
        20.0,
        (0, 1000),
        (5.0, 100.0),
        "Largest wavenumber (rad/m)",
        "Upper limit ξ_max of the wavenumber integral of the 2.5D point-load response "
        "(model.soil.point_load.point_load_response); the tail beyond is estimated and must be "
        "below the wavenumber tolerance. Bounds up to 1000 rad/m: wavelengths down to 6 mm, "
        "far below the lining thickness where the thin-shell model ends.",
        (False, True),
    )
    wavenumber_tolerance = _q(
        1e-3,
        (0, 1),
        (1e-5, 1e-2),
        "Wavenumber integral tolerance (-)",
        "Largest estimated error of the 2.5D wavenumber integral "
        "(model.soil.point_load.point_load_response), relative to the largest response at the "
        "same frequency and depth; a larger estimate raises an error naming the numerics "
        "parameter to raise.",
        (False, True),
    )
    kernel_samples_per_cycle = CountOrOff(
        8,
        bounds=(6, 1024),
        softbounds=(6, 32),
        label="Kernel samples per cycle",
        doc="Frequency sampling of the tunnel–soil kernel on the soil stage's record grid, in "
        "model.soil.response.record_grid_transfer: the kernel is evaluated at frequencies at most "
        "c_s/(N r) apart, N this count, r = a + max_depth the distance from the tunnel axis to "
        "the deepest output point (the outgoing S wave there turns through one cycle every "
        "c_s/r Hz), and interpolated in between (6-point Lagrange); below N such steps (near "
        "0 Hz, where the 2D kernel grows like ln f) at every frequency of the grid. 0 evaluates "
        "it at every frequency. Bounds 6–1024 or 0: with fewer than 6 samples per cycle the "
        "interpolation errs by up to 1 % of the transfer functions (docs/tunnel_soil.md); 8 "
        "keeps their error below 2e-4 and that of the peak displacement and peak deviator "
        "below 1e-5 and 1e-4 on the paper case (tests/test_soil_sampling.py; 12: 2e-5, 4e-7, 5e-6 "
        "with 1.5 times the kernel evaluations).",
    )
    ground_max_distance = _q(
        50.0,
        (10.0, 500.0),
        (20.0, 150.0),
        "Farthest ground-surface distance (m)",
        "Horizontal distance from the tunnel axis, on the ground surface, up to which the "
        "half-space model reports the vibration (model.soil.halfspace_response.ground_distances)."
        " Bounds 10–500 m: vibration assessments look at 0–50 m, and the wave-number panels "
        "narrow as 1/distance.",
    )
    n_ground_distances = Count(
        26,
        bounds=(2, 1001),
        softbounds=(6, 101),
        label="Ground-surface points",
        doc="Number of equally spaced ground-surface points from above the axis (0 m) to the "
        "farthest distance (model.soil.halfspace_response.ground_distances); 26 gives 2 m steps "
        "for 50 m.",
    )
