"""The app's robot link (motorlab.ui.robot) against the emulated robot: pull, record with Stop, send and restore."""

from __future__ import annotations

import copy
import json
import math
import re
import time
import warnings
from pathlib import Path

import pytest

with warnings.catch_warnings():  # starlette ≥ 0.48 prefers httpx2 for its test client; httpx works the same here
    warnings.simplefilter("ignore")
    from starlette.testclient import TestClient

from motorlab.robot.config import leaves
from motorlab.robot.dashboard import STOP_TAG
from motorlab.robot.emulator import EmulatedRobot, RobotFiles
from motorlab.ui.app import create_app

#: The emulated robot runs on the wall clock: make test runs these beside the others (the Makefile).
pytestmark = pytest.mark.realtime


def page_client() -> TestClient:
    """A client of a new app holding the robot token its page holds (as the page's own requests do)."""
    client = TestClient(create_app(host="127.0.0.1", port=8765), base_url="http://127.0.0.1:8765")
    token = re.search(r'name="motorlab-token" content="([^"]+)"', client.get("/").text)
    assert token
    client.headers["X-Motorlab-Token"] = token.group(1)
    return client


@pytest.fixture
def client() -> TestClient:
    return page_client()


def test_connect_to_the_robot_pulls_and_serves_the_files(client: TestClient, robot: EmulatedRobot,
                                                         robot_files: RobotFiles) -> None:
    answer = client.post("/api/robot/pull", data={"host": "127.0.0.1", "http-port": str(robot.http_port)})
    assert answer.status_code == 200, answer.text
    files = answer.json()["files"]
    assert {f["name"] for f in files} >= {robot_files.logs[0].name, robot_files.motorlab[0].name}
    served = {p.name: p for p in [*robot_files.logs, *robot_files.motorlab]}
    for kind in robot_files.tuning.values():
        served.update({p.name: p for p in kind})
    for f in files:
        assert client.get("/" + f["url"]).content == served[f["name"]].read_bytes()
    assert client.get("/api/robot/files/1/../../etc/passwd").status_code == 404
    refused = client.post("/api/robot/pull", data={"host": "127.0.0.1", "http-port": "1"})
    assert refused.status_code == 400
    assert "connection refused" in refused.json()["error"]


def test_record_live_and_stop(client: TestClient, robot: EmulatedRobot) -> None:
    port = str(robot.dashboard_port)
    listed = client.get("/api/robot/opmodes", params={"host": "127.0.0.1", "dashboard-port": port}).json()
    assert "motorlab: quasistatic ramp" in [m["name"] for m in listed["opmodes"]]
    assert client.get("/api/robot/record").json()["state"] == "idle"
    start = client.post("/api/robot/record/start", data={"host": "127.0.0.1", "dashboard-port": port,
                                                         "opmode": "motorlab: quasistatic ramp", "seconds": "20",
                                                         "cpr": "537.6"})
    assert start.status_code == 200, start.text
    deadline = time.monotonic() + 10
    live: dict = {}
    while time.monotonic() < deadline:
        live = client.get("/api/robot/record").json()
        if live["rows"] > 30:
            break
        time.sleep(0.1)
    assert live["state"] == "running"
    assert "voltage" in live["series"]
    assert len(live["time"]) == len(live["series"]["voltage"])
    assert client.post("/api/robot/record/start", data={"opmode": "x"}).status_code == 409  # one at a time
    pressed = time.monotonic()
    client.post("/api/robot/record/stop")
    while robot.active != STOP_TAG and time.monotonic() - pressed < 1:
        time.sleep(0.002)
    assert time.monotonic() - pressed < 0.1
    while client.get("/api/robot/record").json()["state"] != "stopped" and time.monotonic() < deadline:
        time.sleep(0.05)
    done = client.get("/api/robot/record").json()
    assert done["stop_reason"] == "stopped from the app"
    assert done["summary"]["columns"]["voltage"] == "voltage_V"
    log = client.get("/" + done["log"]).text
    assert "# cpr: 537.6" in log
    assert "time_s,battery_V,voltage_V,position_counts,x_velocity" in log


