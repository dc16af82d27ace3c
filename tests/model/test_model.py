"""Closed forms of the motor model."""

from __future__ import annotations

import math

import numpy as np
import pytest

from motorlab.errors import OptionError
from motorlab.model import MotorParams, feedforward_from_params, params_from_feedforward

MOTOR = MotorParams(K=0.35, R=2.0, L=0.6e-3, J=2e-4, b=1e-4, Tf=0.02)


def test_free_speed_balances_torque_and_voltage():
    w = MOTOR.free_speed(12.0)
    i = MOTOR.free_current(12.0)
    assert MOTOR.K * i == pytest.approx(MOTOR.b * w + MOTOR.Tf)
    assert 12.0 == pytest.approx(MOTOR.R * i + MOTOR.K * w)
    assert MOTOR.free_speed(-12.0) == pytest.approx(-w)


def test_no_motion_below_break_away_voltage():
    assert MOTOR.free_speed(0.1) == 0.0
    assert MOTOR.free_current(0.1) == pytest.approx(0.05)


def test_stall_and_time_constants():
    assert MOTOR.stall_current(12.0) == 6.0
    assert MOTOR.stall_torque(12.0) == pytest.approx(0.35 * 6 - 0.02)
    assert MOTOR.electrical_time_constant == pytest.approx(0.3e-3)
    assert MOTOR.mechanical_time_constant == pytest.approx(2e-4 * 2 / (0.35**2 + 2 * 1e-4))


def test_curves_and_peaks_are_consistent():
    c = MOTOR.curves(12.0, points=2001)
    assert c["torque"][0] == pytest.approx(MOTOR.stall_torque(12.0))
    assert c["speed"][-1] == pytest.approx(MOTOR.free_speed(12.0))
    p_max, w_p = MOTOR.peak_power(12.0)
    k = int(np.argmax(c["power"]))
    assert c["power"][k] == pytest.approx(p_max, rel=1e-5)
    assert c["speed"][k] == pytest.approx(w_p, rel=1e-2)
    eff, _ = MOTOR.peak_efficiency(12.0)
    assert 0 < eff < 1
    assert set(MOTOR.figures(12.0)) >= {"stall torque", "free speed", "peak power", "peak efficiency"}


def test_load_reflected_through_gear_ratio():
    loaded = MOTOR.with_load(0.0124, ratio=25)
    assert loaded.J == pytest.approx(2e-4 + 0.0124 * 625)
    with pytest.raises(OptionError):
        MOTOR.with_load(1.0, ratio=0)


def test_feedforward_round_trip():
    ff = feedforward_from_params(MOTOR)
    assert ff["kS"] == pytest.approx(MOTOR.R * MOTOR.Tf / MOTOR.K)
    back = params_from_feedforward(ff["kS"], ff["kV"], ff["kA"], R=MOTOR.R, K=MOTOR.K)
    for name in ("J", "b", "Tf"):
        assert getattr(back, name) == pytest.approx(getattr(MOTOR, name))


@pytest.mark.parametrize("bad", [{"K": 0}, {"R": -1}, {"L": -1e-3}, {"J": math.nan}, {"Tf": -0.1}])
def test_rejects_unphysical_parameters(bad):
    values = MOTOR.to_dict() | bad
    with pytest.raises(OptionError):
        MotorParams(**values)


def test_from_dict_accepts_analysis_json():
    p = MotorParams.from_dict({"K": {"value": 0.35, "stderr": 0.01}, "R": 2.0, "J": {"value": 2e-4}})
    assert p.K == 0.35
    assert p.L == 0.0
    with pytest.raises(OptionError):
        MotorParams.from_dict({"K": 0.3})


@pytest.mark.parametrize("voltage", [1e300, -2e3, math.inf, math.nan])
def test_figures_refuse_voltages_no_gearmotor_runs_on(voltage):
    """Power grows as V²: 1e300 V overflowed into warnings and infinite figures; now refused."""
    with pytest.raises(OptionError, match="voltage"):
        MOTOR.figures(voltage)
    with pytest.raises(OptionError, match="voltage"):
        MOTOR.curves(voltage)
    figures = MOTOR.figures(1000.0)  # the limit itself is fine, every figure finite
    assert all(math.isfinite(value) for value, _ in figures.values())
