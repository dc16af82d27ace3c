"""Helpers shared by the text readers: opening a file safely, parsing numbers with line numbers.

Every problem becomes a :class:`~motorlab.errors.LogFormatError` naming the file and the 1-based line,
so that the command line prints one clear line instead of a traceback.
"""

from __future__ import annotations

import json
import math
import os
import re
import stat
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property, lru_cache
from typing import Any

import numpy as np

from motorlab import progress
from motorlab.errors import LogFormatError, OptionError
from motorlab.units import registry

PathArg = str | os.PathLike[str]


#: Largest input file read without being asked [bytes] (512 MiB: about 6 million rows of an FTC
#: log, far beyond any real run); ``MOTORLAB_MAX_INPUT_SIZE`` (bytes, or "2 GB") lifts it.
MAX_INPUT_SIZE = 512 * 2**20
MAX_SIZE_ENV = "MOTORLAB_MAX_INPUT_SIZE"


@dataclass(frozen=True)
class TextFile:
    """The content of a text log, with what the readers need to know about its ending.

    Attributes
    ----------
    path
        The path as given (a string).
    raw
        The bytes of the file, a UTF-8 byte order mark removed. Kept as bytes: the fast path of
        :func:`fast_table` parses them without ever making the text of a 2M-row log.
    encoding
        ``"utf-8"`` or ``"latin-1"`` (a file that is not UTF-8, e.g. a Windows editor's "µH").
    """

    path: str
    raw: bytes
    encoding: str = "utf-8"

    @cached_property
    def text(self) -> str:
        """The decoded text."""
        return self.raw.decode(self.encoding)

    @cached_property
    def lines(self) -> list[str]:
        """The lines without their terminators (``\\n``, ``\\r\\n`` and ``\\r`` are all accepted)."""
        return self.text.splitlines()

    @property
    def ends_with_newline(self) -> bool:
        """False when the last line has no terminator: a log whose writer stopped mid-line."""
        return self.raw.endswith((b"\n", b"\r"))

    def numbered(self) -> list[tuple[int, str]]:
        """``(line_number, stripped_text)`` of the lines that are not blank (1-based numbers)."""
        return [(n, text.strip()) for n, text in enumerate(self.lines, start=1) if text.strip()]

    def head(self, count: int) -> list[tuple[int, str]]:
        """The first ``count`` non-blank lines as :meth:`numbered` gives them, without decoding the whole file."""
        size = 1 << 16
        while True:
            complete = size >= len(self.raw)
            lines = self.raw[:size].decode(self.encoding, errors="replace").splitlines()
            if not complete:
                lines = lines[:-1]  # the last one may be cut by the prefix
            out = [(n, line.strip()) for n, line in enumerate(lines, start=1) if line.strip()][:count]
            if len(out) >= count or complete:
                return out
            size *= 4

    def is_last(self, line: int) -> bool:
        """True when ``line`` is the last line of the file."""
        return line == len(self.lines)

    def may_be_truncated(self, line: int) -> bool:
        """True when ``line`` is the last line and has no terminator (the writer was cut off)."""
        return self.is_last(line) and not self.ends_with_newline


def max_input_size() -> int:
    """The size limit of an input file [bytes]: :data:`MAX_INPUT_SIZE` or ``$MOTORLAB_MAX_INPUT_SIZE``."""
    text = os.environ.get(MAX_SIZE_ENV, "").strip()
    if not text:
        return MAX_INPUT_SIZE
    shown = text if len(text) <= 60 else text[:57] + "..."
    try:  # pint's parser is bounded (motorlab.units.check_expression): '9**9**9' is refused at once
        value = float(text if _PLAIN_NUMBER.match(text) else registry().Quantity(text).to("byte").magnitude)
    except Exception:  # pint raises several types for text that is no size
        raise OptionError(f"{MAX_SIZE_ENV}={shown!r}: expected a size in bytes, or e.g. '2 GB'") from None
    if not math.isfinite(value) or value <= 0:
        raise OptionError(f"{MAX_SIZE_ENV}={shown!r}: the size limit must be a positive finite number")
    return int(min(value, 2**62))


_PLAIN_NUMBER = re.compile(r"^[0-9]+(\.[0-9]*)?([eE][+-]?[0-9]+)?$")


def _megabytes(size: int) -> str:
    return f"{size / 2**20:.0f} MiB" if size >= 2**20 else f"{size} bytes"


