"""Ready-to-paste code with the gains for a target: Java, Kotlin or Python."""

from __future__ import annotations

from motorlab.control.targets import TargetGains
from motorlab.errors import OptionError

LANGUAGES = ("java", "kotlin", "python")


def _num(x: float) -> str:
    """A floating-point literal valid in Java, Kotlin and Python (always with a '.' or an exponent)."""
    text = f"{x:.6g}"
    if not any(c in text for c in ".en"):
        text += ".0"
    return text


def _comment(language: str) -> str:
    return "#" if language == "python" else "//"


def _constants(tg: TargetGains, language: str, names: list[tuple[str, str, float]]) -> list[str]:
    lines = []
    for name, key, value in names:
        unit = tg.units.get(key, "")
        if language == "java":
            lines.append(f"static final double {name} = {_num(value)};  // {unit}")
        elif language == "kotlin":
            lines.append(f"const val {name} = {_num(value)}  // {unit}")
        else:
            lines.append(f"{name} = {_num(value)}  # {unit}")
    return lines


def emit_snippet(tg: TargetGains, language: str = "java") -> str:
    """Source code setting up the controller of ``tg`` with its gains.

    Parameters
    ----------
    tg
        Gains in a target's units (:func:`motorlab.control.to_target`).
    language
        ``"java"``, ``"kotlin"`` or ``"python"`` (Python: ``volts`` and ``wpilib`` targets only;
        FTC OpModes are Java or Kotlin).

    Returns
    -------
    str
        The snippet, ending with a newline.

    Raises
    ------
    OptionError
        Unknown language, or Python for an FTC target.
    """
    if language not in LANGUAGES:
        raise OptionError(f"unknown language {language!r} (expected one of {', '.join(LANGUAGES)})")
    if language == "python" and (tg.target.startswith("ftc") or tg.target in ("roadrunner", "pedro")):
        raise OptionError("FTC SDK OpModes are written in Java or Kotlin: use --emit java or --emit kotlin")
    if language != "java" and tg.target in ("phoenix5", "spark", "spark-data-port"):
        raise OptionError(f"the {tg.target} snippet is Java (the vendor's examples): use --emit java")
    if language == "kotlin" and tg.target == "phoenix6":
        raise OptionError("the phoenix6 snippet is Java or Python: use --emit java or --emit python")
    c = _comment(language)
    vel = tg.loop == "velocity"
    head = [
        f"{c} motorlab tune: {tg.loop} loop, target {tg.target}, period {tg.period:g} s, "
        f"output in {tg.units['output']}, position in {tg.units['position']}",
    ]
    head += [f"{c} {line}" for line in tg.conversion]
    head += [f"{c} NOTE: {line}" for line in tg.notes]
    g, ff = tg.gains, tg.feedforward
    if tg.target == "ftc-pidf":
        body = _ftc_pidf(tg, language)
    elif tg.target == "roadrunner":
        body = _roadrunner(tg, language)
    elif tg.target == "pedro":
        body = _pedro(tg, language)
    elif tg.target in ("phoenix6", "phoenix5", "spark", "spark-data-port"):
        from motorlab.control.emit_vendors import vendor_snippet

        body = vendor_snippet(tg, language)
    else:
        consts = [("kP", "kP", g["kP"]), ("kI", "kI", g["kI"]), ("kD", "kD", g["kD"])]
        consts += [("kS", "kS", ff["kS"]), ("kV", "kV", ff["kV"]), ("kA", "kA", ff["kA"])]
        if tg.target == "ftc-power":
            consts.append(("NOMINAL_VOLTAGE", "", tg.voltage))
        body = _constants(tg, language, consts)
        if tg.target == "wpilib":
            body += _wpilib(tg, language, vel)
        elif tg.target == "ftc-power":
            body += _ftc_power(language, vel)
        else:
            body += _plain(language, vel)
    return "\n".join(head + body) + "\n"


def _plain(language: str, vel: bool) -> list[str]:
    meas = "measuredVelocity" if vel else "measuredPosition"
    ref = "targetVelocity" if vel else "targetPosition"
    if language == "python":
        return [
            "",
            "class Controller:",
            '    """Feedforward + PID; call update() once per period with the measurement."""',
            "",
            "    def __init__(self, period):",
            "        self.period, self.integral, self.last_error = period, 0.0, None",
            "",
            f"    def update(self, {_snake(ref)}, {_snake(meas)}, target_velocity=0.0, target_acceleration=0.0):",
            f"        error = {_snake(ref)} - {_snake(meas)}",
            "        self.integral += error * self.period",
            "        derivative = 0.0 if self.last_error is None else (error - self.last_error) / self.period",
            "        self.last_error = error",
            "        sign = (target_velocity > 0) - (target_velocity < 0)",
            "        return (kS * sign + kV * target_velocity + kA * target_acceleration"
            " + kP * error + kI * self.integral + kD * derivative)  # volts",
        ]
    semi = ";" if language == "java" else ""
    decl = "double" if language == "java" else "val"
    sign = "Math.signum(targetVelocity)"  # java.lang.Math in both Java and Kotlin
    return [
        "",
        f"// every period: error = {ref} - {meas}; integral += error * period;",
        "// derivative = (error - lastError) / period; lastError = error",
        f"{decl} volts = kS * {sign} + kV * targetVelocity + kA * targetAcceleration"
        f" + kP * error + kI * integral + kD * derivative{semi}",
    ]


