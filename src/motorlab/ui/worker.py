"""What the app's child processes run for the page's plots (the answers themselves come from the CLI).

``python -m motorlab.ui.worker detect FILE...`` prints, per file, its format
(:func:`motorlab.io.detect_format`), the proposed experiment and its signals to plot;
``python -m motorlab.ui.worker panels EXPERIMENT ARG...`` parses ``motorlab analyze EXPERIMENT
ARG...`` with the CLI's own parser, runs ``motorlab.cli.analyze.from_cli`` and prints the result's
data-against-model panels (the curves :func:`motorlab.plot.plot_fit` draws). Errors go through the
one line on stderr, exit code 2, as the CLI's.
"""

from __future__ import annotations

import json
import os
import sys
from collections.abc import Sequence
from typing import Any

import numpy as np

from motorlab.proposal import propose

#: Points sent per curve (a 2M-sample log is thinned by a stride for the browser).
MAX_POINTS = 4000


def _thin(values: np.ndarray) -> list[float | None]:
    arr = np.asarray(values, dtype=float)
    step = max(1, int(np.ceil(arr.size / MAX_POINTS)))
    return [float(v) if np.isfinite(v) else None for v in arr[::step]]


def detect(paths: Sequence[str]) -> list[dict[str, Any]]:
    """Per file: format, proposed experiment and the signals against time (or the error)."""
    from motorlab.errors import MotorlabError
    from motorlab.io import detect_format, read_any
    from motorlab.recording import SIGNALS

    out: list[dict[str, Any]] = []
    for path in paths:
        entry: dict[str, Any] = {"file": os.path.basename(path)}
        try:
            fmt = detect_format(path)
            recording = read_any(path)
        except (MotorlabError, OSError, ValueError) as exc:
            entry["error"] = " ".join(str(exc).split())
            out.append(entry)
            continue
        names = list(recording.signals)
        entry.update(
            format=fmt,
            experiment=propose(fmt, names, str(recording.metadata.get("experiment") or "") or None),
            time=_thin(recording.time),
            signals=[{"name": n, "unit": SIGNALS.get(n, ""), "y": _thin(recording.signals[n])} for n in names],
        )
        out.append(entry)
    return out


def _series(series: Any) -> dict[str, Any] | None:
    if series is None:
        return None
    return {"x": _thin(series.x), "y": _thin(series.y), "label": series.label, "kind": series.kind}


def panels(argv: Sequence[str]) -> list[dict[str, Any]]:
    """The data-against-model panels of ``motorlab analyze EXPERIMENT ARG...`` (first file group)."""
    from motorlab.cli import build_parser
    from motorlab.cli.analyze import from_cli

    args = build_parser().parse_args(["analyze", *argv])
    result = from_cli(args.experiment, list(args.files), args)
    return [
        {
            "title": p.title,
            "x_label": p.x_label,
            "y_label": p.y_label,
            "data": _series(p.data),
            "model": _series(p.model),
            "extra": [_series(s) for s in p.extra],
            "same_x": bool(p.data is not None and p.model is not None and np.array_equal(p.data.x, p.model.x)),
        }
        for p in result.panels
    ]


def main(argv: Sequence[str] | None = None) -> int:
    """Entry of the child process: JSON on stdout, or one error line on stderr and exit code 2."""
    from motorlab.errors import MotorlabError

    args = list(sys.argv[1:] if argv is None else argv)
    if not args or args[0] not in ("detect", "panels"):
        print("motorlab: error: worker: use 'detect FILE...' or 'panels EXPERIMENT ARG...'", file=sys.stderr)
        return 2
    try:
        result = detect(args[1:]) if args[0] == "detect" else panels(args[1:])
    except (MotorlabError, OSError) as exc:  # the analyze call reports the same error in the CLI's words
        print(f"motorlab: error: {' '.join(str(exc).split())}", file=sys.stderr)
        return 2
    print(json.dumps(result, allow_nan=False))
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