def check_input_file(path: PathArg) -> tuple[str, int]:
    """The name and the number of bytes to read of an input file, refusing at once what cannot be a log.

    Only regular files are read: a directory, a FIFO (which would wait for a writer for ever), a
    device such as ``/dev/zero`` (which never ends) or a socket is refused before it is opened;
    so is a file larger than :func:`max_input_size`.

    Raises
    ------
    LogFormatError
        Naming the file and what it is.
    """
    name = os.fspath(path)
    if not isinstance(name, str):  # bytes paths: decode for messages
        name = os.fsdecode(name)
    if not name.strip():
        raise LogFormatError("the file name is empty")
    if "\0" in name:  # no file system holds such a name (os.stat raises ValueError, not OSError)
        raise LogFormatError("the file name contains a NUL byte", path=name.replace("\0", "?"))
    try:
        info = os.stat(name)
    except FileNotFoundError:
        raise LogFormatError("no such file", path=name) from None
    except OSError as exc:
        raise LogFormatError(f"cannot read the file ({exc.strerror})", path=name) from None
    mode = info.st_mode
    if stat.S_ISDIR(mode):
        raise LogFormatError("is a directory, not a log file", path=name)
    if not stat.S_ISREG(mode):
        kind = (
            "a FIFO (named pipe)" if stat.S_ISFIFO(mode)
            else "a device" if stat.S_ISCHR(mode) or stat.S_ISBLK(mode)
            else "a socket" if stat.S_ISSOCK(mode)
            else "not a regular file"
        )
        raise LogFormatError(f"is {kind}, not a log file: only regular files are read", path=name)
    limit = max_input_size()
    if info.st_size > limit:
        raise LogFormatError(
            f"is {_megabytes(info.st_size)}, above the {_megabytes(limit)} limit for an input file; "
            f"set {MAX_SIZE_ENV} (e.g. {MAX_SIZE_ENV}='2 GB') to read it anyway",
            path=name,
        )
    return name, min(limit, int(info.st_size))


def check_distinct(paths: Sequence[PathArg]) -> None:
    """Refuse a file given twice (also under two names): one run's data would be counted twice.

    Raises
    ------
    LogFormatError
        Naming the file given again.
    """
    seen: dict[tuple[int, int] | str, str] = {}
    for path in paths:
        name = os.fsdecode(os.fspath(path))
        try:
            info = os.stat(name)
            key: tuple[int, int] | str = (info.st_dev, info.st_ino)
        except (OSError, ValueError):  # ValueError: a NUL in the name
            key = os.path.abspath(name)  # missing or no name at all: the reader names it
        if key in seen:
            same = "" if seen[key] == name else f" (the same file as {seen[key]})"
            raise LogFormatError(f"given twice{same}: each file of a run is read once", path=name)
        seen[key] = name


def read_bytes(path: PathArg) -> tuple[str, bytes]:
    """The raw content of ``path`` (never modified), or a :class:`LogFormatError` if it cannot be read.

    Every reader comes through here: :func:`check_input_file` refuses special files and files above
    the size limit before anything is read, and at most the limit is ever read.
    """
    name, size = check_input_file(path)
    limit = max_input_size()
    try:
        with open(name, "rb") as handle:
            # Read what stat promised plus one byte: a buffer of the limit's size is never allocated,
            # and a file that grew meanwhile is noticed (then read on up to the limit, no further).
            raw = handle.read(size + 1)
            if len(raw) > size:
                raw += handle.read(limit + 1 - len(raw))
    except IsADirectoryError:
        raise LogFormatError("is a directory, not a log file", path=name) from None
    except OSError as exc:
        raise LogFormatError(f"cannot read the file ({exc.strerror})", path=name) from None
    if len(raw) > limit:  # grew while being read
        raise LogFormatError(f"is larger than the {_megabytes(limit)} limit; set {MAX_SIZE_ENV} to lift it", path=name)
    return name, raw


def decode_text(raw: bytes) -> tuple[str, str]:
    """``(text, encoding)``: UTF-8 (a BOM is dropped), else Latin-1, which every byte sequence is."""
    try:
        return raw.decode("utf-8-sig"), "utf-8"
    except UnicodeDecodeError:
        return raw.decode("latin-1"), "latin-1"


_CONTROL = re.compile(rb"[\x00-\x08\x0e-\x1f\x7f]")


def is_binary(raw: bytes) -> bool:
    """True for bytes no text log holds: a NUL, or control characters in a file that is not UTF-8."""
    if b"\0" in raw:
        return True
    if raw.isascii():
        return False  # ASCII is UTF-8: only a NUL makes it binary
    try:
        raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        return _CONTROL.search(raw) is not None
    return False


