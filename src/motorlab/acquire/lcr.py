"""Read a DER EE DE-5000 LCR meter over its serial link into the file ``motorlab analyze lcr`` reads.

The meter (Cyrustek ES51919 chip, see :mod:`motorlab.acquire.es51919`) sends a packet per reading
at 9600 baud 8N1; the IR-USB cable takes its power from DTR (on) with RTS off. The port is opened
with pyserial's ``serial_for_url``, so it may be a device (``/dev/ttyUSB0``, ``COM3``) or any
pyserial URL (``socket://host:port``, ``rfc2217://host:port``).

Readings whose primary display is blank, "----", "OL" (or any non-value), made in calibration,
sorting or delta mode, or without a usable secondary value, are skipped and counted. A file holds
one kind of reading (``kind``): inductance with Q (any secondary display Q, D, θ or ESR/Rp is
converted to Q exactly) in one equivalent circuit, or DC resistance. In "auto", an interactive run
follows its first reading and a run of consecutive readings prefers inductance. Each row is
written and flushed as soon as it is taken, so an interrupted run keeps what it had.
"""

from __future__ import annotations

import math
import os
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from datetime import UTC, datetime
from typing import IO, Any

from motorlab.acquire.errors import InstrumentError
from motorlab.acquire.es51919 import BAUD_RATE, Packet, PacketReader
from motorlab.errors import OptionError
from motorlab.io.output import check_writable_target

#: What one run of readings may hold (seed 1 takes ten positions).
MAX_LCR_READINGS = 10_000
#: Default wait for one accepted reading [s]; the DE-5000 sends about one packet per second.
DEFAULT_TIMEOUT = 10.0
#: Kinds of reading a file may hold.
KINDS = ("auto", "inductance", "dc_resistance")


@dataclass(frozen=True)
class LCRReading:
    """One accepted reading, ready for a row of the file.

    Attributes
    ----------
    kind
        ``"inductance"`` (L with Q) or ``"dc_resistance"``.
    value
        L [H] or R_dc [Ω].
    quality_factor
        Q [-] (NaN for a DC resistance).
    frequency
        Test frequency [Hz] (0 for DC).
    circuit
        ``"series"``, ``"parallel"`` or ``"none"``.
    primary, secondary
        What the two displays showed (``"2.2000 mH"``, ``"Q 8.900"``).
    """

    kind: str
    value: float
    quality_factor: float
    frequency: float
    circuit: str
    primary: str
    secondary: str


def quality_factor(packet: Packet) -> float:
    """Q of an inductance reading from whatever the secondary display shows (NaN if it cannot).

    Notes
    -----
    Q = 1/D; Q = tan θ; in the series circuit Q = ω·Ls/Rs (ESR), in the parallel one
    Q = Rp/(ω·Lp) — the definitions behind the meter's own D, θ and R displays.
    """
    sec = packet.secondary
    if not sec.shown or packet.frequency <= 0:
        return math.nan
    omega = 2 * math.pi * packet.frequency
    inductance = packet.primary.value
    if sec.quantity == "quality_factor":
        q = sec.value
    elif sec.quantity == "dissipation_factor":
        q = 1 / sec.value if sec.value > 0 else math.nan
    elif sec.quantity == "phase_angle":
        q = math.tan(sec.value) if 0 < sec.value < math.pi / 2 else math.nan
    elif sec.quantity == "resistance":
        if sec.value <= 0:
            return math.nan
        q = sec.value / (omega * inductance) if packet.flags["parallel"] else omega * inductance / sec.value
    else:
        return math.nan
    return q if math.isfinite(q) and q > 0 else math.nan


_SECONDARY_LABEL = {"quality_factor": "Q", "dissipation_factor": "D", "phase_angle": "theta", "resistance": "R",
                    "none": "none"}


