"""``motorlab robot record``: init and start an OpMode through FTC Dashboard, record its telemetry, stop it.

Safety, in this order of precedence:

* nothing starts unless :func:`record` is called with the OpMode's name (the person's explicit
  command); an OpMode already active on the robot is never replaced: the call refuses;
* :meth:`Recorder.stop` (Ctrl-C, the app's Stop button, the time limit) sends ``STOP_OP_MODE`` at
  once, from any thread: one WebSocket frame, well within 100 ms, and once only; the stop is then
  confirmed by reading the robot status back (the OpMode no longer active, or STOPPED) within
  ``timeout`` s, else the recording says THE OPMODE MAY STILL BE RUNNING. An OpMode that ends by itself
  is not sent a STOP. Road Runner's ``ForwardRampLogger`` and ``ManualFeedforwardTuner`` never end by
  themselves (``while (opModeIsActive())``, ``while (!isStopRequested)`` in road-runner-ftc Tuning.kt):
  ``--seconds`` is what stops them;
* the connection is watched by the Dashboard browser's own heartbeat, ``GET_ROBOT_STATUS`` (the
  :class:`~motorlab.robot.dashboard.Dashboard` sends one every second as the browser does; the recorder
  every 0.2 s for the battery column); no answer for :data:`LOST_AFTER` s counts as lost: the recorder
  reconnects (for up to :data:`RECONNECT_FOR` s) only to send ``STOP_OP_MODE``, and says that the robot
  may still be running when it cannot (an OpMode keeps running on the robot when the laptop's Wi-Fi
  drops: FTC Dashboard has no watchdog; the Driver Station's STOP is the one that always works). A
  Dashboard disabled while recording swallows STOP (DashboardCore.java:123-126): said the same way.

The log is a CSV motorlab reads (:func:`motorlab.io.read_csv`): ``time_s`` from the packets' own robot
timestamps (ms, relative to the first packet recorded), ``battery_V`` (the latest robot status's
``batteryVoltage``, the largest hub input voltage; NaN when the robot does not know it or its Dashboard is
older than v0.4.14), then one column per numeric telemetry key. A key
named as a motorlab column (``voltage_V``, ``position_counts`` …, see :data:`ALIASES`) becomes that
signal, so ``motorlab analyze feedforward LOG.csv --cpr N`` reads voltage and encoder position; every
other key is kept as ``x_<key>`` (read, but no signal), its name as the OpMode wrote it (Road Runner's
``ManualFeedforwardTuner``: ``v0``, ``v1``… and ``vref`` [in/s], ``mode`` a word; see :data:`KNOWN_KEYS`).
Values are written exactly as the robot sent them (Dashboard sends every value as a string). An OpMode that
sends its own sample time (``time_s``) and battery voltage (``battery_V``), as motorlab's own do
(ftc/README.md), gives those columns instead of the packets' timestamps and the robot status's battery.
"""

from __future__ import annotations

import math
import re
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from motorlab.io.csv_table import COLUMNS, column_name
from motorlab.robot import RobotLinkError
from motorlab.robot.dashboard import DISABLED, Dashboard, battery_volts, is_idle

#: Seconds without any message from Dashboard (it answers the 0.2 s status requests) = connection lost.
LOST_AFTER = 1.0
#: Seconds spent reconnecting after a loss, only to send STOP_OP_MODE.
RECONNECT_FOR = 3.0
#: Status requests per second while recording (the battery voltage column's rate).
STATUS_RATE = 5.0
#: Largest recording [s] and packets kept (a 100 Hz loop for 10 min).
MAX_SECONDS = 600.0
MAX_PACKETS = 100_000

#: Road Runner's ramp loggers (road-runner-ftc Tuning.kt): no Dashboard telemetry; run until STOP, then
#: save ``/sdcard/RoadRunner/tuning/<type>/<millis>.json`` (``TuningFiles.save``), served at
#: ``/tuning/<type>/latest.json`` (FileServing.kt).
RAMP_LOGGERS = {"ForwardRampLogger": "forward-ramp", "LateralRampLogger": "lateral-ramp",
                "AngularRampLogger": "angular-ramp"}
