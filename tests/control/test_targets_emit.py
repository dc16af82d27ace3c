"""Target conversions (FTC PIDF F convention, power, units) and emitted snippets."""

from __future__ import annotations

import math
import re

import pytest

from motorlab.control.design import Feedforward, design_position_lqr, design_velocity_lqr
from motorlab.control.emit import emit_snippet
from motorlab.control.plant import MechanismUnits
from motorlab.control.targets import HUB_FULL_SCALE, TARGETS, to_target
from motorlab.errors import OptionError

FF = Feedforward(0.25, 0.62, 0.012)  # SI: V, V·s/rad, V·s²/rad
CPR = 537.7
TICKS = MechanismUnits.from_options("ticks", cpr=CPR)


def test_ftc_pidf_f_gives_full_output_at_max_velocity():
    g = design_velocity_lqr(FF.kV, FF.kA)
    for volts in (12.0, 13.5):
        tg = to_target(g, FF, "ftc-pidf", units=TICKS, voltage=volts)
        v_max_ticks = FF.free_speed(volts) * CPR / (2 * math.pi)
        assert tg.gains["kF"] * v_max_ticks == pytest.approx(HUB_FULL_SCALE, rel=1e-12)
        # P round trip: hub units back to volts per rad/s.
        assert tg.gains["kP"] / (HUB_FULL_SCALE / volts) * (CPR / (2 * math.pi)) == pytest.approx(g.kP, rel=1e-12)
        # The equivalent feedforward (what the simulation applies) reaches the battery voltage there.
        assert tg.equivalent_feedforward.voltage(FF.free_speed(volts)) == pytest.approx(volts)


def test_ftc_power_feedforward_is_full_power_at_free_speed():
    g = design_position_lqr(FF.kV, FF.kA)
    tg = to_target(g, FF, "ftc-power", units=TICKS, voltage=12.0)
    v = FF.free_speed(12.0) * CPR / (2 * math.pi)  # ticks/s
    assert tg.feedforward["kS"] + tg.feedforward["kV"] * v == pytest.approx(1.0)
    assert tg.gains["kP"] * 12.0 * CPR / (2 * math.pi) == pytest.approx(g.kP)


@pytest.mark.parametrize(("units", "per_rad"), [("rotations", 1 / (2 * math.pi)), ("degrees", 180 / math.pi)])
def test_volts_target_in_user_units(units, per_rad):
    g = design_position_lqr(FF.kV, FF.kA)
    tg = to_target(g, FF, "volts", units=MechanismUnits.from_options(units))
    assert tg.gains["kP"] == pytest.approx(g.kP / per_rad)
    assert tg.feedforward["kV"] == pytest.approx(FF.kV / per_rad)
    assert tg.feedforward["kS"] == FF.kS


def test_wheel_radius_gives_metres():
    u = MechanismUnits.from_options(wheel_radius=0.05)
    tg = to_target(design_velocity_lqr(FF.kV, FF.kA), FF, "wpilib", units=u)
    assert tg.feedforward["kV"] == pytest.approx(FF.kV / 0.05)
    assert tg.units["kV"] == "V*s/m"


def test_bad_targets_raise():
    g = design_position_lqr(FF.kV, FF.kA)
    with pytest.raises(OptionError, match="velocity loop"):
        to_target(g, FF, "ftc-pidf", units=TICKS)
    with pytest.raises(OptionError, match="--cpr"):
        to_target(g, FF, "ftc-power")
    with pytest.raises(OptionError, match="unknown target"):
        to_target(g, FF, "talon")
    with pytest.raises(OptionError, match="--cpr"):
        MechanismUnits.from_options("ticks")


def _numbers(text: str) -> list[float]:
    return [float(x) for x in re.findall(r"(?<![\w.])-?\d+\.\d*(?:e-?\d+)?", text)]


@pytest.mark.parametrize("target", TARGETS)
@pytest.mark.parametrize("language", ["java", "kotlin", "python"])
def test_snippets_contain_the_gains(target, language):
    loop = "velocity"
    g = design_velocity_lqr(FF.kV, FF.kA)
    units = MechanismUnits.from_options("rad", cpr=TICKS.cpr, wheel_radius=0.02) if target == "pedro" else TICKS
    tg = to_target(g, FF, target, units=units)
    if language == "python" and (target.startswith("ftc") or target in ("roadrunner", "pedro")):
        with pytest.raises(OptionError, match="Java or Kotlin"):
            emit_snippet(tg, language)
        return
    from motorlab.control.targets import TARGET_INFO

    if language not in TARGET_INFO[target].languages:  # the vendors' examples are Java (Phoenix 6: Python too)
        with pytest.raises(OptionError, match="--emit java"):
            emit_snippet(tg, language)
        return
    text = emit_snippet(tg, language)
    found = _numbers(text)
    for value in [*tg.gains.values(), *(tg.feedforward.values() if target != "ftc-pidf" else [])]:
        assert any(math.isclose(value, x, rel_tol=1e-5, abs_tol=1e-12) for x in found), (value, text)
    assert loop in text
    if target == "ftc-pidf":
        assert "setVelocityPIDFCoefficients(" in text
    if target == "wpilib":
        assert "PIDController(kP, kI, kD, 0.02)" in text


def test_unknown_language_raises():
    tg = to_target(design_velocity_lqr(FF.kV, FF.kA), FF)
    with pytest.raises(OptionError, match="language"):
        emit_snippet(tg, "rust")
