"""Option types shared by the library's option descriptions and the command line.

:func:`quantity` turns a number or a pint quantity string into a float in the given SI unit; it is
used as an ``argparse`` ``type`` by the CLI and by the notebook API (:mod:`motorlab.notebook`) to
convert keyword arguments, so both accept ``inertia=7.8e-3`` and ``inertia="7.8 g*m^2"``.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable

from motorlab.errors import OptionError
from motorlab.units import parse_quantity


def quantity(unit: str, *, positive: bool = False, nonnegative: bool = False) -> Callable[[str], float]:
    """A converter that parses numbers or pint quantities into ``unit`` (SI).

    ``--inertia "0.0124 kg*m^2"`` and ``--inertia 0.0124`` both give 0.0124. Bad text raises
    :class:`argparse.ArgumentTypeError` (which argparse reports as one line).
    """

    def convert(text: str) -> float:
        try:
            value = parse_quantity(text, unit, name="value")
        except OptionError as exc:
            raise argparse.ArgumentTypeError(exc.message.removeprefix("value: ")) from None
        if positive and value <= 0:
            raise argparse.ArgumentTypeError(f"{text!r} must be positive")
        if nonnegative and value < 0:
            raise argparse.ArgumentTypeError(f"{text!r} must not be negative")
        return value

    convert.__name__ = f"quantity in {unit}"
    convert.unit = unit  # type: ignore[attr-defined]  # read by the notebook API and the docs tables
    return convert
