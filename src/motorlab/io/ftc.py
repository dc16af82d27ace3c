"""FTC dynamometer OpMode logs: whitespace-separated ``time_ms encoder_counts bus_voltage_V shunt_current_A``.

The OpMode of seed 1 ("Characterizing FTC-legal motors", section "Retrieving the Data from the
Phones") stores its samples in pre-allocated arrays and prints them with ``FileWriter``: the files
start with blank lines, may carry a header line, end with placeholder rows of zeros (the unused part
of the arrays) and a run is split over ``testFile.txt`` and ``testFile2.txt``. The seed tells the
student to clean all this by hand; :func:`read_ftc_log` does it and says what it did in
``metadata``. The two-column variant ``time_ms encoder_counts`` is the tick log of the seed's "Our
First Motor Test Counting Encoder Ticks" (one row per encoder count).

motorlab's own OpModes (``ftc/``, docs/ftc-robot.md) start the file with ``# key: value`` lines
naming the motor, the counts per revolution and the gear ratio (``# cpr: 1120``); they go into
``metadata`` and ``# cpr:`` is used when no ``cpr`` is given. Files without them read as before.
"""

from __future__ import annotations

import itertools
import math
import os
import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from motorlab.errors import LogFormatError, OptionError
from motorlab.io.csv_table import parse_comments
from motorlab.io.glitches import screen_glitches
from motorlab.io.output import write_text_atomic
from motorlab.io.text import (
    PathArg,
    TextFile,
    check_cpr,
    check_distinct,
    fast_table,
    is_number,
    parse_number,
    read_text,
    unit_factor,
)
from motorlab.recording import Recording

#: Column names of the four-column and two-column variants, in file order.
POWER_COLUMNS = ("time_ms", "encoder_counts", "bus_voltage_V", "shunt_current_A")
TICK_COLUMNS = ("time_ms", "encoder_counts")

_TIME_RESTART_CHOICES = ("error", "offset")


@dataclass
class _Part:
    """One file of a (possibly split) run, already cleaned."""

    path: str
    rows: np.ndarray  # (n, ncol), time still in ms
    lines: np.ndarray
    header: str | None
    placeholders: int
    warnings: list[str] = field(default_factory=list)
    fields: dict[str, Any] = field(default_factory=dict)  # leading "# key: value" lines