def _snake(name: str) -> str:
    return "".join("_" + ch.lower() if ch.isupper() else ch for ch in name)


def _wpilib(tg: TargetGains, language: str, vel: bool) -> list[str]:
    period = _num(tg.period)
    quantity = "Velocity" if vel else "Position"
    if language == "python":
        return [
            "",
            "from wpimath.controller import PIDController, SimpleMotorFeedforwardMeters",
            "",
            f"pid = PIDController(kP, kI, kD, {period})",
            "feedforward = SimpleMotorFeedforwardMeters(kS, kV, kA)",
            f"# every {tg.period:g} s (target_velocity from your profile; = the setpoint for a velocity loop):",
            f"volts = feedforward.calculate(target_velocity) + pid.calculate(measured_{quantity.lower()},"
            f" target_{quantity.lower()})",
            "motor.setVoltage(volts)",
        ]
    java = language == "java"
    semi = ";" if java else ""
    new = "new " if java else ""
    decl_pid = "PIDController pid =" if java else "val pid ="
    decl_ff = "SimpleMotorFeedforward feedforward =" if java else "val feedforward ="
    decl_v = "double volts =" if java else "val volts ="
    return [
        "",
        f"import edu.wpi.first.math.controller.PIDController{semi}",
        f"import edu.wpi.first.math.controller.SimpleMotorFeedforward{semi}",
        "",
        f"{decl_pid} {new}PIDController(kP, kI, kD, {period}){semi}",
        f"{decl_ff} {new}SimpleMotorFeedforward(kS, kV, kA){semi}",
        f"// every {tg.period:g} s (targetVelocity from your profile; = the setpoint for a velocity loop):",
        f"{decl_v} feedforward.calculate(targetVelocity) + pid.calculate(measured{quantity}, target{quantity}){semi}",
        f"motor.setVoltage(volts){semi}",
    ]


def _ftc_power(language: str, vel: bool) -> list[str]:
    java = language == "java"
    semi = ";" if java else ""
    d = "double " if java else "val "
    v = "double " if java else "var "
    read = "motor.getVelocity()" if vel else "motor.getCurrentPosition()"
    ref = "targetVelocity" if vel else "targetPosition"
    meas = "velocity" if vel else "position"
    motor = (
        'DcMotorEx motor = hardwareMap.get(DcMotorEx.class, "motor");'
        if java
        else 'val motor = hardwareMap.get(DcMotorEx::class.java, "motor")'
    )
    battery = (
        "VoltageSensor battery = hardwareMap.voltageSensor.iterator().next();"
        if java
        else "val battery = hardwareMap.voltageSensor.iterator().next()"
    )
    timer = "ElapsedTime timer = new ElapsedTime();" if java else "val timer = ElapsedTime()"
    return [
        "",
        "// in runOpMode(), before the loop:",
        motor,
        f"motor.setMode(DcMotor.RunMode.RUN_WITHOUT_ENCODER){semi}  // our PID, not the hub's",
        battery,
        timer,
        f"{v}integral = 0.0{semi}",
        f"{v}lastError = 0.0{semi}",
        "// in the loop (targetVelocity/targetAcceleration from your profile, ticks/s and ticks/s^2):",
        f"{d}dt = timer.seconds(){semi}",
        f"timer.reset(){semi}",
        f"{d}{meas} = {read}{semi}  // ticks{'/s' if vel else ''}",
        f"{d}error = {ref} - {meas}{semi}",
        f"integral += error * dt{semi}",
        f"{d}derivative = dt > 0 ? (error - lastError) / dt : 0.0{semi}"
        if java
        else "val derivative = if (dt > 0) (error - lastError) / dt else 0.0",
        f"lastError = error{semi}",
        f"{d}power = kS * Math.signum(targetVelocity) + kV * targetVelocity + kA * targetAcceleration",
        f"        + kP * error + kI * integral + kD * derivative{semi}",
        f"power *= NOMINAL_VOLTAGE / battery.getVoltage(){semi}  // gains are per {'volt at nominal voltage'}",
        f"motor.setPower(Math.max(-1.0, Math.min(1.0, power))){semi}",
    ]