def test_send_to_the_robot_and_put_back(client: TestClient, robot: EmulatedRobot, tmp_path: Path) -> None:
    fit = json.dumps({"parameters": {"kS": {"value": 0.3, "unit": "V"}, "kV": {"value": 0.125, "unit": "V*s/rad"},
                                     "kA": {"value": 0.0124, "unit": "V*s^2/rad"}}}).encode()
    fields = {"host": "127.0.0.1", "dashboard-port": str(robot.dashboard_port), "target": "roadrunner", "cpr": "8192"}
    before = copy.deepcopy(robot.config)
    plan = client.post("/api/robot/push/plan", data=fields, files={"params": ("fit.json", fit)})
    assert plan.status_code == 200, plan.text
    assert [c["path"] for c in plan.json()["changes"]] == [f"MecanumDrive.PARAMS.{k}" for k in ("kS", "kV", "kA")]
    assert robot.config == before  # a plan writes nothing
    unconfirmed = client.post("/api/robot/push/apply", data=fields, files={"params": ("fit.json", fit)})
    assert unconfirmed.status_code == 400
    assert robot.config == before
    done = client.post("/api/robot/push/apply", data={**fields, "confirm": "yes"}, files={"params": ("fit.json", fit)})
    assert done.status_code == 200, done.text
    assert done.json()["verified"]
    assert leaves(robot.config)["MecanumDrive.PARAMS.kS"][1] == pytest.approx(0.3, rel=1e-9)
    back = client.post("/api/robot/push/restore", data=fields)
    assert back.status_code == 200, back.text
    assert robot.config == before


