"""Road Runner FlightRecorder .log: schema/message decoding (LogFile.kt), runs for feedforward."""

from __future__ import annotations

import struct

import numpy as np
import pytest

from motorlab.analyses.feedforward import feedforward
from motorlab.errors import LogFormatError
from motorlab.io import detect_format, read_any, read_flight_log_channels, write_flight_log
from motorlab.rig.ftc import simulate_flight_log


def _s(text: str) -> bytes:
    raw = text.encode()
    return struct.pack(">i", len(raw)) + raw


def _entry_schema(channel: str, version: int) -> bytes:
    # struct {b: boolean, n: enum{A, BB}, x: int, xs: array<double>, y: long} (fields sorted by name)
    schema = struct.pack(">ii", 0, 5)
    schema += _s("b") + struct.pack(">i", 5)
    schema += _s("n") + struct.pack(">ii", 6, 2) + _s("A") + _s("BB")
    schema += _s("x") + struct.pack(">i", 1)
    schema += _s("xs") + struct.pack(">ii", 7, 3)
    schema += _s("y") + struct.pack(">i", 2)
    pad = b"\0" * 4 if version == 0 else b""  # version 0 reserved 4 bytes too many per array schema
    return struct.pack(">i", 0) + _s(channel) + schema + pad


def _message(index: int) -> bytes:
    return (struct.pack(">ii", 1, index) + b"\x01" + struct.pack(">i", 1) + struct.pack(">i", -7)
            + struct.pack(">idd", 2, 1.5, -2.0) + struct.pack(">q", 2**40))


@pytest.mark.parametrize("version", [0, 1])
def test_decodes_the_spec(tmp_path, version):
    raw = b"RR" + struct.pack(">h", version) + _entry_schema("CH", version) + _message(0) + _message(0)
    raw += struct.pack(">i", 0) + _s("T") + struct.pack(">i", 3) + struct.pack(">iid", 1, 1, 0.25)
    path = tmp_path / "a.log"
    path.write_bytes(raw)
    assert detect_format(path) == "roadrunner-log"
    channels, warnings = read_flight_log_channels(path)
    assert not warnings
    assert channels["CH"].messages == [{"b": True, "n": "BB", "x": -7, "xs": [1.5, -2.0], "y": 2**40}] * 2
    assert channels["T"].messages == [0.25]


def test_writer_round_trip_and_cut_off_file(tmp_path):
    path = tmp_path / "w.log"
    msgs = [("P", {"timestamp": 10**12, "x": 1.0, "ok": False}), ("Q", [1, 2, 3]), ("P", {"timestamp": 5, "x": 2.0,
                                                                                      "ok": True})]
    write_flight_log(path, msgs)
    channels, _ = read_flight_log_channels(path)
    assert [m["x"] for m in channels["P"].messages] == [1.0, 2.0]
    assert channels["Q"].messages == [[1, 2, 3]]
    raw = path.read_bytes()
    path.write_bytes(raw[:-3])  # the robot lost power mid-write
    channels, warnings = read_flight_log_channels(path)
    assert len(channels["P"].messages) == 1
    assert "cut off" in warnings[0]


def test_bad_logs(tmp_path):
    bad = tmp_path / "b.log"
    bad.write_bytes(b"RR\x00\x01" + struct.pack(">i", 9))
    with pytest.raises(LogFormatError, match=r"b\.log: byte 4: unknown entry tag 9"):
        read_flight_log_channels(bad)
    bad.write_bytes(b"RR\x00\x01" + struct.pack(">ii", 1, 0))
    with pytest.raises(LogFormatError, match="only 0 channels"):
        read_flight_log_channels(bad)
    bad.write_bytes(b"RR\x00\x07")
    with pytest.raises(LogFormatError, match="version 7"):
        read_flight_log_channels(bad)
    write_flight_log(bad, [("POSE", {"timestamp": 1, "x": 0.0})])
    with pytest.raises(LogFormatError, match="no drive commands"):
        read_any(bad, cpr=537.7)


def test_feedforward_from_an_ordinary_run(tmp_path):
    path = tmp_path / "auto.log"
    truth = simulate_flight_log(path, seed=4)
    rec = read_any(path, cpr=truth["cpr"])
    assert sorted(rec.segments) == ["leftBack#1", "leftFront#1", "rightBack#1", "rightFront#1"]
    result = feedforward(rec.split()[:1], cpr=truth["cpr"])
    assert result["kS"].value == pytest.approx(truth["kS"], rel=0.05)
    assert result["kV"].value == pytest.approx(truth["kV"], rel=0.01)
    # commands are logged at most every 50 ms: kA carries an interpolation error its stderr leaves out
    assert result["kA"].value == pytest.approx(truth["kA"], rel=0.1)
    assert any("interpolated" in w for w in rec.metadata["warnings"])


@pytest.mark.parametrize(("wheels", "channel"), [(3, "THREE_DEAD_WHEEL_INPUTS"), (2, "TWO_DEAD_WHEEL_INPUTS")])
def test_dead_wheel_runs_give_wheel_travel_in_dead_wheel_ticks(tmp_path, wheels, channel):
    path = tmp_path / "auto-dw.log"
    truth = simulate_flight_log(path, seed=3 + wheels, dead_wheels=wheels)
    channels, _ = read_flight_log_channels(path)
    assert channel in channels
    rec = read_any(path, cpr=truth["cpr"])
    assert len(rec.segments) == 4
    result = feedforward(rec.split()[:1], cpr=truth["cpr"])
    assert result["kS"].value == pytest.approx(truth["kS"], rel=0.05)
    assert result["kV"].value == pytest.approx(truth["kV"], rel=0.01)
    assert result["kA"].value == pytest.approx(truth["kA"], rel=0.1)


def test_two_dead_wheel_travel_follows_the_localizer_twist():
    """x = par − parY·ψ, y = perp − perpX·ψ, ψ the unwrapped IMU yaw; then MecanumKinematics.inverse."""
    from motorlab.io.flightrecorder import Channel, _two_dead_wheel_travel

    psi = np.linspace(0.0, 7.0, 50)  # more than a turn: the IMU's yaw wraps at ±π
    x, y = 300.0 * psi**2, -40.0 * psi
    par_y, perp_x, tw, lm = 1500.0, -900.0, 12000.0, 1.2
    yaw = np.angle(np.exp(1j * psi))
    inputs = Channel("TWO_DEAD_WHEEL_INPUTS", (), [
        {"par": {"position": x[k] + par_y * psi[k]}, "perp": {"position": y[k] + perp_x * psi[k]}, "yaw": yaw[k]}
        for k in range(psi.size)])
    channels = {"TWO_DEAD_WHEEL_INPUTS": inputs,
                "TWO_DEAD_WHEEL_PARAMS": Channel("p", (), [{"parYTicks": par_y, "perpXTicks": perp_x}]),
                "MECANUM_PARAMS": Channel("m", (), [{"inPerTick": 1.2e-3, "lateralInPerTick": 1e-3,
                                                     "trackWidthTicks": tw}])}
    travel = _two_dead_wheel_travel(channels)
    np.testing.assert_allclose(travel["leftFront"], x - y * lm - psi * tw, atol=1e-6)
    np.testing.assert_allclose(travel["rightFront"], x + y * lm + psi * tw, atol=1e-6)
