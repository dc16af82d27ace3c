"""Road Runner ramp logs: reader, 16-bit velocity repair, errors (format: road-runner-ftc Tuning.kt)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from motorlab.cli import main
from motorlab.errors import LogFormatError, OptionError
from motorlab.io import detect_format, read_any, read_roadrunner_ramp
from motorlab.io.roadrunner import (
    RampData,
    drive_voltage,
    held_voltage,
    power_effect_times,
    read_ramp_data,
    repair_velocity,
)
from motorlab.rig.ftc import simulate_ramp, wrap_int16


@pytest.fixture(scope="module")
def ramp(tmp_path_factory):
    path = tmp_path_factory.mktemp("rr") / "forward-ramp.json"
    truth = simulate_ramp(path, seed=3)
    return path, truth


def test_repair_recovers_wrapped_hub_velocities():
    rng = np.random.default_rng(0)
    true = 20 * rng.integers(-12_000, 12_000, 2000)  # up to ±240 000 ticks/s, multiples of 20
    wrapped = wrap_int16(true)
    assert np.any(wrapped != true)
    estimate = true + rng.normal(0, 40_000, true.size)  # central differences can be this far off
    np.testing.assert_array_equal(repair_velocity(wrapped, estimate), true)
    # negated readings (a reversed encoder) are recovered too
    np.testing.assert_array_equal(repair_velocity(-wrapped, -estimate), -true)


def test_reader_gives_voltage_position_and_repaired_velocity(ramp):
    path, truth = ramp
    assert truth["wrapped_samples"] > 50  # the simulated dead wheels do overflow
    assert detect_format(path) == "roadrunner-ramp"
    rec = read_any(path, cpr=truth["cpr"])
    data = read_ramp_data(path)
    raw = json.loads(path.read_text())
    n = len(raw["voltages"]["values"])
    assert len(rec) == n - 3  # the tuning page drops the first sample and the last two
    power = np.mean([np.asarray(p["values"])[1:-2] for p in raw["powers"]], axis=0)
    assert np.all(np.diff([p["values"][100] for p in raw["powers"]]) > 0)  # power(t.seconds()) per motor
    applied = power * np.asarray(raw["voltages"]["values"])[1:-2]
    np.testing.assert_allclose(drive_voltage(data), applied)
    # the recording holds each interval's mean (the next powers act for the end of the interval)
    np.testing.assert_allclose(rec["voltage"], applied, rtol=0.02, atol=0.03)
    assert np.mean(rec["voltage"][:-1] - applied[:-1]) > 0  # a ramp: the next power is higher
    counts = np.mean([np.asarray(p["values"])[1:-2] for p in raw["forwardEncPositions"]], axis=0)
    np.testing.assert_allclose(rec["position"], counts * 2 * math.pi / truth["cpr"])
    assert rec.metadata["repaired"]
    assert rec.metadata["warnings"]
    speed = np.gradient(rec["counts"], rec.time)
    assert all(np.all(np.mod(v, 20) == 0) for v in data.velocities.values())
    vel = np.mean(list(data.velocities.values()), axis=0)
    assert np.median(np.abs(vel - speed)) < 0.02 * np.max(np.abs(speed))  # no wrap left
    assert np.all(drive_voltage(data) >= 0)


def test_needs_cpr_and_names_the_file(ramp, capsys):
    path, _ = ramp
    with pytest.raises(OptionError, match="--cpr"):
        read_roadrunner_ramp(path)
    assert main(["analyze", "feedforward", str(path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert "cpr" in err[0]


def test_lowercase_drive_type_and_missing_flags(tmp_path, ramp):
    path, truth = ramp
    raw = json.loads(path.read_text())
    raw["type"] = "mecanum"
    del raw["forwardEncFixVels"]  # older files: every encoder is repaired
    other = tmp_path / "old.json"
    other.write_text(json.dumps(raw))
    rec = read_roadrunner_ramp(other, cpr=truth["cpr"])
    assert rec.metadata["drive"] == "mecanum"
    assert rec.metadata["repaired"]


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda d: d.pop("voltages"), "not a Road Runner ramp"),
        (lambda d: d["powers"][1]["values"].pop(), "times but"),
        (lambda d: d.__setitem__("type", "SWERVE"), "neither mecanum nor tank"),
        (lambda d: d["forwardEncPositions"][0].__setitem__("values", "x"), "lists of numbers"),
        (lambda d: d.__setitem__("forwardEncFixVels", [True]), "true/false"),
    ],
)
def test_bad_files_give_one_clear_error(tmp_path, ramp, edit, message):
    path, truth = ramp
    raw = json.loads(path.read_text())
    edit(raw)
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(raw, indent=2))
    with pytest.raises(LogFormatError, match=message) as info:
        read_roadrunner_ramp(bad, cpr=truth["cpr"])
    assert "bad.json" in str(info.value)


def test_truncated_json_names_the_line(tmp_path, ramp):
    path, truth = ramp
    bad = tmp_path / "cut.json"
    bad.write_text(path.read_text()[:5000])
    with pytest.raises(LogFormatError, match=r"cut.json:\d+: not valid JSON"):
        read_roadrunner_ramp(bad, cpr=truth["cpr"])


def test_real_hub_overflow_log_is_repaired(real_dir):
    """Road Runner's own test data for its velocity-overflow repair (../shared/data/real/roadrunner-encoder)."""
    path = real_dir / "roadrunner-encoder" / "enc1.csv"
    raw = np.genfromtxt(path, delimiter=",", skip_header=1)
    pos, vel, t = raw[:, 0], raw[:, 1], raw[:, 2]
    estimate = np.gradient(pos, t)
    assert np.all(np.abs(vel) < 2**15)
    assert np.median(np.abs(estimate)) > 2e5
    fixed = repair_velocity(vel, estimate)
    assert np.all(np.mod(fixed - vel, 2**16) == 0)  # only whole wraps added
    assert np.all(np.mod(fixed, 20) == 0)  # the hub's 50 ms window
    inner = slice(1, -1)
    assert np.median(np.abs(fixed[inner] - estimate[inner]) / np.abs(estimate[inner])) < 0.01


