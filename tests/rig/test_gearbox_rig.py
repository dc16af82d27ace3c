"""The virtual dynamometer with a lossy gearbox: truths per direction of power flow, CLI options."""

from __future__ import annotations

import json

import pytest

from motorlab import cli
from motorlab.analyses import common
from motorlab.analyses.spindown import spindown
from motorlab.catalog import Motor
from motorlab.gearbox import Gearbox
from motorlab.rig import VirtualRig


def test_spindown_through_a_back_driven_gearbox(tmp_path):
    """The coast of the flywheel back-drives the gearbox: the rig's truth is the back-driven one, and the
    analysis finds it (γ and Tf/J); K is the back-EMF constant whatever the gearbox loses."""
    motor = Motor.from_catalog("neverest40")
    rig = VirtualRig(motor, unit_seed=1, noise_seed=1, gearbox=motor.gearbox())
    run = rig.spindown(tmp_path / "s.txt")
    expected = run.truth["expected"]
    assert expected["gearbox_flow"] == "back-driven"
    result = spindown(common.read_position_log([str(run.paths[0])], cpr=motor.cpr), cpr=motor.cpr)
    for name in ("gamma", "Tf_over_J", "K"):
        est = result[name]
        assert abs(est.value - expected[name]) <= 4 * est.stderr, name
    assert expected["K"] == pytest.approx(run.truth["params"]["K"])


def test_spinup_truth_is_the_output_torque_constant(tmp_path):
    motor = Motor.from_catalog("neverest40")
    box = Gearbox(ratio=40, efficiency=0.6, loss_torque=0.02)
    run = VirtualRig(motor, gearbox=box).spinup(tmp_path / "u.txt", duration=5.0)
    expected = run.truth["expected"]
    assert expected["K"] == pytest.approx(0.6 * expected["Ke"])
    assert run.truth["gearbox"]["efficiency"] == 0.6
    # The bare gearmotor's model includes the gearbox's drag ÷ η; the motor's own parameters do not.
    assert run.truth["params"]["Tf"] == pytest.approx(run.truth["motor_params"]["Tf"] + 0.02 / 0.6)


def test_ideal_gearbox_by_default(tmp_path):
    run = VirtualRig("neverest40").torque(tmp_path / "t.csv")
    assert run.truth["gearbox"]["efficiency"] == 1.0
    assert run.truth["params"] == run.truth["motor_params"]
    assert run.truth["expected"]["K"] == run.truth["params"]["K"]


def test_simulate_cli_gearbox_options(tmp_path, capsys):
    out = tmp_path / "t.csv"
    assert cli.main(["simulate", "torque", "--motor", "neverest40", "--efficiency", "catalog",
                     "--loss-torque", "0.05 N*m", "-o", str(out)]) == 0
    box = json.loads((tmp_path / "truth.json").read_text())["runs"]["t.csv"]["gearbox"]
    assert box["efficiency"] == pytest.approx(Motor.from_catalog("neverest40").gearbox().efficiency)
    assert box["loss_torque"] == pytest.approx(0.05)
    assert cli.main(["simulate", "session", "--motor", "neverest40", "--units", "1", "--efficiency", "0.7",
                     "-o", str(tmp_path / "session")]) == 0
    truth = json.loads((tmp_path / "session" / "A" / "truth.json").read_text())
    assert {run["gearbox"]["efficiency"] for run in truth["runs"].values()} == {0.7}
    capsys.readouterr()
    with pytest.raises(SystemExit) as exc:
        cli.main(["simulate", "torque", "--motor", "neverest40", "--efficiency", "1.5", "-o", str(out)])
    assert exc.value.code == 2
    assert "efficiency" in capsys.readouterr().err