def _ftc_pidf(tg: TargetGains, language: str) -> list[str]:
    g = tg.gains
    java = language == "java"
    semi = ";" if java else ""
    motor = (
        'DcMotorEx motor = hardwareMap.get(DcMotorEx.class, "motor");'
        if java
        else 'val motor = hardwareMap.get(DcMotorEx::class.java, "motor")'
    )
    return [
        "",
        motor,
        f"motor.setMode(DcMotor.RunMode.RUN_USING_ENCODER){semi}",
        f"motor.setVelocityPIDFCoefficients({_num(g['kP'])}, {_num(g['kI'])}, {_num(g['kD'])}, {_num(g['kF'])}){semi}",
        f"motor.setVelocity(targetTicksPerSecond){semi}  // ticks/s",
    ]


#: Road Runner fields by drive class: TankDrive has no lateral scale or holonomic path gains, and
#: MecanumDrive no turn controller of its own.
_TANK_ONLY = ("turnGain", "turnVelGain")
_MECANUM_ONLY = ("lateralInPerTick", "axialGain", "axialVelGain", "lateralGain", "lateralVelGain", "headingGain",
                 "headingVelGain")


def _roadrunner(tg: TargetGains, language: str) -> list[str]:
    """Road Runner quickstart fields: Java declarations for ``Params``, Kotlin assignments to ``PARAMS``.

    One block for ``MecanumDrive`` and one for ``TankDrive`` (paste the one of your drive class).
    """
    values = {**tg.feedforward, **tg.gains}
    names: list[str] = [k for k in ("inPerTick", "lateralInPerTick", "trackWidthTicks", "kS", "kV", "kA")
                        if k in tg.feedforward]
    names += list(tg.gains)
    blocks = [("MecanumDrive", [k for k in names if k not in _TANK_ONLY]),
              ("TankDrive", [k for k in names if k not in _MECANUM_ONLY])]
    tank_note = "ramseteZeta, ramseteBBar: keep the quickstart's values (motorlab does not derive RAMSETE gains)"
    lines: list[str] = []
    for drive, fields in blocks:
        if language == "java":
            lines += ["", f"// {drive}.java, class Params:"]
            if drive == "TankDrive":
                lines.append(f"// {tank_note}")
            lines += [f"public double {k} = {_num(values[k])};  // {tg.units.get(k, '')}" for k in fields]
        else:
            lines += ["", f"// Kotlin: set the quickstart's {drive}.PARAMS before building the drive"]
            if drive == "TankDrive":
                lines.append(f"// {tank_note}")
            lines += [f"{drive}.PARAMS.apply {{", *[f"    {k} = {_num(values[k])}  // {tg.units.get(k, '')}"
                                                   for k in fields], "}"]
    return lines


def _pedro(tg: TargetGains, language: str) -> list[str]:
    """Pedro Pathing Constants: MecanumConstants and FollowerConstants builders."""
    ff = tg.feedforward
    java = language == "java"
    drive = [f".xVelocity({_num(ff['xVelocity'])})  // in/s at full power",
             f".yVelocity({_num(ff['yVelocity'])})  // in/s, lateral ratio × xVelocity" if "yVelocity" in ff
             else "// .yVelocity(lateral_ratio * xVelocity)  // from the lateral ramp",
             f".nominalVoltage({_num(ff['nominalVoltage'])})",
             f".staticFrictionCoefficient({_num(ff['staticFrictionCoefficient'])})"]
    follower = []
    if "forwardZeroPowerAcceleration" in ff:
        follower.append(f".forwardZeroPowerAcceleration({_num(ff['forwardZeroPowerAcceleration'])})  // in/s^2")
    if "lateralZeroPowerAcceleration" in ff:
        follower.append(f".lateralZeroPowerAcceleration({_num(ff['lateralZeroPowerAcceleration'])})  // in/s^2")
    follower.append(f"// drive PIDF from the position gains: P = {_num(tg.gains['driveP'])} power/in, "
                    f"D = {_num(tg.gains['driveD'])} power*s/in")
    if java:
        head_d = "public static MecanumConstants driveConstants = new MecanumConstants()"
        head_f = "public static FollowerConstants followerConstants = new FollowerConstants()"
        end = ";"
    else:
        head_d, head_f = "val driveConstants = MecanumConstants()", "val followerConstants = FollowerConstants()"
        end = ""
    out = ["", "// Constants (Pedro Pathing quickstart)", head_d]
    out += ["        " + line for line in drive]
    out[-1] += end
    out.append(head_f)
    chained = [line for line in follower if line.startswith(".")]
    comments = [line for line in follower if not line.startswith(".")]
    out += ["        " + line for line in chained]
    if chained:
        out[-1] = out[-1].replace("  //", end + "  //", 1) if "  //" in out[-1] else out[-1] + end
    else:
        out[-1] += end
    return out + comments
