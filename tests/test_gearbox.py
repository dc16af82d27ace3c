"""The gearbox: conversions, the two directions of power flow, the simulator, the catalogue's figures."""

from __future__ import annotations

import math

import numpy as np
import pytest

from motorlab.catalog import list_motors
from motorlab.errors import OptionError
from motorlab.gearbox import (
    Drivetrain,
    Gearbox,
    OutputCurves,
    efficiency_estimate,
    refer_to_motor,
    reflect_to_output,
    speed_at_motor,
    speed_at_output,
)
from motorlab.model import MotorParams
from motorlab.model.simulate import BenchSupply, OpenCircuit, simulate

MOTOR = MotorParams(K=0.69, R=1.04, L=0.7e-3, J=0.015, b=0.004, Tf=0.07)  # output shaft, ideal gearbox


def test_conversions_between_shafts_round_trip():
    at_motor = refer_to_motor(MOTOR, 40)
    assert at_motor.K == pytest.approx(MOTOR.K / 40)
    assert at_motor.J == pytest.approx(MOTOR.J / 1600)
    assert at_motor.Tf == pytest.approx(MOTOR.Tf / 40)
    back = reflect_to_output(at_motor, 40)
    for name in ("K", "R", "L", "J", "b", "Tf"):
        assert getattr(back, name) == pytest.approx(getattr(MOTOR, name))
    assert speed_at_output(speed_at_motor(3.0, 40), 40) == pytest.approx(3.0)
    box = Gearbox(ratio=40, efficiency=0.6, loss_torque=0.05)
    assert box.motor_torque(box.output_torque(0.02)) == pytest.approx(0.02)
    assert box.output_torque(0.02) == pytest.approx(0.6 * 40 * 0.02 - 0.05)


def test_bad_gearbox_figures_are_refused():
    for kwargs in ({"efficiency": 0.0}, {"efficiency": 1.2}, {"back_efficiency": -0.1}, {"ratio": 0.0},
                   {"loss_torque": -1.0}, {"output_inertia": math.nan}):
        with pytest.raises(OptionError):
            Gearbox(**kwargs)


def test_ideal_gearbox_is_the_old_model():
    """With η = 1 and no drag both equivalents are the motor plus its load, as MotorParams.with_load."""
    train = Drivetrain(MOTOR, Gearbox(ratio=40), load_inertia=12.2, load_viscous=0.15, load_coulomb=0.1)
    assert not train.switches
    loaded = MOTOR.with_load(12.2).scaled(b=MOTOR.b + 0.15, Tf=MOTOR.Tf + 0.1)
    assert train.forward() == loaded
    assert train.backward() == loaded
    figures = train.output_figures()
    assert figures["Kt"] == figures["Ke"] == MOTOR.K


def test_lossy_gearbox_equivalents_and_physical_figures():
    box = Gearbox(ratio=40, efficiency=0.5, back_efficiency=0.4, loss_torque=0.05)
    train = Drivetrain(MOTOR, box, load_inertia=2.0)
    fwd, bwd = train.forward(), train.backward()
    assert fwd.J == pytest.approx(MOTOR.J + 2.0 / 0.5)
    assert fwd.Tf == pytest.approx(MOTOR.Tf + 0.05 / 0.5)
    assert bwd.J == pytest.approx(MOTOR.J + 2.0 * 0.4)
    assert bwd.Tf == pytest.approx(MOTOR.Tf + 0.05 * 0.4)
    phys = train.output_figures()
    assert phys["Kt"] == pytest.approx(0.5 * MOTOR.K)
    assert phys["J"] == pytest.approx(2.0 + 0.5 * MOTOR.J)
    back = train.output_figures(back_driven=True)
    assert back["Tf"] == pytest.approx(MOTOR.Tf / 0.4 + 0.05)
    # A bare gearmotor: the armature drives the gearbox's drag whenever it turns.
    bare = Drivetrain(MOTOR, box)
    assert bare.flow(0.0, 5.0, 1.0) > 0
    # A heavy flywheel coasting: it drives the motor's friction through the gearbox.
    assert train.flow(0.0, 5.0, 1.0) < 0


