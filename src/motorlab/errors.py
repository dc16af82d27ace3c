"""Exceptions raised by motorlab.

Library errors subclass built-in exceptions (as python-control's ``exception.py`` does) so that
notebook users can catch ``ValueError``; the CLI turns every :class:`MotorlabError` into one line
on standard error and exit code 2.
"""

from __future__ import annotations

from os import PathLike


class MotorlabError(Exception):
    """Base class of every error motorlab raises on purpose."""


class InputError(MotorlabError, ValueError):
    """Something the user gave (a file, an option, a session) is unusable.

    Parameters
    ----------
    message
        What is wrong, in plain words.
    path
        The file concerned, if any.
    line
        The 1-based line number in ``path``, if known.
    """

    def __init__(self, message: str, *, path: str | PathLike[str] | None = None, line: int | None = None):
        self.message = message
        self.path = None if path is None else str(path)
        self.line = line
        super().__init__(self.one_line())

    def one_line(self) -> str:
        """The message as ``file:line: problem`` (parts that are unknown are left out)."""
        where = ""
        if self.path is not None:
            where = self.path if self.line is None else f"{self.path}:{self.line}"
            where += ": "
        return where + self.message.replace("\n", " ")


class LogFormatError(InputError):
    """A log file cannot be read: empty, binary, truncated, non-numeric, NaN, missing columns."""


class OptionError(InputError):
    """A command-line option or function argument has an impossible value or a wrong unit."""


class SessionError(InputError):
    """A session description (TOML) is invalid: unknown key, missing file, wrong unit."""


class RigError(MotorlabError, ValueError):
    """A (virtual) rig was asked for a set-up it cannot or must not do (e.g. INA219 above 16 V)."""


class FitError(MotorlabError, RuntimeError):
    """A fit could not be carried out on data that was otherwise readable (no coast, too few points)."""
