"""Writing outputs safely: to a temporary name beside the target, renamed when complete.

An interrupted ``motorlab simulate`` or ``characterize`` (Ctrl-C, a full disk, a crash) then leaves
either the old file or the new one, never half a file; and no output may land on a file the user
gave as input (a session whose data file happens to be called ``results.csv``).
"""

from __future__ import annotations

import contextlib
import os
import stat
from collections.abc import Iterable, Iterator
from pathlib import Path

from motorlab.errors import OptionError

PathArg = str | os.PathLike[str]


@contextlib.contextmanager
def atomic_path(path: PathArg) -> Iterator[Path]:
    """A temporary path to write instead of ``path``; renamed onto ``path`` when the block completes.

    The temporary file keeps the extension (``.tmp-<pid>.png``) so that writers choosing the format
    by extension (matplotlib) still do. On any exception, including ``KeyboardInterrupt``, it is
    removed and ``path`` is left as it was.
    """
    target = Path(os.fspath(path))
    check_writable_target(target)
    temporary = target.with_name(f".{target.stem}.tmp-{os.getpid()}{target.suffix}")
    try:
        yield temporary
        os.replace(temporary, target)
    except BaseException:
        with contextlib.suppress(OSError):
            temporary.unlink()
        raise


def check_writable_target(path: PathArg) -> None:
    """Refuse an output path that exists and is not a regular file (a folder, a device, a FIFO, a socket).

    The rename of :func:`atomic_path` would otherwise put a regular file in its place: run as root,
    ``-o /dev/null`` would replace the system's null device.

    Raises
    ------
    OptionError
        Naming the path and what it is; an empty or blank name ("-o ' '": a typo, not a file name).
    """
    if not os.path.basename(os.fspath(path)).strip():
        raise OptionError(f"{os.fspath(path)!r}: the output file name is empty or blank")
    try:
        info = os.stat(path)  # through a symbolic link: what it points to counts
    except OSError:
        return  # absent (or unreadable: the write itself will say so)
    if not stat.S_ISREG(info.st_mode):
        kind = "a directory" if stat.S_ISDIR(info.st_mode) else "a device, FIFO or socket"
        raise OptionError(f"{os.fspath(path)}: is {kind}, not a regular file: motorlab writes its outputs to "
                          "regular files only")


def write_text_atomic(path: PathArg, text: str, *, newline: str | None = None) -> None:
    """Write ``text`` (UTF-8) to ``path`` through :func:`atomic_path`."""
    with atomic_path(path) as temporary, open(temporary, "w", encoding="utf-8", newline=newline) as handle:
        handle.write(text)


def write_bytes_atomic(path: PathArg, data: bytes) -> None:
    """Write ``data`` to ``path`` through :func:`atomic_path`."""
    with atomic_path(path) as temporary, open(temporary, "wb") as handle:
        handle.write(data)


def _identity(path: PathArg) -> tuple[int, int] | str:
    try:
        info = os.stat(path)
    except OSError:
        return os.path.realpath(os.fspath(path))
    return (info.st_dev, info.st_ino)


def check_not_inputs(outputs: Iterable[PathArg], inputs: Iterable[PathArg], *, option: str = "-o") -> None:
    """Refuse, before any work, an output path that is one of the input files (under any name).

    Raises
    ------
    OptionError
        Naming the option, the output and the input it would overwrite.
    """
    given = {}
    for path in inputs:
        given[_identity(path)] = os.fspath(path)
        given[os.path.realpath(os.fspath(path))] = os.fspath(path)
    for out in outputs:
        hit = given.get(_identity(out)) or given.get(os.path.realpath(os.fspath(out)))
        if hit is not None:
            raise OptionError(
                f"{option}: writing {os.fspath(out)} would overwrite the input file {hit}; "
                "choose another folder or name"
            )
