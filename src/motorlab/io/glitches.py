"""Single-sample glitches in a log: found, named by their line, excluded; absurd magnitudes refused.

A failed I²C read makes an FTC OpMode log ``2147483647`` (2³¹−1) counts for one sample; an INA219
library returns ``65535`` for a read that timed out; a hand-typed table gets a stray digit. One
such sample ruins a least-squares fit (a spin-down then ends as "K not determined"), yet the rest
of the log is good. :func:`screen_glitches` finds samples that jump away from both neighbours
(which agree with each other) by far more than the signal's own spread and step, drops those rows
and says so in ``metadata["warnings"]`` with the file and line; a value beyond any measurement
(1e308 A) on many rows refuses the file instead.
"""

from __future__ import annotations

import numpy as np

from motorlab.errors import LogFormatError
from motorlab.recording import Recording

#: Magnitudes no dynamometer measures, per signal in SI (a value beyond is a corrupt sample).
ABSURD: dict[str, float] = {
    "counts": 2.0**53,
    "position": 1e12,
    "velocity": 1e7,
    "speed": 1e7,
    "voltage": 1e5,
    "command": 1e5,
    "battery": 1e5,
    "tach_voltage": 1e5,
    "current": 1e5,
    "mass": 1e6,
    "torque": 1e6,
    "inductance": 1e3,
    "dc_resistance": 1e9,
    "frequency": 1e10,
    "quality_factor": 1e9,
}
DEFAULT_ABSURD = 1e15
#: Time [s] beyond which a timestamp is corrupt (three years).
ABSURD_TIME = 1e8

#: At most this fraction of the rows (and at least two rows) is excluded as glitches; more is data.
MAX_FRACTION = 1e-2
_SAMPLE = 200_000
_BLOCK = 1 << 16


