"""Run the ``motorlab`` CLI for the app: argv from form fields, a warm child process, a time limit.

The app never re-implements a command: it builds the argv the user would type (long option names,
values as typed, units included) and runs the CLI's own ``main`` on it in a child process, so the
answer is the CLI's own, byte for byte. A child process (not a thread) because an analysis can be
stopped only by ending its process: a hostile or huge file gets its time-limit error, a client that
went away ends its command, while the event loop keeps serving other requests.

Warm workers: a child process pays Python's start-up and the imports of numpy, scipy, matplotlib
and motorlab (about 1 s; several on a busy machine) before it can work. :class:`Pool` keeps
:data:`SPARES` children started ahead (:mod:`motorlab.ui.warm`: imported, waiting for one job on
stdin); a command takes one, runs in it, and the process exits, so nothing of one request survives
into the next. The spares are replaced when no command runs (on a two-core laptop a replacement
importing scipy would slow the commands running); a burst that uses them up runs the rest in fresh
``python -P -m motorlab`` processes, which import only what their command needs.

Slots: sessions (``characterize``, many seconds) and short commands (one analysis, gains, the
page's plots) have separate semaphores, so a short analysis never waits behind running sessions.
"""

from __future__ import annotations

import asyncio
import atexit
import contextlib
import json
import os
import signal
import subprocess
import sys
import tempfile
import threading
import weakref
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import IO, Any

#: Seconds one command may run before it is ended.
TIME_LIMIT = 120.0

#: Seconds a session (``characterize``, slot ``"session"``) may run: its work grows with its units (an
#: 8-unit session is about 20 s of CPU and a report of a hundred figures; several times that on a busy machine).
SESSION_TIME_LIMIT = 600.0

#: Short commands (an analysis, gains, plots) at once; the others wait their turn.
CONCURRENCY = max(1, min(4, os.cpu_count() or 1))

