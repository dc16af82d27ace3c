"""Errors of the acquisition layer: an instrument that cannot be reached or does not answer sensibly."""

from __future__ import annotations

from motorlab.errors import MotorlabError


class InstrumentError(MotorlabError, RuntimeError):
    """An instrument cannot be opened, does not answer in time, or answers something impossible.

    The CLI prints it as one line and exits with code 2, like any other :class:`MotorlabError`.
    """
