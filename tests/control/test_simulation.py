"""Closed-loop simulation: the plant step, metrics, and tuned gains on simulated nonlinear motors."""

from __future__ import annotations

import math

import numpy as np
import pytest

from motorlab.control.design import Feedforward, Gains, design_pid_poles, design_position_lqr, design_velocity_lqr
from motorlab.control.simulation import (
    ClosedLoopResponse,
    _ff_advance,
    max_profile,
    response_metrics,
    simulate_closed_loop,
    step_reference,
    trapezoid,
)
from motorlab.model import MotorParams, feedforward_from_params

FF = Feedforward(0.3, 1.2, 0.06)


def test_feedforward_plant_step_is_exact_without_friction():
    kv, ka, volts, dt = 1.2, 0.06, 6.0, 0.037
    x, v = _ff_advance(0.0, 0.0, volts, dt, 0.0, kv, ka)
    tau, v_inf = ka / kv, volts / kv
    assert v == pytest.approx(v_inf * (1 - math.exp(-dt / tau)), rel=1e-12)
    assert x == pytest.approx(v_inf * (dt - tau * (1 - math.exp(-dt / tau))), rel=1e-12)


def test_feedforward_plant_sticks_and_stops_exactly():
    # At rest below kS: no motion.
    assert _ff_advance(0.0, 0.0, 0.29, 1.0, 0.3, 1.2, 0.06) == (0.0, 0.0)
    # Coasting (V = 0) from 2 rad/s: stops at t0 = τ·ln(1 + v0·kV/kS) and stays stopped.
    x, v = _ff_advance(0.0, 2.0, 0.0, 1.0, 0.3, 1.2, 0.06)
    tau, v_inf = 0.05, -0.25
    t0 = tau * math.log((2.0 - v_inf) / -v_inf)
    assert v == 0.0
    assert x == pytest.approx(v_inf * t0 + (2.0 - v_inf) * tau * (1 - math.exp(-t0 / tau)), rel=1e-12)


def test_motor_plant_agrees_with_feedforward_plant_for_small_inductance():
    # Two independent integrators: motorlab.model.simulate (with L) and the exact L = 0 step here.
    p = MotorParams(K=0.35, R=1.1, L=2e-5, J=4e-4, b=1e-4, Tf=0.02)
    ff_d = feedforward_from_params(p)
    ff = Feedforward(ff_d["kS"], ff_d["kV"], ff_d["kA"])
    g = design_velocity_lqr(ff.kV, ff.kA)
    kw = {"duration": 0.4, "voltage": 12.0}
    a = simulate_closed_loop(g, ff, p, step_reference("velocity", 15.0), **kw)
    b = simulate_closed_loop(g, ff, ff, step_reference("velocity", 15.0), **kw)
    assert a.settings["plant"] == "motor"
    assert b.settings["plant"] == "feedforward"
    assert np.max(np.abs(a.speed - b.speed)) < 0.01 * 15.0


def test_metrics_of_a_first_order_response():
    tau = 0.1
    t = np.linspace(0, 2, 20001)
    y = 1 - np.exp(-t / tau)
    resp = ClosedLoopResponse(
        "velocity", "step", t, np.zeros_like(t), y, np.zeros_like(t), np.ones_like(t), 1.0,
        settings={"period": 0.01, "voltage": 12.0},
    )
    m = response_metrics(resp)
    assert m["rise_time"] == pytest.approx(tau * math.log(9), rel=1e-3)
    assert m["settling_time"] == pytest.approx(tau * math.log(50), rel=1e-3)
    assert m["overshoot"] == 0.0
    assert not m["sustained_oscillation"]


