"""Issue 31's last defects, in a real browser, controls found by their visible words only.

* A team's drivetrain SysId file recorded in Feet: its WPILib gains are per foot (V·s/ft), never per metre.
* "Send and check": every number of the old-and-new table rounded to its uncertainty, with its unit.
* "Bring the robot's files": a file the pull could not bring is listed with its reason and what to do, and the
  files it brought are still shown.
"""

from __future__ import annotations

import json
import re
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import ui_browser as browser  # tests/ui/browser.py, loaded by conftest.py

from motorlab.rig.ftc import simulate_ramp
from motorlab.robot.emulator import EmulatedRobot, RobotFiles

pytestmark = browser.needs_browser

#: A team's real drivetrain SysId file in Feet (unitsPerRotation 1.047 ft), read in place from ../shared/data/real.
FEET = "sysid/t2168_drivetrain_0311.json"
_SUPERSCRIPT = str.maketrans("⁻⁰¹²³⁴⁵⁶⁷⁸⁹", "-0123456789")


def _number(text: str) -> float:
    """ "2.219 ± 0.012", "(3.087 ± 0.011) × 10⁻⁴" or "0.676" as a float (the value, not its uncertainty)."""
    found = re.match(r"\(?(-?[0-9.]+)(?: ± [0-9.]+\))?(?: × 10([⁻⁰-⁹¹²³]+))?", text.strip())
    assert found, text
    return float(found.group(1)) * 10.0 ** (int(found.group(2).translate(_SUPERSCRIPT)) if found.group(2) else 0)


def test_a_feet_file_gives_wpilib_gains_per_foot(page: Any, real_dir: Path) -> None:
    feet = real_dir / FEET
    page.open(browser.LAPTOP)
    page.click("Tune a mechanism")
    page.upload("Choose or drop your files", feet)
    page.wait_text("Fitted in the file's own units (Feet")
    page.click("Run the fit")
    page.wait_text(f"Result from {feet.name}", 180)
    fitted = re.search(r"Velocity gain kV\s+(.+?) V·s/m", page.text())  # the fit itself is SI
    assert fitted, page.text()[:3000]
    kv_per_metre = _number(fitted.group(1))
    page.click("Gains for your code")
    page.wait_text("Gains for WPILib")
    row = page.wait(lambda: [r.text for r in page.d.find_elements("css selector", "#gains-table tr")
                             if re.search(r"\bkV\s", r.text)], "the kV row")[0]
    value, unit = re.search(r"\bkV\s+(\S+)\s+(\S+)$", row).groups()  # type: ignore[union-attr]
    assert unit == "V·s/ft", row  # the file's own length unit, never per metre
    assert float(value) == pytest.approx(kv_per_metre * 0.3048, rel=0.01), (row, kv_per_metre)
    from selenium.webdriver.support.ui import Select

    assert Select(page.field("Length unit")).first_selected_option.text.startswith("feet")
    assert "the file's own unit is feet" in page.text()
    assert "not used: the file logs distances" in page.text()  # no wheel radius turns feet into anything
    code = page.words_of("details.command code", hidden=True)
    assert "--units=ft" in code, code
    assert "wheel-radius" not in code, code
    page.check()
    page.shot("feet-gains-laptop.png")
    address = page.d.current_url  # the same gains opened on a phone, by their address
    page.d.set_window_size(*browser.PHONE)
    page.d.get(address)
    page.wait(lambda: page.d.find_element("tag name", "body").get_attribute("data-ready") == "true", "the page")
    page.wait_text("Gains for WPILib")
    assert re.search(r"\bkV\s+\S+\s+V·s/ft", page.words_of("#gains-table"))
    page.wait(lambda: page.d.execute_script("return document.documentElement.scrollWidth <= window.innerWidth"),
              "the figures drawn to the phone's width")  # Plotly follows its box's size a moment after drawing
    page.check()
    page.shot("feet-gains-phone.png")


