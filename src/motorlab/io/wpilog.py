"""WPILib data logs (``.wpilog``): a reader for SysId tests and a small writer.

The format (WPILib Data Log File Format Specification 1.0, ``wpiutil/doc/datalog.adoc`` in
allwpilib): an 8-byte header ``WPILOG`` + version 0x0100, a 4-byte extra-header length and the extra
header (UTF-8), then records. Each record has a 1-byte bitfield giving the byte lengths of the entry
ID (1–4), payload size (1–4) and timestamp (1–8, integer microseconds), all little-endian, then the
payload. Entry ID 0 is a control record: Start (0: entry ID, name, type, metadata), Finish (1) and
Set Metadata (2). Data types: ``double``, ``float``, ``int64``, ``boolean``, ``string``, ``raw`` and
the array types ``double[]``, ``float[]``, ``int64[]``, ``boolean[]``, ``string[]``.

WPILib's ``SysIdRoutine`` logs the test state as a string entry ``sysid-test-state-<mechanism>``
(``quasistatic-forward``, ``quasistatic-reverse``, ``dynamic-forward``, ``dynamic-reverse``,
``none``) and each motor's ``voltage-<motor>-<mechanism>``, ``position-…`` and ``velocity-…``
doubles with the unit name as entry metadata (``Volt``, ``Rotation``, ``Rotation per Second``).
"""

from __future__ import annotations

import json
import re
import struct
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from motorlab.errors import LogFormatError, OptionError
from motorlab.io.frc_json import test_kind
from motorlab.io.output import write_bytes_atomic
from motorlab.io.text import PathArg, read_bytes
from motorlab.recording import Recording
from motorlab.units import registry

MAGIC = b"WPILOG"
VERSION = 0x0100

_NUMERIC = {"double": "<f8", "float": "<f4", "int64": "<i8"}
_ARRAYS = {"double[]": "<f8", "float[]": "<f4", "int64[]": "<i8"}


@dataclass
class WpilogEntry:
    """One entry of a data log: its samples in time order.

    Attributes
    ----------
    name
        Entry name, e.g. ``"voltage-left-drive"``.
    type
        Type string (``"double"``, ``"string"`` …).
    timestamps
        Sample times [s] (the log stores integer microseconds).
    values
        A float array for ``double``/``float``/``int64``; a list for the other types (``str``,
        ``bool``, arrays, ``bytes``).
    metadata
        The entry's metadata string (SysId writes the unit name here).
    """

    name: str
    type: str
    timestamps: np.ndarray
    values: Any
    metadata: str = ""

    def __len__(self) -> int:
        return int(self.timestamps.size)


@dataclass
class _Collecting:
    name: str
    type: str
    metadata: str
    timestamps: list[int] = field(default_factory=list)
    payloads: list[bytes] = field(default_factory=list)
    offsets: list[int] = field(default_factory=list)


def _uint(raw: bytes, start: int, length: int) -> int:
    return int.from_bytes(raw[start : start + length], "little")


def _string(raw: bytes, pos: int, end: int, what: str, name: str, at: int) -> tuple[str, int]:
    if pos + 4 > end:
        raise LogFormatError(f"malformed control record at byte {at}: {what} length cut off", path=name)
    length = _uint(raw, pos, 4)
    if pos + 4 + length > end:
        raise LogFormatError(f"malformed control record at byte {at}: {what} runs past the record", path=name)
    try:
        return raw[pos + 4 : pos + 4 + length].decode("utf-8"), pos + 4 + length
    except UnicodeDecodeError:
        raise LogFormatError(f"malformed control record at byte {at}: {what} is not UTF-8", path=name) from None