#: Most digits an integer of a data file (JSON, TOML) may have: 400 is already beyond any float
#: (1.8e308); Python refuses to convert more than 4,300 at all (a ``ValueError`` from deep inside).
MAX_INTEGER_DIGITS = 400

#: Nesting of brackets from which a data file is "nested too deeply" (no motorlab file nests 10 deep).
MAX_NESTING = 100


class LongIntegerError(ValueError):
    """An integer literal of more than :data:`MAX_INTEGER_DIGITS` digits (``token`` holds it)."""

    def __init__(self, token: str):
        super().__init__(f"an integer of {len(token)} digits")
        self.token = token


def bounded_int(token: str) -> int:
    """``int(token)`` for a JSON/TOML integer literal, refusing one longer than :data:`MAX_INTEGER_DIGITS`."""
    if len(token) > MAX_INTEGER_DIGITS + 1:
        raise LongIntegerError(token)
    return int(token)


def line_of_offset(text: str, offset: int) -> int:
    """The 1-based line of character ``offset`` of ``text``."""
    return text.count("\n", 0, max(offset, 0)) + 1


def long_integer_line(text: str, token: str | None = None) -> int | None:
    """The line of the first run of more than :data:`MAX_INTEGER_DIGITS` digits (or of ``token``)."""
    if token is not None and (at := text.find(token)) >= 0:
        return line_of_offset(text, at)
    match = re.search(rf"\d{{{MAX_INTEGER_DIGITS + 1},}}", text)
    return line_of_offset(text, match.start()) if match else None


def deep_nesting_line(text: str, limit: int = MAX_NESTING) -> int | None:
    """The line where brackets (``[``, ``{``) first nest more than ``limit`` deep, else where they nest deepest.

    Brackets inside strings are counted too: this only points at the line of a file already refused.
    """
    codes = np.frombuffer(text.encode("utf-8", "replace"), dtype=np.uint8)
    if not codes.size:
        return None
    step = np.zeros(256, dtype=np.int64)
    step[[ord("["), ord("{")]] = 1
    step[[ord("]"), ord("}")]] = -1
    depth = np.cumsum(step[codes])
    at = int(np.argmax(depth > min(limit, int(depth.max()) - 1)))
    return int(np.count_nonzero(codes[:at] == 10)) + 1


def load_json(text: str, name: str) -> Any:
    """``json.loads(text)``, with every failure a one-line :class:`LogFormatError` naming the line.

    A syntax error, nesting too deep (Python's recursion limit) and an integer literal of more than
    :data:`MAX_INTEGER_DIGITS` digits (which Python would refuse to convert beyond 4,300, or turn into
    an integer no float can hold) are refused with their line.
    """
    try:
        return json.loads(text, parse_int=bounded_int)
    except json.JSONDecodeError as exc:
        raise LogFormatError(f"not valid JSON ({exc.msg})", path=name, line=exc.lineno) from None
    except LongIntegerError as exc:
        raise LogFormatError(
            f"an integer of {len(exc.token)} digits ({exc.token[:12]}…): not a measurement",
            path=name, line=long_integer_line(text, exc.token),
        ) from None
    except RecursionError:
        raise LogFormatError(
            "not a data file: JSON nested too deeply", path=name, line=deep_nesting_line(text)
        ) from None


def read_text(path: PathArg) -> TextFile:
    """Read a text log: UTF-8 (with or without BOM) or Latin-1, any line endings.

    Raises
    ------
    LogFormatError
        If the file is missing, not a regular file, too large, binary (NUL bytes: "not a text
        file") or empty.
    """
    name, raw = read_bytes(path)
    if not raw or raw.isspace():  # (raw.strip() would copy a 2M-row log)
        raise LogFormatError("the file is empty", path=name)
    if is_binary(raw):
        raise LogFormatError("not a text file (it contains binary data)", path=name)
    return text_file(name, raw)


def text_file(name: str, raw: bytes) -> TextFile:
    """A :class:`TextFile` of ``raw``: UTF-8 (its BOM removed) when it is, else Latin-1."""
    raw = raw.removeprefix(b"\xef\xbb\xbf")
    if raw.isascii():
        return TextFile(path=name, raw=raw, encoding="utf-8")
    try:
        raw.decode("utf-8")
    except UnicodeDecodeError:
        return TextFile(path=name, raw=raw, encoding="latin-1")
    return TextFile(path=name, raw=raw, encoding="utf-8")


