"""The samples of a waveform export, read chunk by chunk (:func:`motorlab.io.scope.read_scope_waveform`).

A Rigol DS1054Z exports up to 24 Mpts per channel. The rows are parsed in C (``numpy.loadtxt``) a
chunk of whole lines at a time, straight from the file; only the chosen channel is kept, as 32-bit
floats (4 bytes a sample: a scope's 8-bit samples written with 3–5 digits lose nothing), and the
sample times are not stored at all when they are the Rigol ``Sequence`` layout's start +
index·increment with consecutive indices (the Rigol indices are parsed as integers, in a third of a
float's time: a quarter of a 24 Mpt export's reading). A chunk the C parser refuses (a comment, a blank line, a
quoted or broken value) is read line by line, which names the bad line. A 24 Mpt export thus takes
about 100 MB instead of several GB.
"""

from __future__ import annotations

import io
import os
import warnings
from dataclasses import dataclass, field

import numpy as np

from motorlab.errors import LogFormatError, OptionError
from motorlab.io._chunks import Chunk, Column, line_chunks
from motorlab.io.csv_table import split_fields
from motorlab.io.text import check_input_file, decode_text, is_binary, parse_number

TIME_HEADERS = {"time_ms": 1e-3, "time_s": 1.0}

_Timing = tuple[float | None, float | None, float]


@dataclass
class Samples:
    """One channel of a waveform export: volts (float32), the sample times, the file line of each sample.

    The times are ``start + (first_index + k)·increment`` when ``x`` is None (consecutive Rigol
    indices), else ``start + x·increment`` (Rigol ``Sequence``) or ``x·time_factor``.
    """

    volts: np.ndarray
    x: np.ndarray | None
    first_index: float
    timing: _Timing
    channel: str
    layout: str
    line_starts: list[int] = field(default_factory=list)
    line_parts: list[int | np.ndarray] = field(default_factory=list)

    def time_at(self, index: np.ndarray) -> np.ndarray:
        """Times [s] of the samples ``index``."""
        start, increment, factor = self.timing
        x = self.first_index + np.asarray(index, dtype=float) if self.x is None else self.x[index]
        if start is not None and increment is not None:
            return start + x * increment
        return x * factor

    def lines_of(self, index: np.ndarray) -> np.ndarray:
        """1-based file lines of the samples ``index``."""
        index = np.asarray(index, dtype=np.int64)
        starts = np.asarray(self.line_starts, dtype=np.int64)
        which = np.searchsorted(starts, index, side="right") - 1
        out = np.empty(index.size, dtype=np.int64)
        for k in np.unique(which):
            sel = which == k
            part = self.line_parts[int(k)]
            local = index[sel] - starts[k]
            out[sel] = part + local if isinstance(part, int) else part[local]
        return out

    def sample_interval(self) -> float:
        """The median time between samples [s] (block by block on a long capture)."""
        start, increment, factor = self.timing
        scale = increment if start is not None and increment is not None else factor
        if self.x is None:
            return float(scale)
        step = 1 << 20
        medians = [np.median(np.diff(self.x[a : a + step + 1])) for a in range(0, self.x.size - 1, step)]
        return float(np.median(medians) * scale)


def head_lines(name: str, count: int) -> tuple[list[tuple[int, str, int]], bool]:
    """The first ``count`` lines that are neither blank nor comments: (number, text, offset after it).

    The second value is False when the file ends its lines with bare carriage returns (then the
    caller reads it whole, as :meth:`str.splitlines` splits it).

    Raises
    ------
    LogFormatError
        An empty or binary file.
    """
    with open(name, "rb") as handle:
        head = handle.read(1 << 16)
    whole = len(head) < 1 << 16
    if not head.strip():
        raise LogFormatError("the file is empty", path=name)
    if is_binary(head if whole else head[: head.rfind(b"\n") + 1]):
        raise LogFormatError("not a text file (it contains binary data)", path=name)
    if head.count(b"\r") != head.count(b"\r\n"):
        return [], False
    out: list[tuple[int, str, int]] = []
    offset = 0
    parts = head.split(b"\n")
    for number, raw in enumerate(parts if whole else parts[:-1], start=1):
        end = offset + len(raw) + 1
        text = decode_text(raw.removeprefix(b"\xef\xbb\xbf") if number == 1 else raw)[0].strip()
        offset = end
        if text and not text.startswith("#"):
            out.append((number, text, min(end, len(head)) if whole else end))
            if len(out) == count:
                break
    return out, True


