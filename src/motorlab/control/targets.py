"""Gains in the units of the controller that will run them.

Targets
-------
``volts``
    Output in volts, lengths in the user's unit (rad, rotations, ticks, metres); time-normalised
    gains. This is SysId's "Default" preset.
``wpilib``
    The same numbers, for WPILib's ``PIDController(kP, kI, kD, period)`` and
    ``SimpleMotorFeedforward(kS, kV, kA)`` (both time-normalised, volts).
``ftc-power``
    A PID written in an FTC OpMode on encoder ticks and motor power (−1 … 1). Power is a fraction of
    the battery voltage, so gains are volts / V_nominal and the OpMode multiplies its output by
    V_nominal / V_battery (read from the hub's ``VoltageSensor``) to stay right as the battery sags.
``ftc-pidf``
    The REV hub's built-in velocity loop, ``DcMotorEx.setVelocityPIDFCoefficients(p, i, d, f)``
    (``RUN_USING_ENCODER``, ``setVelocity`` in ticks/s). The hub's output is ±32767 for full power.
    F follows FIRST's convention F = 32767 / (max velocity in ticks/s at full power)
    ("Motor PIDF Tuning Guide", FIRST Tech Challenge, 2019, section "Calculating PIDF Values from
    Maximum Velocity"; it also suggests P = 0.1·F, I = 0.1·P, D = 0). P, I, D are converted as
    32767/V_nominal output units per volt and per tick/s of error, ASSUMING the hub applies
    them as a textbook, time-normalised PID: NOT CONFIRMED. The hub firmware is closed; its loop
    period and internal scaling are undocumented, and community reverse engineering (wiki
    "(FTC) Motor PIDs", github.com/cwm9cwm9/TTGT-FTC-FRC) describes a velocity-form algorithm whose
    P and I roles differ. Treat these P/I/D as a starting point; F is the reliable part.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from motorlab.control.design import Feedforward, Gains
from motorlab.control.plant import MechanismUnits
from motorlab.errors import OptionError

TARGETS = ("volts", "wpilib", "ftc-power", "ftc-pidf")

#: Full-scale output of the REV Expansion/Control Hub motor controller (16-bit signed duty).
HUB_FULL_SCALE = 32767.0


@dataclass(frozen=True)
class TargetGains:
    """Gains and feedforward in a target's units, with the conversion shown.

    Attributes
    ----------
    target
        One of :data:`TARGETS`.
    loop
        ``"velocity"`` or ``"position"``.
    gains
        ``{"kP", "kI", "kD"}`` in the target's units; ``ftc-pidf`` adds ``"kF"``, the hub's F.
    feedforward
        ``{"kS", "kV", "kA"}`` in the target's units (for ``ftc-pidf``, the model's feedforward in hub
        units, to compare with F; the hub itself applies only F).
    units
        Unit of every number above, and of the quantities the target reads (``"position"``,
        ``"velocity"``, ``"output"``).
    conversion
        Human-readable lines showing how each number was obtained from the SI design.
    notes
        Caveats (unconfirmed conventions).
    equivalent_feedforward
        The feedforward the target actually applies, in volts and SI, for simulation.
    period
        Controller period [s].
    voltage
        Nominal battery voltage used for power/duty conversions [V].
    """

    target: str
    loop: str
    gains: dict[str, float]
    feedforward: dict[str, float]
    units: dict[str, str]
    conversion: list[str]
    notes: list[str]
    equivalent_feedforward: Feedforward
    period: float = 0.02
    voltage: float = 12.0

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: target, gains, feedforward, units, conversion, notes."""
        return {
            "target": self.target,
            "gains": dict(self.gains),
            "feedforward": dict(self.feedforward),
            "units": dict(self.units),
            "period": self.period,
            "voltage": self.voltage,
            "conversion": list(self.conversion),
            "notes": list(self.notes),
        }


def _gain_units(loop: str, out: str, length: str) -> dict[str, str]:
    if loop == "velocity":
        return {"kP": f"{out}/({length}/s)", "kI": f"{out}/{length}", "kD": f"{out}*s^2/{length}"}
    return {"kP": f"{out}/{length}", "kI": f"{out}/({length}*s)", "kD": f"{out}*s/{length}"}


def _ff_units(out: str, length: str) -> dict[str, str]:
    return {"kS": out, "kV": f"{out}*s/{length}", "kA": f"{out}*s^2/{length}"}