#: Telemetry keys of Road Runner's tuning OpModes, what they hold (road-runner-ftc Tuning.kt:
#: ManualFeedforwardTuner, lines 554, 580, 594), written into the log's header.
KNOWN_KEYS = {"vref": "Road Runner ManualFeedforwardTuner: the motion profile's velocity [in/s]",
              "mode": "Road Runner ManualFeedforwardTuner: TUNING_MODE or DRIVER_MODE (a word)"}
_ENCODER_VELOCITY = re.compile(r"v(\d+)")

#: Telemetry key (lower case, spaces and dashes as underscores) -> motorlab column.
ALIASES = {
    "voltage": "voltage_V", "volts": "voltage_V", "applied_voltage": "voltage_V", "voltage_v": "voltage_V",
    "command": "command_V", "command_v": "command_V",
    "position": "position_counts", "counts": "position_counts", "encoder": "position_counts",
    "encoder_counts": "position_counts", "ticks": "position_counts", "position_ticks": "position_counts",
    "current": "current_A", "current_a": "current_A",
    "battery": "battery_V", "battery_voltage": "battery_V",
}


def key_note(opmode: str, key: str) -> str:
    """What a telemetry key of a known OpMode holds (Road Runner's ManualFeedforwardTuner), or ""."""
    if opmode != "ManualFeedforwardTuner":
        return ""
    if key in KNOWN_KEYS:
        return KNOWN_KEYS[key]
    m = _ENCODER_VELOCITY.fullmatch(key)
    return (f"Road Runner ManualFeedforwardTuner: forward encoder {m.group(1)}'s velocity × inPerTick [in/s]"
            if m else "")


def column_for(key: str) -> str:
    """The CSV column a telemetry key is written as (a motorlab column, or ``x_<key>``)."""
    known = column_name(key)
    if known and COLUMNS[known][0] != "time":
        return known
    simple = re.sub(r"[\s\-/()]+", "_", key.strip().lower()).strip("_")
    if simple in ALIASES:
        return ALIASES[simple]
    if "volt" in simple and "batt" not in simple:  # "appliedVoltage", "motor voltage (V)"
        return "voltage_V"
    if any(word in simple for word in ("position", "ticks", "encoder")):  # "encoder position", "leftTicks"
        return "position_counts"
    safe = re.sub(r"[^A-Za-z0-9_.]+", "_", key.strip()).strip("_") or "key"
    return f"x_{safe}"


@dataclass
class Recording:
    """Telemetry recorded so far: rows of (robot time [ms], battery [V], {key: value string})."""

    opmode: str
    rows: list[tuple[int, float, dict[str, str]]] = field(default_factory=list)
    keys: list[str] = field(default_factory=list)
    skipped: dict[str, str] = field(default_factory=dict)  # key -> a value that was not a number
    stop_reason: str = ""
    stop_reason_note: str = ""
    still_running: bool = False
    stop_confirmed: bool = False  # the robot's status read back after STOP shows the OpMode stopped

    def numeric_keys(self) -> list[str]:
        return [k for k in self.keys if k not in self.skipped]


