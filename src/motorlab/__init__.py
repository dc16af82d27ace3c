"""motorlab: characterize brushed DC gearmotors from measurements.

The notebook API (:mod:`motorlab.notebook`, docs/notebook.md)::

    import motorlab as ml
    fit = ml.spindown("log.txt", cpr=560, inertia=7.8e-3)   # every experiment: ml.lcr, ml.pulse ...
    rec = ml.read("log.txt", cpr=560)

The library underneath, for scripts::

    from motorlab.model import MotorParams
    from motorlab.model.simulate import simulate, VoltageDrive
    from motorlab.catalog import Motor
    from motorlab import io, analyses

Everything inside is SI; see ``docs/glossary.md``.
"""

from __future__ import annotations

import importlib
import importlib.util
from typing import Any

__version__ = "0.1.0"

#: The few public types, by the module that defines them (``ml.FitResult`` …).
_TYPES = {
    "FitResult": "motorlab.results", "Estimate": "motorlab.results", "Recording": "motorlab.recording",
    "MotorParams": "motorlab.model", "Motor": "motorlab.catalog",
}
#: The notebook's functions besides one per experiment.
_FUNCTIONS = ("analyze", "read", "describe")


def _experiment_functions() -> list[str]:
    from motorlab.experiments import all_experiments

    return [name.replace("-", "_") for name in all_experiments()]


def _public() -> list[str]:
    return sorted([*_experiment_functions(), *_FUNCTIONS, *_TYPES])


def __getattr__(name: str) -> Any:
    """Every experiment's notebook function, ``analyze``, ``read``, ``describe``, the public types, and the
    subpackages (``motorlab.io`` …); nothing else (``motorlab.os`` is no attribute)."""
    if name == "__all__":
        return _public()
    if name.startswith("__"):
        raise AttributeError(f"module 'motorlab' has no attribute {name!r}")
    if name in _TYPES:
        return getattr(importlib.import_module(_TYPES[name]), name)
    if not name.startswith("_") and importlib.util.find_spec(f"{__name__}.{name}") is not None:
        # A subpackage or root module (``from motorlab import progress``); no experiment's name is one.
        return importlib.import_module(f"{__name__}.{name}")
    if name in _FUNCTIONS or name in _experiment_functions():
        return getattr(importlib.import_module("motorlab.notebook"), name)
    raise AttributeError(f"module 'motorlab' has no attribute {name!r}")


def __dir__() -> list[str]:
    """What a notebook user reaches for: the experiments, the notebook's functions and the public types."""
    return _public()
