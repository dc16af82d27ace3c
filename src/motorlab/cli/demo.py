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
    parser.add_argument(
        "--worn-efficiency",
        type=quantity("", positive=True),
        default=0.8,
        metavar="FACTOR",
        help="factor applied to the worn unit's gearbox efficiency (default 0.8)",
    )
    from motorlab.cli.characterize import add_processes_option

    add_processes_option(parser)
    parser.set_defaults(func=run)


def experiment_rows(result: Any) -> list[tuple[str, str, str, list[str]]]:
    """Every analysis's own estimates against the rig's expectation for that run, unit by unit.

    Returns rows ``(experiment, parameter, unit, cells)`` with one cell per unit:
    ``"value ± stderr (+z σ)"`` where z = (estimate − truth)/stderr, or the estimate alone when the
    rig recorded no expected value for it.
    """
    import json
    import math

    from motorlab.units import format_unit, format_value

    expected: dict[str, dict[str, dict[str, float]]] = {}  # unit -> experiment -> parameter -> truth
    for unit in result.units.values():
        runs = {}
        if unit.spec.truth is not None and Path(unit.spec.truth).exists():
            runs = json.loads(Path(unit.spec.truth).read_text(encoding="utf-8")).get("runs", {})
        expected[unit.name] = {
            name: runs.get(spec.files[0].name, {}).get("expected", {}) for name, spec in unit.spec.experiments.items()
        }
    order: list[tuple[str, str, str]] = []
    for unit in result.units.values():
        for exp, fit in unit.fits.items():
            for par, est in fit.parameters.items():
                key = (exp, par, est.unit)
                if key not in order and not est.note.startswith("given"):
                    order.append(key)
    rows = []
    for exp, par, unit_str in order:
        cells = []
        for unit in result.units.values():
            fit = unit.fits.get(exp)
            est = fit.parameters.get(par) if fit is not None else None
            if est is None or not est.determined:
                cells.append("—" if est is None else "not determined")
                continue
            cell = format_value(est.value, est.stderr) if math.isfinite(est.stderr) else f"{est.value:.5g} ± ?"
            truth = expected.get(unit.name, {}).get(exp, {}).get(par)
            if isinstance(truth, int | float) and math.isfinite(est.stderr) and est.stderr > 0:
                cell += f" ({(est.value - truth) / est.stderr:+.1f}σ)"
            cells.append(cell)
        rows.append((exp, par, format_unit(unit_str), cells))
    return rows


def print_experiment_table(result: Any) -> None:
    """Print :func:`experiment_rows` as a table (each experiment's own estimates against the truth)."""
    from rich.console import Console
    from rich.table import Table

    from motorlab.session.characterize import SHAFTS

    table = Table(title="Every analysis against the simulated truth (estimate ± stderr, distance in σ); under each "
                  "experiment, the shaft and load its figures refer to")
    table.add_column("experiment")
    table.add_column("parameter")
    table.add_column("unit")
    for unit in result.units.values():
        table.add_column(unit.spec.display_name, justify="right")
    previous = ""
    for exp, par, unit_str, cells in experiment_rows(result):
        label = f"{exp}\n[dim]{SHAFTS[exp]}[/]" if exp in SHAFTS else exp
        table.add_row("" if exp == previous else label, par, unit_str, *cells)
        previous = exp
    Console(width=160).print(table)


def print_gearbox_table(result: Any) -> None:
    """η ± σ per unit against the truth, and the output stall torque at the nominal voltage against the catalogue."""
    from rich.console import Console
    from rich.table import Table

    from motorlab.catalog import Motor
    from motorlab.gearbox import OutputCurves
    from motorlab.report.document import unit_params
    from motorlab.units import format_value

    motor = Motor.from_catalog(result.session.motor.catalog) if result.session.motor.catalog else None
    voltage = motor.nominal_voltage if motor is not None else 12.0
    table = Table(title=f"The gearbox (output shaft) and the output stall torque at {voltage:g} V")
    for col in ("unit", "η (Kt/Ke)", "τ0 [N·m]", f"stall torque at {voltage:g} V [N·m]"):
        table.add_column(col, justify="right")
    for unit in result.units.values():
        eta, loss = unit.parameters.get("efficiency"), unit.parameters.get("loss_torque")
        cells = []
        for c, name in ((eta, "efficiency"), (loss, "loss_torque")):
            if c is None or not c.estimate.determined:
                cells.append("not determined")
                continue
            e = c.estimate
            text = format_value(e.value, e.stderr)
            t = unit.truth.get(name)
            if t is not None and e.stderr > 0:
                text += f" (truth {t:.4g}, {(e.value - t) / e.stderr:+.1f}σ)"
            cells.append(text)
        model = unit_params(unit)
        stall = "—"
        if model is not None and eta is not None and eta.estimate.determined:
            torque = OutputCurves(model, eta.estimate.value).stall_torque(voltage)
            stall = f"{torque:.3g}"
            if motor is not None:
                change = 100 * (torque / motor.stall_torque - 1)
                stall += f" ({change:+.0f} % of the catalogue's {motor.stall_torque:.3g})"
        table.add_row(unit.spec.display_name, *cells, stall)
    Console(width=160).print(table)


def run(args: argparse.Namespace) -> int:
    """Simulate, characterise, write, print."""
    from rich.console import Console

    from motorlab.cli.characterize import print_table, report_failures, run_with_progress
    from motorlab.report.document import gains_figure, write_outputs
    from motorlab.session.simulated import write_simulated_session
    from motorlab.session.spec import load_session

    check_option(args.units <= 26, f"--units must be at most 26, got {args.units}")
    check_output_dir(args.output)
    console = Console(stderr=True)
    out = Path(args.output)
    started = time.perf_counter()
    degrade = {args.worn: {"b": args.wear, "efficiency": args.worn_efficiency}} if args.worn else None
    with console.status(f"simulating {args.units} unit(s) of {args.motor} on the virtual dynamometer"):
        toml = write_simulated_session(
            args.motor, units=args.units, out_dir=out / "session", seed=args.seed, degrade=degrade, gearbox="catalog"
        )
    console.print(f"simulated session: {toml}")
    session = load_session(toml)
    result = run_with_progress(session, processes=args.processes)
    # No spinner here: its thread would keep the report's figures from being drawn in forked processes.
    paths = write_outputs(result, out, processes=args.processes)
    gains = result.gains or {}
    figure = gains_figure(result)
    if figure is not None:
        from motorlab.plot import save_figure

        save_figure(figure, out / "step_response.png")
        paths["step"] = out / "step_response.png"
    print_table(result)
    print_gearbox_table(result)
    print_experiment_table(result)
    if gains.get("text"):
        print(f"\nController gains for the median unit ({args.motor}, {gains.get('voltage', 12):g} V):")
        print(gains["text"])
    for key in ("html", "json", "csv", "step"):
        if key in paths:
            print(f"wrote {paths[key]}")
    console.print(f"[dim]demo took {time.perf_counter() - started:.1f} s[/]")
    return report_failures(result, paths)
