"""Units at the edges: parse quantities given by people, convert to SI.

Everything inside motorlab is SI (rad, s, A, V, Ω, H, kg·m², N·m). Text such as ``"0.0124 kg*m^2"``,
``"400 in*oz"`` or ``"130 rpm"`` is parsed with pint and converted here, and nowhere else.
"""

from __future__ import annotations

import math
import re
from functools import lru_cache
from typing import Any

import pint

from motorlab.errors import OptionError

_DIGIT_SEPARATOR = re.compile(r"\d_|_\d")

#: Standard gravity [m/s²], used where a mass stands for a force (scale readings, "in*oz").
STANDARD_GRAVITY = 9.80665


@lru_cache(maxsize=1)
def registry() -> pint.UnitRegistry:
    """The one pint registry motorlab uses (created on first use)."""
    ureg: pint.UnitRegistry = pint.UnitRegistry()
    ureg.define("count = [] = counts = ct")
    ureg.define("rotation = revolution")  # WPILib/SysId write "Rotations"
    return ureg


#: Canonical SI unit strings of the quantities motorlab stores, for display and JSON.
SI_UNITS: dict[str, str] = {
    "K": "V*s/rad",
    "R": "ohm",
    "R_dc": "ohm",
    "L": "H",
    "J": "kg*m^2",
    "b": "N*m*s/rad",
    "Tf": "N*m",
    "gamma": "1/s",
    "Tf_over_J": "rad/s^2",
    "Ka": "A/V",
    "Kt_tach": "V*s/rad",
    "kS": "V",
    "kV": "V*s/rad",
    "kA": "V*s^2/rad",
    "kG": "V",
}


def parse_quantity(value: Any, unit: str, *, name: str = "value") -> float:
    """Convert ``value`` to a float in ``unit`` (an SI unit string).

    Parameters
    ----------
    value
        A number (taken as already in ``unit``), a string holding a plain number (likewise), or a
        string with a unit that pint understands (``"400 in*oz"``, ``"130 rpm"``, ``"7.8 kg*m^2"``).
    unit
        The target unit, e.g. ``"N*m"``, ``"rad/s"``, ``"kg*m^2"``.
    name
        The option's name, used in error messages.

    Returns
    -------
    float
        The magnitude in ``unit``.

    Raises
    ------
    OptionError
        If the text is not a quantity, is not finite, or has a dimension that cannot be converted.

    Notes
    -----
    Torques written with a mass unit times a length (``in*oz``, ``kg*cm`` as printed on gearmotor
    data sheets) mean force units: they are multiplied by standard gravity g₀ = 9.80665 m/s², as
    seed 1 does by hand ("400 in·oz ... 0.454 kg·9.81 m/s²").
    """
    if isinstance(value, bool):
        raise OptionError(f"{name}: expected a quantity in {unit}, got {value!r}")
    if isinstance(value, int | float):
        number = float(value)
    else:
        text = str(value).strip()
        if _DIGIT_SEPARATOR.search(text):  # Python and pint read "1_0" as 10: refuse, do not guess
            raise OptionError(f"{name}: {value!r} is not a number (no '_' between digits)")
        try:
            number = float(text)
        except ValueError:
            number = _parse_with_pint(text, unit, name)
    if not math.isfinite(number):
        raise OptionError(f"{name}: {value!r} is not a finite number")
    return number


def _parse_with_pint(text: str, unit: str, name: str) -> float:
    ureg = registry()
    try:
        quantity: Any = ureg.Quantity(text)
    except Exception as exc:  # pint raises several unrelated types for bad text
        raise OptionError(f"{name}: cannot read {text!r} as a quantity in {unit} ({exc})") from None
    target = ureg.Quantity(1.0, unit)
    if not isinstance(quantity, pint.Quantity):
        return float(quantity)
    try:
        return float(quantity.to(unit).magnitude)
    except pint.DimensionalityError:
        pass
    # A mass standing for a weight: in*oz, kg*cm (torque) or g, kg (force).
    weighted = quantity * ureg.Quantity(STANDARD_GRAVITY, "m/s^2")
    if weighted.dimensionality == target.dimensionality:
        return float(weighted.to(unit).magnitude)
    raise OptionError(
        f"{name}: {text!r} has units of {quantity.units:~P}, which cannot be converted to {unit}"
    )


def format_percent(fraction: float, spec: str = ".2f") -> str:
    """``100·fraction`` as ``"12.34 %"``, or ``"? %"`` when it is not a finite number (never "nan %")."""
    value = 100.0 * float(fraction)
    return f"{value:{spec}} %" if math.isfinite(value) else "? %"


def format_unit(unit: str) -> str:
    """A unit string as printed for people: ``"N*m*s/rad"`` -> ``"N·m·s/rad"``."""
    return unit.replace("**", "^").replace("*", "·").replace("^2", "²").replace("ohm", "Ω")
