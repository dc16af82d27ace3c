"""Oscilloscope data: cursor times of encoder edges, and waveform exports (Rigol DS1000Z CSV).

Seed 1's "Free Motor Spin-Up Experiment" reads the times of encoder transitions off a Rigol DS1054Z.
Both readers return the same shape: ``time`` = edge times [s] and ``counts`` = 0, 1, 2, … (the edge
index), ``metadata["kind"] == "edges"``. One rising edge on one encoder channel is four quadrature
counts (the seed: "the times we recorded ... represent every fourth encoder count"); the analyses
apply that factor, the readers do not.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from motorlab import progress
from motorlab.errors import LogFormatError, OptionError
from motorlab.io._waveform import (
    TIME_HEADERS,
    Samples,
    pick_channel,
    stream_samples,
    waveform_layout,
    waveform_rows,
)
from motorlab.io.csv_table import guess_delimiter, line_at, parse_comments, split_fields
from motorlab.io.text import PathArg, TextFile, fast_table, is_number, parse_number, read_text
from motorlab.recording import Recording

_TIME_HEADERS = TIME_HEADERS

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

    Returns
    -------
    Waveform
        Every sample in memory (float64). :func:`read_scope_waveform` does not make these arrays:
        it reads the file chunk by chunk and keeps the volts as 32-bit floats.

    Raises
    ------
    LogFormatError
        Unknown layout, missing channel, non-numeric or non-finite samples, too few samples.
    """
    samples = stream_samples(path, channel)
    if samples is None:
        return _samples_in_memory(path, channel)
    index = np.arange(samples.volts.size)
    return Waveform(samples.time_at(index), samples.volts.astype(float), samples.lines_of(index), samples.channel,
                    samples.layout)


def _samples_in_memory(path: PathArg, channel: str | None) -> Waveform:
    """:func:`read_waveform_samples` for a file whose lines end with bare carriage returns: read whole."""
    text = read_text(path)
    name = text.path
    numbered = [(n, line) for n, line in text.numbered() if not line.startswith("#")]
    if len(numbered) < 2:
        raise LogFormatError("too short for a waveform (needs a header and samples)", path=name)
    header_no, header_line = numbered[0]
    header = split_fields(header_line, ",")
    layout, channels, used, (start, increment, time_factor) = waveform_layout(header, numbered, name)
    column = pick_channel(channels, channel, name, header_no)
    label = header[column]
    truncatable = len(text.lines) if not text.ends_with_newline else None
    xs, ys, lines = waveform_rows(name, numbered[used:], column, (header[0], label), truncatable)
    if len(xs) < 2:
        raise LogFormatError("fewer than two samples", path=name)
    x_arr = np.asarray(xs)
    time = start + x_arr * increment if start is not None and increment is not None else x_arr * time_factor
    if np.any(np.diff(time) <= 0):
        i = int(np.flatnonzero(np.diff(time) <= 0)[0]) + 1
        raise LogFormatError("sample times must increase", path=name, line=lines[i])
    return Waveform(time, np.asarray(ys), np.asarray(lines, dtype=int), label, layout)


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
    volts = np.asarray(volts)
    levels = trigger_levels(volts, threshold=threshold, hysteresis=hysteresis)
    j = _crossings(volts, levels)
    time = np.asarray(time, dtype=float)
    edges, _ = _interpolate(j, volts, levels["threshold"], lambda k: time[k])
    return edges, levels


def trigger_levels(volts: np.ndarray, *, threshold: float | None, hysteresis: float | None) -> dict[str, float]:
    """The Schmitt trigger's window (see :func:`find_rising_edges`): ``low``, ``high``, ``threshold`` … [V].

    Raises
    ------
    OptionError
        A negative hysteresis.
    """
    low_level, high_level = (float(v) for v in np.percentile(volts, [5, 95]))
    span = high_level - low_level
    if threshold is None:
        threshold = low_level + 0.5 * (LOW_FRACTION + HIGH_FRACTION) * span
    if hysteresis is None:
        hysteresis = (HIGH_FRACTION - LOW_FRACTION) * span
    if hysteresis < 0:
        raise OptionError(f"hysteresis must not be negative, got {hysteresis}")
    return {
        "low": threshold - hysteresis / 2,
        "high": threshold + hysteresis / 2,
        "threshold": threshold,
        "hysteresis": hysteresis,
        "low_level": low_level,
        "high_level": high_level,
    }


