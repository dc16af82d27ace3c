"""Plants from analyze --json files, and the ``motorlab tune`` command."""

from __future__ import annotations

import json
import math

import pytest

import motorlab.cli
from motorlab.control.plant import load_plant
from motorlab.errors import LogFormatError
from motorlab.model import MotorParams, feedforward_from_params

P = MotorParams(K=0.42, R=1.3, L=0.0, J=2e-3, b=1e-3, Tf=0.05)


def _est(value):
    return {"value": value, "stderr": 0.01 * value, "unit": ""}


def test_load_plant_from_motor_parameters(tmp_path):
    f = tmp_path / "p.json"
    f.write_text(json.dumps({"experiment": "identify", "parameters": {k: _est(v) for k, v in P.to_dict().items()}}))
    plant = load_plant([f])
    assert plant.params == P
    ff = feedforward_from_params(P)
    assert plant.feedforward.kV == pytest.approx(ff["kV"])
    assert plant.feedforward.kA == pytest.approx(ff["kA"])


def test_load_plant_merges_lists_and_nested_documents(tmp_path):
    a = tmp_path / "a.json"
    a.write_text(json.dumps([{"parameters": {"K": _est(0.42), "R": _est(1.3)}}, {"parameters": {"J": _est(2e-3)}}]))
    b = tmp_path / "results.json"
    b.write_text(json.dumps({"runs": {"ff": {"parameters": {"kS": _est(0.2), "kV": _est(0.5), "kA": _est(0.01)}}}}))
    plant = load_plant([a, b])
    assert plant.params is not None
    assert plant.params.J == 2e-3
    # Directly measured kS/kV/kA are used for the design; the motor model for simulation.
    assert (plant.feedforward.kS, plant.feedforward.kV, plant.feedforward.kA) == (0.2, 0.5, 0.01)


def test_load_plant_errors(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text('{"parameters": {"K": 1,\n "R": }')
    with pytest.raises(LogFormatError, match=r"bad\.json:2"):
        load_plant([bad])
    empty = tmp_path / "empty.json"
    empty.write_text('{"fit": {}}')
    with pytest.raises(LogFormatError, match="no \"parameters\""):
        load_plant([empty])
    partial = tmp_path / "partial.json"
    partial.write_text(json.dumps({"parameters": {"K": _est(0.4), "R": None}}))
    with pytest.raises(LogFormatError, match="lack"):
        load_plant([partial])


def _run(monkeypatch, capsys, *argv):
    code = motorlab.cli.main(["tune", *argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_cli_json_shape(monkeypatch, capsys):
    code, out, _ = _run(monkeypatch, capsys, "position", "--kv", "3.06", "--ka", "0.327", "--ks", "0.1", "--json",
                        "--qp", "1", "--qv", "1.5", "--r", "7")  # SysId's tolerances
    assert code == 0
    d = json.loads(out)
    assert d["loop"] == "position"
    assert set(d["gains"]) == {"kP", "kI", "kD"}
    assert set(d["feedforward"]) == {"kS", "kV", "kA"}
    assert set(d["response"]) == {"rise_time", "overshoot", "settling_time", "steady_state_error"}
    assert d["gains"]["kP"] == pytest.approx(6.41, abs=0.05)  # SysId's Position test figure
    assert d["units"]["kP"] == "V/rad"
    assert d["max_profile"]["max_velocity"] > 0


def test_cli_params_file_ticks_emit(monkeypatch, capsys, tmp_path):
    f = tmp_path / "p.json"
    f.write_text(json.dumps({"parameters": {k: _est(v) for k, v in P.to_dict().items()}}))
    code, out, _ = _run(
        monkeypatch, capsys, "velocity", "--params", str(f), "--cpr", "537.7", "--target", "ftc-pidf", "--emit", "java"
    )
    assert code == 0
    assert "setVelocityPIDFCoefficients(" in out
    ff = feedforward_from_params(P)
    f_expected = 32767 / ((12 - ff["kS"]) / ff["kV"] * 537.7 / (2 * math.pi))
    assert f"{f_expected:.6g}" in out


def test_cli_plot(monkeypatch, capsys, tmp_path):
    png = tmp_path / "r.png"
    args = ("velocity", "--kv", "0.5", "--ka", "0.02", "--units", "rotations", "--method", "poles")
    code, out, _ = _run(monkeypatch, capsys, *args, "--rise-time", "0.04", "--period", "0.01", "--plot", str(png))
    assert code == 0
    assert png.stat().st_size > 1000
    assert "rise time" in out


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (("position", "--kv", "3", "--ka", "-0.3"), "kA must not be negative"),
        (("position", "--kv", "3"), "give the plant"),
        (("velocity", "--kv", "3", "--ka", "0.3", "--target", "ftc-power"), "--cpr"),
        (("velocity", "--kv", "3", "--ka", "0.3", "--params", "x.json"), "not both"),
        (("velocity", "--kv", "nan", "--ka", "0.3"), "finite"),
        (("velocity", "--kv", "3", "--ka", "0.3", "--target", "talon"), "invalid choice"),
        (("velocity", "--params", "/nonexistent/p.json"), "no such file"),
    ],
)
def test_cli_bad_input_is_one_line_exit_2(monkeypatch, capsys, argv, message):
    try:
        code, _, err = _run(monkeypatch, capsys, *argv)
    except SystemExit as exc:  # argparse errors exit from the parser
        code = exc.code
        err = capsys.readouterr().err
    assert code == 2
    assert message in err
    assert len(err.strip().splitlines()) == 1


def test_results_json_of_characterize_uses_one_units_motor_parameters(tmp_path, capsys):
    """A characterize results.json: only the chosen unit's combined (bare-motor) parameters make the plant.

    Its per-experiment results include flywheel runs (kA of motor + flywheel): mixing them in would
    design for a plant hundreds of times heavier than the motor simulated.
    """

    from motorlab.report.document import write_outputs
    from motorlab.session.characterize import characterize
    from motorlab.session.simulated import write_simulated_session
    from motorlab.session.spec import load_session

    toml = write_simulated_session(
        "neverest40", out_dir=tmp_path / "s", units=2, experiments=("lcr", "spindown", "identify", "feedforward")
    )
    write_outputs(characterize(load_session(toml), control=False, figures=False), tmp_path / "r", report=False)
    results = tmp_path / "r" / "results.json"
    code = motorlab.cli.main(["tune", "velocity", "--params", str(results)])
    assert code == 2
    assert "choose one with --unit" in capsys.readouterr().err
    assert motorlab.cli.main(["tune", "velocity", "--params", str(results), "--unit", "B", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    unit_b = json.loads(results.read_text())["units"]["B"]["parameters"]
    params = MotorParams.from_dict(unit_b)
    expected = feedforward_from_params(params)
    assert doc["feedforward"]["kA"] == pytest.approx(expected["kA"], rel=1e-6)  # the bare motor's kA
    assert doc["response"]["overshoot"] < 10
