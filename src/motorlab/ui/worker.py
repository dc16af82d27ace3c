"""What the app's child processes run for the page's plots (the answers themselves come from the CLI).

``python -m motorlab.ui.worker detect FILE...`` prints, per file, its format
(:func:`motorlab.io.detect_format`), the proposed experiment and its signals to plot;
``python -m motorlab.ui.worker panels EXPERIMENT ARG...`` parses ``motorlab analyze EXPERIMENT
ARG...`` with the CLI's own parser, runs ``motorlab.cli.analyze.from_cli`` and prints the result's
data-against-model panels (the curves :func:`motorlab.plot.plot_fit` draws);
``python -m motorlab.ui.worker response ARG...`` runs ``motorlab tune ARG...`` and prints the
simulated step and profile responses as curves (the interactive plot of the gains step). Errors go
through the one line on stderr, exit code 2, as the CLI's.
"""

from __future__ import annotations

import json
import os
import re
import sys
from collections.abc import Sequence
from typing import Any

import numpy as np

from motorlab.proposal import propose, run_group, task_of

#: Points sent per curve (a 2M-sample log is thinned by a stride for the browser).
MAX_POINTS = 4000


def _thin(values: np.ndarray) -> list[float | None]:
    arr = np.asarray(values, dtype=float)
    step = max(1, int(np.ceil(arr.size / MAX_POINTS)))
    return [float(v) if np.isfinite(v) else None for v in arr[::step]]


#: Each format in words (what the page says it recognised).
FORMAT_WORDS = {
    "ftc-log": "FTC OpMode log",
    "csv": "table of measurements (CSV)",
    "scope-times": "oscilloscope export (times)",
    "scope-waveform": "oscilloscope waveform export",
    "sysid-json": "WPILib SysId file",
    "frc-char-json": "frc-characterization file",
    "wpilog": "WPILib data log",
    "roadrunner-ramp": "Road Runner ramp log",
    "roadrunner-log": "Road Runner FlightRecorder log",
    "session": "session description",
}

#: Which task of the page a file of this format most likely belongs to.
_TASK_BY_FORMAT = {"roadrunner-ramp": "drive", "roadrunner-log": "drive", "session": "bench",
                   "sysid-json": "mechanism", "frc-char-json": "mechanism", "wpilog": "mechanism"}

#: A stand-in counts per revolution that makes an angle in radians read as encoder ticks, so that a
#: log which needs the counts per revolution can be shown before the student has typed it.
_TICKS_AS_RADIANS = 2 * np.pi


def _read_for_detect(path: str, fmt: str, columns: Sequence[str]) -> tuple[Any, list[str]]:
    """The recording of ``path`` and the options it still needs (``["cpr"]`` for a log counting ticks)."""
    from motorlab.errors import OptionError
    from motorlab.io import read_any

    options: dict[str, Any] = {"columns": list(columns)} if columns and fmt == "csv" else {}
    try:
        return read_any(path, **options), []
    except OptionError as exc:
        if "cpr" not in str(exc):
            raise
        return read_any(path, cpr=_TICKS_AS_RADIANS, **options), ["cpr"]


_UNMAPPED = re.compile(r"column '([^']+)'")


def _column_question(entry: dict[str, Any]) -> None:
    """A reader's refusal of a column it cannot name: which column, and the quantities it could be."""
    from motorlab.io.headers import QUANTITIES

    found = _UNMAPPED.search(entry.get("error", ""))
    if found and "--column" in entry["error"]:
        entry["column"] = found.group(1)
        entry["quantities"] = [*QUANTITIES, "skip"]


def _detect_one(path: str, columns: Sequence[str] = ()) -> dict[str, Any]:
    """Format (in words), proposed experiment and task, signals against time, or the reader's refusal."""
    from motorlab.errors import MotorlabError
    from motorlab.io import detect_format
    from motorlab.recording import SIGNALS

    entry: dict[str, Any] = {"file": os.path.basename(path), "path": path}
    if path.lower().endswith(".toml"):
        entry.update(format="session", format_words=FORMAT_WORDS["session"], task="bench", experiment=None,
                     needs=[], time=[], signals=[])
        return entry
    try:
        fmt = detect_format(path)
        entry.update(format=fmt, format_words=FORMAT_WORDS.get(fmt, fmt), task=_TASK_BY_FORMAT.get(fmt))
        recording, needs = _read_for_detect(path, entry["format"], columns)
    except (MotorlabError, OSError, ValueError) as exc:
        entry["error"] = " ".join(str(exc).split())
        _column_question(entry)
        return entry
    names = list(recording.signals)
    units = dict(SIGNALS)
    if needs:  # read with the stand-in: angles are encoder ticks until the student gives the counts
        units.update(position="tick", velocity="tick/s")
    experiment = propose(fmt, names, str(recording.metadata.get("experiment") or "") or None,
                         timed=recording.metadata.get("time") != "row index")
    entry.update(
        experiment=experiment,
        group=run_group(experiment, path),  # runs fitted together (a motor's stall runs), or None
        task=entry["task"] or task_of(experiment)
        or ("mechanism" if experiment in ("spindown", "identify", "feedforward") else "expert"),
        needs=needs,
        cpr=None if needs else recording.metadata.get("cpr"),
        time=_thin(recording.time),
        signals=[{"name": n, "unit": units.get(n, ""), "y": _thin(recording.signals[n])} for n in names],
    )
    return entry


