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
import math
import re
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
import ui_browser as browser  # tests/ui/browser.py, loaded by conftest.py

pytestmark = browser.needs_browser


@pytest.fixture(scope="module")
def ramp(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, float]:
    """A simulated forward ramp (8192-count dead wheels) and its true kV per tick."""
    folder = tmp_path_factory.mktemp("ramp")
    subprocess.run([sys.executable, "-m", "motorlab", "simulate", "roadrunner-ramp", "-o", str(folder / "ramp.json")],
                   check=True, capture_output=True)
    truth = json.loads((folder / "truth.json").read_text())["runs"]["ramp.json"]["expected"]
    return folder / "ramp.json", truth["kV"] * 2 * math.pi / truth["cpr"]


def _kv_per_tick(page: Any) -> float:
    code = page.wait(lambda: [e.text for e in page.d.find_elements("css selector", "pre code") if "kV =" in e.text],
                     "the code to paste")[0]
    found = re.search(r"kV = ([0-9.eE+-]+);\s*// V\*s/tick", code)
    assert found, code
    return float(found.group(1))


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
    kv = _kv_per_tick(page)
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
    """After the journey above: a reload keeps the results, back/forward walk the steps, no foreign host."""
    page.d.refresh()
    page.wait(lambda: page.d.find_element("tag name", "body").get_attribute("data-ready") == "true", "the page")
    assert abs(_kv_per_tick(page) - ramp[1]) / ramp[1] < 0.03  # the gains view came back with its result
    page.d.back()
    page.wait_text("Result from ramp.json")  # the fit step, with its result
    page.d.forward()
    page.wait_text("Gains for Road Runner")
    loaded = page.d.execute_script(
        "return [location.href, ...performance.getEntriesByType('resource').map(e => e.name)]")
    foreign = [url for url in loaded if not url.startswith((page.url, "blob:", "data:"))]
    assert not foreign, foreign
    assert any(url.endswith("/static/plotly.min.js") for url in loaded)