class Recorder:
    """One recording: :meth:`run` does it, :meth:`stop` ends it from any thread."""

    def __init__(self, host: str, port: int, opmode: str, *, seconds: float = 30.0, timeout: float = 5.0,
                 on_update: Callable[[Recording], None] | None = None) -> None:
        if not (0 < seconds <= MAX_SECONDS) or not math.isfinite(seconds):
            raise RobotLinkError(f"--seconds must be between 0 and {MAX_SECONDS:g}, got {seconds:g}")
        self.host, self.port, self.seconds, self.timeout = host, port, float(seconds), timeout
        self.data = Recording(opmode)
        self.on_update = on_update
        self._stop = threading.Event()
        self._stop_reason = ""
        self._lock = threading.Lock()
        self._battery = float("nan")
        self._recording = False
        self._seen_active = False
        self._stop_sent = False
        self._stop_lock = threading.Lock()
        self.dash: Dashboard | None = None
        self.state = "connecting"

    def stop(self, reason: str = "stopped by the user", *, send: bool = True) -> None:
        """End the run now: ``STOP_OP_MODE`` is sent from this thread at once (if started, and not sent
        before); ``send=False`` when the OpMode already ended by itself."""
        with self._lock:
            if not self._stop_reason:
                self._stop_reason = reason
            started = self._recording
        self._stop.set()
        if started and send:
            self._send_stop()

    def _send_stop(self) -> bool:
        """Send ``STOP_OP_MODE`` once per recording; True when it went out (now or before). Its own lock, not
        the data's: a reader of the telemetry (the app's live view) never delays a stop."""
        with self._stop_lock:
            if self._stop_sent:
                return True
            dash = self.dash
            if dash is None:
                return False
            try:  # the run loop sees a loss and reconnects to stop it
                dash.stop_op_mode()
            except RobotLinkError:
                return False
            self._stop_sent = True
            return True

    def _on_telemetry(self, packets: list[dict[str, Any]]) -> None:
        if not self._recording:
            return
        with self._lock:
            for packet in packets:
                if not isinstance(packet, dict) or len(self.data.rows) >= MAX_PACKETS:
                    continue
                data = packet.get("data") or {}
                stamp = packet.get("timestamp")
                if not isinstance(data, dict) or isinstance(stamp, bool) or not isinstance(stamp, int | float):
                    continue
                stamp = int(stamp)
                values = {str(k): str(v) for k, v in data.items()}
                for key, value in values.items():
                    if key not in self.data.keys:
                        self.data.keys.append(key)
                    if key not in self.data.skipped and not _is_number(value):
                        self.data.skipped[key] = value
                self.data.rows.append((stamp, self._battery, values))
        if self.on_update is not None:
            self.on_update(self.data)

    def _start(self, dash: Dashboard) -> None:
        names = [m["name"] for m in dash.op_modes()]
        if self.data.opmode not in names:
            close = [n for n in names if self.data.opmode.lower() in n.lower()][:5]
            hint = f" (did you mean {', '.join(repr(n) for n in close)}?)" if close else f" ({len(names)} on the robot)"
            raise RobotLinkError(f"the robot has no OpMode named {self.data.opmode!r}{hint}: give --opmode exactly as "
                                 "the Driver Station lists it")
        status = dash.status()
        if not is_idle(status):
            raise RobotLinkError(f"an OpMode is already active on the robot ({status.get('activeOpMode')}, "
                                 f"{status.get('activeOpModeStatus')}): stop it on the Driver Station first")
        self._battery = battery_volts(status)
        self.state = "init"
        dash.init_op_mode(self.data.opmode)
        self._seen_active = self._wait_status(dash, lambda s: s.get("activeOpMode") == self.data.opmode,
                                              "initialise", str(status.get("errorMessage") or ""))
        with self._lock:
            self._recording = not self._stop.is_set()
        if not self._recording:
            dash.stop_op_mode()  # stopped while initialising: nothing started, the INIT ends
            self._stop_sent = True
            return
        self.state = "running"
        dash.start_op_mode()

    def _wait_status(self, dash: Dashboard, ok: Callable[[dict[str, Any]], bool], what: str, error: str) -> bool:
        """Wait for the status ``ok`` takes; False when it never came but nothing else is active either
        (a status that does not name OpModes: the run goes on, said in the stop reason)."""
        deadline = time.monotonic() + self.timeout
        status: dict[str, Any] = {}
        while time.monotonic() < deadline and not self._stop.is_set():
            status = dash.status()
            if status.get("errorMessage") and status.get("errorMessage") != error:
                dash.stop_op_mode()  # a new error since INIT (the robot's older global error is not ours)
                raise RobotLinkError(f"the robot reports an error: {status['errorMessage']}; stop sent")
            if ok(status):
                return True
            time.sleep(0.05)
        if not self._stop.is_set() and not is_idle(status):
            dash.stop_op_mode()
            raise RobotLinkError(f"{self.data.opmode} did not {what} within {self.timeout:g} s "
                                 f"({status.get('activeOpMode')} is active); stop sent")
        self.data.stop_reason_note = f"the robot's status never showed {self.data.opmode}"
        return False

    def _watch(self, dash: Dashboard) -> None:
        """Until the time is up, Stop, or the connection is lost: poll the status (battery, heartbeat)."""
        end = time.monotonic() + self.seconds
        period = 1.0 / STATUS_RATE
        while not self._stop.wait(period):
            if time.monotonic() >= end:
                self.stop(f"{self.seconds:g} s elapsed")
                return
            if dash.closed or time.monotonic() - dash.last_message > LOST_AFTER:
                raise _Lost(dash.closed or f"no answer from {dash.address} for {LOST_AFTER:g} s")
            try:
                dash.request_status()
            except RobotLinkError as exc:
                raise _Lost(str(exc)) from None
            latest = dash.latest_status()
            if latest:
                self._battery = battery_volts(latest) if "batteryVoltage" in latest else self._battery
                if latest.get("enabled") is False:
                    self.data.still_running = True
                    self.stop(f"{DISABLED.split(':')[0]} while recording: it ignores STOP_OP_MODE; THE OPMODE MAY "
                              "STILL BE RUNNING, press STOP on the Driver Station", send=False)
                    return
                if self._recording and self._seen_active and latest.get("activeOpMode") not in (None, self.data.opmode):
                    self.stop("the OpMode ended on the robot", send=False)
                    return

    def _stop_after_loss(self, why: str) -> None:
        self.data.stop_reason = f"connection lost ({why})"
        deadline = time.monotonic() + RECONNECT_FOR
        while time.monotonic() < deadline:
            try:
                with Dashboard(self.host, self.port, timeout=1.0) as again:
                    again.stop_op_mode()
                    self.data.stop_reason += "; reconnected and sent STOP"
                    return
            except RobotLinkError:
                time.sleep(0.2)
        self.data.still_running = True
        self.data.stop_reason += ("; could not reconnect: THE OPMODE MAY STILL BE RUNNING, press STOP on the "
                                  "Driver Station")

    def run(self) -> Recording:
        """Connect, init and start the OpMode, record until stopped, stop it; the recording."""
        dash = Dashboard(self.host, self.port, timeout=self.timeout, on_telemetry=self._on_telemetry)
        self.dash = dash
        dash.connect()
        try:
            self._start(dash)
            if self._recording:
                self._watch(dash)
            self._final_stop(dash)
            if not self.data.stop_reason:
                self.data.stop_reason = self._stop_reason or "stopped"
            if self.data.stop_reason_note:
                self.data.stop_reason += f" ({self.data.stop_reason_note})"
        except _Lost as lost:
            self._recording = False
            self._stop_after_loss(str(lost))
        except BaseException:
            if self._recording and not self._send_stop():  # Ctrl-C or a bug: stop the robot before anything else
                self._stop_after_loss("the connection closed")
            raise
        finally:
            self._recording = False
            self.state = "stopped"
            dash.close()
        return self.data

    def _final_stop(self, dash: Dashboard) -> None:
        """Send STOP if it was not sent yet (once), then confirm it by reading the status back."""
        if not self._recording:
            return
        ended_by_itself = self._stop_reason == "the OpMode ended on the robot"
        if not self.data.still_running and not ended_by_itself:
            if not self._send_stop():
                raise _Lost(dash.closed or "STOP_OP_MODE could not be sent")
            self._confirm_stop(dash)
        else:
            self.data.stop_confirmed = ended_by_itself
        time.sleep(0.25)  # the last telemetry batch (sent every ~100 ms) arrives
        with self._lock:
            self._recording = False

    def _confirm_stop(self, dash: Dashboard) -> None:
        """The robot status after STOP: the OpMode no longer active, or STOPPED (``onOpModePostStop``, then
        the SDK's default OpMode ``$Stop$Robot$``); else the recording says it may still run."""
        deadline = time.monotonic() + self.timeout
        status: dict[str, Any] = {}
        while time.monotonic() < deadline:
            try:
                status = dash.status(timeout=max(0.1, deadline - time.monotonic()))
            except RobotLinkError:
                break
            if status.get("activeOpMode") != self.data.opmode or status.get("activeOpModeStatus") == "STOPPED":
                self.data.stop_confirmed = True
                return
            time.sleep(0.02)
        self.data.still_running = True
        shown = f"{status.get('activeOpMode')} {status.get('activeOpModeStatus')}" if status else "no status"
        self.data.stop_reason_note = " ".join(filter(None, [
            self.data.stop_reason_note, f"STOP sent but the robot still shows {shown} after {self.timeout:g} s: "
            "THE OPMODE MAY STILL BE RUNNING, press STOP on the Driver Station"]))