def read_ftc_log(
    paths: PathArg | Sequence[PathArg],
    *,
    cpr: float | None = None,
    current_unit: str | None = None,
    time_restart: str = "error",
) -> Recording:
    """Read an FTC OpMode log (one file or a run split over several files, in order).

    Parameters
    ----------
    paths
        One path, or the files of one run in order (``["testFile.txt", "testFile2.txt"]``).
    cpr
        Encoder counts per revolution of the counted shaft [count/rev]. When given (or written in
        the file as ``# cpr: 1120``), ``position`` [rad] = counts·2π/cpr is added beside ``counts``.
    current_unit
        Unit of the shunt-current column (``"A"`` or ``"mA"``, any pint current unit). By default
        each file's header decides (a column name containing ``mA``), else amperes.
    time_restart
        What to do when a later file starts at an earlier time than the previous file ended:
        ``"error"`` (default) raises; ``"offset"`` assumes the OpMode restarted its timer at the
        split and shifts the later file to start one median sample interval after the previous one.

    Returns
    -------
    Recording
        ``time`` [s]; signals ``counts``, ``position`` [rad] (with ``cpr``), and for the four-column
        variant ``voltage`` [V] (INA219 bus voltage) and ``current`` [A]. ``metadata`` holds
        ``format="ftc-log"``, ``variant`` (``"power"`` or ``"ticks"``), ``cpr``, ``current_unit``,
        ``header``, ``files``, ``file_starts`` (sample index where each file begins),
        ``placeholder_rows_dropped`` and ``warnings``, and every leading ``# key: value`` line of
        the (first) file (numbers as floats: ``motor``, ``gear_ratio``, ``experiment`` …).

    Raises
    ------
    LogFormatError
        Empty or binary file, a non-numeric or non-finite value, a row with a different number of
        columns (except a truncated last line, which is dropped with a warning), a column count other
        than 2 or 4, time going backwards (within a file or across a join), a file holding only
        placeholder zeros, an impossible ``# cpr:`` line.
    OptionError
        Impossible ``cpr``, ``current_unit`` or ``time_restart``.

    Notes
    -----
    Trailing rows whose every field is zero are the unused, pre-allocated part of the OpMode's
    arrays and are dropped; a zero row followed by data is kept (it is a sample). Times are written in
    milliseconds and converted to seconds.

    References
    ----------
    Seed 1, "Retrieving the Data from the Phones" (steps 4–5) and "Our First Motor Test Counting
    Encoder Ticks".
    """
    cpr = check_cpr(cpr)
    if time_restart not in _TIME_RESTART_CHOICES:
        raise OptionError(f"time_restart must be one of {', '.join(_TIME_RESTART_CHOICES)}, got {time_restart!r}")
    parts = [_read_part(p) for p in _path_list(paths)]
    fields = {k: v for p in reversed(parts) for k, v in p.fields.items()}  # the first file's win
    if cpr is None and "cpr" in fields:
        try:
            cpr = check_cpr(fields["cpr"])
        except OptionError as exc:
            raise LogFormatError(f"# cpr: {exc.message.removeprefix('cpr: ')}", path=parts[0].path) from None
    ncol = _column_count(parts)
    times, offsets = _join_times(parts, time_restart)
    if ncol == 4:
        _check_milliseconds(times, parts[0])
    rows = parts[0].rows if len(parts) == 1 else np.concatenate([p.rows for p in parts])
    header = next((p.header for p in parts if p.header is not None), None)
    # Each file's own header decides its current unit (unless the caller says).
    units = [_current_unit(current_unit, p.header) for p in parts]
    signals = _signals(rows, parts, units, cpr)
    starts = np.cumsum([0] + [p.rows.shape[0] for p in parts[:-1]])
    metadata = {
        **fields,
        "format": "ftc-log",
        "variant": "power" if ncol == 4 else "ticks",
        "columns": list(POWER_COLUMNS if ncol == 4 else TICK_COLUMNS),
        "cpr": cpr,
        "current_unit": (units[0] if len(set(units)) == 1 else units) if ncol == 4 else None,
        "header": header,
        "files": [p.path for p in parts],
        "file_starts": [int(s) for s in starts],
        "time_offsets_s": offsets,
        "placeholder_rows_dropped": sum(p.placeholders for p in parts),
        "warnings": [w for p in parts for w in p.warnings],
    }
    recording = Recording(
        time=times,
        signals=signals,
        metadata=metadata,
        source=" + ".join(p.path for p in parts),
        lines=np.concatenate([p.lines for p in parts]),
    )
    return screen_glitches(recording)


def _path_list(paths: PathArg | Sequence[PathArg]) -> list[PathArg]:
    """The files of the run as a list: at least one, no file twice."""
    if isinstance(paths, str | os.PathLike):
        path_list: list[PathArg] = [paths]
    else:
        path_list = list(paths)
    if not path_list:
        raise OptionError("read_ftc_log needs at least one file")
    check_distinct(path_list)
    return path_list


def _column_count(parts: list[_Part]) -> int:
    """The number of columns, the same in every file of the run."""
    ncol = parts[0].rows.shape[1]
    for part in parts[1:]:
        if part.rows.shape[1] != ncol:
            raise LogFormatError(
                f"has {part.rows.shape[1]} columns but {parts[0].path} has {ncol}: not the same run",
                path=part.path,
                line=int(part.lines[0]),
            )
    return ncol


def _check_milliseconds(times: np.ndarray, first: _Part) -> None:
    """Refuse a four-column log whose time column is evidently in seconds (``first``: its first file)."""
    if times.size > 2:
        # The OpMode logs milliseconds; a loop that reads an INA219 over I²C cannot run faster than
        # ~1 kHz. Steps far below a millisecond mean the time column is in seconds (getRuntime()).
        step_ms = float(np.median(np.diff(times))) * 1e3
        if 0 < step_ms < 0.2:
            raise LogFormatError(
                f"the time column steps by {step_ms:.3g} ms (median): it looks like seconds, but this "
                "format's first column is milliseconds (time_ms); convert it, or write a CSV with a time_s column",
                path=first.path,
                line=int(first.lines[0]),
            )


def _signals(rows: np.ndarray, parts: list[_Part], units: list[str], cpr: float | None) -> dict[str, np.ndarray]:
    """Signals in SI from the joined rows: counts, position (with ``cpr``), voltage and current.

    ``units`` is the current unit of each file in ``parts``; the current column is scaled file by
    file.
    """
    signals: dict[str, np.ndarray] = {"counts": rows[:, 1]}
    if cpr is not None:
        signals["position"] = rows[:, 1] * (2.0 * math.pi / cpr)
    if rows.shape[1] == 4:
        signals["voltage"] = rows[:, 2]
        pairs = zip(parts, units, strict=True)
        factors = np.concatenate([np.full(p.rows.shape[0], unit_factor(u, "A")) for p, u in pairs])
        signals["current"] = rows[:, 3] * factors
    return signals


