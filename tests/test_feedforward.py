"""Round trips, coverage, conversions and real SysId data for motorlab.feedforward."""

from __future__ import annotations

import argparse
import math

import numpy as np
import pytest

from motorlab.errors import OptionError
from motorlab.feedforward import (
    add_arguments,
    feedforward,
    from_cli,
    gains_from_params,
    motor_estimates,
    params_from_gains,
    sysid_ols,
)
from motorlab.model import MotorParams
from motorlab.recording import Recording
from motorlab.simulate import VoltageDrive, simulate

# An FTC-like gearmotor with a flywheel, at the output shaft: τm = kA/kV ≈ 0.1 s
MOTOR = MotorParams(K=0.35, R=2.5, L=7e-4, J=5e-3, b=2e-3, Tf=0.03)
GAINS = gains_from_params(MOTOR)
CPR = 560


def sysid_tests(seed: int, *, params: MotorParams = MOTOR, gravity: float = 0.0, voltage_noise: float = 0.02,
                tests: tuple[str, ...] = ("slow-forward", "slow-backward", "fast-forward", "fast-backward"),
                ) -> list[Recording]:
    """SysId's four tests logged every 10 ms: 1 V/s ramps for 6 s and 6 V steps for 2 s.

    The encoder (560 counts/rev at the output) is counted (floor, random phase); the logged voltage
    carries 0.02 V of noise. ``gravity`` [V] is an elevator's constant load, simulated as a voltage
    the motor must overcome (V − kG drives the plant).
    """
    rng = np.random.default_rng(seed)
    q = 2 * math.pi / CPR
    recs = []
    for name in tests:
        sign = 1.0 if name.endswith("forward") else -1.0
        if name.startswith("slow"):
            duration = 6.0

            def command(t, s=sign):
                return s * 1.0 * t
        else:
            duration = 2.0

            def command(t, s=sign):
                return s * 6.0 * np.ones_like(t)

        sim = simulate(params, VoltageDrive(lambda t, c=command: c(t) - gravity), duration=duration, dt=0.01)
        counts = np.floor((sim.position + rng.uniform(0.0, q)) / q)
        volts = sim.voltage + gravity + voltage_noise * rng.standard_normal(sim.time.size)
        recs.append(Recording(sim.time, {"voltage": volts, "position": counts * q, "counts": counts},
                              metadata={"cpr": CPR}, source=f"sim-{seed}:{name}"))
    return recs


def test_gain_conversions_round_trip():
    gains = gains_from_params(MOTOR)
    assert gains["kS"] == pytest.approx(MOTOR.R * MOTOR.Tf / MOTOR.K)
    back = params_from_gains(gains["kS"], gains["kV"], gains["kA"], resistance=MOTOR.R, torque_constant=MOTOR.K)
    for name in ("K", "R", "J", "b", "Tf"):
        assert getattr(back, name) == pytest.approx(getattr(MOTOR, name), rel=1e-12)
    with pytest.raises(OptionError):
        params_from_gains(0.1, 0.3, 0.01, resistance=0.0)


@pytest.mark.parametrize("seed", [1, 2])
def test_round_trip_meets_accuracy_targets(seed):
    recs = sysid_tests(seed)
    result = feedforward(recs)
    targets = {"kS": 0.02, "kV": 0.005, "kA": 0.02}
    for name, tol in targets.items():
        est = result[name]
        assert est.determined
        assert abs(est.value / GAINS[name] - 1) < tol, (name, est)
        assert abs(est.value - GAINS[name]) < 4 * est.stderr, (name, est)
    ols = result.details["sysid_ols"]
    assert abs(ols["kA"] / GAINS["kA"] - 1) > abs(result.value("kA") / GAINS["kA"] - 1)
    assert not result.warnings
    assert [p.y_label for p in result.panels] == ["θ [rad]", "ω [rad/s]"]


def test_coverage_of_95_percent_intervals():
    inside: dict[str, list[bool]] = {}
    for seed in range(50):
        result = feedforward(sysid_tests(500 + seed))
        for name, truth in GAINS.items():
            lo, hi = result[name].interval(1.96)
            inside.setdefault(name, []).append(lo <= truth <= hi)
    for name, hits in inside.items():
        assert 0.90 <= np.mean(hits) <= 0.98, (name, np.mean(hits))


def test_elevator_gravity_term():
    recs = sysid_tests(3, gravity=1.5)
    result = feedforward(recs, mechanism="elevator")
    assert abs(result.value("kG") - 1.5) < 4 * result["kG"].stderr
    assert abs(result.value("kV") / GAINS["kV"] - 1) < 0.01


