"""Helpers shared by the text readers: opening a file safely, parsing numbers with line numbers.

Every problem becomes a :class:`~motorlab.errors.LogFormatError` naming the file and the 1-based line,
so that the command line prints one clear line instead of a traceback.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from functools import lru_cache

from motorlab.errors import LogFormatError, OptionError
from motorlab.units import registry

PathArg = str | os.PathLike[str]


@dataclass(frozen=True)
class TextFile:
    """The lines of a text file, with what the readers need to know about its ending.

    Attributes
    ----------
    path
        The path as given (a string).
    lines
        The lines without their line terminators (``\\n``, ``\\r\\n`` and ``\\r`` are all accepted).
    ends_with_newline
        False when the last line has no terminator: a log whose writer stopped mid-line.
    """

    path: str
    lines: list[str]
    ends_with_newline: bool

    def numbered(self) -> list[tuple[int, str]]:
        """``(line_number, stripped_text)`` of the lines that are not blank (1-based numbers)."""
        return [(n, text.strip()) for n, text in enumerate(self.lines, start=1) if text.strip()]

    def is_last(self, line: int) -> bool:
        """True when ``line`` is the last line of the file."""
        return line == len(self.lines)

    def may_be_truncated(self, line: int) -> bool:
        """True when ``line`` is the last line and has no terminator (the writer was cut off)."""
        return self.is_last(line) and not self.ends_with_newline


def read_bytes(path: PathArg) -> tuple[str, bytes]:
    """The raw content of ``path`` (never modified), or a :class:`LogFormatError` if it cannot be read."""
    name = os.fspath(path)
    if not isinstance(name, str):  # bytes paths: decode for messages
        name = os.fsdecode(name)
    if not name.strip():
        raise LogFormatError("the file name is empty")
    try:
        with open(name, "rb") as handle:
            return name, handle.read()
    except FileNotFoundError:
        raise LogFormatError("no such file", path=name) from None
    except IsADirectoryError:
        raise LogFormatError("is a directory, not a log file", path=name) from None
    except OSError as exc:
        raise LogFormatError(f"cannot read the file ({exc.strerror})", path=name) from None


def read_text(path: PathArg) -> TextFile:
    """Read a text log: UTF-8 (with or without BOM), any line endings.

    Raises
    ------
    LogFormatError
        If the file is missing, binary (NUL bytes or invalid UTF-8: "not a text file") or empty.
    """
    name, raw = read_bytes(path)
    if not raw.strip():
        raise LogFormatError("the file is empty", path=name)
    if b"\0" in raw:
        raise LogFormatError("not a text file (it contains binary data)", path=name)
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = raw[: exc.start].count(b"\n") + 1
        raise LogFormatError("not a text file (invalid UTF-8)", path=name, line=line) from None
    ends = text.endswith(("\n", "\r"))
    return TextFile(path=name, lines=text.splitlines(), ends_with_newline=ends)


def parse_number(token: str, *, path: str, line: int, column: str) -> float:
    """``token`` as a finite float, or a :class:`LogFormatError` naming the column and line."""
    try:
        value = float(token)
    except ValueError:
        shown = token if token else "an empty field"
        raise LogFormatError(f"{column}: {shown!r} is not a number", path=path, line=line) from None
    if not math.isfinite(value):
        raise LogFormatError(f"{column}: {token!r} is not a finite number", path=path, line=line)
    return value


def is_number(token: str) -> bool:
    """True when ``token`` reads as a float (NaN and inf included: they are numbers, only bad ones)."""
    try:
        float(token)
    except ValueError:
        return False
    return True


@lru_cache(maxsize=64)
def unit_factor(unit: str, si_unit: str) -> float:
    """The factor turning a value in ``unit`` into ``si_unit`` (pint), e.g. ``("rpm", "rad/s")``."""
    ureg = registry()
    return float(ureg.Quantity(1.0, unit).to(si_unit).magnitude)


def check_cpr(cpr: float | None) -> float | None:
    """Validate counts per revolution: a finite positive number or None.

    Raises
    ------
    OptionError
        If ``cpr`` is zero, negative or not finite.
    """
    if cpr is None:
        return None
    try:
        value = float(cpr)
    except (TypeError, ValueError):
        raise OptionError(f"cpr: {cpr!r} is not a number") from None
    if not math.isfinite(value) or value <= 0:
        raise OptionError(f"cpr: counts per revolution must be positive, got {cpr!r}")
    return value