def _parse(path: PathArg) -> tuple[str, str, dict[str, WpilogEntry], list[str]]:
    """(path, extra header, entries by name, warnings)."""
    name, raw = read_bytes(path)
    if not raw:
        raise LogFormatError("the file is empty", path=name)
    if len(raw) < 12 or raw[:6] != MAGIC:
        raise LogFormatError("not a WPILib data log (it does not start with WPILOG)", path=name)
    version = _uint(raw, 6, 2)
    if version >> 8 != VERSION >> 8:
        raise LogFormatError(f"unsupported data log version {version >> 8}.{version & 0xFF} (reads 1.x)", path=name)
    extra_length = _uint(raw, 8, 4)
    if 12 + extra_length > len(raw):
        raise LogFormatError("header cut off (extra header longer than the file)", path=name)
    extra = raw[12 : 12 + extra_length].decode("utf-8", errors="replace")
    active: dict[int, _Collecting] = {}
    by_name: dict[str, _Collecting] = {}
    warnings: list[str] = []
    orphans = 0
    pos = 12 + extra_length
    size = len(raw)
    while pos < size:
        at = pos
        bits = raw[pos]
        id_len = (bits & 0x3) + 1
        size_len = ((bits >> 2) & 0x3) + 1
        ts_len = ((bits >> 4) & 0x7) + 1
        head_end = pos + 1 + id_len + size_len + ts_len
        if head_end > size:
            warnings.append(f"record at byte {at} cut off (file truncated); the rest is ignored")
            break
        entry_id = _uint(raw, pos + 1, id_len)
        length = _uint(raw, pos + 1 + id_len, size_len)
        stamp = _uint(raw, pos + 1 + id_len + size_len, ts_len)
        end = head_end + length
        if end > size:
            warnings.append(f"record at byte {at} cut off (file truncated); the rest is ignored")
            break
        pos = end
        if entry_id != 0:
            entry = active.get(entry_id)
            if entry is None:
                orphans += 1
                continue
            entry.timestamps.append(stamp)
            entry.payloads.append(raw[head_end:end])
            entry.offsets.append(at)
            continue
        if length < 5:
            raise LogFormatError(f"malformed control record at byte {at}: too short", path=name)
        kind = raw[head_end]
        target = _uint(raw, head_end + 1, 4)
        if kind == 0:
            entry_name, p = _string(raw, head_end + 5, end, "entry name", name, at)
            entry_type, p = _string(raw, p, end, "entry type", name, at)
            metadata, p = _string(raw, p, end, "metadata", name, at)
            existing = by_name.get(entry_name)
            if existing is not None and existing.type == entry_type:
                active[target] = existing  # restarted after a Finish: same series continues
            else:
                if existing is not None:
                    warnings.append(f"entry {entry_name!r} restarted with type {entry_type}; earlier data dropped")
                collecting = _Collecting(entry_name, entry_type, metadata)
                active[target] = by_name[entry_name] = collecting
        elif kind == 1:
            active.pop(target, None)
        elif kind == 2:
            metadata, _ = _string(raw, head_end + 5, end, "metadata", name, at)
            if target in active:
                active[target].metadata = metadata
        else:
            warnings.append(f"unknown control record type {kind} at byte {at} ignored")
    if orphans:
        warnings.append(f"{orphans} records for entries never started were ignored")
    entries = {key: _decode(c, name) for key, c in by_name.items()}
    return name, extra, entries, warnings


def _decode(entry: _Collecting, path: str) -> WpilogEntry:
    order = np.argsort(np.asarray(entry.timestamps, dtype=np.int64), kind="stable")
    stamps = np.asarray(entry.timestamps, dtype=np.int64)[order] * 1e-6
    payloads = [entry.payloads[i] for i in order]
    offsets = [entry.offsets[i] for i in order]
    values: Any
    if entry.type in _NUMERIC:
        dtype = np.dtype(_NUMERIC[entry.type])
        for payload, at in zip(payloads, offsets, strict=True):
            if len(payload) != dtype.itemsize:
                raise LogFormatError(
                    f"{entry.type} record of {entry.name!r} at byte {at} has {len(payload)} bytes, "
                    f"expected {dtype.itemsize}",
                    path=path,
                )
        values = np.frombuffer(b"".join(payloads), dtype=dtype).astype(float)
    elif entry.type == "boolean":
        values = [bool(p[0]) if p else False for p in payloads]
    elif entry.type in ("string", "json"):
        values = [p.decode("utf-8", errors="replace") for p in payloads]
    elif entry.type in _ARRAYS:
        dtype = np.dtype(_ARRAYS[entry.type])
        values = [np.frombuffer(p[: len(p) - len(p) % dtype.itemsize], dtype=dtype).astype(float) for p in payloads]
    elif entry.type == "boolean[]":
        values = [[bool(b) for b in p] for p in payloads]
    elif entry.type == "string[]":
        values = [_decode_strings(p) for p in payloads]
    else:  # raw, struct:..., protobuf...: kept as bytes
        values = payloads
    return WpilogEntry(entry.name, entry.type, stamps, values, entry.metadata)


