"""Ready-to-paste code with the gains for a target: Java, Kotlin or Python.

Every snippet reads top to bottom as a person pastes it: the import lines first (they go at the top of the
file), then comments saying how the numbers were made, then sections, each under a comment that says
where it goes: ``Fields of <class>:`` (declarations for the body of one class: a snippet never mixes two
classes' fields) and ``Code, <when>:`` (statements for a method). The Java snippets compile as pasted
(tests/control/test_snippets_compile.py compiles each one with javac against small stubs of the vendors'
APIs).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from motorlab.control.targets import TargetGains
from motorlab.errors import OptionError

LANGUAGES = ("java", "kotlin", "python")
#: Road Runner drive classes a snippet can be for (the quickstart's ``MecanumDrive`` and ``TankDrive``).
DRIVES = ("mecanum", "tank")
#: How each section's heading starts: a section of fields (one class's) or of statements.
FIELDS, CODE = "Fields of", "Code,"


def _num(x: float) -> str:
    """A floating-point literal valid in Java, Kotlin and Python (always with a '.' or an exponent)."""
    text = f"{x:.6g}"
    if not any(c in text for c in ".en"):
        text += ".0"
    return text


@dataclass
class _Snippet:
    """The parts of a snippet: import lines, then sections of (heading, lines)."""

    imports: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)  # comments after the header, before the sections
    sections: list[tuple[str, list[str]]] = field(default_factory=list)

    def render(self, comment: str, header: list[str]) -> str:
        out = list(self.imports)
        if out:
            out.append("")
        out += [f"{comment} {line}" for line in [*header, *self.notes]]
        for heading, lines in self.sections:
            out += ["", f"{comment} {heading}", *lines]
        return "\n".join(out) + "\n"


def emit_snippet(tg: TargetGains, language: str = "java", *, drive: str = "mecanum") -> str:
    """Source code setting up the controller of ``tg`` with its gains.

    Parameters
    ----------
    tg
        Gains in a target's units (:func:`motorlab.control.to_target`).
    language
        ``"java"``, ``"kotlin"`` or ``"python"`` (Python: not for the FTC targets, whose OpModes are Java
        or Kotlin).
    drive
        Road Runner only: the drive class whose ``Params`` the snippet fills, ``"mecanum"``
        (``MecanumDrive``, the default) or ``"tank"`` (``TankDrive``).

    Returns
    -------
    str
        The snippet, ending with a newline.

    Raises
    ------
    OptionError
        Unknown language or drive, or a language the target has no snippet in.
    """
    if language not in LANGUAGES:
        raise OptionError(f"unknown language {language!r} (expected one of {', '.join(LANGUAGES)})")
    if drive not in DRIVES:
        raise OptionError(f"unknown drive {drive!r} (expected one of {', '.join(DRIVES)})")
    if language == "python" and (tg.target.startswith("ftc") or tg.target in ("roadrunner", "pedro")):
        raise OptionError("FTC SDK OpModes are written in Java or Kotlin: use --emit java or --emit kotlin")
    if language != "java" and tg.target in ("phoenix5", "spark", "spark-data-port"):
        raise OptionError(f"the {tg.target} snippet is Java (the vendor's examples): use --emit java")
    if language == "kotlin" and tg.target == "phoenix6":
        raise OptionError("the phoenix6 snippet is Java or Python: use --emit java or --emit python")
    comment = "#" if language == "python" else "//"
    header = [
        f"motorlab tune: {tg.loop} loop, target {tg.target}, period {tg.period:g} s, "
        f"output in {tg.units['output']}, position in {tg.units['position']}",
        *tg.conversion,
        *(f"NOTE: {line}" for line in tg.notes),
    ]
    if tg.target == "ftc-pidf":
        snippet = _ftc_pidf(tg, language)
    elif tg.target == "roadrunner":
        snippet = _roadrunner(tg, language, drive)
    elif tg.target == "pedro":
        snippet = _pedro(tg, language)
    elif tg.target in ("phoenix6", "phoenix5", "spark", "spark-data-port"):
        from motorlab.control.emit_vendors import vendor_snippet

        imports, notes, sections = vendor_snippet(tg, language)
        snippet = _Snippet(imports, notes, sections)
    elif tg.target == "wpilib":
        snippet = _wpilib(tg, language)
    elif tg.target == "ftc-power":
        snippet = _ftc_power(tg, language)
    else:
        snippet = _plain(tg, language)
    return snippet.render(comment, header)


def _constants(tg: TargetGains, language: str, names: list[tuple[str, str, float]]) -> list[str]:
    lines = []
    for name, key, value in names:
        unit = tg.units.get(key, "")
        tail = f"  {'#' if language == 'python' else '//'} {unit}" if unit else ""
        if language == "java":
            lines.append(f"static final double {name} = {_num(value)};{tail}")
        elif language == "kotlin":
            lines.append(f"const val {name} = {_num(value)}{tail}")
        else:
            lines.append(f"{name} = {_num(value)}{tail}")
    return lines


def _gain_constants(tg: TargetGains, language: str) -> list[str]:
    g, ff = tg.gains, tg.feedforward
    return _constants(tg, language, [(k, k, g[k]) for k in ("kP", "kI", "kD")] + [(k, k, ff[k]) for k in ("kS", "kV",
                                                                                                       "kA")])


def _inputs(vel: bool) -> str:
    """What the person's code provides, in words."""
    if vel:
        return ("targetVelocity (the setpoint) and targetAcceleration from your profile, measuredVelocity from "
                "your encoder")
    return "targetPosition, targetVelocity, targetAcceleration from your profile, measuredPosition from your encoder"