def _spikes(x: np.ndarray) -> np.ndarray:
    """Indices of samples that leave both neighbours (which agree) by far more than the signal's spread."""
    n = x.size
    if n < 3:
        return np.empty(0, dtype=int)
    # Scales from at most ~200 000 values (a long log's quantiles do not need all of them).
    stride = max(1, n // _SAMPLE)
    q25, q75, q01, q99 = np.percentile(x[::stride], [25, 75, 1, 99])
    block = max(2, min(n, _SAMPLE) // 200)
    starts = range(0, n - 1, max(block, (n - 1) // 200))
    steps = np.concatenate([np.abs(np.diff(x[s : s + block + 1])) for s in starts])
    pieces = [x[s : s + block + 1] for s in starts]
    bends = np.concatenate([np.abs(p[1:-1] - 0.5 * (p[:-2] + p[2:])) for p in pieces if p.size > 2] or [np.zeros(0)])
    # The lower quartile of the steps: a glitch makes two huge steps, which must not set the scale
    # of a short table (five rows of a terminal-velocity experiment). The noise is what a sample leaves
    # the mean of its neighbours by (the median: a glitch bends three samples, which must not set it in
    # a ten-row table; in a five-row one every bend is the glitch's, so the spread caps it), not the
    # signal's spread alone: a ramping count (a coast) spans thousands, yet a 0 among 7491 and 7517 is
    # a glitch. 40 medians of a Gaussian's are 33 standard deviations.
    step_scale = float(np.percentile(steps, 25))
    noise = min(float(np.median(bends)) if bends.size else 0.0, float(q75 - q25))
    floor = max(40.0 * noise, 40.0 * step_scale, 0.01 * max(abs(float(q01)), abs(float(q99))))
    found = []
    for s in range(1, n - 1, _BLOCK):  # in blocks: no n-long temporaries for a 2M-row log
        stop = min(s + _BLOCK, n - 1)
        centre, before, after = x[s:stop], x[s - 1 : stop - 1], x[s + 1 : stop + 1]
        e = np.abs(centre - 0.5 * (before + after))
        candidate = (e > floor) & (np.abs(after - before) < 0.1 * e) & (e > 0)
        found.append(np.flatnonzero(candidate) + s)
    return np.concatenate(found)


def screen_glitches(recording: Recording, *, spikes: bool = True) -> Recording:
    """The recording without its single-sample glitches; each one named in ``metadata["warnings"]``.

    Parameters
    ----------
    recording
        As a reader returns it (``lines`` give the file lines; ``metadata["file_starts"]`` is kept
        consistent for split FTC logs).
    spikes
        Also exclude samples that jump away from both neighbours and back (False: only values beyond any
        measurement; a dynamometer's export, whose single-sample excursions are events of the run).

    Returns
    -------
    Recording
        The same object when nothing was found, else a copy without the glitch rows.

    Raises
    ------
    LogFormatError
        When a signal holds values beyond any measurement (:data:`ABSURD`) on more rows than a
        glitch explains, or every row has the same time.
    """
    n = len(recording)
    if n == 0:
        return recording
    allowed = max(2, int(MAX_FRACTION * n))
    bad: dict[int, str] = {}
    timed = recording.metadata.get("time") != "row index"
    if timed and n > 1 and float(recording.time[-1]) == float(recording.time[0]):
        raise LogFormatError("every row has the same time: the time column does not advance", path=_path(recording))
    columns = [("time", recording.time, ABSURD_TIME)] if timed else []
    # A position computed from counts and the user's cpr is the option's business, not the file's.
    derived = {"position"} if "counts" in recording.signals else set()
    columns += [
        (name, values, ABSURD.get(name, DEFAULT_ABSURD))
        for name, values in recording.signals.items()
        if name not in derived
    ]
    for name, values, limit in columns:
        absurd = np.flatnonzero((values > limit) | (values < -limit))
        if absurd.size > allowed:
            k = int(absurd[0])
            raise LogFormatError(
                f"{name} = {values[k]:.6g} is beyond any measurement (|value| > {limit:g} in SI units) "
                f"on {absurd.size} rows: a corrupt file or a wrong unit",
                path=_path(recording, k),
                line=recording.line_of(k),
            )
        for index in absurd.tolist():
            bad.setdefault(index, f"{name} = {values[index]:.6g} is beyond any measurement")
        if name == "time":
            continue
        jumps = _spikes(values) if absurd.size == 0 and spikes else np.empty(0, dtype=int)
        if 0 < jumps.size <= allowed:
            for index in jumps.tolist():
                bad.setdefault(index, f"{name} = {values[index]:.6g} jumps away from its neighbours and back")
    if not bad or len(bad) > allowed or len(bad) >= n - 1:
        return recording
    keep = np.ones(n, dtype=bool)
    keep[list(bad)] = False
    out = recording.select(keep)
    warnings = list(recording.metadata.get("warnings", []) or [])
    for k, why in sorted(bad.items()):
        line = recording.line_of(k)
        where = f"{_path(recording, k)}:{line}" if line is not None else f"{_path(recording, k)} (row {k + 1})"
        warnings.append(f"{where}: single-sample glitch excluded ({why}; a failed sensor read?)")
    out.metadata["warnings"] = warnings
    starts = recording.metadata.get("file_starts")
    if isinstance(starts, list):
        kept_before = np.concatenate([[0], np.cumsum(keep)])
        out.metadata["file_starts"] = [int(kept_before[s]) for s in starts]
    out.segments = {
        key: (int(np.sum(keep[:a])), int(np.sum(keep[:b]))) for key, (a, b) in recording.segments.items()
    }
    out.metadata["glitches_excluded"] = len(bad)
    return out


def _path(recording: Recording, row: int = 0) -> str | None:
    """The file holding ``row`` (for a run split over several files, the one the row came from)."""
    files = recording.metadata.get("files")
    starts = recording.metadata.get("file_starts")
    if isinstance(files, list) and isinstance(starts, list) and len(files) == len(starts) and files:
        index = int(np.searchsorted(np.asarray(starts), row, side="right")) - 1
        return str(files[max(index, 0)])
    return recording.source or None
