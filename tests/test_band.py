"""Settlement bands (model.study.band): order, zero width, spread, the covariance draw, refusals."""

import json
import math

import numpy as np
import pandas as pd
import pytest

import model
from model.longterm.statements import SETTLEMENT_COVERS
from model.pipeline import run
from model.study import band as band_module
from model.study.band import (
    calibration_draws,
    define_band,
    lognormal_factors,
    settlement_band,
)
from model.study.band_cli import main
from model.study.execution import study_client


@pytest.fixture(scope="module")
def client():
    """A LocalCluster of two single-threaded workers shared by the module's bands."""
    with study_client(None, n_workers=2) as dask_client:
        yield dask_client


@pytest.fixture
def scenario(cheap_scenario):
    """The cheap scenario over 10 years."""
    scenario = cheap_scenario()
    scenario.longterm.years = 10.0
    return scenario


def test_the_public_name_is_the_module_s():
    assert model.settlement_band is settlement_band


def test_zero_cvs_and_one_seed_give_a_zero_width_band_equal_to_the_deterministic_run(
    scenario, client
):
    table = settlement_band(scenario, n_draws=3, seeds=1, scheduler=client)
    expected = run(scenario).longterm
    np.testing.assert_array_equal(table["years"], expected.years)
    for column in ("p05", "p95"):  # exactly: the same run three times, a zero-width band
        np.testing.assert_array_equal(table[column], table["p50"])
    # the worker's run against this process's: equal to rounding (a worker computes with one
    # Numba thread, this process with several; 2e-14 relative seen on a fresh machine)
    np.testing.assert_allclose(table["p50"], expected.settlement_m, rtol=1e-12, atol=0.0)
    assert table.attrs["n_draws"] == 3 and table.attrs["errors"] == {}


def test_band_order_spread_growing_with_cv_and_reproducible(scenario, client):
    widths = []
    for cv in (0.1, 0.3):
        table = settlement_band(
            scenario,
            n_draws=40,
            seeds=2,
            scheduler=client,
            law_cv={"a": cv, "m": cv / 3},
            site_cv={"cu_ratio": cv, "compressibility": cv},
            sampling_seed=7,
        )
        assert table.attrs["n_draws"] == 40
        assert np.all(table["p05"] <= table["p50"]) and np.all(table["p50"] <= table["p95"])
        draws = table.filter(like="draw_").to_numpy()
        assert draws.shape == (len(table), 40)
        np.testing.assert_allclose(table["p50"], np.median(draws, axis=1), rtol=1e-15)
        final = table.iloc[-1]
        widths.append((final["p95"] - final["p05"]) / final["p50"])
    assert widths[1] > 1.5 * widths[0] > 0.0  # log-normal factors: the width grows with the CV
    again = settlement_band(
        scenario,
        n_draws=40,
        seeds=2,
        scheduler=client,
        law_cv={"a": 0.3, "m": 0.1},
        site_cv={"cu_ratio": 0.3, "compressibility": 0.3},
        sampling_seed=7,
    )
    pd.testing.assert_frame_equal(again, table)  # reproducible by seed, bit for bit


def test_the_draws_are_fixed_by_the_sampling_seed_and_use_the_class_values_as_means(scenario):
    first = define_band(scenario, 50, seeds=[3, 4], law_cv={"a": 0.2}, sampling_seed=1)
    assert first == define_band(scenario, 50, seeds=[3, 4], law_cv={"a": 0.2}, sampling_seed=1)
    assert first != define_band(scenario, 50, seeds=[3, 4], law_cv={"a": 0.2}, sampling_seed=2)
    assert [draw["seed"] for draw in first[:4]] == [3, 4, 3, 4]
    # class CH (a, b, m) = (1.2, 0.18, 2.4): the layer becomes 'user' with the class's b, m
    assert {draw["site.layers[0].soil_class"] for draw in first} == {"user"}
    assert {draw["site.layers[0].b"] for draw in first} == {0.18}
    a = np.array([draw["site.layers[0].a"] for draw in first])
    assert a.min() > 0.0 and a.std() > 0.0


def test_lognormal_factors_have_mean_one_and_the_cv():
    """Mean 1 and CV of 0.3 from 200 000 draws: standard errors 7e-4 and ~1.5e-3; tolerance
    5 standard errors. A CV of 0 gives exactly 1."""
    factors = lognormal_factors(0.3, 200_000, np.random.default_rng(0))
    assert abs(factors.mean() - 1.0) < 5 * 0.3 / math.sqrt(factors.size)
    assert abs(factors.std() / factors.mean() - 0.3) < 0.008
    assert np.all(lognormal_factors(0.0, 10, np.random.default_rng(0)) == 1.0)


