"""motorlab: characterize brushed DC gearmotors from measurements.

The notebook API (:mod:`motorlab.notebook`, docs/notebook.md)::

    import motorlab as ml
    fit = ml.spindown("log.txt", cpr=560, inertia=7.8e-3)   # every experiment: ml.lcr, ml.pulse ...
    rec = ml.read("log.txt", cpr=560)

The library underneath, for scripts::

    from motorlab.model import MotorParams
    from motorlab.simulate import simulate, VoltageDrive
    from motorlab.catalog import Motor
    from motorlab import io, analyses

Everything inside is SI; see ``docs/glossary.md``.
"""

from __future__ import annotations

import importlib
import types
from typing import Any

__version__ = "0.1.0"

#: Names :mod:`motorlab.notebook` provides at the top level (imported on first use).
_NOTEBOOK = (
    "analyze", "read", "describe", "spindown", "spinup", "free_spinup", "terminal", "lcr", "torque", "amplifier",
    "tachometer", "pulse", "identify", "feedforward",
)


def __getattr__(name: str) -> Any:
    if name in _NOTEBOOK:
        return getattr(importlib.import_module("motorlab.notebook"), name)
    raise AttributeError(f"module 'motorlab' has no attribute {name!r}")


class CallableModule(types.ModuleType):
    """A submodule that is also its experiment's notebook function.

    ``motorlab.identify`` and ``motorlab.feedforward`` are modules; once imported, Python binds them
    as attributes of the package, where ``ml.identify(...)`` must still run the experiment.
    """

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        notebook = importlib.import_module("motorlab.notebook")
        return getattr(notebook, self.__name__.rsplit(".", 1)[-1])(*args, **kwargs)
