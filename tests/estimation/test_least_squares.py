"""Standard errors against analytic references, and honest 'not determined' flags."""

from __future__ import annotations

import math

import numpy as np
import pytest
from tests._coverage import assert_coverage

from motorlab.errors import FitError
from motorlab.estimation.least_squares import fit_least_squares, fit_linear, r_squared
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
    """γ's 95 % interval over 40 seeds: inside the binomial window of 40 trials (34–40, tests/_coverage.py);
    intervals that hold the truth 60 % of the time pass it less than one time in a thousand."""
    inside: dict[str, list[bool]] = {"gamma": []}
    for seed in range(40):
        rng = np.random.default_rng(seed)
        t = np.linspace(0, 5, 60)
        y = 3.0 * np.exp(-0.7 * t) + rng.normal(0, 0.02, t.size)
        fit = fit_least_squares(lambda p, t=t, y=y: p[0] * np.exp(-p[1] * t) - y, [1.0, 1.0], ["A", "gamma"])
        inside["gamma"].append(bool(abs(fit.values[1] - 0.7) < 1.96 * fit.stderr[1]))
    assert_coverage(inside)


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


def _ar1(rng: np.random.Generator, n: int, phi: float, sigma: float) -> np.ndarray:
    """Stationary AR(1) noise e_t = φ·e_{t−1} + u_t with marginal standard deviation ``sigma``."""
    u = rng.normal(0.0, sigma * math.sqrt(1 - phi**2), n)
    e = np.empty(n)
    e[0] = rng.normal(0.0, sigma)
    for t in range(1, n):
        e[t] = phi * e[t - 1] + u[t]
    return e


def test_hac_covers_under_ar1_noise_where_the_plain_stderr_does_not():
    # A straight line with AR(1) errors (φ = 0.8): the plain stderr assumes n independent samples
    # and is about √((1+φ)/(1−φ)) = 3 times too small; the Newey–West sandwich is not.
    seeds = range(200)
    plain = robust = 0
    for seed in seeds:
        rng = np.random.default_rng(seed)
        x = np.linspace(0.0, 1.0, 400)
        y = 2.0 * x + 1.0 + _ar1(rng, x.size, 0.8, 0.1)
        design = np.column_stack([x, np.ones_like(x)])
        ols = fit_linear(design, y, ["slope", "c"])
        hac = fit_linear(design, y, ["slope", "c"], covariance="hac")
        assert ols.bandwidth is None
        assert hac.bandwidth is not None
        assert hac.values == pytest.approx(ols.values)
        plain += abs(ols.values[0] - 2.0) <= 1.96 * ols.stderr[0]
        robust += abs(hac.values[0] - 2.0) <= 1.96 * hac.stderr[0]
    assert plain <= 0.65 * len(seeds)
    assert 0.88 * len(seeds) <= robust <= 0.99 * len(seeds)


def test_hac_nonlinear_fit_with_groups_and_white_noise():
    # Two traces fitted together, white noise: the HAC result stays close to the plain one, and
    # lags never cross from one trace into the other.
    rng = np.random.default_rng(3)
    t = np.linspace(0, 5, 200)
    y = np.concatenate([3.0 * np.exp(-0.7 * t), 2.0 * np.exp(-0.7 * t)]) + rng.normal(0, 0.02, 2 * t.size)
    groups = np.repeat([0, 1], t.size)

    def residual(p: np.ndarray) -> np.ndarray:
        return np.concatenate([p[0] * np.exp(-p[2] * t), p[1] * np.exp(-p[2] * t)]) - y

    plain = fit_least_squares(residual, [1.0, 1.0, 1.0], ["A", "B", "gamma"])
    hac = fit_least_squares(residual, [1.0, 1.0, 1.0], ["A", "B", "gamma"], covariance="hac", groups=groups)
    assert hac.stderr == pytest.approx(plain.stderr, rel=0.25)
    with pytest.raises(ValueError, match="covariance"):
        fit_linear(np.ones((3, 1)), np.ones(3), ["a"], covariance="sandwich")
    with pytest.raises(FitError, match="groups"):
        fit_least_squares(residual, [1.0, 1.0, 1.0], ["A", "B", "gamma"], covariance="hac", groups=groups[:5])


def test_an_exact_fit_has_unknown_not_zero_uncertainty():
    x = np.array([1.0, 2.0, 3.0, 4.0])
    fit = fit_linear(np.column_stack([x, np.ones_like(x)]), 2.0 * x + 1.0, ["a", "c"])
    assert fit.values == pytest.approx([2.0, 1.0])
    assert np.all(np.isnan(fit.stderr))


@pytest.mark.parametrize("bandwidth", [0.0, 0.7, 3.0, 37.5, 400.0])
def test_hac_meat_through_the_fft_equals_the_lag_by_lag_sum(bandwidth: float) -> None:
    # The Bartlett-weighted sum of lagged cross-products, computed in the frequency domain, equals
    # the direct sum over lags within segments (segments shorter than the bandwidth included).
    from motorlab.estimation.covariance import _bartlett_meat, _segments

    rng = np.random.default_rng(7)
    n, p = 700, 4
    white = np.cumsum(rng.standard_normal((n, p)), axis=0) * 0.1 + rng.standard_normal((n, p))
    groups = np.repeat([0, 1, 2, 3], [300, 5, 1, 394])
    segments = _segments(n, groups)
    direct = white.T @ white
    for lag in range(1, math.floor(bandwidth) + 1):
        gamma = sum(white[s[lag:]].T @ white[s[:-lag]] for s in segments if s.size > lag)
        direct = direct + (1.0 - lag / (bandwidth + 1.0)) * (gamma + np.transpose(gamma))
    tolerance = 1e-9 * np.abs(direct).max()
    assert _bartlett_meat(white, segments, bandwidth) == pytest.approx(direct, rel=1e-10, abs=tolerance)