def test_the_calibration_draw_reproduces_its_covariance(scenario):
    """(ln a, m, b) drawn from a known covariance (correlations −0.6, 0.3, −0.2): the sample
    covariance of 40 000 draws agrees entry by entry within 5 of its standard errors,
    se(Σ̂_ij) = √((Σ_ii Σ_jj + Σ_ij²)/(n − 1)) for a normal sample, and the sample mean
    within 5 standard errors of the fit's (ln a, m, b)."""
    sd = np.array([0.05, 0.08, 0.01])
    correlation = np.array([[1.0, -0.6, 0.3], [-0.6, 1.0, -0.2], [0.3, -0.2, 1.0]])
    covariance = correlation * np.outer(sd, sd)
    fit = {"a": 0.9, "m": 2.1, "b": 0.15, "covariance": covariance.tolist()}
    n = 40_000
    draws = calibration_draws(fit, n, np.random.default_rng(11))
    sample = np.column_stack([np.log(draws[:, 0]), draws[:, 1], draws[:, 2]])
    mean = np.array([math.log(0.9), 2.1, 0.15])
    assert np.all(np.abs(sample.mean(axis=0) - mean) < 5 * sd / math.sqrt(n))
    error = np.sqrt((np.outer(np.diag(covariance), np.diag(covariance)) + covariance**2) / (n - 1))
    assert np.all(np.abs(np.cov(sample, rowvar=False) - covariance) < 5 * error)
    # through define_band: the calibrated layer's a, b, m are these draws
    layer = scenario.site.layers[0]
    layer.soil_class, layer.a, layer.b, layer.m = "user", 0.9, 0.15, 2.1
    band_draws = define_band(scenario, 1000, seeds=1, calibration=fit, sampling_seed=11)
    for column, name in enumerate("amb"):
        drawn = np.array([draw[f"site.layers[0].{name}"] for draw in band_draws])
        expected = calibration_draws(fit, 1000, np.random.default_rng(11))[:, column]
        np.testing.assert_allclose(drawn, expected, rtol=1e-15)


@pytest.fixture
def nothing_submitted(monkeypatch):
    """Fail the test if any task is submitted."""

    def refuse(*args, **kwargs):
        raise AssertionError("a task was submitted")

    monkeypatch.setattr(band_module, "collect_tasks", refuse)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"n_draws": 0}, "n_draws = 0 is outside the allowed range [1, 10000]"),
        ({"n_draws": 2.5}, "n_draws = 2.5 is not a whole number"),
        ({"seeds": 0}, "seeds = 0 is outside the allowed range"),
        ({"seeds": []}, "seeds is empty"),
        ({"law_cv": {"q": 0.1}}, "law_cv['q'] is not a layer property it may vary"),
        ({"law_cv": {"a": -0.1}}, "law_cv['a'] = -0.1 is outside the allowed range [0, 1]"),
        ({"law_cv": {"a": "x"}}, "law_cv['a'] = 'x' is not a number"),
        ({"site_cv": {"cu_ratio": 2.0}}, "site_cv['cu_ratio'] = 2.0 is outside"),
        ({"site_cv": [{}, {}]}, "site_cv has 2 entries but site.layers has 1 layer(s)"),
        ({"site_cv": {"undrained_strength": 0.1}}, "site.layers[0].undrained_strength is None"),
        ({"calibration": {"a": 1.0, "b": 0.1, "m": 2.0}}, "calibration has no 'covariance'"),
        (
            {"calibration": {"a": 1.0, "b": 0.1, "m": 2.0, "covariance": np.eye(3).tolist()}},
            "calibration: no layer of site.layers uses the fitted a = 1 %",
        ),
    ],
)
def test_bad_inputs_are_refused_before_anything_runs(scenario, nothing_submitted, kwargs, message):
    with pytest.raises(ValueError) as error:
        settlement_band(scenario, **{"n_draws": 4, **kwargs})
    assert message in str(error.value)


def test_a_draw_the_layer_refuses_fails_alone_and_is_reported(scenario, client):
    """b drawn with a CV of 1 from 0.18 passes its bound 1 in about 4 of 1000 draws: those
    draws fail with the layer's message, the others make the band."""
    table = settlement_band(scenario, 300, seeds=1, scheduler=client, law_cv={"b": 1.0})
    errors = table.attrs["errors"]
    assert errors and table.attrs["n_draws"] == 300 - len(errors)
    assert all("site.layers[0].b" in message for message in errors.values())
    assert table[band_module.DRAW_COLUMN.format(index=min(errors))].isna().all()


def test_command_line_writes_the_band_and_refuses_bad_input(tmp_path, client, capsys):
    out = tmp_path / "band"
    code = main(
        [
            "--preset", "single_bogie", "--set", "train.speed_kmh=100",
            "--set", "numerics.n_depths=11", "--draws", "4", "--seeds", "2",
            "--law-cv", "a=0.2", "--site-cv", "0:cu_ratio=0.1",
            "--scheduler", client.scheduler.address, "--out", str(out),
        ]
    )  # fmt: skip
    assert code == 0
    table = pd.read_csv(out / "band.csv")
    assert list(table.columns[:5]) == ["years", "p05", "p50", "p95", "mean"]
    printed = capsys.readouterr().out
    assert "band of 4 of 4 draws (2 seeds)" in printed and f"({SETTLEMENT_COVERS})" in printed
    definition = json.loads((out / "band.json").read_text())
    assert definition["settlement_covers"] == SETTLEMENT_COVERS  # issue 25: what it covers
    for argv, message in (
        (["--law-cv", "a"], "--law-cv 'a' must be of the form name=cv"),
        (["--site-cv", "3:cu_ratio=0.1"], "layer 3 is outside the allowed range [0, 0]"),
        (["--draws", "0"], "n_draws = 0 is outside the allowed range"),
    ):
        with pytest.raises(SystemExit) as exit_:
            main([*argv, "--out", str(tmp_path / "bad")], prog="tunnelsettle band")
        assert exit_.value.code == 2
        err = capsys.readouterr().err
        assert err.startswith("error: ") and message in err
