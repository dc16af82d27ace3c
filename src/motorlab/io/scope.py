"""Oscilloscope data: cursor times of encoder edges, and waveform exports (Rigol DS1000Z CSV).

Seed 1's "Free Motor Spin-Up Experiment" reads the times of encoder transitions off a Rigol DS1054Z.
Both readers return the same shape: ``time`` = edge times [s] and ``counts`` = 0, 1, 2, … (the edge
index), ``metadata["kind"] == "edges"``. One rising edge on one encoder channel is four quadrature
counts (the seed: "the times we recorded ... represent every fourth encoder count"); the analyses
apply that factor, the readers do not.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

from motorlab.errors import LogFormatError, OptionError
from motorlab.io._text import PathArg, TextFile, fast_table, is_number, parse_number, read_text
from motorlab.io.csv_table import guess_delimiter, line_at, parse_comments, split_fields
from motorlab.recording import Recording

_TIME_HEADERS = {"time_ms": 1e-3, "time_s": 1.0}

#: Default Schmitt-trigger levels as fractions of the signal's low-to-high range.
LOW_FRACTION = 0.3
HIGH_FRACTION = 0.7


def _edges_recording(times: np.ndarray, lines: np.ndarray | None, source: str, metadata: dict) -> Recording:
    metadata = {"kind": "edges", "counts_unit": "edges", **metadata}
    return Recording(
        time=times,
        signals={"counts": np.arange(times.size, dtype=float)},
        metadata=metadata,
        source=source,
        lines=lines,
    )


def read_scope_times(path: PathArg) -> Recording:
    """Read cursor times of rising edges: one ``time_ms`` (or ``time_s``) column, one edge per row.

    Parameters
    ----------
    path
        A CSV with a single column headed ``time_ms`` or ``time_s``, or a plain list of numbers
        without a header (then taken as milliseconds, and ``metadata["note"]`` says so). Leading
        ``# key: value`` lines are metadata.

    Returns
    -------
    Recording
        ``time`` = edge times [s], ``counts`` = edge index 0, 1, 2, …; ``metadata``: ``format``
        ``"scope-times"``, ``kind`` ``"edges"``, ``time_unit`` as written.

    Raises
    ------
    LogFormatError
        Empty/binary file, more than one column, a non-numeric or non-finite time, times that do not
        strictly increase (two edges cannot share a time).
    """
    text = read_text(path)
    name = text.path
    metadata, comments, start = parse_comments(text)
    first = line_at(text, start)  # from the top of the file: two million edge times are not split here
    if first is None:
        raise LogFormatError("no edge times (only comments)", path=name)
    delimiter = guess_delimiter(first)
    fields = split_fields(first, delimiter)
    if len(fields) == 1 and fields[0].lower() in _TIME_HEADERS:
        unit = "ms" if fields[0].lower() == "time_ms" else "s"
        factor = _TIME_HEADERS[fields[0].lower()]
        data_start = start + 1
    elif all(is_number(f) for f in fields):
        unit, factor, data_start = "ms", 1e-3, start
        metadata["note"] = "no header: times taken as milliseconds"
    else:
        raise LogFormatError(
            f"expected a single column headed time_ms or time_s, found {first[:60]!r}", path=name, line=start + 1
        )
    times, lines = _read_single_column(text, data_start, delimiter, f"time_{unit}")
    if times.size == 0:
        raise LogFormatError("no edge times after the header", path=name, line=data_start)
    times = times * factor
    bad = np.flatnonzero(np.diff(times) <= 0)
    if bad.size:
        i = int(bad[0]) + 1
        raise LogFormatError("edge times must increase from row to row", path=name, line=int(lines[i]))
    metadata.update({"format": "scope-times", "time_unit": unit, "comments": comments})
    return _edges_recording(times, lines, name, metadata)


def _read_single_column(
    text: TextFile, start: int, delimiter: str | None, column: str
) -> tuple[np.ndarray, np.ndarray]:
    table = fast_table(text, start + 1, 1, None)  # a clean column of numbers: parsed in C
    if table is not None and table.truncated is None:
        return table.values[:, 0], table.lines
    values: list[float] = []
    lines: list[int] = []
    for number, raw in enumerate(text.lines[start:], start=start + 1):
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        fields = split_fields(line, delimiter)
        if len(fields) != 1:
            raise LogFormatError(f"expected one value per row, found {len(fields)}", path=text.path, line=number)
        if text.may_be_truncated(number) and not is_number(fields[0]):
            break
        values.append(parse_number(fields[0], path=text.path, line=number, column=column))
        lines.append(number)
    return np.asarray(values, dtype=float), np.asarray(lines, dtype=int)


@dataclass(frozen=True)
class Waveform:
    """A sampled voltage trace: ``time`` [s], ``volts`` [V], the file line of each sample."""

    time: np.ndarray
    volts: np.ndarray
    lines: np.ndarray
    channel: str
    layout: str


def read_waveform_samples(path: PathArg, *, channel: str | None = None) -> Waveform:
    """Read the samples of a waveform CSV (Rigol DS1000Z export or ``time_s,CH1_V`` table).

    Parameters
    ----------
    path
        Rigol layout: ``X,CH1,Start,Increment,`` / ``Sequence,Volt,<start>,<increment>,`` /
        ``<index>,<volts>,`` rows (time = start + index·increment; older firmware writes
        ``Second`` instead of ``Sequence`` and the time itself in the first column). Generic layout:
        a header ``time_s`` (or ``time_ms``) followed by channel columns such as ``CH1_V`` or ``CH1``.
    channel
        Column to use (``"CH1"``, ``"CH2"``, ``"CH1_V"`` …); the first channel by default.

    Raises
    ------
    LogFormatError
        Unknown layout, missing channel, non-numeric or non-finite samples, too few samples.
    """
    text = read_text(path)
    name = text.path
    numbered = [(n, line) for n, line in text.numbered() if not line.startswith("#")]
    if len(numbered) < 2:
        raise LogFormatError("too short for a waveform (needs a header and samples)", path=name)
    header_no, header_line = numbered[0]
    header = split_fields(header_line, ",")
    layout, channels, rows, (start, increment, time_factor) = _waveform_layout(header, numbered, name)
    if not channels:
        raise LogFormatError("no channel column in the header", path=name, line=header_no)
    if channel is None:
        column = 1
    else:
        wanted = channel.lower()
        matches = [i for i, c in enumerate(channels) if c.lower() in (wanted, f"{wanted}_v")]
        if not matches:
            raise OptionError(f"channel {channel!r} is not in {name} (it has: {', '.join(channels)})")
        column = matches[0] + 1
    label = header[column]
    xs, ys, lines = _waveform_rows(text, rows, column, header[0], label)
    if len(xs) < 2:
        raise LogFormatError("fewer than two samples", path=name)
    x_arr = np.asarray(xs)
    time = start + x_arr * increment if start is not None and increment is not None else x_arr * time_factor
    if np.any(np.diff(time) <= 0):
        i = int(np.flatnonzero(np.diff(time) <= 0)[0]) + 1
        raise LogFormatError("sample times must increase", path=name, line=lines[i])
    return Waveform(time, np.asarray(ys), np.asarray(lines, dtype=int), label, layout)


_Timing = tuple[float | None, float | None, float]


def _waveform_layout(
    header: list[str], numbered: list[tuple[int, str]], name: str
) -> tuple[str, list[str], list[tuple[int, str]], _Timing]:
    """Layout, channel names, sample rows and timing of a waveform file from its header line(s).

    ``numbered`` holds the (line number, line) pairs of the file without comments, the header
    first. The timing is ``(start, increment, time_factor)``: a Rigol ``Sequence`` export gives the
    time of sample ``x`` as start + x·increment, other layouts as x·time_factor (start and increment
    then None).
    """
    header_no, header_line = numbered[0]
    lower = [h.lower() for h in header]
    rows = numbered[1:]
    start = increment = None
    if lower and lower[0] == "x":
        layout = "rigol"
        channels = [h for h in header[1:] if h.lower() not in ("start", "increment")]
        units_no, units_line = rows[0]
        units = split_fields(units_line, ",")
        rows = rows[1:]
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
    elif lower and lower[0] in _TIME_HEADERS:
        layout = "table"
        channels = header[1:]
        time_factor = _TIME_HEADERS[lower[0]]
    else:
        raise LogFormatError(
            f"not a waveform export: expected 'X,CH1,Start,Increment' or 'time_s,CH1_V', found {header_line[:60]!r}",
            path=name,
            line=header_no,
        )
    return layout, channels, rows, (start, increment, time_factor)


def _waveform_rows(
    text: TextFile, rows: list[tuple[int, str]], column: int, x_label: str, label: str
) -> tuple[list[float], list[float], list[int]]:
    """First-column values, ``column`` values and line numbers of the sample rows.

    A short or non-numeric last line without a line terminator (the writer was cut off) ends the
    samples quietly; anywhere else it is an error naming the line.
    """
    name = text.path
    xs: list[float] = []
    ys: list[float] = []
    lines: list[int] = []
    for number, line in rows:
        fields = split_fields(line, ",")
        if len(fields) <= column:
            if text.may_be_truncated(number):
                break
            raise LogFormatError(f"row has no {label} value", path=name, line=number)
        try:
            x = parse_number(fields[0], path=name, line=number, column=x_label)
            y = parse_number(fields[column], path=name, line=number, column=label)
        except LogFormatError:
            if text.may_be_truncated(number):
                break
            raise
        xs.append(x)
        ys.append(y)
        lines.append(number)
    return xs, ys, lines


def find_rising_edges(
    time: np.ndarray,
    volts: np.ndarray,
    *,
    threshold: float | None = None,
    hysteresis: float | None = None,
) -> tuple[np.ndarray, dict[str, float]]:
    """Rising-edge times of a logic-like trace, with a Schmitt trigger and linear interpolation.

    Parameters
    ----------
    time
        Sample times [s], increasing.
    volts
        Samples [V].
    threshold
        Centre of the trigger window [V]; by default the middle of the low and high levels.
    hysteresis
        Full width of the window [V]; by default 40 % of the low-to-high range (levels at 30 % and
        70 % of the range).

    Returns
    -------
    edges
        Times [s] where the trace crosses ``threshold`` going up, interpolated linearly between the
        two samples around the crossing, one per low→high transition of the trigger.
    levels
        ``{"low", "high", "threshold", "hysteresis", "low_level", "high_level"}`` [V].

    Notes
    -----
    Low and high levels are the 5th and 95th percentiles, so that ringing and single spikes do not
    set them. A transition counts only when the trace, having been at or below ``threshold −
    hysteresis/2``, reaches ``threshold + hysteresis/2``: noise around one level cannot make edges.
    """
    low_level = float(np.percentile(volts, 5))
    high_level = float(np.percentile(volts, 95))
    span = high_level - low_level
    if threshold is None:
        threshold = low_level + 0.5 * (LOW_FRACTION + HIGH_FRACTION) * span
    if hysteresis is None:
        hysteresis = (HIGH_FRACTION - LOW_FRACTION) * span
    if hysteresis < 0:
        raise OptionError(f"hysteresis must not be negative, got {hysteresis}")
    lo = threshold - hysteresis / 2
    hi = threshold + hysteresis / 2
    levels = {
        "low": lo,
        "high": hi,
        "threshold": threshold,
        "hysteresis": hysteresis,
        "low_level": low_level,
        "high_level": high_level,
    }
    # Trigger state per sample: 1 above hi, 0 below lo, carried forward in between (-1 = not yet known).
    state = np.full(volts.size, -1, dtype=np.int8)
    state[volts >= hi] = 1
    state[volts <= lo] = 0
    known = np.where(state >= 0, np.arange(volts.size), 0)
    np.maximum.accumulate(known, out=known)
    filled = state[known]  # leading samples inside the window stay -1 (state[0] is then -1)
    rises = np.flatnonzero((filled[1:] == 1) & (filled[:-1] == 0)) + 1
    # The crossing lies after the last sample below the threshold before the trigger fired (such a
    # sample exists: the state was low, i.e. at or below threshold - hysteresis/2).
    below_index = np.where(volts <= threshold, np.arange(volts.size), -1)
    np.maximum.accumulate(below_index, out=below_index)
    j = below_index[rises]
    v0, v1 = volts[j], volts[j + 1]
    frac = np.clip((threshold - v0) / (v1 - v0), 0.0, 1.0)  # v1 > threshold >= v0, so v1 != v0
    edges = time[j] + frac * (time[j + 1] - time[j])
    return edges, levels


def read_scope_waveform(
    path: PathArg,
    *,
    threshold: float | None = None,
    hysteresis: float | None = None,
    channel: str | None = None,
) -> Recording:
    """Read an oscilloscope waveform export and return the rising-edge times of the encoder signal.

    Parameters
    ----------
    path
        Rigol DS1000Z CSV export or a ``time_s,CH1_V`` table (see :func:`read_waveform_samples`).
    threshold
        Trigger centre [V]; default halfway between the low and high levels.
    hysteresis
        Trigger window width [V]; default 40 % of the low-to-high range (30 %/70 % levels).
    channel
        Channel column (``"CH1"`` …); the first one by default.

    Returns
    -------
    Recording
        Same shape as :func:`read_scope_times`: ``time`` = edge times [s], ``counts`` = edge index;
        ``lines`` = the file line of the sample just after each crossing; ``metadata``: ``format``
        ``"scope-waveform"``, ``layout`` (``"rigol"`` or ``"table"``), ``channel``, the trigger
        ``levels`` [V], ``n_samples``, ``sample_interval`` [s].

    Raises
    ------
    LogFormatError
        Unreadable file (see :func:`read_waveform_samples`), or no rising edge found.
    """
    wave = read_waveform_samples(path, channel=channel)
    edges, levels = find_rising_edges(wave.time, wave.volts, threshold=threshold, hysteresis=hysteresis)
    name = os.fsdecode(os.fspath(path))
    if edges.size == 0:
        raise LogFormatError(
            f"no rising edge found in {wave.channel} (levels {levels['low_level']:.3g} V to "
            f"{levels['high_level']:.3g} V, trigger {levels['low']:.3g}/{levels['high']:.3g} V)",
            path=name,
        )
    index = np.searchsorted(wave.time, edges, side="left").clip(0, wave.time.size - 1)
    metadata = {
        "format": "scope-waveform",
        "layout": wave.layout,
        "channel": wave.channel,
        "levels": levels,
        "n_samples": int(wave.time.size),
        "sample_interval": float(np.median(np.diff(wave.time))),
    }
    return _edges_recording(edges, wave.lines[index], name, metadata)

