"""Time spans left out of a log (``--exclude 12.5:14.0``): the wheels slipping, a burst of glitches.

A span is ``(start, end)`` in seconds of the log's own time axis (the time the reader returns, which
the app's "signals as read" plot shows). The analyses that read time series honour them in one of
two ways:

* :func:`leave_out` with ``split=False`` drops the samples (fits whose model is a closed form in time,
  one residual per sample: the spin-down's coast, the spin-up's constant-current phase);
* with ``split=True`` it cuts the run at each span into separate runs (the output-error fits, which
  simulate the run from its voltage: dropping samples would join two instants the motor did not join).
  Each piece is then simulated from its own start (its angle offset and, when it starts moving, its
  speed are fitted), so what happened in the span (slip, a current burst) does not carry into the
  state the simulation starts from after it. A piece too short to fit is left out with the span.

What was left out is said in the result: ``details["left_out"]`` and a line among its warnings
("2 time spans left out, 1.40 s, 312 samples").
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from motorlab.errors import OptionError
from motorlab.recording import Recording

Span = tuple[float, float]

_NUMBER = r"[-+]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][-+]?\d+)?"
_SPAN = re.compile(rf"^\s*({_NUMBER})\s*(?:s\s*)?(?::|–|—|\.\.)\s*({_NUMBER})\s*(?:s\s*)?$")


def parse_span(text: str, *, name: str = "exclude") -> Span:
    """One span from ``"12.5:14.0"`` (also ``12.5–14.0``, ``12.5 s:14 s``, ``12.5..14``) [s].

    Raises
    ------
    OptionError
        Not two numbers, not finite, or an end not after the start (naming ``name``).
    """
    found = _SPAN.match(str(text))
    if not found:
        raise OptionError(f"{name}: {text!r} is not a time span; write start:end in seconds of the log's time, "
                          "e.g. 12.5:14.0")
    start, end = float(found.group(1)), float(found.group(2))
    if not (math.isfinite(start) and math.isfinite(end)):
        raise OptionError(f"{name}: {text!r} is not a finite time span")
    if not end > start:
        raise OptionError(f"{name}: {text!r} ends before it starts; write start:end, e.g. 12.5:14.0")
    return start, end


def parse_spans(value: Any, *, name: str = "exclude") -> list[Span]:
    """Spans from text (``"12.5:14, 20:21"``, commas or semicolons between spans), pairs, or a list of either."""
    if value is None:
        return []
    items: Iterable[Any] = [value] if isinstance(value, str) or _is_pair(value) else value
    spans: list[Span] = []
    for item in items:
        if _is_pair(item):
            spans.append(parse_span(f"{float(item[0])!r}:{float(item[1])!r}", name=name))
            continue
        spans.extend(parse_span(part, name=name) for part in re.split(r"[,;]", str(item)) if part.strip())
    return spans


def setting_spans(value: Any, *, takes_spans: bool, hint: str) -> list[Span]:
    """A session table's ``exclude`` (``"12.5:14.0"`` or a list of them) for an experiment.

    ``takes_spans``: whether the experiment's analysis takes time spans; ``hint``: what to do when it does not
    (:func:`motorlab.experiments.exclude_hint`; the caller asks the registry, which reads this module).

    Raises
    ------
    OptionError
        An experiment whose analysis takes no spans (saying what to do), or a value that is no span.
    """
    if value is None:
        return []
    if not takes_spans:
        raise OptionError(hint)
    if not (isinstance(value, str) or (isinstance(value, list) and all(isinstance(v, str) for v in value))):
        raise OptionError(f'expected "START:END" in seconds or a list of them, got {type(value).__name__}')
    try:
        return parse_spans(value)
    except OptionError as exc:
        raise OptionError(exc.message.removeprefix("exclude: ")) from None


def _is_pair(value: Any) -> bool:
    return (isinstance(value, tuple | list) and len(value) == 2
            and all(isinstance(v, int | float) and not isinstance(v, bool) for v in value))


def merged(spans: Sequence[Span]) -> list[Span]:
    """The spans sorted, overlapping ones joined."""
    out: list[list[float]] = []
    for start, end in sorted(spans):
        if out and start <= out[-1][1]:
            out[-1][1] = max(out[-1][1], end)
        else:
            out.append([start, end])
    return [(a, b) for a, b in out]


def mask(time: np.ndarray, spans: Sequence[Span]) -> np.ndarray:
    """True for each sample inside a span (ends included)."""
    time = np.asarray(time, dtype=float)
    out = np.zeros(time.shape, dtype=bool)
    for start, end in spans:
        out |= (time >= start) & (time <= end)
    return out


def span_text(span: Span) -> str:
    """``"12.5–14 s"``."""
    return f"{span[0]:.6g}–{span[1]:.6g} s"


@dataclass
class LeftOut:
    """What :func:`leave_out` took out: the spans, their seconds within the logs, the samples."""

    spans: list[Span]
    seconds: float
    samples: int
    pieces_dropped: int = 0

    def text(self) -> str:
        """``"2 time spans left out, 1.40 s, 312 samples"``."""
        n = len(self.spans)
        words = f"{n} time span{'s' if n != 1 else ''} left out, {self.seconds:.2f} s, {self.samples} sample" + (
            "s" if self.samples != 1 else "")
        return words + " (" + ", ".join(span_text(s) for s in self.spans) + " of the log's time)"

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: spans, seconds, samples and the sentence."""
        return {"spans": [list(s) for s in self.spans], "seconds": self.seconds, "samples": self.samples,
                "pieces_dropped": self.pieces_dropped, "text": self.text()}

    def note(self, result: Any) -> Any:
        """Say it in ``result`` (``details["left_out"]`` and a warning line); returns ``result``."""
        result.details["left_out"] = self.to_dict()
        result.warnings.insert(0, self.text())
        return result