def _decode_strings(payload: bytes) -> list[str]:
    count = _uint(payload, 0, 4) if len(payload) >= 4 else 0
    out, pos = [], 4
    for _ in range(count):
        length = _uint(payload, pos, 4)
        out.append(payload[pos + 4 : pos + 4 + length].decode("utf-8", errors="replace"))
        pos += 4 + length
    return out


def read_wpilog_entries(path: PathArg) -> dict[str, WpilogEntry]:
    """Every entry of a data log, by name, samples sorted by time.

    Raises
    ------
    LogFormatError
        Missing/empty file, no ``WPILOG`` header, an unsupported major version, a malformed control
        record, a numeric record of the wrong size. A record cut off at the end of the file (power
        lost while logging) ends the reading quietly.
    """
    return _parse(path)[2]


# --- SysId tests -------------------------------------------------------------------------------

_ROLES = {
    "voltage": ("voltage", "volts"),
    "position": ("position", "distance"),
    "velocity": ("velocity",),
}
_NOT_MOTOR_VOLTAGE = ("battery", "bus", "supply", "input")

_UNIT_WORDS = {
    "rotation": "revolution",
    "revolution": "revolution",
    "rev": "revolution",
    "radian": "rad",
    "rad": "rad",
    "degree": "degree",
    "deg": "degree",
    "meter": "m",
    "metre": "m",
    "m": "m",
    "foot": "ft",
    "feet": "ft",
    "ft": "ft",
    "inch": "inch",
    "inche": "inch",
    "in": "inch",
    "second": "s",
    "sec": "s",
    "s": "s",
    "minute": "min",
    "min": "min",
    "volt": "V",
    "v": "V",
}


def _pint_unit(text: str) -> str | None:
    """A unit name as SysId/vendor loggers write it (``Rotation per Second``) as a pint string."""
    text = text.strip()
    if text.startswith("{"):  # JSON metadata, e.g. {"source": "NT", "unit": "rotations"}
        try:
            found = json.loads(text)
        except (ValueError, RecursionError):  # not JSON, an integer of 4,300 digits, or nested too deeply
            return None
        unit = found.get("unit", found.get("units")) if isinstance(found, dict) else None
        return _pint_unit(unit) if isinstance(unit, str) and not unit.startswith("{") else None
    if not text:
        return None
    words = re.split(r"[\s_]+|-", text.replace("/", " per ").lower())
    out: list[str] = []
    for word in words:
        if not word:
            continue
        if word == "per":
            out.append("/")
            continue
        base = word[:-1] if word.endswith("s") and word[:-1] in _UNIT_WORDS else word
        if base not in _UNIT_WORDS:
            return _pint_name(text)
        if out and out[-1] != "/":
            out.append("*")
        out.append(_UNIT_WORDS[base])
    return "".join(out) or None


def _pint_name(text: str) -> str | None:
    """``text`` itself when pint knows it as a unit (``rpm``, ``rad/s``), else None."""
    try:
        registry().parse_units(text)
    except Exception:  # pint raises several types for unknown names
        return None
    return text


def _si_factor(unit: str, *, per_time: bool) -> tuple[float, str]:
    """Factor from ``unit`` to SI and the SI unit (rad, m, rad/s or m/s)."""
    ureg = registry()
    for si in ("rad", "m"):
        target = f"{si}/s" if per_time else si
        try:
            quantity = ureg.Quantity(1.0, unit)
            if si == "rad" and quantity.dimensionality != ureg.Quantity(1.0, target).dimensionality:
                continue
            return float(quantity.to(target).magnitude), target
        except Exception:  # pint: undefined unit or wrong dimension
            continue
    raise OptionError(f"unit {unit!r} is not an angle or a length{' per time' if per_time else ''}")


