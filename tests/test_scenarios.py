"""Presets, train types, URL overrides (model/scenarios.py); display units (params/display.py)."""

import pytest

from model import scenarios
from model.params import (
    DISPLAY_UNITS,
    SECTIONS,
    Scenario,
    display_label,
    display_range,
    display_unit,
    parameter_of,
)


def test_every_preset_is_recognised_and_an_edit_makes_it_custom():
    for name in Scenario.preset_names():
        assert scenarios.matching_preset(Scenario.preset(name)) == name
    edited = Scenario.preset("paper")
    edited.soil.density = 1801.0
    assert scenarios.matching_preset(edited) == scenarios.CUSTOM


def test_train_types_set_their_geometry_and_are_recognised():
    scenario = Scenario.paper()
    assert scenarios.train_type_of(scenario.train) == "Type A"
    scenarios.apply_train_type(scenario, "Type B")
    assert (scenario.train.car_length, scenario.train.bogie_distance) == (19.0, 12.6)
    assert scenarios.train_type_of(scenario.train) == "Type B"
    scenario.train.wheelbase = 2.5
    assert scenarios.train_type_of(scenario.train) == scenarios.CUSTOM
    with pytest.raises(KeyError, match="unknown train type 'Type Z'"):
        scenarios.apply_train_type(scenario, "Type Z")


def test_arguments_give_preset_overrides_and_one_message_per_refusal():
    preset, scenario, problems = scenarios.scenario_from_arguments(
        {"preset": "single_bogie", "train.speed_kmh": "70", "theme": "dark"}
    )
    assert preset == "single_bogie" and problems == []
    assert scenario.train.single_bogie and scenario.train.speed_kmh == 70.0
    preset, scenario, problems = scenarios.scenario_from_arguments(
        {"preset": "nope", "soil.youngs_modulus": "-3", "soil.colour": "red"}
    )
    assert preset == "paper" and len(problems) == 3
    assert "unknown preset 'nope'" in problems[0]
    assert "youngs_modulus" in problems[1] and "outside the allowed range" in problems[1]
    assert "unknown parameter 'soil.colour'" in problems[2]
    assert scenario.to_dict() == Scenario.paper().to_dict()


def test_display_units_of_every_parameter():
    """Listed parameters use their engineering unit; the rest keep their label's SI unit."""
    assert display_unit("soil.youngs_modulus") == ("MPa", 1e-6)
    assert display_unit("train.speed_kmh") == ("km/h", 1.0)
    assert display_label("track.fastener_stiffness") == "Fastener stiffness (MN/m)"
    assert display_label("tunnel.poisson_ratio") == "Lining Poisson's ratio"  # "(-)" dropped
    assert display_range("soil.youngs_modulus") == "[1, 100000] MPa"
    assert display_range("numerics.dt") == "[0.001, 1] ms"
    for path in DISPLAY_UNITS:
        parameter_of(path)  # every listed path exists
    for section in SECTIONS:
        for name in Scenario.param[section].class_.param:
            if name != "name":
                unit, factor = display_unit(f"{section}.{name}")
                assert factor > 0 and "(" not in unit, (section, name)
