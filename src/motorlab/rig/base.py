"""What every dynamometer (virtual or real) gives back, and the ``truth.json`` written beside its files.

A rig runs one experiment of the seeds per method and writes exactly the files a real rig writes;
:class:`RigRun` lists them. The virtual rig also knows the truth: it records the unit's true
parameters, what each analysis should find, every instrument setting and the seeds in a
``truth.json`` file in the same folder. One ``truth.json`` holds every run written to its folder,
keyed by the name of the run's first file, so several units and experiments can share a folder.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol, runtime_checkable

from motorlab.errors import InputError, OptionError, RigError
from motorlab.io.output import check_writable_target
from motorlab.results import jsonable

#: Most simulator steps or logged samples one run may produce. Ten million steps take ~80 MB per
#: float array (the simulator keeps six) and minutes to compute; a real log is far shorter (seed 1's
#: FTC logs hold ~1000 rows, a scope trace 12 Mpts at most).
MAX_SAMPLES = 10_000_000
#: Most readings a person takes by hand in one run (LCR positions, table rows, scope cursor edges).
MAX_READINGS = 100_000

#: Identifies a truth file and its layout.
TRUTH_FORMAT = "motorlab-truth"
TRUTH_VERSION = 1
TRUTH_NAME = "truth.json"

PathArg = str | os.PathLike[str]


@dataclass(frozen=True)
class RigRun:
    """The outcome of one experiment on a rig.

    Attributes
    ----------
    experiment
        The experiment's name (``"spindown"``, ``"lcr"`` …).
    paths
        The data files written, in reading order (a split FTC log has two).
    truth_path
        The ``truth.json`` holding this run's truth (``None`` for a real rig).
    truth
        This run's entry of ``truth.json`` (empty for a real rig).
    """

    experiment: str
    paths: tuple[Path, ...]
    truth_path: Path | None = None
    truth: dict[str, Any] = field(default_factory=dict)


@runtime_checkable
class Dynamometer(Protocol):
    """What a rig offers: ``run(experiment, path, **settings)`` for each name in ``experiments``.

    The virtual rig (:class:`motorlab.rig.virtual.VirtualRig`) also has one method per experiment
    (``rig.spindown(path, voltage=12.0)``); a real rig driving hardware implements the same names
    (:class:`motorlab.acquire.bench.BenchRig`: a bench supply and a scope through PyVISA).
    """

    experiments: tuple[str, ...]

    def run(self, experiment: str, path: PathArg, **settings: Any) -> RigRun: ...


def check_size(count: float, what: str, *, limit: int = MAX_SAMPLES, hint: str = "") -> None:
    """Refuse, before anything is allocated, a run that would produce more than ``limit`` items.

    Parameters
    ----------
    count
        How many samples, steps or rows the settings ask for (a float: it may be astronomically
        large, or NaN from an impossible setting).
    what
        What is counted and which settings make it, e.g. ``"samples (--rate × --duration)"``.
    limit
        The largest count allowed (:data:`MAX_SAMPLES` or :data:`MAX_READINGS`).
    hint
        What to change, appended to the message.

    Raises
    ------
    OptionError
        When ``count`` exceeds ``limit`` or is not a number.
    """
    if not count <= limit:  # NaN fails as well
        text = f"{count:.3g}" if math.isfinite(count) else str(count)
        raise OptionError(
            f"these settings ask for {text} {what}, more than the {limit:,} a run may have"
            + (f": {hint}" if hint else "")
        )


def truth_path_for(data_path: PathArg) -> Path:
    """The ``truth.json`` beside ``data_path``."""
    return Path(data_path).with_name(TRUTH_NAME)


def write_truth(data_path: PathArg, entry: dict[str, Any]) -> Path:
    """Add (or replace) the run of ``data_path`` in the ``truth.json`` beside it.

    Parameters
    ----------
    data_path
        The run's first data file; its name is the key of the entry.
    entry
        The run's truth (converted to plain JSON).

    Returns
    -------
    Path
        The ``truth.json`` written.

    Raises
    ------
    RigError
        If a file named ``truth.json`` is there but is not a motorlab truth file (it is not overwritten).
    """
    path = truth_path_for(data_path)
    doc: dict[str, Any] = {"format": TRUTH_FORMAT, "version": TRUTH_VERSION, "runs": {}}
    if path.exists():
        try:
            old = json.loads(path.read_text(encoding="utf-8"))
        except (ValueError, UnicodeDecodeError):
            old = None
        if not isinstance(old, dict) or old.get("format") != TRUTH_FORMAT:
            raise RigError(f"{path} exists and is not a motorlab truth file; not overwriting it")
        doc["runs"] = dict(old.get("runs", {}))
    doc["runs"][Path(data_path).name] = jsonable(entry)
    check_writable_target(path)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(doc, indent=2, allow_nan=False) + "\n", encoding="utf-8")
    tmp.replace(path)
    return path


def read_truth(data_path: PathArg) -> dict[str, Any]:
    """The truth of the run whose first data file is ``data_path`` (from the ``truth.json`` beside it).

    Raises
    ------
    InputError
        If there is no ``truth.json`` or it has no entry for this file.
    """
    path = truth_path_for(data_path)
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise InputError("no truth.json beside this file", path=data_path) from None
    except (ValueError, UnicodeDecodeError):
        raise InputError("not a JSON file", path=path) from None
    runs = doc.get("runs", {}) if isinstance(doc, dict) else {}
    name = Path(data_path).name
    if name not in runs:
        raise InputError(f"no entry for {name!r}", path=path)
    entry: dict[str, Any] = runs[name]
    return entry