def _find(entries: dict[str, WpilogEntry], role: str, given: str | None, mechanism: str | None, path: str) -> str:
    if given is not None:
        if given not in entries:
            raise OptionError(f"{role}_entry {given!r} is not in {path}")
        if entries[given].type not in _NUMERIC:
            raise OptionError(f"{role}_entry {given!r} is a {entries[given].type} entry, not a number")
        return given
    candidates = []
    for key, entry in entries.items():
        base = key.rsplit("/", 1)[-1].lower()
        if entry.type not in _NUMERIC or not any(w in base for w in _ROLES[role]):
            continue
        if role == "voltage" and any(w in base for w in _NOT_MOTOR_VOLTAGE):
            continue
        candidates.append(key)
    if mechanism and len(candidates) > 1:
        own = [c for c in candidates if c.lower().endswith("-" + mechanism.lower())]
        candidates = own or candidates
    if len(candidates) == 1:
        return candidates[0]
    if not candidates:
        raise LogFormatError(f"no numeric entry for {role} (name containing {' or '.join(_ROLES[role])})", path=path)
    raise LogFormatError(
        f"several entries could be the {role}: {', '.join(sorted(candidates))}; choose one with {role}_entry=",
        path=path,
    )


def _state_entry(entries: dict[str, WpilogEntry], given: str | None, path: str) -> str:
    if given is not None:
        if given not in entries or entries[given].type != "string":
            raise OptionError(f"state_entry {given!r} is not a string entry of {path}")
        return given
    found = [
        k
        for k, e in entries.items()
        if e.type == "string" and ("sysid-test-state" in k.lower() or k.lower().endswith("sysidteststate"))
    ]
    if len(found) == 1:
        return found[0]
    if not found:
        raise LogFormatError("no SysId test-state entry (a string entry named sysid-test-state-...)", path=path)
    raise LogFormatError(f"several test-state entries: {', '.join(sorted(found))}; choose with state_entry=", path=path)


def _nearest(source_t: np.ndarray, target_t: np.ndarray) -> np.ndarray:
    """Index into ``source_t`` (sorted) of the sample nearest each ``target_t``."""
    right = np.searchsorted(source_t, target_t).clip(1, source_t.size - 1) if source_t.size > 1 else None
    if right is None:
        return np.zeros(target_t.size, dtype=int)
    left = right - 1
    return np.where(np.abs(target_t - source_t[left]) <= np.abs(source_t[right] - target_t), left, right)


