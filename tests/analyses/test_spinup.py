"""Spin-up analysis: K from a constant-current spin-up of a known flywheel."""

from __future__ import annotations

import argparse
import math

import numpy as np
import pytest

from motorlab.analyses.spindown import spindown
from motorlab.analyses.spinup import spinup
from motorlab.cli.analyze import add_arguments, from_cli
from motorlab.errors import FitError, OptionError
from motorlab.model import MotorParams
from motorlab.model.simulate import BenchSupply, OpenCircuit, simulate
from motorlab.recording import Recording

CPR = 560.0
FLYWHEEL = MotorParams(K=0.37, R=2.0, L=7e-4, J=7.75, b=0.12, Tf=0.25)


def flywheel_log(seed: int, params: MotorParams = FLYWHEEL, *, on_time: float = 60.0,
                 duration: float = 140.0) -> Recording:
    """FTC log (50 ms loop with jitter) of a 3 A spin-up then a coast; INA219-like noise."""
    rng = np.random.default_rng(seed)
    sim = simulate(params, [(0.0, BenchSupply(16.0, 3.0)), (on_time, OpenCircuit())], duration=duration, dt=1e-3)
    steps = 0.05 + rng.exponential(2e-3, int(duration / 0.05) + 2)
    t = rng.uniform(0.005, 0.02) + np.concatenate(([0.0], np.cumsum(steps[:-1])))
    t = t[t < duration - 0.01]
    s = sim.sample(t + 1e-3)
    counts = np.floor(s["position"] * CPR / (2 * math.pi) + 1e-9)
    voltage = np.clip(np.round((s["voltage"] + rng.normal(0, 0.07, t.size)) / 4e-3) * 4e-3, 0, 16)
    current = np.round((s["current"] - 1e-3 + rng.normal(0, 3e-3, t.size)) / 1e-4) * 1e-4
    return Recording(t, {"counts": counts, "voltage": voltage, "current": current}, source="spinup.txt")


def test_round_trip_with_friction_from_a_spindown() -> None:
    covered = 0
    for seed in range(6):
        log = flywheel_log(seed)
        friction = spindown(flywheel_log(100 + seed), cpr=CPR)
        result = spinup(log, cpr=CPR, inertia=FLYWHEEL.J, inertia_stderr=0.01 * FLYWHEEL.J, spindown_result=friction)
        k = result["K"]
        assert k.value == pytest.approx(FLYWHEEL.K, rel=0.015)
        covered += abs(k.value - FLYWHEEL.K) <= 3 * k.stderr
        # J's 1 % uncertainty dominates and must show in K's standard error.
        assert k.relative_error == pytest.approx(0.01, rel=0.2)
        assert result["i"].value == pytest.approx(3.0, rel=0.002)
        assert result.details["current_relative_scatter"] < 0.01
    assert covered >= 5


def test_given_friction_and_the_seeds_frictionless_formula() -> None:
    log = flywheel_log(7)
    with_friction = spinup(log, cpr=CPR, inertia=FLYWHEEL.J, viscous_friction=0.12, coulomb_friction=0.25,
                           viscous_friction_stderr=0.006, coulomb_friction_stderr=0.0125)
    assert with_friction["K"].value == pytest.approx(FLYWHEEL.K, rel=0.015)
    assert abs(with_friction["K"].value - FLYWHEEL.K) < 3 * with_friction["K"].stderr
    naive = spinup(log, cpr=CPR, inertia=FLYWHEEL.J)
    assert naive["K"].value < 0.95 * FLYWHEEL.K  # K = J·α/i ignores the friction torque
    assert any("no friction given" in w for w in naive.warnings)
    assert naive.panels[0].y_label.endswith("[rad]")


def test_bad_input() -> None:
    log = flywheel_log(8, duration=70.0)
    with pytest.raises(OptionError):
        spinup(log, cpr=CPR, inertia=0.0)
    with pytest.raises(OptionError):
        spinup(log, cpr=-1.0, inertia=FLYWHEEL.J)
    quiet = Recording(log.time, {"counts": log["counts"] * 0, "current": log["current"] * 0}, source="q.txt")
    with pytest.raises(FitError, match=r"q\.txt: no spin-up"):
        spinup(quiet, cpr=CPR, inertia=FLYWHEEL.J)
    with pytest.raises(OptionError, match="not both"):
        spinup(log, cpr=CPR, inertia=FLYWHEEL.J, viscous_friction=0.1, spindown_result=spindown(log, cpr=CPR))


def test_cli_with_spindown_file(tmp_path) -> None:
    from motorlab.io.ftc import write_ftc_log

    paths = []
    for name, seed in (("spinup.txt", 9), ("spindown.txt", 10)):
        log = flywheel_log(seed)
        write_ftc_log(tmp_path / name, log.time, log["counts"], log["voltage"], log["current"])
        paths.append(str(tmp_path / name))
    parser = argparse.ArgumentParser()
    add_arguments(parser, "spinup")
    args = parser.parse_args(["--cpr", "560", "--inertia", "7.75 kg*m^2", "--spindown", paths[1]])
    result = from_cli("spinup", paths[:1], args)
    assert result["K"].value == pytest.approx(FLYWHEEL.K, rel=0.015)
    with pytest.raises(OptionError, match="inertia"):
        from_cli("spinup", paths[:1], parser.parse_args(["--cpr", "560"]))


def test_start_after_end_or_outside_the_log_is_refused() -> None:
    log = flywheel_log(5, on_time=20.0, duration=30.0)
    with pytest.raises(OptionError, match=r"--start 8 s.*--end 2 s"):
        spinup(log, inertia=FLYWHEEL.J, cpr=CPR, start=8.0, end=2.0)
    with pytest.raises(OptionError, match=r"--end.*time span") as err:
        spinup(log, inertia=FLYWHEEL.J, cpr=CPR, end=500.0)
    assert err.value.path == "spinup.txt"


def test_current_unit_option_for_logs_in_milliamps(tmp_path, capsys):
    """``--current-unit mA`` (issue 2): a sensor logging mA gives the K of one logging A; K = J·α/i needs it."""
    import json

    from motorlab.cli import main
    from motorlab.io import read_ftc_log, write_ftc_log
    from motorlab.rig import VirtualRig

    run = VirtualRig("neverest40", unit_seed=1, noise_seed=1).spinup(tmp_path / "a.txt", duration=10.0)
    rec = read_ftc_log(run.paths)
    write_ftc_log(tmp_path / "ma.txt", rec.time, rec.signals["counts"], rec.signals["voltage"],
                  rec.signals["current"] * 1e3, header=False)
    inertia = str(run.truth["expected"]["J"]) if "J" in run.truth["expected"] else str(run.truth["totals"]["J"])
    k = {}
    for name, extra in (("a.txt", []), ("ma.txt", ["--current-unit", "mA"])):
        argv = ["analyze", "spinup", str(tmp_path / name), "--cpr", "1120", "--inertia", inertia, "--json", *extra]
        assert main(argv) == 0
        k[name] = json.loads(capsys.readouterr().out)["parameters"]["K"]["value"]
    assert k["ma.txt"] == pytest.approx(k["a.txt"], rel=1e-3)
