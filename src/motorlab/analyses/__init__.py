"""One analysis per experiment of the seeds; every one returns a :class:`~motorlab.results.FitResult`.

``EXPERIMENTS`` maps the CLI name (``motorlab analyze NAME``) to the module that implements it.
Each module provides a library function (named after the experiment),
``add_arguments(parser, experiment)`` and ``from_cli(experiment, paths, args) -> FitResult``.
"""

from __future__ import annotations

import importlib
from types import ModuleType

EXPERIMENTS: dict[str, str] = {
    "spindown": "motorlab.analyses.spindown",
    "spinup": "motorlab.analyses.spinup",
    "free-spinup": "motorlab.analyses.free_spinup",
    "terminal": "motorlab.analyses.terminal",
    "lcr": "motorlab.analyses.lcr",
    "torque": "motorlab.analyses.torque",
    "amplifier": "motorlab.analyses.gains",
    "tachometer": "motorlab.analyses.gains",
    "pulse": "motorlab.analyses.pulse",
    "identify": "motorlab.identify",
    "feedforward": "motorlab.feedforward",
}


def load(name: str) -> ModuleType:
    """The module implementing experiment ``name``."""
    return importlib.import_module(EXPERIMENTS[name])