def leave_out(recordings: Sequence[Recording], spans: Sequence[Span], *, split: bool,
              min_samples: int = 20) -> tuple[list[Recording], LeftOut]:
    """The recordings without the samples inside ``spans`` (dropped, or the runs cut there: see the module).

    Raises
    ------
    OptionError
        A span that holds no sample of any recording (naming the logs' time range), or spans that leave
        nothing to fit.
    """
    spans = merged(spans)
    recs = list(recordings)
    masks = [mask(rec.time, spans) for rec in recs]
    for span in spans:
        if not any(np.any(mask(rec.time, [span])) for rec in recs):
            lo = min(float(rec.time[0]) for rec in recs if len(rec))
            hi = max(float(rec.time[-1]) for rec in recs if len(rec))
            raise OptionError(f"the time span {span_text(span)} to leave out holds no sample: the log's time runs "
                              f"{lo:.4g}–{hi:.4g} s", path=_sources(recs))
    out: list[Recording] = []
    samples = int(sum(int(m.sum()) for m in masks))
    dropped = 0
    for rec, m in zip(recs, masks, strict=True):
        if not m.any():
            out.append(rec)
            continue
        if not split:
            out.append(rec.select(~m))
            continue
        pieces = _runs_of(~m)
        for k, (a, b) in enumerate(pieces):
            if b - a < min_samples:
                samples += b - a
                dropped += 1
                continue
            piece = rec.select(slice(a, b))
            label = rec.metadata.get("segment") or "run"
            piece.metadata["segment"] = f"{label}, part {k + 1} of {len(pieces)}" if len(pieces) > 1 else label
            out.append(piece)
    if not out or all(len(r) == 0 for r in out):
        raise OptionError("the time spans to leave out leave nothing of the log to fit", path=_sources(recs))
    lo = min(float(rec.time[0]) for rec in recs if len(rec))
    hi = max(float(rec.time[-1]) for rec in recs if len(rec))
    seconds = float(sum(max(0.0, min(b, hi) - max(a, lo)) for a, b in spans))
    return out, LeftOut(list(spans), seconds, samples, dropped)


def _runs_of(keep: np.ndarray) -> list[tuple[int, int]]:
    """``[(start, stop), ...]`` of the stretches where ``keep`` is True."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], keep.astype(np.int8), [0]])))
    return [(int(a), int(b)) for a, b in zip(edges[::2], edges[1::2], strict=True)]


def _sources(recs: Sequence[Recording]) -> str | None:
    names = list(dict.fromkeys(rec.source for rec in recs if rec.source))
    return " + ".join(names) or None
