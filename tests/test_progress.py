"""Progress reports: the library reports through a context variable; front ends listen."""

from __future__ import annotations

import io
import json

from motorlab import progress


def test_reports_reach_the_installed_reporter_and_nothing_else() -> None:
    seen: list[progress.Progress] = []
    with progress.reporting(seen.append), progress.task("units", total=2, unit="unit") as step:
        step.advance(detail="unit A")
        step.advance(detail="unit B")
    assert [(p.done, p.detail, p.finished) for p in seen] == [
        (0, "", False), (1, "unit A", False), (2, "unit B", False), (2, "unit B", True)]
    assert seen[-1].fraction() == 1.0
    with progress.task("nobody listens") as step:  # no reporter: no error, nothing recorded
        step.advance()
    assert len(seen) == 4
    assert not progress.active()


def test_json_lines_are_throttled_but_the_last_always_goes() -> None:
    out = io.StringIO()
    with progress.reporting(progress.JsonLines(out, interval=60.0)), progress.task("rows", total=10) as step:
        for _ in range(10):
            step.advance()
    lines = [json.loads(line)["progress"] for line in out.getvalue().splitlines()]
    assert lines[0]["done"] == 0
    assert lines[-1] == {**lines[-1], "done": 10, "finished": True}
    assert len(lines) == 2