class _Lost(Exception):
    """The Dashboard connection went silent or closed while recording."""


def _is_number(text: str) -> bool:
    try:
        return math.isfinite(float(text)) and "_" not in text
    except ValueError:
        return False


def write_log(data: Recording, path: str | Path, *, host: str = "", cpr: float | None = None) -> dict[str, Any]:
    """Write the recording as a CSV motorlab reads (temporary file + rename); a summary of what was written."""
    from motorlab.io.output import write_text_atomic

    # Dashboard sends a packet's keys sorted (a SortedMap: TelemetryPacket.java): the signals motorlab reads
    # come first, in its own column order, then the other keys as they came.
    order = list(COLUMNS)
    keys = sorted(data.numeric_keys(),
                  key=lambda k: order.index(column_for(k)) if column_for(k) in order else len(order))
    if not data.rows:
        if data.opmode in RAMP_LOGGERS:
            kind = RAMP_LOGGERS[data.opmode]
            raise RobotLinkError(f"{data.opmode} sends no telemetry to FTC Dashboard ({data.stop_reason}): it saved "
                                 f"its ramp file on the robot when stopped; bring it with motorlab robot pull "
                                 f"(/tuning/{kind}/latest.json), then motorlab analyze feedforward FILE --cpr N")
        raise RobotLinkError(f"{data.opmode} sent no telemetry to FTC Dashboard ({data.stop_reason}): the OpMode must "
                             "send packets (FtcDashboard.getInstance().sendTelemetryPacket, or MultipleTelemetry)")
    if not keys:
        bad = ", ".join(f"{k}={v!r}" for k, v in list(data.skipped.items())[:3])
        raise RobotLinkError(f"no telemetry key of {data.opmode} is a number ({bad}): send numbers "
                             "(packet.put(\"voltage\", v))")
    clock, own_battery, per_second = _own_time_and_battery(keys)
    shown = [k for k in keys if k not in (clock, own_battery)]
    columns = _columns(shown)
    t0 = data.rows[0][0]
    confirmed = ("yes: the robot's status showed the OpMode stopped" if data.stop_confirmed
                 else "NO: the OpMode may still be running" if data.still_running else "not checked")
    lines = [f"# source: FTC Dashboard {host}", f"# opmode: {data.opmode}", f"# stop_reason: {data.stop_reason}",
             f"# stop_confirmed: {confirmed}", f"# robot_time_ms_at_zero: {t0}"]
    if cpr is not None:
        lines.append(f"# cpr: {cpr:g}")
    if clock is not None:
        lines.append(f"# column time_s: telemetry key {clock!r} (the OpMode's clock, from its first sample)")
    if own_battery is not None:
        lines.append(f"# column battery_V: telemetry key {own_battery!r}")
    lines += [f"# column {col}: telemetry key {key!r}" + (f" ({note})" if (note := key_note(data.opmode, key)) else "")
              for key, col in zip(shown, columns, strict=True)]
    lines.append(",".join(["time_s", "battery_V", *columns]))
    written = 0
    c0: float | None = None
    for stamp, battery, values in data.rows:
        if any(values.get(k) is None or not _is_number(values[k]) for k in keys):
            continue  # a packet without every numeric key (an init screen, a status line)
        volts = repr(battery) if math.isfinite(battery) else "nan"
        if clock is None:
            stamp_s = f"{(stamp - t0) / 1000:.3f}"
        else:
            c0 = float(values[clock]) if c0 is None else c0
            stamp_s = f"{(float(values[clock]) - c0) * per_second:.6f}"
        volts = values[own_battery] if own_battery is not None else volts
        lines.append(",".join([stamp_s, volts, *(values[k] for k in shown)]))
        written += 1
    if not written:
        raise RobotLinkError(f"no telemetry packet of {data.opmode} holds every numeric key at once: nothing to write")
    write_text_atomic(Path(path), "\n".join(lines) + "\n")
    named = dict(zip(shown, columns, strict=True)) | {k: c for k, c in ((clock, "time_s"), (own_battery, "battery_V"))
                                                       if k is not None}
    return {"rows": written, "columns": named,
            "skipped": dict(data.skipped), "stop_reason": data.stop_reason, "still_running": data.still_running,
            "stop_confirmed": data.stop_confirmed}


