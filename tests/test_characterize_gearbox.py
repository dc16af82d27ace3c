"""A session with a back-EMF experiment and a torque test: η ± σ per unit, the fleet, the report's answer."""

from __future__ import annotations

import csv
import json

import pytest

from motorlab.characterize import characterize
from motorlab.report import write_outputs
from motorlab.session import load_session
from motorlab.simulated_session import write_simulated_session


@pytest.fixture(scope="module")
def worn_gearbox_session(tmp_path_factory):
    out = tmp_path_factory.mktemp("gearbox")
    toml = write_simulated_session("neverest40", out_dir=out / "session", units=3, seed=2, gearbox="catalog",
                                   degrade={"C": {"efficiency": 0.8}}, experiments=("spindown", "torque"))
    result = characterize(load_session(toml), control=False, figures=False)
    return out, result


def test_efficiency_per_unit_and_the_worn_gearbox_stands_out(worn_gearbox_session):
    _, result = worn_gearbox_session
    for unit in result.units.values():
        eta = unit.parameters["efficiency"]
        assert eta.source == "torque ÷ spindown"
        est, truth = eta.estimate, unit.truth["efficiency"]
        assert abs(est.value - truth) < 0.03
        assert abs(est.value - truth) <= 3 * est.stderr
        assert unit.parameters["loss_torque"].estimate.unit == "N*m"
        # K stays the back-EMF constant: the lever's Kt = η·Ke is not mixed into it.
        assert unit.parameters["K"].source == "spindown"
        assert unit.parameters["K"].estimate.value == pytest.approx(unit.truth["K"], rel=0.03)
    flagged = {(o.unit, o.parameter) for o in result.fleet.outliers}
    assert ("C", "efficiency") in flagged
    assert not {u for u, p in flagged if p == "efficiency"} - {"C"}


def test_results_files_and_report_answer_the_seed(worn_gearbox_session):
    out, result = worn_gearbox_session
    paths = write_outputs(result, out / "results")
    doc = json.loads(paths["json"].read_text())
    assert doc["units"]["A"]["parameters"]["efficiency"]["unit"] == "1"
    assert doc["units"]["A"]["experiments"]["torque"]["details"]["shaft"].startswith("output (lever)")
    with paths["csv"].open() as handle:
        rows = list(csv.DictReader(handle))
    assert "efficiency (1)" in rows[0]
    eta_a = result.units["A"].parameters["efficiency"].estimate.value
    assert float(rows[0]["efficiency (1)"]) == pytest.approx(eta_a, rel=1e-5)
    html = paths["html"].read_text()
    assert 'id="gearbox"' in html
    assert "Ke×N" in html
    assert "the gearbox explains it" in html