def test_stopped_is_said_only_once_the_log_is_written(robot: EmulatedRobot, monkeypatch: pytest.MonkeyPatch) -> None:
    """The recorder ends before its log is on disk: the page stops asking at "stopped", so the log must be there."""
    from motorlab.robot import record

    real = record.write_log

    def slow(*args: object, **kwargs: object) -> object:
        time.sleep(1.0)  # a loaded machine writing the log
        return real(*args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(record, "write_log", slow)
    client = page_client()
    fields = {"host": "127.0.0.1", "dashboard-port": str(robot.dashboard_port), "opmode": "motorlab: quasistatic ramp",
              "seconds": "20"}
    start = client.post("/api/robot/record/start", data=fields)
    assert start.status_code == 200, start.text
    deadline = time.monotonic() + 20
    while client.get("/api/robot/record").json()["rows"] < 10 and time.monotonic() < deadline:
        time.sleep(0.05)
    client.post("/api/robot/record/stop")
    seen = []
    while time.monotonic() < deadline:
        state = client.get("/api/robot/record").json()
        seen.append(state["state"])
        if state["state"] == "stopped":
            break
        time.sleep(0.05)
    assert state["state"] == "stopped"
    assert state["log"], seen  # said "stopped" with the log, never before it
    assert "saving the log" in seen


def _record(client: TestClient, robot: EmulatedRobot, opmode: str, seconds: float, **extra: str) -> dict:
    """Start ``opmode`` through the app, let it run ``seconds`` (the app stops it), and return the final state."""
    fields = {"host": "127.0.0.1", "dashboard-port": str(robot.dashboard_port), "opmode": opmode,
              "seconds": str(seconds), **extra}
    start = client.post("/api/robot/record/start", data=fields)
    assert start.status_code == 200, start.text
    deadline = time.monotonic() + seconds + 20
    while (state := client.get("/api/robot/record").json())["state"] != "stopped":
        assert time.monotonic() < deadline, state["state"]
        time.sleep(0.1)
    assert "error" not in state, state["error"]
    return dict(state)


def test_tune_and_prove_it(client: TestClient, robot: EmulatedRobot) -> None:
    """Issue 32, item 7, through the app's API: record a ramp, fit it, check the drive with the gains on the
    robot (the quickstart's zeros), push the fit's gains, check again: the emulated drive follows its gains,
    so the tracking error falls, and both runs are kept with the gains they ran with."""
    _record(client, robot, "motorlab: quasistatic ramp", 3, cpr="537.6")
    log = client.get("/api/robot/record/log").content
    fit = client.post("/api/analyze/feedforward", data={"cpr": "537.6"}, files={"file": ("run.csv", log)})
    assert fit.status_code == 200, fit.text
    kv = fit.json()["parameters"]["kV"]
    truth = robot.plant.kV * robot.plant.cpr / (2 * math.pi)  # V·s/rad
    assert abs(kv["value"] - truth) < 4 * kv["stderr"] + 1e-3 * truth
    assert client.get("/api/robot/checks").json()["before"] is None

    before = _record(client, robot, "ManualFeedforwardTuner", 3, check="before")
    assert before["check"] == "before"
    assert robot.active == STOP_TAG  # the app stopped it: the tuner runs until STOP
    fields = {"host": "127.0.0.1", "dashboard-port": str(robot.dashboard_port), "target": "roadrunner",
              "cpr": "537.6", "confirm": "yes"}
    pushed = client.post("/api/robot/push/apply", data=fields, files={"params": ("fit.json", fit.content)})
    assert pushed.status_code == 200, pushed.text
    _record(client, robot, "ManualFeedforwardTuner", 3, check="after")

    checks = client.get("/api/robot/checks").json()
    old, new = checks["before"], checks["after"]
    assert old["gains"] == {"kS": 0.0, "kV": 0.0, "kA": 0.0, "inPerTick": 1.0}  # what the run ran with
    assert new["gains"]["kV"] == pytest.approx(robot.plant.kV, rel=0.01)
    assert old["unit"] == new["unit"] == "ticks/s"
    assert len(new["time"]) == len(new["target"]) == len(new["measured"]) > 200
    assert max(new["target"]) == pytest.approx(robot.config["__value"]["MecanumDrive"]["__value"]["PARAMS"]
                                               ["__value"]["maxWheelVel"]["__value"], rel=0.05)
    assert old["rms"] > 10 * new["rms"]  # with zeros the drive never moves; with the fit it follows
    assert new["rms"] < 1.5  # ticks/s: the encoder's whole-tick velocity and one loop of lag
    assert "Before: RMS tracking error" in checks["words"]
    assert "times better" in checks["words"]
    # The restore puts the zeros back: the next check would track as badly as the first.
    assert client.post("/api/robot/push/restore", data=fields).status_code == 200
    assert leaves(robot.config)["MecanumDrive.PARAMS.kV"][1] == 0.0


def test_a_check_needs_a_verification_opmode(client: TestClient, robot: EmulatedRobot) -> None:
    state = client.post("/api/robot/record/start", data={"host": "127.0.0.1", "opmode": "x", "check": "later"})
    assert state.status_code == 400
    assert "before or after" in state.json()["error"]
    fields = {"host": "127.0.0.1", "dashboard-port": str(robot.dashboard_port), "opmode": "motorlab: quasistatic ramp",
              "seconds": "0.5", "check": "before"}
    assert client.post("/api/robot/record/start", data=fields).status_code == 200
    deadline = time.monotonic() + 20
    while (state := client.get("/api/robot/record").json())["state"] != "stopped":
        assert time.monotonic() < deadline
        time.sleep(0.1)
    assert "ManualFeedforwardTuner" in state["error"]
    assert client.get("/api/robot/checks").json()["before"] is None


def test_stop_works_whatever_started_the_opmode(robot: EmulatedRobot) -> None:
    """An OpMode started elsewhere (the Driver Station; a page of the app before it restarted): the page's Stop
    sends STOP_OP_MODE to the robot it names, with no token needed (a stale page must still stop the robot)."""
    from motorlab.robot.dashboard import Dashboard

    with Dashboard("127.0.0.1", robot.dashboard_port) as dash:
        dash.init_op_mode("motorlab: quasistatic ramp")
        dash.status()
        dash.start_op_mode()
        dash.status()
    assert robot.status == "RUNNING"
    fresh = TestClient(create_app(host="127.0.0.1", port=8765), base_url="http://127.0.0.1:8765")  # no token
    stop = fresh.post("/api/robot/record/stop", data={"host": "127.0.0.1", "dashboard-port": str(robot.dashboard_port)},
                      headers={"Origin": "http://127.0.0.1:8765"})
    assert stop.status_code == 200, stop.text
    assert stop.json()["sent"] == "STOP_OP_MODE"
    assert robot.active == STOP_TAG
    gone = fresh.post("/api/robot/record/stop", data={"host": "127.0.0.1", "dashboard-port": "1"})
    assert gone.status_code == 400
    assert "press STOP on the Driver Station" in gone.json()["error"]
