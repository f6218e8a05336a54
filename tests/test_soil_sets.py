"""The library of named strain-law sets (issue 25 item 2, model/params/soil_sets.py).

Every set carries its citation, where it was read and its test conditions; choosing one by
name (Python, ``--set``, scenario JSON, the dashboard's control) puts its law and constants in
every layer; an unknown name is refused in the project's voice.
"""

import argparse
import json

import numpy as np
import pytest
from param.parameterized import discard_events

from model.cli import load_scenario
from model.longterm.settlement import long_term_settlement
from model.longterm.strain_laws import permanent_strain_percent
from model.params import Layer, Scenario, ScenarioError, Site
from model.params.longterm import LongTerm
from model.params.soil_sets import (
    LAYERS,
    NOT_READ,
    SOIL_SETS,
    Conditions,
    get_soil_set,
    strain_law_constants,
)
from model.soil.stresses import StressResponse

CONDITIONS = ("soil", "confining_stress", "frequency", "drainage", "cycles")


def _stress(deviator_Pa) -> StressResponse:
    """A stress-stage result with a given q_d profile on 0–10 m (12 cycles per passage)."""
    deviator = np.asarray(deviator_Pa, dtype=float)
    return StressResponse(
        depth_m=np.linspace(0.0, 10.0, deviator.size),
        t_s=np.zeros(1),
        deviator_history_Pa=deviator[:, None],
        deviator_Pa=deviator,
        rainflow_cycles=np.full(deviator.size, 12.0),
    )


def _two_layer_scenario() -> Scenario:
    """Paper case with two layers of different own constants, pore pressure off."""
    scenario = Scenario.paper()
    scenario.longterm.pore_pressure_law = "none"
    scenario.site = Site(
        layers=[
            Layer(name="clay", thickness=20.0, soil_class="user", a=0.5, b=0.1, m=1.5),
            Layer(name="silt", thickness=80.0, soil_class="ML"),
        ]
    )
    return scenario


@pytest.mark.parametrize("name", list(SOIL_SETS))
def test_every_set_has_its_citation_where_read_and_test_conditions(name):
    """A set without its source or its conditions is not a literature value."""
    chosen = SOIL_SETS[name]
    assert chosen.name == name
    assert chosen.law in LongTerm.param["law"].objects
    assert "(19" in chosen.citation or "(20" in chosen.citation  # author (year)
    assert chosen.read.strip()
    assert isinstance(chosen.conditions, Conditions)
    for field in CONDITIONS:
        assert getattr(chosen.conditions, field).strip(), f"{name}: {field} is empty"
    assert chosen.a > 0 and 0 < chosen.b < 1 and chosen.m > 0
    assert (chosen.n is not None) == (chosen.law == "chai_miura")
    # every constant is accepted by the layer parameters it replaces
    Layer(soil_class="user", **chosen.constants())


def test_the_library_holds_li_and_seligs_four_classes_as_the_layers_do():
    """The named Li & Selig sets are the classes a layer can choose, value for value."""
    for soil_class in ("ML", "MH", "CL", "CH"):
        chosen = SOIL_SETS[f"li_selig_{soil_class}"]
        layer = Layer(soil_class=soil_class)
        assert (chosen.a, chosen.b, chosen.m) == layer.law_parameters("li_selig")


def test_no_pore_pressure_constant_is_claimed():
    """No soft-clay pore-pressure set could be read: none is offered as one."""
    assert all(chosen.pore_pressure is None for chosen in SOIL_SETS.values())
    assert NOT_READ == "not read"


def test_choosing_a_set_chooses_its_law_and_validates():
    scenario = Scenario.paper()
    scenario.longterm.soil_set = "chai_miura_CH"
    assert scenario.longterm.law == "chai_miura"
    scenario.validate()
    scenario.longterm.law = "li_selig"  # a law the set does not belong to: back to the layers
    assert scenario.longterm.soil_set == LAYERS
    scenario.validate()
    scenario.longterm.soil_set = "li_selig_MH"
    scenario.longterm.law = "li_selig"  # the set's own law: the set stays
    assert scenario.longterm.soil_set == "li_selig_MH"


def test_a_set_and_another_law_together_are_refused_by_validate():
    """Only a scenario built around the watchers (both values forced in) can hold a set with
    another law; validate names both and what to do."""
    scenario = Scenario.paper()
    with discard_events(scenario.longterm):
        scenario.longterm.soil_set = "chai_miura_CH"
    assert scenario.longterm.law == "li_selig"
    with pytest.raises(ScenarioError, match="longterm.soil_set = 'chai_miura_CH'.*'chai_miura'"):
        scenario.validate()


