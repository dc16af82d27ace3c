"""``motorlab characterize SESSION.toml [-o DIR]``: run a whole session and write the results and the report.

Exit codes: 0 when every analysis ran; 3 when the results are written but some analyses failed (one
line on stderr; a failure never stops the other units and each unit's status says why); 2 when the
session is refused before any analysis runs.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import Any

from motorlab.cli.analyze import add_options
from motorlab.cli.common import EXIT_PARTIAL, check_output_dir
from motorlab.experiments._commands import command_options


def register(subparsers: Any) -> None:
    """Add the ``characterize`` sub-command."""
    parser = subparsers.add_parser(
        "characterize",
        help="run every analysis of a session (TOML) and write results.json, results.csv, report.html",
        description="Validate the session description, run every analysis it has files for on every unit, "
        "combine the sources (the most precise wins; disagreements are reported), test the fleet for "
        "outliers, and write results.json, results.csv (one row per unit) and a self-contained report.html.",
        epilog="Exit codes: 0 every analysis ran; 3 the results are written but some analyses failed (one line on "
        "stderr; each unit's status says why); 2 the session was refused before any analysis (one line naming "
        "the file, line and key); 1 an internal error.",
    )
    add_options(parser, command_options("characterize"))
    parser.add_argument(
        "-o", "--output", metavar="DIR", help="folder for the results (default: 'results' beside the session file)"
    )
    parser.add_argument("--no-report", action="store_true", help="write results.json and results.csv only")
    parser.add_argument("--quiet", action="store_true", help="no progress bar and no table")
    add_processes_option(parser)
    parser.set_defaults(func=run)


def add_processes_option(parser: argparse.ArgumentParser) -> None:
    """``--processes N``: how many processes analyse the units and draw the report."""
    from motorlab.cli.common import positive_int
    from motorlab.parallel import default_processes

    parser.add_argument(
        "--processes", type=positive_int, default=default_processes(), metavar="N",
        help="analyse the units, then draw the report's figures, in up to N processes at once "
        "(default: %(default)s; 1 runs everything in this process)",
    )


def run(args: argparse.Namespace) -> int:
    """Load, characterise, write, print the table."""
    from motorlab.io.csv_table import check_header
    from motorlab.io.output import check_not_inputs
    from motorlab.report.document import write_outputs
    from motorlab.session.characterize import output_paths, session_inputs
    from motorlab.session.spec import load_session

    session = load_session(args.session)  # every validation error happens here, before any analysis
    if args.output is not None:
        check_output_dir(args.output)  # "-o ''" is refused, not taken as the default folder
    out_dir = Path(args.output) if args.output is not None else session.folder / "results"
    check_output_dir(out_dir)
    check_not_inputs(output_paths(out_dir, report=not args.no_report), session_inputs(session))
    from motorlab.io.headers import column_mapping

    for unit in session.units.values():  # a column in an unknown unit is refused now, not after hours
        for spec in unit.experiments.values():
            with column_mapping(spec.settings.get("columns")):
                for path in spec.files:
                    if path.suffix.lower() == ".csv" and path.is_file() and _is_table(path):
                        check_header(path)
    result = run_with_progress(session, quiet=args.quiet, processes=args.processes)
    paths = write_outputs(result, out_dir, report=not args.no_report, processes=args.processes)
    if not args.quiet:
        print_table(result)
    for unit in result.units.values():  # a value in the table that breaks physics is never shown silently
        for warning in unit.warnings:
            print(f"motorlab: warning: unit {unit.spec.display_name}: {warning}", file=sys.stderr)
    for kind in ("json", "csv", "html"):
        if kind in paths:
            print(f"wrote {paths[kind]}")
    return report_failures(result, paths)


def _is_table(path: Path) -> bool:
    """True for a CSV table with a unit header (not a scope export); unreadable files are the analyses' to report."""
    from motorlab.errors import LogFormatError
    from motorlab.io import detect_format

    try:
        return detect_format(path) == "csv"
    except LogFormatError:
        return False


