"""The simulator against closed forms and an independent fine-step ODE solution."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from motorlab.errors import OptionError
from motorlab.model import MotorParams
from motorlab.model.simulate import (
    MODE_CURRENT,
    MODE_OPEN,
    MODE_VOLTAGE,
    BenchSupply,
    CurrentDrive,
    OpenCircuit,
    State,
    VoltageDrive,
    simulate,
)

MOTOR = MotorParams(K=0.35, R=2.0, L=0.6e-3, J=2e-4, b=1e-4, Tf=0.02)


def test_steady_state_speed_and_current_under_voltage():
    sim = simulate(MOTOR, VoltageDrive(12.0), duration=1.0, dt=1e-4)
    assert sim.speed[-1] == pytest.approx(MOTOR.free_speed(12.0), rel=1e-9)
    assert sim.current[-1] == pytest.approx(MOTOR.free_current(12.0), rel=1e-7)
    assert np.all(sim.mode[:-1] == MODE_VOLTAGE)


def test_stall_current_with_locked_rotor():
    heavy = MOTOR.with_load(1e3)
    sim = simulate(heavy, VoltageDrive(6.0), duration=0.005, dt=1e-5)
    # After many electrical time constants the current is V/R (back-EMF negligible).
    assert sim.current[-1] == pytest.approx(MOTOR.stall_current(6.0), rel=1e-3)
    # First-order rise of the current, i = V/R·(1 − e^(−t·R/L)), before the rotor moves noticeably.
    t = sim.time[:50]
    assert sim.current[:50] == pytest.approx(3.0 * -np.expm1(-t * MOTOR.R / MOTOR.L), abs=1e-4)


def test_exponential_spin_down_with_coulomb_friction_stops_exactly():
    sim = simulate(MOTOR, [(0.0, VoltageDrive(12.0)), (0.5, OpenCircuit())], duration=2.0, dt=1e-3)
    k = 500
    w0 = sim.speed[k]
    gamma, c = MOTOR.b / MOTOR.J, MOTOR.Tf / MOTOR.b
    tau = sim.time[k:] - 0.5
    expected = np.maximum((w0 + c) * np.exp(-gamma * tau) - c, 0.0)
    assert sim.speed[k:] == pytest.approx(expected, abs=1e-9)
    t_stop = math.log((w0 + c) / c) / gamma
    stops = [t for t, name in sim.events if name == "speed reached zero"]
    assert stops == [pytest.approx(0.5 + t_stop, abs=1e-9)]
    # Once stopped it stays stopped: no chatter, constant angle.
    after = sim.time > 0.5 + t_stop + 1e-3
    assert np.all(sim.speed[after] == 0.0)
    assert np.ptp(sim.position[after]) == 0.0
    # Open circuit: no current, terminal voltage is the back-EMF.
    assert np.all(sim.current[k:] == 0.0)
    assert sim.voltage[k:] == pytest.approx(MOTOR.K * sim.speed[k:])
    assert np.all(sim.mode[k:-1] == MODE_OPEN)


def test_position_is_the_exact_integral_of_speed_for_coast():
    sim = simulate(MOTOR, OpenCircuit(), duration=0.3, dt=1e-3, initial=State(speed=20.0, position=1.0))
    gamma, c, w0 = MOTOR.b / MOTOR.J, MOTOR.Tf / MOTOR.b, 20.0
    t_stop = math.log((w0 + c) / c) / gamma
    t = np.minimum(sim.time, t_stop)  # after the stop the angle stays where it was
    theta = 1.0 + (w0 + c) / gamma * -np.expm1(-gamma * t) - c * t
    assert sim.position == pytest.approx(theta, rel=1e-10)


def test_stiction_holds_the_shaft_below_break_away():
    # K·V/R = 0.35·0.1/2 = 0.0175 N·m < Tf = 0.02 N·m: the shaft never moves.
    sim = simulate(MOTOR, VoltageDrive(0.1), duration=0.2, dt=1e-4)
    assert np.all(sim.speed == 0.0)
    assert np.all(sim.position == 0.0)
    assert sim.current[-1] == pytest.approx(0.05, rel=1e-6)


def test_current_drive_constant_acceleration_and_terminal_voltage():
    p = MOTOR.scaled(b=0.0)
    sim = simulate(p, CurrentDrive(0.5), duration=0.2, dt=1e-3)
    alpha = (p.K * 0.5 - p.Tf) / p.J
    assert sim.speed == pytest.approx(alpha * sim.time, rel=1e-9, abs=1e-12)
    assert sim.position == pytest.approx(0.5 * alpha * sim.time**2, rel=1e-9, abs=1e-12)
    assert sim.voltage == pytest.approx(p.R * 0.5 + p.K * sim.speed)
    assert np.all(sim.mode[:-1] == MODE_CURRENT)


def test_bench_supply_crosses_over_from_constant_current_to_constant_voltage():
    flywheel = MOTOR.with_load(2e-3)
    supply = BenchSupply(12.0, 1.5)
    sim = simulate(flywheel, supply, duration=6.0, dt=1e-3)
    names = [name for _, name in sim.events]
    assert "supply enters constant current" in names
    assert "supply enters constant voltage" in names
    assert sim.current.max() <= 1.5 + 1e-9
    cc = sim.mode == MODE_CURRENT
    assert sim.current[cc] == pytest.approx(1.5)
    # The CC → CV crossover happens when R·I + K·ω reaches the setpoint.
    t_cv = next(t for t, name in sim.events if name == "supply enters constant voltage")
    w_cv = np.interp(t_cv, sim.time, sim.speed)
    assert flywheel.R * 1.5 + flywheel.K * w_cv == pytest.approx(12.0, rel=2e-5)  # linear interpolation of ω
    assert sim.speed[-1] == pytest.approx(flywheel.free_speed(12.0), rel=1e-3)
    assert np.all(sim.voltage <= 12.0 + 1e-9)


def test_bench_supply_cannot_sink_current():
    # Spinning faster than the setpoint's free speed: the supply stops sourcing, the motor coasts.
    sim = simulate(MOTOR, BenchSupply(3.0, 2.0), duration=0.5, dt=1e-4, initial=State(speed=30.0))
    assert sim.current.min() >= -1e-12
    assert MODE_OPEN in sim.mode
    assert sim.speed[-1] == pytest.approx(MOTOR.free_speed(3.0), rel=1e-3)


def _reference(p: MotorParams, v_of_t, t_end: float, t_eval: np.ndarray) -> np.ndarray:
    """A fine-step solution with a smooth friction law, for motion without stops."""

    def rhs(t, x):
        i, w, _ = x
        return [(v_of_t(t) - p.R * i - p.K * w) / p.L, (p.K * i - p.b * w - p.Tf * np.sign(w)) / p.J, w]

    sol = solve_ivp(rhs, (0, t_end), [0.0, 5.0, 0.0], t_eval=t_eval, method="Radau", rtol=1e-10, atol=1e-12)
    return sol.y


def test_matches_an_implicit_ode_solver_on_a_staircase_voltage():
    def volts(t):
        return np.where(np.asarray(t) < 0.05, 6.0, np.where(np.asarray(t) < 0.1, 12.0, 3.0))

    t_eval = np.linspace(0, 0.15, 151)
    sim = simulate(MOTOR, VoltageDrive(volts), duration=0.15, dt=1e-3, initial=State(speed=5.0))
    ref = _reference(MOTOR, lambda t: float(volts(t)), 0.15, t_eval)
    assert sim.current == pytest.approx(ref[0], abs=2e-4)
    assert sim.speed == pytest.approx(ref[1], abs=1e-4)
    assert sim.position == pytest.approx(ref[2], abs=1e-6)


def test_reversal_through_zero_under_a_square_wave():
    sim = simulate(MOTOR, VoltageDrive(lambda t: 12.0 * np.sign(np.sin(2 * np.pi * 2 * t) + 1e-12)),
                   duration=1.0, dt=1e-4)
    assert sim.speed.max() > 0.9 * MOTOR.free_speed(12.0)
    assert sim.speed.min() < -0.9 * MOTOR.free_speed(12.0)
    # Each reversal passes through ω = 0 once and does not stick (|K·i| ≫ Tf there).
    zeros = [t for t, name in sim.events if name == "speed reached zero"]
    assert 3 <= len(zeros) <= 4


def test_zero_inductance_is_quasi_static():
    p = MOTOR.scaled(L=0.0)
    sim = simulate(p, VoltageDrive(12.0), duration=0.5, dt=1e-3)
    assert sim.speed[-1] == pytest.approx(p.free_speed(12.0), rel=1e-6)
    assert sim.current == pytest.approx((12.0 - p.K * sim.speed) / p.R)


@pytest.mark.parametrize(
    "kwargs",
    [{"duration": 0.0}, {"duration": 1.0, "dt": -1e-3}, {"duration": math.nan}],
)
def test_rejects_impossible_settings(kwargs):
    with pytest.raises(OptionError):
        simulate(MOTOR, VoltageDrive(1.0), **kwargs)


def test_rejects_bad_supply_and_schedule():
    with pytest.raises(OptionError):
        BenchSupply(12.0, 0.0)
    with pytest.raises(OptionError):
        simulate(MOTOR, [(1.0, OpenCircuit()), (0.5, VoltageDrive(1.0))], duration=2.0)
    with pytest.raises(OptionError):
        simulate(MOTOR, VoltageDrive(lambda t: np.full_like(t, np.nan)), duration=0.1)


@pytest.mark.parametrize("seed", range(4))
def test_modal_step_equals_the_matrix_exponential(seed):
    from scipy import linalg

    from motorlab.model.simulate import _continuous, _discretise, _Regime

    rng = np.random.default_rng(seed)
    p = MotorParams(K=rng.uniform(0.05, 1), R=rng.uniform(0.5, 5), L=rng.uniform(1e-4, 2e-3),
                    J=10 ** rng.uniform(-5, 0), b=rng.uniform(0, 1e-2), Tf=rng.uniform(0, 0.1))
    for reg in (_Regime("V", 1), _Regime("V", 0), _Regime("I", -1), _Regime("O", 1)):
        names, a, bm = _continuous(p, reg)
        n = len(names)
        m = np.zeros((n + 3, n + 3))
        m[:n, :n] = a
        m[:n, n + 1 :] = bm
        if "w" in names:
            m[n, names.index("w")] = 1.0
        e = linalg.expm(m * 1e-3)
        lin = _discretise(p, reg, 1e-3)
        assert lin.ad == pytest.approx(e[:n, :n], rel=1e-9, abs=1e-12)
        assert lin.bd == pytest.approx(e[:n, n + 1 :], rel=1e-9, abs=1e-12)
        assert lin.theta_u == pytest.approx(e[n, n + 1 :], rel=1e-8, abs=1e-15)
