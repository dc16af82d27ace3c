"""``motorlab analyze EXPERIMENT FILE... [options] [--json] [--plot FILE.png] [--each]``.

One sub-parser per experiment description (:mod:`motorlab.experiments`), its options generated from
the description's :class:`~motorlab.experiments.Option` list (:func:`add_arguments`); the run hands
the parsed values to the description (:func:`from_cli`). This module owns the shared options and
the output: a table for people, one JSON object (or a list with ``--each``) for programs, and a
figure with ``--plot``.
"""

from __future__ import annotations

import argparse
import math
import os
from collections.abc import Sequence
from typing import Any

from motorlab.cli.common import (
    Parser,
    check_figure_path,
    column_rule,
    finite_number,
    positive_int,
    positive_number,
    print_json,
    quantity,
    time_spans,
)
from motorlab.experiments import Option, all_experiments, get
from motorlab.results import Estimate, FitResult
from motorlab.units import format_unit

#: Correlations above this are listed in the human output.
MIN_CORRELATION = 0.5


def register(subparsers: Any) -> None:
    """Add ``analyze`` and one sub-command per experiment."""
    parser = subparsers.add_parser(
        "analyze",
        help="fit one experiment's measurements (spindown, lcr, torque, pulse ...)",
        description="Fit the measurements of one experiment and report the parameters with standard errors.",
    )
    sub = parser.add_subparsers(dest="experiment", metavar="EXPERIMENT", parser_class=Parser)
    sub.required = True
    for name, exp in all_experiments().items():
        sp = sub.add_parser(name, help=exp.summary, description=exp.summary)
        sp.add_argument("files", nargs="+", metavar="FILE", help="measurement file(s)")
        sp.add_argument("--json", action="store_true", help="print one JSON object (SI units) instead of a table")
        sp.add_argument("--plot", metavar="FILE.png", default=None, help="save data against the fitted model")
        sp.add_argument(
            "--each", action="store_true",
            help="analyse every file on its own (a list of JSON objects, or one table per file)",
        )
        add_arguments(sp, name)
        sp.set_defaults(func=run)


def add_arguments(parser: argparse.ArgumentParser, experiment: str) -> None:
    """The options of ``experiment``'s description as argparse options of ``parser``."""
    add_options(parser, get(experiment).options)


def flags(opt: Option) -> list[str]:
    """The CLI spellings of ``opt`` (``--Km``, ``--K``; a positional argument's name)."""
    if opt.positional:
        return [opt.key]
    return [f"--{name}" for name in (opt.name, *opt.aliases)]


def add_options(parser: argparse.ArgumentParser, options: Sequence[Option]) -> dict[str, Any]:
    """``options`` (a command's descriptions) as argparse arguments of ``parser``; returns the groups by title."""
    groups: dict[str, Any] = {}
    for opt in options:
        target: Any = parser
        if opt.group:
            target = groups.get(opt.group) or groups.setdefault(opt.group, parser.add_argument_group(opt.group))
        target.add_argument(*flags(opt), **_argparse_keywords(opt))
    return groups


def _argparse_keywords(opt: Option) -> dict[str, Any]:
    """``add_argument``'s keywords for ``opt`` (its help with the unit and default appended)."""
    out: dict[str, Any] = {"help": opt.cli_help, "default": opt.default}
    if not opt.positional:
        out["dest"] = opt.key
    if opt.kind == "flag":
        out["action"] = "store_false" if opt.default is True else "store_true"
        out["default"] = bool(opt.default)
        return out
    if opt.metavar:
        out["metavar"] = opt.metavar
    if opt.required and not opt.positional:
        out["required"] = True
    if opt.kind == "choice":
        out["choices"] = opt.choices
    elif opt.kind == "files":
        if not opt.positional:
            out["action"] = "append"
    elif opt.kind == "int":
        out["type"] = positive_int
    elif opt.kind == "number":
        out["type"] = positive_number if opt.positive else finite_number
    elif opt.kind == "text":
        pass
    elif opt.kind == "columns":
        out["action"] = "append"
        out["type"] = column_rule
    elif opt.kind == "spans":
        out["action"] = "append"
        out["type"] = time_spans
    else:
        assert opt.unit is not None
        out["type"] = quantity(opt.unit, positive=opt.positive, nonnegative=opt.nonnegative)
    return out


def from_cli(experiment: str, paths: list[str], args: argparse.Namespace) -> FitResult:
    """Run ``experiment`` on ``paths`` with the options parsed into ``args``."""
    exp = get(experiment)
    values = {opt.key: getattr(args, opt.key, opt.default) for opt in exp.options}
    return exp.analyze(paths, values)


