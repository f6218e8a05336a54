"""Parameter objects: presets, JSON round trip, bounds, derived quantities against hand values."""

import json
import math
import re

import param
import pytest

from model.params import (
    PRESETS_FILE,
    SECTIONS,
    Irregularity,
    Numerics,
    Quantity,
    Scenario,
    ScenarioError,
    Soil,
    Track,
    Train,
    Tunnel,
    Vehicle,
)
from model.params.quantities import number_text, split_label

PARAM_CLASSES = (Vehicle, Train, Track, Irregularity, Tunnel, Soil, Numerics)


def _bounded_parameters():
    for cls in PARAM_CLASSES:
        for name, p in cls.param.objects("existing").items():
            if isinstance(p, param.Number) and p.bounds is not None:
                yield pytest.param(cls, name, p, id=f"{cls.__name__}.{name}")


@pytest.mark.parametrize("name", Scenario.preset_names())
def test_every_preset_loads_and_validates(name):
    scenario = Scenario.preset(name)
    scenario.validate()


def test_preset_classmethods_match_data():
    assert Scenario.paper().to_dict() == Scenario.preset("paper").to_dict()
    assert Scenario.type_b().train.car_length == 19.0
    assert Scenario.paper_soil_lame().soil.poisson_ratio == pytest.approx(0.44, abs=5e-4)


def test_paper_preset_is_the_model_sheet_reading():
    s = Scenario.paper()
    assert (s.train.n_cars, s.train.speed_kmh, s.train.single_bogie) == (6, 80.0, False)
    assert s.irregularity.track_class == 6
    assert (s.soil.youngs_modulus, s.soil.poisson_ratio) == (6e6, 0.3)
    assert s.tunnel.thickness == 0.30


@pytest.mark.parametrize(
    ("preset", "quantities"),
    [
        ("paper_soil_lame", {"lame_lambda": 1.4e9, "shear_modulus": 1.91e8}),
        ("paper_soil_wave_speeds", {"p_wave_speed": 524.0, "s_wave_speed": 190.0}),
    ],
)
def test_soil_presets_reproduce_the_paper_table_4_values(preset, quantities):
    """The presets store E and ν; the derived λ, μ or c1, c2 must give back Table 4 (1e-12 rel)."""
    soil = Scenario.preset(preset).soil
    stored = json.loads(PRESETS_FILE.read_text())["presets"][preset]["source"]
    assert stored == quantities
    for name, value in quantities.items():
        assert getattr(soil, name) == pytest.approx(value, rel=1e-12)


@pytest.mark.parametrize("name", Scenario.preset_names())
def test_json_round_trip_is_exact(name):
    scenario = Scenario.preset(name)
    scenario.train.speed_kmh = 61.123456789012345
    scenario.numerics.n_rail_modes = 777
    text = scenario.to_json()
    again = Scenario.from_json(text)
    assert again.to_dict() == scenario.to_dict()
    assert again.to_json() == text


def test_copy_is_independent():
    a = Scenario.paper()
    b = a.copy()
    b.soil.youngs_modulus = 1e7
    assert a.soil.youngs_modulus == 6e6


def test_unknown_names_are_refused():
    with pytest.raises(KeyError, match="unknown parameter"):
        Scenario.from_dict({"soil": {"stiffness": 1.0}})
    with pytest.raises(KeyError, match="unknown section"):
        Scenario.from_dict({"ground": {}})
    with pytest.raises(KeyError, match="unknown preset"):
        Scenario.preset("nope")


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("[1]", "a scenario must be an object of sections, not list"),
        ('{"train": 5}', "section 'train' must be an object of parameters, not int"),
        ("{", "Expecting property name"),
    ],
)
def test_malformed_scenario_json_is_a_value_error(text, message):
    with pytest.raises(ValueError, match=message):
        Scenario.from_json(text)


@pytest.mark.parametrize(("cls", "name", "p"), list(_bounded_parameters()))
def test_every_bound_refuses_a_bad_value_with_a_clear_message(cls, name, p):
    low, high = p.bounds
    bad = (high * 2 + 1) if high is not None else (low - 1 if low is not None else None)
    if low is not None and p.inclusive_bounds[0] is False:
        bad = low  # the excluded end itself
    obj = cls()
    with pytest.raises(ValueError) as info:
        setattr(obj, name, bad)
    message = str(info.value)
    assert message.startswith(f"{cls.__name__.lower()}.{name} = {number_text(bad)}")
    assert "allowed range" in message
    assert split_label(p.label)[0] in message


@pytest.mark.parametrize(("cls", "name", "p"), list(_bounded_parameters()))
def test_every_parameter_has_label_doc_and_softbounds_inside_bounds(cls, name, p):
    assert p.doc and p.label
    if isinstance(p, Quantity):
        assert p.label.endswith(")"), "a physical quantity's label ends with its unit"
    soft_low, soft_high = p.softbounds
    low, high = p.bounds
    assert low is None or soft_low >= low
    assert high is None or soft_high <= high
    default = p.default
    assert default is None or (soft_low <= default <= soft_high), "default outside slider range"


