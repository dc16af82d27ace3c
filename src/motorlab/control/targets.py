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
``roadrunner``
    Road Runner 1.0's ``MecanumDrive.PARAMS`` / ``TankDrive.PARAMS`` (road-runner-quickstart
    ``MecanumDrive.java``): kS [V], kV [V per tick/s], kA [V per tick/s²] "in tick units" (the drive
    builds ``MotorFeedforward(kS, kV / inPerTick, kA / inPerTick)`` on inches), and the path
    controller gains of ``HolonomicController``: a position error e [in] becomes a velocity command
    axialGain·e that the feedforward turns into kV·axialGain·e volts, so axialGain = kP/kV [1/s] and
    axialVelGain = kD/kV [-] (velocity loop: axialVelGain = kP/kV); the lateral and heading gains are
    given the same values (the same wheels do the work). inPerTick = 2π·r/cpr with ``--wheel-radius``.
    ``TankDrive.Params`` has the same feedforward fields (no ``lateralInPerTick``) but follows paths
    with RAMSETE (``ramseteZeta``, ``ramseteBBar``: the quickstart's values are kept, motorlab does not
    derive them); its turn controller gains ``turnGain``, ``turnVelGain`` take the heading gains' values.
``phoenix6``, ``phoenix5``, ``spark``, ``spark-data-port``
    CTRE and REV smart motor controllers, with WPILib SysId's feedback presets' unit conversions,
    periods and measurement delays (:mod:`motorlab.control.presets`).
``pedro``
    Pedro Pathing's tuner constants (Pedro-Pathing/PedroPathing ``MecanumConstants``,
    ``FollowerConstants``; Quickstart ``Tuning.java``): ``xVelocity`` [in/s], the forward speed at full
    power (ForwardVelocityTuner) = (V − kS)/kV; ``forwardZeroPowerAcceleration`` [in/s², negative], the
    coasting deceleration with the motors floating (ForwardZeroPowerAccelerationTuner:
    ``startTeleopDrive(false)``): open terminals leave friction only, −(kS + (kV − K)·v)/kA, given as
    −kS/kA (K = kV, no viscous friction: the smallest magnitude); ``staticFrictionCoefficient`` =
    kS / nominalVoltage (the share of the battery that static friction takes, in
    ``Mecanum.getVoltageNormalized``); the drive PIDF (P, D on the remaining distance [in] → power)
    from the position gains. ``yVelocity`` and ``lateralZeroPowerAcceleration`` need the lateral
    ramp's ratio (``analyze feedforward … lateral.json``): yVelocity = lateral_ratio·xVelocity, and
    lateralZeroPowerAcceleration = −kS/lateral_kA (Pedro's LateralZeroPowerAccelerationTuner: strafe to
    30 in/s, ``setTeleOpDrive(0, 0, 0, true)``, average the per-loop accelerations down to the
    velocity constraint; with Coulomb friction only the deceleration is the constant kS/kA_lat).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from motorlab.control.design import Feedforward, Gains
from motorlab.control.plant import MechanismUnits
from motorlab.control.presets import PRESETS, preset_gains
from motorlab.errors import OptionError

TARGETS = ("volts", "wpilib", "ftc-power", "ftc-pidf", "roadrunner", "pedro", "phoenix6", "phoenix5", "spark",
           "spark-data-port")


@dataclass(frozen=True)
class TargetInfo:
    """What a person choosing a target needs to know (``GET /api/schema``'s ``targets``).

    ``label`` names it in words, ``units`` says what its gains are in, ``needs`` lists the options
    it cannot do without (``cpr``, ``wheel-radius``), ``loops`` the loops it runs, ``languages``
    the ``--emit`` languages it has snippets for, ``delay`` its measurement delay [s] when
    ``--delay`` is not given and ``period`` its controller period [s] when ``--period`` is not
    (SysId's presets, :mod:`motorlab.control.presets`).
    """

    key: str
    label: str
    units: str
    needs: tuple[str, ...] = ()
    loops: tuple[str, ...] = ("velocity", "position")
    languages: tuple[str, ...] = ("java", "kotlin", "python")
    delay: float = 0.0
    period: float = 0.02

    def to_dict(self) -> dict[str, Any]:
        return {"key": self.key, "label": self.label, "units": self.units, "needs": list(self.needs),
                "loops": list(self.loops), "languages": list(self.languages), "delay": self.delay,
                "period": self.period}


