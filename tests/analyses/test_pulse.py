"""Square-wave pulse analysis (seed 2): J, Tf, b and the friction-model verdict on simulated traces."""

from __future__ import annotations

import math

import numpy as np
import pytest

from motorlab.analyses.pulse import pulse
from motorlab.errors import FitError, LogFormatError, OptionError
from motorlab.io import read_csv, write_csv
from motorlab.model import MotorParams
from motorlab.model.simulate import CurrentDrive, simulate
from motorlab.recording import Recording

KA, KM = 2.0, 0.1  # amplifier [A/V], torque constant [N·m/A]
J_TRUE = 7.0e-4  # the seed's 76 mm aluminium wheel plus the shaft [kg·m²]


def pulse_trace(
    seed: int, *, b: float, tf: float, noise: float = 0.3, period: float = 2.0, duty: float = 0.1, cycles: int = 3,
) -> Recording:
    """The seed's set-up: a 1 V unipolar square wave into a current amplifier (I = Ka·V), the speed
    from a tachometer with noise, read on a scope at 1 kHz with 0.1 rad/s resolution."""
    rng = np.random.default_rng(seed)
    motor = MotorParams(K=KM, R=2.0, L=2e-3, J=J_TRUE, b=b, Tf=tf)
    start = 0.1

    def command(t: np.ndarray) -> np.ndarray:
        t = np.asarray(t, dtype=float)
        return np.where((t >= start) & (np.mod(t - start, period) < duty * period), 1.0, 0.0)

    sim = simulate(motor, CurrentDrive(lambda t: KA * command(t)), duration=cycles * period, dt=1e-3)
    speed = np.round((sim.speed + rng.normal(0, noise, sim.time.size)) / 0.1) * 0.1
    volts = command(sim.time) + rng.normal(0, 0.003, sim.time.size)
    return Recording(sim.time, {"command": volts, "velocity": speed}, source=f"pulse-{seed}.csv")


@pytest.mark.parametrize(
    ("b", "tf", "verdict"),
    [(0.0, 0.02, "coulomb"), (2e-4, 0.02, "both"), (6e-4, 0.0, "viscous")],
)
def test_round_trip_and_friction_verdict(b, tf, verdict):
    seeds = range(4)
    inside = {"J": 0, "Tf": 0, "b": 0}
    for seed in seeds:
        result = pulse(pulse_trace(seed, b=b, tf=tf), amplifier_gain=KA, torque_constant=KM)
        assert result.details["friction_model"] == verdict
        assert result.warnings[0].startswith("Is the shaft friction viscous?")
        assert {row["model"] for row in result.details["friction_models"]} == {"viscous", "coulomb", "both"}
        assert result.value("J") == pytest.approx(J_TRUE, rel=0.01)
        truths = {"J": J_TRUE, "Tf": tf}
        if verdict == "coulomb":
            assert "b" not in result
        else:
            truths["b"] = b
            assert result.value("b") == pytest.approx(b, rel=0.05)
            assert result.value("gamma") == pytest.approx(b / J_TRUE, rel=0.05)
        if tf:
            assert result.value("Tf") == pytest.approx(tf, rel=0.02)
        else:
            assert abs(result.value("Tf")) < 0.002
        for name, value in truths.items():
            est = result[name]
            inside[name] += abs(est.value - value) <= 3 * est.stderr
        assert result.r2 > 0.99
    for name, count in inside.items():
        if name in result:
            assert count >= len(seeds) - 1, name


def test_seed_slope_method_is_kept_in_details():
    result = pulse(pulse_trace(1, b=0.0, tf=0.02), amplifier_gain=KA, torque_constant=KM)
    slopes = result.details["slopes"]
    assert len(slopes) == 3
    for row in slopes:
        assert row["coast_slope"] < 0 < row["accel_slope"]  # Ω̇2 < 0 in the coast (eq. (4))
        assert row["J"] == pytest.approx(J_TRUE, rel=0.03)
        assert row["Tf"] == pytest.approx(0.02, rel=0.05)


def test_tachometer_voltage_file_and_reversed_polarity(tmp_path):
    rec = pulse_trace(2, b=2e-4, tf=0.02)
    kt = 0.03
    path = tmp_path / "scope.csv"
    write_csv(path, {"time_s": rec.time, "command_V": rec["command"], "tach_voltage_V": -kt * rec["velocity"]})
    with pytest.raises(OptionError, match="tach"):
        pulse(read_csv(path), amplifier_gain=KA, torque_constant=KM)
    result = pulse(read_csv(path), amplifier_gain=KA, torque_constant=KM, tach_gain=kt)
    assert result.value("J") == pytest.approx(J_TRUE, rel=0.01)
    assert any("opposite" in w for w in result.warnings)