def test_every_parameter_doc_names_where_it_is_used():
    """Traceability (issue 9): each doc names the module or class member that reads it."""
    where = re.compile(r"\bmodel\.\w+|\b(Train|Track|Scenario|Vehicle|LongTerm)\.\w+")
    scenario = Scenario()
    for section in SECTIONS:
        for name, p in getattr(scenario, section).param.objects("existing").items():
            if name != "name":
                assert where.search(p.doc or ""), f"{section}.{name}"


def test_constructor_arguments_are_checked_with_the_same_message():
    with pytest.raises(ValueError, match=r"^soil.poisson_ratio = 0.7 is outside the allowed range"):
        Soil(poisson_ratio=0.7)


@pytest.mark.parametrize("bad", [float("nan"), float("inf"), -float("inf")])
@pytest.mark.parametrize(
    ("cls", "name", "p"), [c for c in _bounded_parameters() if isinstance(c.values[2], Quantity)]
)
def test_non_finite_values_are_refused_everywhere(cls, name, p, bad):
    with pytest.raises(ValueError, match=rf"^{cls.__name__.lower()}\.{name} = .* allowed range"):
        setattr(cls(), name, bad)


@pytest.mark.parametrize("bad", [1, 5, -1, 1025])
def test_kernel_sampling_takes_zero_or_at_least_six_samples_per_cycle(bad):
    """0 (every frequency) and [6, 1024] are accepted; 1–5 samples per cycle would interpolate
    across too coarse a sampling (errors up to 1 %, docs/tunnel_soil.md) and are refused with
    the parameter, the value and the allowed values named."""
    numerics = Numerics()
    for good in (0, 6, 1024):
        numerics.kernel_samples_per_cycle = good
        assert numerics.kernel_samples_per_cycle == good
    with pytest.raises(
        ValueError,
        match=rf"^numerics\.kernel_samples_per_cycle = {bad} is outside the allowed range "
        r"\[6, 1024\] or 0 \(Kernel samples per cycle\)$",
    ):
        numerics.kernel_samples_per_cycle = bad
    with pytest.raises(ValueError, match=r"numerics.kernel_samples_per_cycle = 'x' is not a whole"):
        Scenario().set_value("numerics.kernel_samples_per_cycle", "x")
    scenario = Scenario()
    scenario.set_value("numerics.kernel_samples_per_cycle", "0")
    assert Scenario.from_json(scenario.to_json()).numerics.kernel_samples_per_cycle == 0


def test_dotted_set_parses_and_refuses():
    s = Scenario.paper()
    s.set_value("train.speed_kmh", "60")
    s.set_value("train.single_bogie", "true")
    s.set_value("numerics.n_rail_modes", "none")
    assert (s.train.speed_kmh, s.train.single_bogie, s.numerics.n_rail_modes) == (60.0, True, None)
    with pytest.raises(ValueError, match=r"train.speed_kmh = 'fast' is not a number"):
        s.set_value("train.speed_kmh", "fast")
    with pytest.raises(ValueError, match=r"allowed range \[1, 400\]"):
        s.set_value("train.speed_kmh", "-5")
    with pytest.raises(KeyError, match="section.parameter"):
        s.set_value("speed", "5")
    with pytest.raises(KeyError, match="unknown parameter 'train.speed'"):
        s.set_value("train.speed", "5")


# ---- derived quantities against hand values -------------------------------------------------


def test_static_wheel_load_from_table_1():
    """(38 500 + 2·2 980 + 4·1 350) kg · 9.81 / 8 wheels = 61.14 kN (docs/model.md: 61.1 kN)."""
    assert Vehicle().static_wheel_load == pytest.approx(49860 * 9.81 / 8, rel=1e-12)
    assert Vehicle().static_wheel_load == pytest.approx(61.1e3, rel=1e-3)


def test_soil_wave_speeds_and_lame_constants():
    """E = 6 MPa, ν = 0.3, ρ = 1800: μ = E/2.6, λ = 1.5 μ... c2 = √(μ/ρ) = 35.8 m/s.

    The issue quotes c2 = 35.7 m/s; the exact value is 35.806 m/s (0.3 % above, a rounding).
    """
    soil = Soil()
    mu = 6e6 / 2.6
    lam = 2 * 0.3 * mu / 0.4
    assert soil.shear_modulus == pytest.approx(mu, rel=1e-14)
    assert soil.lame_lambda == pytest.approx(lam, rel=1e-14)
    assert soil.bulk_modulus == pytest.approx(6e6 / (3 * (1 - 0.6)), rel=1e-14)
    assert soil.s_wave_speed == pytest.approx(35.806, abs=1e-3)
    assert soil.s_wave_speed == pytest.approx(35.7, rel=4e-3)
    assert soil.p_wave_speed == pytest.approx(math.sqrt((lam + 2 * mu) / 1800), rel=1e-14)