def _read_part(path: PathArg) -> _Part:
    text = read_text(path)
    fields, comments, _first = parse_comments(text)  # leading "# key: value" lines (motor, cpr, ratio)
    parsed = _parse_fast(text, len(fields) + len(comments)) or _parse_slow(text)
    return _clean_part(text.path, *parsed, fields)


def _parse_fast(text: TextFile, n_comments: int) -> tuple[np.ndarray, np.ndarray, str | None, list[str]] | None:
    """The rows of a clean log parsed in C (a 2M-row log in about a second), or None (slow path)."""
    head = [(n, line) for n, line in text.head(n_comments + 2) if not line.startswith("#")]
    if not head:
        return None
    header: str | None = None
    if not all(is_number(t) for t in head[0][1].split()):
        header = head[0][1]
        head = head[1:]
    if not head or not all(is_number(t) for t in head[0][1].split()):
        return None
    ncol = len(head[0][1].split())
    if ncol not in (2, 4):
        return None
    table = fast_table(text, head[0][0], ncol, None)
    if table is None:
        return None
    warnings = []
    if table.truncated is not None:
        number, line = table.truncated
        warnings.append(f"{text.path}:{number}: truncated last line dropped ({line[:40]!r})")
    return table.values, table.lines, header, warnings


def _parse_slow(text: TextFile) -> tuple[np.ndarray, np.ndarray, str | None, list[str]]:
    """Line by line: finds and names the first bad line."""
    name = text.path
    header: str | None = None
    ncol: int | None = None
    values: list[list[float]] = []
    lines: list[int] = []
    warnings: list[str] = []
    for number, line in text.numbered():
        tokens = line.split()
        if ncol is None and line.startswith("#"):
            continue  # "# key: value" lines (fields) and comments before the data
        if ncol is None and not all(is_number(t) for t in tokens):
            if header is not None:
                raise LogFormatError(f"a second text line before the data: {line[:40]!r}", path=name, line=number)
            header = line
            continue
        if ncol is None:
            ncol = len(tokens)
            if ncol not in (2, 4):
                raise LogFormatError(
                    f"expected 4 columns ({' '.join(POWER_COLUMNS)}) or 2 ({' '.join(TICK_COLUMNS)}), "
                    f"found {ncol}",
                    path=name,
                    line=number,
                )
        if len(tokens) != ncol or not all(is_number(t) for t in tokens):
            if text.may_be_truncated(number):
                warnings.append(f"{name}:{number}: truncated last line dropped ({line[:40]!r})")
                break
            if len(tokens) != ncol:
                raise LogFormatError(f"expected {ncol} columns, found {len(tokens)}", path=name, line=number)
        columns = POWER_COLUMNS if ncol == 4 else TICK_COLUMNS
        values.append([parse_number(t, path=name, line=number, column=c) for t, c in zip(tokens, columns, strict=True)])
        lines.append(number)
    if not values:
        raise LogFormatError("no data rows (only blank or text lines)", path=name)
    return np.array(values, dtype=float), np.asarray(lines, dtype=int), header, warnings


def _clean_part(
    name: str, rows: np.ndarray, lines: np.ndarray, header: str | None, warnings: list[str], fields: dict[str, Any]
) -> _Part:
    """Drop the trailing placeholder zeros, check that time runs forward."""
    nonzero = np.flatnonzero(np.any(rows != 0.0, axis=1))
    if nonzero.size == 0:
        raise LogFormatError("only placeholder rows of zeros, no data", path=name, line=int(lines[0]))
    keep = int(nonzero[-1]) + 1
    placeholders = rows.shape[0] - keep
    rows = rows[:keep]
    line_arr = lines[:keep]
    backwards = np.flatnonzero(np.diff(rows[:, 0]) < 0)
    if backwards.size:
        i = int(backwards[0]) + 1
        raise LogFormatError(
            f"time goes backwards ({rows[i, 0]:g} ms after {rows[i - 1, 0]:g} ms)",
            path=name,
            line=int(line_arr[i]),
        )
    return _Part(name, rows, line_arr, header, placeholders, warnings, fields)


