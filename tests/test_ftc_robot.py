"""The robot code in ``ftc/``: it compiles against the SDK stubs, and its OpModes, run in the JVM against
a simulated hub, motor and INA219, write logs that motorlab analyses back to the simulation's truth.

The Java side (``ftc/TeamCode/src/test/java/.../sim``) runs the real OpMode classes: a motor+load plant
(J·dω/dt = K·i − b·ω − Tf·sgn ω, i from a current-limited bench supply behind the relay or from the
hub's H-bridge), a hub whose commands take ~1.2 ms and whose bulk reads are cached, and an INA219
emulated at register level (calibration, PGA clipping, 4 mV / 10 µV quanta, noise).
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from motorlab.analyses.feedforward import feedforward
from motorlab.analyses.spindown import spindown
from motorlab.io import read_csv, read_ftc_log
from motorlab.robot.emulator import EmulatedRobot, OpModeSpec
from motorlab.robot.emulator_jvm import JvmOpMode

ROOT = Path(__file__).resolve().parents[1]
FTC = ROOT / "ftc"
SIM = "org.firstinspires.ftc.teamcode.motorlab.sim.RunSim"
JAVAC = shutil.which("javac")
JAVA = shutil.which("java")
#: The JVM's options for these short runs: the client compiler only (C1) and one garbage-collector thread. The
#: programs and their output are the same; the JVM spends half the CPU (a 64-file javac: 5.6 s against 2.7 s, a
#: spin-down OpMode: 0.9 s against 0.4 s), most of it otherwise in the server compiler's threads.
JVM_OPTIONS = ("-XX:TieredStopAtLevel=1", "-XX:+UseSerialGC")

pytestmark = pytest.mark.skipif(
    JAVAC is None or JAVA is None,
    reason="javac/java not found: install a JDK (Debian: apt-get install default-jdk-headless; .ci/run does)",
)


#: Official samples (FtcRobotController/.../external/samples) that use motors, servos, digital/touch inputs,
#: bulk reads, telemetry (with its log) and gamepads (with rumble and edge detection), and nothing else of the
#: SDK: they must compile unmodified against ftc/sdk-stubs. Names are paths under samples/, without ".java".
SAMPLES = (
    "BasicOpMode_Linear", "BasicOpMode_Iterative", "BasicOmniOpMode_Linear", "ConceptMotorBulkRead",
    "ConceptRampMotorSpeed", "ConceptNullOp", "RobotAutoDriveByEncoder_Linear", "RobotAutoDriveByTime_Linear",
    "ConceptTelemetry", "ConceptGamepadRumble", "RobotTeleopTank_Iterative", "RobotTeleopPOV_Linear",
    "ConceptScanServo", "ConceptGamepadTouchpad", "ConceptGamepadEdgeDetection", "ConceptBlackboard",
    "ConceptRevSPARKMini", "SensorDigitalTouch", "SensorTouch",
    "externalhardware/RobotHardware", "externalhardware/ConceptExternalHardwareClass",
)


def _javac(sources: list[Path], out: Path, classpath: Path | None = None, *, strict: bool = True) -> None:
    # Lint warnings are shown (not fatal: newer JDKs add lints, and call release 8 obsolete).
    args = [str(JAVAC), *(f"-J{o}" for o in JVM_OPTIONS), "--release", "8", "-encoding", "UTF-8", "-d", str(out)]
    args += ["-Xlint:all,-options"] if strict else ["-nowarn"]
    if classpath is not None:
        args += ["-cp", str(classpath)]
    listing = out.parent / f"{out.name}-sources.txt"
    listing.write_text("\n".join(str(s) for s in sources) + "\n", encoding="utf-8")
    done = subprocess.run([*args, f"@{listing}"], capture_output=True, text=True, timeout=300, check=False)
    assert done.returncode == 0, done.stderr[-4000:]


@pytest.fixture(scope="module")
def classes(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Stubs, OpModes and simulator compiled with ``javac --release 8``."""
    out = tmp_path_factory.mktemp("ftc") / "classes"
    out.mkdir()
    _javac(sorted(FTC.rglob("*.java")), out)
    return out