def test_motor_estimates_follow_what_is_given():
    result = feedforward(sysid_tests(4))
    none = motor_estimates(result, resistance=None, torque_constant=None)
    assert not any(e.determined for e in none.values())
    r_only = motor_estimates(result, resistance=MOTOR.R, torque_constant=None)
    assert r_only["R"].determined
    assert not r_only["K"].determined
    assert not r_only["J"].determined
    assert "K ≤" in r_only["K"].note
    both = motor_estimates(result, resistance=MOTOR.R, torque_constant=MOTOR.K)
    assert abs(both["J"].value / MOTOR.J - 1) < 0.03
    assert abs(both["Tf"].value / MOTOR.Tf - 1) < 0.05


def test_excitation_warnings():
    steps_only = feedforward(sysid_tests(5, tests=("fast-forward", "fast-backward")))
    assert any("kS from kV" in w or "separate static" in w for w in steps_only.warnings)
    ramps_only = feedforward(sysid_tests(6, tests=("slow-forward", "slow-backward")))
    assert any("no acceleration event" in w for w in ramps_only.warnings)


def test_unknown_mechanism_raises():
    with pytest.raises(OptionError):
        feedforward(sysid_tests(7, tests=("fast-forward",)), mechanism="turret")


def test_real_sysid_flywheel(real_dir):
    from motorlab.io import read_sysid_json

    runs = read_sysid_json(real_dir / "sysid-flywheel.json").split()
    assert len(runs) == 4
    result = feedforward(runs)
    ols = sysid_ols(runs)
    for name in ("kS", "kV", "kA"):
        assert result[name].determined, name
        assert result.value(name) > 0, name
    # the published method and this one agree where the data are informative
    assert abs(result.value("kV") / ols["kV"] - 1) < 0.05
    assert abs(result.value("kS") / ols["kS"] - 1) < 0.2


def test_cli_on_sysid_json(real_dir):
    parser = argparse.ArgumentParser()
    add_arguments(parser, "feedforward")
    args = parser.parse_args(["--R", "0.1"])
    result = from_cli("feedforward", [str(real_dir / "sysid-flywheel.json")], args)
    assert result.experiment == "feedforward"
    assert result["R"].value == pytest.approx(0.1)
    assert not result["K"].determined
    assert result.to_dict()["parameters"]["kV"]["unit"] == "V*s/rad"


# --------------------------------------------------------------------------------------------------
# the virtual dynamometer's own SysId files
# --------------------------------------------------------------------------------------------------

TARGETS = {"kS": 0.02, "kV": 0.005, "kA": 0.02}


def _rig_sysid(tmp_path, motor: str, seed: int, **settings):
    from motorlab.identify import read_runs
    from motorlab.rig import VirtualRig
    from motorlab.rig.flywheel import Flywheel

    ratio = settings.pop("ratio", None)
    rig = VirtualRig(motor, unit_seed=seed % 5, noise_seed=seed,
                     flywheel=None if ratio is None else Flywheel(ratio=ratio))
    run = rig.sysid(tmp_path / "sysid.json", **settings)
    return feedforward(read_runs([str(run.paths[0])], cpr=None)), run.truth["expected"]


@pytest.mark.parametrize("seed", range(6))
def test_rig_sysid_ftc_like_meets_accuracy_targets(tmp_path, seed):
    """FTC-like rig files: 560 counts/rev at the output, rows every 10 ms, 0.02 V on the logged voltage.

    The NeveRest 20 with the steel disc straight on its output shaft (τm = kA/kV ≈ 0.18 s: kA is
    observable at 10 ms), 0.5 V/s ramps for 14 s and 7 V steps for 2 s. The rig's controller also
    repeats 20 ms status frames (the angle lags by up to a frame) and jitters the rows by 0.3 ms.
    With 1 V/s ramps the frames' unknown phase (±5 ms of lag) leaves kS within ≈ 3 %.
    """
    result, truth = _rig_sysid(tmp_path, "neverest20", seed, ratio=1.0, ramp_rate=0.5,
                               quasistatic_duration=14.0, dynamic_duration=2.0)
    assert result.details["status_frames"]["period_s"] == pytest.approx(0.02, rel=0.15)
    for name, tolerance in TARGETS.items():
        est = result[name]
        assert est.determined, name
        assert abs(est.value / truth[name] - 1) < tolerance, (name, est, truth[name])
        assert abs(est.value - truth[name]) < 3.5 * est.stderr, (name, est, truth[name])
    assert not result.warnings


def test_rig_sysid_default_flywheel_file(tmp_path):
    """``motorlab simulate sysid`` as it comes: flywheel through the 25:1 gearbox, τm ≈ 20 s.

    kV = K + R·b/K is far above K here (b·N² of the flywheel bearings), as it should be.
    """
    result, truth = _rig_sysid(tmp_path, "neverest40", 1)
    assert truth["kV"] > 1.2 * truth["K"]
    for name, tolerance in TARGETS.items():
        est = result[name]
        assert abs(est.value / truth[name] - 1) < tolerance, (name, est, truth[name])
        assert abs(est.value - truth[name]) < 3.5 * est.stderr, (name, est, truth[name])
    assert result.details["residual_rms"]["position"] < 0.05
