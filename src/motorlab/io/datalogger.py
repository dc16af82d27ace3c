"""The FTC SDK's Datalogger files (``Timestamp,OpModeStatus,Loop Counter,<field>…``), read as a robot writes them.

The FTC wiki's Datalogging tutorial (FIRST-Tech-Challenge/FtcRobotController wiki, "Datalogging", credited
to @Windwoes) gives teams two files, ``Datalogger.java`` and the sample OpMode ``ConceptDatalogger``
("Concept Datalogger v01"), copied unchanged into hundreds of team repositories. What they write, from
that source:

* ``Datalogger.Builder.build()`` puts a ``Timestamp`` field first when ``AutoTimestamp.DECIMAL_SECONDS``
  is asked for: ``TimestampField.writeToBuffer`` writes the seconds since the logger was built, from
  ``System.currentTimeMillis()``, with ``DecimalFormat("000.000")`` (ms resolution: ``013.817``);
* ``writeHeader()`` writes the field names joined by ``,``; ``writeLine()`` each field's text joined by
  ``,``, with no quoting, to ``/sdcard/FIRST/java/src/Datalogs/<name>.txt`` (OnBot Java) or
  ``/sdcard/FIRST/Datalogs/<name>.csv``;
* a ``GenericField`` keeps the text of its last ``set``, ``""`` before the first; ``set(double)`` and
  ``set(float)`` format ``"%.3f"`` in the robot's default locale (a decimal comma on a robot set to
  French or German makes an extra field), ``set(int)`` ``Integer.toString``;
* the sample's fields are ``OpModeStatus`` (the text ``INIT`` in one row written before START, then
  ``RUNNING``), ``Loop Counter`` (empty in the INIT row), ``Yaw``, ``Pitch``, ``Roll`` (IMU angles) and
  ``Battery`` (``VoltageSensor.getVoltage()``, volts); teams replace these with their own names
  (``Intake``: ``DcMotorEx.getVelocity()``, encoder ticks per second).

So the reader takes ``Timestamp`` as the time [s], ``OpModeStatus`` as a text column (the ``RUNNING`` rows
are the data; the others are kept in the metadata), ``Loop Counter`` as the loop number (gaps reported),
and every other field by its name, as the CSV reader names a header in words
(:func:`motorlab.io.headers.resolve_column`, ``--column`` rules first): ``Battery`` is the battery voltage
[V]. A velocity or position without a unit is the SDK's: encoder ticks (per second), turned into rad(/s)
with the counts per revolution (``cpr``), which the file never holds. A field no word names (``Intake``,
``Yaw``) is left out with a warning that names the ``--column`` rule that would read it; when no field
can be read at all, that is the refusal.
"""

from __future__ import annotations

import math
import re
from collections import Counter
from collections.abc import Sequence
from typing import Any

import numpy as np

from motorlab.errors import LogFormatError, OptionError
from motorlab.io.glitches import screen_glitches
from motorlab.io.headers import (
    QUANTITIES,
    ColumnRule,
    current_mapping,
    parse_column_mapping,
    resolve_column,
    to_si,
    unknown_column_message,
    worded_column,
)
from motorlab.io.text import PathArg, TextFile, check_cpr, parse_number, read_text
from motorlab.recording import SIGNALS, Recording

#: The fields the SDK's Datalogger and its sample write whatever the team logs (lower case).
TIMESTAMP, STATUS, LOOP = "timestamp", "opmodestatus", "loop counter"
#: The status of the rows that are the run (ConceptDatalogger sets it after waitForStart()).
RUNNING = "RUNNING"
#: Quantities a Datalogger field holds in encoder ticks when it names no unit (the SDK's DcMotorEx units).
_TICKS = {"velocity": "count/s", "position": "count", "counts": "count"}