def _plain(tg: TargetGains, language: str) -> _Snippet:
    vel = tg.loop == "velocity"
    meas = "measuredVelocity" if vel else "measuredPosition"
    ref = "targetVelocity" if vel else "targetPosition"
    period = _num(tg.period)
    consts = _gain_constants(tg, language)
    if language == "python":
        return _Snippet(sections=[("Constants:", consts), ("Code: a controller to call once per period:", [
            "class Controller:",
            '    """Feedforward + PID; call update() once per period with the measurement."""',
            "",
            "    def __init__(self, period):",
            "        self.period, self.integral, self.last_error = period, 0.0, None",
            "",
            f"    def update(self, {_snake(ref)}, {_snake(meas)}, "
            f"{'' if vel else 'target_velocity=0.0, '}target_acceleration=0.0):",
            f"        error = {_snake(ref)} - {_snake(meas)}",
            "        self.integral += error * self.period",
            "        derivative = 0.0 if self.last_error is None else (error - self.last_error) / self.period",
            "        self.last_error = error",
            "        sign = (target_velocity > 0) - (target_velocity < 0)",
            "        return (kS * sign + kV * target_velocity + kA * target_acceleration",
            "                + kP * error + kI * self.integral + kD * derivative)  # volts",
        ])])
    java = language == "java"
    semi = ";" if java else ""
    var = "double " if java else "var "
    val = "double " if java else "val "
    state = [f"{var}integral = 0.0{semi}", f"{var}lastError = 0.0{semi}"]
    code = [
        f"{val}error = {ref} - {meas}{semi}",
        f"integral += error * {period}{semi}",
        f"{val}derivative = (error - lastError) / {period}{semi}",
        f"lastError = error{semi}",
        f"{val}volts = kS * Math.signum(targetVelocity) + kV * targetVelocity + kA * targetAcceleration",
        f"        + kP * error + kI * integral + kD * derivative{semi}  // to your motor",
    ]
    if java:
        return _Snippet(sections=[(f"{FIELDS} your class:", consts + state),
                                  (f"{CODE} every {tg.period:g} s ({_inputs(vel)}):", code)])
    return _Snippet(sections=[("Constants, at the top of the file:", consts),
                              (f"{FIELDS} your class:", state),
                              (f"{CODE} every {tg.period:g} s ({_inputs(vel)}):", code)])


