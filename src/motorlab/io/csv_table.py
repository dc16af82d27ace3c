"""CSV tables whose header names each column with its unit (``time_s,voltage_V,current_mA``).

The header is the contract: each known column name maps to a canonical signal and the unit it is
written in (:data:`COLUMNS`); values are converted to SI with pint factors, never by code per column.
Leading ``# key: value`` lines are metadata (``# cpr: 1120``, ``# experiment: terminal``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from motorlab.errors import LogFormatError, OptionError
from motorlab.io.glitches import screen_glitches
from motorlab.io.headers import (
    COLUMNS,
    ColumnRule,
    column_name,
    current_mapping,
    is_worded_header,
    parse_column_mapping,
    resolve_column,
    to_si,
    unknown_column_message,
)
from motorlab.io.output import write_text_atomic
from motorlab.io.text import (
    PathArg,
    TextFile,
    check_cpr,
    check_input_file,
    fast_table,
    is_number,
    parse_number,
    read_text,
    text_file,
)
from motorlab.recording import SIGNALS, Recording

#: Prefix of user columns that the reader skips (notes, extra instruments).
EXTRA_PREFIX = "x_"



def is_known_header(fields: list[str]) -> bool:
    """True when ``fields`` look like a header of this format: every name known or an ``x_`` extra, or
    names in words with units (``Current (A)``) and the columns mapped (:mod:`motorlab.io.headers`)."""
    names = [f for f in fields if f]
    if bool(names) and all(column_name(f) or f.startswith(EXTRA_PREFIX) for f in names) and any(
        column_name(f) for f in names
    ):
        return True
    return not all(is_number(f) for f in names) and is_worded_header(
        [f for f in names if not f.startswith(EXTRA_PREFIX)], current_mapping()
    )


def split_fields(line: str, delimiter: str | None, *, width: int = 0) -> list[str]:
    """Fields of ``line`` (``delimiter=None`` splits on whitespace).

    Trailing empty fields beyond ``width`` are removed (a trailing delimiter, as Rigol scopes write);
    empty fields within the first ``width`` are kept, so that a missing value is noticed.
    """
    fields = line.split() if delimiter is None else [f.strip().strip('"') for f in line.split(delimiter)]
    while len(fields) > width and fields[-1] == "":
        fields.pop()
    return fields


def guess_delimiter(header: str) -> str | None:
    """Comma, semicolon or tab if the header holds one (in that order), else whitespace (None)."""
    for delimiter in (",", ";", "\t"):
        if delimiter in header:
            return delimiter
    return None


def parse_comments(text: TextFile) -> tuple[dict[str, Any], list[str], int]:
    """Leading ``# key: value`` metadata, other leading comment lines, and the index of the first data line.

    Values that read as numbers become floats; everything else stays a string.
    """
    metadata: dict[str, Any] = {}
    comments: list[str] = []
    count = 64
    head = text.head(count)  # the top of the file only: a 2M-row table is not split into lines here
    while len(head) == count and all(line.startswith("#") for _, line in head):
        count *= 4
        head = text.head(count)
    for number, line in head:
        if not line.startswith("#"):
            return metadata, comments, number - 1
        body = line.lstrip("#").strip()
        key, sep, value = body.partition(":")
        if sep and key.strip() and " " not in key.strip():
            value = value.strip()
            metadata[key.strip()] = float(value) if is_number(value) else value
        elif body:
            comments.append(body)
    return metadata, comments, len(text.lines)  # only comments (a short file: splitting it is cheap)


def line_at(text: TextFile, index: int) -> str | None:
    """The stripped line at 0-based ``index`` if it is not blank, from the top of the file only."""
    count = 64
    while True:
        head = text.head(count)
        for number, line in head:
            if number == index + 1:
                return line
            if number > index + 1:
                return None
        if len(head) < count:
            return None
        count *= 4


def read_csv(path: PathArg, *, cpr: float | None = None, columns: Any = None) -> Recording:
    """Read a CSV table whose header names the columns with their units.

    Parameters
    ----------
    path
        The file. Comma-separated; semicolons, tabs or whitespace are accepted too.
    cpr
        Encoder counts per revolution [count/rev]; overrides a ``# cpr:`` metadata line. With a
        ``position_counts`` column and a cpr, ``position`` [rad] = counts·2π/cpr is added.
    columns
        Column rules for headers the reader does not know (``{"Amps": "current"}``,
        ``["I (mA)=current"]``: :func:`motorlab.io.headers.parse_column_mapping`); default: the
        rules in force (:func:`motorlab.io.headers.column_mapping`, set by ``--column``). Headers in
        words with a unit in brackets (``Current (A)``, ``Torque 6V (N · m)``) need none.

    Returns
    -------
    Recording
        Signals in SI under canonical names (see :data:`COLUMNS`); ``time`` [s] from ``time_s`` or
        ``time_ms``, else the row index (``metadata["time"] == "row index"``). ``metadata`` holds the
        ``# key: value`` lines, ``format="csv"``, ``columns`` (header as written), ``units``
        (signal -> unit as written), ``cpr``, ``comments`` and ``warnings``.

    Raises
    ------
    LogFormatError
        Empty or binary file, no header, an unknown column (the message lists the known ones; user
        columns must start with ``x_``), two columns for one signal, a missing or non-numeric value,
        NaN/inf, time going backwards. A truncated last line is dropped with a warning.
    OptionError
        Impossible ``cpr`` (argument or metadata).
    """
    text = read_text(path)
    name = text.path
    metadata, comments, start = parse_comments(text)
    header_line = line_at(text, start)
    if header_line is None:
        raise LogFormatError("no header line naming the columns (only comments)", path=name)
    delimiter = guess_delimiter(header_line)
    header = split_fields(header_line, delimiter)
    header_no = start + 1
    if all(is_number(f) for f in header):
        raise LogFormatError(
            "no header line naming the columns (e.g. time_s,voltage_V,current_A)", path=name, line=header_no
        )
    rules = parse_column_mapping(columns) if columns is not None else current_mapping()
    try:
        targets = _resolve_header(header, path=name, line=header_no, rules=rules)
    except LogFormatError:
        _refuse_at_once(text, header, header_no, delimiter, rules)  # before any question about a column
        raise

    used = [i for i, t in enumerate(targets) if t is not None]
    table = fast_table(text, header_no + 1, len(header), delimiter)
    if table is not None:  # a clean numeric table, parsed in C
        data = table.values if len(used) == table.values.shape[1] else table.values[:, used]
        line_arr = table.lines
        warnings = []
        if table.truncated is not None:
            number, line = table.truncated
            warnings.append(f"{name}:{number}: truncated last line dropped ({line[:40]!r})")
    else:
        data, line_arr, warnings = _parse_rows(text, start, header, delimiter, used)
    if data.shape[0] == 0:
        raise LogFormatError(NO_ROWS, path=name, line=header_no)
    del text, table  # the file's bytes are not needed any more (a 2M-row table: 100 MB)
    # A header in words only (Time,Amps,Volts,Torque 6V (N · m)) is an instrument's export (a dynamometer's
    # DAQ), not a robot's log of sensor reads: a sample that jumps away and back there is an event of the run
    # (a current limit reached, turns shorting, brushes arcing), which the analyses name; only values beyond
    # any measurement are excluded from it.
    worded = all(column_name(f) is None for f in header if f.strip() and not f.startswith(EXTRA_PREFIX))
    if worded:
        metadata["glitch_screening"] = ("values beyond any measurement only: an instrument's export in words, "
                                        "whose single-sample excursions are events of the run")
    return _assemble(name, data, line_arr, warnings, header, targets, used, metadata, comments, cpr,
                     spikes=not worded)


#: What a table must hold, said when a file is refused before any question about its columns (issue 31, point 7).
EXPECTED = ("motorlab expected a table of measurements: a header naming each column with its unit "
            "(time_s,voltage_V,current_A) or in words (Time,Amps,Volts), then one row of numbers per sample; "
            "or a log of a format it reads (docs/formats.md)")
NO_ROWS = f"no data rows after the header: {EXPECTED}"


def _refuse_at_once(text: TextFile, header: list[str], header_no: int, delimiter: str | None,
                    rules: tuple[ColumnRule, ...]) -> None:
    """Refuse in one step a table whose columns would otherwise be asked about one by one (issue 31, point 7).

    A header with no row under it has nothing to read whatever its columns are; a table none of whose
    columns motorlab knows and none of whose columns can be time (no column rises from row to row: random
    numbers, a spreadsheet of something else) would take a question per column before being refused. Both
    are refused here, in words that say what motorlab expected. The rows are parsed once, in C, and only
    when no column is known (bounded time on a file of any size).
    """
    name = text.path
    if not _has_data_row(text, header_no):
        raise LogFormatError(NO_ROWS, path=name, line=header_no)
    named = [f for f in header if f.strip() and not f.startswith(EXTRA_PREFIX)]
    if not named or not all(_unknown(f, rules) for f in named):
        return  # a column it knows: asking about the others is the quick way to read the file
    table = fast_table(text, header_no + 1, len(header), delimiter)
    if table is None or table.values.shape[0] < 2:
        return  # not a clean numeric table: the line-by-line reader names the problem
    steps = np.diff(table.values, axis=0)
    if not np.any(np.all(steps >= 0, axis=0) & np.any(steps > 0, axis=0)):
        shown = ", ".join(named[:4]) + (" …" if len(named) > 4 else "")
        raise LogFormatError(f"motorlab knows none of its columns ({shown}) and none of them can be time (none "
                             f"rises from row to row): {EXPECTED}", path=name, line=header_no)


def _has_data_row(text: TextFile, header_no: int) -> bool:
    """Whether any line after the header (line ``header_no``) is neither blank nor a comment."""
    count = 64
    while True:
        head = text.head(count)
        if any(number > header_no and not line.startswith("#") for number, line in head):
            return True
        if len(head) < count:
            return False
        count *= 4


def _unknown(field: str, rules: tuple[ColumnRule, ...]) -> bool:
    """Whether no rule, known name or name in words gives the column a quantity."""
    if any(rule.header.casefold() == field.strip().casefold() for rule in rules) or column_name(field) is not None:
        return False
    try:
        return resolve_column(field, rules) == "unknown"
    except LogFormatError:
        return False  # a quantity with a unit motorlab cannot read: not unknown, the header's error says so


def _parse_rows(
    text: TextFile, start: int, header: list[str], delimiter: str | None, used: list[int]
) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Line by line (the slow path): finds and names the first bad line."""
    name = text.path
    rows: list[list[float]] = []
    lines: list[int] = []
    warnings: list[str] = []
    for number, raw in enumerate(text.lines[start + 1 :], start=start + 2):
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        fields = split_fields(line, delimiter, width=len(header))
        if len(fields) != len(header):
            if text.may_be_truncated(number) and len(fields) < len(header):
                warnings.append(f"{name}:{number}: truncated last line dropped ({line[:40]!r})")
                break
            raise LogFormatError(
                f"expected {len(header)} columns ({', '.join(header)}), found {len(fields)}",
                path=name,
                line=number,
            )
        try:
            rows.append([parse_number(fields[i], path=name, line=number, column=header[i]) for i in used])
        except LogFormatError:
            if text.may_be_truncated(number) and all(is_number(fields[i]) for i in used[:-1]):
                warnings.append(f"{name}:{number}: truncated last line dropped ({line[:40]!r})")
                break
            raise
        lines.append(number)
    return np.array(rows, dtype=float).reshape(len(rows), len(used)), np.asarray(lines, dtype=int), warnings


