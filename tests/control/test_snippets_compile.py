"""Every emitted snippet as a person pastes it (issue 31, item 6): import lines first, one class's fields, comments
in words (no command-line flags), and the Java compiles with javac against small stubs of the vendors' APIs
(tests/control/java_stubs, written from their public signatures), as tests/test_ftc_robot.py compiles ftc/."""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import pytest

from motorlab.control import DesignRequest, Feedforward, MechanismUnits, Plant, design_for_target, emit_snippet
from motorlab.control.emit import CODE, FIELDS
from motorlab.control.targets import TARGET_INFO, TARGETS

STUBS = Path(__file__).parent / "java_stubs"
JAVAC = shutil.which("javac")
FIT = Plant(Feedforward(0.3, 0.125, 0.0124), geometry={"lateral_ratio": 0.85, "track_width_ticks": 23840.0,
                                                         "lateral_kA": 0.0155})
UNITS = MechanismUnits.from_options("rad", cpr=8192, wheel_radius=0.0175)

#: The quickstart's Params fields (acmerobotics/road-runner-quickstart 08f08988, MecanumDrive.java and TankDrive.java).
QUICKSTART_PARAMS = {
    "MecanumDrive": {"logoFacingDirection", "usbFacingDirection", "inPerTick", "lateralInPerTick", "trackWidthTicks",
                     "kS", "kV", "kA", "maxWheelVel", "minProfileAccel", "maxProfileAccel", "maxAngVel", "maxAngAccel",
                     "axialGain", "lateralGain", "headingGain", "axialVelGain", "lateralVelGain", "headingVelGain"},
    "TankDrive": {"logoFacingDirection", "usbFacingDirection", "inPerTick", "trackWidthTicks", "kS", "kV", "kA",
                  "maxWheelVel", "minProfileAccel", "maxProfileAccel", "maxAngVel", "maxAngAccel", "ramseteZeta",
                  "ramseteBBar", "turnGain", "turnVelGain"},
}

#: What a person's class provides to the pasted code (the snippets name them in their comments).
INPUTS = ("double targetVelocity, targetAcceleration, targetPosition, measuredVelocity, measuredPosition, "
          "targetTicksPerSecond, targetRotationsPerSecond, targetRotations, targetTicksPer100ms, targetTicks, "
          "targetRpm;")
DEVICES = {
    "wpilib": ("edu.wpi.first.wpilibj.motorcontrol.MotorController", "MotorController motor;"),
    "phoenix6": ("com.ctre.phoenix6.hardware.TalonFX", "TalonFX talonFX;"),
    "phoenix5": ("com.ctre.phoenix.motorcontrol.can.TalonSRX", "TalonSRX talon;"),
    "spark": ("com.revrobotics.spark.SparkMax", "SparkMax spark;"),
    "spark-data-port": ("com.revrobotics.spark.SparkMax", "SparkMax spark;"),
}


def _cases() -> list[tuple[str, str, str]]:
    out = []
    for target in TARGETS:
        for loop in ("velocity", "position"):
            if target == "ftc-pidf" and loop == "position":
                continue
            for drive in ("mecanum", "tank") if target == "roadrunner" else ("mecanum",):
                out.append((target, loop, drive))
    return out


CASES = _cases()


def _snippet(target: str, loop: str, drive: str, language: str) -> str:
    _, tg = design_for_target(FIT, DesignRequest(loop, target=target, units=UNITS))
    return emit_snippet(tg, language, drive=drive)


def _sections(text: str, comment: str = "//") -> tuple[list[str], list[tuple[str, list[str]]]]:
    """(import lines, [(heading, lines)]): after the imports and the header's comments, a heading is a comment
    line right after a blank line."""
    lines = text.splitlines()
    imports = [line for line in lines if line.startswith(("import ", "from "))]
    start = len(imports) + (1 if imports else 0)
    while start < len(lines) and lines[start].startswith(comment):
        start += 1
    sections: list[tuple[str, list[str]]] = []
    for k, line in enumerate(lines[:start] + lines[start:]):
        if k < start:
            continue
        if sections and line and not (k > 0 and lines[k - 1] == "" and line.startswith(comment)):
            sections[-1][1].append(line)
        elif k > 0 and lines[k - 1] == "" and line.startswith(comment):
            sections.append((line[len(comment):].strip(), []))
    return imports, sections


