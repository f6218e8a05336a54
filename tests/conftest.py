"""Shared test fixtures."""

import pytest

from model.params import Scenario


def _cheap_scenario() -> Scenario:
    """Single bogie at 100 km/h on a 64.8 m rail (~0.8 s, 8 k steps), 11 output depths."""
    scenario = Scenario.preset("single_bogie")
    scenario.train.speed_kmh = 100.0
    scenario.numerics.n_depths = 11
    return scenario


@pytest.fixture(scope="session")
def cheap_scenario():
    """Factory of a fresh cheap scenario: the whole pipeline runs in about a second."""
    return _cheap_scenario
