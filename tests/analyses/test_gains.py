"""Amplifier and tachometer gains: round trips, intercepts, nominal comparison, bad input."""

from __future__ import annotations

import numpy as np
import pytest

from motorlab.analyses.gains import amplifier, fit_straight_line, tachometer
from motorlab.errors import FitError, LogFormatError
from motorlab.io import read_csv, write_csv
from motorlab.recording import Recording


def amplifier_rows(seed: int, *, ka: float = 1.94, offset: float = 0.0) -> Recording:
    """DMM readings [A] (1 mA resolution, 0.3 % gain noise) at inputs 0.25…2.25 V."""
    rng = np.random.default_rng(seed)
    v = np.arange(0.25, 2.3, 0.25)
    i = ka * v * (1 + rng.normal(0, 0.003, v.size)) + offset
    return Recording(np.arange(v.size, dtype=float), {"command": v, "current": np.round(i, 3)}, source="amp.csv")


def tach_rows(seed: int, *, kt: float = 0.0286) -> Recording:
    """Optical tachometer [rpm, 0.1 rpm resolution] and DMM [V, 1 mV] at several speeds."""
    rng = np.random.default_rng(seed)
    rpm = np.array([200.0, 400, 600, 900, 1200, 1500, 1800])
    w = rpm * 2 * np.pi / 60 * (1 + rng.normal(0, 0.002, rpm.size))
    volts = np.round(kt * w + rng.normal(0, 0.002, rpm.size), 3)
    return Recording(np.arange(rpm.size, dtype=float), {"speed": np.round(w, 2), "tach_voltage": volts})


def test_amplifier_round_trip():
    seeds = range(12)
    inside = 0
    for seed in seeds:
        result = amplifier(amplifier_rows(seed))
        ka = result["Ka"]
        assert ka.unit == "A/V"
        assert ka.value == pytest.approx(1.94, rel=0.01)
        inside += abs(ka.value - 1.94) <= 3 * ka.stderr
        assert set(result.parameters) == {"Ka", "I0"}
    assert inside >= 0.9 * len(seeds)


def test_amplifier_nominal_and_offset_warnings():
    near = amplifier(amplifier_rows(1), nominal=2.0)
    assert not near.warnings  # 3 % off the nominal 2 A/V: fine
    far = amplifier(amplifier_rows(1, ka=1.5), nominal=2.0)
    assert any("nominal" in w for w in far.warnings)
    assert far.details["relative_difference_from_nominal"] == pytest.approx(-0.25, abs=0.01)
    offset = amplifier(amplifier_rows(2, offset=0.1))
    assert offset.value("I0") == pytest.approx(0.1, abs=0.02)
    assert any("intercept" in w for w in offset.warnings)


def test_tachometer_round_trip_and_file(tmp_path):
    inside = 0
    for seed in range(10):
        result = tachometer(tach_rows(seed))
        est = result["Kt_tach"]
        assert est.unit == "V*s/rad"
        assert est.value == pytest.approx(0.0286, rel=0.01)
        inside += abs(est.value - 0.0286) <= 3 * est.stderr
    assert inside >= 9
    rec = tach_rows(0)
    path = tmp_path / "tach.csv"
    write_csv(path, {"speed_rpm": rec["speed"] * 60 / (2 * np.pi), "tach_voltage_V": rec["tach_voltage"]})
    assert tachometer(read_csv(path)).value("Kt_tach") == pytest.approx(tachometer(rec).value("Kt_tach"), rel=1e-9)


def test_two_rows_give_no_uncertainty():
    rec = Recording(np.arange(2.0), {"command": np.array([1.0, 2.0]), "current": np.array([2.0, 4.1])})
    result = amplifier(rec)
    assert result.value("Ka") == pytest.approx(2.1)
    assert np.isnan(result["Ka"].stderr)
    assert any("two rows" in w for w in result.warnings)


def test_bad_input():
    with pytest.raises(FitError):
        amplifier(Recording(np.arange(1.0), {"command": np.ones(1), "current": np.ones(1)}))
    with pytest.raises(FitError, match="same"):
        fit_straight_line(np.ones(4), np.arange(4.0))
    with pytest.raises(LogFormatError, match="current"):
        amplifier(Recording(np.arange(3.0), {"command": np.ones(3)}, source="a.csv"))
    with pytest.raises(LogFormatError, match="tach_voltage"):
        tachometer(Recording(np.arange(3.0), {"speed": np.ones(3)}))


def test_virtual_rig_files(tmp_path):
    from motorlab.rig import VirtualRig

    for seed in range(3):
        rig = VirtualRig("neverest40", unit_seed=seed, noise_seed=seed)
        amp_run = rig.amplifier(tmp_path / f"amp-{seed}.csv")
        amp = amplifier(read_csv(amp_run.paths[0]), nominal=2.0)
        truth = amp_run.truth["expected"]
        assert amp.value("Ka") == pytest.approx(truth["Ka"], rel=0.005)
        assert abs(amp.value("Ka") - truth["Ka"]) <= 3 * amp["Ka"].stderr
        assert amp.value("I0") == pytest.approx(truth["offset"], abs=5 * amp["I0"].stderr)
        assert not any("nominal" in w for w in amp.warnings)  # 2 % low: within the tolerance
        tach_run = rig.tachometer(tmp_path / f"tach-{seed}.csv")
        tach = tachometer(read_csv(tach_run.paths[0]))
        k_true = tach_run.truth["expected"]["Kt_tach"]
        assert tach.value("Kt_tach") == pytest.approx(k_true, rel=0.01)
        assert abs(tach.value("Kt_tach") - k_true) <= 3 * tach["Kt_tach"].stderr
