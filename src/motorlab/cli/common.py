"""Pieces shared by the command-line modules: a one-line-error parser and option types."""

from __future__ import annotations

import argparse
import math
import os
import re
import sys
from collections.abc import Callable
from typing import Any, NoReturn

import numpy as np

from motorlab.errors import OptionError
from motorlab.units import parse_quantity

#: Exit codes of ``motorlab`` (see :func:`motorlab.cli.main`).
EXIT_INTERNAL = 1
EXIT_INPUT = 2
EXIT_PARTIAL = 3


_RST_LITERAL = re.compile(r"``(.+?)``", re.DOTALL)
_RST_ROLE = re.compile(r":[a-z]+:`~?([^`]+)`")


def plain_text(text: str) -> str:
    """``text`` without reStructuredText markup: ````V = kS````, ``:func:`x``` read as plain words."""
    return _RST_ROLE.sub(lambda m: m.group(1).rsplit(".", 1)[-1], _RST_LITERAL.sub(r"\1", text))


class Parser(argparse.ArgumentParser):
    """An ``ArgumentParser`` whose errors are one line on stderr and exit code 2.

    Help texts come from docstrings; :meth:`format_help` shows them without reStructuredText markup.
    """

    def format_help(self) -> str:
        return plain_text(super().format_help())

    def _get_values(self, action: argparse.Action, arg_strings: list[str]) -> Any:
        # ``--R=--``: Python's argparse drops the "--" and hands the option an empty list, unconverted
        # (its type never runs), which then meets arithmetic as a list. "--" is no value: refused.
        if action.option_strings and "--" in arg_strings and action.nargs not in (argparse.PARSER, argparse.REMAINDER):
            self.error(f"argument {'/'.join(action.option_strings)}: expected a value, got '--'")
        return super()._get_values(action, arg_strings)

    def error(self, message: str) -> NoReturn:
        """``motorlab: error: SUB-COMMAND: message`` like every other refusal, and exit code 2."""
        command = self.prog.split(None, 1)[1] if " " in self.prog else ""
        if message.startswith("unrecognized arguments") and "--exclude" in message:
            message += f"; {_exclude_hint()}"
        print(f"motorlab: error: {command + ': ' if command else ''}{message}", file=sys.stderr)
        raise SystemExit(EXIT_INPUT)


def _exclude_hint() -> str:
    from motorlab.experiments import exclude_hint

    return exclude_hint()


def finite_number(text: str) -> float:
    """A plain finite number (``--kv 1.2``); argparse reports a bad one in one line."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"{text!r} is not a finite number")
    return value


def positive_number(text: str) -> float:
    """A plain positive finite number (``--cpr 537.7``)."""
    value = finite_number(text)
    if value <= 0:
        raise argparse.ArgumentTypeError(f"{text!r} must be positive")
    return value


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
    return convert


def column_rule(text: str) -> str:
    """An argparse ``type`` for ``--column "HEADER=quantity"`` (:mod:`motorlab.io.headers`): the rule as text."""
    from motorlab.io.headers import parse_column_mapping

    try:
        (rule,) = parse_column_mapping(text)
    except OptionError as exc:
        raise argparse.ArgumentTypeError(exc.message.removeprefix("--column ")) from None
    return rule.text()


def time_spans(text: str) -> str:
    """An argparse ``type`` for ``--exclude 12.5:14.0`` (several: ``12.5:14,20:21``; :mod:`motorlab.timespans`)."""
    from motorlab.timespans import parse_spans

    try:
        parse_spans(text)
    except OptionError as exc:
        raise argparse.ArgumentTypeError(exc.message.removeprefix("exclude: ")) from None
    return text


def _whole_number(text: str) -> int:
    """Digits with an optional sign, nothing else: Python's ``int`` would also take "1_0" as 10."""
    stripped = text.strip()
    if not stripped.lstrip("+-").isdigit() or not stripped.isascii():
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number")
    return int(stripped)


def nonnegative_int(text: str) -> int:
    """An argparse ``type`` for a whole number ≥ 0 (seeds)."""
    value = _whole_number(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"{text!r} must not be negative")
    return value


def positive_int(text: str) -> int:
    """An argparse ``type`` for a whole number > 0."""
    value = _whole_number(text)
    if value <= 0:
        raise argparse.ArgumentTypeError(f"{text!r} must be positive")
    return value