def test_first_power_time_is_extrapolated_past_the_idle_split():
    """MidpointTimer: the first setPower's split also spans the end of the previous iteration."""
    starts = np.arange(10) * 0.03  # each iteration: 10 ms idle, then four 2 ms setPowers, a 2 ms battery read
    ends = starts[:, None] + 0.010 + 0.002 * np.arange(1, 6)[None, :]
    previous = np.concatenate([[0.0], ends[:-1, -1]])
    mids = 0.5 * (np.column_stack([previous, ends[:, :-1]]) + ends)
    names = ["powers0", "powers1", "powers2", "powers3"]
    data = RampData(kind="forward", drive="mecanum", time=ends[:, -1] + 0.001, battery=np.full(10, 12.0),
                    powers=dict.fromkeys(names, 0.1 * starts), positions={}, velocities={},
                    power_times={k: mids[:, i] for i, k in enumerate(names)}, voltage_time=mids[:, 4])
    effect = power_effect_times(data)
    assert mids[3, 0] < ends[3, 0] - 0.004  # as logged: 5 ms before the command's middle
    np.testing.assert_allclose(effect["powers0"], ends[:, 0] - 0.001, atol=1e-12)  # the command's middle
    np.testing.assert_allclose(effect["powers2"], ends[:, 2] - 0.001, atol=1e-12)
    # each motor holds its old power until the new one acts: the interval means
    held = held_voltage(data)
    dt = np.diff(data.time)
    expected = np.mean([0.1 * starts[:-1] + 0.1 * 0.03 * (data.time[1:] - effect[k][1:]) / dt for k in names], axis=0)
    np.testing.assert_allclose(held[:-1], 12.0 * expected, rtol=1e-12)