#: What to log for a signal a Datalogger file lacks, in words (``Recording.require`` adds it to its refusal).
LACKS = {
    "voltage": "log the voltage applied to the motor, power × battery voltage, in a field named 'Voltage' (V)",
    "position": "log the encoder, getCurrentPosition(), in a field named 'Position' (ticks) and give the "
                "encoder's counts per revolution",
    "current": "log the motor current, getCurrent(CurrentUnit.AMPS), in a field named 'Current (A)'",
}


#: A field whose unit in brackets is encoder ticks or counts (per second).
_TICK_UNIT = re.compile(
    r"^(?P<words>.*?)\s*[(\[]\s*(?:ticks?|counts?)\s*(?P<per>(?:/|per)\s*(?:s|sec|second))?\s*[)\]]$", re.IGNORECASE)


def is_datalogger_header(fields: Sequence[str]) -> bool:
    """True for the header a Datalogger writes: an ``OpModeStatus`` field, or ``Timestamp`` first and a
    ``Loop Counter`` (the sample's fields; a team may rename the others)."""
    lower = [f.strip().lower() for f in fields]
    return len(lower) > 1 and (STATUS in lower or (lower[0] == TIMESTAMP and LOOP in lower))


def _target(field: str, rules: Sequence[ColumnRule], name: str) -> tuple[str, str] | str | None:
    """(signal, unit) of a data field, None to skip it, or ``"unknown"``; ticks where the SDK's units apply."""
    explicit = next((r for r in rules if r.header.casefold() == field.strip().casefold()), None)
    if explicit is not None:
        if explicit.quantity is None:
            return None
        if explicit.unit is None and explicit.quantity in _TICKS:
            return QUANTITIES[explicit.quantity][0], _TICKS[explicit.quantity]
        return resolve_column(field, rules)
    ticks = _TICK_UNIT.match(field.strip())
    if ticks:  # "Intake (ticks/s)", "Arm position [ticks]": pint's count is dimensionless, so said here
        words = ticks.group("words").lower()
        per_second = bool(ticks.group("per"))
        quantity = "velocity" if per_second else ("position" if "position" in words else "counts")
        return QUANTITIES[quantity][0], "count/s" if per_second else "count"
    try:
        worded = worded_column(field)
    except LogFormatError as exc:
        bare = next((q for q in _TICKS if f"names a {q} without a unit" in str(exc)), None)
        if bare is None:  # a unit that is not one of the quantity
            raise LogFormatError(str(exc), path=name, line=1) from None
        return QUANTITIES[bare][0], _TICKS[bare]  # "Intake Velocity": the SDK's ticks per second
    if worded is None:
        return "unknown"
    quantity, unit = worded
    signal, si = QUANTITIES[quantity]
    return signal, unit or _TICKS.get(quantity) or si