_FTC = ("java", "kotlin")

#: Every target, in :data:`TARGETS`' order.
TARGET_INFO: dict[str, TargetInfo] = {t.key: t for t in (
    TargetInfo("volts", "Volts (any controller)", "volts and your length unit"),
    TargetInfo("wpilib", "WPILib PIDController and SimpleMotorFeedforward", "volts and your length unit"),
    TargetInfo("ftc-power", "FTC OpMode PID on motor power", "motor power (−1…1) per encoder tick",
               needs=("cpr",), languages=_FTC),
    TargetInfo("ftc-pidf", "FTC hub velocity PIDF (setVelocityPIDFCoefficients)",
               "hub output (32767 = full power) per encoder tick per second", needs=("cpr",),
               loops=("velocity",), languages=_FTC),
    TargetInfo("roadrunner", "Road Runner 1.0 drive", "volts per encoder tick", needs=("cpr",), languages=_FTC),
    TargetInfo("pedro", "Pedro Pathing follower", "inches and motor power", needs=("wheel-radius",),
               languages=_FTC),
    TargetInfo("phoenix6", "CTRE Phoenix 6 (TalonFX, Kraken)", "volts per rotation, rotations per second",
               languages=("java", "python"), delay=PRESETS["phoenix6"].measurement_delay,
               period=PRESETS["phoenix6"].period),
    TargetInfo("phoenix5", "CTRE Phoenix 5 (Talon SRX, Victor SPX), native units",
               "output (1023 = full) per encoder tick, ticks per 100 ms", needs=("cpr",), languages=("java",),
               delay=PRESETS["phoenix5"].measurement_delay, period=PRESETS["phoenix5"].period),
    TargetInfo("spark", "REV SPARK MAX / SPARK Flex, the brushless motor's own encoder",
               "duty cycle per rotation, per RPM", languages=("java",), delay=PRESETS["spark"].measurement_delay,
               period=PRESETS["spark"].period),
    TargetInfo("spark-data-port", "REV SPARK MAX / SPARK Flex, an encoder on the data or brushed-encoder port",
               "duty cycle per rotation, per RPM", languages=("java",),
               delay=PRESETS["spark-data-port"].measurement_delay,
               period=PRESETS["spark-data-port"].period),
)}

#: Metres per inch.
INCH = 0.0254

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
    geometry: dict[str, float] | None = None,
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
    geometry
        Road Runner ramp results (``lateral_ratio``, ``track_width_ticks``) for ``roadrunner`` and
        ``pedro``.

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
    if units.base == "m" and target not in ("volts", "wpilib", "pedro"):
        raise OptionError(f"target {target} counts the motor's turns, but the model gives kV per metre travelled (its "
                          "file logs distances): use volts, wpilib or pedro, or fit a log of the shaft's angle")
    if target in ("volts", "wpilib"):
        n = units.per_radian
        u = units.short
        conv = []
        if n != 1.0:
            conv.append(f"lengths: 1 {units.base} = {n:.6g} {u}; gains and kV, kA divided by {n:.6g}")
        unit_map = {
            **_gain_units(loop, "V", u),
            **_ff_units("V", u),
            "output": "V",
            "position": u,
            "velocity": f"{u}/s",
        }
        g_user, ff_user = gains.scaled(n).to_dict(), feedforward.scaled(n).to_dict()
        return TargetGains(target, loop, g_user, ff_user, unit_map, conv, [], feedforward, gains.period, voltage)
    if target in PRESETS:
        g, ff, unit_map, conv, notes = preset_gains(gains, feedforward, target, units, voltage)
        applied = Feedforward(feedforward.kS, feedforward.kV, feedforward.kA if target == "phoenix6" else 0.0)
        return TargetGains(target, loop, g, ff, unit_map, conv, notes, applied, gains.period, voltage)
    if target == "roadrunner":
        return _roadrunner(gains, feedforward, units, voltage, geometry or {})
    if target == "pedro":
        return _pedro(gains, feedforward, units, voltage, geometry or {})
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
    return _ftc_pidf(gains, feedforward, units, voltage)


