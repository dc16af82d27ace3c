"""The coverage rule of the suite (tests/_coverage.py): its windows, its false alarms and what it catches."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import binom
from tests._coverage import assert_coverage, coverage_window, pass_chance


@pytest.mark.parametrize("n", [30, 40, 50, 100])
def test_window_has_the_stated_false_alarm_rate_on_each_side(n):
    lo, hi = coverage_window(n)
    assert binom.cdf(lo - 1, n, 0.95) <= 0.005 < binom.cdf(lo, n, 0.95)
    assert binom.sf(hi, n, 0.95) <= 0.005
    assert hi == n or binom.sf(hi - 1, n, 0.95) > 0.005
    assert coverage_window(100) == (89, 100)


def test_calibrated_intervals_pass_and_the_white_residual_ones_fail():
    """Drawn hit records: 95 % intervals pass the 30-trial window about 99.7 % of the time, 60 % ones
    (the old white-residual intervals) about 0.6 %."""
    rng = np.random.default_rng(1)

    def passes(rate: float) -> float:
        ok = 0
        for _ in range(2000):
            try:
                assert_coverage({"x": list(rng.random(30) < rate)})
                ok += 1
            except AssertionError:
                pass
        return ok / 2000

    assert passes(0.95) == pytest.approx(pass_chance(30, 0.95), abs=0.01)
    assert passes(0.60) <= 0.02


def test_too_few_trials_are_refused_as_proving_nothing():
    with pytest.raises(AssertionError, match="cannot refuse"):
        assert_coverage({"x": [True] * 12})
