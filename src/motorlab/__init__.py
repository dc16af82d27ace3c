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
import importlib.util
import types
from typing import Any

__version__ = "0.1.0"

def __getattr__(name: str) -> Any:
    """``analyze``, ``read``, ``describe`` and one function per experiment, from :mod:`motorlab.notebook`."""
    if name.startswith("__"):
        raise AttributeError(f"module 'motorlab' has no attribute {name!r}")
    if importlib.util.find_spec(f"{__name__}.{name}") is not None:
        # A submodule (``from motorlab import feedforward`` wants the module): identify and
        # feedforward are CallableModules, so ml.identify(...) still runs the experiment.
        return importlib.import_module(f"{__name__}.{name}")
    try:
        return getattr(importlib.import_module("motorlab.notebook"), name)
    except AttributeError:
        raise AttributeError(f"module 'motorlab' has no attribute {name!r}") from None


class CallableModule(types.ModuleType):
    """A submodule that is also its experiment's notebook function.

    ``motorlab.identify`` and ``motorlab.feedforward`` are modules; once imported, Python binds them
    as attributes of the package, where ``ml.identify(...)`` must still run the experiment.
    """

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        notebook = importlib.import_module("motorlab.notebook")
        return getattr(notebook, self.__name__.rsplit(".", 1)[-1])(*args, **kwargs)
