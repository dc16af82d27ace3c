"""What the app's child processes run for the page's plots (the answers themselves come from the CLI).

``python -m motorlab.ui.worker detect FILE...`` prints, per file, its format
(:func:`motorlab.io.detect_format`), the proposed experiment and its signals to plot;
``python -m motorlab.ui.worker panels EXPERIMENT ARG...`` parses ``motorlab analyze EXPERIMENT
ARG...`` with the CLI's own parser, runs ``motorlab.cli.analyze.from_cli`` and prints the result's
data-against-model panels (the curves :func:`motorlab.plot.plot_fit` draws);
``python -m motorlab.ui.worker fit EXPERIMENT ARG...`` does both in one run (the CLI's JSON and the
panels: the page's click on "Run the fit");
``python -m motorlab.ui.worker response ARG...`` runs ``motorlab tune ARG...`` and prints the
simulated step and profile responses as curves (the interactive plot of the gains step). Errors go
through the one line on stderr, exit code 2, as the CLI's.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import re
import sys
from collections.abc import Iterator, Sequence
from typing import Any

import numpy as np

from motorlab.proposal import propose, run_group, task_of

#: Points sent per curve: a long log is thinned for the browser (a plot of 2,000 points per trace draws in a
#: few tens of milliseconds; 20,000 froze the page for seconds with two results shown).
MAX_POINTS = 2000


def _listed(values: Any) -> list[float | None]:
    """The values as a JSON list, null where not finite."""
    arr = np.asarray(values, dtype=float).ravel()
    out: list[float | None] = arr.tolist()
    for k in np.flatnonzero(~np.isfinite(arr)).tolist():
        out[k] = None
    return out


def _thin(values: np.ndarray) -> list[float | None]:
    """Every k-th value, at most :data:`MAX_POINTS` (signals shown as read: the raw view)."""
    arr = np.asarray(values, dtype=float)
    step = max(1, int(np.ceil(arr.size / MAX_POINTS)))
    return _listed(arr[::step])


def keep_extremes(y: Any, limit: int = MAX_POINTS) -> np.ndarray:
    """Indices of at most ``limit`` samples of ``y`` that keep its shape: the first, smallest, largest and last
    sample of each of ``limit // 4`` equal runs (in order), so a spike or a step is never thinned away.

    Samples that are not finite are left to the bucket they fall in (chosen as any other sample when none
    of the bucket is finite). Vectorised (one stable sort by bucket and value): a 20,000-row log's curves are
    thinned in milliseconds, not the half second a loop over the buckets took.
    """
    arr = np.asarray(y, dtype=float)
    n = arr.size
    if n <= limit:
        return np.arange(n)
    edges = np.unique(np.linspace(0, n, max(1, limit // 4) + 1).astype(int))
    starts, ends = edges[:-1], edges[1:] - 1
    bucket = np.repeat(np.arange(starts.size), np.diff(edges))
    finite = np.isfinite(arr)
    # the first of each bucket in (bucket, value) order is its smallest; in (bucket, −value) order its largest;
    # a stable sort keeps the first of equal values, as nanargmin and nanargmax do
    low = np.lexsort((np.where(finite, arr, np.inf), bucket))[starts]
    high = np.lexsort((np.where(finite, -arr, np.inf), bucket))[starts]
    some = np.add.reduceat(finite, starts) > 0  # a bucket with no finite sample keeps its ends only
    return np.unique(np.concatenate([starts, ends, low[some], high[some]]))


def gaps(x: Any) -> np.ndarray:
    """Positions ``k`` where the time ``x[k] → x[k+1]`` jumps by more than ten typical steps (between the tests
    of a SysId file, a span left out): a line drawn there would cross a stretch with no data."""
    arr = np.asarray(x, dtype=float)
    if arr.size < 3:
        return np.zeros(0, dtype=int)
    step = np.diff(arr)
    positive = step[np.isfinite(step) & (step > 0)]
    if not positive.size:
        return np.zeros(0, dtype=int)
    return np.flatnonzero(~(np.abs(step) <= 10 * float(np.median(positive))) & np.isfinite(step))


def _broken(values: list[float | None], cuts: np.ndarray) -> list[float | None]:
    """``values`` with a null after each position of ``cuts`` (Plotly breaks a line at a null)."""
    out = list(values)
    for k in sorted((int(c) for c in cuts), reverse=True):
        out.insert(k + 1, None)
    return out


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
    "datalogger": "FTC SDK Datalogger file",
}

#: Which task of the page a file of this format most likely belongs to.
_TASK_BY_FORMAT = {"roadrunner-ramp": "drive", "roadrunner-log": "drive", "session": "bench",
                   "sysid-json": "mechanism", "frc-char-json": "mechanism", "wpilog": "mechanism",
                   "datalogger": "mechanism"}

#: A stand-in counts per revolution that makes an angle in radians read as encoder ticks, so that a
#: log which needs the counts per revolution can be shown before the student has typed it.
_TICKS_AS_RADIANS = 2 * np.pi


def _read_for_detect(path: str, fmt: str, columns: Sequence[str]) -> tuple[Any, list[str]]:
    """The recording of ``path`` and the options it still needs (``["cpr"]`` for a log counting ticks)."""
    from motorlab.errors import OptionError
    from motorlab.io import read_any

    options: dict[str, Any] = {"columns": list(columns)} if columns and fmt in ("csv", "datalogger") else {}
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
        lacks=recording.metadata.get("lacks", {}),  # what the file does not log, in words (a Datalogger file)
        cpr=None if needs else recording.metadata.get("cpr"),
        own_units=own_units(recording.metadata),
        time=_thin(recording.time),
        signals=[{"name": n, "unit": units.get(n, ""), "y": _thin(recording.signals[n])} for n in names],
    )
    return entry


def own_units(metadata: dict[str, Any]) -> dict[str, Any] | None:
    """The units a file carries (SysId's ``units`` and ``unitsPerRotation``), or None.

    Such a file is fitted in them: no counts per revolution or wheel radius typed for another mechanism
    applies to it, and its gains default to them (``tune``: rotations for a shooter in rotations).
    """
    from motorlab.io.frc_json import GAIN_UNITS

    units = metadata.get("units")
    if metadata.get("format") not in ("sysid-json", "frc-char-json", "wpilog") or not isinstance(units, str):
        return None
    per = metadata.get("unitsPerRotation")
    return {"units": units, "per_rotation": float(per) if isinstance(per, int | float) else None,
            "assumed": bool(metadata.get("units_assumed")), "tune_units": GAIN_UNITS.get(units.lower(), "rad")}


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


def _kept_breaks(full_gaps: np.ndarray, keep: np.ndarray) -> np.ndarray:
    """Positions in ``keep`` after which a gap of the full series lies (both ends of each gap are kept)."""
    if not full_gaps.size:
        return np.zeros(0, dtype=int)
    return np.unique(np.searchsorted(keep, full_gaps, side="right") - 1)


def _thinned(x: Any, y: Any, limit: int = MAX_POINTS) -> tuple[np.ndarray, np.ndarray]:
    """The samples kept of a curve (its extremes, both ends of each gap of ``x``) and the breaks among them."""
    cut = gaps(x)
    if not cut.size:
        return keep_extremes(y, limit), cut
    keep = np.union1d(keep_extremes(y, max(4, limit - 2 * cut.size)), np.concatenate([cut, cut + 1]))
    return keep, _kept_breaks(cut, keep)


def _series(series: Any, keep: np.ndarray | None = None, *, clock: Any = None,
            limit: int = MAX_POINTS) -> dict[str, Any] | None:
    """A curve for the browser: the samples ``keep`` (else its own extremes, at most ``limit``); a line is
    broken (a null) wherever its time (``clock``, else its x) jumps: never drawn across the gaps between tests."""
    if series is None:
        return None
    x, y = np.asarray(series.x, dtype=float), np.asarray(series.y, dtype=float)
    breaks = np.zeros(0, dtype=int)
    if keep is None:
        keep, breaks = _thinned(np.asarray(clock, dtype=float) if clock is not None else x, y, limit)
    xs, ys = _listed(x[keep]), _listed(y[keep])
    if series.kind != "data":
        xs, ys = _broken(xs, breaks), _broken(ys, breaks)
    return {"x": xs, "y": ys, "label": series.label, "kind": series.kind}


#: Measured points drawn per panel (and as many residuals): each is an element of the page's drawing, so
#: fewer than a line's points, keeping each stretch's extremes (a figure then draws in tens of milliseconds).
MAX_MARKERS = 300


def panel_curves(result: Any) -> list[dict[str, Any]]:
    """The data-against-model panels of a fit for the browser: at most :data:`MAX_MARKERS` measured points
    (each stretch's extremes kept) with their residuals and their time in the log, a model line of at most
    :data:`MAX_POINTS` points broken where the time jumps (between the tests of a SysId file).
    """
    out = []
    for p in result.panels:
        data, model = p.data, p.model
        same_x = bool(data is not None and model is not None and np.array_equal(data.x, model.x))
        timed = p.time is not None and data is not None and len(p.time) == len(data.x)
        clock = np.asarray(p.time if timed else data.x, dtype=float) if data is not None else None
        keep = _thinned(clock, data.y, MAX_MARKERS)[0] if data is not None and clock is not None else None
        residual = None
        if same_x and keep is not None:
            dx = np.asarray(data.x, dtype=float)[keep]
            dy = np.asarray(data.y, dtype=float)[keep] - np.asarray(model.y, dtype=float)[keep]
            residual = {"x": _listed(dx), "y": _listed(dy)}
        out.append({
            "title": p.title,
            "x_label": p.x_label,
            "y_label": p.y_label,
            "data": _series(data, keep),
            "model": _series(model, clock=clock if same_x else None),
            "residual": residual,  # measured − model at the measured points drawn
            "extra": [_series(s) for s in p.extra],
            "same_x": same_x,
            # each point's time in the log (what a span left out is given in), at the points drawn
            "time": _listed(np.asarray(p.time, dtype=float)[keep]) if timed and keep is not None else None,
        })
    return out


def panels(argv: Sequence[str]) -> list[dict[str, Any]]:
    """The data-against-model panels of ``motorlab analyze EXPERIMENT ARG...`` (first file group)."""
    from motorlab.cli import build_parser
    from motorlab.cli.analyze import from_cli

    args = build_parser().parse_args(["analyze", *argv])
    return panel_curves(from_cli(args.experiment, list(args.files), args))


@contextlib.contextmanager
def _caught(module: Any, name: str) -> Iterator[tuple[list[Any], io.StringIO]]:
    """While inside: what ``module.name`` returns (the CLI computes it) collected, and what is printed kept.

    The CLI runs as the user would run it (its options, its JSON, its errors); the objects it computes on
    the way to its printing (a fit's result, a designed loop) give the page's plots.
    """
    caught: list[Any] = []
    real = getattr(module, name)

    def catch(*a: Any, **k: Any) -> Any:
        caught.append(real(*a, **k))
        return caught[-1]

    printed = io.StringIO()
    setattr(module, name, catch)
    try:
        with contextlib.redirect_stdout(printed):
            yield caught, printed
    finally:
        setattr(module, name, real)


def fit(argv: Sequence[str]) -> int:
    """``motorlab analyze EXPERIMENT ARG... --json`` and its panels in one run (one analysis, not two).

    The CLI's own ``main`` runs the analysis (its JSON, its one-line errors and exit codes, byte for byte);
    the result it computes is caught on its way to the printing and its panels added: prints
    ``{"result": <what analyze --json prints>, "panels": [...]}``.
    """
    import motorlab.cli.analyze as cli_analyze
    from motorlab.cli import main as cli_main

    with _caught(cli_analyze, "from_cli") as (caught, printed):
        code = cli_main(["analyze", *argv, "--json"])
    if code != 0:
        return code
    print(json.dumps({"result": json.loads(printed.getvalue()), "panels": panel_curves(caught[0])}, allow_nan=False))
    return 0


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
    import motorlab.cli.tune as cli_tune
    from motorlab.cli import build_parser

    args = build_parser().parse_args(["tune", *argv])
    args.json, args.plot = True, None
    with _caught(cli_tune, "tune") as (caught, printed):
        cli_tune.run(args)
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
    if args and args[0] == "fit":
        return fit(args[1:])
    if not args or args[0] not in commands:
        print("motorlab: error: worker: use 'detect FILE...', 'fit EXPERIMENT ARG...', 'panels EXPERIMENT ARG...' "
              "or 'response ARG...'", file=sys.stderr)
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
