"""The robot link in a real browser (Chromium), against the emulated robot on 127.0.0.1: connect and bring the
files home, start a run, see it live, press Stop, fit it. Controls are found by their visible words."""

from __future__ import annotations

import time
from collections.abc import Iterator
from typing import Any

import pytest
import ui_browser as browser  # tests/ui/browser.py, loaded by conftest.py

from motorlab.rig.ftc import simulate_ramp
from motorlab.robot.dashboard import STOP_TAG
from motorlab.robot.emulator import EmulatedRobot, RobotFiles

pytestmark = browser.needs_browser


@pytest.fixture(scope="module")
def robot(tmp_path_factory: pytest.TempPathFactory) -> Iterator[EmulatedRobot]:
    folder = tmp_path_factory.mktemp("sdcard")
    ramp = folder / "1732521600000.json"
    simulate_ramp(ramp, kind="forward", seed=3)
    with EmulatedRobot(RobotFiles({"forward-ramp": [ramp]}), lifetime=300) as emulated:
        yield emulated


def test_connect_record_stop_and_fit(page: Any, robot: EmulatedRobot) -> None:
    page.open(browser.LAPTOP)
    page.click("Connect to the robot")
    page.type("Robot address", "127.0.0.1")
    page.type("Web server port", str(robot.http_port))
    page.type("FTC Dashboard port", str(robot.dashboard_port))
    page.click("Connect to the robot")
    page.wait_text("1 file brought back")
    page.wait_text("Road Runner ramp log")
    page.check()
    page.shot("ui-robot-pull.png")

    page.click("Record a run")
    page.click("List the robot's OpModes")
    page.wait_text("OpModes; battery")
    page.choose("OpMode", "motorlab: quasistatic ramp (motorlab)")
    page.type("Encoder counts per revolution", "537.6")
    page.click("Start the OpMode on the robot")
    page.wait(lambda: page.d.switch_to.alert, "the confirmation").accept()
    page.wait(lambda: robot.status == "RUNNING", "the OpMode running")
    page.wait_text("packets")
    page.check()
    page.shot("ui-robot-record.png")
    page.click("Stop the robot")
    pressed = time.monotonic()
    page.wait(lambda: robot.active == STOP_TAG, "the robot stopped", seconds=5)
    assert time.monotonic() - pressed < 1.0  # the click's round trip through the browser and the app
    page.wait_text("Stopped: stopped from the app")
    page.click("Fit this run")
    page.wait_text("run.csv")
