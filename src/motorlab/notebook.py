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

import os
from collections.abc import Sequence
from typing import Any

from motorlab.errors import OptionError
from motorlab.experiments import get
from motorlab.recording import Recording
from motorlab.results import FitResult

PathLike = str | os.PathLike[str]


def describe(experiment: str) -> list[dict[str, Any]]:
    """The options of ``experiment`` (:meth:`motorlab.experiments.Option.schema`): name, keyword, unit,
    default, choices, required, help."""
    return [opt.schema() for opt in get(experiment).options]


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
    exp = get(experiment)
    return exp.analyze(_paths(files), exp.values(opts))


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


def __getattr__(name: str) -> Any:
    """``spindown``, ``free_spinup`` ...: the function of every described experiment (one per module of
    :mod:`motorlab.experiments`, so a new experiment module gives a new function)."""
    from motorlab.experiments import all_experiments

    experiment = name.replace("_", "-")
    if experiment in all_experiments():
        return _make(experiment)
    raise AttributeError(f"module 'motorlab.notebook' has no attribute {name!r}")