def _snake(name: str) -> str:
    return "".join("_" + ch.lower() if ch.isupper() else ch for ch in name)


def _wpilib(tg: TargetGains, language: str) -> _Snippet:
    period = _num(tg.period)
    vel = tg.loop == "velocity"
    quantity = "Velocity" if vel else "Position"
    consts = _gain_constants(tg, language)
    if language == "python":
        return _Snippet(
            imports=["from wpimath.controller import PIDController, SimpleMotorFeedforwardMeters"],
            sections=[("Constants:", consts),
                      ("Set up once:", [f"pid = PIDController(kP, kI, kD, {period})",
                                        "feedforward = SimpleMotorFeedforwardMeters(kS, kV, kA)"]),
                      (f"Every {tg.period:g} s ({_snake(_inputs(vel))}):", [
                          "volts = feedforward.calculate(target_velocity) + "
                          f"pid.calculate(measured_{quantity.lower()}, target_{quantity.lower()})",
                          "motor.setVoltage(volts)"])])
    java = language == "java"
    semi = ";" if java else ""
    imports = [f"import edu.wpi.first.math.controller.PIDController{semi}",
               f"import edu.wpi.first.math.controller.SimpleMotorFeedforward{semi}"]
    objects = ([f"PIDController pid = new PIDController(kP, kI, kD, {period});",
                "SimpleMotorFeedforward feedforward = new SimpleMotorFeedforward(kS, kV, kA);"] if java else
               [f"val pid = PIDController(kP, kI, kD, {period})",
                "val feedforward = SimpleMotorFeedforward(kS, kV, kA)"])
    decl = "double volts =" if java else "val volts ="
    code = [f"{decl} feedforward.calculate(targetVelocity) + pid.calculate(measured{quantity}, target{quantity}){semi}",
            f"motor.setVoltage(volts){semi}"]
    when = f"{CODE} every {tg.period:g} s ({_inputs(vel)}; motor: your motor controller):"
    if java:
        return _Snippet(imports, sections=[(f"{FIELDS} your subsystem class:", consts + objects), (when, code)])
    return _Snippet(imports, sections=[("Constants, at the top of the file:", consts),
                                       (f"{FIELDS} your subsystem class:", objects), (when, code)])


def _ftc_imports(language: str, *names: str) -> list[str]:
    semi = ";" if language == "java" else ""
    hardware = "com.qualcomm.robotcore.hardware"
    paths = {"DcMotor": f"{hardware}.DcMotor", "DcMotorEx": f"{hardware}.DcMotorEx",
             "VoltageSensor": f"{hardware}.VoltageSensor", "ElapsedTime": "com.qualcomm.robotcore.util.ElapsedTime"}
    return [f"import {paths[n]}{semi}" for n in names]


def _ftc_motor(language: str) -> str:
    if language == "java":
        return 'DcMotorEx motor = hardwareMap.get(DcMotorEx.class, "motor");'
    return 'val motor = hardwareMap.get(DcMotorEx::class.java, "motor")'


