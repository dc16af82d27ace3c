"""The notebook API: one function per experiment, options named as the CLI's long options.

    import motorlab as ml
    fit = ml.spindown("log.txt", cpr=560, inertia=7.8e-3)   # or inertia="7.8 g*m^2"
    fit                # a short repr; in Jupyter a table of value ± stderr and unit
    fit.plot()         # data against the model (a matplotlib Figure, or into ax=)
    fit.to_dict()      # the JSON object of ``motorlab analyze --json``
    rec = ml.read("log.txt", cpr=560)

Every function takes the measurement file(s) first (one path, or several: a list or further
positional arguments) and the experiment's options as keywords. A keyword is the CLI's long
option without its dashes, ``-`` written ``_`` (``inertia_stderr`` for ``--inertia-stderr``,
``Ka`` for ``--Ka``); the name the analysis uses inside (``amplifier_gain``) is accepted too.
Numbers are SI; strings may carry units (parsed by pint), exactly as on the command line.
The result is the :class:`~motorlab.results.FitResult` the CLI prints, with the shaft its figures
refer to in ``details["shaft"]``.
"""

from __future__ import annotations

import argparse
import os
from collections.abc import Sequence
from typing import Any

from motorlab.errors import OptionError
from motorlab.recording import Recording
from motorlab.results import FitResult

PathLike = str | os.PathLike[str]


class _OptionParser(argparse.ArgumentParser):
    """Collects an experiment's option descriptions; never parses a command line."""

    def error(self, message: str) -> Any:  # pragma: no cover - never called: no parse_args here
        raise OptionError(message)


def describe(experiment: str) -> list[dict[str, Any]]:
    """The options of ``experiment``: name, other names, unit, default, choices, required, help.

    Names are those :func:`analyze` accepts (the first is the CLI's long option, ``_`` for ``-``).
    """
    return [_describe(action) for action in _actions(experiment)]


def _actions(experiment: str) -> list[argparse.Action]:
    from motorlab import analyses

    if experiment not in analyses.EXPERIMENTS:
        known = ", ".join(analyses.EXPERIMENTS)
        raise OptionError(f"unknown experiment {experiment!r}; known: {known}")
    parser = _OptionParser(prog=f"motorlab.{experiment}", add_help=False)
    analyses.load(experiment).add_arguments(parser, experiment)
    return [a for a in parser._actions if a.option_strings]


def _names(action: argparse.Action) -> list[str]:
    names = [s.lstrip("-").replace("-", "_") for s in action.option_strings if s.startswith("--")]
    if action.dest not in names:
        names.append(action.dest)
    return names


def _describe(action: argparse.Action) -> dict[str, Any]:
    names = _names(action)
    flag = action.nargs == 0
    return {
        "name": names[0],
        "aliases": names[1:],
        "dest": action.dest,
        "unit": getattr(action.type, "unit", None),
        "type": "flag" if flag else ("quantity" if hasattr(action.type, "unit") else
                                     getattr(action.type, "__name__", "str") if action.type else "str"),
        "default": action.default,
        "choices": list(action.choices) if action.choices is not None else None,
        "required": bool(action.required),
        "help": action.help or "",
    }


def _convert(action: argparse.Action, name: str, value: Any) -> Any:
    if action.nargs == 0:  # a flag (store_true / store_false)
        if not isinstance(value, bool):
            raise OptionError(f"{name}: expected True or False, got {value!r}")
        return value if action.const is True or action.const is None else not value
    if value is None:
        return None
    convert: Any = action.type
    if convert is not None:
        text = value if isinstance(value, str) else repr(value)
        try:
            value = convert(text)
        except (argparse.ArgumentTypeError, ValueError) as exc:
            raise OptionError(f"{name}: {exc}") from None
    if action.choices is not None and value not in action.choices:
        raise OptionError(f"{name}: {value!r} is not one of {', '.join(map(str, action.choices))}")
    return value


def _namespace(experiment: str, given: dict[str, Any]) -> argparse.Namespace:
    actions = _actions(experiment)
    by_name = {n: a for a in actions for n in _names(a)}
    unknown = [k for k in given if k not in by_name]
    if unknown:
        known = ", ".join(_names(a)[0] for a in actions)
        raise OptionError(f"{experiment}: unknown option(s) {', '.join(unknown)}; known: {known}")
    values = {a.dest: a.default for a in actions}
    seen: dict[str, str] = {}
    for key, value in given.items():
        action = by_name[key]
        if action.dest in seen:
            raise OptionError(f"{experiment}: {key} and {seen[action.dest]} are the same option")
        seen[action.dest] = key
        values[action.dest] = _convert(action, key, value)
    missing = [_names(a)[0] for a in actions if a.required and values[a.dest] is None]
    if missing:
        raise OptionError(f"{experiment}: give {', '.join(missing)}")
    return argparse.Namespace(**values)


def _paths(files: Sequence[Any]) -> list[str]:
    out: list[str] = []
    for item in files:
        if isinstance(item, str | os.PathLike):
            out.append(os.fspath(item))
        else:
            out.extend(os.fspath(p) for p in item)
    if not out:
        raise OptionError("give the measurement file(s) to analyse")
    return out


def analyze(experiment: str, *files: PathLike | Sequence[PathLike], **opts: Any) -> FitResult:
    """Run the analysis of ``experiment`` on ``files`` with the CLI's options as keywords.

    Raises
    ------
    OptionError
        An unknown option, a value that cannot be read, a required option missing.
    LogFormatError, FitError
        As the analysis.
    """
    from motorlab import analyses
    from motorlab.efficiency import SHAFTS

    args = _namespace(experiment, opts)
    args.experiment = experiment
    result: FitResult = analyses.load(experiment).from_cli(experiment, _paths(files), args)
    if experiment in SHAFTS:
        result.details.setdefault("shaft", SHAFTS[experiment])
    return result


def read(path: PathLike | Sequence[PathLike], *, cpr: float | str | None = None, **opts: Any) -> Recording:
    """Read a log of any supported format (:func:`motorlab.io.read_any`); ``cpr`` may carry a unit."""
    from motorlab.io import read_any
    from motorlab.units import parse_quantity

    counts = None if cpr is None else parse_quantity(cpr, "count", name="cpr")
    return read_any(path, cpr=counts, **opts)


def _make(experiment: str) -> Any:
    def run(*files: PathLike | Sequence[PathLike], **opts: Any) -> FitResult:
        return analyze(experiment, *files, **opts)

    name = experiment.replace("-", "_")
    run.__name__ = run.__qualname__ = name
    run.__doc__ = (
        f"``motorlab analyze {experiment}`` from Python: ``{name}(file, ..., option=value)`` -> FitResult.\n\n"
        f"Options as the CLI's long options (see ``motorlab.notebook.describe({experiment!r})``); numbers in SI "
        "or strings with units."
    )
    return run


spindown = _make("spindown")
spinup = _make("spinup")
free_spinup = _make("free-spinup")
terminal = _make("terminal")
lcr = _make("lcr")
torque = _make("torque")
amplifier = _make("amplifier")
tachometer = _make("tachometer")
pulse = _make("pulse")
identify = _make("identify")
feedforward = _make("feedforward")

#: The experiment functions by CLI name.
FUNCTIONS = {
    "spindown": spindown, "spinup": spinup, "free-spinup": free_spinup, "terminal": terminal, "lcr": lcr,
    "torque": torque, "amplifier": amplifier, "tachometer": tachometer, "pulse": pulse, "identify": identify,
    "feedforward": feedforward,
}