def _assemble(
    name: str,
    data: np.ndarray,
    line_arr: np.ndarray,
    warnings: list[str],
    header: list[str],
    targets: list[tuple[str, str] | None],
    used: list[int],
    metadata: dict[str, Any],
    comments: list[str],
    cpr: float | None,
    *,
    spikes: bool = True,
) -> Recording:
    """Columns to SI signals, time checked, cpr applied: the Recording of :func:`read_csv`."""
    signals: dict[str, np.ndarray] = {}
    units: dict[str, str] = {}
    time: np.ndarray | None = None
    for col, index in enumerate(used):
        target = targets[index]
        assert target is not None  # used holds only resolved columns
        signal, unit = target
        si = "s" if signal == "time" else SIGNALS[signal]
        values = to_si(data[:, col], unit, si)  # SI already: a view, no copy
        units[signal] = unit
        if signal == "time":
            time = values
        else:
            signals[signal] = values
    if time is None:
        time = np.arange(data.shape[0], dtype=float)
        metadata["time"] = "row index"
    else:
        backwards = np.flatnonzero(np.diff(time) < 0)
        if backwards.size:
            i = int(backwards[0]) + 1
            raise LogFormatError("time goes backwards", path=name, line=int(line_arr[i]))

    if cpr is None and "cpr" in metadata:
        try:
            cpr = check_cpr(metadata["cpr"])
        except OptionError as exc:
            raise LogFormatError(f"# cpr: {exc.message.removeprefix('cpr: ')}", path=name) from None
    cpr = check_cpr(cpr)
    if cpr is not None and "counts" in signals and "position" not in signals:
        signals["position"] = signals["counts"] * (2.0 * math.pi / cpr)
    metadata.update(
        {
            "format": "csv",
            "columns": header,
            "units": units,
            "cpr": cpr,
            "comments": comments,
            "warnings": warnings,
        }
    )
    return screen_glitches(Recording(time=time, signals=signals, metadata=metadata, source=name, lines=line_arr),
                           spikes=spikes)