def test_soil_constructors_invert_each_other():
    soil = Soil.from_wave_speeds(524.0, 190.0, 1800.0)
    assert soil.poisson_ratio == pytest.approx((7.6066 - 2) / (2 * (7.6066 - 1)), rel=1e-4)
    again = Soil.from_lame(soil.lame_lambda, soil.shear_modulus, soil.density)
    assert again.youngs_modulus == pytest.approx(soil.youngs_modulus, rel=1e-13)


def test_track_derived_check_values_from_the_model_sheet():
    """docs/model.md §2–3: β = 1.14 1/m, 0.78 mm under 61.1 kN, Hertz compression ≈ 81 µm."""
    track = Track()
    k = 8e7 * 4e7 / (1.2e8 * 0.6)
    assert track.winkler_modulus == pytest.approx(k, rel=1e-14)
    assert track.winkler_beta == pytest.approx(1.14, abs=5e-3)
    deflection = 61.1e3 * track.winkler_beta / (2 * k)
    assert deflection == pytest.approx(0.78e-3, abs=5e-6)
    assert track.hertz_constant == pytest.approx(4.57 * 0.42**-0.149 * 1e-8, rel=1e-14)
    assert track.hertz_compression(61.1e3) == pytest.approx(81e-6, rel=0.01)
    track.wheel_tread = "worn"
    assert track.hertz_constant == pytest.approx(3.86 * 0.42**-0.115 * 1e-8, rel=1e-14)


def test_tunnel_ring_properties():
    tunnel = Tunnel()
    assert tunnel.ring_radius == pytest.approx(2.85)
    K = 3.45e10 * 0.3 / (1 - 0.17**2)
    assert tunnel.extensional_stiffness == pytest.approx(K, rel=1e-14)
    assert tunnel.bending_stiffness == pytest.approx(K * 0.09 / 12, rel=1e-14)


def test_train_geometry_type_a():
    train = Train()
    offsets = train.axle_offsets
    assert len(offsets) == 24 == train.n_wheels
    assert offsets[:4] == pytest.approx([0.0, 2.4, 15.7, 18.1])
    assert offsets[4] == pytest.approx(22.0)
    assert train.axle_span == pytest.approx(5 * 22 + 18.1)
    train.single_bogie = True
    assert train.axle_offsets == [0.0, 2.4]
    assert train.speed == pytest.approx(80 / 3.6, rel=1e-14)


def test_rail_length_modes_and_passage_for_the_paper_case():
    """L ≥ 2(20 + 10 + 128.1) = 316.2 m, rounded up to an even number of 0.6 m spacings."""
    s = Scenario.paper()
    assert s.rail_length == pytest.approx(316.8)
    assert s.rail_modes == 528
    assert s.passage_duration == pytest.approx((20 + 128.1) / (80 / 3.6))
    assert s.car_body_pitch_inertia == pytest.approx(38500 * 22**2 / 12)
    s.vehicle.car_body_pitch_inertia = 1.2e6
    assert s.car_body_pitch_inertia == 1.2e6
    s.train.single_bogie = True
    assert s.rail_length == pytest.approx(64.8)
    assert round(s.rail_length / s.track.block_spacing) % 2 == 0


def test_cross_parameter_validation_lists_every_problem():
    s = Scenario.paper()
    s.irregularity.wavelength_min = 60.0
    s.train.bogie_distance = 21.0
    s.numerics.n_rail_modes = 100
    with pytest.raises(ScenarioError) as info:
        s.validate()
    message = str(info.value)
    assert "wavelength_min = 60 m" in message
    assert "car_length = 22 m" in message
    assert "n_rail_modes = 100 is too few" in message and "0.5 L/L_s = 273" in message


def test_sections_cover_every_scenario_parameter():
    assert set(SECTIONS) == set(Scenario.param) - {"name"}


def test_a_scenario_file_with_the_former_axis_depth_path_still_loads():
    """The axis depth moved from longterm to tunnel (issue 23): a file written before, with
    longterm.axis_depth, loads to the same scenario; giving both paths with different values is
    refused, naming both."""
    current = Scenario.paper()
    current.tunnel.axis_depth = 22.0
    data = current.to_dict()
    data["longterm"]["axis_depth"] = data["tunnel"].pop("axis_depth")
    assert Scenario.from_json(json.dumps(data)).to_dict() == current.to_dict()
    data["tunnel"]["axis_depth"] = 21.0
    with pytest.raises(ValueError, match=r"longterm.axis_depth = 22.0 and tunnel.axis_depth = 21"):
        Scenario.from_json(json.dumps(data))
