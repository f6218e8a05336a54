"""Shared test fixtures, and the report header saying which system packages are missing."""

import pytest
from system_requirements import chromium_missing, opensees_missing

from model.params import Scenario
from model.pipeline import StageCache, run


def pytest_report_header(config):
    """Say at the start which tests will be skipped for a missing system package, and why."""
    missing = [
        f"{tests} will be skipped: {reason}"
        for tests, reason in (
            ("browser tests", chromium_missing()),
            ("FE tests", opensees_missing()),
        )
        if reason
    ]
    return missing or None


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


@pytest.fixture(scope="module")
def cache():
    """A stage cache shared by the tests of one module."""
    return StageCache()


@pytest.fixture(scope="module")
def base_results(cache, cheap_scenario):
    """The cheap scenario's results (what-if tests: the run that gets pinned)."""
    return run(cheap_scenario(), cache=cache)


@pytest.fixture(scope="module")
def stiff_results(cache, cheap_scenario):
    """The cheap scenario with a stiffer soil (what-if tests: a run that differs)."""
    scenario = cheap_scenario()
    scenario.soil.youngs_modulus = 12e6
    return run(scenario, cache=cache)