def _own_time_and_battery(keys: list[str]) -> tuple[str | None, str | None, float]:
    """The keys an OpMode sends its own sample time and battery voltage under (``time_s`` or ``time_ms``,
    ``battery_V``: motorlab's OpModes do), and the time key's seconds per unit. The OpMode's clock times a
    sample where it was read (µs); a packet's timestamp is when it was queued, in whole ms."""
    from motorlab.io.text import unit_factor

    clock = next((k for k in keys if (c := column_name(k)) and COLUMNS[c][0] == "time"), None)
    battery = next((k for k in keys if column_name(k) == "battery_V"), None)
    per_second = unit_factor(COLUMNS[column_name(clock) or "time_s"][1], "s") if clock else 1.0
    return clock, battery, per_second


def _columns(keys: list[str]) -> list[str]:
    out: list[str] = []
    for key in keys:
        col = column_for(key)
        while col in out or col in ("time_s", "battery_V"):
            col = f"x_{col.removeprefix('x_')}_"
        out.append(col)
    return out


def latest_ramp_name(host: str, http_port: int, kind: str, *, timeout: float = 5.0) -> str | None:
    """The name of the robot's newest ``kind`` ramp file (``X-Filename`` of ``/tuning/<kind>/latest.json``),
    or None (none yet, or no Road Runner web routes)."""
    from motorlab.robot.http import RobotHttp

    try:
        reply = RobotHttp(host, http_port, timeout=timeout).get(f"/tuning/{kind}/latest.json")
    except RobotLinkError:
        return None
    return reply.headers.get("x-filename") if reply.status == 200 else None


def fetch_ramp_file(host: str, http_port: int, kind: str, before: str | None, folder: Path, *,
                    timeout: float = 5.0) -> Path:
    """The ramp file a Road Runner ramp logger saved when it stopped (a newer name than ``before``), written
    byte for byte into ``folder`` under the robot's name; :class:`RobotLinkError` when none came within
    ``timeout`` s (``TuningFiles.save`` runs after the OpMode's loop ends)."""
    from motorlab.robot.http import RobotHttp
    from motorlab.robot.pull import check_name, write_atomic

    robot = RobotHttp(host, http_port, timeout=timeout)
    path = f"/tuning/{kind}/latest.json"
    deadline = time.monotonic() + timeout
    while True:
        reply = robot.get(path)
        name = reply.headers.get("x-filename") if reply.status == 200 else None
        if name and name != before:
            check_name(name, path)
            write_atomic(folder, name, reply.body)
            return folder / name
        if time.monotonic() > deadline:
            raise RobotLinkError(f"{path} from {robot.address}: no new ramp file within {timeout:g} s of the stop "
                                 f"(HTTP {reply.status}): pull it later with motorlab robot pull")
        time.sleep(0.2)