def parse_number(token: str, *, path: str, line: int, column: str) -> float:
    """``token`` as a finite float, or a :class:`LogFormatError` naming the column and line."""
    try:
        if "_" in token:  # Python reads "1_0" as 10; no instrument writes that
            raise ValueError(token)
        value = float(token)
    except ValueError:
        shown = token if token else "an empty field"
        raise LogFormatError(f"{column}: {shown!r} is not a number", path=path, line=line) from None
    if not math.isfinite(value):
        raise LogFormatError(f"{column}: {token!r} is not a finite number", path=path, line=line)
    return value


def is_number(token: str) -> bool:
    """True when ``token`` reads as a float (NaN and inf included: they are numbers, only bad ones)."""
    if "_" in token:  # float("1_0") == 10.0: a digit separator no instrument writes
        return False
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


#: Encoder counts per revolution a real encoder can have [count/rev]: at least one count (a
#: fractional cpr above one is real: 537.7 for a 19.2:1 gearmotor), at most 2³⁰ (the finest absolute
#: encoders give 2²⁴–2²⁹ counts before a gearbox multiplies them). Every reader and every analysis
#: refuses a cpr outside (``--cpr 1e-12`` would scale counts into absurd angles that still "fit").
CPR_RANGE = (1.0, 2.0**30)


def check_cpr(cpr: float | None) -> float | None:
    """Validate counts per revolution: a finite number within :data:`CPR_RANGE`, or None.

    Raises
    ------
    OptionError
        If ``cpr`` is not a number, not finite, or outside :data:`CPR_RANGE`.
    """
    if cpr is None:
        return None
    try:
        value = float(cpr)
    except (TypeError, ValueError, OverflowError):
        raise OptionError(f"cpr: {str(cpr)[:40]!r} is not a number (--cpr)") from None
    low, high = CPR_RANGE
    if not math.isfinite(value) or value <= 0:
        raise OptionError(f"cpr: counts per revolution (--cpr) must be positive, got {value!r}")
    if not low <= value <= high:
        raise OptionError(
            f"cpr: the encoder counts per revolution (--cpr) must lie between {low:g} and {high:.0f} [count/rev], "
            f"got {value!r} (an encoder gives at least one count per turn)"
        )
    return value


# ---- the fast path for large numeric tables --------------------------------------------------------

_NON_BLANK = re.compile(rb"\S")
_CHUNK = 1 << 21  # bytes scanned at a time: bounds the temporary arrays of a 2M-row log to a few MB
_NUMERIC = np.zeros(256, dtype=bool)
_NUMERIC[np.frombuffer(b"0123456789+-.eE \t\r\n", dtype=np.uint8)] = True
_SEPARATOR = np.zeros(256, dtype=bool)
_SEPARATOR[np.frombuffer(b" \t\r\n", dtype=np.uint8)] = True


@dataclass(frozen=True)
class Table:
    """Rows parsed by :func:`fast_table`: values, their 1-based file lines, a dropped truncated last line."""

    values: np.ndarray
    lines: np.ndarray
    truncated: tuple[int, str] | None = None


def _line_offset(raw: bytes, line: int) -> int:
    """Byte offset where 1-based ``line`` starts (lines ended by ``\\n``)."""
    offset = 0
    for _ in range(line - 1):
        offset = raw.index(b"\n", offset) + 1
    return offset


@dataclass(frozen=True)
class _Scan:
    """What :func:`_scan` found: line count, blank lines, the last line's fields and start."""

    n_lines: int
    blank: np.ndarray
    last_fields: int
    last_start: int