def check_figure_path(path: str, *, option: str = "--plot") -> None:
    """Refuse a figure file name before any work: an unknown extension or a folder that is not there.

    Raises
    ------
    OptionError
        Naming ``option`` and the path.
    """
    from motorlab.plot import FIGURE_FORMATS

    ext = os.path.splitext(path)[1].lower()
    if ext not in FIGURE_FORMATS:
        raise OptionError(f"{option} {path}: use a .png, .pdf or .svg file name")
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise OptionError(f"{option} {path}: the directory {folder} does not exist")
    from motorlab.io.output import check_writable_target

    try:
        check_writable_target(path)
    except OptionError as exc:
        raise OptionError(f"{option} {exc.message}") from None


def check_output_dir(path: str | os.PathLike[str], *, option: str = "-o") -> None:
    """Refuse an output folder that cannot be created, before any (long) work is done.

    The folder may exist or not; what must not happen is finding out after the analyses that a
    file stands where the folder (or one of its parents) should be.

    Raises
    ------
    OptionError
        Naming ``option``, the path and the file in the way.
    """
    if not os.fspath(path).strip():
        raise OptionError(f"{option}: the folder name is empty")
    target = os.path.abspath(os.fspath(path))
    probe = target
    while not os.path.exists(probe):
        parent = os.path.dirname(probe)
        if parent == probe:
            break
        probe = parent
    if not os.path.isdir(probe):
        raise OptionError(f"{option} {os.fspath(path)}: {probe} is a file, not a folder")
    if not os.access(probe, os.W_OK):
        raise OptionError(f"{option} {os.fspath(path)}: the folder {probe} is not writable")


#: Failures of the numerics on numbers that are readable but absurd (1e308, 1e-300, identical
#: timestamps, JSON nested a million deep): the input's fault, reported as such (exit 2).
NUMERICAL_ERRORS: tuple[type[BaseException], ...] = (
    np.linalg.LinAlgError,
    OverflowError,
    FloatingPointError,
    RecursionError,
    MemoryError,
)

_NON_FINITE = re.compile(r"\b(inf|infs|nan|nans|not finite|infinite)\b", re.IGNORECASE)
_OUTPUT_OPTIONS = {"output", "out", "out_dir", "plot", "o", "emit"}


def is_numerical_failure(exc: BaseException) -> bool:
    """True for an exception the numerics raise on absurd numbers (see :data:`NUMERICAL_ERRORS`).

    A ``ValueError`` counts when it complains of non-finite values (scipy's "array must not contain
    infs or NaNs" after an overflow); any other ``ValueError`` is a bug.
    """
    if isinstance(exc, NUMERICAL_ERRORS):
        return True
    return type(exc) is ValueError and bool(_NON_FINITE.search(str(exc)))


def input_paths(args: argparse.Namespace) -> list[str]:
    """The existing files among the parsed options (``files``, ``session``, ``--params`` …), outputs excluded."""
    found: list[str] = []
    for key, value in vars(args).items():
        if key in _OUTPUT_OPTIONS:
            continue
        values = value if isinstance(value, list | tuple) else [value]
        for item in values:
            if isinstance(item, str | os.PathLike) and os.path.isfile(item) and os.fspath(item) not in found:
                found.append(os.fspath(item))
    return found


def numerical_failure_message(exc: BaseException, args: argparse.Namespace) -> str:
    """One line for a numerical failure: the input files, the cause, and what to look at."""
    causes: dict[type[BaseException], str] = {
        np.linalg.LinAlgError: "a singular or ill-conditioned system",
        OverflowError: "an overflow",
        FloatingPointError: "a floating-point failure",
        RecursionError: "nesting too deep",
        MemoryError: "more memory than there is",
    }
    cause = next((text for kind, text in causes.items() if isinstance(exc, kind)), "values that are not finite")
    detail = " ".join(str(exc).split())[:120]
    files = input_paths(args)
    where = f"{', '.join(files)}: " if files else ""
    hint = (
        "values far outside any measurement (such as 1e308 or 1e-300), identical timestamps or options "
        "that contradict each other cannot be computed with"
    )
    return f"{where}the computation failed on these numbers ({cause}{': ' + detail if detail else ''}); {hint}"


def check_option(condition: bool, message: str) -> None:
    """Raise :class:`OptionError` with ``message`` unless ``condition`` holds."""
    if not condition:
        raise OptionError(message)


def print_json(obj: Any) -> None:
    """Print a JSON document (NaN written as null) to stdout."""
    import json

    print(json.dumps(obj, indent=2, allow_nan=False))
