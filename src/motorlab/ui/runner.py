"""Run the ``motorlab`` CLI for the app: argv from form fields, a child process, a time limit.

The app never re-implements a command: it builds the argv the user would type (long option names,
values as typed, units included) and runs ``python -m motorlab`` on it in a child process, so the
answer is the CLI's own, byte for byte. A child process (not a thread) because an analysis can be
stopped only by ending its process: a hostile or huge file gets its time-limit error while the
event loop keeps serving other requests. A semaphore bounds how many run at once.
"""

from __future__ import annotations

import asyncio
import os
import sys
import weakref
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

#: Seconds one command may run before it is ended.
TIME_LIMIT = 120.0

#: Child processes at once (the others wait their turn).
CONCURRENCY = max(1, min(4, os.cpu_count() or 1))

_TRUE = {"1", "true", "on", "yes"}


@dataclass(frozen=True)
class Outcome:
    """What a command printed and returned."""

    code: int
    stdout: str
    stderr: str

    def error_line(self) -> str:
        """The CLI's one-line message (its last line on stderr), without the ``prog: error:`` prefix."""
        lines = [line for line in self.stderr.splitlines() if line.strip()]
        errors = [line for line in lines if ": error: " in line or "internal error" in line]
        line = (errors or lines or [f"exit code {self.code}"])[-1]
        return line.split(": error: ", 1)[-1] if ": error: " in line else line


def build_argv(
    head: Sequence[str], fields: Sequence[Mapping[str, Any]], values: Mapping[str, Sequence[str]], files: Sequence[str]
) -> list[str]:
    """The command line for ``head`` (``["analyze", "spindown"]``) from form ``values`` and upload paths.

    Every value goes as ``--name=value`` (so ``-1120`` stays a value for the CLI to judge); a field
    that is no option of the command goes too, and the CLI refuses it in its own words. Flags count
    when their value is 1/true/on/yes; positional file arguments take the uploaded ``files``.
    """
    by_name = {f["name"]: f for f in fields}
    argv = list(head)
    positional = [f for f in fields if f["positional"]]
    for f in positional:
        if f["kind"] == "file":
            argv.extend(files)
        else:
            argv.extend(str(v) for v in values.get(f["name"], ())[:1])
    for name, given in values.items():
        spec = by_name.get(name)
        if spec is not None and spec["positional"]:
            continue
        if spec is not None and spec["kind"] == "flag":
            if any(str(v).strip().lower() in _TRUE for v in given):
                argv.append(spec["option"])
            continue
        for value in given:
            if str(value) == "" and spec is not None:
                continue  # an empty form field: the CLI's default
            argv.append(f"--{name}={value}")
    return argv


_slots: weakref.WeakKeyDictionary[asyncio.AbstractEventLoop, asyncio.Semaphore] = weakref.WeakKeyDictionary()


def _semaphore() -> asyncio.Semaphore:
    """The slots of the running event loop (a semaphore belongs to one loop; tests run several servers)."""
    loop = asyncio.get_running_loop()
    if loop not in _slots:
        _slots[loop] = asyncio.Semaphore(CONCURRENCY)
    return _slots[loop]


async def run_module(module: str, argv: Sequence[str], *, cwd: str, time_limit: float | None = None) -> Outcome:
    """Run ``python -m module argv...`` in ``cwd``; end it after ``time_limit`` (default :data:`TIME_LIMIT`) seconds."""
    limit = TIME_LIMIT if time_limit is None else time_limit
    env = {**os.environ, "MPLBACKEND": "Agg", "PYTHONIOENCODING": "utf-8"}
    env.pop("MOTORLAB_TRACEBACK", None)
    async with _semaphore():
        proc = await asyncio.create_subprocess_exec(
            sys.executable, "-m", module, *argv, cwd=cwd, env=env,
            stdin=asyncio.subprocess.DEVNULL, stdout=asyncio.subprocess.PIPE, stderr=asyncio.subprocess.PIPE,
        )
        try:
            out, err = await asyncio.wait_for(proc.communicate(), timeout=limit)
        except TimeoutError:
            proc.kill()
            await proc.wait()
            return Outcome(124, "", f"motorlab: error: the command took longer than {limit:g} s and was stopped")
    return Outcome(int(proc.returncode or 0), out.decode("utf-8", "replace"), err.decode("utf-8", "replace"))


async def run_cli(argv: Sequence[str], *, cwd: str, time_limit: float | None = None) -> Outcome:
    """Run ``motorlab argv...`` (the CLI's own entry, :func:`motorlab.cli.main`) in a child process."""
    return await run_module("motorlab", argv, cwd=cwd, time_limit=time_limit)
