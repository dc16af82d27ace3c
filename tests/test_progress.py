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


def test_an_analysis_reports_its_reading_and_its_fit(tmp_path) -> None:
    # What the CLI draws as bars (and the app's worker streams): the analysis, the file read in MB,
    # the fit's steps, each ending with a finished report.
    from motorlab import experiments
    from motorlab.rig import VirtualRig

    run = VirtualRig("neverest40", unit_seed=0, noise_seed=0).pulse(tmp_path / "pulse.csv")
    experiment = experiments.get("pulse")
    seen: list[progress.Progress] = []
    with progress.reporting(seen.append):
        experiment.analyze(run.paths, experiment.values({"Ka": "1.96 A/V", "K": "0.7 N*m/A"}))
    tasks = {p.what: [q for q in seen if q.what == p.what] for p in seen}
    assert tasks["Analysing pulse.csv"][0].detail == "pulse"
    reading = tasks["Reading pulse.csv"]
    assert reading[0].unit == "MB"
    assert reading[-1].finished
    fitting = tasks["Fitting the pulse response"]
    assert [p.done for p in fitting] == [0, 1, 2, 3, 3]
    assert "coast-downs" in fitting[1].detail
    assert all(reports[-1].finished for reports in tasks.values())
    assert seen[-1].what == "Analysing pulse.csv"  # the analysis ends last: its steps were inside it


def test_output_error_fits_report_their_iterations(tmp_path) -> None:
    from motorlab import experiments
    from motorlab.rig import VirtualRig

    run = VirtualRig("neverest40", unit_seed=0, noise_seed=0).run("sysid", tmp_path / "sysid.json")
    experiment = experiments.get("feedforward")
    seen: list[progress.Progress] = []
    with progress.reporting(seen.append):
        experiment.analyze(run.paths, experiment.values({}))
    fitting = [p for p in seen if p.what == "Fitting the model"]
    assert fitting[0].unit == "iterations"
    assert len(fitting) >= 3
    assert fitting[-1].finished
    assert fitting[1].detail.startswith("χ²")
    assert any(p.what == "Reading sysid.json" and p.finished for p in seen)