def accept(packet: Packet, kind: str) -> tuple[LCRReading | None, str]:
    """The reading ``packet`` gives for a file of ``kind``, or ``None`` and why it is skipped."""
    if packet.special_mode:
        return None, f"{packet.special_mode} mode"
    prim = packet.primary
    if not prim.shown:
        return None, f"display {prim.state}"
    if prim.quantity not in ("inductance", "dc_resistance"):
        return None, f"the meter measures {prim.quantity}, not a winding's L or DCR"
    if kind != "auto" and prim.quantity != kind:
        return None, f"{prim.quantity} reading in a file of {kind}"
    if prim.value <= 0:
        return None, "non-positive reading"
    sec_text = f"{_SECONDARY_LABEL[packet.secondary.quantity]} {packet.secondary.text()}"
    if prim.quantity == "dc_resistance":
        return LCRReading("dc_resistance", prim.value, math.nan, packet.frequency, "none", prim.text(), sec_text), ""
    q = quality_factor(packet)
    if not math.isfinite(q):
        return None, f"no usable Q (secondary display: {sec_text})"
    return LCRReading("inductance", prim.value, q, packet.frequency, packet.circuit, prim.text(), sec_text), ""


@dataclass
class LCRLog:
    """The file being written: header on the first reading, one flushed row per reading."""

    path: str
    port: str
    handle: IO[str] | None = None
    kind: str = ""
    circuit: str = ""
    rows: int = 0
    started: float = field(default_factory=time.monotonic)

    def write(self, reading: LCRReading, position: int | None) -> None:
        """Append ``reading`` (opening the file and writing its header first)."""
        if self.handle is None:
            self.kind, self.circuit = reading.kind, reading.circuit
            check_writable_target(self.path)  # a FIFO would hang the reading, a device would swallow it
            self.handle = open(self.path, "w", encoding="utf-8", newline="")  # noqa: SIM115 (kept open)
            meta = {"experiment": "lcr", "instrument": "DER EE DE-5000 (Cyrustek ES51919)", "port": self.port,
                    "started": datetime.now(UTC).isoformat(timespec="seconds")}
            if reading.kind == "inductance":
                meta["circuit"] = reading.circuit
            lines = [f"# {k}: {v}" for k, v in meta.items()]
            cols = ["L_uH", "Q", "frequency_Hz"] if reading.kind == "inductance" else ["DCR_ohm"]
            lines.append(",".join([*cols, "x_position", "x_time_s", "x_primary", "x_secondary"]))
            self.handle.write("\n".join(lines) + "\n")
        if reading.kind == "inductance":
            values = [f"{reading.value * 1e6:.10g}", f"{reading.quality_factor:.10g}", f"{reading.frequency:g}"]
        else:
            values = [f"{reading.value:.10g}"]
        pos = "" if position is None else str(position)
        extra = [pos, f"{time.monotonic() - self.started:.3f}", reading.primary, reading.secondary]
        self.handle.write(",".join(values + [e.replace(",", ";") for e in extra]) + "\n")
        self.handle.flush()
        self.rows += 1

    def close(self) -> None:
        """Close the file (if any reading was written)."""
        if self.handle is not None:
            self.handle.close()


def open_serial(port: str, *, rts: bool = False, dtr: bool = True, read_timeout: float = 0.1) -> Any:
    """Open ``port`` (a device or pyserial URL) at 9600 8N1 with DTR/RTS set as the meter's cable needs.

    Raises
    ------
    InstrumentError
        If the port cannot be opened (missing device, refused connection, bad URL).
    """
    import serial  # pyserial

    if not port.strip():
        raise OptionError("--port: the port is empty (a device such as /dev/ttyUSB0 or a URL socket://host:port)")
    try:
        ser = serial.serial_for_url(port, do_not_open=True, baudrate=BAUD_RATE, bytesize=serial.EIGHTBITS,
                                    parity=serial.PARITY_NONE, stopbits=serial.STOPBITS_ONE, timeout=read_timeout)
        ser.dtr = dtr  # applied when the port opens
        ser.rts = rts
        # pyserial's socket handler empties its input when it opens: a meter (or emulator) that starts
        # sending at once would lose its first packets. Stale bytes are harmless (the reader resyncs).
        ser.reset_input_buffer = lambda: None
        try:
            ser.open()
        finally:
            del ser.reset_input_buffer
    except (serial.SerialException, ValueError, OSError) as exc:
        detail = " ".join(str(exc).split()) or type(exc).__name__
        raise InstrumentError(f"{port}: cannot open the LCR meter's port ({detail})") from None
    return ser


