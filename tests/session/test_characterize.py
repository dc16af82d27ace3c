"""A simulated session characterised end to end: estimates against the truth, combination, fleet, failures."""

from __future__ import annotations

import csv
import dataclasses
import json
import math
import shutil
from pathlib import Path

import pytest

from motorlab.report.document import write_outputs
from motorlab.results import Estimate
from motorlab.rig.units import UnitSpread
from motorlab.session.characterize import PARAMETERS, characterize, combine
from motorlab.session.simulated import write_simulated_session
from motorlab.session.spec import load_session

#: A production batch (tighter than the rig's default spread) so that a doubled b must stand out.
BATCH = UnitSpread(K=0.02, R=0.04, L=0.04, J=0.03, b=0.06, Tf=0.06)
EXPERIMENTS = ("lcr", "spindown", "terminal", "free-spinup")


@pytest.fixture(scope="module")
def session_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("session")
    write_simulated_session(
        "neverest40", out_dir=out, units=3, seed=3, degrade={"B": {"b": 2.0}}, spread=BATCH, experiments=EXPERIMENTS
    )
    return out


@pytest.fixture(scope="module")
def result(session_dir: Path):  # type: ignore[no-untyped-def]
    return characterize(load_session(session_dir / "session.toml"), control=False, figures=False)


def test_simulated_session_toml(session_dir: Path) -> None:
    session = load_session(session_dir / "session.toml")
    assert list(session.units) == ["A", "B", "C"]
    assert list(session.units["A"].experiments) == list(EXPERIMENTS)
    assert session.healthy_spread == pytest.approx(dataclasses.asdict(BATCH))
    assert session.units["B"].truth is not None
    assert "b × 2" in session.units["B"].notes


def test_estimates_against_truth(result) -> None:  # type: ignore[no-untyped-def]
    for name, unit in result.units.items():
        assert unit.status == "ok", name
        assert set(unit.parameters) == set(PARAMETERS)
        for p in PARAMETERS:
            est = unit.parameters[p].estimate
            truth = unit.truth[p]
            assert est.determined, (name, p)
            assert est.stderr > 0, (name, p)
            assert abs(est.value - truth) < 4 * est.stderr, (name, p, est, truth)
            assert abs(est.value / truth - 1) < 0.08, (name, p, est, truth)
    sources = {p: c.source for p, c in result.units["A"].parameters.items()}
    assert sources == {"J": "free-spinup", "b": "terminal", "Tf": "terminal", "K": "spindown", "R": "lcr", "L": "lcr"}


def test_k_stderr_reaches_downstream(result) -> None:  # type: ignore[no-untyped-def]
    # b = (K·I − Tf)/ω scales with K: its relative error can be no smaller than K's.
    unit = result.units["A"]
    k = unit.parameters["K"].estimate
    b = unit.parameters["b"].estimate
    assert b.relative_error >= 0.99 * k.relative_error


def test_worn_unit_flagged_only(result) -> None:  # type: ignore[no-untyped-def]
    assert [(o.unit, o.parameter) for o in result.fleet.outliers] == [("B", "b")]
    assert result.fleet.outliers[0].ratio == pytest.approx(2.0, rel=0.25)


def test_outputs(result, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    paths = write_outputs(result, tmp_path, report=False)
    doc = json.loads(paths["json"].read_text())
    a = doc["units"]["A"]["parameters"]["K"]
    assert set(a) >= {"value", "stderr", "unit", "source"}
    assert a["unit"] == "V*s/rad"
    assert doc["fleet"]["outliers"][0]["unit"] == "B"
    assert doc["units"]["A"]["experiments"]["spindown"]["parameters"]["K"]["value"] == pytest.approx(a["value"])
    with paths["csv"].open() as handle:
        rows = list(csv.DictReader(handle))
    assert [r["unit"] for r in rows] == ["A", "B", "C"]
    assert float(rows[1]["b (N*m*s/rad)"]) == pytest.approx(result.units["B"].parameters["b"].estimate.value, rel=1e-5)
    assert "b is" in rows[1]["fleet outliers"]
    assert rows[0]["status"] == "ok"


def test_one_failing_unit_does_not_stop_the_others(session_dir: Path, tmp_path: Path) -> None:
    copy = tmp_path / "copy"
    shutil.copytree(session_dir, copy)
    (copy / "C" / "terminal.csv").write_text("current_A,frequency_Hz\n0.3,abc\n")  # not a number
    result = characterize(load_session(copy / "session.toml"), control=False, figures=False)
    c = result.units["C"]
    assert "terminal" in c.failures
    assert "terminal failed" in c.status
    assert "b" not in c.parameters
    assert "K" in c.parameters
    assert "J" in c.parameters
    assert result.units["A"].status == "ok"
    assert result.units["B"].status == "ok"


def test_combine_precision_and_disagreement() -> None:
    a = Estimate("K", 0.70, 0.01, "V*s/rad")
    b = Estimate("K", 0.71, 0.002, "V*s/rad")
    c = Estimate("K", 0.60, 0.01, "V*s/rad")
    d = Estimate("K", math.nan, math.nan, "V*s/rad", determined=False)
    combined, disagreements = combine("K", {"torque": a, "spindown": b, "identify": d})
    assert combined is not None
    assert combined.source == "spindown"
    assert combined.estimate.value == 0.71
    assert disagreements == []
    combined, disagreements = combine("K", {"torque": a, "spindown": b, "pulse": c})
    assert combined is not None
    assert combined.source == "spindown"
    pairs = {(x.first, x.second) for x in disagreements}
    assert pairs == {("torque", "pulse"), ("spindown", "pulse")}
    assert all(x.sigmas > 3 for x in disagreements)
    combined, _ = combine("K", {"identify": d})
    assert combined is not None
    assert not combined.estimate.determined
    assert combine("K", {}) == (None, [])


def test_units_analysed_in_two_processes_give_the_same_results(session_dir: Path, result) -> None:  # type: ignore[no-untyped-def]
    from motorlab import progress

    told: list[tuple[str, str]] = []
    seen: list[progress.Progress] = []
    session = load_session(session_dir / "session.toml")
    with progress.reporting(seen.append):
        shared = characterize(session, control=False, figures=False, processes=2,
                              progress=lambda unit, experiment: told.append((unit, experiment)))
    assert json.dumps(shared.to_dict(), sort_keys=True) == json.dumps(result.to_dict(), sort_keys=True)
    # Each unit's experiments, told from the processes that ran them, in each unit's order.
    for unit in ("A", "B", "C"):
        assert [e for u, e in told if u == unit] == [*EXPERIMENTS, ""]
    units = [p for p in seen if p.what == "Characterising the units"]
    assert units[-1].finished
    assert units[-1].done == units[-1].total == 3
    assert any(p.detail.startswith("unit ") and ": " in p.detail for p in units)  # the experiment running
