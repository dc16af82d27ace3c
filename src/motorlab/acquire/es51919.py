"""The Cyrustek ES51919 LCR chip's 17-byte packets (DER EE DE-5000, Mastech MS5308, UNI-T UT612 …).

The meter sends one packet per reading, 9600 baud 8N1, without being asked. The chip's data sheet
does not describe the host protocol; this module follows the reverse-engineered description in
libsigrok's ``src/lcr/es51919.c`` (Janne Huttunen 2014, Gerhard Sittig 2019; the driver
``deree-de5000``), cross-checked with the first public decoding on the EEVblog forum ("Decoding
DER EE LCR Meter DE-5000 serial bitstream", 2014). Layout (byte offsets)::

    0-1   header 0x00 0x0D                 15-16 footer 0x0D 0x0A   (no checksum)
    2     flags: bit0 hold, bit1 reference shown, bit2 delta, bit3 calibration, bit4 sorting,
          bit5 auto LCR, bit6 auto range, bit7 parallel (else series) equivalent circuit
    3     bits 5-7 test frequency: 0 100 Hz, 1 120 Hz, 2 1 kHz, 3 10 kHz, 4 100 kHz, 5 DC
          (bits 0-4 unknown; the forum post reads bit 3 as auto-power-off)
    4     tolerance in sorting mode (0 none, 3 ±0.25 % … 10 −20/+80 %)
    5-9   primary display: 5 quantity (1 L, 2 C, 3 R, 4 DCR); 6-7 value, big-endian signed
          16-bit; 8 bits 0-2 decimals (value·10^−n), bits 3-6 unit (bit 7: units locked, per
          the forum post; libsigrok counts it in the unit); 9 bits 0-3 display state
    10-14 secondary display, same layout; quantity 0 none, 1 D, 2 Q, 3 R (ESR or Rp), 4 θ

Units: 0 none, 1 Ω, 2 kΩ, 3 MΩ, 5 µH, 6 mH, 7 H, 8 kH, 9 pF, 10 nF, 11 µF, 12 mF, 13 %, 14 °.
Display states: 0 a value, 1 blank, 2 "----", 3 "OL", 7 "PASS", 8 "FAIL", 9 "OPEn", 10 "Srt".
A count of 20000 (0x4E20) also means "outside limits" (the display has 19999 counts).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

#: Bytes per packet.
PACKET_SIZE = 17
HEADER = b"\x00\x0d"
FOOTER = b"\x0d\x0a"
#: Serial settings of the meter's IR-USB cable (9600 baud, 8 data bits, no parity, 1 stop bit).
BAUD_RATE = 9600
#: Counts of the display: 19999; 20000 (0x4E20) marks a reading outside the limits.
OVER_RANGE_COUNT = 20000

#: Frequency code (byte 3, bits 5-7) -> test frequency [Hz] (0 = DC).
FREQUENCIES: dict[int, float] = {0: 100.0, 1: 120.0, 2: 1000.0, 3: 10_000.0, 4: 100_000.0, 5: 0.0}
#: Primary quantity code (byte 5).
PRIMARY: dict[int, str] = {1: "inductance", 2: "capacitance", 3: "resistance", 4: "dc_resistance"}
#: Secondary quantity code (byte 10). Code 3 is ESR in series mode, the parallel resistance in parallel mode.
SECONDARY: dict[int, str] = {
    0: "none", 1: "dissipation_factor", 2: "quality_factor", 3: "resistance", 4: "phase_angle",
}
#: Unit code (bits 3-7 of byte 8/13) -> (unit as displayed, factor to SI). Degrees go to radians and
#: percent to a fraction; code 4 is unused.
UNITS: dict[int, tuple[str, float]] = {
    0: ("", 1.0), 1: ("ohm", 1.0), 2: ("kohm", 1e3), 3: ("Mohm", 1e6),
    5: ("uH", 1e-6), 6: ("mH", 1e-3), 7: ("H", 1.0), 8: ("kH", 1e3),
    9: ("pF", 1e-12), 10: ("nF", 1e-9), 11: ("uF", 1e-6), 12: ("mF", 1e-3),
    13: ("%", 1e-2), 14: ("deg", math.pi / 180),
}
#: Display state code (bits 0-3 of byte 9/14).
STATES: dict[int, str] = {
    0: "normal", 1: "blank", 2: "----", 3: "OL", 7: "PASS", 8: "FAIL", 9: "OPEn", 10: "Srt",
}
#: Tolerance code (byte 4) in sorting mode.
TOLERANCES: dict[int, str] = {
    0: "", 3: "±0.25%", 4: "±0.5%", 5: "±1%", 6: "±2%", 7: "±5%", 8: "±10%", 9: "±20%", 10: "-20+80%",
}
_FLAG_BITS = ("hold", "reference", "delta", "calibration", "sorting", "auto_lcr", "auto_range", "parallel")


class PacketError(ValueError):
    """Seventeen bytes framed like a packet whose fields hold codes the protocol does not know."""


@dataclass(frozen=True)
class Display:
    """One of the meter's two displays.

    Attributes
    ----------
    quantity
        ``"inductance"``, ``"capacitance"``, ``"resistance"``, ``"dc_resistance"`` (primary) or
        ``"none"``, ``"dissipation_factor"``, ``"quality_factor"``, ``"resistance"``,
        ``"phase_angle"`` (secondary).
    state
        ``"normal"`` when a value is shown, else what the display shows (``"OL"``, ``"----"``,
        ``"blank"`` …).
    count
        The signed count on the display (without its decimal point).
    decimals
        Digits after the decimal point.
    unit
        The unit as displayed (``"mH"``, ``"ohm"``, ``"deg"``, ``""``).
    value
        The reading in SI [H, F, Ω, rad; D, Q and % as plain numbers]; NaN unless ``state`` is normal.
    """

    quantity: str
    state: str
    count: int
    decimals: int
    unit: str
    value: float

    @property
    def shown(self) -> bool:
        """True when the display shows a value."""
        return self.state == "normal"

    def text(self) -> str:
        """What the display shows, e.g. ``"1.2340 mH"`` or ``"OL"``."""
        if not self.shown:
            return self.state
        number = f"{self.count / 10**self.decimals:.{self.decimals}f}"
        return f"{number} {self.unit}".strip()


@dataclass(frozen=True)
class Packet:
    """One decoded packet.

    Attributes
    ----------
    frequency
        Test frequency [Hz]; 0 for DC (DCR mode).
    flags
        ``hold``, ``reference``, ``delta``, ``calibration``, ``sorting``, ``auto_lcr``,
        ``auto_range``, ``parallel`` (byte 2).
    tolerance
        Sorting tolerance as shown (empty when not set).
    primary, secondary
        The two displays.
    raw
        The 17 bytes.
    """

    frequency: float
    flags: dict[str, bool]
    tolerance: str
    primary: Display
    secondary: Display
    raw: bytes

    @property
    def circuit(self) -> str:
        """``"parallel"`` or ``"series"`` equivalent circuit (``"none"`` for a DC resistance)."""
        if self.primary.quantity == "dc_resistance":
            return "none"
        return "parallel" if self.flags["parallel"] else "series"

    @property
    def special_mode(self) -> str | None:
        """``"calibration"``, ``"sorting"`` (libsigrok ignores those packets) or ``"delta"`` (relative mode:
        the displays show differences from a stored reference, not the part's values)."""
        for name in ("calibration", "sorting", "delta"):
            if self.flags[name]:
                return name
        return None


def _display(data: bytes, names: dict[int, str], where: str) -> Display:
    code = data[0]
    if code not in names:
        raise PacketError(f"unknown {where} quantity code {code}")
    count = int.from_bytes(data[1:3], "big", signed=True)
    decimals = data[3] & 0x07
    # Bits 3-6: libsigrok reads bits 3-7 and rejects codes above 14; the EEVblog decoding reads bit 7
    # as "units locked". Masking it agrees with libsigrok on every packet libsigrok accepts.
    unit_code = (data[3] >> 3) & 0x0F
    if unit_code not in UNITS:
        raise PacketError(f"unknown {where} unit code {unit_code}")
    unit, factor = UNITS[unit_code]
    state_code = data[4] & 0x0F
    state = STATES.get(state_code, f"state {state_code}")
    if state == "normal" and abs(count) >= OVER_RANGE_COUNT:
        state = "OL"  # 0x4E20: "outside limits" (libsigrok's note)
    value = count * 10.0**-decimals * factor if state == "normal" else math.nan
    return Display(names[code], state, count, decimals, unit, value)


def decode(packet: bytes) -> Packet:
    """Decode one 17-byte packet.

    Raises
    ------
    PacketError
        Wrong length, header or footer, or a frequency, quantity or unit code the protocol does not have.
    """
    if len(packet) != PACKET_SIZE:
        raise PacketError(f"a packet has {PACKET_SIZE} bytes, got {len(packet)}")
    if packet[:2] != HEADER or packet[15:] != FOOTER:
        raise PacketError("no 00 0D header or 0D 0A footer")
    flags = {name: bool(packet[2] >> bit & 1) for bit, name in enumerate(_FLAG_BITS)}
    code = packet[3] >> 5
    if code not in FREQUENCIES:
        raise PacketError(f"unknown test frequency code {code}")
    tolerance = TOLERANCES.get(packet[4], f"code {packet[4]}")
    primary = _display(packet[5:10], PRIMARY, "primary")
    secondary = _display(packet[10:15], SECONDARY, "secondary")
    return Packet(FREQUENCIES[code], flags, tolerance, primary, secondary, bytes(packet))


class PacketReader:
    """Cut a byte stream into packets, resynchronising after partial packets and noise.

    Bytes are appended with :meth:`feed`; whenever the buffer does not start with a header and end
    a packet's length later with a footer, one byte is dropped and the search goes on (libsigrok's
    ``serial-lcr`` does the same). Framed packets with unknown codes are dropped the same way.

    Attributes
    ----------
    skipped
        Bytes dropped so far while resynchronising.
    invalid
        Framed packets whose fields could not be decoded.
    """

    def __init__(self) -> None:
        self._buffer = bytearray()
        self.skipped = 0
        self.invalid = 0

    def clear(self) -> None:
        """Forget buffered bytes (after flushing the port)."""
        self._buffer.clear()

    def feed(self, data: bytes) -> list[Packet]:
        """Append ``data``; return the packets completed by it, in order."""
        self._buffer.extend(data)
        packets: list[Packet] = []
        buf = self._buffer
        while len(buf) >= PACKET_SIZE:
            if buf[:2] == HEADER and buf[15:PACKET_SIZE] == FOOTER:
                try:
                    packets.append(decode(bytes(buf[:PACKET_SIZE])))
                except PacketError:
                    self.invalid += 1
                else:
                    del buf[:PACKET_SIZE]
                    continue
            del buf[0]
            self.skipped += 1
        return packets


# ---- encoding (for the emulator and tests) -------------------------------------------------------
_FAMILY = {
    "inductance": (5, 6, 7, 8), "capacitance": (9, 10, 11, 12), "resistance": (1, 2, 3),
    "dc_resistance": (1, 2, 3), "dissipation_factor": (0,), "quality_factor": (0,), "phase_angle": (14,),
    "none": (0,),
}


def display_bytes(quantity_code: int, count: int, decimals: int, unit_code: int, state: int = 0) -> bytes:
    """The five bytes of one display."""
    return bytes([quantity_code]) + int(count).to_bytes(2, "big", signed=True) + bytes(
        [(unit_code << 3) | (decimals & 7), state & 0x0F])


def autorange(quantity: str, value: float, *, max_decimals: int = 4) -> tuple[int, int, int]:
    """``(count, decimals, unit_code)`` showing ``value`` [SI] with the most digits within 19999 counts."""
    best: tuple[int, int, int] | None = None
    for unit_code in _FAMILY[quantity]:
        factor = UNITS[unit_code][1]
        for decimals in range(max_decimals, -1, -1):
            count = round(value / factor * 10**decimals)
            if abs(count) < OVER_RANGE_COUNT and (best is None or abs(count) > abs(best[0])):
                best = (count, decimals, unit_code)
                break
    if best is None:
        raise ValueError(f"{value!r} cannot be displayed as {quantity}")
    return best


def encode(
    primary: tuple[str, float | str],
    secondary: tuple[str, float | str] = ("none", "blank"),
    *,
    frequency: float = 1000.0,
    parallel: bool = False,
    hold: bool = False,
    auto_range: bool = True,
    auto_lcr: bool = True,
) -> bytes:
    """One packet as the meter sends it; a display's value may be a number [SI] or a state (``"OL"``).

    Examples
    --------
    ``encode(("inductance", 2.2e-3), ("quality_factor", 8.9))`` is "2.2000 mH, Q 8.900 at 1 kHz".
    """
    inverse_primary = {v: k for k, v in PRIMARY.items()}
    inverse_secondary = {v: k for k, v in SECONDARY.items()}
    inverse_state = {v: k for k, v in STATES.items()}
    freq_code = {v: k for k, v in FREQUENCIES.items()}[float(frequency)]
    flags = (hold << 0) | (auto_lcr << 5) | (auto_range << 6) | (parallel << 7)
    out = bytearray(HEADER + bytes([flags, (freq_code << 5) | 0x10, 0]))
    for (quantity, value), codes in ((primary, inverse_primary), (secondary, inverse_secondary)):
        unit_code = _FAMILY[quantity][0]
        if isinstance(value, str):
            out += display_bytes(codes[quantity], 0, 0, unit_code, inverse_state[value])
        else:
            count, decimals, unit_code = autorange(quantity, value)
            out += display_bytes(codes[quantity], count, decimals, unit_code)
    out += FOOTER
    return bytes(out)