def read_datalogger(path: PathArg, *, cpr: float | None = None, columns: Any = None) -> Recording:
    """Read an FTC SDK Datalogger file (see the module's notes for what the SDK writes).

    Parameters
    ----------
    path
        The ``.txt`` (OnBot Java) or ``.csv`` file the Datalogger wrote, as it is.
    cpr
        Encoder counts per revolution [count/rev]: needed for a field in ticks per second (a velocity),
        used for one in ticks (a position is then added beside the counts).
    columns
        ``--column`` rules for the fields (``"Intake=velocity"``: ticks per second; ``"Intake=velocity
        [rpm]"``; ``"Yaw=skip"``), as :func:`motorlab.io.read_csv` takes them; default: the rules in force.

    Returns
    -------
    Recording
        ``time`` [s] from ``Timestamp`` (the row index when the file has none); the ``RUNNING`` rows'
        fields in SI (``battery`` [V], ``velocity`` [rad/s], ``counts``, ``position`` [rad] …).
        ``metadata``: ``format="datalogger"``, ``cpr``, ``columns`` (the header), ``fields`` (field ->
        signal), ``units``, ``status_rows`` (rows per OpModeStatus), ``init`` (the last INIT row's fields
        as written), ``loop_counter`` (first, last, missed loops), ``unread`` (fields no name says the
        quantity of), ``lacks`` (signal -> what to log for it, in words) and ``warnings``.

    Raises
    ------
    LogFormatError
        No header, a row with another number of fields than the header (a decimal comma, a comma in a
        text value), a value that is not a number, time going backwards, no field that names a quantity
        (the message gives the ``--column`` rule), no ``RUNNING`` row with every field set.
    OptionError
        A field in ticks per second and no ``cpr``; an impossible ``cpr``.
    """
    text = read_text(path)
    name = text.path
    numbered = text.numbered()
    if not numbered:
        raise LogFormatError("the file is empty", path=name)
    header_no, header_line = numbered[0]
    header = [f.strip() for f in header_line.split(",")]
    lower = [f.lower() for f in header]
    if not is_datalogger_header(header):
        raise LogFormatError("not a Datalogger header (Timestamp,OpModeStatus,Loop Counter,…)", path=name,
                             line=header_no)
    rules = parse_column_mapping(columns) if columns is not None else current_mapping()
    time_at = lower.index(TIMESTAMP) if TIMESTAMP in lower else None
    status_at = lower.index(STATUS) if STATUS in lower else None
    loop_at = lower.index(LOOP) if LOOP in lower else None
    fields, unread = _fields(header, rules, name, skip=(time_at, status_at, loop_at))
    if not fields:
        first = unread[0] if unread else ""
        raise LogFormatError(f"Datalogger file: {unknown_column_message(first, rules)}", path=name, line=header_no)
    warnings = [f"{name}: field {f!r} names no quantity and is not read: map it with --column \"{f}=QUANTITY\""
                for f in unread]

    rows = _split_rows(text, numbered[1:], header, warnings)
    statuses = Counter(values[status_at] for _n, values in rows) if status_at is not None else Counter()
    running = [r for r in rows if status_at is None or r[1][status_at] == RUNNING] if statuses.get(RUNNING) else rows
    init = [values for _n, values in rows if status_at is not None and values[status_at] == "INIT"]
    running = _set_rows(running, fields, header, name, warnings)

    lines = np.array([n for n, _v in running], dtype=int)
    data = {k: np.array([parse_number(v[k], path=name, line=n, column=header[k]) for n, v in running])
            for k in fields}
    if time_at is not None:
        time = np.array([parse_number(v[time_at], path=name, line=n, column=header[time_at]) for n, v in running])
        back = np.flatnonzero(np.diff(time) < 0)
        if back.size:
            raise LogFormatError("time goes backwards", path=name, line=int(lines[back[0] + 1]))
    else:
        time = np.arange(len(running), dtype=float)
    metadata: dict[str, Any] = {"time": "row index"} if time_at is None else {}

    cpr = check_cpr(cpr)
    signals, units = _signals(fields, data, header, cpr, name)
    loops = _loop_counter([v[loop_at] for _n, v in running]) if loop_at is not None else {}
    unread_hint = f" (or, if the field {unread[0]!r} holds it, --column \"{unread[0]}=QUANTITY\")" if unread else ""
    lacks = {signal: f"a Datalogger file holds only the fields its OpMode logged: {how}{unread_hint}"
             for signal, how in LACKS.items() if signal not in signals}
    metadata.update({
        "format": "datalogger",
        "lacks": lacks,
        "cpr": cpr,
        "columns": header,
        "fields": {header[k]: target[0] for k, target in fields.items()},
        "units": units,
        "status_rows": dict(statuses),
        "init": dict(zip(header, init[-1], strict=True)) if init else {},
        "loop_counter": loops,
        "unread": unread,
        "comments": [],
        "warnings": warnings,
    })
    return screen_glitches(Recording(time=time, signals=signals, metadata=metadata, source=name, lines=lines))


def _fields(header: list[str], rules: Sequence[ColumnRule], name: str,
            skip: tuple[int | None, ...]) -> tuple[dict[int, tuple[str, str]], list[str]]:
    """Index -> (signal, unit) of the fields read, and the names of those no word names."""
    fields: dict[int, tuple[str, str]] = {}
    unread: list[str] = []
    for k, field in enumerate(header):
        if k in skip:
            continue
        target = _target(field, rules, name)
        if isinstance(target, tuple):
            fields[k] = target
        elif target == "unknown":
            unread.append(field)
    return fields, unread