def _roadrunner(gains: Gains, feedforward: Feedforward, units: MechanismUnits, voltage: float,
                geometry: dict[str, float]) -> TargetGains:
    """Road Runner 1.0 drive PARAMS (see the module docstring)."""
    if units.cpr is None:
        raise OptionError("target roadrunner counts ticks: give --cpr (counts per revolution of the encoder the "
                          "gains were measured at)")
    rad_per_tick = 2 * math.pi / units.cpr
    ff = {"kS": feedforward.kS, "kV": feedforward.kV * rad_per_tick, "kA": feedforward.kA * rad_per_tick}
    kv = feedforward.kV
    # HolonomicController: velocity command = axialGain·(position error) + axialVelGain·(velocity error),
    # volts = kV·command: the position loop's kP and kD, or a velocity loop's kI (on the integral of the
    # velocity error, the position error) and kP.
    k_x, k_v, names = ((gains.kP, gains.kD, ("kP", "kD")) if gains.loop == "position"
                       else (gains.kI, gains.kP, ("kI", "kP")))
    path = {"axialGain": k_x / kv, "axialVelGain": k_v / kv}
    # TankDrive has no holonomic path gains (it follows paths with RAMSETE): its turn controller,
    # turnGain·e + turnVelGain·ė on the heading, plays the heading gains' part.
    g = {**path, "lateralGain": path["axialGain"], "lateralVelGain": path["axialVelGain"],
         "headingGain": path["axialGain"], "headingVelGain": path["axialVelGain"],
         "turnGain": path["axialGain"], "turnVelGain": path["axialVelGain"]}
    unit_map = {
        "kS": "V", "kV": "V*s/tick", "kA": "V*s^2/tick", "axialGain": "1/s", "lateralGain": "1/s",
        "headingGain": "1/s", "axialVelGain": "1", "lateralVelGain": "1", "headingVelGain": "1",
        "turnGain": "1/s", "turnVelGain": "1",
        "output": "V", "position": "tick", "velocity": "tick/s", "inPerTick": "in/tick",
    }
    conv = [
        f"ticks: cpr = {units.cpr:g}; kV, kA [V per rad/s, rad/s²] × 2π/cpr = × {rad_per_tick:.6g} per tick",
        f"path gains: axialGain = {names[0]}/kV = {k_x:.6g}/{kv:.6g}; axialVelGain = {names[1]}/kV = "
        f"{k_v:.6g}/{kv:.6g} (HolonomicController turns the position error and the velocity error into a "
        "velocity command that the feedforward converts to volts; lateral and heading the same, and TankDrive's "
        "turnGain, turnVelGain)",
    ]
    notes = ["kS, kV, kA are for the encoder whose cpr was given (dead wheels or drive motors): the same "
             "encoder as Road Runner's inPerTick"]
    if "track_width_ticks" in geometry:
        ff["trackWidthTicks"] = geometry["track_width_ticks"]
        unit_map["trackWidthTicks"] = "tick"
    free = feedforward.free_speed(voltage)
    if units.metres is not None:
        in_per_tick = units.metres * rad_per_tick / INCH
        ff["inPerTick"] = in_per_tick
        if "lateral_ratio" in geometry:
            ff["lateralInPerTick"] = geometry["lateral_ratio"] * in_per_tick
            unit_map["lateralInPerTick"] = "in/tick"
            conv.append(f"lateralInPerTick = lateral_ratio × inPerTick = {geometry['lateral_ratio']:.6g} × inPerTick")
        conv.append(f"inPerTick = 2π·r/cpr = {in_per_tick:.6g} in (wheel radius {units.metres:g} m)")
        notes.append(f"maxWheelVel must stay below the free speed (V − kS)/kV = {free * units.metres / INCH:.4g} "
                     f"in/s at {voltage:g} V")
    else:
        notes.append("give the radius of the encoder's wheel to get inPerTick")
    return TargetGains("roadrunner", gains.loop, g, ff, unit_map, conv, notes, feedforward, gains.period, voltage)


