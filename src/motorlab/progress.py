"""Progress of long work: reported by the library, shown by whichever front end is listening.

The library never prints progress itself. A long analysis (a session's units, a fit's iterations, a
capture read in chunks) reports steps through :func:`task`; a front end installs a reporter with
:func:`reporting` and shows them: the CLI as a rich progress bar on stderr (only when the work runs
longer than a couple of seconds), the browser app's worker as JSON lines it streams to the page.
With no reporter installed, reporting costs one context-variable look-up.

Examples
--------
>>> from motorlab import progress
>>> with progress.task("Fitting units", total=3, unit="unit") as step:
...     for name in "ABC":
...         step.advance(detail=f"unit {name}")
"""

from __future__ import annotations

import contextlib
import contextvars
import json
import sys
import time
from collections.abc import Callable, Iterator
from dataclasses import asdict, dataclass
from typing import IO, Any


@dataclass(frozen=True)
class Progress:
    """One report: ``done`` of ``total`` (None when unknown) of the work named ``what``.

    ``detail`` says what is being done now ("unit B: spindown"); ``unit`` names what is counted
    ("unit", "row", "MB"); ``finished`` is True on the last report of a task.
    """

    what: str
    done: float
    total: float | None = None
    unit: str = ""
    detail: str = ""
    finished: bool = False

    def fraction(self) -> float | None:
        """Done / total, or None when the total is unknown."""
        return None if not self.total else min(1.0, self.done / self.total)

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


Reporter = Callable[[Progress], None]

_reporter: contextvars.ContextVar[Reporter | None] = contextvars.ContextVar("motorlab_progress", default=None)


@contextlib.contextmanager
def reporting(reporter: Reporter | None) -> Iterator[None]:
    """Send every :class:`Progress` reported inside the ``with`` block to ``reporter``."""
    token = _reporter.set(reporter)
    try:
        yield
    finally:
        _reporter.reset(token)


def active() -> bool:
    """Whether anybody listens (to skip work done only to report progress)."""
    return _reporter.get() is not None


class Task:
    """A task under way; :meth:`advance` and :meth:`update` report it (see :func:`task`)."""

    def __init__(self, what: str, total: float | None, unit: str) -> None:
        self.what, self.total, self.unit = what, total, unit
        self.done = 0.0
        self.detail = ""

    def _send(self, finished: bool = False) -> None:
        reporter = _reporter.get()
        if reporter is not None:
            reporter(Progress(self.what, self.done, self.total, self.unit, self.detail, finished))

    def advance(self, amount: float = 1.0, *, detail: str | None = None) -> None:
        """``amount`` more done; ``detail`` says what comes next."""
        self.done += amount
        if detail is not None:
            self.detail = detail
        self._send()

    def update(self, done: float, *, total: float | None = None, detail: str | None = None) -> None:
        """Set how much is done (and the total, when it became known)."""
        self.done = done
        if total is not None:
            self.total = total
        if detail is not None:
            self.detail = detail
        self._send()


@contextlib.contextmanager
def task(what: str, *, total: float | None = None, unit: str = "", detail: str = "") -> Iterator[Task]:
    """Report a piece of long work: a first report on entry, a finished one on exit."""
    step = Task(what, total, unit)
    step.detail = detail
    step._send()
    try:
        yield step
    finally:
        step._send(finished=True)


class JsonLines:
    """A reporter writing one JSON object a line, ``{"progress": {...}}``, at most every ``interval`` s.

    The browser app's worker runs the CLI with ``MOTORLAB_PROGRESS=json`` and reads these lines from
    the child's stderr while it runs.
    """

    def __init__(self, stream: IO[str] | None = None, *, interval: float = 0.2) -> None:
        self.stream, self.interval = stream, interval
        self._last = 0.0

    def __call__(self, p: Progress) -> None:
        now = time.monotonic()
        if not p.finished and now - self._last < self.interval:
            return
        self._last = now
        stream = self.stream or sys.stderr
        stream.write(json.dumps({"progress": p.to_dict()}) + "\n")
        stream.flush()


class Terminal:
    """A reporter drawing a rich progress bar on stderr, once the work has run for ``delay`` seconds.

    Short work shows nothing; a terminal that is not interactive shows nothing either.
    """

    def __init__(self, *, delay: float = 2.0) -> None:
        self.delay = delay
        self.start = time.monotonic()
        self._bar: Any = None
        self._ids: dict[str, Any] = {}

    def __call__(self, p: Progress) -> None:
        if self._bar is None:
            if time.monotonic() - self.start < self.delay or p.finished or not sys.stderr.isatty():
                return
            from rich.console import Console
            from rich.progress import BarColumn, TextColumn, TimeElapsedColumn
            from rich.progress import Progress as Bar

            self._bar = Bar(TextColumn("{task.description}"), BarColumn(), TextColumn("{task.fields[count]}"),
                            TimeElapsedColumn(), console=Console(stderr=True), transient=True)
            self._bar.start()
        key = p.what
        count = f"{p.done:g}/{p.total:g} {p.unit}".strip() if p.total else f"{p.done:g} {p.unit}".strip()
        label = f"{p.what}: {p.detail}" if p.detail else p.what
        if key not in self._ids:
            self._ids[key] = self._bar.add_task(label, total=p.total, count=count)
        self._bar.update(self._ids[key], completed=p.done, total=p.total, description=label, count=count)
        if p.finished:
            self._bar.remove_task(self._ids.pop(key))
            if not self._ids:  # nothing under way: stop the bar's refresh thread (a later task starts it again)
                self.close()

    def close(self) -> None:
        if self._bar is not None:
            self._bar.stop()
            self._bar = None