def read_wpilog(
    path: PathArg,
    *,
    voltage_entry: str | None = None,
    position_entry: str | None = None,
    velocity_entry: str | None = None,
    state_entry: str | None = None,
    position_unit: str | None = None,
    velocity_unit: str | None = None,
) -> Recording:
    """Read SysId tests from a WPILib data log.

    Parameters
    ----------
    path
        The ``.wpilog`` file.
    voltage_entry, position_entry, velocity_entry
        Entry names; by default the numeric entry whose name contains ``voltage`` (not battery/bus),
        ``position`` (or ``distance``), ``velocity``, preferring those ending with the mechanism
        name of the state entry (SysIdRoutine's ``voltage-<motor>-<mechanism>``).
    state_entry
        The test-state string entry; by default the one named ``sysid-test-state-…``.
    position_unit, velocity_unit
        Units the entries are logged in (pint strings: ``"rotation"``, ``"rad"``, ``"m"``,
        ``"rotation/s"``, ``"rpm"``). By default the entries' metadata (SysId writes ``Rotation``,
        ``Rotation per Second``, ``Meter`` …); the velocity unit defaults to the velocity entry's
        metadata, else to the position unit per second.

    Returns
    -------
    Recording
        On the voltage entry's timestamps [s]: ``voltage`` [V], ``position`` [rad or m], ``velocity``
        [rad/s or m/s]; ``segments`` per test (names as logged: ``quasistatic-forward`` …, a repeated
        test gets ``#2``). ``metadata``: ``format`` ``"wpilog"``, ``entries`` (role -> name),
        ``entry_units`` (metadata strings), ``position_unit``/``velocity_unit`` (SI), ``mechanism``,
        ``segment_kinds``, ``extra_header``, ``rows_dropped``, ``repeated_fraction`` (rows whose
        position and velocity repeat the previous row's) and ``warnings``.

    Raises
    ------
    LogFormatError
        Not a data log, no test-state entry, no or ambiguous signal entries, a unit that cannot be
        determined, NaN values, no test found.
    OptionError
        A named entry or unit that does not exist or does not fit.

    Notes
    -----
    Resampling: SysIdRoutine appends voltage, position and velocity in the same loop iteration,
    microseconds apart, so each voltage sample takes the *nearest* position and velocity sample
    (no interpolation: values refreshed by slower status frames stay as logged). Voltage samples
    farther than two sample intervals outside the position/velocity records are dropped. The test
    state of a sample is the last state logged up to half a voltage interval after it (the state may
    be appended just after the voltage in the same iteration).
    """
    name, extra, entries, warnings = _parse(path)
    state_name = _state_entry(entries, state_entry, name)
    lowered = state_name.lower()
    mechanism = state_name[lowered.index("sysid-test-state-") + 17 :] if "sysid-test-state-" in lowered else None
    roles = {role: _find(entries, role, given, mechanism, name) for role, given in
             (("voltage", voltage_entry), ("position", position_entry), ("velocity", velocity_entry))}
    voltage = entries[roles["voltage"]]
    position = entries[roles["position"]]
    velocity = entries[roles["velocity"]]
    _check_samples({"voltage": voltage, "position": position, "velocity": velocity}, name)
    volt_factor, pos_factor, vel_factor, pos_si, vel_si = _unit_factors(
        voltage, position, velocity, position_unit, velocity_unit, name, warnings
    )
    t, keep, step = _overlap(voltage, position, velocity, name)
    signals = {
        "voltage": voltage.values[keep] * volt_factor,
        "position": position.values[_nearest(position.timestamps, t)] * pos_factor,
        "velocity": velocity.values[_nearest(velocity.timestamps, t)] * vel_factor,
    }
    moved = np.column_stack([signals["position"], signals["velocity"]])
    repeated = np.all(np.diff(moved, axis=0) == 0, axis=1)
    state = entries[state_name]
    index = np.searchsorted(state.timestamps, t + 0.5 * step, side="right") - 1
    labels = [state.values[i] if i >= 0 else "" for i in index]
    segments = _segments(labels)
    if not segments:
        raise LogFormatError(f"no SysId test in {state_name!r} (states seen: {sorted(set(labels))})", path=name)
    metadata = {
        "format": "wpilog",
        "entries": {**roles, "state": state_name},
        "entry_units": {"voltage": voltage.metadata, "position": position.metadata, "velocity": velocity.metadata},
        "position_unit": pos_si,
        "velocity_unit": vel_si,
        "mechanism": mechanism,
        "segment_kinds": {key: test_kind(key) for key in segments},
        "extra_header": extra,
        "rows_dropped": int((~keep).sum()),
        "repeated_fraction": float(repeated.mean()) if repeated.size else 0.0,
        "warnings": warnings,
    }
    return Recording(time=t, signals=signals, metadata=metadata, source=name, segments=segments)


def _check_samples(signals: dict[str, WpilogEntry], path: str) -> None:
    """Each signal entry (by role) holds samples, all of them finite."""
    for role, entry in signals.items():
        bad = np.flatnonzero(~np.isfinite(entry.values))
        if bad.size:
            raise LogFormatError(
                f"{role} entry {entry.name!r} has a non-finite value at t = {entry.timestamps[bad[0]]:.6f} s", path=path
            )
        if len(entry) == 0:
            raise LogFormatError(f"{role} entry {entry.name!r} has no samples", path=path)


def _unit_factors(
    voltage: WpilogEntry,
    position: WpilogEntry,
    velocity: WpilogEntry,
    position_unit: str | None,
    velocity_unit: str | None,
    path: str,
    warnings: list[str],
) -> tuple[float, float, float, str, str]:
    """Factors to SI of the voltage, position and velocity entries, then the SI position and velocity units.

    The units given by the caller win over the entries' metadata; a voltage metadata that is not a
    voltage unit is taken as volts with a warning appended to ``warnings``.
    """
    pos_unit = position_unit or _pint_unit(position.metadata)
    if pos_unit is None:
        raise LogFormatError(
            f"position entry {position.name!r} does not say its unit (metadata {position.metadata!r}); "
            "give position_unit= (e.g. 'rotation', 'rad', 'm')",
            path=path,
        )
    pos_factor, pos_si = _si_factor(pos_unit, per_time=False)
    # The velocity entry's own metadata wins over "position unit per second" (a log may give rpm).
    vel_unit = velocity_unit or _pint_unit(velocity.metadata) or f"({pos_unit})/s"
    vel_factor, vel_si = _si_factor(vel_unit, per_time=True)
    if vel_si != f"{pos_si}/s":
        raise OptionError(f"velocity unit {vel_unit!r} does not match position unit {pos_unit!r}")
    volt_unit = _pint_unit(voltage.metadata)
    volt_factor = 1.0
    if volt_unit is not None:
        try:
            volt_factor = float(registry().Quantity(1.0, volt_unit).to("V").magnitude)
        except Exception:  # not a voltage unit in the metadata: the name said voltage, take volts
            warnings.append(f"voltage metadata {voltage.metadata!r} is not a voltage unit; taken as volts")
    return volt_factor, pos_factor, vel_factor, pos_si, vel_si