def pick_channel(channels: list[str], channel: str | None, name: str, line: int) -> int:
    """The column of ``channel`` (``"CH1"``, ``"CH1_V"`` …; the first channel when None).

    Raises
    ------
    LogFormatError
        No channel column in the header.
    OptionError
        A channel the file does not have.
    """
    if not channels:
        raise LogFormatError("no channel column in the header", path=name, line=line)
    if channel is None:
        return 1
    wanted = channel.lower()
    matches = [i for i, c in enumerate(channels) if c.lower() in (wanted, f"{wanted}_v")]
    if not matches:
        raise OptionError(f"channel {channel!r} is not in {name} (it has: {', '.join(channels)})")
    return matches[0] + 1


def waveform_layout(
    header: list[str], numbered: list[tuple[int, str]], name: str
) -> tuple[str, list[str], int, _Timing]:
    """Layout, channel names, header lines used (1 or 2) and timing of a waveform file.

    ``numbered`` holds the first (line number, line) pairs of the file without comments, the header
    first. The timing is ``(start, increment, time_factor)``: a Rigol ``Sequence`` export gives the
    time of sample ``x`` as start + x·increment, other layouts as x·time_factor (start and increment
    then None).
    """
    header_no, header_line = numbered[0]
    lower = [h.lower() for h in header]
    start = increment = None
    if lower and lower[0] == "x":
        layout, used = "rigol", 2
        channels = [h for h in header[1:] if h.lower() not in ("start", "increment")]
        units_no, units_line = numbered[1]
        units = split_fields(units_line, ",")
        kind = units[0].lower() if units else ""
        if kind == "sequence":
            if "start" not in lower or "increment" not in lower:
                raise LogFormatError("Rigol header without Start and Increment", path=name, line=header_no)
            try:
                start = parse_number(units[lower.index("start")], path=name, line=units_no, column="Start")
                increment = parse_number(
                    units[lower.index("increment")], path=name, line=units_no, column="Increment"
                )
            except IndexError:
                raise LogFormatError("Start/Increment values missing", path=name, line=units_no) from None
            if increment <= 0:
                raise LogFormatError("Increment must be positive", path=name, line=units_no)
        elif kind != "second":
            raise LogFormatError(
                f"second line should start with Sequence or Second, found {units_line[:40]!r}",
                path=name,
                line=units_no,
            )
        time_factor = 1.0
    elif lower and lower[0] in TIME_HEADERS:
        layout, used = "table", 1
        channels = header[1:]
        time_factor = TIME_HEADERS[lower[0]]
    else:
        raise LogFormatError(
            f"not a waveform export: expected 'X,CH1,Start,Increment' or 'time_s,CH1_V', found {header_line[:60]!r}",
            path=name,
            line=header_no,
        )
    return layout, channels, used, (start, increment, time_factor)


def waveform_rows(
    name: str, rows: list[tuple[int, str]], column: int, labels: tuple[str, str], truncatable: int | None
) -> tuple[list[float], list[float], list[int]]:
    """First-column values, ``column`` values and line numbers of the sample rows, line by line.

    A short or non-numeric line ``truncatable`` (the file's last, without a line terminator: the
    writer was cut off) ends the samples quietly; anywhere else it is an error naming the line.
    """
    x_label, label = labels
    xs: list[float] = []
    ys: list[float] = []
    lines: list[int] = []
    for number, line in rows:
        fields = split_fields(line, ",")
        if len(fields) <= column:
            if number == truncatable:
                break
            raise LogFormatError(f"row has no {label} value", path=name, line=number)
        try:
            x = parse_number(fields[0], path=name, line=number, column=x_label)
            y = parse_number(fields[column], path=name, line=number, column=label)
        except LogFormatError:
            if number == truncatable:
                break
            raise
        xs.append(x)
        ys.append(y)
        lines.append(number)
    return xs, ys, lines