#: Samples the trigger looks at in one go (bounds its temporary arrays on a 24 Mpt capture).
_BLOCK = 1 << 20


def _crossings(volts: np.ndarray, levels: dict[str, float]) -> np.ndarray:
    """For each rise of the trigger, the last sample at or below the threshold before it (block by block).

    Trigger state per sample: 1 at or above ``high``, 0 at or below ``low``, carried forward in
    between (unknown until the trace first leaves the window); a rise is a sample whose state is 1
    after a 0. The crossing lies after the last sample below the threshold before the rise (such a
    sample exists: the state was low, i.e. at or below threshold − hysteresis/2).
    """
    lo, hi, threshold = levels["low"], levels["high"], levels["threshold"]
    state, last_below = -1, -1
    found = []
    for a in range(0, volts.size, _BLOCK):
        v = np.asarray(volts[a : a + _BLOCK], dtype=float)
        mark = np.full(v.size, -1, dtype=np.int8)
        mark[v >= hi] = 1
        mark[v <= lo] = 0
        known = np.where(mark >= 0, np.arange(v.size), -1)
        np.maximum.accumulate(known, out=known)
        filled = np.where(known >= 0, mark[np.maximum(known, 0)], state).astype(np.int8)
        before = np.concatenate([np.array([state], dtype=np.int8), filled[:-1]])
        rises = np.flatnonzero((filled == 1) & (before == 0))
        below = np.where(v <= threshold, np.arange(a, a + v.size), -1)
        np.maximum.accumulate(below, out=below)
        below = np.where(below >= 0, below, last_below)
        found.append(below[rises])
        state, last_below = int(filled[-1]), int(below[-1])
    return np.concatenate(found) if found else np.zeros(0, dtype=np.int64)


def _interpolate(
    j: np.ndarray, volts: np.ndarray, threshold: float, time_at: Callable[[np.ndarray], np.ndarray]
) -> tuple[np.ndarray, np.ndarray]:
    """Edge times between samples j and j + 1 where the trace crosses ``threshold``, and the index of the
    first sample at or after each edge."""
    v0 = np.asarray(volts[j], dtype=float)
    v1 = np.asarray(volts[j + 1], dtype=float)
    frac = np.clip((threshold - v0) / (v1 - v0), 0.0, 1.0)  # v1 > threshold >= v0, so v1 != v0
    t0, t1 = time_at(j), time_at(j + 1)
    edges = t0 + frac * (t1 - t0)
    after = np.where(edges > t0, j + 1, j)
    return edges, after


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
    samples = stream_samples(path, channel)
    name = os.fsdecode(os.fspath(path))
    if samples is None:  # bare carriage returns: read whole
        wave = _samples_in_memory(path, channel)
        samples = Samples(wave.volts.astype(np.float32), wave.time, 0.0, (None, None, 1.0), wave.channel, wave.layout,
                          [0], [wave.lines])
    with progress.task(f"Finding the edges of {samples.channel}", total=samples.volts.size, unit="samples") as step:
        levels = trigger_levels(samples.volts, threshold=threshold, hysteresis=hysteresis)
        j = _crossings(samples.volts, levels)
        step.update(samples.volts.size)
    if j.size == 0:
        raise LogFormatError(
            f"no rising edge found in {samples.channel} (levels {levels['low_level']:.3g} V to "
            f"{levels['high_level']:.3g} V, trigger {levels['low']:.3g}/{levels['high']:.3g} V)",
            path=name,
        )
    edges, after = _interpolate(j, samples.volts, levels["threshold"], samples.time_at)
    index = after.clip(0, samples.volts.size - 1)
    metadata = {
        "format": "scope-waveform",
        "layout": samples.layout,
        "channel": samples.channel,
        "levels": levels,
        "n_samples": int(samples.volts.size),
        "sample_interval": samples.sample_interval(),
    }
    return _edges_recording(edges, samples.lines_of(index), name, metadata)
