"""Refusals in one step (issue 31, point 7): a table with no data rows, or none of whose columns motorlab knows
and none of which can be time, is refused at once, in words that say what motorlab expected, never after a
round of questions about its columns (the app asks one per column it does not know)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import httpx
import numpy as np
import pytest
import ui_browser as browser  # tests/ui/browser.py, loaded by conftest.py

from motorlab.errors import LogFormatError
from motorlab.io import read_csv


def _detect(server: Any, path: Path) -> dict[str, Any]:
    with open(path, "rb") as handle:
        response = httpx.post(f"{server.url}/api/detect", files=[("file", (path.name, handle))], timeout=120)
    assert response.status_code == 200, response.text
    return dict(response.json()[0])


@pytest.mark.parametrize("header", ["Load,Amps", "time_s,current_A", "a;b;c"])
def test_a_header_without_rows_is_refused_before_any_column_question(server: Any, tmp_path: Path,
                                                                     header: str) -> None:
    path = tmp_path / "empty.csv"
    path.write_text(f"# a comment\n{header}\n\n# another\n", encoding="utf-8")
    entry = _detect(server, path)
    assert "column" not in entry, entry  # no question about "Load"
    assert entry["error"].startswith("empty.csv:2: no data rows after the header: motorlab expected a table")


def test_random_numbers_are_refused_at_once(server: Any, tmp_path: Path) -> None:
    path = tmp_path / "numbers.csv"
    rng = np.random.default_rng(7)
    np.savetxt(path, rng.random((5_000, 5)), delimiter=",", fmt="%.6f", header="a,b,c,d,e", comments="")
    entry = _detect(server, path)
    assert "column" not in entry, entry
    assert "knows none of its columns (a, b, c, d …) and none of them can be time" in entry["error"]
    assert "motorlab expected a table of measurements" in entry["error"]


def test_a_column_that_can_be_time_still_gets_its_question(tmp_path: Path) -> None:
    """Unknown names over a rising column (a time in other words): the person is asked, as before."""
    path = tmp_path / "ramp.csv"
    t = np.arange(50) * 0.01
    np.savetxt(path, np.column_stack([t, np.sin(40 * t)]), delimiter=",", header="stamp,reading", comments="")
    with pytest.raises(LogFormatError, match="column 'stamp' names no quantity"):
        read_csv(path)


@browser.needs_browser
def test_the_page_says_it_in_one_step(page: Any, tmp_path: Path) -> None:
    path = tmp_path / "header-only.csv"
    path.write_text("Load,Amps\n", encoding="utf-8")
    page.open(browser.PHONE)
    page.upload("Choose or drop any log", path)
    page.wait_text("no data rows after the header")
    assert "does not know what the column" not in page.text()
    page.check()
