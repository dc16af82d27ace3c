"""Options and readers several experiments share (encoder, inertia, current unit, CSV column mapping)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from motorlab.errors import OptionError
from motorlab.experiments import Option
from motorlab.model.load import MATERIALS, disc_inertia

CPR = Option(
    "cpr", "count", positive=True, label="Encoder counts per revolution",
    help="of the shaft the encoder turns with, e.g. 560 for a NeveRest 20",
)
CURRENT_UNIT = Option(
    "current-unit", kind="choice", choices=("A", "mA"), label="Unit of the current column",
    help="of an FTC log; left empty: from its header, else amperes",
)
COLUMN = Option(
    "column", kind="columns", dest="columns", metavar='"HEADER=QUANTITY"', label="Column mapping",
    help='read a CSV column whose header motorlab does not know as a quantity, e.g. "Amps=current", '
         '"I (mA)=current", "Load=torque [oz*in]" or "Notes=skip"; one rule per column (headers in words '
         'with a unit in brackets, such as "Current (A)", need none)',
)
EXCLUDE = Option(
    "exclude", kind="spans", metavar="START:END", label="Time spans to leave out",
    help="stretches of the log not to fit, start:end in seconds of the log's own time, e.g. 12.5:14.0 where the "
         "wheels slipped; several separated by commas",
)


def spans(values: Mapping[str, Any]) -> list[tuple[float, float]]:
    """The time spans to leave out (``exclude``), as ``(start, end)`` [s] whatever form they came in."""
    from motorlab.timespans import parse_spans

    given = values.get("exclude")
    if given and not isinstance(given, str) and all(isinstance(g, str) for g in given):
        given = ",".join(given)  # the CLI's repeated --exclude, each checked already
    return parse_spans(given)


def without_spans(recordings: list[Any], values: Mapping[str, Any], *, split: bool) -> tuple[list[Any], Any]:
    """The recordings without the time spans to leave out, and what was left out (None: nothing asked)."""
    asked = spans(values)
    if not asked:
        return recordings, None
    from motorlab.timespans import leave_out

    return leave_out(recordings, asked, split=split)


def noted(result: Any, left: Any) -> Any:
    """``result``, saying what was left out (when anything was)."""
    return result if left is None else left.note(result)


_INERTIA_GROUP = "inertia at the encoder shaft (its value, or the flywheel disc)"
INERTIA = (
    Option("inertia", "kg*m^2", positive=True, group=_INERTIA_GROUP, label="Flywheel moment of inertia",
           help='everything that turns, seen at the encoder shaft, e.g. "0.0124 kg*m^2"; or give the disc below'),
    Option("inertia-stderr", "kg*m^2", nonnegative=True, group=_INERTIA_GROUP,
           label="Uncertainty of the moment of inertia", help="its standard error; left empty: exact"),
    Option("disc-radius", "m", positive=True, group=_INERTIA_GROUP, label="Flywheel disc radius",
           help='instead of the inertia: the disc\'s radius, e.g. "75 mm"'),
    Option("disc-thickness", "m", positive=True, group=_INERTIA_GROUP, label="Flywheel disc thickness",
           help='instead of the inertia: the disc\'s thickness, e.g. "50 mm"'),
    Option("material", kind="choice", choices=tuple(sorted(MATERIALS)), default="steel", group=_INERTIA_GROUP,
           label="Flywheel material", help="what the disc is made of (steel: 7850 kg/m³)"),
    Option("ratio", "", positive=True, default=1.0, group=_INERTIA_GROUP, label="Flywheel to encoder speed ratio",
           help="flywheel speed ÷ encoder-shaft speed, e.g. 25 behind a 25:1 step-up gearbox"),
)


#: Speed ratios a rig's gear train can have (a 3,700:1 FTC planetary stack, with margin both ways).
RATIO_RANGE = (1e-4, 1e4)


def inertia_of(values: Mapping[str, Any]) -> tuple[float | None, float | None]:
    """The inertia [kg·m²] and its standard error from ``inertia`` or the disc options (or None)."""
    disc = values.get("disc_radius") is not None or values.get("disc_thickness") is not None
    if values.get("inertia") is not None and disc:
        raise OptionError("give either --inertia or the flywheel disc (--disc-radius, --disc-thickness), not both")
    if values.get("ratio") is not None:
        from motorlab.analyses.common import check_range

        check_range(values["ratio"], "the flywheel to encoder speed ratio (--ratio)", *RATIO_RANGE, "",
                    why="a gear train steps speed up or down by at most a few thousand")
    if disc:
        if values.get("disc_radius") is None or values.get("disc_thickness") is None:
            raise OptionError("a flywheel disc needs both --disc-radius and --disc-thickness")
        inertia = disc_inertia(values["disc_radius"], values["disc_thickness"],
                               density=MATERIALS[values.get("material") or "steel"], ratio=values.get("ratio") or 1.0)
        return inertia, values.get("inertia_stderr")
    return values.get("inertia"), values.get("inertia_stderr")


def read_tables(paths: list[str]) -> list[Any]:
    """Headed CSV files, one recording each (:func:`motorlab.analyses.common.read_tables`)."""
    from motorlab.analyses.common import read_tables as read

    return read(paths)
