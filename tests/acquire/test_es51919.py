"""The ES51919 packet decoder against hand-assembled packets (libsigrok's layout) and the resynchroniser."""

from __future__ import annotations

import math

import pytest

from motorlab.acquire.es51919 import PACKET_SIZE, PacketError, PacketReader, decode, display_bytes, encode


def _packet(flags: int, config: int, primary: bytes, secondary: bytes, tolerance: int = 0) -> bytes:
    return b"\x00\x0d" + bytes([flags, config, tolerance]) + primary + secondary + b"\x0d\x0a"


def test_decodes_hand_assembled_inductance_with_q() -> None:
    # 1 kHz (code 2 in bits 5-7, bit 4 set as the meter sends), auto range, series.
    # Primary: L (1), count 0x08A6 = 2214, unit mH (6) with 3 decimals -> 2.214 mH.
    # Secondary: Q (2), count 0x0379 = 889, no unit, 2 decimals -> 8.89.
    pkt = _packet(0x40, (2 << 5) | 0x10, bytes([1, 0x08, 0xA6, (6 << 3) | 3, 0]),
                  bytes([2, 0x03, 0x79, (0 << 3) | 2, 0]))
    p = decode(pkt)
    assert p.frequency == 1000.0
    assert p.primary.quantity == "inductance"
    assert p.primary.value == pytest.approx(2.214e-3)
    assert p.primary.text() == "2.214 mH"
    assert p.secondary.quantity == "quality_factor"
    assert p.secondary.value == pytest.approx(8.89)
    assert p.circuit == "series"
    assert p.flags["auto_range"]
    assert not p.flags["hold"]


@pytest.mark.parametrize(
    ("code", "hz"), [(0, 100.0), (1, 120.0), (2, 1000.0), (3, 10_000.0), (4, 100_000.0), (5, 0.0)])
def test_frequency_codes(code: int, hz: float) -> None:
    pkt = _packet(0, code << 5, bytes([4, 0, 173, (1 << 3) | 2, 0]), bytes(5))
    assert decode(pkt).frequency == hz


def test_flags_states_units_and_signed_values() -> None:
    # parallel + hold; ESR in kΩ; secondary θ negative (capacitive) in degrees.
    pkt = _packet(0x81, 3 << 5, bytes([3, 0x04, 0xD2, (2 << 3) | 3, 0]), bytes([4, 0xFF, 0x38, (14 << 3) | 1, 0]))
    p = decode(pkt)
    assert p.flags["parallel"]
    assert p.flags["hold"]
    assert p.circuit == "parallel"
    assert p.primary.value == pytest.approx(1.234e3)  # 1.234 kΩ
    assert p.secondary.value == pytest.approx(math.radians(-20.0))  # 0xFF38 = -200 -> -20.0°
    for state, name in ((1, "blank"), (2, "----"), (3, "OL"), (9, "OPEn"), (10, "Srt")):
        q = decode(_packet(0, 2 << 5, bytes([1, 0, 0, 6 << 3, state]), bytes(5)))
        assert q.primary.state == name
        assert not q.primary.shown
        assert math.isnan(q.primary.value)
    # 0x4E20 = 20000 counts is "outside limits" even with a normal state byte.
    over = decode(_packet(0, 2 << 5, bytes([1, 0x4E, 0x20, 6 << 3, 0]), bytes(5)))
    assert over.primary.state == "OL"


def test_calibration_and_sorting_modes_are_flagged() -> None:
    assert decode(_packet(0x08, 2 << 5, bytes([1, 0, 10, 6 << 3, 0]), bytes(5))).special_mode == "calibration"
    p = decode(_packet(0x10, 2 << 5, bytes([1, 0, 10, 6 << 3, 0]), bytes(5), tolerance=5))
    assert p.special_mode == "sorting"
    assert decode(_packet(0x04, 2 << 5, bytes([1, 0, 10, 6 << 3, 0]), bytes(5))).special_mode == "delta"
    assert p.tolerance == "±1%"


def test_unknown_codes_are_refused() -> None:
    with pytest.raises(PacketError, match="frequency"):
        decode(_packet(0, 7 << 5, bytes([1, 0, 1, 6 << 3, 0]), bytes(5)))
    with pytest.raises(PacketError, match="unit"):
        decode(_packet(0, 2 << 5, bytes([1, 0, 1, 4 << 3, 0]), bytes(5)))
    locked = decode(_packet(0, 2 << 5, bytes([1, 0, 12, 0x80 | (6 << 3) | 1, 0]), bytes(5)))  # bit 7: units locked
    assert locked.primary.value == pytest.approx(1.2e-3)
    with pytest.raises(PacketError, match="quantity"):
        decode(_packet(0, 2 << 5, bytes([9, 0, 1, 6 << 3, 0]), bytes(5)))
    with pytest.raises(PacketError, match="header"):
        decode(b"\x01" * PACKET_SIZE)


def test_encode_round_trip() -> None:
    pkt = encode(("inductance", 2.345e-3), ("phase_angle", math.atan(9.0)), frequency=10_000.0, parallel=True)
    p = decode(pkt)
    assert p.frequency == 10_000.0
    assert p.circuit == "parallel"
    assert p.primary.value == pytest.approx(2.345e-3, rel=1e-4)
    assert math.tan(p.secondary.value) == pytest.approx(9.0, rel=2e-3)
    assert display_bytes(2, 889, 2, 0) == bytes([2, 0x03, 0x79, 2, 0])


def test_reader_resynchronises_on_noise_and_partial_packets() -> None:
    good = [encode(("inductance", v), ("quality_factor", 9.0)) for v in (1e-3, 2e-3, 3e-3)]
    stream = b"\x0d\x0a\x00" + good[0][:9] + b"\x00\x0d\xff" + good[0] + good[1][:5] + b"\x42" * 20 + good[1] + good[2]
    reader = PacketReader()
    got = []
    for k in range(0, len(stream), 5):  # bytes arrive in small pieces
        got += reader.feed(stream[k : k + 5])
    assert [p.primary.value for p in got] == pytest.approx([1e-3, 2e-3, 3e-3])
    assert reader.skipped == len(stream) - 3 * PACKET_SIZE