def report_failures(result: Any, paths: dict[str, Any]) -> int:
    """One line on stderr when some analyses failed; the exit code (0, or 3 = written with failures).

    A failed analysis does not stop the other units (each unit's row in results.csv says why), but
    a script running ``motorlab characterize`` must be able to tell that the table has holes.
    """
    failed = [(unit.name, experiment) for unit in result.units.values() for experiment in unit.failures]
    if not failed:
        return 0
    where = paths.get("csv") or paths.get("json") or "the results"
    shown = ", ".join(f"{unit}: {experiment}" for unit, experiment in failed[:4])
    if len(failed) > 4:
        shown += ", …"
    print(
        f"motorlab: {len(failed)} analys{'is' if len(failed) == 1 else 'es'} failed ({shown}); "
        f"the other results are written and each unit's status in {where} says why",
        file=sys.stderr,
    )
    return EXIT_PARTIAL


def run_with_progress(session: Any, *, quiet: bool = False, figures: bool = False, processes: int = 1) -> Any:
    """:func:`motorlab.session.characterize.characterize`; it reports its progress through :mod:`motorlab.progress`.

    The CLI's reporter shows a bar on a terminal (after 2 s), or JSON lines for the app
    (``MOTORLAB_PROGRESS=json``, which ``--quiet`` leaves on: the app runs the command quiet). No
    figure is drawn here (``figures``): the numbers are written first, the report draws its figures.
    """
    import os

    from motorlab import progress
    from motorlab.session.characterize import characterize

    if quiet and os.environ.get("MOTORLAB_PROGRESS") != "json":
        with progress.reporting(None):
            return characterize(session, figures=figures, processes=processes)
    return characterize(session, figures=figures, processes=processes)


def print_table(result: Any, *, truth: bool = True) -> None:
    """The estimates ± standard errors (against the truth for simulated sessions), printed with rich.

    One row per parameter and one column per unit, which fits a terminal; ``results.csv`` and the
    report keep seed 1's layout (one row per unit).
    """
    from rich.console import Console
    from rich.table import Table

    from motorlab.report.document import DISPLAY_UNITS
    from motorlab.session.characterize import table_parameters
    from motorlab.units import format_value

    console = Console()
    table = Table(title=result.session.title)
    table.add_column("")
    table.add_column("unit", style="dim")
    units = list(result.units.values())
    for unit in units:
        table.add_column(unit.spec.display_name, justify="right")
    flagged = {(o.unit, o.parameter) for o in result.fleet.outliers}
    for p in table_parameters(result):
        label, scale = DISPLAY_UNITS[p]
        cells = []
        for unit in units:
            combined = unit.parameters.get(p)
            if combined is None or not combined.estimate.determined:
                cells.append("—")
                continue
            est = combined.estimate
            text = format_value(est.value, est.stderr, scale=scale)
            t = unit.truth.get(p) if truth else None
            if t is not None:
                dev = (est.value - t) / est.stderr if math.isfinite(est.stderr) and est.stderr > 0 else math.nan
                text += f"\n[dim]truth {t * scale:.4g} ({dev:+.1f}σ)[/]"
            if (unit.name, p) in flagged:
                text = f"[bold red]{text}[/]"
            cells.append(text)
        table.add_row(p, label, *cells)
    table.add_row("status", "", *[u.status if u.status == "ok" else "[red]see below[/]" for u in units])
    console.print(table)
    console.print("[dim]estimate ± standard error; the source of each is in results.json and the report[/]")
    for unit in units:
        for experiment, why in unit.failures.items():
            console.print(f"[red]{unit.spec.display_name}: {experiment} failed: {why}[/]")
        for d in unit.disagreements:
            console.print(f"[yellow]{unit.spec.display_name}: sources disagree: {d.message()}[/]")
    if result.fleet.outliers:
        for o in result.fleet.outliers:
            console.print(f"[bold red]fleet: unit {o.unit} stands out: {o.message()}[/]")
    else:
        console.print(f"fleet: {result.fleet.verdict()}")
