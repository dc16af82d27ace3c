"""Standard errors against analytic references, and honest 'not determined' flags."""

from __future__ import annotations

import math

import numpy as np
import pytest

from motorlab.errors import FitError
from motorlab.fitting import fit_least_squares, fit_linear, r_squared
from motorlab.results import Estimate, FitResult


def test_straight_line_stderr_matches_textbook_formula():
    rng = np.random.default_rng(1)
    x = np.linspace(0, 10, 40)
    y = 0.37 * x + 0.2 + rng.normal(0, 0.05, x.size)
    fit = fit_linear(np.column_stack([x, np.ones_like(x)]), y, ["K", "c"])
    s2 = np.sum(fit.residuals**2) / (x.size - 2)
    sxx = np.sum((x - x.mean()) ** 2)
    assert fit.stderr[0] == pytest.approx(math.sqrt(s2 / sxx), rel=1e-9)
    assert fit.stderr[1] == pytest.approx(math.sqrt(s2 * (1 / x.size + x.mean() ** 2 / sxx)), rel=1e-9)
    assert fit.correlation[0, 1] == pytest.approx(-x.mean() / math.sqrt(np.mean(x**2)), rel=1e-9)


def test_nonlinear_fit_coverage_of_an_exponential_decay():
    inside = 0
    seeds = range(40)
    for seed in seeds:
        rng = np.random.default_rng(seed)
        t = np.linspace(0, 5, 60)
        y = 3.0 * np.exp(-0.7 * t) + rng.normal(0, 0.02, t.size)
        fit = fit_least_squares(lambda p, t=t, y=y: p[0] * np.exp(-p[1] * t) - y, [1.0, 1.0], ["A", "gamma"])
        inside += abs(fit.values[1] - 0.7) < 1.96 * fit.stderr[1]
    assert 0.85 * len(seeds) <= inside <= len(seeds)


def test_collinear_parameters_are_not_determined():
    x = np.linspace(0, 1, 20)
    design = np.column_stack([x, 2 * x, np.ones_like(x)])
    fit = fit_linear(design, 3 * x + 1, ["a", "b", "c"])
    assert not fit.determined[0]
    assert not fit.determined[1]
    assert fit.determined[2]
    est = fit.estimates({"a": "V", "b": "V", "c": "V"})
    assert not est["a"].determined
    assert "not determined" in str(est["a"])


def test_too_few_points_is_a_fit_error():
    with pytest.raises(FitError):
        fit_linear(np.ones((1, 2)), np.ones(1), ["a", "b"])


def test_result_report_and_json():
    res = FitResult(
        "demo",
        {
            "K": Estimate("K", 0.37, 0.002, "V*s/rad"),
            "L": Estimate("L", math.nan, math.nan, "H", determined=False, note="no fast transients"),
        },
        correlation=np.array([[1.0, 0.9], [0.9, 1.0]]),
        correlation_names=["K", "L"],
        rmse=0.01,
        rmse_unit="rad",
        r2=0.999,
        n_points=10,
        warnings=["a warning"],
    )
    text = res.report()
    assert "K = 0.37 ± 0.002 V·s/rad (0.54 %)" in text
    assert "L = not determined" in text
    assert "C(K, L) = +0.9000" in text
    doc = res.to_dict()
    assert doc["parameters"]["K"] == {"value": 0.37, "stderr": 0.002, "unit": "V*s/rad"}
    assert doc["parameters"]["L"]["value"] is None
    assert doc["fit"]["r2"] == 0.999
    assert doc["warnings"] == ["a warning"]


def test_r_squared():
    y = np.array([1.0, 2.0, 3.0])
    assert r_squared(y, y) == 1.0
    assert math.isnan(r_squared(np.ones(3), np.ones(3)))
