"""``motorlab robot record`` and ``push`` against the emulated FTC Dashboard: telemetry into a log that
``analyze feedforward`` reads back to the emulated motor's truth; gains into MecanumDrive.PARAMS and back."""

from __future__ import annotations

import copy
import csv
import json
import math
import threading
import time
from pathlib import Path

import pytest

from motorlab.cli import main
from motorlab.robot import RobotLinkError
from motorlab.robot.config import leaves
from motorlab.robot.dashboard import STOP_TAG, Dashboard
from motorlab.robot.emulator import EmulatedRobot, Plant, default_config_tree
from motorlab.robot.record import Recorder

OPMODE = "motorlab: quasistatic ramp"


def _record(robot: EmulatedRobot, out: Path, *extra: str) -> int:
    return main(["robot", "record", "--host", "127.0.0.1", "--dashboard-port", str(robot.dashboard_port),
                 "--opmode", OPMODE, "-o", str(out), *extra])


def test_record_captures_the_telemetry_and_analyze_feedforward_reads_it(
        robot: EmulatedRobot, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    log = tmp_path / "run.csv"
    assert _record(robot, log, "--seconds", "2.5", "--cpr", str(robot.plant.cpr)) == 0
    out = capsys.readouterr().out
    assert "'state' is not a number" in out
    kinds = [m["type"] for m in robot.received]
    assert kinds.index("INIT_OP_MODE") < kinds.index("START_OP_MODE") < kinds.index("STOP_OP_MODE")
    assert robot.active == STOP_TAG

    rows = list(csv.DictReader(line for line in log.read_text().splitlines() if not line.startswith("#")))
    assert 150 <= len(rows) <= 300  # a 10 ms loop for 2.5 s (fewer when the machine is loaded)
    expected = robot.plant.run(5.0)
    for row in rows:  # keys, values and timestamps exactly as the robot sent them
        t, volts, x, v = expected[round(float(row["time_s"]) / robot.plant.period)]
        assert float(row["time_s"]) == pytest.approx(t, abs=5e-4)
        assert row["voltage_V"] == f"{volts:.4f}"
        assert row["position_counts"] == f"{x:.0f}"
        assert row["x_velocity"] == f"{v:.3f}"
        assert float(row["battery_V"]) == robot.battery

    assert main(["analyze", "feedforward", str(log), "--json"]) == 0
    fit = json.loads(capsys.readouterr().out)["parameters"]
    p = Plant()
    per_rad = p.cpr / (2 * math.pi)
    truth = {"kS": p.kS, "kV": p.kV * per_rad, "kA": p.kA * per_rad}
    for name, value in truth.items():
        assert abs(fit[name]["value"] - value) < 4 * fit[name]["stderr"] + 2e-3 * value, (name, fit[name], value)


def test_stop_reaches_the_robot_within_100_ms(robot: EmulatedRobot) -> None:
    recorder = Recorder("127.0.0.1", robot.dashboard_port, OPMODE, seconds=30)
    thread = threading.Thread(target=recorder.run, daemon=True)
    thread.start()
    deadline = time.monotonic() + 10
    while robot.status != "RUNNING" and time.monotonic() < deadline:
        time.sleep(0.01)
    time.sleep(0.3)
    assert robot.status == "RUNNING"
    pressed = time.monotonic()
    recorder.stop()
    while robot.active != STOP_TAG and time.monotonic() - pressed < 1.0:
        time.sleep(0.001)
    latency = time.monotonic() - pressed
    assert robot.active == STOP_TAG
    assert latency < 0.1, latency
    thread.join(5)
    assert not thread.is_alive()
    assert recorder.data.stop_reason == "stopped by the user"


def test_lost_connection_ends_the_recording_and_says_the_robot_may_run(robot_files: object, tmp_path: Path) -> None:
    with EmulatedRobot(lifetime=30) as flaky:
        recorder = Recorder("127.0.0.1", flaky.dashboard_port, OPMODE, seconds=30)
        thread = threading.Thread(target=recorder.run, daemon=True)
        thread.start()
        deadline = time.monotonic() + 10
        while flaky.status != "RUNNING" and time.monotonic() < deadline:
            time.sleep(0.01)
        time.sleep(0.3)
        flaky.stop()  # the Wi-Fi goes
        lost = time.monotonic()
        thread.join(10)
    assert not thread.is_alive()
    assert time.monotonic() - lost < 6.0  # 1 s of silence + 3 s of reconnecting, at most
    assert "connection lost" in recorder.data.stop_reason
    assert recorder.data.still_running
    assert "STOP on the Driver Station" in recorder.data.stop_reason
    assert recorder.data.rows  # what came before is kept


def test_record_refuses_unknown_opmode_and_a_running_one(robot: EmulatedRobot, tmp_path: Path,
                                                         capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["robot", "record", "--host", "127.0.0.1", "--dashboard-port", str(robot.dashboard_port),
                 "--opmode", "quasistatic", "-o", str(tmp_path / "a.csv")]) == 2
    err = capsys.readouterr().err
    assert "no OpMode named 'quasistatic'" in err
    assert "did you mean 'motorlab: quasistatic ramp'" in err
    robot.active, robot.status = "LocalizationTest", "RUNNING"
    assert _record(robot, tmp_path / "b.csv") == 2
    assert "already active" in capsys.readouterr().err
    assert not any(m["type"] == "INIT_OP_MODE" for m in robot.received)
    assert not (tmp_path / "a.csv").exists()
    assert not (tmp_path / "b.csv").exists()


def test_no_dashboard_is_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    with EmulatedRobot(lifetime=10) as gone:
        closed = gone.dashboard_port
    with EmulatedRobot(dashboard=False, lifetime=10) as no_dash:
        for port, words in ((closed, "no FTC Dashboard"), (no_dash.http_port, "not FTC Dashboard's WebSocket")):
            assert main(["robot", "record", "--host", "127.0.0.1", "--dashboard-port", str(port), "--opmode", OPMODE,
                         "-o", str(tmp_path / "x.csv")]) == 2
            err = capsys.readouterr().err.strip().splitlines()
            assert words in err[-1]
            assert err[-1].startswith("motorlab: error:")
    assert not (tmp_path / "x.csv").exists()


@pytest.fixture(scope="module")
def fit(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("fit") / "fit.json"
    path.write_text(json.dumps({"experiment": "feedforward", "parameters": {
        "kS": {"value": 0.3057812733394148, "stderr": 0.003, "unit": "V"},
        "kV": {"value": 0.12534218382790457, "stderr": 1e-4, "unit": "V*s/rad"},
        "kA": {"value": 0.012422532761357064, "stderr": 1e-4, "unit": "V*s^2/rad"}}}))
    return path


def _push(robot: EmulatedRobot, *extra: str) -> int:
    return main(["robot", "push", "--host", "127.0.0.1", "--dashboard-port", str(robot.dashboard_port), *extra])


def test_push_writes_kS_kV_kA_per_tick_only_and_restore_puts_them_back(
        robot: EmulatedRobot, fit: Path, capsys: pytest.CaptureFixture[str]) -> None:
    before = copy.deepcopy(robot.config)
    assert _push(robot, "--params", str(fit), "--target", "roadrunner", "--cpr", "8192", "--yes") == 0
    out = capsys.readouterr().out
    assert "until the robot controller app restarts" in out
    assert "public double kV = " in out  # the code to paste for good
    after = leaves(robot.config)
    tick = 2 * math.pi / 8192
    want = {"kS": 0.3057812733394148, "kV": 0.12534218382790457 * tick, "kA": 0.012422532761357064 * tick}
    for name, value in want.items():
        assert after[f"MecanumDrive.PARAMS.{name}"][1] == pytest.approx(value, rel=1e-6)
    changed = {p for p, v in leaves(before).items() if after[p] != v}
    assert changed == {f"MecanumDrive.PARAMS.{n}" for n in want}
    saves = [m for m in robot.received if m["type"] == "SAVE_CONFIG"]
    assert len(saves) == 1
    assert set(leaves(saves[0]["configDiff"])) == changed  # the diff holds those leaves only
    assert robot.errors == []
    assert (fit.parent / "fit.robot-push.json").is_file()

    assert _push(robot, "--params", str(fit), "--restore", "--yes") == 0
    assert robot.config == before


def test_push_asks_and_refuses_while_an_opmode_runs(robot: EmulatedRobot, fit: Path, tmp_path: Path,
                                                    capsys: pytest.CaptureFixture[str]) -> None:
    state = str(tmp_path / "state.json")
    before = copy.deepcopy(robot.config)
    assert _push(robot, "--params", str(fit), "--target", "roadrunner", "--cpr", "8192", "--state", state) == 2
    assert "confirm with --yes" in capsys.readouterr().err  # no terminal to ask on: nothing written
    robot.active, robot.status = "LocalizationTest", "RUNNING"
    assert _push(robot, "--params", str(fit), "--target", "roadrunner", "--cpr", "8192", "--yes", "--state", state) == 2
    assert "--while-running" in capsys.readouterr().err
    assert robot.config == before
    assert not any(m["type"] == "SAVE_CONFIG" for m in robot.received)
    assert _push(robot, "--params", str(fit), "--target", "roadrunner", "--cpr", "8192", "--yes",
                 "--while-running", "--state", state) == 0
    assert robot.config != before


def test_a_tree_without_the_fields_is_one_line(fit: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    tree = default_config_tree()
    del tree["__value"]["MecanumDrive"]
    with EmulatedRobot(config_tree=tree, lifetime=20) as other:
        assert _push(other, "--params", str(fit), "--target", "roadrunner", "--cpr", "8192", "--yes",
                     "--state", str(tmp_path / "s.json")) == 2
        err = capsys.readouterr().err.strip()
        assert "no MecanumDrive.PARAMS.kS" in err
        assert "\n" not in err
        assert _push(other, "--params", str(fit), "--target", "roadrunner", "--cpr", "8192", "--yes", "--state",
                     str(tmp_path / "s.json"), "--config", "kS=Elsewhere.kS") == 2
        assert "no Elsewhere.kS" in capsys.readouterr().err
    assert not (tmp_path / "s.json").exists()


def test_dashboard_client_reads_status_and_opmodes(robot: EmulatedRobot) -> None:
    with Dashboard("127.0.0.1", robot.dashboard_port) as dash:
        assert dash.status()["batteryVoltage"] == robot.battery
        assert {m["name"] for m in dash.op_modes()} >= {OPMODE}
        assert dash.config() == robot.config
    with pytest.raises(RobotLinkError, match="not connected"):
        dash.stop_op_mode()


@pytest.mark.parametrize("inherited", ["default", "ignored"])
def test_ctrl_c_stops_the_robot_and_keeps_the_log(robot: EmulatedRobot, tmp_path: Path, inherited: str) -> None:
    """SIGINT stops the OpMode within 0.1 s, also in a process started with SIGINT ignored (a shell's
    background job: Python then leaves it ignored, and this test failed when the suite ran as one)."""
    import signal
    import subprocess
    import sys

    disposition = signal.SIG_IGN if inherited == "ignored" else signal.SIG_DFL
    log = tmp_path / "run.csv"
    proc = subprocess.Popen([sys.executable, "-m", "motorlab", "robot", "record", "--host", "127.0.0.1",
                             "--dashboard-port", str(robot.dashboard_port), "--opmode", OPMODE, "--seconds", "60",
                             "-o", str(log)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, disposition))
    try:
        deadline = time.monotonic() + 30
        while robot.status != "RUNNING" and time.monotonic() < deadline:
            time.sleep(0.01)
        time.sleep(0.5)
        assert robot.status == "RUNNING"
        pressed = time.monotonic()
        proc.send_signal(signal.SIGINT)
        while robot.active != STOP_TAG and time.monotonic() - pressed < 2.0:
            time.sleep(0.001)
        latency = time.monotonic() - pressed
        _, err = proc.communicate(timeout=20)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert robot.active == STOP_TAG
    assert latency < 0.1, latency
    assert proc.returncode == 0, err
    assert "Ctrl-C" in log.read_text()


def test_telemetry_without_numbers_is_one_line(tmp_path: Path) -> None:
    from motorlab.robot.record import Recording, write_log

    data = Recording("Words", rows=[(1000, 12.5, {"state": "ramping"}), (1010, 12.5, {"state": "done"})],
                     keys=["state"], skipped={"state": "ramping"}, stop_reason="1 s elapsed")
    with pytest.raises(RobotLinkError, match="no telemetry key of Words is a number"):
        write_log(data, tmp_path / "x.csv")
    with pytest.raises(RobotLinkError, match="sent no telemetry"):
        write_log(Recording("Quiet", stop_reason="1 s elapsed"), tmp_path / "x.csv")
    assert not (tmp_path / "x.csv").exists()


@pytest.mark.parametrize(("key", "column"), [
    ("voltage", "voltage_V"), ("Applied Voltage", "voltage_V"), ("voltage_V", "voltage_V"),
    ("battery voltage", "battery_V"), ("position", "position_counts"), ("encoder position", "position_counts"),
    ("position_rad", "position_rad"), ("velocity", "x_velocity"), ("loop time (ms)", "x_loop_time_ms"),
])
def test_telemetry_keys_become_columns(key: str, column: str) -> None:
    from motorlab.robot.record import column_for

    assert column_for(key) == column
