"""Pieces shared by the command-line modules: a one-line-error parser and option types."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from typing import Any, NoReturn

from motorlab.errors import OptionError
from motorlab.units import parse_quantity

EXIT_INPUT = 2


class Parser(argparse.ArgumentParser):
    """An ``ArgumentParser`` whose errors are one line on stderr and exit code 2."""

    def error(self, message: str) -> NoReturn:
        print(f"{self.prog}: error: {message}", file=sys.stderr)
        raise SystemExit(EXIT_INPUT)


def quantity(unit: str, *, positive: bool = False, nonnegative: bool = False) -> Callable[[str], float]:
    """An argparse ``type`` that parses numbers or pint quantities into ``unit`` (SI).

    ``--inertia "0.0124 kg*m^2"`` and ``--inertia 0.0124`` both give 0.0124.
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
    return convert


def positive_int(text: str) -> int:
    """An argparse ``type`` for a whole number > 0."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
    if value <= 0:
        raise argparse.ArgumentTypeError(f"{text!r} must be positive")
    return value


def check_option(condition: bool, message: str) -> None:
    """Raise :class:`OptionError` with ``message`` unless ``condition`` holds."""
    if not condition:
        raise OptionError(message)


def print_json(obj: Any) -> None:
    """Print a JSON document (NaN written as null) to stdout."""
    import json

    print(json.dumps(obj, indent=2, allow_nan=False))
