"""Pieces shared by the command-line modules: a one-line-error parser and option types."""

from __future__ import annotations

import argparse
import os
import sys
from typing import Any, NoReturn

from motorlab.errors import OptionError
from motorlab.options import quantity  # noqa: F401  (the CLI's option type; defined in the library)

#: Exit codes of ``motorlab`` (see :func:`motorlab.cli.main`).
EXIT_INTERNAL = 1
EXIT_INPUT = 2
EXIT_PARTIAL = 3


class Parser(argparse.ArgumentParser):
    """An ``ArgumentParser`` whose errors are one line on stderr and exit code 2."""

    def error(self, message: str) -> NoReturn:
        print(f"{self.prog}: error: {message}", file=sys.stderr)
        raise SystemExit(EXIT_INPUT)


def nonnegative_int(text: str) -> int:
    """An argparse ``type`` for a whole number ≥ 0 (seeds)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"{text!r} must not be negative")
    return value


def positive_int(text: str) -> int:
    """An argparse ``type`` for a whole number > 0."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
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


def check_option(condition: bool, message: str) -> None:
    """Raise :class:`OptionError` with ``message`` unless ``condition`` holds."""
    if not condition:
        raise OptionError(message)


def print_json(obj: Any) -> None:
    """Print a JSON document (NaN written as null) to stdout."""
    import json

    print(json.dumps(obj, indent=2, allow_nan=False))
