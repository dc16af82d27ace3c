"""Flywheel inertia and reflection; drawing units around the catalogue values."""

from __future__ import annotations

import math

import numpy as np
import pytest

from motorlab.catalog import Motor
from motorlab.errors import OptionError
from motorlab.model import PARAMETER_NAMES, MotorParams
from motorlab.rig.flywheel import Disc, Flywheel
from motorlab.rig.units import Commutator, UnitSpread, draw_unit, unit_name


def test_disc_inertia_is_half_m_r_squared() -> None:
    disc = Disc(radius=0.075, thickness=0.05, material="steel")
    assert disc.mass == pytest.approx(math.pi * 0.075**2 * 0.05 * 7850)
    assert disc.inertia == pytest.approx(0.5 * disc.mass * 0.075**2)
    # Seed 1's disc: its formula gives 0.0195 kg·m² (the seed's text says 0.0124, a slip).
    assert disc.inertia == pytest.approx(0.01951, rel=1e-3)
    assert Disc(0.038, 0.076, 2600.0).inertia == pytest.approx(0.5 * math.pi * 0.038**4 * 2600 * 0.076)
    with pytest.raises(OptionError):
        Disc(radius=-1.0)
    with pytest.raises(OptionError):
        Disc(material="cheese")


def test_flywheel_reflects_through_the_ratio() -> None:
    fw = Flywheel(ratio=25.0, viscous_friction=1e-4, coulomb_friction=2e-3, gear_inertia=0.0)
    p = MotorParams(K=0.7, R=1.0, L=7e-4, J=0.01, b=0.008, Tf=0.14)
    loaded = fw.attach(p)
    assert loaded.J == pytest.approx(0.01 + fw.disc.inertia * 625)
    assert loaded.b == pytest.approx(0.008 + 1e-4 * 625)
    assert loaded.Tf == pytest.approx(0.14 + 2e-3 * 25)  # a torque reflects by N, not N²
    assert (loaded.K, loaded.R, loaded.L) == (p.K, p.R, p.L)


def test_default_flywheel_spinup_takes_tens_of_seconds() -> None:
    loaded = Flywheel().attach(Motor.from_catalog("neverest40").nominal_params())
    assert 10.0 < loaded.mechanical_time_constant < 60.0
    assert 30.0 < loaded.J / loaded.b < 120.0  # coast time constant: the seed's flywheel coasts ~a minute


def test_unit_names() -> None:
    assert [unit_name(k) for k in (0, 1, 2, 25, 26, 27)] == ["A", "B", "C", "Z", "AA", "AB"]
    with pytest.raises(OptionError):
        unit_name(-1)


def test_draw_unit_is_deterministic_and_units_differ() -> None:
    motor = Motor.from_catalog("neverest40")
    a1, a2, b = draw_unit(motor, 0), draw_unit(motor, 0), draw_unit(motor, 1)
    assert a1 == a2
    assert a1 != b
    other = draw_unit(Motor.from_catalog("neverest20"), 0)
    nominal40, nominal20 = motor.nominal_params(), Motor.from_catalog("neverest20").nominal_params()
    assert a1.K / nominal40.K != pytest.approx(other.K / nominal20.K)  # the motor's key enters the draw
    with pytest.raises(OptionError):
        draw_unit(motor, -1)


def test_draw_unit_spreads_are_as_documented() -> None:
    motor = Motor.from_catalog("neverest20")
    nominal = motor.nominal_params()
    spread = UnitSpread()
    logs = np.array([[math.log(getattr(draw_unit(motor, s), n) / getattr(nominal, n)) for n in PARAMETER_NAMES]
                     for s in range(400)])
    for k, name in enumerate(PARAMETER_NAMES):
        sigma = getattr(spread, name)
        assert abs(logs[:, k].mean()) < 4 * sigma / math.sqrt(400)
        assert logs[:, k].std() == pytest.approx(sigma, rel=0.15)


def test_commutator_positions() -> None:
    p = MotorParams(K=0.35, R=1.9, L=690e-6, J=0.004, b=0.002, Tf=0.07)
    com = Commutator()
    true = com.positions(p, 2000, np.random.default_rng(0))
    assert np.all(np.abs(true["inductance"] / p.L - 1) <= com.inductance_variation + 1e-12)
    winding = p.R - com.mean_good_contact
    assert np.all(true["dc_resistance"] >= winding * (1 - com.resistance_variation))
    assert np.all(true["ac_resistance"] > true["dc_resistance"])
    poor = true["contact_resistance"] > 0.25 * p.R
    assert poor.mean() == pytest.approx(com.poor_contact_probability, abs=0.04)
    # The model's R is the running resistance: a good contact reads R on average.
    good = true["dc_resistance"][~poor]
    assert good.mean() == pytest.approx(p.R, abs=4 * good.std() / np.sqrt(good.size))