def _scan(raw: bytes, begin: int, ncol: int, delimiter: int | None) -> _Scan | None:
    """Check that every line of ``raw[begin:]`` holds ``ncol`` numeric fields (or none), chunk by chunk.

    Only the indices of blank lines are kept (a 2M-row log has none), not a count per line. The
    last line (after the last newline) is returned apart: it may be a truncated one. None when a
    byte is not part of a number or a line has another number of fields.
    """
    allowed = _NUMERIC.copy()
    separator = _SEPARATOR.copy()
    if delimiter is not None:
        allowed[delimiter] = separator[delimiter] = True
    blank: list[np.ndarray] = []
    carry_fields = carry_delims = 0
    n_lines = 0
    last_start = begin
    previous_is_separator = True
    for at in range(begin, len(raw), _CHUNK):
        chunk = np.frombuffer(raw, dtype=np.uint8, count=min(_CHUNK, len(raw) - at), offset=at)
        if not allowed[chunk].all():
            return None
        is_sep = separator[chunk]
        first = np.flatnonzero(~is_sep & np.concatenate([[previous_is_separator], is_sep[:-1]]))
        newline = np.flatnonzero(chunk == 10)
        bounds = np.concatenate([[0], newline + 1, [chunk.size]])
        fields = np.diff(np.searchsorted(first, bounds))
        fields[0] += carry_fields
        good = (fields[:-1] == ncol) | (fields[:-1] == 0)
        if delimiter is not None:
            delims = np.diff(np.searchsorted(np.flatnonzero(chunk == delimiter), bounds))
            delims[0] += carry_delims
            good &= (delims[:-1] == ncol - 1) | (fields[:-1] == 0)
            carry_delims = int(delims[-1])
        if not good.all():
            return None
        blank.append(np.flatnonzero(fields[:-1] == 0) + n_lines)
        n_lines += newline.size
        carry_fields = int(fields[-1])
        if newline.size:
            last_start = at + int(newline[-1]) + 1
        previous_is_separator = bool(is_sep[-1])
    if delimiter is not None and carry_fields == ncol and carry_delims != ncol - 1:
        return None
    return _Scan(n_lines, np.concatenate(blank) if blank else np.empty(0, dtype=int), carry_fields, last_start)


def fast_table(text: TextFile, first_line: int, ncol: int, delimiter: str | None) -> Table | None:
    """Parse the rows of a purely numeric table in C (numpy), or None when the slow path must do it.

    The slow, line-by-line readers name the line and the problem of any bad row; this function only
    takes the clean case: from ``first_line`` on, nothing but numbers, separators and line ends
    (no comment, no NaN, no hexadecimal, no ``1_0``), every non-blank line with ``ncol`` fields
    (``delimiter``-separated, or whitespace when None). A last line without a line end and with
    fewer fields (a writer cut off) is dropped and reported. Anything else returns None and the
    caller's own loop finds and names the problem. The file's bytes are parsed in place, chunk by
    chunk: no text, no list of lines, no Python float per value.
    """
    raw = text.raw
    try:
        begin = _line_offset(raw, first_line)
    except ValueError:
        return None
    if _NON_BLANK.search(raw, begin) is None or raw.count(b"\r", begin) != raw.count(b"\r\n", begin):
        return None  # nothing, or a bare CR ending lines that \n-counting would not see
    code = None if delimiter is None else ord(delimiter)
    scan = _scan(raw, begin, ncol, code)
    if scan is None:
        return None
    truncated: tuple[int, str] | None = None
    end = len(raw)
    n_rows_lines = scan.n_lines  # complete lines (ended by a newline)
    if scan.last_fields == ncol:
        n_rows_lines += 1  # a complete last line without its newline
    elif scan.last_fields:
        if text.ends_with_newline or scan.last_fields > ncol:
            return None
        end = scan.last_start
        truncated = (first_line + scan.n_lines, raw[end:].decode("ascii").strip())
    nonblank = np.arange(n_rows_lines)
    if scan.blank.size:
        nonblank = np.delete(nonblank, scan.blank)
    if nonblank.size == 0:
        return None
    values = np.empty(nonblank.size * ncol)
    filled = 0
    with warnings.catch_warnings(), progress.task(f"Reading {os.path.basename(text.path)}", unit="MB",
                                                  total=round(len(raw) / 1e6, 1)) as step:
        warnings.simplefilter("error")  # a token C cannot read ("1e", "+-") stops the parse: slow path
        at = begin
        while at < end:
            step.update(round(at / 1e6, 1))
            stop = raw.rfind(b"\n", at, min(at + _CHUNK, end)) + 1 if at + _CHUNK < end else end
            if stop <= at:
                stop = end if raw.find(b"\n", at, end) < 0 else raw.find(b"\n", at, end) + 1
            piece = raw[at:stop] if code is None else raw[at:stop].replace(bytes([code]), b" ")
            at = stop
            if not piece.strip():  # numpy reads a blank piece as [-1.0]
                continue
            try:
                parsed = np.fromstring(piece, dtype=float, sep=" ")
            except (ValueError, DeprecationWarning):
                return None
            if filled + parsed.size > values.size:
                return None
            values[filled : filled + parsed.size] = parsed
            filled += parsed.size
        step.update(round(len(raw) / 1e6, 1))
    if filled != values.size or not np.all(np.isfinite(values)):
        return None
    return Table(values.reshape(nonblank.size, ncol), nonblank.astype(int) + first_line, truncated)