def run(args: argparse.Namespace) -> int:
    """Run the analysis the parsed ``args`` ask for and print the result."""
    plot_path = args.plot
    if plot_path is not None:
        check_figure_path(plot_path)
        from motorlab.io.output import check_not_inputs

        check_not_inputs([plot_path], args.files, option="--plot")
    groups = [[path] for path in args.files] if args.each else [list(args.files)]
    results = [from_cli(args.experiment, paths, args) for paths in groups]
    if plot_path is not None:
        _save_plots(results, plot_path, each=args.each)
    if args.json:
        objects = [result.to_dict() for result in results]
        print_json(objects if args.each else objects[0])
    else:
        _print_tables(results)
    return 0


def plot_paths(path: str, results: Sequence[FitResult], *, each: bool) -> list[str]:
    """Figure file names: ``path`` itself, or ``stem-<file stem>.ext`` per result with ``--each``."""
    if not each or len(results) == 1:
        return [path]
    stem, ext = os.path.splitext(path)
    out = []
    for k, result in enumerate(results):
        source = result.sources[0] if result.sources else f"{k + 1}"
        name = f"{stem}-{os.path.splitext(os.path.basename(source))[0]}{ext}"
        out.append(name if name not in out else f"{stem}-{k + 1}{ext}")
    return out


def _save_plots(results: Sequence[FitResult], path: str, *, each: bool) -> None:
    # plot_fit draws on a bare Figure (no pyplot), which saves through the Agg canvas: no window opens.
    from motorlab.plot import plot_fit, save_figure

    for result, target in zip(results, plot_paths(path, results, each=each), strict=True):
        save_figure(plot_fit(result), target)


# ---- human output --------------------------------------------------------------------------------


def _fmt(value: float, digits: str = ".6g") -> str:
    return format(value, digits) if math.isfinite(value) else "?"


def parameter_rows(result: FitResult) -> list[tuple[str, str, str, str, str, str]]:
    """Rows (parameter, value, ± stderr, unit, relative error %, note) of the parameter table."""
    rows = []
    for est in result.parameters.values():
        rows.append(_row(est))
    return rows


def _row(est: Estimate) -> tuple[str, str, str, str, str, str]:
    unit = format_unit(est.unit)
    if not est.determined:
        return est.name, "not determined", "", unit, "", est.note
    rel = est.relative_error
    return (
        est.name,
        _fmt(est.value),
        f"± {_fmt(est.stderr, '.2g')}",
        unit,
        f"{100 * rel:.2f}" if math.isfinite(rel) else "?",
        est.note,
    )


def _print_tables(results: Sequence[FitResult]) -> None:
    from rich.console import Console
    from rich.table import Table

    console = Console(highlight=False)
    if not console.is_terminal:
        # Piped or redirected: rich would assume 80 columns and squeeze the tables; files are not that narrow.
        console = Console(highlight=False, width=max(console.width, 120))
    for k, result in enumerate(results):
        if k:
            console.print()
        title = result.experiment
        if result.sources:
            title += ": " + ", ".join(result.sources)
        table = Table(title=title, title_justify="left")
        table.add_column("parameter")
        table.add_column("value", justify="right")
        table.add_column("± stderr", justify="left")
        table.add_column("unit")
        table.add_column("rel. error %", justify="right")
        table.add_column("note", overflow="fold")
        for row in parameter_rows(result):
            table.add_row(*row)
        console.print(table)
        stats = [f"data points {result.n_points}"]
        if math.isfinite(result.rmse):
            stats.append(f"residual RMS {result.rmse:.4g} {format_unit(result.rmse_unit)}")
        if math.isfinite(result.r2):
            stats.append(f"R² {result.r2:.6f}")
        console.print("fit: " + ", ".join(stats))
        if "shaft" in result.details:
            console.print(f"shaft: {result.details['shaft']}")
        if result.details.get("R_temperature"):
            console.print(f"temperature of R: {result.details['R_temperature']}", markup=False)
        input_model = result.details.get("input_model")
        if isinstance(input_model, dict) and input_model.get("text"):  # identify: the voltage between samples
            console.print(f"input model: {input_model['text']}", markup=False)
        pairs = result.correlations(MIN_CORRELATION)
        if pairs:
            console.print(
                f"correlations above {MIN_CORRELATION}: " + ", ".join(f"C({a}, {b}) = {c:+.3f}" for a, b, c in pairs)
            )
        for name, value in result.details.items():
            if isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
                console.print(_details_table(name, value))
        if result.warnings:
            console.print("warnings:")
            for w in result.warnings:
                console.print(f"  - {w}", markup=False, soft_wrap=True)


def _details_table(name: str, rows: list[dict[str, Any]]) -> Any:
    from rich.table import Table

    columns: list[str] = []
    for row in rows:
        for key in row:
            if key not in columns:
                columns.append(key)
    table = Table(title=name.replace("_", " "), title_justify="left")
    for col in columns:
        table.add_column(col, justify="right")
    for row in rows:
        table.add_row(*(_cell(row.get(col)) for col in columns))
    return table


def _cell(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, bool):
        return "yes" if value else ""
    if isinstance(value, float):
        return _fmt(value, ".5g")
    return str(value)

