"""CTRE and REV targets against WPILib SysId's own preset numbers (allwpilib
sysid/src/test/native/cpp/analysis/FeedbackAnalysisTest.cpp: Kv, Ka per unit, LQR qp=1 qv=1.5 r=7)."""

from __future__ import annotations

import math

import pytest

from motorlab.control import Feedforward
from motorlab.control.emit import emit_snippet
from motorlab.control.plant import MechanismUnits, Plant
from motorlab.control.presets import PRESETS
from motorlab.control.targets import TARGET_INFO, TARGETS
from motorlab.control.tune import DesignRequest, tune
from motorlab.errors import OptionError


def _gains(loop: str, kv: float, ka: float, target: str, *, cpr: float | None = None, delay: float | None = None,
           period: float | None = None) -> dict[str, float]:
    """SysId's tests give Kv, Ka per rotation: motorlab's plant is per radian (× 1/2π)."""
    units = MechanismUnits.from_options("rotations", cpr=cpr)
    plant = Plant(Feedforward(0.0, kv / (2 * math.pi), ka / (2 * math.pi)))
    info = TARGET_INFO[target]
    # SysId's tolerances, given explicitly (per rotation: the unit in use), since tune's defaults are physical.
    request = DesignRequest(loop, target=target, units=units, period=info.period if period is None else period,
                            delay=info.delay if delay is None else delay, qp=1.0, qv=1.5, r=7.0)
    result = tune(plant, request)
    return result.target.gains


def test_sysid_presets_are_copied_exactly() -> None:
    assert PRESETS["phoenix5"].output_per_volt_at_12 == 1023.0 / 12.0
    assert PRESETS["phoenix5"].velocity_time_factor == 0.1
    assert PRESETS["phoenix5"].measurement_delay == pytest.approx(0.0815)
    assert (PRESETS["phoenix6"].period, PRESETS["phoenix6"].measurement_delay) == (0.001, 0.001)
    assert PRESETS["spark"].measurement_delay == pytest.approx(0.112)
    assert PRESETS["spark-data-port"].measurement_delay == pytest.approx(0.0815)
    assert {"phoenix6", "phoenix5", "spark", "spark-data-port"} <= set(TARGETS)


def test_velocity_phoenix5_matches_sysid() -> None:
    # VelocityCTRE: Kp = 259.21276731541178 (±5e-5); VelocityCTREConversion: the same ÷ 3 with 3 ticks per rotation.
    assert _gains("velocity", 1.97, 0.179, "phoenix5", cpr=1)["kP"] == pytest.approx(259.21276731541178, abs=5e-4)
    assert _gains("velocity", 1.97, 0.179, "phoenix5", cpr=3)["kP"] == pytest.approx(259.21276731541178 / 3, abs=5e-4)


def test_spark_matches_sysid() -> None:
    # PositionREV: Kp 0.30202, Kd 48.518 (±0.05); VelocityREV: 0.00241 (±0.005).
    position = _gains("position", 3.060, 0.327, "spark")
    assert position["kP"] == pytest.approx(0.30202, abs=0.05)
    assert position["kD"] == pytest.approx(48.518, abs=0.05)
    assert _gains("velocity", 1.97, 0.179, "spark")["kP"] == pytest.approx(0.00241, abs=0.005)


def test_default_preset_and_its_latency_compensation_match_sysid() -> None:
    # Position: 6.41, 2.48; PositionWithLatencyCompensation (10 ms): 5.92, 2.12 (±0.05), per rotation.
    plain = _gains("position", 3.060, 0.327, "volts", period=0.02, delay=0.0)
    delayed = _gains("position", 3.060, 0.327, "volts", period=0.02, delay=0.010)
    assert (plain["kP"], plain["kD"]) == (pytest.approx(6.41, abs=0.05), pytest.approx(2.48, abs=0.05))
    assert (delayed["kP"], delayed["kD"]) == (pytest.approx(5.92, abs=0.05), pytest.approx(2.12, abs=0.05))
    # Phoenix 6 works in volts per rotation, time-normalised: the Default preset's numbers at 1 ms.
    phoenix6 = _gains("position", 3.060, 0.327, "phoenix6")
    same = _gains("position", 3.060, 0.327, "volts", period=0.001, delay=0.001)
    assert phoenix6["kP"] == pytest.approx(same["kP"])
    assert phoenix6["kD"] == pytest.approx(same["kD"])


def test_feedforward_in_the_controllers_units() -> None:
    units = MechanismUnits.from_options("rotations", cpr=2048)
    plant = Plant(Feedforward(0.24, 1.2 / (2 * math.pi), 0.1 / (2 * math.pi)))
    five = tune(plant, DesignRequest("velocity", target="phoenix5", units=units, period=0.001, delay=0.0815)).target
    # kF: output (1023 = 12 V) per tick/100 ms = kV [V per rot/s] × 1023/12 / (2048 × 0.1)
    assert five.gains["kF"] == pytest.approx(1.2 * 1023 / 12 / (2048 * 0.1))
    assert five.feedforward["kS"] == pytest.approx(0.24 / 12)
    spark = tune(plant, DesignRequest("velocity", target="spark", units=units, period=0.001, delay=0.112)).target
    assert spark.gains["kF"] == pytest.approx(1.2 / 60 / 12)  # duty cycle per RPM
    six = tune(plant, DesignRequest("velocity", target="phoenix6", units=units, period=0.001, delay=0.001)).target
    assert six.feedforward == {"kS": pytest.approx(0.24), "kV": pytest.approx(1.2), "kA": pytest.approx(0.1)}
    assert "Slot0Configs" in emit_snippet(six, "java")
    assert "slot0.k_p" in emit_snippet(six, "python")
    assert "config_kF(0, " in emit_snippet(five, "java")
    assert "velocityFF(" in emit_snippet(spark, "java")
    with pytest.raises(OptionError):
        emit_snippet(spark, "python")
    with pytest.raises(OptionError, match="cpr"):
        tune(plant, DesignRequest("velocity", target="phoenix5", units=MechanismUnits.from_options("rotations")))