#: Sessions (``characterize``) at once, in their own slots.
SESSIONS = max(1, min(2, (os.cpu_count() or 1) // 2))

#: Warm child processes kept ready (0, or env ``MOTORLAB_UI_WARM=0``: a fresh ``python -m`` per command).
SPARES = 2

_TRUE = {"1", "true", "on", "yes"}

#: Environment variables a child must not inherit from the app's own environment.
_SCRUBBED = ("MOTORLAB_TRACEBACK", "MOTORLAB_PROGRESS")


@dataclass(frozen=True)
class Outcome:
    """What a command printed and returned (progress lines, when streamed, are not in ``stderr``)."""

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


def _child_env() -> dict[str, str]:
    env = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",  # as the CLI (cli/__init__)
           **os.environ, "MPLBACKEND": "Agg", "PYTHONIOENCODING": "utf-8"}
    for name in _SCRUBBED:
        env.pop(name, None)
    return env


#: Each command runs in a process group of its own (POSIX), so that ending it also ends the processes it
#: started (``characterize`` analyses units in a small pool of processes: :mod:`motorlab.parallel`).
_OWN_GROUP: dict[str, Any] = {"start_new_session": True} if os.name == "posix" else {}


def end(proc: subprocess.Popen[bytes]) -> None:
    """End a command at once: its whole process group (POSIX), or the process."""
    if _OWN_GROUP:
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(proc.pid, signal.SIGKILL)
    with contextlib.suppress(OSError):
        proc.kill()


def _warm_enabled() -> bool:
    return SPARES > 0 and os.environ.get("MOTORLAB_UI_WARM", "1") not in ("0", "false", "no")


class Pool:
    """Warm child processes (:mod:`motorlab.ui.warm`), shared by every event loop of the process."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._spares: list[subprocess.Popen[bytes]] = []
        self.started = 0  # warm processes started so far (for tests and benchmarks)
        atexit.register(self.close)

    def spawn(self, *args: str) -> subprocess.Popen[bytes]:
        """A new warm process (``python -P -m motorlab.ui.warm ARGS``); its stderr is not read (``--serve``)."""
        self.started += 1
        return subprocess.Popen(
            [sys.executable, "-P", "-m", "motorlab.ui.warm", *args], cwd=tempfile.gettempdir(), env=_child_env(),
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL if args else subprocess.PIPE,
            **_OWN_GROUP,
        )

    def fill(self) -> None:
        """Start spares until :data:`SPARES` are ready (or starting)."""
        if not _warm_enabled():
            return
        with self._lock:
            self._spares = [p for p in self._spares if p.poll() is None]
            while len(self._spares) < SPARES:
                self._spares.append(self.spawn())

    def take(self) -> subprocess.Popen[bytes] | None:
        """A warm process for one job, or None when none is ready (the caller starts a fresh one)."""
        with self._lock:
            while self._spares:
                proc = self._spares.pop(0)
                if proc.poll() is None:
                    return proc
            return None

    def close(self) -> None:
        """End the spares (at exit; they also end by themselves when the app's end of their stdin closes)."""
        with self._lock:
            spares, self._spares = self._spares, []
        for proc in [*spares, *RUNNING]:  # the commands still running too: they are in groups of their own
            end(proc)
            proc.wait()
            for pipe in (proc.stdin, proc.stdout, proc.stderr):
                if pipe is not None:
                    pipe.close()


POOL = Pool()

_slots: weakref.WeakKeyDictionary[asyncio.AbstractEventLoop, dict[str, asyncio.Semaphore]] = weakref.WeakKeyDictionary()


def _semaphore(slot: str) -> asyncio.Semaphore:
    """The ``slot``'s semaphore on the running event loop (a semaphore belongs to one loop)."""
    loop = asyncio.get_running_loop()
    if loop not in _slots:
        _slots[loop] = {"short": asyncio.Semaphore(CONCURRENCY), "session": asyncio.Semaphore(SESSIONS)}
    return _slots[loop][slot]


#: Jobs a resident worker runs (``(module, first argument)``): the gains and their curves, computed from
#: typed numbers in a fraction of a second, recomputed at each change of an option on the page.
RESIDENT_JOBS = {("motorlab", "tune"), ("motorlab.ui.worker", "response")}

#: Nice value of sessions' processes: the CPU goes to short commands first (a session's table is
#: seconds away anyway; an analysis or a change of the gains is waited for).
SESSION_NICENESS = 10


class Resident:
    """One warm process (``motorlab.ui.warm --serve``) running short jobs one at a time, for the whole app.

    A gains change would otherwise take a spare (then replaced: a new Python importing scipy) for
    0.1 s of work. A job that runs past its time limit, or whose client goes away, ends the process (the
    next is started when the app is idle); while the resident is busy or starting, a job runs the
    ordinary way, in a spare or a fresh process, so nothing queues behind it. One per Python process,
    whatever the event loops: its answers are read in a thread, not through a loop's pipe transport.
    """

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self.proc: subprocess.Popen[bytes] | None = None
        self.ready = False
        self.busy = False
        self.jobs = 0  # jobs run so far (for tests and benchmarks)

    def start_soon(self) -> None:
        """Start the process (when none runs); it is ready once its imports are done (a thread waits for it)."""
        if not _warm_enabled():
            return
        with self._lock:
            if self.busy or (self.proc is not None and self.proc.poll() is None):
                return
            self.proc, self.ready = POOL.spawn("--serve"), False
            proc = self.proc
        threading.Thread(target=self._wait_ready, args=(proc,), daemon=True).start()

    def _wait_ready(self, proc: subprocess.Popen[bytes]) -> None:
        assert proc.stdout is not None
        with contextlib.suppress(OSError, ValueError):
            said = proc.stdout.readline().strip() == b"ready"
            with self._lock:
                if self.proc is proc:
                    self.ready = said

    async def start(self) -> None:
        """:meth:`start_soon`, then wait until the process is ready (or has ended)."""
        self.start_soon()
        while self.proc is not None and not self.ready and self.proc.poll() is None:
            await asyncio.sleep(0.05)

    def _take(self) -> subprocess.Popen[bytes] | None:
        with self._lock:
            proc = self.proc
            if self.busy or not self.ready or proc is None or proc.poll() is not None:
                return None
            self.busy = True
            return proc

    async def run(self, module: str, argv: Sequence[str], cwd: str, env: Mapping[str, str],
                  limit: float) -> Outcome | None:
        """The job's outcome, or None when the resident cannot take it now (the caller runs it otherwise)."""
        proc = self._take()
        if proc is None:
            return None
        assert proc.stdin is not None
        assert proc.stdout is not None
        try:
            job = {"module": module, "argv": list(argv), "cwd": cwd, "env": dict(env)}
            proc.stdin.write((json.dumps(job) + "\n").encode())
            proc.stdin.flush()
            line = await asyncio.wait_for(asyncio.get_running_loop().run_in_executor(None, proc.stdout.readline),
                                          timeout=limit)
            if not line:  # it died (ended from outside): the job runs the ordinary way
                self.close()
                return None
            self.jobs += 1
            answer = json.loads(line)
            err = "".join(k for k in str(answer["stderr"]).splitlines(keepends=True) if not k.startswith('{"progress"'))
            return Outcome(int(answer["code"]), str(answer["stdout"]), err)
        except TimeoutError:
            self.close()  # its reading thread gets the end of the pipe and finishes
            return Outcome(124, "", f"motorlab: error: the command took longer than {limit:g} s and was stopped")
        except (OSError, ValueError):
            self.close()
            return None
        except asyncio.CancelledError:  # the client went away: the job's state is unknown, end the process
            self.close()
            raise
        finally:
            self.busy = False

    def close(self) -> None:
        """End the process."""
        with self._lock:
            proc, self.proc, self.ready = self.proc, None, False
        if proc is not None:
            end(proc)
            proc.wait()
            for pipe in (proc.stdin, proc.stdout, proc.stderr):
                if pipe is not None:
                    with contextlib.suppress(OSError):
                        pipe.close()


RESIDENT = Resident()
atexit.register(RESIDENT.close)


def resident() -> Resident:
    """The app's resident worker (:data:`RESIDENT`)."""
    return RESIDENT


#: Commands running now (their processes), for tests: a cancelled request leaves none behind.
RUNNING: set[subprocess.Popen[bytes]] = set()


def _start(module: str, argv: Sequence[str], cwd: str, env: Mapping[str, str]) -> subprocess.Popen[bytes]:
    """A child running ``module argv`` in ``cwd``: a warm one given the job, or a fresh ``python -P -m``."""
    proc = POOL.take() if _warm_enabled() else None
    if proc is None:  # a burst used the spares up: a fresh process imports only what its command needs
        return subprocess.Popen(
            [sys.executable, "-P", "-m", module, *argv], cwd=cwd, env={**_child_env(), **env},
            stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE, **_OWN_GROUP,
        )
    job = json.dumps({"module": module, "argv": list(argv), "cwd": cwd, "env": dict(env)}) + "\n"
    stdin = proc.stdin
    assert stdin is not None

    def send() -> None:  # a thread: the child reads its job only once its imports are done
        try:
            stdin.write(job.encode())
        except OSError:
            pass  # ended before it read its job (killed): its outcome says so
        finally:
            with contextlib.suppress(OSError):
                stdin.close()

    threading.Thread(target=send, daemon=True).start()
    return proc


async def _reader(pipe: IO[bytes]) -> tuple[asyncio.StreamReader, asyncio.BaseTransport]:
    loop = asyncio.get_running_loop()
    reader = asyncio.StreamReader(limit=1 << 24)
    transport, _ = await loop.connect_read_pipe(lambda: asyncio.StreamReaderProtocol(reader), pipe)
    return reader, transport


async def _collect(proc: subprocess.Popen[bytes], on_progress: Callable[[dict[str, Any]], None] | None) -> tuple[
        bytes, bytes]:
    """Read the child's stdout and stderr to their end; progress lines go to ``on_progress``, not stderr."""
    assert proc.stdout is not None
    assert proc.stderr is not None
    out_reader, out_transport = await _reader(proc.stdout)
    err_reader, err_transport = await _reader(proc.stderr)
    try:
        async def errors() -> bytes:
            kept = bytearray()
            while line := await err_reader.readline():
                if on_progress is not None and line.startswith(b'{"progress"'):
                    with contextlib.suppress(ValueError):
                        on_progress(json.loads(line)["progress"])
                        continue
                kept += line
            return bytes(kept)

        out, err = await asyncio.gather(out_reader.read(), errors())
        while proc.poll() is None:  # both pipes closed: the process is exiting
            await asyncio.sleep(0.005)
        return out, err
    finally:
        out_transport.close()
        err_transport.close()


#: Seconds after the last command ends before the spares it used are replaced: a new Python importing scipy
#: takes a CPU for seconds, and on a two-core laptop the browser draws the answer's figures in those first moments.
REFILL_DELAY = 1.5


def _refill_if_idle() -> None:
    """Replace the spares used and start the resident worker, unless a command runs again."""
    if not RUNNING:
        POOL.fill()
        resident().start_soon()


async def run_module(
    module: str, argv: Sequence[str], *, cwd: str, time_limit: float | None = None, slot: str = "short",
    on_progress: Callable[[dict[str, Any]], None] | None = None,
) -> Outcome:
    """Run ``python -m module argv...`` in ``cwd``; end it after ``time_limit`` s.

    The default limit is :data:`TIME_LIMIT`, or :data:`SESSION_TIME_LIMIT` in the ``"session"`` slot.

    ``slot`` is ``"short"`` or ``"session"``. With ``on_progress`` the child reports progress
    (``MOTORLAB_PROGRESS=json``) and each report's dict is handed to it while the command runs. A
    cancelled call (the client went away) ends the child at once.
    """
    limit = (SESSION_TIME_LIMIT if slot == "session" else TIME_LIMIT) if time_limit is None else time_limit
    env = {"MOTORLAB_PROGRESS": "json"} if on_progress is not None else {}
    if _warm_enabled() and (module, argv[0] if argv else "") in RESIDENT_JOBS:
        answered = await resident().run(module, argv, cwd, env, limit)
        if answered is not None:
            return answered
    async with _semaphore(slot):
        proc = _start(module, argv, cwd, env)
        if slot == "session" and hasattr(os, "setpriority"):
            with contextlib.suppress(OSError):  # the processes it forks inherit it
                os.setpriority(os.PRIO_PROCESS, proc.pid, SESSION_NICENESS)
        RUNNING.add(proc)
        try:
            out, err = await asyncio.wait_for(_collect(proc, on_progress), timeout=limit)
        except TimeoutError:
            return Outcome(124, "", f"motorlab: error: the command took longer than {limit:g} s and was stopped")
        finally:
            # Synchronous first: a cancelled request may be cancelled again at the next await.
            running = proc.poll() is None
            if running:
                end(proc)
            RUNNING.discard(proc)
            if not RUNNING:  # idle: replace the spares used soon (not while commands run: they need the CPU)
                asyncio.get_running_loop().call_later(REFILL_DELAY, _refill_if_idle)
            if running:  # reap it (in a thread: Popen.wait blocks)
                with contextlib.suppress(asyncio.CancelledError):
                    await asyncio.shield(asyncio.get_running_loop().run_in_executor(None, proc.wait))
    return Outcome(int(proc.returncode or 0), out.decode("utf-8", "replace"), err.decode("utf-8", "replace"))


async def run_cli(argv: Sequence[str], *, cwd: str, time_limit: float | None = None, slot: str = "short",
                  on_progress: Callable[[dict[str, Any]], None] | None = None) -> Outcome:
    """Run ``motorlab argv...`` (the CLI's own entry, :func:`motorlab.cli.main`) in a child process."""
    return await run_module("motorlab", argv, cwd=cwd, time_limit=time_limit, slot=slot, on_progress=on_progress)
