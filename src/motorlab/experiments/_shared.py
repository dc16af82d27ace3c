"""Options and readers several experiments share (encoder, inertia, current unit, CSV column mapping)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from motorlab.errors import OptionError
from motorlab.experiments import Option
from motorlab.plan import MATERIALS, disc_inertia

CPR = Option(
    "cpr", "count", positive=True,
    help="encoder counts per revolution of the counted shaft (e.g. 560 for a NeveRest 20)",
)
CURRENT_UNIT = Option(
    "current-unit", kind="choice", choices=("A", "mA"),
    help="unit of the current column of an FTC log (default: from its header, else A)",
)
COLUMN = Option(
    "column", kind="columns", dest="columns", metavar='"HEADER=QUANTITY"',
    help='read a CSV column whose header motorlab does not know as a quantity, e.g. "Amps=current", '
         '"I (mA)=current", "Load=torque [oz*in]" or "Notes=skip" (repeatable; headers in words with a unit in '
         'brackets, such as "Current (A)", need none)',
)
_INERTIA_GROUP = "inertia at the encoder shaft (give --inertia or a disc)"
INERTIA = (
    Option("inertia", "kg*m^2", positive=True, group=_INERTIA_GROUP,
           help='total inertia at the encoder shaft, e.g. "0.0124 kg*m^2"'),
    Option("inertia-stderr", "kg*m^2", nonnegative=True, group=_INERTIA_GROUP,
           help="standard error of the inertia [kg·m²] (default: exact)"),
    Option("disc-radius", "m", positive=True, group=_INERTIA_GROUP, help='flywheel disc radius, e.g. "75 mm"'),
    Option("disc-thickness", "m", positive=True, group=_INERTIA_GROUP, help="flywheel disc thickness [m]"),
    Option("material", kind="choice", choices=tuple(sorted(MATERIALS)), default="steel", group=_INERTIA_GROUP,
           help="flywheel material (default steel, 7850 kg/m³)"),
    Option("ratio", "", positive=True, default=1.0, group=_INERTIA_GROUP,
           help="flywheel speed / encoder-shaft speed (25 for the seed's step-up gearbox)"),
)


def inertia_of(values: Mapping[str, Any]) -> tuple[float | None, float | None]:
    """The inertia [kg·m²] and its standard error from ``inertia`` or the disc options (or None)."""
    disc = values.get("disc_radius") is not None or values.get("disc_thickness") is not None
    if values.get("inertia") is not None and disc:
        raise OptionError("give either --inertia or the flywheel disc (--disc-radius, --disc-thickness), not both")
    if disc:
        if values.get("disc_radius") is None or values.get("disc_thickness") is None:
            raise OptionError("a flywheel disc needs both --disc-radius and --disc-thickness")
        inertia = disc_inertia(values["disc_radius"], values["disc_thickness"],
                               density=MATERIALS[values.get("material") or "steel"], ratio=values.get("ratio") or 1.0)
        return inertia, values.get("inertia_stderr")
    return values.get("inertia"), values.get("inertia_stderr")


def read_tables(paths: list[str]) -> list[Any]:
    """Headed CSV files, one recording each (:func:`motorlab.analyses._common.read_tables`)."""
    from motorlab.analyses._common import read_tables as read

    return read(paths)
