"""The app in a real browser (Debian's Chromium, headless, driven by Selenium) as a student uses it.

The Road Runner journey of issue 22: a ramp file with dead wheels (8192 counts/rev) is recognised
and proposed on upload without any option; the student types 8192 in the field labelled with
"counts per revolution", runs the fit, follows "Gains", picks "Road Runner", and the code to paste
holds kV per tick within 3 % of the virtual dynamometer's truth. At 1366×768 and at 390×844; every
view is checked for flags outside code boxes, unnamed fields and sideways scrolling; a reload
restores the results; the back button walks the steps; nothing is loaded from another host.
Controls are found by their visible words only (tests/ui/browser.py).
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import pytest
import ui_browser as browser  # tests/ui/browser.py, loaded by conftest.py

pytestmark = browser.needs_browser


@pytest.mark.parametrize("size", [browser.LAPTOP, browser.PHONE], ids=["laptop", "phone"])
def test_road_runner_ramp_to_gains(page: Any, ramp: tuple[Path, float], size: tuple[int, int]) -> None:
    path, true_kv = ramp
    laptop = size == browser.LAPTOP
    page.open(size)
    page.check()
    if laptop:
        page.shot("ui-tasks.png")
    if laptop:  # from the task, as the first screen asks
        page.click("Tune a Road Runner or Pedro Pathing drive")
        page.upload("Choose or drop your files", path)
    else:  # from the file: the page recognises it and opens its task
        page.upload("Choose or drop any log", path)
    page.wait_text("Road Runner ramp log")
    page.wait_text("Proposed: Road Runner feedforward fit")  # on upload, before any option was given
    options = page.field("What this file measures").find_elements("tag name", "option")
    bare = [o.get_attribute("value") for o in options if o.text.strip() == o.get_attribute("value")]
    assert not bare, f"experiments named by their key, not in words: {bare}"  # (the stall runs read "stall")
    page.type("counts per revolution", "8192")
    page.check()
    page.click("Run the fit")
    page.wait_text("Result from ramp.json")
    assert "Velocity gain kV" in page.text()  # the parameter in words, with its symbol
    assert "?" not in page.text().split("Result from ramp.json")[1].split("The same as a command")[0]
    page.check()
    if laptop:
        page.shot("ui-fit.png")
    page.click("Gains")
    page.click("Road Runner")
    kv = browser.kv_per_tick(page)
    assert abs(kv - true_kv) / true_kv < 0.03, (kv, true_kv)
    page.wait(lambda: len(page.d.find_elements("css selector", ".plots .main-svg")) >= 2, "the step and profile plots")
    page.check()
    # the counts per revolution typed once is the one the gains use, and is shown there
    assert page.field("counts per revolution").get_attribute("value") == "8192"
    if laptop:
        page.shot("ui-gains.png")
    else:
        page.shot("ui-gains-phone.png")
        sizes = page.d.execute_script("return [...document.querySelectorAll('.plots svg text')]"
                                      ".map(t => parseFloat(getComputedStyle(t).fontSize))")
        assert sizes
        assert min(sizes) >= 10, sizes


def test_reload_back_and_offline(page: Any, ramp: tuple[Path, float]) -> None:
    """After the journey above (made again here: xdist may run this test in another worker, on a browser of its
    own): a reload keeps the results, back/forward walk the steps, no foreign host."""
    page.open(browser.LAPTOP)
    page.click("Tune a Road Runner or Pedro Pathing drive")
    page.upload("Choose or drop your files", ramp[0])
    page.type("counts per revolution", "8192")
    page.click("Run the fit")
    page.wait_text("Result from ramp.json")
    page.click("Gains")
    page.click("Road Runner")
    browser.kv_per_tick(page)
    page.d.refresh()
    page.wait(lambda: page.d.find_element("tag name", "body").get_attribute("data-ready") == "true", "the page")
    assert abs(browser.kv_per_tick(page) - ramp[1]) / ramp[1] < 0.03  # the gains view came back with its result
    page.d.back()
    page.wait_text("Result from ramp.json")  # the fit step, with its result
    page.d.forward()
    page.wait_text("Gains for Road Runner")
    loaded = page.d.execute_script(
        "return [location.href, ...performance.getEntriesByType('resource').map(e => e.name)]")
    foreign = [url for url in loaded if not url.startswith((page.url, "blob:", "data:"))]
    assert not foreign, foreign
    assert any(url.endswith("/static/plotly.min.js") for url in loaded)


def _lift_dead_wheels(path: Path, out: Path, t1: float, t2: float) -> None:
    """The ramp with its dead wheels off the floor from t1 to t2 s (tests/test_timespans.py does the same)."""
    doc = json.loads(path.read_text())
    for key in ("forwardEncPositions", "forwardEncVels"):
        for enc in doc[key]:
            t = [float(x) for x in enc["times"]]
            i1 = next(k for k, x in enumerate(t) if x >= t1)
            i2 = next(k for k, x in enumerate(t) if x >= t2)
            v = list(enc["values"])
            if key == "forwardEncPositions":
                missed = v[i2] - v[i1]
                enc["values"] = v[:i1] + [v[i1]] * (i2 - i1) + [x - missed for x in v[i2:]]
            else:
                enc["values"] = v[:i1] + [0] * (i2 - i1) + v[i2:]
    out.write_text(json.dumps(doc))


def _kv(page: Any) -> tuple[float, float]:
    """kV and its uncertainty as the result table says them ("0.1253 ± 0.0000x V·s/rad", "(4.0 ± 2.7) × 10⁻⁷ …")."""
    found = re.search(r"Velocity gain kV\s+\(?(-?[0-9.]+) ± ([0-9.]+)\)?(?: × 10([⁻⁰-⁹¹²³]+))? V·s/rad", page.text())
    assert found, page.text()[:3000]
    power = 0
    if found.group(3):
        power = int(found.group(3).translate(str.maketrans("⁻⁰¹²³⁴⁵⁶⁷⁸⁹", "-0123456789")))
    return float(found.group(1)) * 10.0**power, float(found.group(2)) * 10.0**power


def _box_select(page: Any, x0: float, x1: float) -> None:
    """Drag the box tool over x0..x1 (in the first plot's x axis) across the whole height, as a hand does."""
    from selenium.webdriver.common.action_chains import ActionChains

    page.d.find_element("css selector", ".plots .modebar-btn[data-title='Box Select']").click()
    area = page.d.find_element("css selector", ".plots .nsewdrag")
    left, right = page.d.execute_script(
        "const gd = document.querySelector('.plots .js-plotly-plot'); const ax = gd._fullLayout.xaxis;"
        "return [ax.l2p(arguments[0]), ax.l2p(arguments[1])];", x0, x1)
    width, height = area.size["width"], area.size["height"]
    ActionChains(page.d).move_to_element_with_offset(area, int(left - width / 2), -height // 2 + 2).click_and_hold() \
        .move_by_offset(int(right - left), height - 4).release().perform()


def _on_a_phone(page: Any, shot: str) -> None:
    """The same view at 390 px: checked and photographed, then back to the laptop."""
    page.d.set_window_size(*browser.PHONE)
    page.wait(lambda: page.d.execute_script("return document.documentElement.scrollWidth <= window.innerWidth"),
              "the plots redrawn to the phone's width")  # Plotly follows the window's size a moment later
    page.check()
    page.shot(shot)
    page.d.set_window_size(*browser.LAPTOP)


def test_a_stretch_of_a_long_log_left_out_on_the_plot(page: Any, ramp: tuple[Path, float], tmp_path: Path) -> None:
    """A ramp whose dead wheels lifted for a second: selected on the plot, left out, fitted again, put back."""
    path, _ = ramp
    true_kv = json.loads((path.parent / "truth.json").read_text())["runs"]["ramp.json"]["expected"]["kV"]
    _lift_dead_wheels(path, tmp_path / "bumpy.json", 2.5, 3.5)
    page.open(browser.LAPTOP)
    page.click("Tune a Road Runner or Pedro Pathing drive")
    page.upload("Choose or drop your files", tmp_path / "bumpy.json")
    page.wait_text("Proposed: Road Runner feedforward fit")
    page.type("counts per revolution", "8192")
    page.click("Run the fit")
    page.wait_text("Result from bumpy.json")
    if "Velocity gain kV not determined" not in page.text():  # the stretch ruins the fit
        kv, err = _kv(page)
        assert abs(kv - true_kv) > 3 * err + 0.001
    assert "To leave a stretch of the log out" in page.text()
    page.wait(lambda: page.d.find_elements("css selector", ".plots .nsewdrag"), "the plots")
    _box_select(page, 2.45, 3.55)
    page.wait_text("and fit again")
    offer = next(b.text for b in page.d.find_elements("tag name", "button") if "and fit again" in b.text)
    found = re.fullmatch(r"Leave out ([0-9.]+)–([0-9.]+) s and fit again", offer)
    assert found, offer
    start, end = float(found.group(1)), float(found.group(2))
    assert 2.3 < start < 2.5 < 3.5 < end < 3.7
    flag = f"--exclude={found.group(1)}:{found.group(2)}"
    assert any(flag in e.text for e in page.d.find_elements("css selector", "pre code")), flag  # the CLI form
    page.check()
    page.shot("ui-leave-out.png")
    _on_a_phone(page, "ui-leave-out-phone.png")
    page.click("and fit again")
    page.wait_text("time span left out)")
    said = page.words_of(".left-out")
    assert re.match(r"1 time span left out, [0-9.]+ s, \d+ samples", said), said
    kv, err = _kv(page)
    assert abs(kv - true_kv) < 3 * err + 0.0005, (kv, err, true_kv)
    page.wait(lambda: page.d.execute_script(  # the span is shaded on the plots against the log's time
        "return [...document.querySelectorAll('.plots svg text')].some(t => t.textContent === 'left out')"),
        "the span shaded on the plots")
    assert any(flag in e.get_attribute("textContent") for e in page.d.find_elements("css selector", "pre code"))
    page.check()
    page.shot("ui-left-out.png")
    _on_a_phone(page, "ui-left-out-phone.png")
    page.click("Put them back")
    page.wait(lambda: "left out)" not in page.text() and "Result from bumpy.json" in page.text(),
              "the whole log fitted again")
    codes = page.d.find_elements("css selector", "pre code")
    assert not any("--exclude" in e.get_attribute("textContent") for e in codes)
    assert "Velocity gain kV not determined" in page.text() or abs(_kv(page)[0] - true_kv) > 0.001
