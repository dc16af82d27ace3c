"""Dynamometer exports are what they are on upload (issue 31, point 5).

VEX's locked-rotor runs (``<motor>-locked-rotor-data-<V>v-….csv``: Time, Amps, Volts, Torque) are proposed as
the stall analysis and a motor's runs as one joint fit; its motor curve (``…-motor-curve-data-….csv``: Speed
(RPM), Torque, Current, …) as the curve analysis; both in the "characterise motors on a bench" task, never
as a lever arm on a scale. The app's joint fit is the CLI's (``motorlab analyze stall A.csv B.csv``), and
the page sets each run's own answer beside the joint one. The real exports are read where they are
(../shared/data/real/dyno).
"""

from __future__ import annotations

import contextlib
import io
import shutil
from pathlib import Path
from typing import Any

import httpx
import pytest
import ui_browser as browser  # tests/ui/browser.py, loaded by conftest.py

from motorlab import cli
from motorlab.proposal import propose_dynamometer, run_group
from motorlab.ui.worker import detect

#: Two short locked-rotor runs of one motor (34 and 12 healthy samples: a joint fit takes about a second).
RUNS = ("775pro-locked-rotor-data-8v-20151209.csv", "775pro-locked-rotor-data-10v-20151209.csv")
CURVE = "775pro-motor-curve-data-20151208.csv"


def test_every_vex_export_is_proposed_as_what_it_is(dyno_dir: Path) -> None:
    locked = sorted(dyno_dir.glob("*-locked-rotor-data-*v-*.csv"))
    curves = sorted(dyno_dir.glob("*-motor-curve-data-*.csv"))
    assert len(locked) >= 30
    assert len(curves) == 6
    found = detect(["--", *map(str, locked + curves)])
    for entry in found:
        assert "error" not in entry, entry
        want = "curve" if "motor-curve" in entry["file"] else "stall"
        assert (entry["experiment"], entry["task"]) == (want, "bench"), entry["file"]
    groups = {e["group"] for e in found if e["experiment"] == "stall"}
    assert groups == {"stall:775pro", "stall:neverest", "stall:am-9015", "stall:bag", "stall:cim", "stall:mini-cim"}
    assert all(e["group"] is None for e in found if e["experiment"] == "curve")  # one fit per curve


def test_a_lever_arm_table_is_still_the_torque_analysis() -> None:
    """current and scale readings, no time, no voltage: the lever arm on a scale, not a stall run."""
    assert propose_dynamometer(["current", "torque"], timed=False) is None
    assert propose_dynamometer(["current", "mass"], timed=True) is None
    assert propose_dynamometer(["time", "current", "voltage", "torque", "speed"], timed=True) is None
    assert run_group("stall", "runs/a.csv") == run_group("stall", "b.csv") == "stall"  # other names: one group
    assert run_group("curve", "x.csv") is None


def test_the_apps_joint_stall_fit_is_the_cli_s(server: Any, dyno_dir: Path, tmp_path: Path) -> None:
    with contextlib.ExitStack() as stack:
        files = [("file", (name, stack.enter_context(open(dyno_dir / name, "rb")))) for name in RUNS]
        response = httpx.post(f"{server.url}/api/analyze/stall", files=files, timeout=120)
    assert response.status_code == 200, response.text
    for name in RUNS:
        shutil.copy(dyno_dir / name, tmp_path / name)
    out = io.StringIO()
    with contextlib.chdir(tmp_path), contextlib.redirect_stdout(out):
        assert cli.main(["analyze", "stall", *RUNS, "--json"]) == 0
    out = out.getvalue()
    assert response.text == out  # byte for byte: the same joint fit of the same files
    assert [row["file"] for row in response.json()["details"]["runs"]] == list(RUNS)


def _drop(page: Any, words: str, paths: list[Path]) -> None:
    """Drop ``paths`` together on the box whose label holds ``words`` (a drop event carrying the files)."""
    box = page.field(words).find_element("xpath", "./ancestor::label")
    page.d.execute_script("""
      const [box, files] = arguments;
      const dt = new DataTransfer();
      for (const [name, bytes] of files) dt.items.add(new File([new Uint8Array(bytes)], name, { type: "text/csv" }));
      box.dispatchEvent(new DragEvent("drop", { dataTransfer: dt, bubbles: true, cancelable: true }));
    """, box, [[p.name, list(p.read_bytes())] for p in paths])


def _card(page: Any, title: str) -> Any:
    """The fit card whose heading holds ``title`` (found by its words)."""
    xpath = f"//section[.//h3[contains(normalize-space(.), {title!r})]]"
    shown = lambda: [e for e in page.d.find_elements("xpath", xpath) if e.is_displayed()]  # noqa: E731
    found = page.wait(shown, f"the card {title!r}")
    return found[0]


@browser.needs_browser
@pytest.mark.parametrize("size", [browser.LAPTOP, browser.PHONE], ids=["laptop", "phone"])
def test_runs_dropped_on_the_first_screen_fit_together(page: Any, dyno_dir: Path, size: tuple[int, int]) -> None:
    page.open(size)
    paths = [dyno_dir / name for name in (*RUNS, CURVE)]
    if size == browser.LAPTOP:
        page.upload("Choose or drop any log", *paths)
    else:  # dropped together on the box, as a person drags them from a folder
        _drop(page, "Choose or drop any log", paths)
    page.wait_text("Proposed: Locked rotor (stall) runs and heat")
    page.wait_text("Proposed: Motor curve")
    proposed = [line for line in page.text().splitlines() if line.startswith("Proposed:")]
    assert len(proposed) == 3, proposed
    assert not any("lever" in line.lower() for line in proposed), proposed
    assert page.d.execute_script("return document.body.dataset.view") == "bench/fit"
    stall = _card(page, "Locked rotor")
    assert f"From {RUNS[0]}, {RUNS[1]}" in stall.text  # one joint fit of the motor's runs
    page.check()
    stall.find_element("xpath", ".//button[normalize-space(.)='Run the fit']").click()
    page.wait(lambda: "All 2 runs together" in _card(page, "Locked rotor").text
              and "Fitting each run alone" not in _card(page, "Locked rotor").text, "each run beside the joint fit")
    text = _card(page, "Locked rotor").text
    assert f"{RUNS[0]} alone" in text
    assert f"{RUNS[1]} alone" in text
    assert "Back-EMF constant" in text
    page.check()
    page.shot(f"ui-dyno-{size[0]}.png")
