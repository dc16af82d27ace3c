"""LQR gains against WPILib SysId's own test figures, and pole placement on the linear plant."""

from __future__ import annotations

import math

import numpy as np
import pytest

import control
from motorlab.control.design import (
    Feedforward,
    design_pid_poles,
    design_position_lqr,
    design_velocity_lqr,
    discretize,
    lqr_gain,
    sysid_gains,
)
from motorlab.control.simulation import linear_step_metrics
from motorlab.errors import OptionError

# allwpilib sysid/src/test/native/cpp/analysis/FeedbackAnalysisTest.cpp: (kV, kA, preset, delay,
# encoder factor, expected kP, expected kD, tolerance). LQR parameters qp=1, qv=1.5, r=7 throughout.
VELOCITY_CASES = [
    (3.060, 0.327, "default", 1.0, 2.11, 0.05),  # Velocity1
    (0.0693, 0.1170, "default", 1.0, 3.11, 0.05),  # Velocity2
    (0.0693, 0.1170, "default", 3.0 * 1023, 3.11 / (3 * 1023), 0.005),  # VelocityConversion
    (1.97, 0.179, "ctre-v5", 1.0, 259.21276731541178, 0.00005),  # VelocityCTRE
    (1.97, 0.179, "ctre-v5", 3.0, 259.21276731541178 / 3, 0.00005),  # VelocityCTREConversion
    (1.97, 0.179, "rev-neo-builtin", 1.0, 0.00241, 0.005),  # VelocityREV
]


@pytest.mark.parametrize(("kv", "ka", "preset", "enc", "kp", "tol"), VELOCITY_CASES)
def test_velocity_gains_match_sysid_tests(kv, ka, preset, enc, kp, tol):
    got_kp, got_kd = sysid_gains("velocity", kv, ka, preset, encoder_factor=enc)
    assert got_kp == pytest.approx(kp, abs=tol)
    assert got_kd == 0.0


def test_position_gains_match_sysid_tests():
    kp, kd = sysid_gains("position", 3.060, 0.327, "default")
    assert kp == pytest.approx(6.41, abs=0.05)
    assert kd == pytest.approx(2.48, abs=0.05)
    # PositionREV: 1 ms period, 112 ms delay, not time-normalised (kD divided by the period).
    kp, kd = sysid_gains("position", 3.060, 0.327, "rev-neo-builtin")
    assert kp == pytest.approx(0.30202, abs=0.05)
    assert kd == pytest.approx(48.518, abs=0.05)


def test_position_latency_compensation_matches_sysid_test():
    g = design_position_lqr(3.060, 0.327, qp=1, qv=1.5, r=7, period=0.02, delay=0.010)
    assert g.kP == pytest.approx(5.92, abs=0.05)
    assert g.kD == pytest.approx(2.12, abs=0.05)


@pytest.mark.parametrize(("kv", "ka"), [(3.06, 0.327), (0.0693, 0.117), (1.97, 0.179), (0.5, 0.02)])
def test_lqr_agrees_with_python_control_dlqr(kv, ka):
    # An independent Riccati solver (python-control's dlqr) on the same discretised plant.
    a = np.array([[0.0, 1.0], [0.0, -kv / ka]])
    b = np.array([[0.0], [1.0 / ka]])
    ad, bd = discretize(a, b, 0.02)
    k_ref, _, _ = control.dlqr(ad, bd, np.diag([1.0, 1 / 1.5**2]), np.array([[1 / 49.0]]))
    g = design_position_lqr(kv, ka, qp=1, qv=1.5, r=7, period=0.02)
    assert [g.kP, g.kD] == pytest.approx(np.asarray(k_ref).ravel(), rel=1e-8)


def test_lqr_is_unit_invariant():
    # Designing in rotations with tolerances in rotations = designing in rad and converting.
    kv, ka, n = 3.06, 0.327, 1 / (2 * math.pi)
    g_rad = design_position_lqr(kv, ka, qp=0.5 / n, qv=2 / n, r=7)
    g_rot = design_position_lqr(kv / n, ka / n, qp=0.5, qv=2, r=7)
    assert g_rot.kP == pytest.approx(g_rad.kP / n, rel=1e-9)
    assert g_rot.kD == pytest.approx(g_rad.kD / n, rel=1e-9)


def test_delay_lowers_gains_and_zero_delay_changes_nothing():
    g0 = design_velocity_lqr(3.06, 0.327)
    g1 = design_velocity_lqr(3.06, 0.327, delay=0.02)
    assert g1.kP < g0.kP
    k = lqr_gain(np.array([[-3.06 / 0.327]]), np.array([[1 / 0.327]]), (1.5,), 7, period=0.02, delay=0.0)
    assert k[0, 0] == g0.kP


def test_negligible_ka_follows_sysid_special_cases():
    assert design_velocity_lqr(1.0, 1e-9).kP == 0.0
    g = design_position_lqr(2.0, 0.0)
    assert g.kD == 0.0
    assert g.kP > 0


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [({"ka": -0.1}, "kA"), ({"kv": 0.0}, "kV"), ({"period": 0.0}, "period"), ({"delay": -1}, "delay"), ({"r": 0}, "r")],
)
def test_bad_design_inputs_raise(kwargs, match):
    args = {"kv": 1.0, "ka": 0.1, **kwargs}
    with pytest.raises(OptionError, match=match):
        design_velocity_lqr(args.pop("kv"), args.pop("ka"), **args)


@pytest.mark.parametrize(
    ("loop", "ff", "rise", "overshoot"),
    [
        ("velocity", Feedforward(0.1, 3.06, 0.327), 0.12, 5.0),
        ("velocity", Feedforward(0.1, 0.5, 0.05), 0.06, 10.0),
        ("position", Feedforward(0.1, 3.06, 0.327), 0.3, 5.0),
        ("position", Feedforward(0.1, 0.5, 0.02), 0.15, 0.0),
        ("position", Feedforward(0.1, 1.2, 0.05), 0.2, 15.0),
    ],
)
def test_pole_placement_meets_request_on_linear_plant(loop, ff, rise, overshoot):
    g = design_pid_poles(loop, ff, rise_time=rise, overshoot=overshoot, period=0.01)
    tr, os_ = linear_step_metrics(g, ff, horizon=15 * rise)
    assert tr == pytest.approx(rise, rel=0.05)
    assert os_ <= overshoot + 0.3
    assert g.kP > 0
    assert g.kI >= 0
    assert g.kD >= 0


def test_pole_placement_rejects_impossible_requests():
    ff = Feedforward(0.0, 3.06, 0.327)
    with pytest.raises(OptionError, match="shorter rise time"):
        design_pid_poles("velocity", ff, rise_time=1.0)
    with pytest.raises(OptionError, match="periods"):
        design_pid_poles("position", ff, rise_time=0.01, period=0.02)
    with pytest.raises(OptionError, match="overshoot"):
        design_pid_poles("position", ff, rise_time=0.3, overshoot=120)
