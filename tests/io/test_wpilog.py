"""WPILib data logs: the specification's own example bytes, writer round trips, SysId extraction."""

from __future__ import annotations

import math

import numpy as np
import pytest

from motorlab.errors import LogFormatError, OptionError
from motorlab.io.wpilog import (
    WpilogEntry,
    read_wpilog,
    read_wpilog_entries,
    write_sysid_wpilog,
    write_wpilog,
)

# Examples of the WPILib Data Log File Format Specification 1.0 (wpiutil/doc/datalog.adoc).
SPEC_HEADER = bytes.fromhex("57 50 49 4c 4f 47 00 01 00 00 00 00")
SPEC_START = bytes.fromhex(
    "20 00 1a 40 42 0f 00 01 00 00 00 04 00 00 00 74 65 73 74 05 00 00 00 69 6e 74 36 34 00 00 00 00"
)
SPEC_INT = bytes.fromhex("20 01 08 40 42 0f 03 00 00 00 00 00 00 00")
SPEC_METADATA = bytes.fromhex(
    "20 00 18 40 42 0f 02 01 00 00 00 0f 00 00 00 7b 22 73 6f 75 72 63 65 22 3a 22 4e 54 22 7d"
)
SPEC_FINISH = bytes.fromhex("20 00 05 40 42 0f 01 01 00 00 00")


def test_reads_the_specification_examples(tmp_path):
    path = tmp_path / "spec.wpilog"
    # The data record after Finish belongs to no entry and is ignored (with a warning).
    path.write_bytes(SPEC_HEADER + SPEC_START + SPEC_INT + SPEC_METADATA + SPEC_FINISH + SPEC_INT)
    entries = read_wpilog_entries(path)
    assert list(entries) == ["test"]
    entry = entries["test"]
    assert entry.type == "int64"
    assert entry.metadata == '{"source":"NT"}'
    np.testing.assert_array_equal(entry.values, [3.0])
    np.testing.assert_array_equal(entry.timestamps, [1.0])


def test_writer_produces_the_specification_bytes(tmp_path):
    path = tmp_path / "mine.wpilog"
    write_wpilog(path, [WpilogEntry("test", "int64", np.array([1.0]), [3])])
    assert path.read_bytes() == SPEC_HEADER + SPEC_START + SPEC_INT


def test_round_trip_of_every_type(tmp_path):
    rng = np.random.default_rng(0)
    t = np.sort(rng.uniform(0, 100, 20))
    entries = [
        WpilogEntry("d", "double", t, rng.normal(size=20), "Volt"),
        WpilogEntry("f", "float", t, np.float32(rng.normal(size=20)).astype(float)),
        WpilogEntry("i", "int64", t, rng.integers(-(2**40), 2**40, 20).astype(float)),
        WpilogEntry("b", "boolean", t[:3], [True, False, True]),
        WpilogEntry("s", "string", t[:2], ["quasistatic-forward", "ünïcode"]),
        WpilogEntry("da", "double[]", t[:2], [np.array([1.0, 2.0]), np.array([])]),
        WpilogEntry("sa", "string[]", t[:1], [["a", "bc"]]),
        WpilogEntry("ba", "boolean[]", t[:1], [[True, False]]),
        WpilogEntry("r", "raw", t[:1], [b"\x00\x01\xff"]),
    ]
    path = tmp_path / "all.wpilog"
    write_wpilog(path, entries, extra_header="motorlab test")
    back = read_wpilog_entries(path)
    assert list(back) == [e.name for e in entries]
    for entry in entries:
        got = back[entry.name]
        assert got.type == entry.type
        assert got.metadata == entry.metadata
        np.testing.assert_allclose(got.timestamps, np.rint(entry.timestamps * 1e6) * 1e-6)
        if entry.type in ("double", "float", "int64"):
            np.testing.assert_array_equal(got.values, entry.values)
        elif entry.type == "double[]":
            for a, b in zip(got.values, entry.values, strict=True):
                np.testing.assert_array_equal(a, b)
        else:
            assert list(got.values) == list(entry.values)


def sysid_run(rng, *, dt=0.005):
    """Four SysId tests of a flywheel, in SI, with the states SysIdRoutine logs."""
    pieces, states = [], []
    t0 = 0.0
    for name, volts in (
        ("quasistatic-forward", lambda s: 0.5 * s),
        ("quasistatic-reverse", lambda s: -0.5 * s),
        ("dynamic-forward", lambda s: 7.0 + 0 * s),
        ("dynamic-reverse", lambda s: -7.0 + 0 * s),
    ):
        s = np.arange(0, 2.0, dt)
        pieces.append((t0 + s, volts(s)))
        states += [name] * s.size
        t0 += 3.0
    time = np.concatenate([p[0] for p in pieces])
    voltage = np.concatenate([p[1] for p in pieces])
    velocity = 5.0 * voltage + rng.normal(0, 0.1, voltage.size)  # rad/s
    position = np.cumsum(velocity) * dt
    return time, voltage, position, velocity, states


