"""Reading a capture straight from the file, a chunk of whole lines at a time.

A Rigol DS1054Z exports up to 24 million samples per channel (about 500 MB of CSV): holding the
file's bytes, its lines or a Python float per value would take gigabytes. :func:`line_chunks`
reads a file from a byte offset in chunks of :data:`CHUNK` bytes cut at line ends, with the
1-based line number of each chunk's first line, and reports the bytes read through
:mod:`motorlab.progress`; :class:`Column` gathers the parsed values of one column into a
preallocated array that grows only when the estimate was short.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from motorlab import progress
from motorlab.errors import LogFormatError
from motorlab.io.text import max_input_size

#: Bytes read at a time (whole lines; a chunk's parse makes arrays of a few times this size).
CHUNK = 1 << 23
#: A "line" longer than this is no line of a capture (a file without line ends): refused.
MAX_LINE = 1 << 24


@dataclass(frozen=True)
class Chunk:
    """Whole lines of a file: their bytes, the number of the first line, and whether the file ends here.

    ``data`` ends with a line end, except in the file's last chunk when its last line has none
    (then ``last`` is True and that line may be one the writer was cut off in).
    """

    data: bytes
    first_line: int
    last: bool
    #: Line ends in ``data`` (counted once: a 24 Mpt export is 500 MB of them).
    newlines: int = -1

    def lines(self) -> int:
        """Lines in ``data`` (the last one counts also without its line end)."""
        newlines = self.data.count(b"\n") if self.newlines < 0 else self.newlines
        return newlines + (0 if self.data.endswith(b"\n") else 1)


def line_chunks(name: str, offset: int, first_line: int, *, what: str) -> Iterator[Chunk]:
    """The lines of ``name`` from byte ``offset`` on, in chunks, with progress in MB read.

    Parameters
    ----------
    name
        A regular file, already checked (:func:`motorlab.io.text.check_input_file`).
    offset
        Byte offset of the first line to read; ``first_line`` is its 1-based number.
    what
        What is reported as under way ("Reading capture.csv").

    Raises
    ------
    LogFormatError
        The file cannot be read, grows beyond the size limit while read, or holds a line longer
        than :data:`MAX_LINE` bytes.
    """
    try:
        size = os.stat(name).st_size
        handle = open(name, "rb")  # noqa: SIM115 (closed below, after the last chunk)
    except OSError as exc:
        raise LogFormatError(f"cannot read the file ({exc.strerror})", path=name) from None
    limit = max_input_size()
    with handle, progress.task(what, total=round(size / 1e6, 1), unit="MB") as step:
        handle.seek(offset)
        carry = b""
        line = first_line
        done = offset
        while True:
            try:
                block = handle.read(CHUNK)
            except OSError as exc:
                raise LogFormatError(f"cannot read the file ({exc.strerror})", path=name) from None
            done += len(block)
            if done > limit:
                raise LogFormatError("grew beyond the size limit for an input file while being read", path=name)
            if not block:
                if carry:
                    yield Chunk(carry, line, True)
                step.update(round(done / 1e6, 1))
                return
            data = carry + block if carry else block
            cut = data.rfind(b"\n") + 1
            if cut == 0:
                if len(data) > MAX_LINE:
                    raise LogFormatError(f"a line longer than {MAX_LINE >> 20} MiB: not a capture", path=name,
                                         line=line)
                carry = data
                continue
            carry = data[cut:]
            piece = data[:cut] if cut < len(data) else data
            newlines = piece.count(b"\n")
            yield Chunk(piece, line, False, newlines)
            line += newlines
            step.update(round(done / 1e6, 1))


class Column:
    """Values of one column gathered chunk by chunk into one array (``dtype``), grown when needed."""

    def __init__(self, estimate: int, dtype: type = np.float64) -> None:
        self.values: np.ndarray = np.empty(max(int(estimate), 16), dtype=dtype)
        self.size = 0

    def extend(self, values: np.ndarray) -> None:
        """Append ``values`` (converted to the column's dtype)."""
        end = self.size + values.size
        if end > self.values.size:
            grown = np.empty(max(end, int(self.values.size * 1.25)), dtype=self.values.dtype)
            grown[: self.size] = self.values[: self.size]
            self.values = grown
        self.values[self.size : end] = values
        self.size = end

    def array(self) -> np.ndarray:
        """The values gathered: the buffer itself, trimmed in place (no copy of a 24M-sample column)."""
        if self.size != self.values.size:
            self.values.resize(self.size, refcheck=False)  # nobody else holds a view of the buffer
        return self.values