def _split_rows(text: TextFile, numbered: list[tuple[int, str]], header: list[str],
                warnings: list[str]) -> list[tuple[int, list[str]]]:
    """(line number, fields) of each row; a row with another number of fields than the header refused."""
    rows: list[tuple[int, list[str]]] = []
    for number, line in numbered:
        values = [v.strip() for v in line.split(",")]
        if len(values) != len(header):
            if text.may_be_truncated(number) and len(values) < len(header):
                warnings.append(f"{text.path}:{number}: truncated last line dropped ({line[:40]!r})")
                break
            raise LogFormatError(
                f"expected {len(header)} fields ({', '.join(header)}), found {len(values)}: a value holding a "
                "comma (a decimal comma: the Datalogger formats numbers in the robot's language settings; "
                "set the Control Hub's language to English, or format with Locale.US)", path=text.path, line=number)
        rows.append((number, values))
    return rows


def _signals(fields: dict[int, tuple[str, str]], data: dict[int, np.ndarray], header: list[str], cpr: float | None,
             name: str) -> tuple[dict[str, np.ndarray], dict[str, str]]:
    """The fields' values in SI under their signal names (ticks through the cpr), and the units as written."""
    signals: dict[str, np.ndarray] = {}
    units: dict[str, str] = {}
    for k, (signal, unit) in fields.items():
        if signal in signals:
            raise LogFormatError(f"fields {header[k]!r} and another are both read as {signal}: skip one with "
                                 f"--column \"{header[k]}=skip\"", path=name, line=1)
        units[signal] = unit
        if unit == "count/s":
            if cpr is None:
                raise OptionError(f"{name}: field {header[k]!r} is a velocity in encoder ticks per second (the "
                                  "SDK's getVelocity()): give the encoder's counts per revolution (cpr, --cpr N)")
            signals[signal] = data[k] * (2 * math.pi / cpr)
        elif signal == "counts" or unit == "count":
            signals["counts"] = data[k]
            if cpr is not None:
                signals["position"] = data[k] * (2 * math.pi / cpr)
        else:
            signals[signal] = to_si(data[k], unit, SIGNALS[signal])
    return signals, units


def _loop_counter(values: list[str]) -> dict[str, Any]:
    """First and last loop number, and the loops with no row (a Datalogger OpMode counts each loop)."""
    counter = [float(v) for v in values if v.isascii() and v.lstrip("-").isdigit()]
    if not counter:
        return {}
    return {"first": counter[0], "last": counter[-1],
            "missed": int(max(0.0, counter[-1] - counter[0] + 1 - len(counter)))}


def _set_rows(running: list[tuple[int, list[str]]], fields: dict[int, tuple[str, str]], header: list[str],
              name: str, warnings: list[str]) -> list[tuple[int, list[str]]]:
    """The rows whose fields are all set (a field is "" until the OpMode first sets it); a field never set
    is dropped from ``fields``. Refuses when nothing is left."""
    for k in [k for k in fields if all(values[k] == "" for _n, values in running)]:
        warnings.append(f"{name}: field {header[k]!r} is never set in a RUNNING row: not read")
        del fields[k]
    if not fields:
        raise LogFormatError("no field is ever set after START: the OpMode logged nothing but its status",
                             path=name, line=1)
    unset = [r for r in running if any(r[1][k] == "" for k in fields)]
    if unset:
        warnings.append(f"{name}: {len(unset)} row(s) with a field not yet set left out (first: line {unset[0][0]})")
        left_out = {n for n, _v in unset}
        running = [r for r in running if r[0] not in left_out]
    if not running:
        raise LogFormatError("no RUNNING row with every field set: the OpMode logged nothing after START",
                             path=name, line=1)
    return running