def check_header(path: PathArg, columns: Any = None) -> None:
    """Check the header of a CSV table without reading its rows (a session's files, before any analysis).

    Raises
    ------
    LogFormatError
        An unknown column or unit (``current_furlongs``), two columns for one signal, no header.
    """
    name, _limit = check_input_file(path)
    with open(name, "rb") as handle:
        head = handle.read(1 << 16)
    lines = text_file(name, head[: head.rfind(b"\n") + 1] or head)
    _metadata, _comments, start = parse_comments(lines)
    if start >= len(lines.lines):
        return  # read_csv explains
    header = split_fields(lines.lines[start].strip(), guess_delimiter(lines.lines[start].strip()))
    if not all(is_number(f) for f in header):
        rules = parse_column_mapping(columns) if columns is not None else current_mapping()
        _resolve_header(header, path=name, line=start + 1, rules=rules)


def _resolve_header(
    header: list[str], *, path: str, line: int, rules: tuple[ColumnRule, ...] = ()
) -> list[tuple[str, str] | None]:
    """Map each header field to (signal, unit), None for ``x_`` extras and skipped columns; errors for
    unknown/duplicates. A column rule (``--column``) comes first, then the known names (``current_A``),
    then names in words with a unit in brackets (:func:`motorlab.io.headers.resolve_column`)."""
    targets: list[tuple[str, str] | None] = []
    seen: dict[str, str] = {}
    for field in header:
        ruled = any(rule.header.casefold() == field.strip().casefold() for rule in rules)
        if field.startswith(EXTRA_PREFIX) and not ruled:
            targets.append(None)
            continue
        known = None if ruled else column_name(field)
        if known is None:
            try:
                target = resolve_column(field, rules)
            except LogFormatError as exc:
                raise LogFormatError(exc.message + f"; map it with --column \"{field}=QUANTITY [UNIT]\"",
                                     path=path, line=line) from None
            if target == "unknown":
                raise LogFormatError(unknown_column_message(field, rules), path=path, line=line)
            if target is None:
                targets.append(None)
                continue
            assert isinstance(target, tuple)
            signal, unit = target
            if signal in seen:
                raise LogFormatError(f"columns {seen[signal]!r} and {field!r} both give {signal}: "
                                     f"skip one with --column \"{field}=skip\"", path=path, line=line)
            seen[signal] = field
            targets.append((signal, unit))
            continue
        signal, unit = COLUMNS[known]
        if signal in seen:
            raise LogFormatError(f"columns {seen[signal]!r} and {field!r} both give {signal}", path=path, line=line)
        seen[signal] = field
        targets.append((signal, unit))
    return targets