@pytest.fixture(scope="module")
def robot(tmp_path_factory: pytest.TempPathFactory) -> Iterator[EmulatedRobot]:
    """An emulated robot with a forward ramp, and a FlightRecorder log whose name Road Runner's file server
    cannot be asked for (a space in it): the pull brings the ramp and names the log as not brought back."""
    folder = tmp_path_factory.mktemp("sdcard")
    ramp = folder / "1732521600000.json"
    simulate_ramp(ramp, kind="forward", seed=3)
    odd = folder / "2026_11_25__10_42_00_000__Two Words.log"
    odd.write_bytes(bytes(range(256)) * 4)
    with EmulatedRobot(RobotFiles({"forward-ramp": [ramp]}, [odd]), lifetime=300) as emulated:
        yield emulated


def test_the_pull_lists_what_it_could_not_bring(page: Any, robot: EmulatedRobot) -> None:
    browser.pull_from(page, robot)
    page.wait_text("1 file brought back. 1 could not be brought back")
    page.wait_text("Road Runner ramp log")  # the file it brought, still shown
    box = page.words_of("section.not-pulled")
    assert "Not brought back (1)" in box
    assert "2026_11_25__10_42_00_000__Two Words.log" in box
    assert "its name holds a space, & or =, which Road Runner's file server cannot be asked for: not pulled" in box
    assert "What to do: rename it on the robot or copy it by USB." in box
    page.check()
    page.shot("robot-pull-partial.png")


def test_send_and_check_rounds_every_number_to_its_uncertainty(page: Any, robot: EmulatedRobot,
                                                               tmp_path: Path) -> None:
    """A fit's kS, kV, kA with their standard errors → Road Runner's fields in ticks: each new value to two
    significant digits of its standard error, with its unit; the robot's values with their unit."""
    fit = tmp_path / "fit.json"
    fit.write_text(json.dumps({"experiment": "feedforward", "parameters": {
        "kS": {"value": 0.123456789, "stderr": 0.0041234, "unit": "V"},
        "kV": {"value": 0.40251234567, "stderr": 0.0012345678, "unit": "V*s/rad"},
        "kA": {"value": 0.0523456789, "stderr": 0.00234567, "unit": "V*s^2/rad"}}}))
    for size in (browser.LAPTOP, browser.PHONE):
        page.open(size)
        page.click("Connect to the robot")
        page.click("Send and check")
        page.type("Robot address", "127.0.0.1")
        page.type("FTC Dashboard port", str(robot.dashboard_port))
        page.upload("The fit (a motorlab result file, .json)", fit)
        page.type("Encoder counts per revolution", "8192")
        page.click("Show old and new values")
        page.wait_text("MecanumDrive.PARAMS.kV")
        rows = {r.find_elements("css selector", "td")[0].text: [c.text for c in r.find_elements("css selector", "td")]
                for r in page.d.find_elements("css selector", "main table tbody tr")}
        # kV per tick = 0.40251234567 × 2π/8192 ± 0.0012345678 × 2π/8192: (3.087 ± 0.0095) × 10⁻⁴ V·s/tick
        assert rows["MecanumDrive.PARAMS.kV"][2] == "(3.0872 ± 0.0095) × 10⁻⁴ V·s/tick", rows
        assert rows["MecanumDrive.PARAMS.kS"][2] == "123.5 ± 4.1 mV", rows
        assert rows["MecanumDrive.PARAMS.kA"][2] == "(4.01 ± 0.18) × 10⁻⁵ V·s²/tick", rows
        for _, old, _new in rows.values():  # the robot's own values: a number and the unit
            assert re.fullmatch(r"-?[0-9.]+(?: × 10[⁻⁰-⁹¹²³]+)? m?V(·s²?/tick)?", old), old
        page.check()
        page.shot(f"robot-send-rounded-{'laptop' if size == browser.LAPTOP else 'phone'}.png")
