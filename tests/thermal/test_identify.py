"""identify --thermal: the winding's temperature as a state of the whole-model fit (docs/identify.md, "Heat")."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from motorlab.analyses.identify import identify
from motorlab.errors import OptionError
from motorlab.io import read_any
from motorlab.recording import Recording
from motorlab.rig import VirtualRig
from motorlab.thermal.identify import network_for, temperature_trajectory
from motorlab.thermal.network import ThermalModel

NAMES = ("K", "R", "L", "J", "b", "Tf")


def _heated_log(tmp: Path, seed: int) -> tuple[Recording, dict, float]:
    """8 s of random steps to 12 V at 100 Hz on a NeveRest 40 whose winding heats (25 → ~26.5 °C)."""
    rig = VirtualRig("neverest40", noise_seed=seed, unit_seed=1, heating=True)
    run = rig.transient(tmp / f"heated{seed}.csv", profile="random", duration=8.0, rate=100.0)
    return read_any(run.paths[0], cpr=rig.motor.cpr), run.truth, rig.motor.cpr


def test_temperature_trajectory_is_the_networks_response_to_the_heat() -> None:
    thermal = ThermalModel(winding_to_case=0.9, case_to_ambient=5.0, winding_capacity=20.0, case_capacity=150.0,
                           resistance_coefficient=0.0)
    t = np.linspace(0.0, 60.0, 601)
    tw, tc = temperature_trajectory(thermal, t, np.full(t.size, 3.0), 1.2, 25.0)
    for k in (100, 600):
        expected = thermal.step(25.0, 25.0, 1.2 * 9.0, float(t[k]))
        assert tw[k] == pytest.approx(expected[0], abs=1e-6)
        assert tc[k] == pytest.approx(expected[1], abs=1e-6)
    # with copper's coefficient the heat grows with the temperature: a warmer winding than without
    hot = temperature_trajectory(ThermalModel(0.9, 5.0, 20.0, 150.0), t, np.full(t.size, 3.0), 1.2, 25.0)[0]
    assert hot[-1] > tw[-1] + 0.05


def test_the_network_comes_from_the_motor_the_log_names_or_is_refused(tmp_path: Path) -> None:
    rec = Recording(np.arange(3.0), {"voltage": np.ones(3)}, metadata={"motor": "corehex"})
    thermal, origin = network_for([rec])
    assert "corehex" in origin
    assert thermal.winding_capacity == pytest.approx(10.0)
    assert "neverest40" in network_for([rec], motor="neverest40")[1]
    with pytest.raises(OptionError, match="--motor"):
        network_for([rec], motor="no-such-motor")
    assert "550-size" in network_for([Recording(np.arange(3.0), {"voltage": np.ones(3)})])[1]


def test_thermal_needs_the_current(tmp_path: Path) -> None:
    rig = VirtualRig("neverest40", noise_seed=1, heating=True)
    run = rig.transient(tmp_path / "t.csv", profile="steps", duration=1.0, rate=200.0, include_current=False)
    with pytest.raises(OptionError, match="needs the current"):
        identify(read_any(run.paths[0], cpr=rig.motor.cpr), cpr=rig.motor.cpr, thermal=True)


@pytest.mark.slow
@pytest.mark.parametrize("seed", [1, 4, 5])
def test_heated_log_round_trip_truth_within_three_standard_errors(tmp_path: Path, seed: int) -> None:
    """Three noise seeds (one case each, so that the workers share them): every determined parameter
    within 3 standard errors, R at 25 °C, the winding's peak within 0.3 °C; seed 1 also fitted as if R
    were constant, which biases R beyond 5 standard errors (what the heat state is for)."""
    rec, truth, cpr = _heated_log(tmp_path, seed)
    expected = truth["expected"]
    assert truth["temperatures"]["winding_end_C"] > 26.0  # it heated
    result = identify(rec, cpr=cpr, thermal=True)
    for name in NAMES:
        est = result[name]
        if est.determined:
            assert abs(est.value - expected[name]) <= 3 * est.stderr, (seed, name, est.value, expected[name])
    assert result["R"].determined
    assert result["K"].determined
    assert "25 °C" in result["R"].note
    assert "25 °C" in result.details["R_temperature"]
    thermal = result.details["thermal"]
    assert "neverest40" in thermal["network_from"]
    assert thermal["winding_max_C"] == pytest.approx(truth["temperatures"]["winding_max_C"], abs=0.3)
    assert any("the winding warmed from 25 to" in w for w in result.warnings)
    if seed == 1:  # the same log fitted as if R were constant: R comes out high, beyond its uncertainty
        plain = identify(rec, cpr=cpr)
        bias = plain["R"].value - expected["R"]
        assert bias > 5 * plain["R"].stderr, (bias, plain["R"].stderr)
        assert math.isclose(plain["R"].value / expected["R"] - 1, 0.00393 * 0.6, rel_tol=0.6)


def test_cli_takes_the_network_a_stall_run_measured(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    import json

    from motorlab import cli

    rig = VirtualRig("neverest40", noise_seed=2, heating=True)
    run = rig.stall(tmp_path / "stall.csv", voltage=6.0, duration=60.0)
    capsys.readouterr()
    assert cli.main(["analyze", "stall", str(run.paths[0]), "--json"]) == 0
    (tmp_path / "fit.json").write_text(capsys.readouterr().out)
    fit = json.loads((tmp_path / "fit.json").read_text())
    log = rig.transient(tmp_path / "log.csv", profile="steps", duration=1.5, rate=200.0)
    capsys.readouterr()
    assert cli.main(["analyze", "identify", str(log.paths[0]), "--thermal-fit", str(tmp_path / "fit.json"),
                     "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    thermal = doc["details"]["thermal"]
    assert thermal["network_from"] == "given"
    assert thermal["network"]["winding_capacity"] == pytest.approx(fit["parameters"]["C_w"]["value"])
    assert "25 °C" in doc["details"]["R_temperature"]
