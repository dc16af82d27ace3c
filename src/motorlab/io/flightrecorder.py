"""Road Runner's FlightRecorder logs (``RoadRunner/logs/*.log``): channels, and drive runs for feedforward.

Format (road-runner-ftc ``RoadRunner/src/main/java/com/acmerobotics/roadrunner/ftc/LogFile.kt``,
commit 1f35428; see ``docs/formats.md``): big-endian (``java.nio.ByteBuffer``), a 4-byte header
``'R' 'R'`` + version (int16: 0 initial, 1 since 5f2a758), then entries, each an int32 tag:

* ``0`` schema entry: int32 length + UTF-8 channel name, then the channel's schema;
* ``1`` message entry: int32 channel index (order of the schema entries), then the encoded object.

Schemas are an int32 tag: 0 struct (int32 field count, then per field int32 length + UTF-8 name and
the field's schema; fields sorted by name), 1 int32, 2 int64, 3 float64, 4 string (int32 length +
UTF-8), 5 boolean (1 byte), 6 enum (int32 count, then the constant names; a value is the int32
ordinal), 7 array (element schema; a value is int32 length + elements). Version-0 writers reserved 4
bytes too many for every array schema, written as zeros after the schema entry; they are skipped.

The quickstart's drives log ``MECANUM_COMMAND`` / ``TANK_COMMAND`` (battery ``voltage`` and each
motor's power, at most every 50 ms: ``DownsampledWriter``) and ``MECANUM_LOCALIZER_INPUTS`` /
``TANK_LOCALIZER_INPUTS`` (each drive encoder's ``position`` and ``velocity`` in ticks, every
update), with ``timestamp`` = ``System.nanoTime()``.
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from motorlab.errors import LogFormatError, OptionError
from motorlab.io.text import PathArg, check_cpr, read_bytes
from motorlab.recording import Recording

MAGIC = b"RR"
#: Schema tags of LogFile.kt.
STRUCT, INT, LONG, DOUBLE, STRING, BOOLEAN, ENUM, ARRAY = range(8)
_PRIMITIVE = {INT: (">i", 4), LONG: (">q", 8), DOUBLE: (">d", 8), BOOLEAN: (">?", 1)}
#: Mecanum wheels in the order of MecanumCommandMessage / MecanumLocalizerInputsMessage.
MECANUM_WHEELS = ("leftFront", "leftBack", "rightBack", "rightFront")
#: A gap between drive commands longer than this ends a followed trajectory [s].
COMMAND_GAP = 0.2

Schema = tuple[Any, ...]


@dataclass
class Channel:
    """One channel of a flight log: its schema and its messages (decoded to dicts, lists, values)."""

    name: str
    schema: Schema
    messages: list[Any] = field(default_factory=list)

    def column(self, *path: str) -> np.ndarray:
        """``[message[path[0]][path[1]]... for message in messages]`` as a float array."""
        out = []
        for msg in self.messages:
            for key in path:
                msg = msg[key]
            out.append(msg)
        return np.asarray(out, dtype=float)


class _Reader:
    def __init__(self, name: str, raw: bytes):
        self.name, self.raw, self.pos = name, raw, 0

    def fail(self, problem: str) -> LogFormatError:
        return LogFormatError(f"byte {self.pos}: {problem}", path=self.name)

    def take(self, n: int) -> bytes:
        if n < 0 or self.pos + n > len(self.raw):
            raise EOFError
        chunk = self.raw[self.pos:self.pos + n]
        self.pos += n
        return chunk

    def int32(self) -> int:
        return int(struct.unpack(">i", self.take(4))[0])

    def text(self) -> str:
        n = self.int32()
        if n > len(self.raw):
            raise self.fail(f"string length {n} exceeds the file")
        try:
            return self.take(n).decode("utf-8")
        except UnicodeDecodeError:
            raise self.fail("a name is not UTF-8") from None

    def schema(self, depth: int = 0) -> tuple[Schema, int]:
        """(schema, number of array schemas in it)."""
        if depth > 32:
            raise self.fail("schema nested too deeply")
        tag = self.int32()
        if tag == STRUCT:
            count = self.int32()
            if not 0 < count < 10_000:
                raise self.fail(f"struct with {count} fields")
            fields, arrays = [], 0
            for _ in range(count):
                name = self.text()
                sub, n_arr = self.schema(depth + 1)
                fields.append((name, sub))
                arrays += n_arr
            return (STRUCT, tuple(fields)), arrays
        if tag in _PRIMITIVE or tag == STRING:
            return (tag,), 0
        if tag == ENUM:
            count = self.int32()
            if not 0 <= count < 100_000:
                raise self.fail(f"enum with {count} constants")
            return (ENUM, tuple(self.text() for _ in range(count))), 0
        if tag == ARRAY:
            sub, n_arr = self.schema(depth + 1)
            return (ARRAY, sub), n_arr + 1
        raise self.fail(f"unknown schema tag {tag}")

    def value(self, schema: Schema) -> Any:
        tag = schema[0]
        if tag in _PRIMITIVE:
            fmt, size = _PRIMITIVE[tag]
            return struct.unpack(fmt, self.take(size))[0]
        if tag == STRING:
            return self.text()
        if tag == STRUCT:
            return {name: self.value(sub) for name, sub in schema[1]}
        if tag == ENUM:
            k = self.int32()
            return schema[1][k] if 0 <= k < len(schema[1]) else k
        n = self.int32()
        if n < 0 or n > len(self.raw) - self.pos:
            raise self.fail(f"array length {n} exceeds the file")
        return [self.value(schema[1]) for _ in range(n)]


def read_flight_log_channels(path: PathArg) -> tuple[dict[str, Channel], list[str]]:
    """Every channel of a FlightRecorder ``.log`` with its decoded messages, and warnings.

    Raises
    ------
    LogFormatError
        Not a flight log (no ``RR`` header), an unknown version, tag or schema, a message on a
        channel without schema. A file cut off in the middle of an entry (the robot lost power)
        keeps the complete entries, with a warning.
    """
    name, raw = read_bytes(path)
    if len(raw) < 4 or raw[:2] != MAGIC:
        raise LogFormatError("not a Road Runner flight log (no 'RR' header)", path=name)
    version = struct.unpack(">h", raw[2:4])[0]
    if version not in (0, 1):
        raise LogFormatError(f"flight log version {version} (known: 0, 1)", path=name)
    r = _Reader(name, raw)
    r.pos = 4
    channels: list[Channel] = []
    warnings: list[str] = []
    while r.pos < len(raw):
        start = r.pos
        try:
            tag = r.int32()
            if tag == 0:
                channel = r.text()
                schema, arrays = r.schema()
                if version == 0:  # 4 unused bytes per array schema
                    r.take(4 * arrays)
                channels.append(Channel(channel, schema))
            elif tag == 1:
                index = r.int32()
                if not 0 <= index < len(channels):
                    raise r.fail(f"message on channel {index}, but only {len(channels)} channels are declared")
                channels[index].messages.append(r.value(channels[index].schema))
            else:
                r.pos = start
                raise r.fail(f"unknown entry tag {tag}")
        except EOFError:
            warnings.append(f"{name}: the log ends inside an entry at byte {start} (cut off); "
                            "the entries before it are kept")
            break
    return {c.name: c for c in channels}, warnings


def _blocks(times: np.ndarray) -> list[tuple[float, float]]:
    """Time spans of contiguous command streams (gaps over COMMAND_GAP split them)."""
    if times.size == 0:
        return []
    cuts = np.flatnonzero(np.diff(times) > COMMAND_GAP)
    starts = np.concatenate([[0], cuts + 1])
    stops = np.concatenate([cuts, [times.size - 1]])
    return [(float(times[a]), float(times[b])) for a, b in zip(starts, stops, strict=True) if b > a]


def _params(channels: dict[str, Channel], name: str, keys: tuple[str, ...]) -> dict[str, float]:
    if name not in channels or not channels[name].messages:
        raise LogFormatError(f"dead-wheel runs need the {name} channel (the quickstart writes it when the drive "
                             "is built)")
    msg = channels[name].messages[-1]
    missing = [k for k in keys if k not in msg]
    if missing:
        raise LogFormatError(f"{name} lacks {', '.join(missing)}")
    return {k: float(msg[k]) for k in keys}


def _dead_wheel_travel(channels: dict[str, Channel]) -> dict[str, np.ndarray]:
    """Each mecanum wheel's travel [dead-wheel ticks] from three dead wheels (robot frame).

    ThreeDeadWheelLocalizer (quickstart): x = (par0Y·par1 − par1Y·par0)/(par0Y − par1Y),
    y = perpX·(par1 − par0)/(par0Y − par1Y) + perp, ψ = (par0 − par1)/(par0Y − par1Y); then the wheels
    by ``MecanumKinematics.inverse`` (road-runner Kinematics.kt): x ∓ y·lateralMultiplier ∓ ψ·trackWidth,
    lateralMultiplier = inPerTick / lateralInPerTick (MecanumDrive.java). All linear, so totals work.
    """
    dw = _params(channels, "THREE_DEAD_WHEEL_PARAMS", ("par0YTicks", "par1YTicks", "perpXTicks"))
    mp = _params(channels, "MECANUM_PARAMS", ("inPerTick", "lateralInPerTick", "trackWidthTicks"))
    inputs = channels["THREE_DEAD_WHEEL_INPUTS"]
    p0, p1, pp = (inputs.column(k, "position") for k in ("par0", "par1", "perp"))
    p0, p1, pp = p0 - p0[0], p1 - p1[0], pp - pp[0]
    span = dw["par0YTicks"] - dw["par1YTicks"]
    if span == 0 or mp["lateralInPerTick"] == 0:
        raise LogFormatError("THREE_DEAD_WHEEL_PARAMS / MECANUM_PARAMS are not tuned (par0YTicks = par1YTicks or "
                             "lateralInPerTick = 0)")
    x = (dw["par0YTicks"] * p1 - dw["par1YTicks"] * p0) / span
    y = dw["perpXTicks"] * (p1 - p0) / span + pp
    psi = (p0 - p1) / span
    return _mecanum_inverse(x, y, psi, mp)


def _mecanum_inverse(x: np.ndarray, y: np.ndarray, psi: np.ndarray, mp: dict[str, float]) -> dict[str, np.ndarray]:
    """Wheel travel [ticks] from the robot-frame travel x, y [ticks] and yaw ψ [rad] (Kinematics.kt inverse)."""
    lm, tw = mp["inPerTick"] / mp["lateralInPerTick"], mp["trackWidthTicks"]
    return {"leftFront": x - y * lm - psi * tw, "leftBack": x + y * lm - psi * tw,
            "rightBack": x - y * lm + psi * tw, "rightFront": x + y * lm + psi * tw}


def _two_dead_wheel_travel(channels: dict[str, Channel]) -> dict[str, np.ndarray]:
    """Each mecanum wheel's travel [dead-wheel ticks] from two dead wheels and the IMU's yaw.

    TwoDeadWheelLocalizer (quickstart): the twist of an update is x = Δpar − parYTicks·Δψ,
    y = Δperp − perpXTicks·Δψ, ψ the IMU's yaw (``TWO_DEAD_WHEEL_INPUTS.yaw`` [rad], unwrapped here as
    ``Rotation2d.minus`` does); then ``MecanumKinematics.inverse`` as for three dead wheels.
    """
    dw = _params(channels, "TWO_DEAD_WHEEL_PARAMS", ("parYTicks", "perpXTicks"))
    mp = _params(channels, "MECANUM_PARAMS", ("inPerTick", "lateralInPerTick", "trackWidthTicks"))
    if mp["lateralInPerTick"] == 0:
        raise LogFormatError("MECANUM_PARAMS is not tuned (lateralInPerTick = 0)")
    inputs = channels["TWO_DEAD_WHEEL_INPUTS"]
    par, perp = (inputs.column(k, "position") for k in ("par", "perp"))
    psi = np.unwrap(inputs.column("yaw"))
    psi = psi - psi[0]
    x = par - par[0] - dw["parYTicks"] * psi
    y = perp - perp[0] - dw["perpXTicks"] * psi
    return _mecanum_inverse(x, y, psi, mp)


def _wheels(channels: dict[str, Channel]) -> tuple[Channel, Channel, dict[str, tuple[str, np.ndarray]]]:
    """(command channel, inputs channel, wheel -> (power field, wheel travel [ticks] per input message))."""
    if "MECANUM_COMMAND" in channels and "MECANUM_LOCALIZER_INPUTS" in channels:
        inputs = channels["MECANUM_LOCALIZER_INPUTS"]
        wheels = {w: (f"{w}Power", inputs.column(w, "position")) for w in MECANUM_WHEELS}
        return channels["MECANUM_COMMAND"], inputs, wheels
    if "MECANUM_COMMAND" in channels and "THREE_DEAD_WHEEL_INPUTS" in channels:
        travel = _dead_wheel_travel(channels)
        return channels["MECANUM_COMMAND"], channels["THREE_DEAD_WHEEL_INPUTS"], {
            w: (f"{w}Power", travel[w]) for w in MECANUM_WHEELS}
    if "MECANUM_COMMAND" in channels and "TWO_DEAD_WHEEL_INPUTS" in channels:
        travel = _two_dead_wheel_travel(channels)
        return channels["MECANUM_COMMAND"], channels["TWO_DEAD_WHEEL_INPUTS"], {
            w: (f"{w}Power", travel[w]) for w in MECANUM_WHEELS}
    if "TANK_COMMAND" in channels and "TANK_LOCALIZER_INPUTS" in channels:
        inputs = channels["TANK_LOCALIZER_INPUTS"]
        wheels = {side: (f"{side}Power", np.asarray([np.mean([p["position"] for p in m[side]])
                                                      for m in inputs.messages], dtype=float))
                  for side in ("left", "right")}
        return channels["TANK_COMMAND"], inputs, wheels
    raise LogFormatError(
        "no drive commands with localizer inputs (MECANUM_COMMAND + MECANUM_LOCALIZER_INPUTS, "
        "THREE_DEAD_WHEEL_INPUTS or TWO_DEAD_WHEEL_INPUTS, or TANK_COMMAND + TANK_LOCALIZER_INPUTS); "
        "channels: " + ", ".join(sorted(channels)))


def read_flight_recorder(path: PathArg, *, cpr: float | None = None) -> Recording:
    """Drive runs of a flight log as one recording per wheel and followed trajectory (``segments``).

    Parameters
    ----------
    path
        A FlightRecorder ``.log`` of an OpMode that followed trajectories with the quickstart's
        ``MecanumDrive`` (drive-encoder, two- or three-dead-wheel localizer) or ``TankDrive``.
    cpr
        Counts per revolution of the encoders whose ticks the positions count: the drive motors', or
        the dead wheels' for a dead-wheel localizer (wheel travel is then in dead-wheel ticks, as Road
        Runner's kV is).

    Returns
    -------
    Recording
        Segments ``<wheel>#<n>``: ``voltage`` = power × battery [V], linearly interpolated between the
        logged commands (logged at most every 50 ms) onto the encoder reads; ``position`` [rad] and
        ``counts`` of that wheel's encoder; ``time`` [s] from the first message.

    Raises
    ------
    LogFormatError
        As :func:`read_flight_log_channels`, or no drive commands with localizer inputs.
    OptionError
        Without ``cpr``.
    """
    cpr = check_cpr(cpr)
    channels, warnings = read_flight_log_channels(path)
    name = str(path)
    if cpr is None:
        raise OptionError(f"{name}: a flight log counts encoder ticks: give --cpr (counts per revolution of "
                          "the drive motors' encoders)")
    try:
        command, inputs, wheels = _wheels(channels)
    except LogFormatError as exc:
        raise LogFormatError(str(exc.args[0]) if exc.args else "no drive data", path=name) from None
    tc = command.column("timestamp") * 1e-9
    ti = inputs.column("timestamp") * 1e-9
    t0 = min(tc.min(initial=math.inf), ti.min(initial=math.inf))
    tc, ti = tc - t0, ti - t0
    battery = command.column("voltage")
    applied = {key: command.column(key) * battery for key, _ in wheels.values()}
    times, volts, counts, segments = [], [], [], {}
    n = 0
    for number, (a, b) in enumerate(_blocks(tc), start=1):
        inside = (ti >= a) & (ti <= b)
        if np.count_nonzero(inside) < 10:
            continue
        for wheel, (power_key, travel) in wheels.items():
            v = np.interp(ti[inside], tc, applied[power_key])
            x = travel[inside]
            segments[f"{wheel}#{number}"] = (n, n + x.size)
            n += x.size
            times.append(ti[inside])
            volts.append(v)
            counts.append(x)
    if not segments:
        raise LogFormatError("no followed trajectory with at least 10 encoder reads between drive commands",
                             path=name)
    c = np.concatenate(counts)
    signals = {"voltage": np.concatenate(volts), "counts": c, "position": c * 2 * math.pi / cpr}
    warnings.append(f"{name}: drive commands are logged at most every 50 ms; the voltage between them is "
                    "interpolated linearly, an error the standard errors do not include (kA mostly: a few %)")
    meta = {"format": "roadrunner-flight-log", "cpr": cpr, "channels": sorted(channels), "warnings": warnings,
            "position_unit": "rad"}
    return Recording(np.concatenate(times), signals, metadata=meta, source=name, segments=segments)


# ---- writer (tests and the virtual rig) ----------------------------------------------------------


def schema_of(value: Any) -> Schema:
    """The schema LogFile.kt would derive for a Python value (dict: struct with sorted fields)."""
    if isinstance(value, bool):
        return (BOOLEAN,)
    if isinstance(value, int):
        return (LONG,) if abs(value) >= 2**31 else (INT,)
    if isinstance(value, float):
        return (DOUBLE,)
    if isinstance(value, str):
        return (STRING,)
    if isinstance(value, list):
        return (ARRAY, schema_of(value[0]))
    if isinstance(value, dict):
        return (STRUCT, tuple((k, schema_of(value[k])) for k in sorted(value)))
    raise TypeError(f"no flight-log schema for {type(value).__name__}")


def _encode_schema(schema: Schema) -> bytes:
    tag = schema[0]
    out = struct.pack(">i", tag)
    if tag == STRUCT:
        out += struct.pack(">i", len(schema[1]))
        for name, sub in schema[1]:
            raw = name.encode()
            out += struct.pack(">i", len(raw)) + raw + _encode_schema(sub)
    elif tag == ENUM:
        out += struct.pack(">i", len(schema[1]))
        for name in schema[1]:
            out += struct.pack(">i", len(name.encode())) + name.encode()
    elif tag == ARRAY:
        out += _encode_schema(schema[1])
    return out


def _encode_value(schema: Schema, value: Any) -> bytes:
    tag = schema[0]
    if tag in _PRIMITIVE:
        return struct.pack(_PRIMITIVE[tag][0], value)
    if tag == STRING:
        raw = value.encode()
        return struct.pack(">i", len(raw)) + raw
    if tag == STRUCT:
        return b"".join(_encode_value(sub, value[name]) for name, sub in schema[1])
    if tag == ENUM:
        return struct.pack(">i", schema[1].index(value))
    return struct.pack(">i", len(value)) + b"".join(_encode_value(schema[1], v) for v in value)


def write_flight_log(
    path: PathArg, messages: list[tuple[str, Any]], *, schemas: dict[str, Schema] | None = None
) -> None:
    """Write ``(channel, value)`` messages as LogFile.kt's ``LogWriter`` (version 1) does.

    A channel's schema is ``schemas[channel]`` or :func:`schema_of` its first value.
    """
    schemas = dict(schemas or {})
    index: dict[str, int] = {}
    out = bytearray(MAGIC + struct.pack(">h", 1))
    for channel, value in messages:
        if channel not in index:
            schema = schemas.setdefault(channel, schema_of(value))
            index[channel] = len(index)
            raw = channel.encode()
            out += struct.pack(">ii", 0, len(raw)) + raw + _encode_schema(schema)
        out += struct.pack(">ii", 1, index[channel]) + _encode_value(schemas[channel], value)
    with open(path, "wb") as handle:
        handle.write(bytes(out))
