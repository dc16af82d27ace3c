"""Independent pieces of long work shared among a few processes: a session's units, a report's figures.

A session's units are analysed independently, and each unit's section of the report is drawn
independently; numpy releases the GIL too seldom in those loops for threads to help, so
:func:`map_in_processes` hands the pieces to ``processes`` child processes and gives the results
back in the order of the items.

The children are forked (Linux, and this process runs no other Python thread): they start at once
with every module and the work already in memory. With a thread running (a progress bar's, a test
runner's), whose locks a fork would copy in any state, they are forked by multiprocessing's fork
server instead: a single-threaded process started once per process, which imports
:data:`FORKSERVER_PRELOAD` once, so each child starts with the imports done and only the work is
pickled to it. Where there is no fork server (Windows) they are spawned, which costs each child
Python's start and the imports (a second or two). A child ignores Ctrl+C (the parent ends the pool); a
front end that must be able to stop everything ends the process group (:mod:`motorlab.ui.runner`).

Messages: a piece of work may call :func:`tell` (``tell(("unit B", "spindown"))``); the parent hands
each message to ``on_message`` while it waits, so progress reported in a child reaches the front end.
"""

from __future__ import annotations

import multiprocessing
import os
import signal
import sys
import threading
import warnings
from collections.abc import Callable, Sequence
from multiprocessing.context import BaseContext
from typing import Any

#: What the fork server imports once, before it forks any child: the modules of the work handed to
#: :func:`map_in_processes` (a session's units, a report's sections) and what they draw and fit with.
FORKSERVER_PRELOAD = ("motorlab.session.characterize", "motorlab.report.document", "motorlab.plot",
                      "matplotlib.backends.backend_agg", "scipy.optimize")

#: Default number of processes: two on a machine with two CPUs or more (the work of a front end that
#: is also serving other requests should not take every core of a bigger machine).
DEFAULT_PROCESSES = 2

_work: tuple[Callable[[Any], Any], Sequence[Any]] | None = None
_messages: Any = None


def default_processes() -> int:
    """:data:`DEFAULT_PROCESSES`, or 1 on a machine with one CPU."""
    return max(1, min(DEFAULT_PROCESSES, os.cpu_count() or 1))


def can_fork() -> bool:
    """Whether children may be forked here: Linux, no other Python thread, and not itself a pool's
    child (a daemonic process may have none). Work too short to repay a spawned child's start
    runs here when this is False."""
    return _fork_safe() and not multiprocessing.current_process().daemon


def _fork_safe() -> bool:
    return sys.platform == "linux" and threading.active_count() == 1


class Forked:
    """``fn(item)`` started in a forked child (only where :func:`can_fork`) while this process goes on;
    :meth:`result` waits for it. The child reports no progress and ignores Ctrl+C (this process ends it)."""

    def __init__(self, fn: Callable[[Any], Any], item: Any) -> None:
        context = multiprocessing.get_context("fork")
        self._answer, sender = context.Pipe(duplex=False)
        self._process = context.Process(target=_forked, args=(fn, item, sender), daemon=True)
        self._process.start()
        sender.close()

    def result(self) -> Any:
        """``fn(item)``, or the exception it raised (a child that died without answering: ChildProcessError)."""
        try:
            answer = self._answer.recv()
        except EOFError:  # it ended without answering
            answer = None
        except BaseException:  # Ctrl+C here: end the child too
            self._process.terminate()
            raise
        finally:
            self._process.join()
            self._answer.close()
        if answer is None:
            raise ChildProcessError(f"a forked child ended with code {self._process.exitcode}")
        ok, value = answer
        if not ok:
            raise value
        return value


def _forked(fn: Callable[[Any], Any], item: Any, sender: Any) -> None:
    from motorlab import progress

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    with progress.reporting(None):
        try:
            answer = (True, fn(item))
        except Exception as exc:  # handed to the parent, which raises it
            answer = (False, exc)
    sender.send(answer)
    sender.close()


def _context() -> BaseContext:
    """Fork where it is safe; else the fork server (its imports done once); else spawn."""
    if _fork_safe():
        return multiprocessing.get_context("fork")
    if "forkserver" in multiprocessing.get_all_start_methods():
        context = multiprocessing.get_context("forkserver")
        context.set_forkserver_preload(list(FORKSERVER_PRELOAD))  # read when the server starts, at first use
        return context
    return multiprocessing.get_context("spawn")


def _start(work: tuple[Callable[[Any], Any], Sequence[Any]], messages: Any) -> None:
    """A child's initialiser: keep the work and the message queue; leave Ctrl+C to the parent."""
    global _work, _messages
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _work, _messages = work, messages


def _run(index: int) -> tuple[int, Any]:
    from motorlab import progress

    assert _work is not None
    fn, items = _work
    with progress.reporting(None):  # a child's own progress would interleave with the parent's
        return index, fn(items[index])


class _Here:
    """:func:`tell` when the work runs in this process: the message goes straight to ``on_message``."""

    def __init__(self, on_message: Callable[[Any], None] | None) -> None:
        self.on_message = on_message

    def put(self, message: Any) -> None:
        if self.on_message is not None:
            self.on_message(message)


def tell(message: Any) -> None:
    """Send ``message`` to the ``on_message`` of the :func:`map_in_processes` running this work."""
    if _messages is not None:
        _messages.put(message)


def map_in_processes(fn: Callable[[Any], Any], items: Sequence[Any], *, processes: int = 1,
                     on_message: Callable[[Any], None] | None = None,
                     on_result: Callable[[int, Any], None] | None = None) -> list[Any]:
    """``[fn(item) for item in items]``, computed in up to ``processes`` child processes.

    Parameters
    ----------
    fn
        A module-level function (a child of the fork server, or a spawned one, imports it by name).
    items
        The pieces of work (pickled to the fork server's or spawned children; forked children have them
        already).
    processes
        At most this many children; 1 (or a single item) runs everything here, in this process.
    on_message
        Called in this process with each message a piece of work sent with :func:`tell`.
    on_result
        Called in this process as ``on_result(index, result)`` as each piece finishes (in any order).

    Returns
    -------
    list
        The results, in the order of ``items``. An exception raised by ``fn`` is raised here.
    """
    global _messages
    count = min(processes, len(items))
    if count <= 1:
        results = []
        saved, _messages = _messages, _Here(on_message)
        try:
            for k, item in enumerate(items):
                results.append(fn(item))
                if on_result is not None:
                    on_result(k, results[-1])
        finally:
            _messages = saved
        return results
    context = _context()
    messages = context.SimpleQueue() if on_message is not None else None
    with warnings.catch_warnings():
        # Python 3.12 warns when a process with threads forks; numpy's BLAS threads are fork-safe
        # (they register at-fork handlers) and no Python thread runs here (see _context).
        warnings.simplefilter("ignore", DeprecationWarning)
        pool = context.Pool(count, initializer=_start, initargs=((fn, items), messages))
    found: dict[int, Any] = {}
    try:
        pending = pool.imap_unordered(_run, range(len(items)))
        while len(found) < len(items):
            _relay(messages, on_message)
            try:
                index, result = pending.next(timeout=0.02)
            except multiprocessing.TimeoutError:
                continue
            found[index] = result
            if on_result is not None:
                on_result(index, result)
        _relay(messages, on_message)
        pool.close()
        pool.join()
    finally:
        pool.terminate()
        if messages is not None:
            messages.close()
    return [found[k] for k in range(len(items))]


def _relay(messages: Any, on_message: Callable[[Any], None] | None) -> None:
    if messages is None or on_message is None:
        return
    while not messages.empty():
        on_message(messages.get())