def _join_times(parts: list[_Part], time_restart: str) -> tuple[np.ndarray, list[float]]:
    """Times [s] of the concatenated parts; later files must continue the clock (or be offset)."""
    pieces = [parts[0].rows[:, 0] * 1e-3]
    offsets = [0.0]
    for previous, part in itertools.pairwise(parts):
        last = pieces[-1][-1]
        own = part.rows[:, 0] * 1e-3
        offset = 0.0
        if own[0] < last:
            if time_restart == "error":
                raise LogFormatError(
                    f"time goes backwards across the join ({own[0] * 1e3:g} ms after "
                    f"{last * 1e3:g} ms at the end of {previous.path}); if the OpMode restarted its "
                    "timer, use time_restart='offset'",
                    path=part.path,
                    line=int(part.lines[0]),
                )
            steps = np.diff(pieces[-1])
            step = float(np.median(steps)) if steps.size else 0.0
            offset = last + step - own[0]
        pieces.append(own + offset)
        offsets.append(offset)
    return np.concatenate(pieces), offsets


_MILLIAMP = re.compile(r"(^|[^a-zA-Z])mA([^a-zA-Z]|$)")


def _current_unit(current_unit: str | None, header: str | None) -> str:
    if current_unit is None:
        return "mA" if header is not None and _MILLIAMP.search(header) else "A"
    try:
        unit_factor(current_unit, "A")
    except Exception:  # pint raises several types for unknown or wrong-dimension units
        raise OptionError(f"current_unit: {current_unit!r} is not a unit of current") from None
    return current_unit


def write_ftc_log(
    path: PathArg,
    time_s: np.ndarray,
    counts: np.ndarray,
    voltage: np.ndarray | None = None,
    current: np.ndarray | None = None,
    *,
    header: bool = True,
    placeholder_rows: int = 0,
    crlf: bool = False,
    blank_lines: int = 0,
    current_unit: str = "A",
    fields: dict[str, Any] | None = None,
) -> None:
    """Write a log exactly as the FTC OpMode does, for the virtual rig and for tests.

    Parameters
    ----------
    path
        File to create (overwritten if it exists).
    time_s
        Sample times [s]; written in milliseconds.
    counts
        Encoder counts [count]; rounded to whole counts.
    voltage, current
        Bus voltage [V] and shunt current [A]; both or neither (neither gives the two-column tick log).
    header
        Write a header line naming the columns.
    placeholder_rows
        Rows of zeros appended, as the OpMode's pre-allocated arrays leave them.
    crlf
        Use ``\\r\\n`` line endings (a file that went through a Windows editor).
    blank_lines
        Blank lines written before everything else (the phone's files start with some).
    current_unit
        ``"A"`` or ``"mA"``: the unit the current is written in (INA219 libraries differ).
    fields
        ``# key: value`` lines written first, as motorlab's OpModes do (``{"cpr": 1120,
        "motor": "neverest40", "gear_ratio": 40}``).

    Raises
    ------
    OptionError
        Arrays of different lengths, non-finite values, only one of voltage/current, bad unit.
    """
    time_s = np.asarray(time_s, dtype=float)
    columns = [time_s * 1e3, np.rint(np.asarray(counts, dtype=float))]
    if (voltage is None) != (current is None):
        raise OptionError("write_ftc_log: give both voltage and current, or neither")
    names = list(TICK_COLUMNS)
    if voltage is not None and current is not None:
        factor = unit_factor(current_unit, "A")
        columns += [np.asarray(voltage, dtype=float), np.asarray(current, dtype=float) / factor]
        names = [*POWER_COLUMNS[:3], f"shunt_current_{current_unit}"]
    for name, column in zip(names, columns, strict=True):
        if column.shape != time_s.shape:
            raise OptionError(f"write_ftc_log: {name} has {column.size} values, time has {time_s.size}")
        if not np.all(np.isfinite(column)):
            raise OptionError(f"write_ftc_log: {name} holds NaN or inf")
    if placeholder_rows < 0:
        raise OptionError("write_ftc_log: placeholder_rows must not be negative")
    out = [""] * blank_lines
    for key, value in (fields or {}).items():
        text = str(value)
        if not key.isidentifier() or "\n" in text or "\r" in text:
            raise OptionError(f"write_ftc_log: field {key!r}: {text!r} cannot be written as '# key: value'")
        out.append(f"# {key}: {text}")
    if header:
        out.append(" ".join(names))
    four = len(columns) == 4
    for k in range(time_s.size):
        row = f"{columns[0][k]:.6f} {int(columns[1][k])}"
        if four:
            row += f" {columns[2][k]:.6g} {columns[3][k]:.6g}"
        out.append(row)
    out += ["0.0 0 0.0 0.0" if four else "0.0 0"] * placeholder_rows
    newline = "\r\n" if crlf else "\n"
    write_text_atomic(path, newline.join(out) + newline, newline="")