def write_csv(
    path: PathArg,
    columns: Mapping[str, Any],
    *,
    metadata: Mapping[str, Any] | None = None,
) -> None:
    """Write a table :func:`read_csv` reads back (for the virtual rig and for tests).

    Parameters
    ----------
    path
        File to create (overwritten if it exists).
    columns
        Header name -> values, e.g. ``{"time_s": t, "voltage_V": v}``; values in the unit the name
        says. Names must be known (:data:`COLUMNS`) or start with ``x_``.
    metadata
        Written first as ``# key: value`` lines (e.g. ``{"cpr": 1120, "experiment": "terminal"}``).

    Raises
    ------
    OptionError
        Unknown column name, columns of different lengths, non-finite values, a metadata key or
        value that would not read back (newline, colon in the key).
    """
    names = list(columns)
    if not names:
        raise OptionError("write_csv: no columns")
    arrays = []
    for key in names:
        if column_name(key) is None and not key.startswith(EXTRA_PREFIX):
            raise OptionError(f"write_csv: unknown column {key!r}; known columns: {', '.join(COLUMNS)}")
        if any(c in key for c in ",;\t\n "):
            raise OptionError(f"write_csv: column name {key!r} contains a delimiter")
        values = np.asarray(columns[key])
        if values.ndim != 1:
            raise OptionError(f"write_csv: column {key!r} must be one-dimensional")
        if not key.startswith(EXTRA_PREFIX) and not np.all(np.isfinite(values.astype(float))):
            raise OptionError(f"write_csv: column {key!r} holds NaN or inf")
        arrays.append(values)
    size = arrays[0].size
    for key, values in zip(names, arrays, strict=True):
        if values.size != size:
            raise OptionError(f"write_csv: column {key!r} has {values.size} values, {names[0]!r} has {size}")
    out = []
    for key, value in (metadata or {}).items():
        text = str(value)
        if ":" in str(key) or "\n" in str(key) + text or not str(key).strip() or " " in str(key):
            raise OptionError(f"write_csv: metadata {key!r}: {text!r} cannot be written as '# key: value'")
        out.append(f"# {key}: {text}")
    out.append(",".join(names))
    for k in range(size):
        out.append(",".join(_format(values[k]) for values in arrays))
    write_text_atomic(path, "\n".join(out) + "\n", newline="")


def _format(value: Any) -> str:
    if isinstance(value, float | np.floating):
        return repr(float(value))
    if isinstance(value, int | np.integer):
        return str(int(value))
    return str(value)
