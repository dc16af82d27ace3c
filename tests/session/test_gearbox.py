"""A session with a back-EMF experiment and a torque test: η ± σ per unit, the fleet, the report's answer."""

from __future__ import annotations

import csv
import json

import pytest

from motorlab.report.document import write_outputs
from motorlab.session.characterize import characterize
from motorlab.session.simulated import write_simulated_session
from motorlab.session.spec import load_session


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


def _bare_curve(path, *, ratio_kt_k: float) -> None:
    """A 12 V curve of a bare motor whose torque per amp is ``ratio_kt_k`` of its back-EMF constant."""
    import numpy as np

    from motorlab.io import write_csv

    k, r, tf, volts = 0.0172, 1.04, 0.002, 12.0
    kt = ratio_kt_k * k
    free = (kt * volts / r - tf) / (kt * k / r)
    speed = np.linspace(0.0, free, 30)
    current = (volts - k * speed) / r
    rng = np.random.default_rng(5)
    write_csv(path, {"speed_rad_per_s": speed, "current_A": current + rng.normal(0, 1e-3, speed.size),
                     "torque_Nm": kt * current - tf + rng.normal(0, 1e-5, speed.size)})


def test_report_splits_kt_ke_into_motor_and_gearbox(tmp_path):
    """A curve of the bare motor in the session: the report gives Kt/K to the motor and η/(Kt/K) to the gearbox."""
    from motorlab.report.document import render_report

    toml = write_simulated_session("neverest40", out_dir=tmp_path, units=2, seed=3, gearbox="catalog",
                                   experiments=("spindown", "torque"))
    _bare_curve(tmp_path / "A" / "curve.csv", ratio_kt_k=0.9)
    toml.write_text(toml.read_text() + '\n[units.A.curve]\nfiles = ["A/curve.csv"]\nvoltage = "12 V"\n')
    result = characterize(load_session(toml), control=False, figures=False)
    curve_fit = result.units["A"].fits["curve"]
    assert curve_fit["Kt_over_K"].value == pytest.approx(0.9, abs=0.01)
    html = render_report(result, figures=False)  # its words are checked; the figures are tests/report's
    assert "Split with the curve run of unit A" in html
    for name in ("A", "B"):  # B has no curve of its own: the session's (the same motor model) is used
        eta = result.units[name].parameters["efficiency"].estimate.value
        assert f"η/(Kt/K) = {eta / curve_fit['Kt_over_K'].value:.3g}" in html
    # without a bare-motor run the report says where the rest would come from
    toml2 = write_simulated_session("neverest40", out_dir=tmp_path / "plain", units=1, seed=3, gearbox="catalog",
                                    experiments=("spindown", "torque"))
    plain = render_report(characterize(load_session(toml2), control=False, figures=False), figures=False)
    assert "All of it is given to the gearbox here" in plain


def test_a_stall_run_held_at_the_gearbox_output_is_not_taken_for_the_bare_motor(tmp_path):
    """The simulated session's stall runs hold the gearmotor's output: their torque per amp is N·η times the
    motor's K, ~12 times the back-EMF constant, which no bare motor gives. The report split the shortfall
    with it (a gearbox of 2.5 % efficiency); now it is passed over and the report says what would tell."""
    from motorlab.report.document import render_report
    from motorlab.session.efficiency import bare_motor_ratio

    toml = write_simulated_session("neverest40", out_dir=tmp_path, units=1, seed=3, gearbox="catalog",
                                   experiments=("spindown", "torque", "stall"))
    result = characterize(load_session(toml), control=False, figures=False)
    unit = result.units["A"]
    assert unit.fits["stall"]["K"].value > 5 * unit.parameters["K"].estimate.value / 40  # the output shaft's
    assert bare_motor_ratio({"A": unit.fits}, "A", k_output=unit.parameters["K"].estimate, ratio=40.0) is None
    html = render_report(result, figures=False)  # its words are checked; the figures are tests/report's
    assert "Split with" not in html
    assert "All of it is given to the gearbox here" in html