def _overlap(
    voltage: WpilogEntry, position: WpilogEntry, velocity: WpilogEntry, path: str
) -> tuple[np.ndarray, np.ndarray, float]:
    """Voltage timestamps [s] kept, the mask keeping them, and the voltage sample interval [s].

    A voltage sample is kept when it lies no more than two (largest median) sample intervals outside
    the span that both the position and the velocity records cover.
    """
    t = voltage.timestamps
    step = float(np.median(np.diff(t))) if t.size > 1 else 0.0
    steps = [step] + [float(np.median(np.diff(e.timestamps))) for e in (position, velocity) if len(e) > 1]
    tolerance = 2.0 * max(steps)
    first = max(position.timestamps[0], velocity.timestamps[0]) - tolerance
    last = min(position.timestamps[-1], velocity.timestamps[-1]) + tolerance
    keep = (t >= first) & (t <= last)
    t = t[keep]
    if t.size == 0:
        raise LogFormatError("the voltage and position/velocity entries do not overlap in time", path=path)
    return t, keep, step


def _segments(labels: Sequence[str]) -> dict[str, tuple[int, int]]:
    """Runs of equal test state (``none`` and unknown excluded); repeats named ``name#2`` …"""
    segments: dict[str, tuple[int, int]] = {}
    start = 0
    for k in range(1, len(labels) + 1):
        if k < len(labels) and labels[k] == labels[start]:
            continue
        label = labels[start]
        if label and label.lower() != "none":
            key, n = label, 1
            while key in segments:
                n += 1
                key = f"{label}#{n}"
            segments[key] = (start, k)
        start = k
    return segments


# --- writing -----------------------------------------------------------------------------------


def _encode_value(entry_type: str, value: Any) -> bytes:
    if entry_type in _NUMERIC:
        return np.asarray(value, dtype=_NUMERIC[entry_type]).tobytes()
    if entry_type in _ARRAYS:
        return np.asarray(value, dtype=_ARRAYS[entry_type]).tobytes()
    if entry_type == "boolean":
        return b"\x01" if value else b"\x00"
    if entry_type == "boolean[]":
        return bytes(1 if v else 0 for v in value)
    if entry_type in ("string", "json"):
        return str(value).encode("utf-8")
    if entry_type == "string[]":
        out = struct.pack("<I", len(value))
        for item in value:
            data = str(item).encode("utf-8")
            out += struct.pack("<I", len(data)) + data
        return out
    return bytes(value)