def test_an_unknown_name_is_refused_naming_parameter_value_and_options():
    lt = LongTerm()
    with pytest.raises(ValueError) as refused:
        lt.soil_set = "shanghai_clay"
    text = str(refused.value)
    assert text.startswith("longterm.soil_set = 'shanghai_clay' is not one of the options")
    assert "'layers'" in text and "'li_selig_CH'" in text and "(Soil parameter set)" in text
    with pytest.raises(ValueError, match="longterm.soil_set = 'nope' is not one of the options"):
        get_soil_set("nope")


def test_a_set_replaces_every_layers_constants_in_the_settlement():
    """With a set, both layers take its constants: the stage's strain equals the law evaluated
    by hand with the set's a, b, m (rel 1e-12, rounding); with 'layers' each keeps its own."""
    scenario = _two_layer_scenario()
    stress = _stress(np.linspace(4e3, 1e3, 21))
    own = long_term_settlement(stress, scenario)
    scenario.longterm.soil_set = "li_selig_CL"
    chosen = long_term_settlement(stress, scenario)
    assert own.settlement_m[-1] != pytest.approx(chosen.settlement_m[-1], rel=1e-3)
    cl = SOIL_SETS["li_selig_CL"]
    expected = permanent_strain_percent(
        "li_selig",
        cl.a,
        cl.b,
        cl.m,
        1.0,
        chosen.deviator_Pa,
        chosen.strength_Pa,
        chosen.static_deviator_Pa,
        chosen.n_cycles,
    )
    np.testing.assert_allclose(chosen.strain_percent, expected, rtol=1e-12)
    assert chosen.law_parameters == {"a": cl.a, "b": cl.b, "m": cl.m}
    assert "soil set li_selig_CL" in chosen.statement and "Li, D. & Selig" in chosen.statement
    assert "user values" in own.statement and "soil class ML" in own.statement


def test_the_chai_miura_set_brings_its_n():
    layer = Layer(n=2.5)
    assert strain_law_constants("chai_miura_CH", "chai_miura", layer)["n"] == 1.0
    assert strain_law_constants(LAYERS, "chai_miura", layer)["n"] == 2.5


def test_a_set_travels_through_the_scenario_json_and_the_command_line(tmp_path):
    scenario = Scenario.paper()
    scenario.longterm.soil_set = "chai_miura_CH"
    again = Scenario.from_json(scenario.to_json())
    assert (again.longterm.soil_set, again.longterm.law) == ("chai_miura_CH", "chai_miura")
    assert json.loads(scenario.to_json())["longterm"]["soil_set"] == "chai_miura_CH"
    args = argparse.Namespace(
        scenario=None, preset="paper", borehole=None, overrides=["longterm.soil_set=li_selig_MH"]
    )
    from_cli = load_scenario(args)
    assert (from_cli.longterm.soil_set, from_cli.longterm.law) == ("li_selig_MH", "li_selig")
    args.overrides = ["longterm.soil_set=wuxi"]
    with pytest.raises(ValueError, match="longterm.soil_set = 'wuxi' is not one of the options"):
        load_scenario(args)


def test_the_dashboard_control_lists_every_set(dashboard_inputs):
    """The control comes from the parameter: a select holding 'layers' and every set; choosing
    a set there sets the scenario's set and its law."""
    control = dashboard_inputs.controls["longterm.soil_set"]
    options = control.widget.options
    options = list(options.values()) if isinstance(options, dict) else list(options)
    assert options == [LAYERS, *SOIL_SETS]
    control.widget.value = "chai_miura_CH"
    longterm = dashboard_inputs.scenario.longterm
    assert (longterm.soil_set, longterm.law) == ("chai_miura_CH", "chai_miura")


def test_applying_a_calibration_fit_returns_to_the_layers_constants():
    from dashboard.longterm_view import apply_fit

    lt, layer = LongTerm(soil_set="li_selig_CH"), Layer()
    apply_fit(lt, layer, {"a": 0.9, "b": 0.15, "m": 2.1})
    assert lt.soil_set == LAYERS and lt.law == "li_selig"
    assert layer.law_parameters("li_selig") == (0.9, 0.15, 2.1)


@pytest.fixture
def dashboard_inputs():
    from dashboard.inputs import InputsPanel
    from dashboard.messages import Messages

    return InputsPanel(Scenario.paper(), "paper", Messages(), lambda: None)


def test_the_band_refuses_to_draw_constants_a_set_overrides():
    """Drawing a layer's a while a named set fixes every layer's a would draw nothing the run
    uses: refused before anything runs, naming the set and the way out."""
    from model.study.band import define_band

    scenario = Scenario.paper()
    scenario.longterm.soil_set = "li_selig_CH"
    with pytest.raises(ValueError, match="longterm.soil_set = 'li_selig_CH' fixes"):
        define_band(scenario, 4, law_cv={"a": 0.2})
    assert len(define_band(scenario, 4)) == 4  # the seeds alone are fine
