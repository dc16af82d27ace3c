"""The other journeys of issue 22 in a real browser, as a student makes them (controls found by their words).

- an FTC spin-down, then the gains ask for the winding resistance, the LCR table is added there, and
  the FTC PIDF code is copied (K against the virtual dynamometer's truth);
- a session as a zip and as loose files → its results and report → gains (the session's catalogue motor gives the
  counts per revolution: never asked); a wrong file dropped on the finished session keeps its results;
- a WPILib SysId file → WPILib gains in the file's own unit (kV per rotation against the truth), on a phone;
- a dynamometer CSV with worded headers and one column it cannot name, answered in the column picker.
"""

from __future__ import annotations

import math
import re
import shutil
from pathlib import Path
from typing import Any

import ui_browser as browser  # tests/ui/browser.py, loaded by conftest.py

pytestmark = browser.needs_browser

_NUMBER = r"([0-9.]+(?: × 10[⁻⁰¹²³⁴⁵⁶⁷⁸⁹]+)?)"


def _value(text: str, row: str) -> tuple[float, float]:
    """Value and uncertainty of the table row starting with ``row`` ("Back-EMF constant K")."""
    found = re.search(re.escape(row) + r"\s+([0-9.]+) ± ([0-9.]+) (\S*)", text)
    assert found, f"no row {row!r} in {text[:2000]}"
    return float(found.group(1)), float(found.group(2))


def test_ftc_spindown_then_lcr_added_in_the_gains(page: Any, sim_session: Path, truth: dict[str, Any]) -> None:
    true = truth["runs"]["spindown.txt"]["params"]
    page.open(browser.LAPTOP)
    page.click("Tune a mechanism")
    page.upload("Choose or drop your files", sim_session / "A" / "spindown.txt")
    page.wait_text("FTC OpMode log")
    page.type("counts per revolution", "1120")
    page.type("Moment of inertia", f"{true['J']:.6g} kg*m^2")
    page.check()
    page.click("Run the fit")
    page.wait_text("Result from spindown.txt")
    k, k_err = _value(page.text(), "Back-EMF constant K")
    assert abs(k - true["K"]) < 4 * k_err + 0.0015  # the value is rounded to its uncertainty
    page.click("Gains")
    page.wait_text("The gains need a little more")  # never a dead end: what is missing, and where it comes from
    assert "Winding resistance R" in page.text()
    assert "LCR" in page.text()
    page.check()
    page.shot("ui-needs.png")
    page.upload("Add the file of that measurement", sim_session / "A" / "lcr.csv")
    page.wait_text("Gains for")
    page.click("PIDF")
    code = page.wait(lambda: [e.text for e in page.d.find_elements("css selector", "pre code")
                              if "setVelocityPIDFCoefficients" in e.text], "the FTC PIDF code")[0]
    page.d.execute_cdp_cmd("Browser.grantPermissions", {
        "origin": page.url, "permissions": ["clipboardReadWrite", "clipboardSanitizedWrite"]})
    page.click("Copy the code")
    page.wait(lambda: "Copied" in page.text(), "the copy button's answer")
    pasted = page.d.execute_async_script(
        "navigator.clipboard.readText().then(arguments[0], e => arguments[0](String(e)))")
    assert pasted.strip() == code.strip()
    page.check()


