"""Gains for smart motor controllers, as WPILib SysId's feedback presets define them.

SysId (wpilibsuite/allwpilib, ``sysid/src/main/native/include/sysid/analysis/FeedbackControllerPreset.h``)
describes each controller by five numbers, and ``FeedbackAnalysis.cpp`` applies them to the LQR gains:

================  ===========  ==============  ======  ==========  ===========
preset            output/volt  velocity time   period  normalized  meas. delay
================  ===========  ==============  ======  ==========  ===========
CTRE Phoenix 5    1023/12      0.1 (per 100ms) 1 ms    no          81.5 ms
CTRE Phoenix 6    1            1               1 ms    yes         1 ms
REV, brushless    1/12         60 (per minute) 1 ms    no          112 ms
 encoder port
REV, brushed      1/12         60              1 ms    no          81.5 ms
 port/data port
================  ===========  ==============  ======  ==========  ===========

* Position loop: ``Kp = K[0]·out``, ``Kd = K[1]·out / (1 if normalized else period)``.
* Velocity loop: ``Kp = K·out / (velocity time factor · encoder factor)``, where the encoder factor
  converts the user's unit to the controller's (ticks per rotation for Phoenix 5, 1 for rotations).
* The LQR is discretised at the preset's period and latency-compensated for its measurement delay.

The delays: Phoenix 5 and a REV encoder on the data port measure velocity as a 100 ms backward
difference (50 ms) averaged over 64 samples 1 ms apart (31.5 ms); a NEO's built-in encoder on a
SPARK averages 8 samples 32 ms apart (112 ms); Phoenix 6 devices filter with ~1 ms latency.

motorlab designs in SI (volts per radian) with the preset's period and delay (``--period`` and
``--delay`` left empty), then converts:

``phoenix6``  (TalonFX/Kraken, ``Slot0Configs``, ``PositionVoltage``/``VelocityVoltage``): volts per
    rotation of the shaft the gains are for, rotations per second; kS, kV, kA in the same units.
``phoenix5``  (Talon SRX/Victor SPX, ``config_kP`` …): native units: 1023 = full output at the
    nominal voltage (enable voltage compensation), position in ticks (``--cpr``), velocity in ticks
    per 100 ms, kD per 1 ms loop; kF = kV in those units; kS as an arbitrary feedforward fraction.
``spark``, ``spark-data-port``  (REV SPARK MAX/Flex, REVLib's closed loop): duty cycle (1 = full)
    per rotation and per RPM (the encoder's default units: conversion factor 1), kD per 1 ms loop;
    FF (velocityFF) = kV per RPM; kS as an arbitrary feedforward in volts.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from motorlab.control.design import Feedforward, Gains
from motorlab.control.plant import MechanismUnits
from motorlab.errors import OptionError

TWO_PI = 2 * math.pi


@dataclass(frozen=True)
class Preset:
    """One SysId feedback preset (the names as in ``FeedbackControllerPreset.h``)."""

    output_per_volt_at_12: float  #: outputConversionFactor (per volt at SysId's 12 V)
    velocity_time_factor: float  #: outputVelocityTimeFactor
    period: float  #: [s]
    normalized: bool
    measurement_delay: float  #: [s]


#: SysId's presets (allwpilib FeedbackControllerPreset.h: kCTREv5, kCTREv6, kREVNEOBuiltIn, kREVNonNEO).
PRESETS = {
    "phoenix5": Preset(1023.0 / 12.0, 0.1, 0.001, False, 0.0815),
    "phoenix6": Preset(1.0, 1.0, 0.001, True, 0.001),
    "spark": Preset(1.0 / 12.0, 60.0, 0.001, False, 0.112),
    "spark-data-port": Preset(1.0 / 12.0, 60.0, 0.001, False, 0.0815),
}


def preset_gains(gains: Gains, feedforward: Feedforward, target: str, units: MechanismUnits,
                 voltage: float) -> tuple[dict[str, float], dict[str, float], dict[str, str], list[str], list[str]]:
    """Gains and feedforward in ``target``'s units: ``(gains, feedforward, units, conversion, notes)``.

    Raises
    ------
    OptionError
        Phoenix 5 without ``--cpr`` (its native units are encoder ticks).
    """
    p = PRESETS[target]
    vel = gains.loop == "velocity"
    time = p.velocity_time_factor  # error per second → per 100 ms (0.1) or per minute (60)
    notes: list[str] = []
    if target == "phoenix6":
        per, out, pos, speed, out_name = 1.0 / TWO_PI, 1.0, "rot", "rot/s", "V"  # rotations per rad
        conv = ["rotations: gains [V per rad, rad/s] × 2π = V per rotation, per rotation/s (time-normalised)"]
        notes.append("rotations of the shaft the gains are for: set SensorToMechanismRatio so that the TalonFX "
                     "counts them")
    elif target == "phoenix5":
        if units.cpr is None:
            raise OptionError("target phoenix5 works in encoder ticks: give --cpr (2048 for a Falcon 500's "
                              "integrated sensor, 4096 for a CTRE Mag Encoder)")
        per = units.cpr / TWO_PI  # ticks per rad
        out, pos, speed, out_name = 1023.0 / voltage, "tick", "tick/100ms", "output"
        conv = [f"ticks: cpr = {units.cpr:g}; output: 1023 = {voltage:g} V (voltage compensation on)",
                "velocity in ticks per 100 ms"]
    else:
        per = 1.0 / TWO_PI  # rotations per rad
        out, pos, speed, out_name = 1.0 / voltage, "rot", "rpm", "duty"
        conv = [f"rotations and RPM (the encoder's conversion factors left at 1); duty cycle: 1 = {voltage:g} V"]
    native = out / (per * time)  # V per rad/s → output per unit of the controller's velocity
    ff = {"kS": feedforward.kS / voltage if target == "phoenix5" else feedforward.kS,
          "kV": feedforward.kV * native, "kA": feedforward.kA * native}
    unit_map = {"kS": "output fraction (1 = full)" if target == "phoenix5" else "V",
                "kV": f"{out_name}/({speed})", "kA": f"{out_name}/({speed}/s)"}
    if vel:
        kp = gains.kP * out / (per * time)
        ki = gains.kI * out / (per * time) * (1.0 if p.normalized else p.period)
        kd = gains.kD * out / (per * time) / (1.0 if p.normalized else p.period)
        err = speed
    else:
        kp = gains.kP * out / per
        ki = gains.kI * out / per * (1.0 if p.normalized else p.period)
        kd = gains.kD * out / per / (1.0 if p.normalized else p.period)
        err = pos
    g = {"kP": kp, "kI": ki, "kD": kd}
    if target != "phoenix6":
        g["kF"] = ff["kV"]  # the controller's velocity feedforward (Phoenix 5 kF, REVLib velocityFF)
        unit_map["kF"] = unit_map["kV"]
    per_loop = "" if p.normalized else " per 1 ms loop"
    step = "s" if p.normalized else "ms"
    output = {"V": "V", "output": f"output (1023 = {voltage:g} V)", "duty": f"duty cycle (1 = {voltage:g} V)"}
    unit_map.update({"kP": f"{out_name}/({err})", "kI": f"{out_name}/({err}*{step})",
                     "kD": f"{out_name}*{step}/({err})", "output": output[out_name], "position": pos,
                     "velocity": f"{pos}/s"})
    conv.append(f"SysId preset: period {p.period * 1e3:g} ms, measurement delay {p.measurement_delay * 1e3:g} ms, "
                f"{'time-normalised' if p.normalized else 'kI, kD' + per_loop}")
    return g, ff, unit_map, conv, notes