@pytest.mark.parametrize("language", ["java", "kotlin", "python"])
def test_snippets_start_with_their_imports_and_speak_in_words(language: str) -> None:
    comment = "#" if language == "python" else "//"
    for target, loop, drive in CASES:
        if language not in TARGET_INFO[target].languages:
            continue
        text = _snippet(target, loop, drive, language)
        lines = text.splitlines()
        imports, sections = _sections(text, comment)
        # Imports first: every import line comes before anything else.
        assert lines[:len(imports)] == imports, (target, text)
        assert sections, (target, text)
        fields = [h for h, _ in sections if h.startswith(FIELDS)]
        assert len(fields) <= 1, (target, fields)  # one class's fields per snippet
        if target == "roadrunner":
            cls = "MecanumDrive" if drive == "mecanum" else "TankDrive"
            other = "TankDrive" if drive == "mecanum" else "MecanumDrive"
            assert all(other not in h for h, _ in sections), (drive, text)
            assert any(cls in h for h, _ in sections)
        comments = [line.split(comment, 1)[1] for line in lines if comment in line]
        flags = [c for c in comments if re.search(r"(?<![\w-])--[a-z]", c)]
        assert not flags, (target, language, flags)  # words, not the command line's flags
        if language == "python":
            compile(text, f"<{target} {loop}>", "exec")  # Python: valid as pasted


def _java_class(name: str, target: str, text: str) -> str:
    imports, sections = _sections(text)
    fields = [line for h, body in sections if h.startswith(FIELDS) for line in body]
    code = [line for h, body in sections if h.startswith(CODE) for line in body]
    assert all(h.startswith((FIELDS, CODE)) for h, _ in sections), [h for h, _ in sections]
    extra = [f"import {DEVICES[target][0]};"] if target in DEVICES else []
    base = " extends LinearOpMode" if target.startswith("ftc") else ""
    if base:
        extra.append("import com.qualcomm.robotcore.eventloop.opmode.LinearOpMode;")
    device = DEVICES[target][1] if target in DEVICES else ""
    body = "\n".join([f"    {INPUTS}", f"    {device}", *("    " + f for f in fields),
                      "    public void runOpMode() {", *("        " + c for c in code), "    }"])
    return "\n".join([*imports, *extra, "", f"public class {name}{base} {{", body, "}", ""])


@pytest.mark.skipif(JAVAC is None, reason="javac not found: install a JDK (Debian: default-jdk-headless)")
def test_java_snippets_compile_as_pasted(tmp_path: Path) -> None:
    sources = []
    for k, (target, loop, drive) in enumerate(CASES):
        text = _snippet(target, loop, drive, "java")
        if target == "roadrunner":  # fields of the quickstart's Params: the names it has, in a class of their own
            cls = "MecanumDrive" if drive == "mecanum" else "TankDrive"
            _, sections = _sections(text)
            (heading, fields), = sections
            assert heading.startswith(f"{FIELDS} {cls}.Params")
            names = {re.match(r"public double (\w+) = ", f).group(1) for f in fields}  # type: ignore[union-attr]
            assert names <= QUICKSTART_PARAMS[cls], names - QUICKSTART_PARAMS[cls]
            assert {"kS", "kV", "kA", "inPerTick"} <= names
            source = "\n".join([f"class Params{k} {{", *fields, "}", ""])
        else:
            source = _java_class(f"Pasted{k}", target, text)
        path = tmp_path / f"{'Params' if target == 'roadrunner' else 'Pasted'}{k}.java"
        path.write_text(source, encoding="utf-8")
        sources.append(path)
    stubs = sorted(STUBS.rglob("*.java"))
    out = tmp_path / "classes"
    out.mkdir()
    done = subprocess.run([str(JAVAC), "--release", "8", "-nowarn", "-encoding", "UTF-8", "-d", str(out),
                           *map(str, stubs + sources)], capture_output=True, text=True, timeout=300, check=False)
    assert done.returncode == 0, done.stderr[-4000:]
    assert len(list(out.glob("Pasted*.class"))) + len(list(out.glob("Params*.class"))) == len(CASES)
