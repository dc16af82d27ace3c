"""The robot link in a real browser (Chromium), against the emulated robot on 127.0.0.1: connect and bring the
files home, start a run, see it live, press Stop, fit it. Controls are found by their visible words."""

from __future__ import annotations

import re
import time
from collections.abc import Iterator
from typing import Any

import pytest
import ui_browser as browser  # tests/ui/browser.py, loaded by conftest.py

from motorlab.rig.ftc import simulate_ramp
from motorlab.robot.config import leaves
from motorlab.robot.dashboard import STOP_TAG
from motorlab.robot.emulator import EmulatedRobot, RobotFiles

#: The emulated robot runs on the wall clock: make test runs these beside the others (the Makefile).
pytestmark = [browser.needs_browser, pytest.mark.realtime]


@pytest.fixture(scope="module")
def robot(tmp_path_factory: pytest.TempPathFactory) -> Iterator[EmulatedRobot]:
    folder = tmp_path_factory.mktemp("sdcard")
    ramp = folder / "1732521600000.json"
    simulate_ramp(ramp, kind="forward", seed=3)
    with EmulatedRobot(RobotFiles({"forward-ramp": [ramp]}), lifetime=300) as emulated:
        yield emulated


def test_connect_record_stop_and_fit(page: Any, robot: EmulatedRobot) -> None:
    browser.pull_from(page, robot)
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
    page.click("Open it in the mechanism task")
    page.wait_text("run.csv")


@pytest.fixture
def fresh_robot() -> Iterator[EmulatedRobot]:
    """An emulated robot with the quickstart's gains (kS = kV = kA = 0) for one journey."""
    with EmulatedRobot(lifetime=300) as emulated:
        yield emulated


def stop_in_view(page: Any) -> str:
    """The Stop bar's words, asserting its button is on screen (inside the window, not scrolled away)."""
    found = page.d.execute_script(
        "const b = [...document.querySelectorAll('button')].find(x => x.textContent === 'Stop the robot');"
        "const r = b.getBoundingClientRect();"
        "return [r.top >= 0 && r.bottom <= window.innerHeight && r.width > 0, b.parentElement.textContent];")
    assert found[0], "the Stop button is not in view"
    return str(found[1])


@pytest.mark.parametrize("size", [browser.LAPTOP, browser.PHONE], ids=["laptop", "phone"])
def test_tune_and_prove_it(page: Any, fresh_robot: EmulatedRobot, size: tuple[int, int]) -> None:
    """Issue 32, item 7, as a person does it: record a ramp, fit it, check the drive, send the gains, check it
    again, see both runs side by side, put the old values back; Stop in view throughout."""
    robot = fresh_robot
    name = "laptop" if size == browser.LAPTOP else "phone"
    page.open(size)
    page.click("Connect to the robot")
    page.click("Record a run")
    page.type("Robot address", "127.0.0.1")
    page.type("FTC Dashboard port", str(robot.dashboard_port))
    assert "Nothing runs on the robot" in stop_in_view(page)
    page.click("List the robot's OpModes")
    page.wait_text("OpModes; battery")
    page.choose("OpMode", "motorlab: quasistatic ramp (motorlab)")
    page.type("Stop after (s)", "2.5")
    page.type("Encoder counts per revolution", "537.6")
    page.click("Start the OpMode on the robot")
    page.wait(lambda: page.d.switch_to.alert, "the confirmation").accept()
    page.wait(lambda: robot.status == "RUNNING", "the ramp running")
    assert "motorlab: quasistatic ramp runs on the robot" in stop_in_view(page)
    page.wait_text("Stopped: 2.5 s elapsed")
    page.click("Fit this run")
    page.wait_text("The fit: kS =")
    page.check()
    page.shot(f"ui-robot-fit-{name}.png")

    page.click("Send these gains to the robot")
    page.wait_text("The fit of the run recorded at")
    page.type("Each check runs for (s)", "5.5")  # forwards and back: two legs of 2.6 s
    for label in ("before", "after"):
        if label == "after":
            page.click("Show old and new values")
            page.wait_text("MecanumDrive.PARAMS.kV")
            assert robot.received[-1]["type"] != "SAVE_CONFIG"  # showing writes nothing
            page.click("Write these values to the robot")
            page.wait_text("Written, read back and checked")
        started = len([m for m in robot.received if m["type"] == "START_OP_MODE"])
        page.click(f"Check {label} writing")
        page.wait(lambda: page.d.switch_to.alert, "the confirmation").accept()
        page.wait(lambda: robot.active == "ManualFeedforwardTuner", "the check running")
        assert "ManualFeedforwardTuner runs on the robot" in stop_in_view(page)
        page.wait_text(f"The check {label} writing is done", seconds=30)
        assert [m["type"] for m in robot.received].count("START_OP_MODE") == started + 1  # one click, one run
    page.wait_text("times better")
    words = page.words_of(".check-words")
    before, after = (float(x) for x in re.findall(r"RMS tracking error ([\d.]+) ticks/s", words))
    assert before > 10 * after, words
    assert len(page.d.find_elements("css selector", ".plot-area .main-svg")) >= 2  # both plots drawn
    assert leaves(robot.config)["MecanumDrive.PARAMS.kV"][1] == pytest.approx(robot.plant.kV, rel=0.01)
    page.shot(f"ui-robot-check-{name}.png")
    page.check()
    page.click("Put the old values back")
    page.wait_text("The old values are back on the robot")
    assert leaves(robot.config)["MecanumDrive.PARAMS.kV"][1] == 0.0