def _ftc_power(tg: TargetGains, language: str) -> _Snippet:
    vel = tg.loop == "velocity"
    java = language == "java"
    semi = ";" if java else ""
    d = "double " if java else "val "
    v = "double " if java else "var "
    read = "motor.getVelocity()" if vel else "motor.getCurrentPosition()"
    ref = "targetVelocity" if vel else "targetPosition"
    meas = "velocity" if vel else "position"
    battery = ("VoltageSensor battery = hardwareMap.voltageSensor.iterator().next();" if java
               else "val battery = hardwareMap.voltageSensor.iterator().next()")
    timer = "ElapsedTime timer = new ElapsedTime();" if java else "val timer = ElapsedTime()"
    consts = _gain_constants(tg, language) + _constants(tg, language, [("NOMINAL_VOLTAGE", "", tg.voltage)])
    before = [
        _ftc_motor(language),
        f"motor.setMode(DcMotor.RunMode.RUN_WITHOUT_ENCODER){semi}  // our PID, not the hub's",
        battery, timer, f"{v}integral = 0.0{semi}", f"{v}lastError = 0.0{semi}",
    ]
    loop = [
        f"{d}dt = timer.seconds(){semi}",
        f"timer.reset(){semi}",
        f"{d}{meas} = {read}{semi}  // ticks{'/s' if vel else ''}",
        f"{d}error = {ref} - {meas}{semi}",
        f"integral += error * dt{semi}",
        f"{d}derivative = dt > 0 ? (error - lastError) / dt : 0.0{semi}" if java
        else "val derivative = if (dt > 0) (error - lastError) / dt else 0.0",
        f"lastError = error{semi}",
        f"{'double' if java else 'var'} power = kS * Math.signum(targetVelocity) + kV * targetVelocity "
        "+ kA * targetAcceleration",
        f"        + kP * error + kI * integral + kD * derivative{semi}",
        f"power *= NOMINAL_VOLTAGE / battery.getVoltage(){semi}  // the gains are per volt at the nominal voltage",
        f"motor.setPower(Math.max(-1.0, Math.min(1.0, power))){semi}",
    ]
    imports = _ftc_imports(language, "DcMotor", "DcMotorEx", "VoltageSensor", "ElapsedTime")
    inputs = (f"{ref}{', targetVelocity' if not vel else ''}, targetAcceleration from your profile, in ticks"
              f"{'/s' if vel else ''} and ticks/s^2")
    sections = [(f"{FIELDS} your OpMode class:" if java else "Constants, at the top of the file:", consts),
                (f"{CODE} in runOpMode(), before the loop:", before),
                (f"{CODE} in the loop ({inputs}):", loop)]
    return _Snippet(imports, sections=sections)


def _ftc_pidf(tg: TargetGains, language: str) -> _Snippet:
    g = tg.gains
    semi = ";" if language == "java" else ""
    setup = [
        _ftc_motor(language),
        f"motor.setMode(DcMotor.RunMode.RUN_USING_ENCODER){semi}",
        f"motor.setVelocityPIDFCoefficients({_num(g['kP'])}, {_num(g['kI'])}, {_num(g['kD'])}, {_num(g['kF'])}){semi}",
    ]
    return _Snippet(_ftc_imports(language, "DcMotor", "DcMotorEx"), sections=[
        (f"{CODE} in runOpMode(), before the loop:", setup),
        (f"{CODE} in the loop (targetTicksPerSecond: the speed you want, in ticks/s):",
         [f"motor.setVelocity(targetTicksPerSecond){semi}"]),
    ])


#: Road Runner quickstart fields by drive class (road-runner-quickstart, MecanumDrive.java and TankDrive.java,
#: ``Params``): TankDrive has no lateral scale or holonomic path gains, MecanumDrive no turn controller of its own.
_RR_FIELDS = {
    "mecanum": ("inPerTick", "lateralInPerTick", "trackWidthTicks", "kS", "kV", "kA", "axialGain", "lateralGain",
                "headingGain", "axialVelGain", "lateralVelGain", "headingVelGain"),
    "tank": ("inPerTick", "trackWidthTicks", "kS", "kV", "kA", "turnGain", "turnVelGain"),
}


