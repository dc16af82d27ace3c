"""Gains for Road Runner's MecanumDrive.PARAMS and Pedro Pathing's constants."""

from __future__ import annotations

import json
import math

import pytest

from motorlab.cli import main
from motorlab.control import Feedforward, Gains, MechanismUnits, emit_snippet, to_target
from motorlab.errors import OptionError

FF = Feedforward(0.3, 0.125, 0.0124)  # V, V·s/rad, V·s²/rad at a dead wheel's encoder
POS = Gains("position", kP=2.5, kD=0.45)


def test_roadrunner_units_are_ticks():
    units = MechanismUnits.from_options("rad", cpr=8192, wheel_radius=0.0175)
    tg = to_target(POS, FF, "roadrunner", units=units)
    per_tick = 2 * math.pi / 8192
    assert tg.feedforward["kV"] == pytest.approx(0.125 * per_tick)
    assert tg.feedforward["kA"] == pytest.approx(0.0124 * per_tick)
    assert tg.feedforward["kS"] == 0.3
    assert tg.feedforward["inPerTick"] == pytest.approx(2 * math.pi * 0.0175 / 8192 / 0.0254)
    # a position error of e volts-worth: kV·axialGain = kP
    assert tg.gains["axialGain"] * FF.kV == pytest.approx(POS.kP)
    assert tg.gains["headingVelGain"] * FF.kV == pytest.approx(POS.kD)
    java = emit_snippet(tg, "java")
    assert "public double kV = " in java
    assert "public double inPerTick" in java
    kotlin = emit_snippet(tg, "kotlin")
    assert "MecanumDrive.PARAMS.apply {" in kotlin
    assert "    kA = " in kotlin
    # MecanumDrive by default; TankDrive.Params on request: the same feedforward, its turn controller instead of
    # the holonomic path gains, and never both classes' fields in one snippet.
    assert "double turnGain" not in java
    assert "TankDrive.Params" not in java
    tank = emit_snippet(tg, "java", drive="tank")
    assert "public double kV = " in tank
    assert "public double turnGain = " in tank
    assert "double axialGain" not in tank
    assert "lateralInPerTick" not in tank
    assert "MecanumDrive.Params" not in tank
    assert tg.gains["turnGain"] == tg.gains["headingGain"]
    assert "TankDrive.PARAMS.apply {" in emit_snippet(tg, "kotlin", drive="tank")
    with pytest.raises(OptionError, match="drive"):
        emit_snippet(tg, "java", drive="swerve")
    with pytest.raises(OptionError, match="Java or Kotlin"):
        emit_snippet(tg, "python")
    with pytest.raises(OptionError, match="--cpr"):
        to_target(POS, FF, "roadrunner")


@pytest.mark.parametrize("gains", [POS, Gains("velocity", kP=0.568297)])
def test_roadrunner_note_computes_the_gains_its_table_shows(gains):
    """The conversion note names each path gain with the formula that gives its value in the table (it
    said axialGain = kP/kV for a velocity loop whose axialGain is 0)."""
    tg = to_target(gains, FF, "roadrunner", units=MechanismUnits.from_options("rad", cpr=8192))
    note = next(line for line in tg.conversion if line.startswith("path gains"))
    for name in ("axialGain", "axialVelGain"):
        formula = note.split(f"{name} = ")[1].split(";")[0].split(" (")[0]
        if formula.startswith("0"):
            assert tg.gains[name] == 0.0, name
        else:
            numerator, denominator = formula.split(" = ")[1].split("/")
            assert tg.gains[name] == pytest.approx(float(numerator) / float(denominator), rel=1e-5), name


def test_pedro_constants_from_the_model():
    units = MechanismUnits.from_options("rad", cpr=8192, wheel_radius=0.0175)
    tg = to_target(POS, FF, "pedro", units=units, voltage=12.0)
    in_per_rad = 0.0175 / 0.0254
    assert tg.feedforward["xVelocity"] == pytest.approx((12.0 - 0.3) / 0.125 * in_per_rad)
    assert tg.feedforward["forwardZeroPowerAcceleration"] == pytest.approx(-0.3 / 0.0124 * in_per_rad)
    assert tg.feedforward["staticFrictionCoefficient"] == pytest.approx(0.3 / 12.0)
    java = emit_snippet(tg, "java")
    assert ".xVelocity(" in java
    assert "new FollowerConstants()" in java
    assert java.count(";") >= 2
    assert "val driveConstants = MecanumConstants()" in emit_snippet(tg, "kotlin")
    with pytest.raises(OptionError, match="--wheel-radius"):
        to_target(POS, FF, "pedro", units=MechanismUnits.from_options("rad", cpr=8192))


def test_cli_target_roadrunner(capsys):
    code = main(["tune", "position", "--kv", "0.125", "--ka", "0.0124", "--ks", "0.3", "--cpr", "8192",
                 "--target", "roadrunner", "--emit", "java"])
    out = capsys.readouterr().out
    assert code == 0
    assert "public double kS = 0.3;" in out
    assert main(["tune", "position", "--kv", "0.125", "--ka", "0.0124", "--target", "roadrunner"]) == 2


def test_ramp_geometry_reaches_the_snippets(tmp_path, capsys):
    doc = {"experiment": "feedforward", "parameters": {
        "kS": {"value": 0.3, "stderr": 0.01, "unit": "V"}, "kV": {"value": 0.125, "stderr": 1e-4, "unit": "V*s/rad"},
        "kA": {"value": 0.0124, "stderr": 1e-3, "unit": "V*s^2/rad"},
        "lateral_ratio": {"value": 0.85, "stderr": 1e-3, "unit": "1"},
        "lateral_kA": {"value": 0.0155, "stderr": 1e-3, "unit": "V*s^2/rad"},
        "track_width_ticks": {"value": 23840.0, "stderr": 6.0, "unit": "tick"}}}
    path = tmp_path / "rr.json"
    path.write_text(json.dumps(doc))
    common = ["tune", "position", "--params", str(path), "--cpr", "8192", "--wheel-radius", "17.5mm",
              "--qp", "0.0127", "--qv", "0.127", "--emit", "java"]
    assert main([*common, "--target", "roadrunner"]) == 0
    out = capsys.readouterr().out
    assert "public double trackWidthTicks = 23840.0;" in out
    in_per_tick = 2 * math.pi * 0.0175 / 8192 / 0.0254
    assert f"lateralInPerTick = {0.85 * in_per_tick:.6g};" in out
    assert main([*common, "--target", "pedro"]) == 0
    out = capsys.readouterr().out
    x = (12.0 - 0.3) / 0.125 * 0.0175 / 0.0254
    assert f".yVelocity({0.85 * x:.6g})" in out
    # Pedro's LateralZeroPowerAccelerationTuner: friction alone decelerating the strafing robot
    assert f".lateralZeroPowerAcceleration({-0.3 / 0.0155 * 0.0175 / 0.0254:.6g})" in out
