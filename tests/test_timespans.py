"""Time spans left out of a log (``--exclude``): round trips on the virtual dynamometer with a corrupted stretch.

A dead wheel that lifts off a bump for a second (its counts stop, then go on short of the distance
travelled) ruins a Road Runner ramp's fit; with the stretch left out the truth is back within three
standard errors. The same for an INA219 reading a quarter high during a spin-down's coast, and a current
sensor reading 1 A high in a transient log.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from motorlab.errors import OptionError
from motorlab.experiments import get
from motorlab.recording import Recording
from motorlab.timespans import leave_out, parse_spans


def _simulate(kind: str, out: Path, *extra: str) -> dict:
    """``motorlab simulate`` in this process (the command's own process is tested in tests/cli)."""
    from motorlab.cli import main

    assert main(["simulate", kind, *extra, "-o", str(out)]) == 0
    return dict(json.loads((out.parent / "truth.json").read_text())["runs"][out.name])


def _lifted_wheel(path: Path, out: Path, t1: float, t2: float) -> None:
    """The ramp with its dead wheels off the floor from t1 to t2: counts frozen, then short by what was missed."""
    doc = json.loads(path.read_text())
    for enc in doc["forwardEncPositions"]:
        t, v = np.array(enc["times"]), np.array(enc["values"], dtype=float)
        i1, i2 = np.searchsorted(t, t1), np.searchsorted(t, t2)
        missed = v[i2] - v[i1]
        v[i1:i2] = v[i1]
        v[i2:] -= missed
        enc["values"] = [int(x) for x in v]
    for enc in doc["forwardEncVels"]:
        t, v = np.array(enc["times"]), np.array(enc["values"], dtype=float)
        v[(t >= t1) & (t < t2)] = 0
        enc["values"] = [int(x) for x in v]
    out.write_text(json.dumps(doc))


def _z(result: object, truth: dict, names: tuple[str, ...]) -> dict[str, float]:
    return {n: (result[n].value - truth[n]) / result[n].stderr for n in names}  # type: ignore[index]


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_road_runner_ramp_with_a_lifted_dead_wheel(tmp_path: Path, seed: int) -> None:
    truth = _simulate("roadrunner-ramp", tmp_path / "ramp.json", "--seed", str(seed))["expected"]
    _lifted_wheel(tmp_path / "ramp.json", tmp_path / "bad.json", 2.5, 3.5)
    exp = get("feedforward")
    names = ("kS", "kV", "kA")
    ruined = exp.analyze([str(tmp_path / "bad.json")], exp.values({"cpr": 8192}))
    assert max(abs(z) for z in _z(ruined, truth, names).values()) > 3  # the corrupted stretch ruins the fit
    fixed = exp.analyze([str(tmp_path / "bad.json")], exp.values({"cpr": 8192, "exclude": "2.45:3.55"}))
    z = _z(fixed, truth, names)
    assert all(abs(v) < 3 for v in z.values()), z
    left = fixed.details["left_out"]
    assert left["spans"] == [[2.45, 3.55]]
    assert left["seconds"] == pytest.approx(1.1)
    assert 40 < left["samples"] < 120
    assert fixed.warnings[0] == left["text"]
    assert left["text"].startswith(f"1 time span left out, 1.10 s, {left['samples']} samples")
    # the panels say each point's time in the log: none inside the span
    times = np.concatenate([p.time for p in fixed.panels if p.time is not None])
    assert times.size
    assert not np.any((times > 2.46) & (times < 3.54))


def test_spindown_with_a_voltage_reading_high_for_two_seconds(tmp_path: Path) -> None:
    run = _simulate("spindown", tmp_path / "spindown.txt", "--motor", "neverest40")
    lines = (tmp_path / "spindown.txt").read_text().splitlines()
    rows = [line.split() for line in lines[1:]]
    t = np.array([float(r[0]) for r in rows]) / 1000
    cut = t[np.flatnonzero(np.array([float(r[3]) for r in rows]) > 1)[-1] + 1]
    for r, tt in zip(rows, t, strict=True):
        if cut + 3 <= tt <= cut + 5:
            r[2] = f"{float(r[2]) * 1.25:.3f}"  # the INA219 reads a quarter high
    (tmp_path / "bad.txt").write_text("\n".join([lines[0], *(" ".join(r) for r in rows)]) + "\n")
    exp = get("spindown")
    ruined = exp.analyze([str(tmp_path / "bad.txt")], exp.values({"cpr": 1120}))
    assert abs(_z(ruined, run["params"], ("K",))["K"]) > 3
    span = f"{cut + 2.95:.2f}:{cut + 5.05:.2f}"
    fixed = exp.analyze([str(tmp_path / "bad.txt")], exp.values({"cpr": 1120, "exclude": [span]}))
    assert abs(_z(fixed, run["params"], ("K",))["K"]) < 3
    assert fixed.details["left_out"]["samples"] == 21  # 10 Hz rows over 2.1 s


@pytest.mark.slow
def test_identify_with_a_current_sensor_reading_high(tmp_path: Path) -> None:
    run = _simulate("transient", tmp_path / "transient.csv", "--motor", "neverest40")
    lines = (tmp_path / "transient.csv").read_text().splitlines()
    head = next(k for k, line in enumerate(lines) if line.startswith("time_s"))
    out = lines[: head + 1]
    for line in lines[head + 1:]:
        f = line.split(",")
        if 1.5 <= float(f[0]) <= 1.8:
            f[2] = f"{float(f[2]) + 1.0:.3f}"  # the current sensor reads 1 A high for 0.3 s
        out.append(",".join(f))
    (tmp_path / "bad.csv").write_text("\n".join(out) + "\n")
    exp = get("identify")
    names = ("K", "R", "L", "J", "b", "Tf")
    ruined = exp.analyze([str(tmp_path / "bad.csv")], exp.values({"cpr": 1120}))
    fixed = exp.analyze([str(tmp_path / "bad.csv")], exp.values({"cpr": 1120, "exclude": "1.49:1.81"}))
    z = _z(fixed, run["params"], names)
    assert all(abs(v) < 3 for v in z.values()), z
    # the burst's residuals had inflated the uncertainty of K (Newey–West); left out, it is the clean log's
    assert fixed["K"].stderr < 0.5 * ruined["K"].stderr
    assert "left out" in fixed.warnings[0]


def _recording(n: int = 100) -> Recording:
    t = np.arange(n) * 0.01
    return Recording(t, {"position": t**2, "voltage": np.ones(n)}, source="log.csv")


def test_spans_parsed_in_every_form_and_refused_in_words() -> None:
    assert parse_spans("12.5:14.0") == [(12.5, 14.0)]
    assert parse_spans(["1:2", "3 s–4 s", (5, 6)]) == [(1.0, 2.0), (3.0, 4.0), (5.0, 6.0)]
    assert parse_spans("1..2, 3:4; 5:6") == [(1.0, 2.0), (3.0, 4.0), (5.0, 6.0)]
    for bad, words in [("3:2", "ends before it starts"), ("a:b", "not a time span"), ("1:inf", "not a time span")]:
        with pytest.raises(OptionError, match=words):
            parse_spans(bad)
    with pytest.raises(OptionError, match=r"log\.csv: the time span 5–6 s to leave out holds no sample"):
        leave_out([_recording()], [(5.0, 6.0)], split=False)
    with pytest.raises(OptionError, match="leave nothing"):
        leave_out([_recording()], [(-1.0, 2.0)], split=True)


def test_dropping_and_cutting_a_run() -> None:
    rec = _recording()
    (dropped,), left = leave_out([rec], [(0.295, 0.395), (0.35, 0.495)], split=False)  # overlapping: merged
    assert len(dropped) == 80
    assert left.samples == 20
    assert left.spans == [(0.295, 0.495)]
    assert left.text() == "1 time span left out, 0.20 s, 20 samples (0.295–0.495 s of the log's time)"
    pieces, left = leave_out([rec], [(0.295, 0.495), (0.895, 0.955)], split=True)
    # 0–0.29 s (30 samples) and 0.5–0.89 s (40); 0.96–0.99 s is too short to fit and goes with the span
    assert [len(p) for p in pieces] == [30, 40]
    assert left.samples == 20 + 6 + 4
    assert left.pieces_dropped == 1
    assert pieces[1].time[0] == pytest.approx(0.5)  # each piece keeps the log's own time


def test_cli_takes_the_spans_and_an_analysis_without_time_refuses_them(tmp_path: Path,
                                                                      capsys: pytest.CaptureFixture[str]) -> None:
    """The commands run in this process (one ``motorlab`` process each gave the same answers, 6 s slower)."""
    from motorlab.cli import main

    _simulate("roadrunner-ramp", tmp_path / "ramp.json", "--seed", "1")
    capsys.readouterr()
    cmd = ["analyze", "feedforward", str(tmp_path / "ramp.json"), "--cpr", "8192"]
    assert main([*cmd, "--exclude", "1:1.5", "--exclude=2:2.5", "--json"]) == 0
    left = json.loads(capsys.readouterr().out)["details"]["left_out"]
    assert left["spans"] == [[1.0, 1.5], [2.0, 2.5]]
    assert left["text"].startswith("2 time spans left out, 1.00 s,")
    with pytest.raises(SystemExit) as refused:  # argparse refuses it, as the console script's process exits
        main([*cmd, "--exclude", "2:1"])
    assert refused.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert "ends before it starts" in err
    with pytest.raises(SystemExit) as refused:
        main(["analyze", "lcr", str(tmp_path / "ramp.json"), "--exclude", "1:2"])
    assert refused.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert "leave the rows out of a copy of the file" in err
    with pytest.raises(OptionError, match="leave the rows out of a copy of the file"):  # the notebook's words
        get("lcr").values({"exclude": "1:2"})


def test_a_session_leaves_spans_out_and_refuses_them_where_no_analysis_takes_them(tmp_path: Path) -> None:
    from motorlab.errors import SessionError
    from motorlab.session.characterize import characterize
    from motorlab.session.simulated import write_simulated_session
    from motorlab.session.spec import load_session

    write_simulated_session("neverest40", out_dir=tmp_path, units=1, seed=5, experiments=("lcr", "spindown"))
    toml = tmp_path / "session.toml"
    text = toml.read_text()
    spindown = 'files = ["A/spindown.txt"]'
    toml.write_text(text.replace(spindown, f'{spindown}\nexclude = ["40:41", "45:45.5"]'))
    done = characterize(load_session(toml), control=False, figures=False)
    fit = done.units["A"].fits["spindown"]
    assert fit.details["left_out"]["spans"] == [[40.0, 41.0], [45.0, 45.5]]
    assert fit.warnings[0].startswith("2 time spans left out, 1.50 s,")
    toml.write_text(text.replace('files = ["A/lcr.csv"]', 'files = ["A/lcr.csv"]\nexclude = "1:2"'))
    with pytest.raises(SessionError, match="leave the rows out of a copy of the file"):
        load_session(toml)
    toml.write_text(text.replace(spindown, f'{spindown}\nexclude = "2:1"'))
    with pytest.raises(SessionError, match="ends before it starts"):
        load_session(toml)
