"""Fleet outlier test: a worn unit stands out, healthy units do not, across seeds."""

from __future__ import annotations

import dataclasses
import functools
import math

import numpy as np
import pytest

from motorlab.catalog import Motor
from motorlab.results import Estimate
from motorlab.rig.units import UnitSpread, draw_unit
from motorlab.session.fleet import HEALTHY_SPREAD, fleet_summary, robust_z
from motorlab.units import SI_UNITS

PARAMS = ("J", "b", "Tf", "K", "R", "L")
#: One production batch: units agree closer than the rig's default (seed-like) spread.
BATCH = UnitSpread(K=0.02, R=0.04, L=0.04, J=0.03, b=0.06, Tf=0.06)
#: Relative standard errors of the estimates, as the simulated session gives them (≈ 0.1-4 %).
MEASUREMENT = {"J": 0.02, "b": 0.01, "Tf": 0.01, "K": 0.002, "R": 0.03, "L": 0.015}


@functools.lru_cache(maxsize=1)
def _motor() -> Motor:
    return Motor.from_catalog("neverest40")


def fleet_estimates(
    seed: int, *, units: int = 3, worn: str | None = None, factor: float = 2.0, spread: UnitSpread = BATCH
) -> dict[str, dict[str, Estimate]]:
    """Estimates of a simulated fleet: true draws plus measurement noise with honest standard errors."""
    motor = _motor()
    rng = np.random.default_rng(seed)
    out = {}
    for k in range(units):
        name = "ABCDEFGH"[k]
        params = draw_unit(motor, 1000 * seed + k, spread=spread)  # type: ignore[arg-type]
        if name == worn:
            params = params.scaled(b=params.b * factor)
        out[name] = {}
        for p in PARAMS:
            se = MEASUREMENT[p] * getattr(params, p)
            value = getattr(params, p) + se * rng.standard_normal()
            out[name][p] = Estimate(p, value, se, SI_UNITS[p])
    return out


def test_healthy_spread_matches_the_rig() -> None:
    # The floor of the outlier test is the spread the virtual rig draws healthy units with.
    assert dataclasses.asdict(UnitSpread()) == HEALTHY_SPREAD


@pytest.mark.parametrize("seed", range(6))
def test_doubled_b_is_flagged_and_no_healthy_unit_in_a_batch(seed: int) -> None:
    worn = "ABC"[seed % 3]
    healthy_spread = dataclasses.asdict(BATCH)
    summary = fleet_summary(fleet_estimates(seed, worn=worn), healthy_spread=healthy_spread, model="NeveRest 40")
    assert [(o.unit, o.parameter) for o in summary.outliers] == [(worn, "b")]
    outlier = summary.outliers[0]
    assert 1.6 < outlier.ratio < 2.5
    assert outlier.message().startswith("b is ")
    assert "× the median of its siblings" in outlier.message()
    assert fleet_summary(fleet_estimates(seed), healthy_spread=healthy_spread).outliers == []


def test_doubled_b_against_the_rig_default_spread_over_many_fleets() -> None:
    # Power and false alarms with the spreads the virtual rig draws healthy units with.
    seeds = range(60)
    found = sum(
        [(o.unit, o.parameter) for o in fleet_summary(fleet_estimates(s, worn="B", spread=UnitSpread())).outliers]
        == [("B", "b")]
        for s in seeds
    )
    false_alarms = sum(bool(fleet_summary(fleet_estimates(s + 500, spread=UnitSpread())).outliers) for s in seeds)
    assert found >= 0.85 * len(seeds)
    assert false_alarms <= 1


def test_small_fleets_use_the_healthy_spread_not_their_own_mad() -> None:
    # Three units, one doubled: a MAD from three points would be inflated by the worn unit itself.
    x = np.array([1.0, 1.1, 2.2])
    z, _, spread = robust_z(x, np.zeros(3), relative_floor=0.1)
    assert spread == 0.1
    assert z[2] == pytest.approx(math.log(2.2 / 1.1) / 0.1)
    # Five or more units: the MAD may widen the spread.
    _, _, spread5 = robust_z(np.array([1.0, 1.3, 1.6, 2.0, 2.5]), np.zeros(5), relative_floor=0.1)
    assert spread5 > 0.1


def test_robust_z_rule() -> None:
    x = np.array([1.0, 1.05, 2.0, 1.02, 0.97])
    z, median, spread = robust_z(x, np.zeros(5), relative_floor=0.05)
    assert median == 1.02
    # ln spread: MAD of ln x = median(|ln x − ln 1.02|) → s = max(1.4826·MAD, 0.05).
    s = max(1.4826 * float(np.median(np.abs(np.log(x) - math.log(1.02)))), 0.05)
    assert spread == pytest.approx(s)
    assert z == pytest.approx(np.log(x / 1.02) / s)
    # A poorly measured unit is not flagged for its own noise: σ/x enters the denominator.
    z_noisy, _, _ = robust_z(x, np.array([0.0, 0.0, 2.0, 0.0, 0.0]), relative_floor=0.05)
    assert abs(z_noisy[2]) < 1.0
    # Non-positive values: the test runs on x itself.
    z_lin, median_lin, _ = robust_z(np.array([-0.1, 0.0, 0.1]), np.zeros(3), relative_floor=0.1)
    assert median_lin == 0.0
    assert np.all(np.isfinite(z_lin))


def test_few_units_and_undetermined_estimates() -> None:
    est = fleet_estimates(0, units=2)
    summary = fleet_summary(est)
    assert summary.outliers == []
    assert any("no outlier test" in n for n in summary.notes)
    est = fleet_estimates(1)
    est["A"]["b"] = Estimate("b", math.nan, math.nan, SI_UNITS["b"], determined=False)
    summary = fleet_summary(est)
    assert summary.parameters["b"].n == 2
    assert summary.parameters["K"].n == 3
    d = summary.to_dict()
    assert d["parameters"]["K"]["n"] == 3


def test_fewer_than_three_units_say_no_test_ran() -> None:
    two = fleet_summary(fleet_estimates(0, units=2))
    assert not two.tested
    assert two.verdict().startswith("no outlier test")
    three = fleet_summary(fleet_estimates(0, units=3))
    assert three.tested
    assert three.verdict().startswith("no unit stands out")