def _random_motor(rng: np.random.Generator) -> MotorParams:
    # FTC-like gearmotors at the output shaft: K 0.2-0.7 V·s/rad, R ~1 Ω, loads 1e-4-1e-2 kg·m².
    return MotorParams(
        K=rng.uniform(0.2, 0.7),
        R=rng.uniform(0.8, 2.0),
        L=0.0,
        J=10 ** rng.uniform(-4, -2),
        b=rng.uniform(0, 5e-3),
        Tf=rng.uniform(0.02, 0.15),
    )


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_lqr_gains_on_nonlinear_motor_settle_without_oscillation(seed):
    rng = np.random.default_rng(seed)
    p = _random_motor(rng)
    d = feedforward_from_params(p)
    ff = Feedforward(d["kS"], d["kV"], d["kA"])
    cpr = 537.7
    # Velocity loop: step to half the free speed, with 12 V saturation, friction and quantisation.
    # Velocity is measured as a count difference over one period: a T/2 delay, compensated as
    # SysId's presets do for backward differences.
    g = design_velocity_lqr(ff.kV, ff.kA, delay=0.01)
    size = 0.5 * ff.free_speed(12.0)
    r = simulate_closed_loop(g, ff, p, step_reference("velocity", size), duration=1.5, cpr=cpr, delay=0.0)
    assert not r.metrics["sustained_oscillation"]
    assert math.isfinite(r.metrics["settling_time"])
    assert r.metrics["overshoot"] < 10.0
    # Position loop on a trapezoidal profile: no limit cycle, ends close to the goal.
    gp = design_position_lqr(ff.kV, ff.kA, qp=0.05, qv=1.0)
    lim = max_profile(ff, 12.0)
    ref, total = trapezoid(4 * math.pi, lim.max_velocity, lim.max_acceleration)
    rp = simulate_closed_loop(gp, ff, p, ref, duration=total + 1.0, cpr=cpr, kind="profile")
    assert not rp.metrics["sustained_oscillation"]
    # Coulomb friction leaves at most kS/kP of error (plus a count) once the motor stops.
    assert abs(rp.metrics["steady_state_error"]) <= ff.kS / gp.kP + 2 * math.pi / cpr + 1e-9


@pytest.mark.parametrize(("seed", "overshoot"), [(11, 2.0), (14, 5.0), (16, 10.0)])
def test_pole_placement_meets_overshoot_on_nonlinear_motor(seed, overshoot):
    # Loaded gearmotors (flywheel-like J), Coulomb friction, 12 V saturation, 1120-count encoder with
    # velocity from a count difference over each 10 ms period (its T/2 lag is the design delay).
    rng = np.random.default_rng(seed)
    p = MotorParams(
        K=rng.uniform(0.2, 0.7),
        R=rng.uniform(0.8, 2.0),
        L=0.0,
        J=10 ** rng.uniform(-2.5, -1.5),
        b=rng.uniform(0, 5e-3),
        Tf=rng.uniform(0.02, 0.15),
    )
    d = feedforward_from_params(p)
    ff = Feedforward(d["kS"], d["kV"], d["kA"])
    rise, period = 1.1 * ff.time_constant, 0.01
    g = design_pid_poles("velocity", ff, rise_time=rise, overshoot=overshoot, period=period, delay=period / 2)
    size = 0.4 * ff.free_speed(12.0)
    r = simulate_closed_loop(
        g, ff, p, step_reference("velocity", size), duration=max(1.0, 20 * rise), cpr=1120, delay=0.0
    )
    assert not r.metrics["sustained_oscillation"]
    assert r.metrics["overshoot"] <= overshoot + 1.5
    assert r.metrics["rise_time"] == pytest.approx(rise, rel=0.1)
    assert abs(r.metrics["steady_state_error"]) < 0.02 * size


def test_saturation_clamps_voltage():
    g = Gains("position", kP=200.0, kD=5.0)
    r = simulate_closed_loop(g, FF, FF, step_reference("position", 10.0), duration=1.0, voltage=6.0)
    assert np.max(np.abs(r.voltage)) == pytest.approx(6.0)
    assert r.metrics["saturated_fraction"] > 0.1


def test_max_profile_is_followable_by_feedforward_alone():
    lim = max_profile(FF, 12.0, headroom=0.1)
    ref, total = trapezoid(30.0, lim.max_velocity, lim.max_acceleration)
    t = np.linspace(0, total, 2001)
    x, v, a = np.array([ref(ti) for ti in t]).T
    needed = FF.kS * np.sign(v) + FF.kV * v + FF.kA * a
    assert np.max(needed) <= 0.9 * 12.0 + 1e-9
    assert np.max(needed) == pytest.approx(0.9 * 12.0, rel=1e-2)  # the limit is reached (on this grid)
    assert x[-1] == pytest.approx(30.0)
    # Feedforward alone (no feedback) on the matching plant tracks the profile closely.
    r = simulate_closed_loop(Gains("position", 0.0), FF, FF, ref, duration=total, kind="profile", target=30.0)
    assert r.metrics["max_tracking_error"] < 0.01 * 30.0


def test_oscillation_detector_tells_a_creep_from_a_swing():
    from motorlab.control.simulation import _oscillates

    t = np.linspace(0.0, 1.0, 200)
    assert not _oscillates(1.0 - 0.5 * np.exp(-t), 0.01)  # monotone creep over a wide range
    assert _oscillates(np.sin(20 * t), 0.01)  # a sustained swing
    assert not _oscillates(0.002 * np.sin(20 * t), 0.01)  # inside the band