def run_sim(classes: Path, out: Path, **options: object) -> dict:
    """Run one OpMode in the simulator; its JSON summary (stop reason, log path, truth ...)."""
    out.mkdir(parents=True, exist_ok=True)
    args = [str(JAVA), *JVM_OPTIONS, "-cp", str(classes), SIM, f"out={out}", *(f"{k}={v}" for k, v in options.items())]
    done = subprocess.run(args, capture_output=True, text=True, timeout=120, check=False)
    assert done.returncode == 0, done.stderr[-4000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_every_source_compiles_for_java_8(classes: Path) -> None:
    names = {p.stem for p in (classes / "org/firstinspires/ftc/teamcode/motorlab").glob("*.class")}
    assert {"Ina219", "SpinDownOpMode", "SpinUpOpMode", "QuasistaticOpMode", "DynamicStepOpMode"} <= names
    # Class file major version 52 = Java 8 (what the FTC SDK's Android toolchain accepts).
    raw = (classes / "org/firstinspires/ftc/teamcode/motorlab/Ina219.class").read_bytes()
    assert int.from_bytes(raw[6:8], "big") == 52


@pytest.mark.skipif(not os.environ.get("MOTORLAB_FTC_SAMPLES"),
                    reason="set MOTORLAB_FTC_SAMPLES to FtcRobotController's external/samples folder")
def test_official_samples_compile_unmodified_against_the_stubs(tmp_path: Path) -> None:
    """The FTC SDK's samples cannot be shipped here; point MOTORLAB_FTC_SAMPLES at them (docs/ftc-robot.md)."""
    folder = Path(os.environ["MOTORLAB_FTC_SAMPLES"])
    samples = [folder / f"{name}.java" for name in SAMPLES if (folder / f"{name}.java").is_file()]
    found = {p.stem for p in samples}
    assert {"BasicOpMode_Linear", "ConceptMotorBulkRead"} <= found, f"{folder} lacks the official samples"
    stubs = tmp_path / "stubs"
    stubs.mkdir()
    _javac(sorted((FTC / "sdk-stubs").rglob("*.java")), stubs)
    out = tmp_path / "samples"
    out.mkdir()
    _javac(samples, out, classpath=stubs, strict=False)
    assert len(list(out.rglob("*.class"))) >= len(samples)


@pytest.mark.parametrize("seed", [1, 2])
def test_spindown_round_trip_through_the_jvm(classes: Path, tmp_path: Path, seed: int) -> None:
    """Relay rig (seed 1): the log's K, γ = b/J and Tf/J against the Java model's truth."""
    summary = run_sim(classes, tmp_path, experiment="spindown", seed=seed)
    assert summary["stop_reason"] == "complete"
    assert not summary["relay_closed"]
    truth = summary["truth"]
    rec = read_ftc_log(summary["log"])
    assert rec.metadata["experiment"] == "spindown"
    assert rec.metadata["motor"] == "neverest40"
    assert rec.metadata["cpr"] == truth["cpr"]  # from the header: no cpr passed
    assert rec.metadata["gear_ratio"] == 40.0
    assert rec.metadata["drive"] == "relay"
    step_ms = float(np.median(np.diff(rec.time))) * 1e3
    assert 3.0 < step_ms < 8.0  # one bulk read + two INA219 registers per loop
    assert summary["bulk_reads"] >= rec.time.size  # MANUAL caching: one bulk read per sample

    # The INA219 path (calibration, current register): the supply's constant-current phase (the first
    # ~0.4 s after the relay closes, until R·i + K·ω reaches 12 V) reads 2.5 A.
    current = rec.signals["current"]
    first = int(np.flatnonzero(current > 1.0)[0])
    assert float(np.median(current[first + 2:first + 40])) == pytest.approx(2.5, rel=2e-3)

    result = spindown(rec, inertia=truth["J"])
    p = result.parameters
    for name, true in (("gamma", truth["b"] / truth["J"]), ("Tf_over_J", truth["Tf"] / truth["J"])):
        assert abs(p[name].value - true) < 4 * p[name].stderr, (name, p[name], true)
    # K: the INA219 is read ~1 transaction before the encoder latch, a timing offset the stderr does not
    # include; its bias (≈ offset·|dω/dt|/ω) is a few 1e-4 here (docs/ftc-robot.md, "Timing").
    assert p["K"].value == pytest.approx(truth["K"], rel=1e-3)
    assert p["b"].value == pytest.approx(truth["b"], rel=1e-3)
    assert p["Tf"].value == pytest.approx(truth["Tf"], rel=2e-3)


def test_cli_analyses_the_log_with_the_headers_cpr(classes: Path, tmp_path: Path,
                                                  capsys: pytest.CaptureFixture[str]) -> None:
    """``motorlab analyze`` (in this process: tests/cli/test_bad_input.py runs the real entry point) on the log."""
    from motorlab.cli import main

    summary = run_sim(classes, tmp_path, experiment="spindown", seed=3)
    capsys.readouterr()
    assert main(["analyze", "spindown", summary["log"], "--inertia", "0.1", "--json"]) == 0
    k = json.loads(capsys.readouterr().out)["parameters"]["K"]
    assert k["value"] == pytest.approx(summary["truth"]["K"], rel=1e-3)


def test_hub_spindown_logs_counts_and_the_cutoff(classes: Path, tmp_path: Path) -> None:
    """Without relay and INA219 the hub cuts the power (FLOAT): no back-EMF, so γ and Tf/J only."""
    summary = run_sim(classes, tmp_path, experiment="spindown", drive="hub", ina="no", seed=4)
    rec = read_ftc_log(summary["log"])
    assert rec.metadata["variant"] == "ticks"
    assert rec.metadata["drive"] == "hub"
    result = spindown(rec, cutoff=rec.metadata["cutoff_s"], inertia=summary["truth"]["J"])
    assert "K" not in result.parameters
    truth = summary["truth"]
    assert result.parameters["gamma"].value == pytest.approx(truth["b"] / truth["J"], rel=1e-3)
    assert result.parameters["Tf_over_J"].value == pytest.approx(truth["Tf"] / truth["J"], rel=2e-3)


def test_mechanism_tests_give_the_feedforward_gains(classes: Path, tmp_path: Path) -> None:
    """Quasistatic ramps and dynamic steps, both ways, hub drive: kS = R·Tf/K, kV = K + R·b/K, kA = R·J/K."""
    plant = {"J": 0.02, "b": 0.005, "Tf": 0.1}
    runs = []
    for k, (experiment, direction) in enumerate(
        [("quasistatic", "forward"), ("quasistatic", "backward"), ("dynamic", "forward"), ("dynamic", "backward")]
    ):
        summary = run_sim(classes, tmp_path / f"{experiment}-{direction}", experiment=experiment,
                          direction=direction, drive="hub", ina="no", seed=10 + k, **plant)
        assert summary["stop_reason"] == "complete"
        assert summary["hub_power"] == 0.0
        runs.append(read_ftc_log(summary["log"]))
    t = summary["truth"]
    result = feedforward(runs)
    p = result.parameters
    assert p["kS"].value == pytest.approx(t["R"] * t["Tf"] / t["K"], rel=5e-3)
    assert p["kV"].value == pytest.approx(t["K"] + t["R"] * t["b"] / t["K"], rel=1e-3)
    # The command takes effect ~one hub transaction (≈1.2 ms) before the encoder latch that the ZOH of
    # the fit assumes: kA comes out low by ≈ kV·1.5 ms ≈ 2 % (docs/ftc-robot.md, "Timing").
    ka = t["R"] * t["J"] / t["K"]
    assert -0.04 < p["kA"].value / ka - 1 < 0.0


def test_ina219_refuses_to_run_above_16_volts(classes: Path, tmp_path: Path) -> None:
    """An 18 V supply in constant current: the bus (R·i + K·ω) climbs as the motor speeds up; the first
    reading at 16 V ends the run and opens the relay, before anything at 16 V or more is logged."""
    summary = run_sim(classes, tmp_path, experiment="spindown", supply_V=18, seed=5)
    assert "above 16.0 V" in summary["stop_reason"]
    assert not summary["relay_closed"]
    rec = read_ftc_log(summary["log"])
    volts = rec.signals["voltage"]
    assert np.all(volts < 16.0)
    assert volts[-1] > 15.8  # it stopped at the next reading
    assert rec.time[-1] < 2.0  # long before the 4 s powered phase ends
    assert any("above 16.0 V" in line for line in summary["screen"])


@pytest.mark.parametrize(
    ("option", "reason"),
    [("max_current=1.0", "limit: current"), ("max_speed=1500", "limit: speed"), ("max_seconds=1.5", "limit: time")],
)
def test_limits_stop_the_motor(classes: Path, tmp_path: Path, option: str, reason: str) -> None:
    key, value = option.split("=")
    summary = run_sim(classes, tmp_path, experiment="spinup", seed=6, **{key: value})
    assert summary["stop_reason"].startswith(reason), summary["stop_reason"]
    assert not summary["relay_closed"]
    rec = read_ftc_log(summary["log"])
    assert rec.time[-1] < 4.0  # stopped well before the 4.5 s schedule ends


def test_ina219_register_arithmetic_matches_the_data_sheet(classes: Path) -> None:
    """0x399F reset word, calibration 4096 for 0.1 Ω and 100 µA, refusals (RegisterCheck.java)."""
    done = subprocess.run([str(JAVA), *JVM_OPTIONS, "-cp", str(classes),
                           "org.firstinspires.ftc.teamcode.motorlab.sim.RegisterCheck"],
                          capture_output=True, text=True, timeout=60, check=False)
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.strip() == "ok"


def test_a_current_beyond_the_shunt_range_is_flagged(classes: Path, tmp_path: Path) -> None:
    """Seed 1 sets a 4 A supply limit for the AM20, but 0.1 Ω and ±320 mV end at 3.2 A: the clipped rows
    are counted and the Driver Station says so (the run itself continues)."""
    summary = run_sim(classes, tmp_path, experiment="spinup", supply_A=4.0, seed=7)
    assert summary["stop_reason"] == "complete"
    assert summary["saturated_rows"] > 10
    assert any(line.startswith("WARNING") and "3.20 A" in line for line in summary["screen"])
    rec = read_ftc_log(summary["log"])
    assert float(np.max(rec.signals["current"])) == pytest.approx(3.2, rel=2e-3)


def test_the_log_handler_serves_the_opmode_logs_to_robot_pull(classes: Path, tmp_path: Path) -> None:
    """MotorlabLogFiles' handlers (registered as the SDK's @WebHandlerRegistrar does) behind a JVM web server on
    127.0.0.1: ``motorlab robot pull`` lists and brings back every log byte for byte."""
    from motorlab.cli import main

    summary = run_sim(classes, tmp_path / "run", experiment="spindown", drive="hub", ina="no", seed=6)
    folder = Path(summary["log"]).parent
    (folder / "notes with spaces.txt").write_bytes(b"# not a log\r\n\x00\xff")
    server = subprocess.Popen([str(JAVA), *JVM_OPTIONS, "-cp", str(classes),
                               "org.firstinspires.ftc.teamcode.motorlab.sim.LogServer", str(folder), "60"],
                              stdout=subprocess.PIPE, text=True)
    try:
        assert server.stdout is not None
        port = server.stdout.readline().strip()
        out = tmp_path / "pulled"
        assert main(["robot", "pull", "--host", "127.0.0.1", "--http-port", port, "-o", str(out)]) == 0
    finally:
        server.terminate()
        server.wait(10)
        if server.stdout is not None:
            server.stdout.close()
    originals = sorted(p for p in folder.iterdir() if p.is_file())
    assert len(originals) == 2
    for original in originals:
        assert (out / "motorlab" / original.name).read_bytes() == original.read_bytes()
    assert sorted(p.name for p in (out / "motorlab").iterdir()) == [p.name for p in originals]


def _sim_robot(classes: Path, out: Path, seconds: float, **options: object) -> tuple[EmulatedRobot, JvmOpMode]:
    """An emulated robot whose "motorlab: quasistatic ramp" is the real OpMode in the JVM, in real time."""
    args = [str(JAVA), *JVM_OPTIONS, "-cp", str(classes), SIM, f"out={out}", "realtime=yes", "dashboard=yes",
            "stdin_stop=yes",
            *(f"{k}={v}" for k, v in options.items())]
    robot = EmulatedRobot(opmodes=[OpModeSpec("motorlab: quasistatic ramp", "motorlab", "quasistatic_ramp")],
                          lifetime=seconds + 30)
    opmode = JvmOpMode(args)
    robot.external_opmode = opmode
    return robot, opmode


def test_recorded_dashboard_telemetry_of_the_opmode_analyses_to_the_truth(
        classes: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """record → analyze: the real QuasistaticOpMode publishes each sample to FTC Dashboard (numbers, units in
    the keys); ``motorlab robot record`` logs them from the emulated robot and ``motorlab analyze feedforward``
    reads that log with no column, unit or cpr given, to kS = R·Tf/K, kV = K + R·b/K, kA = R·J/K of the plant.
    ``record`` stops the OpMode at --seconds, before its ramp ends: STOP reaches the OpMode."""
    from motorlab.cli import main

    robot, opmode = _sim_robot(classes, tmp_path / "robot", 3.0, experiment="quasistatic", drive="hub", ina="no",
                               ramp=3, max_V=12, seed=21)
    log = tmp_path / "ramp.csv"
    with robot:
        assert main(["robot", "record", "--host", "127.0.0.1", "--dashboard-port", str(robot.dashboard_port),
                     "--opmode", "motorlab: quasistatic ramp", "--seconds", "3", "-o", str(log)]) == 0
    summary = opmode.summary
    assert summary["stop_reason"] == "stopped from the Driver Station", (summary, opmode.stderr)
    assert opmode.dropped == 0
    rec = read_csv(log)
    assert {"voltage", "current", "counts", "position", "velocity", "battery"} <= set(rec.signals)
    # every sample the OpMode took while recording, with the OpMode's own clock (µs, not the packets' ms)
    assert rec.time.size > 0.8 * summary["rows"]
    steps = np.diff(rec.time)
    assert 3e-3 < float(np.median(steps)) < 8e-3
    assert len({round(x * 1e6) for x in steps}) > 50
    capsys.readouterr()
    assert main(["analyze", "feedforward", str(log), "--json"]) == 0
    p = json.loads(capsys.readouterr().out)["parameters"]
    t = summary["truth"]
    truth = {"kS": t["R"] * t["Tf"] / t["K"], "kV": t["K"] + t["R"] * t["b"] / t["K"], "kA": t["R"] * t["J"] / t["K"]}
    for name in ("kS", "kV"):
        assert abs(p[name]["value"] - truth[name]) < 4 * p[name]["stderr"], (name, p[name], truth[name])
    # kA: the command's ~1 hub transaction ahead of the encoder latch biases it low by up to ~2 % (see
    # test_mechanism_tests_give_the_feedforward_gains), which its stderr does not include.
    assert -0.04 < p["kA"]["value"] / truth["kA"] - 1 < 0.01


#: Keys every OpMode publishes to FTC Dashboard (ftc/README.md's table); voltage and current where the log has them.
KEYS = {"time_s", "position_counts", "position_rad", "velocity_rad_per_s"}


@pytest.mark.parametrize(
    ("experiment", "options", "power"),
    [("spindown", {"run_s": 1, "coast_s": 1}, True), ("spindown", {"drive": "hub", "ina": "no", "run_s": 1,
                                                                  "coast_s": 1}, False),
     ("spinup", {"run_s": 1}, True), ("quasistatic", {"drive": "hub", "ina": "no", "ramp": 8}, True),
     ("dynamic", {"drive": "hub", "ina": "no", "step_s": 0.5}, True)],
)
def test_every_opmode_publishes_each_logged_sample_to_dashboard(classes: Path, tmp_path: Path, experiment: str,
                                                                options: dict, power: bool) -> None:
    """Each packet holds one logged row: the same numbers as the log file, in SI with the units in the keys."""
    args = [str(JAVA), *JVM_OPTIONS, "-cp", str(classes), SIM, f"out={tmp_path}", f"experiment={experiment}",
            "dashboard=yes", "seed=8", *(f"{k}={v}" for k, v in options.items())]
    done = subprocess.run(args, capture_output=True, text=True, timeout=120, check=False)
    assert done.returncode == 0, done.stderr[-4000:]
    lines = [json.loads(line) for line in done.stdout.splitlines() if line.startswith("{")]
    summary, packets = lines[-1], [p["data"] for p in lines[:-1]]
    assert summary["stop_reason"] == "complete"
    assert len(packets) == summary["rows"] == summary["dashboard_packets"] > 100
    expected = KEYS | ({"voltage_V", "current_A"} if power else set())
    expected |= {"battery_V"} if "drive" in options else set()  # the hub drive reads the battery each loop
    assert all(set(p) == expected for p in packets), (set(packets[0]), expected)
    rec = read_ftc_log(summary["log"])
    sent = {key: np.array([float(p[key]) for p in packets]) for key in expected}  # every value a number
    np.testing.assert_allclose(sent["time_s"], rec.time, atol=1e-6)
    np.testing.assert_array_equal(sent["position_counts"], rec.signals["counts"])
    np.testing.assert_allclose(sent["position_rad"], rec.signals["counts"] * 2 * np.pi / summary["truth"]["cpr"])
    if power:
        np.testing.assert_allclose(sent["voltage_V"], rec.signals["voltage"], atol=1e-4)
        np.testing.assert_allclose(sent["current_A"], rec.signals["current"], atol=1e-5)


#: Java comments and string literals (what names a class without using it).
_JAVA_NOISE = re.compile(r'/\*.*?\*/|//[^\n]*|"(?:\\.|[^"\\])*"', re.DOTALL)


def test_the_opmodes_compile_and_run_without_ftc_dashboard(classes: Path, tmp_path: Path) -> None:
    """A project without FTC Dashboard: DashboardTelemetry.java deleted (ftc/README.md), no Dashboard library.
    No other source names Dashboard or that class (so they compile against the SDK alone), and the OpModes,
    run with neither on the class path, run as before and publish nothing."""
    main_sources = sorted((FTC / "TeamCode/src/main").rglob("*.java"))
    code = {p.name: _JAVA_NOISE.sub(" ", p.read_text(encoding="utf-8")) for p in main_sources}
    naming = [name for name, text in code.items() if name != "DashboardTelemetry.java"
              and ("acmerobotics" in text or "DashboardTelemetry" in text)]
    assert naming == []
    assert "acmerobotics" in code["DashboardTelemetry.java"]
    robot = tmp_path / "classes"  # the compiled OpModes and simulator without Dashboard, its stand-in, the class
    shutil.copytree(classes, robot, ignore=shutil.ignore_patterns("acmerobotics", "DashboardTelemetry*",
                                                                   "SimDashboard*"))
    done = subprocess.run([str(JAVA), *JVM_OPTIONS, "-cp", str(robot), SIM, f"out={tmp_path}", "experiment=quasistatic",
                           "drive=hub", "ina=no", "ramp=8", "seed=9"],
                          capture_output=True, text=True, timeout=120, check=False)
    assert done.returncode == 0, done.stderr[-4000:]
    summary = json.loads(done.stdout.strip().splitlines()[-1])
    assert summary["stop_reason"] == "complete"
    assert summary["dashboard_packets"] == 0
    assert read_ftc_log(summary["log"]).time.size == summary["rows"] > 100


#: The FTC Dashboard stubs and the upstream files they stand for (acmerobotics/ftc-dashboard).
DASHBOARD_STUBS = {
    "com/acmerobotics/dashboard/FtcDashboard.java":
        "FtcDashboard/src/main/java/com/acmerobotics/dashboard/FtcDashboard.java",
    "com/acmerobotics/dashboard/telemetry/TelemetryPacket.java":
        "DashboardCore/src/main/java/com/acmerobotics/dashboard/telemetry/TelemetryPacket.java",
}
_PUBLIC = re.compile(r"^\s*(public [^=;{]*\))\s*\{", re.MULTILINE)


@pytest.mark.skipif(not os.environ.get("MOTORLAB_FTC_DASHBOARD"),
                    reason="set MOTORLAB_FTC_DASHBOARD to a checkout of acmerobotics/ftc-dashboard (any tag)")
def test_the_dashboard_stubs_have_the_real_signatures() -> None:
    """Every public method and constructor of the two stubs is declared the same upstream (docs/ftc-robot.md)."""
    upstream_root = Path(os.environ["MOTORLAB_FTC_DASHBOARD"])
    for stub, upstream in DASHBOARD_STUBS.items():
        real = " ".join((upstream_root / upstream).read_text(encoding="utf-8").split())
        mine = _PUBLIC.findall((FTC / "sdk-stubs/src/main/java" / stub).read_text(encoding="utf-8"))
        assert mine, stub
        for signature in mine:
            assert " ".join(signature.split()) in real, (stub, signature)