def check_new_output(path: str) -> None:
    """Refuse an output path that is a folder, has no folder, or is a file with content (never overwritten)."""
    if not path.strip():
        raise OptionError("-o: the file name is empty")
    if os.path.isdir(path):
        raise OptionError(f"-o {path}: is a folder")
    if os.path.exists(path) and os.path.getsize(path) > 0:
        raise OptionError(f"-o {path}: the file exists and is not empty; not overwriting it (choose another name)")
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise OptionError(f"-o {path}: the folder {folder} does not exist")


@dataclass
class _Stream:
    """Packets from the port with a bounded wait, counting what was skipped and why."""

    ser: Any
    port: str
    reader: PacketReader = field(default_factory=PacketReader)
    pending: deque[Packet] = field(default_factory=deque)
    received: int = 0
    packets: int = 0
    skipped: dict[str, int] = field(default_factory=dict)

    def flush(self) -> None:
        self.ser.reset_input_buffer()
        self.reader.clear()
        self.pending.clear()

    def next_reading(self, kind: str, circuit: str, timeout: float) -> LCRReading:
        deadline = time.monotonic() + timeout
        while True:
            if not self.pending:
                self.pending.extend(self._packets(deadline, timeout))
                continue
            reading, why = accept(self.pending.popleft(), kind)
            if reading is not None and circuit and reading.circuit != circuit:
                why = f"{reading.circuit} circuit in a file of {circuit}"
            elif reading is not None:
                return reading
            self.skipped[why] = self.skipped.get(why, 0) + 1

    def _packets(self, deadline: float, timeout: float) -> list[Packet]:
        if time.monotonic() > deadline:
            raise InstrumentError(f"{self.port}: no usable DE-5000 reading in {timeout:g} s ({self.summary()})")
        try:
            data = self.ser.read(max(1, min(self.ser.in_waiting, 4096)))
        except Exception as exc:  # pyserial raises SerialException (an OSError) or socket errors
            raise InstrumentError(f"{self.port}: reading failed ({' '.join(str(exc).split())})") from None
        self.received += len(data)
        packets = self.reader.feed(data)
        self.packets += len(packets)
        return packets

    def summary(self) -> str:
        """What arrived so far, for messages."""
        if self.received == 0:
            return "nothing received: is the meter on, its PC link enabled and the cable in place?"
        text = f"{self.received} bytes, {self.packets} packets"
        if self.packets == 0:
            return text + " (no 17-byte packet: wrong port, baud rate or meter?)"
        reasons = ", ".join(f"{n} × {why}" for why, n in sorted(self.skipped.items(), key=lambda kv: -kv[1]))
        return text + (f"; skipped {reasons}" if reasons else "")


