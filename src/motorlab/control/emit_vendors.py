"""Snippets for CTRE Phoenix 6, Phoenix 5 and REVLib's SPARK MAX/Flex (gains from :mod:`motorlab.control.presets`).

The calls are the vendors' documented APIs: Phoenix 6 ``Slot0Configs`` (kP … kA, applied through the
device's configurator) with ``PositionVoltage``/``VelocityVoltage``; Phoenix 5 ``config_kP`` …
``config_kF`` with voltage compensation and ``DemandType.ArbitraryFeedForward``; REVLib 2025
``SparkMaxConfig.closedLoop.pid(...).velocityFF(...)`` and ``SparkClosedLoopController.setReference``
with an arbitrary feedforward in volts (``ArbFFUnits.kVoltage``).
"""

from __future__ import annotations

from motorlab.control.targets import TargetGains

Sections = list[tuple[str, list[str]]]


def _n(x: float) -> str:
    text = f"{x:.6g}"
    return text if any(c in text for c in ".en") else text + ".0"


def vendor_snippet(tg: TargetGains, language: str) -> tuple[list[str], list[str], Sections]:
    """(import lines, comments, sections) of the snippet for ``tg.target`` in ``language``.

    Sections are (heading, lines) as :mod:`motorlab.control.emit` renders them: ``Code, …`` headings hold
    statements for a method.
    """
    g, ff, u = tg.gains, tg.feedforward, tg.units
    vel = tg.loop == "velocity"
    period = f"every {tg.period * 1e3:g} ms loop of yours (the controller runs its own 1 ms loop)"
    if tg.target == "phoenix6":
        control = "VelocityVoltage" if vel else "PositionVoltage"
        setpoint = "targetRotationsPerSecond" if vel else "targetRotations"
        when = f"Code, each time the setpoint changes ({setpoint}; talonFX: your TalonFX):"
        if language == "python":
            return (["from phoenix6 import configs, controls"], [], [
                ("Code, once when the robot starts:", [
                    "slot0 = configs.Slot0Configs()",
                    *[f"slot0.k_{k[1].lower()} = {_n(v)}  # {u.get(k, '')}" for k, v in (*ff.items(), *g.items())],
                    "talon_fx.configurator.apply(slot0)"]),
                (when.replace(setpoint, _snake(setpoint)).replace("talonFX", "talon_fx"),
                 [f"talon_fx.set_control(controls.{control}({_snake(setpoint)}).with_slot(0))"])])
        imports = ["import com.ctre.phoenix6.configs.Slot0Configs;", f"import com.ctre.phoenix6.controls.{control};"]
        return (imports, [], [
            ("Code, once when the robot starts (your subsystem's constructor):", [
                "Slot0Configs slot0 = new Slot0Configs();",
                *[f"slot0.{k} = {_n(v)};  // {u.get(k, '')}" for k, v in (*ff.items(), *g.items())],
                "talonFX.getConfigurator().apply(slot0);"]),
            (when, [f"talonFX.setControl(new {control}({setpoint}).withSlot(0));"])])
    model = f"the model's feedforward: kS = {_n(ff['kS'])} {u['kS']}, kV = {_n(ff['kV'])} {u['kV']}, " \
            f"kA = {_n(ff['kA'])} {u['kA']}"
    if tg.target == "phoenix5":
        mode = "Velocity" if vel else "Position"
        setpoint = "targetTicksPer100ms" if vel else "targetTicks"
        inputs = "targetTicksPer100ms" + ("" if vel else ", targetTicks") + "; talon: your Talon SRX or Victor SPX"
        imports = ["import com.ctre.phoenix.motorcontrol.ControlMode;",
                   "import com.ctre.phoenix.motorcontrol.DemandType;"]
        return (imports, [model], [
                    ("Code, once when the robot starts (your subsystem's constructor):", [
                        f"talon.configVoltageCompSaturation({_n(tg.voltage)});  // 1023 = {tg.voltage:g} V",
                        "talon.enableVoltageCompensation(true);",
                        *[f"talon.config_{k}(0, {_n(g[k])});  // {u.get(k, '')}" for k in ("kP", "kI", "kD", "kF")]]),
                    (f"Code, {period} ({inputs}); kS = {_n(ff['kS'])} of full output against the direction "
                     "of travel:",
                     [f"talon.set(ControlMode.{mode}, {setpoint}, DemandType.ArbitraryFeedForward, "
                      f"{_n(ff['kS'])} * Math.signum(targetTicksPer100ms));"])])
    kind = "kVelocity" if vel else "kPosition"
    setpoint = "targetRpm" if vel else "targetRotations"
    inputs = "targetRpm" + ("" if vel else ", targetRotations") + "; spark: your SparkMax"
    return ([
        "import com.revrobotics.spark.ClosedLoopSlot;",
        "import com.revrobotics.spark.SparkBase.ControlType;",
        "import com.revrobotics.spark.SparkBase.PersistMode;",
        "import com.revrobotics.spark.SparkBase.ResetMode;",
        "import com.revrobotics.spark.SparkClosedLoopController.ArbFFUnits;",
        "import com.revrobotics.spark.config.SparkMaxConfig;  // SparkFlexConfig for a SPARK Flex"],
        [model], [
            ("Code, once when the robot starts (your subsystem's constructor):", [
                "SparkMaxConfig config = new SparkMaxConfig();",
                f"config.closedLoop.pid({_n(g['kP'])}, {_n(g['kI'])}, {_n(g['kD'])})"
                f".velocityFF({_n(g['kF'] if vel else 0.0)});  // {u.get('kP', '')}; FF {u.get('kF', '')}",
                "spark.configure(config, ResetMode.kResetSafeParameters, PersistMode.kPersistParameters);"]),
            (f"Code, {period} ({inputs}); kS = {_n(ff['kS'])} V against the direction of travel, as an arbitrary "
             "feedforward:", [
                f"spark.getClosedLoopController().setReference({setpoint}, ControlType.{kind}, ClosedLoopSlot.kSlot0,",
                f"        {_n(ff['kS'])} * Math.signum(targetRpm), ArbFFUnits.kVoltage);"])])


def _snake(name: str) -> str:
    return "".join("_" + ch.lower() if ch.isupper() else ch for ch in name)
