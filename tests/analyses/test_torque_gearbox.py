"""Gearbox efficiency and loss torque from a stall-torque test at the output (analyze torque --ratio --K)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from motorlab import cli
from motorlab.analyses.torque import torque
from motorlab.catalog import Motor
from motorlab.errors import OptionError
from motorlab.gearbox import Gearbox
from motorlab.io import read_csv
from motorlab.recording import Recording
from motorlab.rig import VirtualRig


def test_round_trip_efficiency_at_several_etas_and_seeds(tmp_path):
    """Virtual-rig lever tests of gearmotors with known η (0.5-0.95) and τ0, the motor's K given with a 1 %
    standard error (and drawn off by it): η within 0.03 and the truth inside the 95 % interval at the expected
    rate, for η and for the loss torque."""
    motor = Motor.from_catalog("neverest40")
    cases = [(eta, seed) for eta in (0.5, 0.7, 0.95) for seed in range(4)]
    inside_eta = inside_loss = 0
    for eta, seed in cases:
        box = Gearbox(ratio=motor.gear_ratio, efficiency=eta, loss_torque=0.03)
        rig = VirtualRig(motor, unit_seed=seed, noise_seed=seed, gearbox=box)
        run = rig.torque(tmp_path / f"t-{eta}-{seed}.csv")
        k_true = rig.params.K / motor.gear_ratio
        k_se = 0.01 * k_true
        k_given = k_true + k_se * np.random.default_rng(seed).standard_normal()
        result = torque(read_csv(run.paths[0]), ratio=motor.gear_ratio, motor_constant=k_given,
                        motor_constant_stderr=k_se)
        est, loss = result["efficiency"], result["loss_torque"]
        assert est.determined
        assert loss.determined
        assert abs(est.value - eta) < 0.03, (eta, seed)
        assert 0 < est.stderr < 0.03
        assert run.truth["expected"]["efficiency"] == eta
        inside_eta += abs(est.value - eta) <= 1.96 * est.stderr
        inside_loss += abs(loss.value - 0.03) <= 1.96 * loss.stderr
        assert result.details["K_motor"] == k_given
    assert inside_eta >= 0.75 * len(cases)
    assert inside_loss >= 0.75 * len(cases)


def test_k_error_enters_the_efficiency_error():
    current = np.repeat([1.0, 2.0, 3.0, 4.0], 2)
    tau = 0.5 * 40 * 0.0175 * current - 0.02 + np.tile([1e-3, -1e-3], 4)
    rec = Recording(np.arange(current.size, dtype=float), {"current": current, "torque": tau})
    sharp = torque(rec, ratio=40, motor_constant=0.0175)["efficiency"]
    blurred = torque(rec, ratio=40, motor_constant=0.0175, motor_constant_stderr=0.0175 * 0.05)["efficiency"]
    assert sharp.value == pytest.approx(blurred.value)
    assert blurred.stderr == pytest.approx(math.hypot(sharp.stderr, 0.05 * sharp.value), rel=1e-6)


def test_one_current_cannot_separate_efficiency_from_loss_torque():
    current = np.full(6, 2.0)
    tau = 0.6 * 0.7 * current - 0.03 + np.linspace(-1e-3, 1e-3, 6)
    rec = Recording(np.arange(6.0), {"current": current, "torque": tau})
    result = torque(rec, ratio=40, motor_constant=0.7 / 40)
    assert not result["efficiency"].determined
    assert not result["loss_torque"].determined
    apparent = result["apparent_efficiency"]
    assert apparent.determined
    assert apparent.value == pytest.approx(0.6 - 0.03 / (0.7 * 2.0), rel=1e-3)  # a lower bound on η
    assert any("not determined" in w for w in result.warnings)


def test_without_k_the_old_behaviour():
    current = np.array([1.0, 2.0, 3.0])
    rec = Recording(np.arange(3.0), {"current": current, "torque": 0.2 * current + np.array([1e-3, -2e-3, 1e-3])})
    result = torque(rec)
    assert "efficiency" not in result
    assert "loss_torque" not in result
    with pytest.raises(OptionError):
        torque(rec, ratio=0.0, motor_constant=0.01)
    with pytest.raises(OptionError):
        torque(rec, ratio=40, motor_constant=-0.01)


def test_cli_reports_efficiency_in_json(tmp_path, capsys):
    out = tmp_path / "t.csv"
    assert cli.main(["simulate", "torque", "--motor", "neverest40", "--efficiency", "0.6", "-o", str(out)]) == 0
    truth = json.loads((tmp_path / "truth.json").read_text())["runs"]["t.csv"]
    assert truth["gearbox"]["efficiency"] == 0.6
    k_motor = truth["motor_params"]["K"] / 40
    capsys.readouterr()
    code = cli.main(["analyze", "torque", str(out), "--ratio", "40", "--K", f"{k_motor}", "--K-stderr",
                     f"{0.005 * k_motor}", "--json"])
    assert code == 0
    doc = json.loads(capsys.readouterr().out)
    params = doc["parameters"]
    assert params["efficiency"]["value"] == pytest.approx(0.6, abs=0.03)
    assert params["efficiency"]["unit"] == "1"
    assert params["loss_torque"]["value"] == pytest.approx(truth["gearbox"]["loss_torque"], abs=0.01)
    with pytest.raises(SystemExit) as exc:
        cli.main(["analyze", "torque", str(out), "--K", "-1"])
    assert exc.value.code == 2


def test_unphysical_efficiency_is_warned():
    current = np.array([1.0, 2.0, 3.0, 4.0])
    tau = 0.7 * current + np.array([1e-3, -1e-3, 1e-3, -1e-3])  # Kt = 0.7 at the output, but K_m given ÷ 80
    result = torque(Recording(np.arange(4.0), {"current": current, "torque": tau}), ratio=40,
                    motor_constant=0.7 / 80)
    assert result["efficiency"].value > 1
    assert any("exceeds 1" in w for w in result.warnings)


def test_one_current_read_with_meter_noise_is_still_one_current():
    """A meter's scatter around one setpoint (2.002, 1.999 ... A) is no lever to separate η from τ0."""
    current = 2.0 + np.array([0.002, -0.001, 0.0, 0.001, -0.002, 0.001])
    rng = np.random.default_rng(3)
    tau = 0.6 * 0.7 * current - 0.03 + rng.normal(0.0, 2e-3, current.size)
    result = torque(Recording(np.arange(6.0), {"current": current, "torque": tau}), ratio=40,
                    motor_constant=0.7 / 40, motor_constant_stderr=1e-4)
    assert not result["efficiency"].determined
    assert not result["loss_torque"].determined
    assert result["apparent_efficiency"].value == pytest.approx(0.6 - 0.03 / (0.7 * 2.0), rel=0.02)
    assert not any("polarity" in w or "offset" in w for w in result.warnings)


def test_gearbox_options_without_the_motor_k_are_refused():
    current = np.array([1.0, 2.0, 3.0])
    rec = Recording(np.arange(3.0), {"current": current, "torque": 0.2 * current - 0.01})
    with pytest.raises(OptionError, match="--K"):
        torque(rec, ratio=40)
    with pytest.raises(OptionError, match="--K"):
        torque(rec, motor_constant_stderr=1e-4)


def test_with_the_motor_k_the_intercept_is_the_loss_torque_not_an_untared_scale():
    current = np.array([0.5, 1.0, 1.5, 2.0, 2.5, 3.0])
    tau = 0.7 * 0.7 * current - 0.05 + np.array([1e-3, -1e-3, 2e-3, 0.0, -2e-3, 1e-3])
    rec = Recording(np.arange(6.0), {"current": current, "torque": tau})
    assert any("offset" in w for w in torque(rec).warnings)  # without a gearbox: friction or an untared scale
    result = torque(rec, ratio=40, motor_constant=0.7 / 40)
    assert not any("offset" in w for w in result.warnings)
    assert result["loss_torque"].value == pytest.approx(0.05, abs=0.005)