def test_session_zip_and_loose_files(page: Any, sim_session: Path, truth: dict[str, Any], tmp_path: Path) -> None:
    archive = Path(shutil.make_archive(str(tmp_path / "bench"), "zip", sim_session))
    page.open(browser.LAPTOP)
    page.click("Characterise motors on a bench")
    page.upload("Choose the session file", archive)
    page.click("Run the session")
    page.wait_text("Each unit's parameters", 180)
    assert "Fleet check" in page.text()
    page.wait_text("The printable report", 180)  # the table comes first, the report after it
    page.check()
    page.shot("ui-session.png")
    page.click("Gains")
    page.wait_text("The gains need a little more")  # the session gives K, R, L: the load's inertia is asked for
    assert "Moment of inertia J" in page.text()
    page.type("Type the moment of inertia", f"{truth['runs']['spindown.txt']['params']['J']:.6g}")
    page.click("Use this value")
    page.click("PIDF")
    # FTC's velocity PIDF counts encoder ticks: the session names its catalogue motor, whose encoder gives them
    page.wait_text("Encoder counts per revolution: 1120, of the session's motor")
    assert not page._visible("//label[contains(., 'counts per revolution')]")  # never asked
    page.wait(lambda: any("setVelocityPIDFCoefficients" in e.text for e in page.d.find_elements("css selector", "pre")),
              "the FTC PIDF code from the session")
    page.check()

    page.d.back()  # the session step, with its result kept; now the same session as loose files, on a phone
    page.wait_text("Each unit's parameters")
    # a wrong file dropped on the finished session: refused in words, the results kept
    page.upload("Choose the session file", sim_session / "A" / "lcr.csv")
    page.click("Run the session")
    page.wait_text("no session here")
    assert "the results below are from the session run before, kept as they were" in page.text()
    assert "Each unit's parameters" in page.text()
    assert "'session' field" not in page.text()  # no field that does not exist
    page.d.set_window_size(*browser.PHONE)
    page.check()
    loose = [sim_session / "session.toml", *sorted((sim_session / "A").iterdir())]
    page.upload("Choose the session file", *loose)
    page.wait_text("all chosen")
    page.click("Run the session")
    page.wait_text("Each unit's parameters", 180)
    # read in one step, found again if the view was redrawn in between (the report arriving after the table)
    table = page.wait(lambda: page.text(page.d.find_element("xpath", "//table[caption[contains(., \"Each unit's "
                                                             "parameters\")]]")), "the units' table")
    assert "ok" in table
    page.check()
    page.d.set_window_size(*browser.LAPTOP)


def test_sysid_to_wpilib_on_a_phone(page: Any, simulated_sysid: tuple[Path, dict[str, Any]]) -> None:
    path, expected = simulated_sysid
    page.open(browser.PHONE)
    page.click("Tune a mechanism")
    page.upload("Choose or drop your files", path)
    page.wait_text("WPILib SysId file")
    page.check()
    page.click("Run the fit")
    page.wait_text("Result from sysid.json")
    page.check()
    page.click("Gains")
    page.click("WPILib")
    page.wait_text("Gains for WPILib")
    found = re.search(r"kV\s+" + _NUMBER + r" V·s/rot", page.text())  # in the file's own unit (Rotations)
    assert found, page.text()
    per_rotation = expected["kV"] * 2 * math.pi  # the truth is per radian
    assert abs(float(found.group(1)) - per_rotation) / per_rotation < 0.03
    page.check()