def _record(entry_id: int, stamp_us: int, payload: bytes) -> bytes:
    def width(n: int, most: int) -> int:
        return min(max(1, (n.bit_length() + 7) // 8), most)

    id_len, size_len, ts_len = width(entry_id, 4), width(len(payload), 4), width(stamp_us, 8)
    bits = (id_len - 1) | ((size_len - 1) << 2) | ((ts_len - 1) << 4)
    return (
        bytes([bits])
        + entry_id.to_bytes(id_len, "little")
        + len(payload).to_bytes(size_len, "little")
        + stamp_us.to_bytes(ts_len, "little")
        + payload
    )


def _text(value: str) -> bytes:
    data = value.encode("utf-8")
    return struct.pack("<I", len(data)) + data


def write_wpilog(path: PathArg, entries: Iterable[WpilogEntry], *, extra_header: str = "") -> None:
    """Write entries as a WPILib data log (format 1.0), records in time order.

    Parameters
    ----------
    path
        File to create (overwritten if it exists).
    entries
        The entries; ``timestamps`` [s] ≥ 0 (stored as integer microseconds), ``values`` one per
        timestamp, of the entry's ``type``.
    extra_header
        The free extra-header string.

    Raises
    ------
    OptionError
        Duplicate names, timestamps and values of different lengths, negative or non-finite times.

    Notes
    -----
    Every entry is started (control record type 0) at its first timestamp, before any data record;
    data records of all entries are then interleaved by time, as a robot program writes them.
    """
    entries = list(entries)
    names = [e.name for e in entries]
    if len(set(names)) != len(names):
        raise OptionError("write_wpilog: duplicate entry names")
    header = MAGIC + struct.pack("<H", VERSION) + _text(extra_header)
    starts: list[bytes] = []
    records: list[tuple[int, int, bytes]] = []
    for entry_id, entry in enumerate(entries, start=1):
        stamps = np.asarray(entry.timestamps, dtype=float)
        if len(entry.values) != stamps.size:
            raise OptionError(f"write_wpilog: {entry.name!r} has {len(entry.values)} values for {stamps.size} times")
        if stamps.size and (not np.all(np.isfinite(stamps)) or stamps.min() < 0):
            raise OptionError(f"write_wpilog: {entry.name!r} has negative or non-finite timestamps")
        micros = np.rint(stamps * 1e6).astype(np.int64)
        first = int(micros.min()) if micros.size else 0
        payload = (
            b"\x00" + struct.pack("<I", entry_id) + _text(entry.name) + _text(entry.type) + _text(entry.metadata)
        )
        starts.append(_record(0, first, payload))
        for k, stamp in enumerate(micros):
            payload = _encode_value(entry.type, entry.values[k])
            records.append((int(stamp), entry_id, _record(entry_id, int(stamp), payload)))
    records.sort(key=lambda r: r[0])  # stable: same-time records keep the entries' order
    write_bytes_atomic(path, header + b"".join(starts) + b"".join(r[2] for r in records))


def write_sysid_wpilog(
    path: PathArg,
    time_s: np.ndarray,
    voltage: np.ndarray,
    position: np.ndarray,
    velocity: np.ndarray,
    states: Sequence[str],
    *,
    mechanism: str = "mechanism",
    motor: str = "motor",
    unit: str = "Rotation",
) -> None:
    """Write a data log the way WPILib's ``SysIdRoutine`` does (for the virtual rig and tests).

    Parameters
    ----------
    path
        File to create.
    time_s
        Sample times [s] of the routine's loop.
    voltage
        Applied voltage [V] (signed).
    position, velocity
        In SI: [rad], [rad/s] for angular ``unit`` values, [m], [m/s] for ``"Meter"``; written in
        ``unit`` and ``unit per Second``.
    states
        Test state per sample: ``"quasistatic-forward"``, ``"dynamic-reverse"``, ``"none"`` …
    mechanism, motor
        Names in the entries ``sysid-test-state-<mechanism>``, ``voltage-<motor>-<mechanism>`` …
    unit
        ``"Rotation"``, ``"Radian"``, ``"Degree"`` or ``"Meter"`` (as SysIdRoutine names units).
    """
    time_s = np.asarray(time_s, dtype=float)
    pint_unit = _pint_unit(unit)
    if pint_unit is None:
        raise OptionError(f"write_sysid_wpilog: unknown unit {unit!r}")
    factor, _ = _si_factor(pint_unit, per_time=False)
    if len(states) != time_s.size:
        raise OptionError("write_sysid_wpilog: one state per sample is needed")
    suffix = f"{motor}-{mechanism}"
    write_wpilog(
        path,
        [
            WpilogEntry(f"sysid-test-state-{mechanism}", "string", time_s, list(states)),
            WpilogEntry(f"voltage-{suffix}", "double", time_s, np.asarray(voltage, dtype=float), "Volt"),
            WpilogEntry(f"position-{suffix}", "double", time_s, np.asarray(position, dtype=float) / factor, unit),
            WpilogEntry(
                f"velocity-{suffix}", "double", time_s, np.asarray(velocity, dtype=float) / factor, f"{unit} per Second"
            ),
        ],
        extra_header="motorlab virtual rig",
    )


def is_wpilog(head: bytes) -> bool:
    """True when ``head`` (the first bytes of a file) starts a WPILib data log."""
    return head[:6] == MAGIC


__all__ = [
    "WpilogEntry",
    "is_wpilog",
    "read_wpilog",
    "read_wpilog_entries",
    "write_sysid_wpilog",
    "write_wpilog",
]