def _pedro(gains: Gains, feedforward: Feedforward, units: MechanismUnits, voltage: float,
           geometry: dict[str, float]) -> TargetGains:
    """Pedro Pathing tuner constants (see the module docstring)."""
    if units.metres is None:
        raise OptionError("target pedro works in inches: give --wheel-radius (the radius of the wheel the gains "
                          "were measured at: a dead wheel or a drive wheel)")
    in_per_rad = units.metres / INCH
    free = feedforward.free_speed(voltage)
    if free <= 0:
        raise OptionError(f"at {voltage:g} V the drive does not move (kS = {feedforward.kS:.3g} V)")
    ff = {"xVelocity": free * in_per_rad, "staticFrictionCoefficient": feedforward.kS / voltage,
          "nominalVoltage": voltage}
    if feedforward.kA > 0:
        ff["forwardZeroPowerAcceleration"] = -feedforward.kS / feedforward.kA * in_per_rad
    if "lateral_ratio" in geometry:
        ff["yVelocity"] = geometry["lateral_ratio"] * ff["xVelocity"]
    if geometry.get("lateral_kA", 0.0) > 0:  # the perpendicular dead wheel: same radius as --wheel-radius
        ff["lateralZeroPowerAcceleration"] = -feedforward.kS / geometry["lateral_kA"] * in_per_rad
    power_per_in = 1.0 / (voltage * in_per_rad)
    g = {"driveP": gains.kP * power_per_in, "driveD": gains.kD * power_per_in} if gains.loop == "position" else \
        {"driveP": 0.0, "driveD": gains.kP * power_per_in}
    unit_map = {"xVelocity": "in/s", "yVelocity": "in/s", "forwardZeroPowerAcceleration": "in/s^2",
                "lateralZeroPowerAcceleration": "in/s^2",
                "staticFrictionCoefficient": "1",
                "nominalVoltage": "V", "driveP": "power/in", "driveD": "power*s/in", "output": "power",
                "position": "in", "velocity": "in/s", "kS": "V", "kV": "V*s/in", "kA": "V*s^2/in"}
    conv = [
        f"inches: 1 m = {in_per_rad:.6g} in" if units.base == "m" else
        f"inches: wheel radius {units.metres:g} m = {in_per_rad:.6g} in per rad",
        f"xVelocity = (V − kS)/kV at {voltage:g} V = {ff['xVelocity']:.6g} in/s",
        f"drive P, D [power per in]: kP, kD [V per rad] / {voltage:g} V / {in_per_rad:.6g}",
    ]
    notes = [
        "forwardZeroPowerAcceleration = −kS/kA assumes no viscous friction (K = kV): the coasting deceleration "
        "is at least this large; the analysis needs the back-EMF constant K to tell the viscous part",
        "yVelocity = lateral_ratio × xVelocity and lateralZeroPowerAcceleration = −kS/lateral_kA need the lateral "
        "ramp (motorlab analyze feedforward forward.json lateral.json; lateral_kA where its break-away shows "
        "the strafing inertia): the motors' friction kS decelerating the strafing robot's inertia, the same "
        "assumptions as forwardZeroPowerAcceleration, and roller friction beyond the forward ramp's kS left out "
        "(Pedro's LateralZeroPowerAccelerationTuner measures it all: prefer its number when you have run it)",
        "staticFrictionCoefficient = kS / nominalVoltage (our reading of Mecanum.getVoltageNormalized)",
    ]
    if feedforward.kA <= 0:
        notes.append("kA not determined: forwardZeroPowerAcceleration not determined")
    return TargetGains("pedro", gains.loop, g, ff, unit_map, conv, notes, feedforward, gains.period, voltage)


def _ftc_pidf(gains: Gains, feedforward: Feedforward, units: MechanismUnits, voltage: float) -> TargetGains:
    """The REV hub's velocity PIDF (see the module docstring)."""
    target, loop = "ftc-pidf", gains.loop
    assert units.cpr is not None
    ticks_per_rad = units.cpr / (2 * math.pi)
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