def test_dynamometer_csv_with_worded_headers(page: Any, tmp_path: Path) -> None:
    rows = ["Amps,Torque (N·m),Load"]  # no time, no voltage: a lever on a scale (a timed run is a stall run)
    for k in range(20):
        current = 0.5 + 0.15 * k
        rows.append(f"{current:.3f},{0.35 * current - 0.02 + 0.001 * (-1) ** k:.5f},{k}")
    (tmp_path / "dyno.csv").write_text("\n".join(rows) + "\n", encoding="utf-8")
    page.open(browser.LAPTOP)
    page.click("Analyse one experiment")
    page.upload("Choose or drop your files", tmp_path / "dyno.csv")
    page.wait_text("does not know what the column “Load” holds")
    page.check()
    page.choose("Which quantity is the column", "nothing to read (leave it out)")
    page.click("Read the file again")
    page.wait_text("Proposed: Stall torque on a lever")
    page.click("Run the fit")
    page.wait_text("Result from dyno.csv")
    k, k_err = _value(page.text(), "Back-EMF constant K")
    assert abs(k - 0.35) < 4 * k_err + 0.001
    page.check()

    # points picked on the plot with the box tool are left out and the fit runs again
    from selenium.webdriver.common.action_chains import ActionChains

    page.d.find_element("css selector", ".plots .modebar-btn[data-title='Box Select']").click()
    area = page.d.find_element("css selector", ".plots .nsewdrag")
    width, height = area.size["width"], area.size["height"]
    ActionChains(page.d).move_to_element_with_offset(area, width // 6, -height // 2 + 3).click_and_hold() \
        .move_by_offset(width // 3 - 6, height - 6).release().perform()
    page.click("selected point")
    page.wait_text("left out)")
    k2, k2_err = _value(page.text(), "Back-EMF constant K")
    assert abs(k2 - 0.35) < 4 * k2_err + 0.001
    assert (tmp_path / "dyno.csv").read_text(encoding="utf-8").count("\n") == 21  # the file given is kept whole


def test_a_running_session_shows_its_units_then_its_table_before_its_report(page: Any, tmp_path: Path) -> None:
    from motorlab.session.simulated import write_simulated_session

    folder = tmp_path / "bench"
    write_simulated_session("neverest40", out_dir=folder, units=2, seed=6, experiments=("lcr", "spindown", "identify"))
    archive = Path(shutil.make_archive(str(tmp_path / "bench"), "zip", folder))
    page.open(browser.LAPTOP)
    page.click("Characterise motors on a bench")
    page.upload("Choose the session file", archive)
    page.watch_status()  # the steps are seen however fast the machine ends them
    page.click("Run the session")
    # The person sees how many units are done of how many, and which experiment runs now, on which unit (the
    # steps reach the page at most every 0.2 s, progress.JsonLines: a fast machine may run an experiment in less;
    # tests/session/test_characterize.py holds every step to its words).
    running = re.compile(r"Characterising the units: [01] of 2 units done( \(unit [AB]: (lcr|spindown|identify)\)|"
                         r" \(unit A done\)|$)")
    page.shown(running, "the units done and the experiment running", 120)
    page.shot("ui-session-running.png")
    # Results first: the table while the report's figures are still being drawn, then the report.
    page.shown(re.compile("The report with its figures is being drawn"), "the table before the report", 180)
    page.wait_text("Each unit's parameters", 180)
    page.shown(re.compile(r"Drawing the report: \d of \d sections done"), "the report's sections counted", 60)
    page.shot("ui-session-table-first.png")
    page.check()
    page.wait_text("The printable report", 180)
    assert "being drawn" not in page.text()
    page.check()
    # at 1366 px every column of the units' table (R, L, η …) is within its box, none cut off
    right, box, columns = page.d.execute_script(
        "const t = document.querySelector('#session-table'); const b = t.closest('.scroll').getBoundingClientRect();"
        "const heads = [...t.querySelectorAll('thead th')].map(h => h.getBoundingClientRect().right);"
        "return [Math.max(...heads), b.right, heads.length]")
    assert columns >= 6
    assert right <= box + 1, (right, box)
    page.shot("ui-session-wide.png")
    # on a phone the embedded report is fitted to the width: nothing scrolls sideways, in the page or the report
    page.d.set_window_size(*browser.PHONE)
    page.click("The printable report")
    page.d.switch_to.frame(page.d.find_element("css selector", "details.report iframe"))
    inside = page.d.execute_script("return [document.documentElement.scrollWidth, window.innerWidth]")
    page.d.switch_to.default_content()
    assert inside[0] <= inside[1] + 1, inside
    page.check()
    page.shot("ui-report-phone.png")
    page.d.set_window_size(*browser.LAPTOP)


def test_typing_goes_on_while_a_result_arrives(page: Any, sim_session: Path) -> None:
    """A fit's result arriving redraws the view: the field being typed in keeps its focus, caret and text, an
    opened section stays open."""
    page.open(browser.LAPTOP)
    page.click("Tune a mechanism")
    page.upload("Choose or drop your files", sim_session / "A" / "spindown.txt")
    page.wait_text("FTC OpMode log")
    page.type("counts per revolution", "1120")
    # The fit's answer is held in the page until the first keystrokes are in (so the redraw falls mid-typing).
    page.d.execute_script("""
        const real = window.fetch;
        window.__hold = new Promise((resolve) => { window.__release = resolve; });
        window.fetch = async (...args) => {
          const answer = await real(...args);
          if (String(args[0]).includes("api/analyze")) await window.__hold;
          return answer;
        };""")
    page.click("Run the fit")
    page.click("Gains")
    page.click("More settings")  # a section opened before the redraw stays open
    box = page.field("Type the winding resistance")
    box.click()
    box.send_keys("1.2")
    box.send_keys("\ue012")  # the caret one to the left: 1.|2
    assert "spindown.txt (" not in page.text()  # no result yet
    page.d.execute_script("window.__release()")
    page.wait_text("spindown.txt (")  # the result arrived: the view was drawn again
    assert page.d.execute_script(
        "return [...document.querySelectorAll('details')].some(d => d.open && d.textContent.includes('More settings'))")
    typing = page.d.switch_to.active_element
    assert "winding resistance" in page.d.execute_script("return arguments[0].labels[0].textContent", typing).lower()
    assert typing.get_attribute("value") == "1.2"
    typing.send_keys("5")  # typed where the caret was
    assert typing.get_attribute("value") == "1.52"
    page.click("Use this value")
    page.wait(lambda: not page._visible("//label[contains(., 'Type the winding resistance')]"),
              "the resistance taken (no longer asked for)")
    page.check()