def _parse_chunk(
    chunk: Chunk, name: str, column: int, labels: tuple[str, str], *, integer_x: bool = False
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """x, the channel's values and the lines of a chunk's rows (None: one row per line of the chunk).

    ``integer_x``: x is a sample index (Rigol ``Sequence``), tried as integers first (numpy converts
    them in a third of a float's time); a chunk whose x are not all integers is read as floats.
    """
    expected = chunk.lines()
    for dtype in ([[("x", "<i8"), ("y", "<f8")]] if integer_x else []) + [[("x", "<f8"), ("y", "<f8")]]:
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("error")  # "input contained no data": the slow path says what is wrong
                table = np.loadtxt(io.BytesIO(chunk.data), delimiter=",", usecols=(0, column), comments=None,
                                   ndmin=1, dtype=dtype)
        except (ValueError, UserWarning, OverflowError):
            continue
        x, y = table["x"].astype(float), table["y"]
        if table.shape[0] == expected and np.isfinite(x).all() and np.isfinite(y).all():
            return x, y, None
    text = chunk.data.decode("latin-1")  # the numbers are ASCII; any other byte is named as not a number
    rows = [(n, line.strip()) for n, line in enumerate(text.split("\n"), start=chunk.first_line)]
    rows = [(n, line) for n, line in rows if line and not line.startswith("#")]
    truncatable = chunk.first_line + expected - 1 if chunk.last else None
    xs, ys, lines = waveform_rows(name, rows, column, labels, truncatable)
    return np.asarray(xs, dtype=float), np.asarray(ys, dtype=float), np.asarray(lines, dtype=np.int64)


@dataclass
class _Gather:
    """What :func:`stream_samples` has gathered so far."""

    volts: Column
    consecutive: bool
    x: Column | None = None
    first_x: float = 0.0
    last_x: float = -np.inf
    line_starts: list[int] = field(default_factory=list)
    line_parts: list[int | np.ndarray] = field(default_factory=list)

    def add(self, xs: np.ndarray, ys: np.ndarray, lines: np.ndarray | None, first_line: int, name: str) -> None:
        if xs.size == 0:
            return
        steps = np.diff(xs)
        bad = np.flatnonzero(steps <= 0) + 1
        if xs[0] <= self.last_x:
            bad = np.concatenate([[0], bad])
        if bad.size:
            k = int(bad[0])
            line = int(lines[k]) if lines is not None else first_line + k
            raise LogFormatError("sample times must increase", path=name, line=line)
        n = self.volts.size
        if self.consecutive and not (xs[0] == (self.last_x + 1 if n else xs[0]) and np.all(steps == 1)):
            self.consecutive = False  # from now on the indices are kept
            self.x = Column(self.volts.values.size)
            self.x.extend(self.first_x + np.arange(n, dtype=float))
        if n == 0:
            self.first_x = float(xs[0])
        if self.x is not None:
            self.x.extend(xs)
        self.last_x = float(xs[-1])
        self.line_starts.append(n)
        self.line_parts.append(first_line if lines is None else lines)
        self.volts.extend(ys)


def stream_samples(path: str | os.PathLike[str], channel: str | None) -> Samples | None:
    """The samples of one channel of a waveform export, read chunk by chunk; None for bare-CR line ends.

    Raises
    ------
    LogFormatError
        Unknown layout, non-numeric or non-finite samples, times that do not increase, too few samples.
    OptionError
        A channel the file does not have.
    """
    name, size = check_input_file(path)
    head, plain = head_lines(name, 2)
    if not plain:
        return None
    if len(head) < 2:
        raise LogFormatError("too short for a waveform (needs a header and samples)", path=name)
    header = split_fields(head[0][1], ",")
    layout, channels, used, timing = waveform_layout(header, [(n, t) for n, t, _ in head], name)
    column = pick_channel(channels, channel, name, head[0][0])
    labels = (header[0], header[column])
    first_line, offset = head[used - 1][0] + 1, head[used - 1][2]
    estimate = max(size - offset, 0) // 12  # a Rigol row is about 20 bytes; grown if need be
    gather = _Gather(Column(estimate, np.float32), consecutive=layout == "rigol" and timing[0] is not None)
    if not gather.consecutive:
        gather.x = Column(estimate)
    base = os.path.basename(name)
    for chunk in line_chunks(name, offset, first_line, what=f"Reading {base}"):
        xs, ys, lines = _parse_chunk(chunk, name, column, labels, integer_x=gather.consecutive)
        gather.add(xs, ys, lines, chunk.first_line, name)
    if gather.volts.size < 2:
        raise LogFormatError("fewer than two samples", path=name)
    x = None if gather.x is None else gather.x.array()
    return Samples(gather.volts.array(), x, gather.first_x, timing, labels[1], layout, gather.line_starts,
                   gather.line_parts)