def detect(args: Sequence[str]) -> list[dict[str, Any]]:
    """Per file: format, proposed experiment and the signals against time (or the error).

    ``args`` are ``[--column=RULE ...] [--] FILE...``: the column rules (``Amps=current``) a CSV is
    read with. A file that needs an option to be read (a Road Runner log counts ticks: ``cpr``) is
    still recognised and proposed, with ``needs`` naming the option and its angles shown in ticks; a
    CSV column no reader can name gives ``column`` (its header) and ``quantities`` (what it may be).
    """
    args = list(args)
    cut = args.index("--") if "--" in args else 0
    columns = [a.split("=", 1)[1] for a in args[:cut] if a.startswith("--column=")]
    return [_detect_one(path, columns) for path in args[cut + 1 if "--" in args else 0:]]


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
            # each point's time in the log (what a span left out is given in), thinned as the points
            "time": _thin(p.time) if p.time is not None and p.data is not None and len(p.time) == len(p.data.x)
            else None,
        }
        for p in result.panels
    ]


def _curve(resp: Any, per: float) -> dict[str, Any]:
    """One simulated closed-loop run as curves in the target's units (time, reference, output, voltage)."""
    return {
        "kind": resp.kind,
        "time": _thin(resp.time),
        "reference": _thin(np.asarray(resp.reference) * per),
        "output": _thin(np.asarray(resp.output) * per),
        "voltage": _thin(resp.voltage),
    }


def response(argv: Sequence[str]) -> dict[str, Any]:
    """The step and profile responses of ``motorlab tune ARG...`` as curves, with the tune JSON.

    The CLI's own ``run`` designs the loop (so the options mean exactly what they mean there) and
    prints its JSON (returned under ``"tune"``: the page needs one run for the gains and the plot);
    the :class:`~motorlab.control.tune.TuneResult` it computes is caught on its way to the printing.
    """
    import contextlib
    import io

    import motorlab.cli.tune as cli_tune
    from motorlab.cli import build_parser

    args = build_parser().parse_args(["tune", *argv])
    args.json, args.plot = True, None
    caught: list[Any] = []
    design = cli_tune.tune

    def catch(*a: Any, **k: Any) -> Any:
        caught.append(design(*a, **k))
        return caught[-1]

    printed = io.StringIO()
    cli_tune.tune = catch  # type: ignore[assignment]
    try:
        with contextlib.redirect_stdout(printed):
            cli_tune.run(args)
    finally:
        cli_tune.tune = design  # type: ignore[assignment]
    result = caught[-1]
    per = result._display_per_radian()
    quantity = "velocity" if result.gains.loop == "velocity" else "position"
    return {
        "tune": json.loads(printed.getvalue()),  # what `motorlab tune ... --json` prints, so one run gives both
        "loop": result.gains.loop,
        "unit": result.target.units[quantity],
        "step": _curve(result.step, per),
        "profile": _curve(result.profile, per),
    }


def main(argv: Sequence[str] | None = None) -> int:
    """Entry of the child process: JSON on stdout, or one error line on stderr and exit code 2."""
    from motorlab.errors import MotorlabError

    args = list(sys.argv[1:] if argv is None else argv)
    commands = {"detect": detect, "panels": panels, "response": response}
    if not args or args[0] not in commands:
        print("motorlab: error: worker: use 'detect FILE...', 'panels EXPERIMENT ARG...' or 'response ARG...'",
              file=sys.stderr)
        return 2
    try:
        result: Any = commands[args[0]](args[1:])
    except (MotorlabError, OSError) as exc:  # the analyze call reports the same error in the CLI's words
        print(f"motorlab: error: {' '.join(str(exc).split())}", file=sys.stderr)
        return 2
    print(json.dumps(result, allow_nan=False))
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