def test_forced_coulomb_model_on_viscous_data_is_flagged():
    result = pulse(pulse_trace(0, b=2e-4, tf=0.02), amplifier_gain=KA, torque_constant=KM, friction="coulomb")
    assert "b" not in result
    assert any("as asked" in w for w in result.warnings)


def test_bad_input():
    rec = pulse_trace(0, b=0.0, tf=0.02, cycles=1)
    flat = Recording(rec.time, {"command": np.zeros(rec.time.size), "velocity": rec["velocity"]}, source="flat.csv")
    with pytest.raises(FitError, match=r"^flat\.csv: the command never changes"):
        pulse(flat, amplifier_gain=KA, torque_constant=KM)
    # Ka = 1e-300 A/V made J ~ 1e-300 kg·m² and J² underflow: a ZeroDivisionError, now refused.
    with pytest.raises(OptionError, match="--Ka"):
        pulse(rec, amplifier_gain=1e-300, torque_constant=KM)
    with pytest.raises(OptionError, match="--K"):
        pulse(rec, amplifier_gain=KA, torque_constant=1e300)
    with pytest.raises(OptionError):
        pulse(rec, amplifier_gain=0.0, torque_constant=KM)
    with pytest.raises(OptionError):
        pulse(rec, amplifier_gain=KA, torque_constant=KM, friction="sticky")
    with pytest.raises(LogFormatError, match="speed"):
        pulse(Recording(rec.time, {"command": rec["command"]}), amplifier_gain=KA, torque_constant=KM)
    with pytest.raises(LogFormatError, match="command"):
        pulse(Recording(rec.time, {"velocity": rec["velocity"]}), amplifier_gain=KA, torque_constant=KM)
    backwards = Recording(rec.time[::-1].copy(), {"command": rec["command"], "velocity": rec["velocity"]})
    with pytest.raises(LogFormatError, match="time"):
        pulse(backwards, amplifier_gain=KA, torque_constant=KM)
    # Too weak to break away: Ka·Km·V = 0.2 N·m below Tf.
    stuck = pulse_trace(0, b=0.0, tf=0.3, cycles=1)
    with pytest.raises(FitError):
        pulse(stuck, amplifier_gain=KA, torque_constant=KM)


def test_virtual_rig_chain(tmp_path):
    """Amplifier gain and offset from the rig's amplifier file, then the rig's pulse trace.

    The rig's tachometer has commutator ripple, which correlates neighbouring residuals: the
    Newey–West standard errors account for it, and those of Ka, I0 and the held command levels are
    propagated, so the truth lies within 3 standard errors in at least 90 % of the units."""
    from motorlab.analyses.gains import amplifier
    from motorlab.rig import VirtualRig

    inside = {"J": 0, "Tf": 0}
    runs = [(motor, seed) for motor in ("neverest20", "corehex", "neverest37", "gobilda5202_19", "hdhex40")
            for seed in range(2)]
    for motor, seed in runs:
        rig = VirtualRig(motor, unit_seed=seed, noise_seed=seed)
        amp = amplifier(read_csv(rig.amplifier(tmp_path / "amp.csv").paths[0]))
        run = rig.pulse(tmp_path / "pulse.csv")
        truth = run.truth["expected"]
        result = pulse(read_csv(run.paths[0]), amplifier_gain=amp.value("Ka"), amplifier_offset=amp.value("I0"),
                       amplifier_gain_stderr=amp["Ka"].stderr, amplifier_offset_stderr=amp["I0"].stderr,
                       gain_offset_correlation=float(amp.correlation[0, 1]), torque_constant=truth["K"])
        assert result.details["friction_model"] == "both"
        for name, tolerance in (("J", 0.01), ("b", 0.03), ("Tf", 0.03)):
            assert result.value(name) == pytest.approx(truth[name], rel=tolerance), (motor, seed, name)
        for name in inside:
            inside[name] += abs(result.value(name) - truth[name]) <= 3 * result[name].stderr
    for name, count in inside.items():
        assert count >= 0.9 * len(runs), (name, count)


def test_input_uncertainties_are_propagated():
    rec = pulse_trace(1, b=2e-4, tf=0.02)
    exact = pulse(rec, amplifier_gain=KA, torque_constant=KM)
    loose = pulse(rec, amplifier_gain=KA, torque_constant=KM, amplifier_gain_stderr=0.01 * KA,
                  amplifier_offset_stderr=0.002, torque_constant_stderr=0.01 * KM)
    assert loose.value("J") == exact.value("J")
    # J ∝ Ka·Km: 1 % on each adds √2 % in quadrature.
    assert loose["J"].relative_error == pytest.approx(math.hypot(exact["J"].relative_error, 0.01 * math.sqrt(2)),
                                                      rel=0.02)
    assert loose["Tf"].stderr > exact["Tf"].stderr + 0.5 * KM * 0.002
    with pytest.raises(OptionError):
        pulse(rec, amplifier_gain=KA, torque_constant=KM, gain_offset_correlation=1.5)