@pytest.mark.parametrize("unit", ["Rotation", "Radian", "Meter"])
def test_sysid_log_round_trip(tmp_path, unit):
    rng = np.random.default_rng(1)
    time, voltage, position, velocity, states = sysid_run(rng)
    path = tmp_path / "sysid.wpilog"
    write_sysid_wpilog(path, time, voltage, position, velocity, states, mechanism="shooter", unit=unit)
    rec = read_wpilog(path)
    assert list(rec.segments) == ["quasistatic-forward", "quasistatic-reverse", "dynamic-forward", "dynamic-reverse"]
    assert rec.metadata["mechanism"] == "shooter"
    assert rec.metadata["entries"]["voltage"] == "voltage-motor-shooter"
    assert rec.metadata["position_unit"] == ("m" if unit == "Meter" else "rad")
    np.testing.assert_allclose(rec.time, np.rint(time * 1e6) * 1e-6)
    np.testing.assert_allclose(rec["voltage"], voltage)
    np.testing.assert_allclose(rec["position"], position, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(rec["velocity"], velocity, rtol=1e-12, atol=1e-12)
    for part in rec.split():
        kind = rec.metadata["segment_kinds"][part.metadata["segment"]]
        assert np.all(part["voltage"] * kind["direction"] >= 0)
        assert len(part) == 400


def test_resampling_takes_the_nearest_sample_and_the_state_logged_with_it(tmp_path):
    t = np.arange(0, 1.0, 0.02) + 1.0
    n = t.size
    # Position refreshed every third loop (a status frame), logged 40 µs after the voltage; the
    # state is appended 10 µs after the voltage, and once more as "none" at the end.
    slow = t[::3] + 40e-6
    states = ["quasistatic-forward"] * (n // 2) + ["dynamic-forward"] * (n - n // 2)
    entries = [
        WpilogEntry("sysid-test-state-arm", "string", np.append(t + 10e-6, t[-1] + 0.05), [*states, "none"]),
        WpilogEntry("voltage-m-arm", "double", t, np.arange(n, dtype=float), "Volt"),
        WpilogEntry("position-m-arm", "double", slow, np.arange(slow.size, dtype=float), "Rotation"),
        WpilogEntry("velocity-m-arm", "double", t + 40e-6, np.full(n, 2.0), '{"source": "NT", "unit": "rpm"}'),
        WpilogEntry("/SystemStats/BatteryVoltage", "double", t, np.full(n, 12.3)),
    ]
    path = tmp_path / "arm.wpilog"
    write_wpilog(path, entries)
    rec = read_wpilog(path)
    assert rec.segments == {"quasistatic-forward": (0, n // 2), "dynamic-forward": (n // 2, n)}
    expected = np.round(np.arange(n) / 3.0)  # nearest refreshed position sample
    np.testing.assert_allclose(rec["position"], expected * 2 * math.pi)
    np.testing.assert_allclose(rec["velocity"], 2.0 * 2 * math.pi / 60)
    assert rec.metadata["velocity_unit"] == "rad/s"
    # Velocity never changes; position changes every third row: 2 of 3 rows repeat.
    assert rec.metadata["repeated_fraction"] == pytest.approx(2 / 3, abs=0.03)


def test_entry_choice_and_units_can_be_given(tmp_path):
    t = np.arange(0, 0.5, 0.01)
    entries = [
        WpilogEntry("sysid-test-state-lift", "string", t[:1], ["dynamic-reverse"]),
        WpilogEntry("voltage-a-lift", "double", t, -np.ones(t.size)),
        WpilogEntry("voltage-b-lift", "double", t, -np.ones(t.size)),
        WpilogEntry("position-a-lift", "double", t, -t),
        WpilogEntry("velocity-a-lift", "double", t, -np.ones(t.size)),
    ]
    path = tmp_path / "lift.wpilog"
    write_wpilog(path, entries)
    with pytest.raises(LogFormatError, match=r"several entries could be the voltage: .*voltage_entry="):
        read_wpilog(path)
    with pytest.raises(LogFormatError, match=r"does not say its unit.*position_unit="):
        read_wpilog(path, voltage_entry="voltage-a-lift")
    rec = read_wpilog(path, voltage_entry="voltage-a-lift", position_unit="inch")
    np.testing.assert_allclose(rec["velocity"], -0.0254)
    assert rec.metadata["position_unit"] == "m"
    assert list(rec.segments) == ["dynamic-reverse"]
    with pytest.raises(OptionError, match="not in"):
        read_wpilog(path, voltage_entry="volts")
    with pytest.raises(OptionError, match="angle or a length"):
        read_wpilog(path, voltage_entry="voltage-a-lift", position_unit="kg")


def test_repeated_tests_get_numbered_segments(tmp_path):
    t = np.arange(0, 0.6, 0.01)
    states = ["quasistatic-forward"] * 20 + ["none"] * 20 + ["quasistatic-forward"] * 20
    write_sysid_wpilog(tmp_path / "r.wpilog", t, np.ones(t.size), t, np.ones(t.size), states)
    rec = read_wpilog(tmp_path / "r.wpilog")
    assert rec.segments == {"quasistatic-forward": (0, 20), "quasistatic-forward#2": (40, 60)}
    assert rec.metadata["segment_kinds"]["quasistatic-forward#2"] == {"kind": "quasistatic", "direction": 1}


def test_truncated_log_keeps_complete_records(tmp_path):
    t = np.arange(0, 1.0, 0.01)
    path = tmp_path / "cut.wpilog"
    write_sysid_wpilog(path, t, np.ones(t.size), t, np.ones(t.size), ["dynamic-forward"] * t.size)
    data = path.read_bytes()
    path.write_bytes(data[:-5])  # power lost in the middle of the last record
    rec = read_wpilog(path)
    assert len(rec) == t.size  # the velocity record that was cut is the last one: nearest is used
    assert any("cut off" in w for w in rec.metadata["warnings"])


def test_bad_logs(tmp_path):
    path = tmp_path / "bad.wpilog"
    path.write_bytes(b"")
    with pytest.raises(LogFormatError, match="empty"):
        read_wpilog(path)
    path.write_text("time_s,voltage_V\n0,1\n")
    with pytest.raises(LogFormatError, match="not a WPILib data log"):
        read_wpilog(path)
    path.write_bytes(b"WPILOG\x00\x02\x00\x00\x00\x00")
    with pytest.raises(LogFormatError, match=r"unsupported data log version 2\.0"):
        read_wpilog(path)
    # A Start record whose name length (255) runs past the record's 10-byte payload.
    path.write_bytes(SPEC_HEADER + bytes.fromhex("20 00 0a 40 42 0f 00 01 00 00 00 ff 00 00 00 78"))
    with pytest.raises(LogFormatError, match="malformed control record at byte 12: entry name runs past"):
        read_wpilog_entries(path)
    path.write_bytes(SPEC_HEADER + SPEC_START + SPEC_INT)
    with pytest.raises(LogFormatError, match="no SysId test-state entry"):
        read_wpilog(path)
    t = np.arange(0, 0.1, 0.01)
    write_wpilog(path, [
        WpilogEntry("sysid-test-state-x", "string", t, ["none"] * t.size),
        WpilogEntry("voltage-m-x", "double", t, np.ones(t.size), "Volt"),
        WpilogEntry("position-m-x", "double", t, np.where(t > 0.05, np.nan, t), "Rotation"),
        WpilogEntry("velocity-m-x", "double", t, np.ones(t.size), "Rotation per Second"),
    ])
    with pytest.raises(LogFormatError, match=r"position entry 'position-m-x' has a non-finite value at t = 0\.06"):
        read_wpilog(path)
    with pytest.raises(OptionError, match="duplicate"):
        write_wpilog(path, [WpilogEntry("a", "double", t, t), WpilogEntry("a", "double", t, t)])


def test_velocity_entry_metadata_wins_when_the_position_unit_is_given(tmp_path):
    """Position without metadata (unit given by the user), velocity logged in rpm: read as rpm."""
    t = np.arange(0, 0.5, 0.01)
    entries = [
        WpilogEntry("sysid-test-state-arm", "string", t[:1], ["quasistatic-forward"]),
        WpilogEntry("voltage-arm", "double", t, np.ones(t.size)),
        WpilogEntry("position-arm", "double", t, t),
        WpilogEntry("velocity-arm", "double", t, np.full(t.size, 60.0), metadata="rpm"),
    ]
    path = tmp_path / "arm.wpilog"
    write_wpilog(path, entries)
    rec = read_wpilog(path, position_unit="rotation")
    np.testing.assert_allclose(rec["velocity"], 2 * np.pi)  # 60 rpm = 1 rev/s = 2π rad/s