def acquire_lcr(
    port: str,
    path: str,
    *,
    readings: int,
    interactive: bool = False,
    kind: str = "auto",
    timeout: float = DEFAULT_TIMEOUT,
    rts: bool = False,
    dtr: bool = True,
    ask: Callable[[str], str] | None = None,
    report: Callable[[str], None] | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> LCRLog:
    """Take ``readings`` accepted readings from a DE-5000 on ``port`` and write them to ``path``.

    Parameters
    ----------
    port
        Serial device or pyserial URL (``socket://127.0.0.1:7000``).
    path
        CSV to write (refused if it exists and is not empty): ``L_uH,Q,frequency_Hz`` with
        ``# circuit:``, or ``DCR_ohm``, plus ``x_`` columns the reader skips (shaft position, time,
        both displays as shown).
    readings
        Number of readings (shaft positions in interactive mode).
    interactive
        Ask before each reading ("turn the shaft to position k, press Enter; q stops"): the port is
        flushed, the first reading after Enter (possibly taken while the shaft moved) is discarded
        and the next accepted one is kept.
    kind
        ``"inductance"``, ``"dc_resistance"`` or ``"auto"``: interactively the first accepted reading
        decides; for consecutive readings inductance wins if any arrives (see :func:`_consecutive`).
    timeout
        Longest wait for one accepted reading [s].
    rts, dtr
        Modem lines (the cable is powered with DTR on and RTS off).
    ask, report, progress
        Prompt function (default :func:`input`), message sink, progress callback ``(done, total)``.

    Returns
    -------
    LCRLog
        The file written and the number of rows.

    Raises
    ------
    OptionError
        Bad settings or an output file that exists.
    InstrumentError
        Port cannot be opened, or no usable reading arrives within ``timeout`` (rows already taken
        stay in the file).
    """
    if not 1 <= readings <= MAX_LCR_READINGS:
        raise OptionError(f"--readings must lie between 1 and {MAX_LCR_READINGS}, got {readings}")
    if not (math.isfinite(timeout) and 0 < timeout <= 3600):
        raise OptionError(f"--timeout must lie between 0 and 3600 s, got {timeout:g} s")
    if kind not in KINDS:
        raise OptionError(f"the kind of reading must be one of {', '.join(KINDS)}, got {kind!r}")
    check_new_output(path)
    ask = ask or input
    say = report or (lambda text: None)
    ser = open_serial(port, rts=rts, dtr=dtr)
    log = LCRLog(path, port)
    stream = _Stream(ser, port)
    try:
        if interactive:
            for k in range(1, readings + 1):
                answer = ask(f"Turn the shaft to position {k} of {readings}, then press Enter (q stops): ")
                if answer.strip().lower() in ("q", "quit"):
                    break
                stream.flush()
                stream.next_reading(log.kind or kind, log.circuit, timeout)  # may predate Enter: discarded
                _record(log, stream.next_reading(log.kind or kind, log.circuit, timeout), k, say)
                if progress is not None:
                    progress(k, readings)
        else:
            _consecutive(stream, log, readings, kind, timeout, say, progress)
    except InstrumentError as exc:
        if log.rows:  # what was read is kept (flushed row by row): say so in the one error line
            raise InstrumentError(f"{exc}; the {log.rows} reading(s) taken are kept in {path}") from None
        raise
    finally:
        log.close()
        ser.close()
    if stream.skipped:
        say("skipped: " + ", ".join(f"{n} × {why}" for why, n in stream.skipped.items()))
    return log


def _record(log: LCRLog, reading: LCRReading, position: int | None, say: Callable[[str], None]) -> None:
    log.write(reading, position)
    say(f"reading {log.rows}: {reading.primary}, {reading.secondary}"
        + (f" at {reading.frequency:g} Hz ({reading.circuit})" if reading.kind == "inductance" else ""))


def _consecutive(stream: _Stream, log: LCRLog, readings: int, kind: str, timeout: float,
                 say: Callable[[str], None], progress: Callable[[int, int], None] | None) -> None:
    """``readings`` consecutive accepted readings.

    With ``kind="auto"`` the file holds inductance readings when the meter gives any: DC
    resistances are held back until ``readings`` of them arrived with no inductance reading among
    them (a meter in DCR mode); an inductance reading first discards them (a meter switched between
    modes gives the L/Q file; take the DCR file with ``--kind dc_resistance``).
    """
    held: list[LCRReading] = []
    while log.rows < readings:
        reading = stream.next_reading(log.kind or kind, log.circuit, timeout)
        if not log.kind and kind == "auto" and reading.kind == "dc_resistance":
            held.append(reading)
            if len(held) < readings:
                continue
            for r in held:
                _record(log, r, None, say)
            break
        if held:
            why = "dc_resistance reading before the inductance ones"
            stream.skipped[why] = stream.skipped.get(why, 0) + len(held)
            held.clear()
        _record(log, reading, None, say)
        if progress is not None:
            progress(log.rows, readings)