def _brute_force(train: Drivetrain, t_off: float, duration: float, h: float = 2e-5) -> np.ndarray:
    """Euler integration of the two-direction model (the power flow decided at each step), 12 V / 4 A."""
    fwd, bwd = train.forward(), train.backward()
    i = w = 0.0
    out = []
    for k in range(round(duration / h)):
        if k * h < t_off:
            v_needed = fwd.R * 4.0 + fwd.K * w
            i = 4.0 if v_needed <= 12.0 else (12.0 - fwd.K * w) / fwd.R
        else:
            i = 0.0
        if w == 0.0 and abs(fwd.K * i) <= fwd.Tf:
            w = 0.0
        else:
            p = fwd if train.flow(i, w, 1.0) >= 0 else bwd
            w = max(w + h * (p.K * i - p.b * w - p.Tf) / p.J, 0.0)
        if k % round(0.1 / h) == 0:
            out.append(w)
    return np.array(out)


def test_simulator_switches_with_the_power_flow():
    """Spin a load up through a lossy gearbox and let it coast: the exact simulator agrees with a fine
    Euler integration of the two-direction model, and it is neither of the single equivalents."""
    motor = MOTOR.scaled(L=0.0)
    train = Drivetrain(motor, Gearbox(ratio=40, efficiency=0.5, back_efficiency=0.6, loss_torque=0.05),
                       load_inertia=0.3, load_viscous=0.02)
    drive = [(0.0, BenchSupply(12.0, 4.0)), (1.0, OpenCircuit())]
    sim = simulate(train, drive, duration=2.0, dt=1e-3)
    reference = _brute_force(train, 1.0, 2.0)
    grid = sim.speed[::100][: reference.size]
    assert np.max(np.abs(grid - reference)) < 2e-3 * np.max(reference)
    forward_only = simulate(train.forward(), drive, duration=2.0, dt=1e-3)
    assert abs(forward_only.speed[-1] - sim.speed[-1]) > 0.05 * np.max(sim.speed)


def test_catalogue_gearboxes_reproduce_the_sheets():
    """For every catalogue motor: the output stall torque with the derived η is the sheet's, and motor +
    gearbox run free exactly as the nominal model (free speed and current unchanged)."""
    for motor in list_motors():
        box = motor.gearbox()
        nominal = motor.nominal_params()
        assert 0 < box.efficiency <= 1, motor.key
        assert box.loss_torque >= 0, motor.key
        assert OutputCurves(nominal, box.efficiency).stall_torque(motor.nominal_voltage) == pytest.approx(
            motor.stall_torque, rel=1e-9
        ), motor.key
        assert Drivetrain(motor.motor_params(), box).forward().Tf == pytest.approx(nominal.Tf), motor.key
    neverest40 = next(m for m in list_motors() if m.key == "neverest40")
    assert neverest40.gearbox().efficiency == pytest.approx(0.316, abs=0.005)  # docs/gearbox.md


def test_output_curves_scale_torque_and_power_by_eta():
    curves = OutputCurves(MOTOR, 0.4)
    plain = MOTOR.curves(12.0)
    geared = curves.curves(12.0)
    np.testing.assert_allclose(geared["torque"], 0.4 * plain["torque"])
    np.testing.assert_allclose(geared["speed"], plain["speed"])
    assert curves.stall_torque(12.0) == pytest.approx(0.4 * MOTOR.stall_torque(12.0))


def test_efficiency_estimate_propagates_both_errors():
    est = efficiency_estimate(0.3, 0.003, 0.6, 0.012)
    assert est.value == pytest.approx(0.5)
    assert est.stderr == pytest.approx(0.5 * math.hypot(0.01, 0.02))
    assert not efficiency_estimate(0.3, 0.003, 0.0, 0.0).determined