def to_target(
    gains: Gains,
    feedforward: Feedforward,
    target: str = "volts",
    *,
    units: MechanismUnits | None = None,
    voltage: float = 12.0,
) -> TargetGains:
    """Convert SI gains (volts per rad) and feedforward to a controller's units.

    Parameters
    ----------
    gains
        Designed gains [V per rad, rad/s ...] (:class:`Gains`).
    feedforward
        kS [V], kV [V·s/rad], kA [V·s²/rad].
    target
        One of :data:`TARGETS`.
    units
        The user's length unit (``volts``/``wpilib``) and the encoder's counts per revolution
        (required by the FTC targets, which count ticks). Default: radians.
    voltage
        Nominal battery voltage for power and duty conversions [V].

    Returns
    -------
    TargetGains

    Raises
    ------
    OptionError
        Unknown target, FTC target without ``units.cpr``, or ``ftc-pidf`` for a position loop.

    Notes
    -----
    With n length units per radian (n = cpr/2π for ticks), a gain in V per rad becomes V/n per unit.
    Power = V / V_nominal; hub output = 32767 · V / V_nominal.
    """
    units = units or MechanismUnits("rad", 1.0)
    if target not in TARGETS:
        raise OptionError(f"unknown target {target!r} (expected one of {', '.join(TARGETS)})")
    if not (voltage > 0 and math.isfinite(voltage)):
        raise OptionError(f"battery voltage must be positive, got {voltage}")
    loop = gains.loop
    if target in ("volts", "wpilib"):
        n = units.per_radian
        u = units.short
        conv = []
        if n != 1.0:
            conv.append(f"lengths: 1 rad = {n:.6g} {u}; gains and kV, kA divided by {n:.6g}")
        unit_map = {
            **_gain_units(loop, "V", u),
            **_ff_units("V", u),
            "output": "V",
            "position": u,
            "velocity": f"{u}/s",
        }
        g_user, ff_user = gains.scaled(n).to_dict(), feedforward.scaled(n).to_dict()
        return TargetGains(target, loop, g_user, ff_user, unit_map, conv, [], feedforward, gains.period, voltage)
    if units.cpr is None:
        raise OptionError(f"target {target} works in encoder ticks: give --cpr (counts per revolution)")
    ticks_per_rad = units.cpr / (2 * math.pi)
    if target == "ftc-power":
        scale = 1.0 / (voltage * ticks_per_rad)
        g_pow = {"kP": gains.kP * scale, "kI": gains.kI * scale, "kD": gains.kD * scale}
        ff_pow = {"kS": feedforward.kS / voltage, "kV": feedforward.kV * scale, "kA": feedforward.kA * scale}
        conv = [
            f"ticks: cpr = {units.cpr:g}, 1 rad = {ticks_per_rad:.6g} ticks",
            f"power = volts / {voltage:g} V: gains [V per rad, per rad/s ...] × {scale:.6g} = power per tick",
            f"in the OpMode multiply the power by {voltage:g} / battery voltage (VoltageSensor)",
        ]
        unit_map = {
            **_gain_units(loop, "power", "tick"),
            **_ff_units("power", "tick"),
            "output": f"power (1 = {voltage:g} V)",
            "position": "tick",
            "velocity": "tick/s",
        }
        return TargetGains(target, loop, g_pow, ff_pow, unit_map, conv, [], feedforward, gains.period, voltage)
    # ftc-pidf
    if loop != "velocity":
        raise OptionError(
            "target ftc-pidf is the hub's velocity loop (setVelocityPIDFCoefficients); "
            "for a position loop use --target ftc-power"
        )
    free = feedforward.free_speed(voltage)
    if free <= 0:
        raise OptionError(f"at {voltage:g} V the motor does not turn (kS = {feedforward.kS:.3g} V)")
    per_volt = HUB_FULL_SCALE / voltage
    scale = per_volt / ticks_per_rad
    free_ticks = free * ticks_per_rad
    f = HUB_FULL_SCALE / free_ticks
    g_hub = {"kP": gains.kP * scale, "kI": gains.kI * scale, "kD": gains.kD * scale, "kF": f}
    # The model's own feedforward in hub units, for comparison with F (the hub has no kS, kA terms).
    ff_hub = {"kS": feedforward.kS * per_volt, "kV": feedforward.kV * scale, "kA": feedforward.kA * scale}
    conv = [
        f"ticks: cpr = {units.cpr:g}, 1 rad = {ticks_per_rad:.6g} ticks",
        f"hub output ('hub'): 32767 = full power = {voltage:g} V, i.e. {per_volt:.6g} per volt",
        f"P, I, D = kP, kI, kD [V per rad/s, rad, rad/s²] × {per_volt:.6g} / {ticks_per_rad:.6g} = × {scale:.6g}",
        f"max velocity at {voltage:g} V = (V − kS)/kV = {free_ticks:.6g} ticks/s; "
        f"F = 32767 / {free_ticks:.6g} = {f:.6g}",
    ]
    notes = [
        "F = 32767 / max ticks per second is FIRST's convention (Motor PIDF Tuning Guide, 2019)",
        "P, I, D assume the hub runs a time-normalised PID on ticks/s error: not confirmed (closed "
        "firmware, loop period unknown); start from them and check on the robot",
        "the hub's F has no kS term: below max velocity it gives less than kS + kV·v, P and I make up the rest",
    ]
    unit_map = {
        **_gain_units(loop, "hub", "tick"),
        **_ff_units("hub", "tick"),
        "kF": "hub/(tick/s)",
        "output": f"hub output (32767 = {voltage:g} V)",
        "position": "tick",
        "velocity": "tick/s",
    }
    # What the hub applies as feedforward, in volts: F·v·V/32767 = V/v_free·v, a secant through 0.
    equivalent = Feedforward(0.0, voltage / free, 0.0)
    return TargetGains(target, loop, g_hub, ff_hub, unit_map, conv, notes, equivalent, gains.period, voltage)