def _roadrunner(tg: TargetGains, language: str, drive: str) -> _Snippet:
    """Road Runner quickstart fields of one drive class: Java declarations in ``Params``, Kotlin assignments."""
    values = {**tg.feedforward, **tg.gains}
    names = [k for k in _RR_FIELDS[drive] if k in values]
    cls = "MecanumDrive" if drive == "mecanum" else "TankDrive"
    notes = []
    if drive == "tank":
        notes += ["ramseteZeta, ramseteBBar: keep the quickstart's values (motorlab does not derive RAMSETE "
                  "gains); turnGain, turnVelGain are the heading gains of the turn controller",
                  "CHECK the sign in TankDrive.TurnAction: the quickstart (road-runner-quickstart 08f08988) "
                  "multiplies turnGain by the actual heading minus the target heading, the opposite of "
                  "MecanumDrive's HolonomicController; with positive gains write the target minus the actual "
                  "heading there, as MecanumDrive does, or the turn correction pushes the wrong way"]
    else:
        notes.append("for a TankDrive, ask for the tank drive's snippet: its Params has other fields")
    if language == "java":
        lines = [f"public double {k} = {_num(values[k])};  // {tg.units.get(k, '')}" for k in names]
        return _Snippet(notes=notes, sections=[
            (f"{FIELDS} {cls}.Params ({cls}.java), in place of the quickstart's values:", lines)])
    lines = [f"{cls}.PARAMS.apply {{", *[f"    {k} = {_num(values[k])}  // {tg.units.get(k, '')}" for k in names], "}"]
    return _Snippet(notes=notes, sections=[(f"{CODE} before the {cls} is built:", lines)])


def _pedro(tg: TargetGains, language: str) -> _Snippet:
    """Pedro Pathing Constants: MecanumConstants and FollowerConstants builders (fields of class Constants)."""
    ff = tg.feedforward
    java = language == "java"
    semi = ";" if java else ""
    drive = [f".xVelocity({_num(ff['xVelocity'])})  // in/s at full power",
             f".yVelocity({_num(ff['yVelocity'])})  // in/s, lateral ratio × xVelocity" if "yVelocity" in ff
             else "// .yVelocity(lateral ratio × xVelocity): from the lateral ramp",
             f".nominalVoltage({_num(ff['nominalVoltage'])})",
             f".staticFrictionCoefficient({_num(ff['staticFrictionCoefficient'])})"]
    follower = []
    if "forwardZeroPowerAcceleration" in ff:
        follower.append(f".forwardZeroPowerAcceleration({_num(ff['forwardZeroPowerAcceleration'])})  // in/s^2")
    if "lateralZeroPowerAcceleration" in ff:
        follower.append(f".lateralZeroPowerAcceleration({_num(ff['lateralZeroPowerAcceleration'])})  // in/s^2")
    if java:
        head_f = "public static FollowerConstants followerConstants = new FollowerConstants()"
        head_d = "public static MecanumConstants driveConstants = new MecanumConstants()"
    else:
        head_f, head_d = "val followerConstants = FollowerConstants()", "val driveConstants = MecanumConstants()"
    lines = [*_statement(head_f, follower, semi), *_statement(head_d, drive, semi)]
    imports = [f"import com.pedropathing.follower.FollowerConstants{semi}",
               f"import com.pedropathing.ftc.drivetrains.MecanumConstants{semi}"]
    notes = [f"drive PIDF from the position gains: P = {_num(tg.gains['driveP'])} power/in, "
             f"D = {_num(tg.gains['driveD'])} power*s/in"]
    where = f"{FIELDS} Constants (Constants.java), in place of the quickstart's values:" if java else \
        "In the Constants object (Constants.kt), in place of the quickstart's values:"
    return _Snippet(imports, notes, [(where, lines)])


def _statement(head: str, calls: list[str], end: str) -> list[str]:
    """A builder's declaration: ``head`` and its calls, indented, the statement's end after the last call (before
    its comment)."""
    out = [head, *("        " + line for line in calls)]
    last = max((i for i, line in enumerate(out) if i == 0 or line.lstrip().startswith(".")))
    code, sep, rest = out[last].partition("  //")
    out[last] = code + end + (sep + rest if sep else "")
    return out
