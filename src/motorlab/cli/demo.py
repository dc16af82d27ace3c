"""``motorlab demo``: simulate a session of three units, characterise it, write the report, print the table.

The project's main job end to end (``make demo`` runs ``motorlab demo -o out/demo``): the virtual
dynamometer runs every experiment of the seeds on three units of one catalogue motor, every
analysis runs, the sources are combined, the fleet is tested for worn units, controller gains are
designed, and ``out/demo/report.html`` is written. The table printed compares each estimate ± its
standard error with the simulated truth.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

from motorlab.cli.common import check_option, check_output_dir, nonnegative_int, positive_int, quantity


def register(subparsers: Any) -> None:
    """Add the ``demo`` sub-command."""
    parser = subparsers.add_parser(
        "demo",
        help="simulate and characterise three units of a motor; write out/demo/report.html",
        description="Simulate a full characterisation session (every experiment, several units of one "
        "catalogue motor) on the virtual dynamometer, characterise it, print the estimates against the "
        "truth and write report.html, results.json and results.csv.",
    )
    parser.add_argument("--motor", default="neverest40", help="catalogue key or name (default neverest40)")
    parser.add_argument("--units", type=positive_int, default=3, help="number of units (default 3)")
    parser.add_argument("--seed", type=nonnegative_int, default=0, help="fleet and noise seed (default 0)")
    parser.add_argument("-o", "--output", default="out/demo", metavar="DIR", help="output folder (out/demo)")
    parser.add_argument("--worn", metavar="UNIT", help="make one unit worn (its viscous friction multiplied)")
    parser.add_argument(
        "--wear",
        type=quantity("", positive=True),
        default=3.0,
        metavar="FACTOR",
        help="factor applied to the worn unit's b (default 3)",
    )
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Simulate, characterise, write, print."""
    from rich.console import Console

    from motorlab.characterize import write_outputs
    from motorlab.cli.characterize import print_table, report_failures, run_with_progress
    from motorlab.session import load_session, write_simulated_session

    check_option(args.units <= 26, f"--units must be at most 26, got {args.units}")
    check_output_dir(args.output)
    console = Console(stderr=True)
    out = Path(args.output)
    started = time.perf_counter()
    degrade = {args.worn: {"b": args.wear}} if args.worn else None
    with console.status(f"simulating {args.units} unit(s) of {args.motor} on the virtual dynamometer"):
        toml = write_simulated_session(
            args.motor, units=args.units, out_dir=out / "session", seed=args.seed, degrade=degrade
        )
    console.print(f"simulated session: {toml}")
    session = load_session(toml)
    result = run_with_progress(session)
    with console.status("writing the report"):
        paths = write_outputs(result, out)
        gains = result.gains or {}
        figure = gains.get("figure")
        if figure is not None:
            from motorlab.plot import save_figure

            save_figure(figure, out / "step_response.png")
            paths["step"] = out / "step_response.png"
    print_table(result)
    if gains.get("text"):
        print(f"\nController gains for the median unit ({args.motor}, {gains.get('voltage', 12):g} V):")
        print(gains["text"])
    for key in ("html", "json", "csv", "step"):
        if key in paths:
            print(f"wrote {paths[key]}")
    console.print(f"[dim]demo took {time.perf_counter() - started:.1f} s[/]")
    return report_failures(result, paths)
