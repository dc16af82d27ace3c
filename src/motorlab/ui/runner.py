"""Run the ``motorlab`` CLI for the app: argv from form fields, a warm child process, a time limit.

The app never re-implements a command: it builds the argv the user would type (long option names,
values as typed, units included) and runs the CLI's own ``main`` on it in a child process, so the
answer is the CLI's own, byte for byte. A child process (not a thread) because an analysis can be
stopped only by ending its process: a hostile or huge file gets its time-limit error, a client that
went away ends its command, while the event loop keeps serving other requests.

The fork server: a child process would pay Python's start-up and the imports of numpy, scipy,
matplotlib and motorlab (about 3 s of CPU; seconds of waiting on a busy machine) before it works.
:class:`Pool` keeps one process that did those imports (:mod:`motorlab.ui.warm` ``--fork-server``); each
command is forked from it (milliseconds), runs in its own process and session, and exits, so nothing of
one request survives into the next and a command is still ended by ending its process group. Until the
server is ready (its own imports, at the app's start) or when it is gone, a command runs in a fresh
``python -P -m motorlab`` process, which imports only what its command needs.

Slots: sessions (``characterize``, many seconds) and short commands (one analysis, gains, the
page's plots) have separate semaphores, so a short analysis never waits behind running sessions.
"""

from __future__ import annotations

import asyncio
import atexit
import contextlib
import itertools
import json
import os
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
import weakref
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import IO, Any, TypeAlias

#: Seconds one command may run before it is ended.
TIME_LIMIT = 120.0

#: Seconds a session (``characterize``, slot ``"session"``) may run: its work grows with its units (an
#: 8-unit session is about 20 s of CPU and a report of a hundred figures; several times that on a busy machine).
SESSION_TIME_LIMIT = 600.0

#: Short commands (an analysis, gains, plots) at once; the others wait their turn.
CONCURRENCY = max(1, min(4, os.cpu_count() or 1))

#: Sessions (``characterize``) at once, in their own slots.
SESSIONS = max(1, min(2, (os.cpu_count() or 1) // 2))

#: Processes a session's units are analysed and its report drawn in (``characterize --processes``): twice the
#: CPUs, at most 4. The units take about the same time each, so three units in two processes end in two units'
#: time, in three processes sharing the two CPUs in one and a half (the 3-unit session's table 2.2–2.4 s against
#: 2.5–2.9 s, benchmarks/bench_ui.py); a session runs at a lower priority, so short commands still come first.
SESSION_PROCESSES = max(2, min(4, 2 * (os.cpu_count() or 1)))

#: Seconds a command waits for the fork server to say it has forked it (it does nothing else: milliseconds).
FORK_WAIT = 10.0

#: Whether commands are forked from a fork server here: Linux (file descriptors passed over a ``SOCK_SEQPACKET``
#: socket; macOS's system frameworks are not safe to use in a forked child, Windows has no fork).
FORKING = sys.platform == "linux" and hasattr(socket, "send_fds")

#: Elsewhere, warm processes kept started ahead, each taking one command (``python -P -m motorlab.ui.warm``).
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


def end(proc: subprocess.Popen[bytes] | Forked) -> None:
    """End a command at once: its whole process group (POSIX), or the process."""
    if _OWN_GROUP:
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(proc.pid, signal.SIGKILL)
    with contextlib.suppress(OSError):
        proc.kill()


def _warm_enabled() -> bool:
    """Whether commands are forked from the fork server and gains run in the resident worker (env
    ``MOTORLAB_UI_WARM=0``: a fresh ``python -P -m`` per command)."""
    return os.environ.get("MOTORLAB_UI_WARM", "1") not in ("0", "false", "no")


class Forked:
    """A command forked by the fork server, seen as a :class:`subprocess.Popen` is (``pid``, ``stdin``, ``stdout``,
    ``stderr``, ``poll``, ``wait``, ``kill``, ``returncode``); its exit code comes from the server, which reaps it."""

    def __init__(self, stdout: int, stderr: int | None, server: socket.socket, stdin: int | None = None) -> None:
        self.pid = 0
        self.returncode: int | None = None
        self.server = server  # the fork server's socket: it reports this command's end
        self.stdout: IO[bytes] = os.fdopen(stdout, "rb")
        self.stderr: IO[bytes] | None = os.fdopen(stderr, "rb") if stderr is not None else None
        self.stdin: IO[bytes] | None = os.fdopen(stdin, "wb") if stdin is not None else None
        self.forked = threading.Event()
        self._ended = threading.Event()

    def ended(self, code: int) -> None:
        self.returncode = code
        self._ended.set()

    def poll(self) -> int | None:
        return self.returncode

    def wait(self, timeout: float | None = None) -> int:
        if not self._ended.wait(timeout):
            raise subprocess.TimeoutExpired(f"forked command {self.pid}", timeout or 0.0)
        assert self.returncode is not None
        return self.returncode

    def kill(self) -> None:
        if self.returncode is None and self.pid:
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.kill(self.pid, signal.SIGKILL)

    def close(self) -> None:
        """Close this side's pipes."""
        for pipe in (self.stdin, self.stdout, self.stderr):
            if pipe is not None:
                with contextlib.suppress(OSError):
                    pipe.close()


#: A command's process: a fresh Python, or one forked by the fork server.
Child: TypeAlias = "subprocess.Popen[bytes] | Forked"


class Pool:
    """The fork server (``python -P -m motorlab.ui.warm --fork-server FD``), shared by every event loop of the
    process: started by :meth:`fill`, it forks each command (:meth:`fork`)."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._send = threading.Lock()
        self.server: subprocess.Popen[bytes] | None = None
        self._socket: socket.socket | None = None
        self.ready = False
        self._jobs: dict[int, Forked] = {}
        self._spares: list[subprocess.Popen[bytes]] = []
        self._ids = itertools.count(1)
        self.started = 0  # Python processes started so far, the fork server's and the resident's (tests, benchmarks)
        self.forks = 0  # commands forked so far (tests, benchmarks)
        atexit.register(self.close)

    def wait_ready(self, seconds: float = 120.0) -> bool:
        """:meth:`fill`, then wait until the fork server has done its imports (or ``seconds`` have passed); False
        where commands are not forked."""
        self.fill()
        deadline = time.monotonic() + seconds
        while FORKING and not self.ready and time.monotonic() < deadline and _warm_enabled():
            time.sleep(0.02)
        return self.ready

    def spawn(self, *args: str, **popen: Any) -> subprocess.Popen[bytes]:
        """A new Python preloaded with the commands' imports (``python -P -m motorlab.ui.warm ARGS``)."""
        self.started += 1
        streams = {"stdin": subprocess.PIPE, "stdout": subprocess.PIPE, "stderr": subprocess.DEVNULL, **popen}
        return subprocess.Popen([sys.executable, "-P", "-m", "motorlab.ui.warm", *args], cwd=tempfile.gettempdir(),
                                env=_child_env(), **streams, **_OWN_GROUP)

    def fill(self) -> None:
        """Start the fork server unless it runs (its imports take seconds: :meth:`fork` uses it once ready); where
        there is none (not :data:`FORKING`), start spares until :data:`SPARES` are ready or starting."""
        if not _warm_enabled():
            return
        if not FORKING:
            with self._lock:
                self._spares = [p for p in self._spares if p.poll() is None]
                while len(self._spares) < SPARES:
                    self._spares.append(self.spawn(stderr=subprocess.PIPE))
            return
        with self._lock:
            if self.server is not None and self.server.poll() is None:
                return
            ours, theirs = socket.socketpair(socket.AF_UNIX, socket.SOCK_SEQPACKET)
            with theirs:
                server = self.spawn("--fork-server", str(theirs.fileno()), pass_fds=(theirs.fileno(),),
                                    stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL)
            self.server, self._socket, self.ready = server, ours, False
        threading.Thread(target=self._listen, args=(server, ours), daemon=True).start()

    def _listen(self, server: subprocess.Popen[bytes], sock: socket.socket) -> None:
        """The server's messages: ready, each command forked, each command ended; at its end, its commands
        are ended too (no one would report their exit)."""
        with contextlib.suppress(OSError):
            while message := sock.recv(1 << 16):
                said = json.loads(message)
                if said.get("ready"):
                    with self._lock:
                        self.ready = self.server is server
                    continue
                job = self._jobs.get(int(said["id"]))
                if job is None:
                    if "pid" in said:  # forked after its command gave up waiting: nobody reads its pipes
                        with contextlib.suppress(ProcessLookupError, PermissionError):
                            os.kill(int(said["pid"]), signal.SIGKILL)
                    continue
                if "pid" in said:
                    job.pid = int(said["pid"])
                    job.forked.set()
                else:
                    self._jobs.pop(int(said["id"]), None)
                    job.ended(int(said["exit"]))
        with self._lock:
            if self.server is server:
                self.server, self._socket, self.ready = None, None, False
            orphans = [job for job in self._jobs.values() if job.server is sock and job.returncode is None]
        for job in orphans:
            end(job)
            job.forked.set()
            job.ended(-signal.SIGKILL)
        with contextlib.suppress(OSError):
            sock.close()
        server.wait()

    def fork(self, module: str, argv: Sequence[str], cwd: str, env: Mapping[str, str], *,
             resident: bool = False) -> Forked | None:
        """The command forked by the server, or None when it is not ready (the caller starts a fresh Python).

        ``resident``: the resident worker (``motorlab.ui.warm --serve``), which reads its jobs from a pipe
        (:attr:`Forked.stdin`) and writes nothing to stderr that anyone reads (it goes to the null device); it
        counts among the processes :attr:`started`, not among the commands :attr:`forks`."""
        job = {"module": module, "argv": list(argv), "cwd": cwd, "env": dict(env)}
        with self._lock:
            sock = self._socket if self.ready and FORKING else None
        if sock is None:
            return None
        out_r, out_w = os.pipe()
        if resident:
            in_r, in_w = os.pipe()
            err_r, err_w = None, os.open(os.devnull, os.O_WRONLY)
            passed = [out_w, err_w, in_r]
        else:
            in_w = None
            err_r, err_w = os.pipe()
            passed = [out_w, err_w]
        forked, ident = Forked(out_r, err_r, sock, in_w), next(self._ids)
        self._jobs[ident] = forked
        try:
            with self._send:
                socket.send_fds(sock, [json.dumps({"id": ident, **job}).encode()], passed)
        except OSError:
            self._jobs.pop(ident, None)
            forked.close()
            return None
        finally:
            for fd in passed:
                os.close(fd)
        if not forked.forked.wait(FORK_WAIT) or not forked.pid:  # the server is stuck or gone
            self._jobs.pop(ident, None)
            forked.close()
            return None
        if resident:
            self.started += 1
        else:
            self.forks += 1
        return forked

    def spare(self, module: str, argv: Sequence[str], cwd: str, env: Mapping[str, str]) -> Child | None:
        """Where commands are not forked: a spare given the command, or None when none is left."""
        with self._lock:
            spares = [p for p in self._spares if p.poll() is None]
            proc, self._spares = (spares[0], spares[1:]) if spares else (None, [])
        if proc is None:
            return None
        stdin = proc.stdin
        assert stdin is not None
        job = json.dumps({"module": module, "argv": list(argv), "cwd": cwd, "env": dict(env)}) + "\n"

        def send() -> None:  # a thread: the spare reads its job only once its imports are done
            with contextlib.suppress(OSError):  # ended before it read its job: its outcome says so
                stdin.write(job.encode())
            with contextlib.suppress(OSError):
                stdin.close()

        threading.Thread(target=send, daemon=True).start()
        return proc

    def close(self) -> None:
        """End the commands still running (they are in groups of their own), the spares, then the fork server."""
        with self._lock:
            spares, self._spares = self._spares, []
        for proc in [*spares, *RUNNING]:
            end(proc)
            with contextlib.suppress(subprocess.TimeoutExpired):
                proc.wait(timeout=5)
        for proc in spares:
            for pipe in (proc.stdin, proc.stdout, proc.stderr):
                if pipe is not None:
                    pipe.close()
        with self._lock:
            server, sock, self.server, self._socket, self.ready = self.server, self._socket, None, None, False
        if sock is not None:
            with contextlib.suppress(OSError):
                sock.close()
        if server is not None:
            end(server)
            server.wait()


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

    A gains change (0.1 s of work, at each option changed) would otherwise be a process forked, its pipes
    and its end. A job that runs past its time limit, or whose client goes away, ends the process (the
    next is started when the app is idle); while the resident is busy or starting, a job runs the
    ordinary way, forked or in a fresh process, so nothing queues behind it. One per Python process,
    whatever the event loops: its answers are read in a thread, not through a loop's pipe transport.
    """

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self.proc: Child | None = None
        self.ready = False
        self.busy = False
        self.starting = False  # a thread is getting the process (waiting for the fork server to be ready)
        self._closes = 0  # times closed: a process got for an earlier start, after a close, is ended at once
        self.jobs = 0  # jobs run so far (for tests and benchmarks)

    def start_soon(self) -> None:
        """Start the process (when none runs or is starting): forked by the fork server once that is ready, its
        imports already done there; a Python of its own where commands are not forked or the server cannot be had.
        It is ready once it says so (a thread waits for it)."""
        if not _warm_enabled():
            return
        with self._lock:
            if self.busy or self.starting or (self.proc is not None and self.proc.poll() is None):
                return
            self.starting, self.ready, closes = True, False, self._closes
        threading.Thread(target=self._start, args=(closes,), daemon=True).start()

    def _start(self, closes: int) -> None:
        proc: Child | None = None
        try:
            if FORKING and POOL.wait_ready():
                proc = POOL.fork("motorlab.ui.warm", ["--serve"], tempfile.gettempdir(), {}, resident=True)
            if proc is None:
                proc = POOL.spawn("--serve")
        finally:
            with self._lock:
                self.starting = False
                late = proc is not None and self._closes != closes
                if proc is not None and not late:
                    self.proc = proc
        if late:  # closed meanwhile (the app ending, a test): this one is not wanted
            _close_child(proc)
        elif proc is not None:
            self._wait_ready(proc)

    def _wait_ready(self, proc: Child) -> None:
        assert proc.stdout is not None
        with contextlib.suppress(OSError, ValueError):
            said = proc.stdout.readline().strip() == b"ready"
            with self._lock:
                if self.proc is proc:
                    self.ready = said

    async def start(self) -> None:
        """:meth:`start_soon`, then wait until the process is ready (or has ended)."""
        self.start_soon()
        while self.starting or (self.proc is not None and not self.ready and self.proc.poll() is None):
            await asyncio.sleep(0.05)

    def _take(self) -> Child | None:
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
        """End the process (and one being started)."""
        with self._lock:
            proc, self.proc, self.ready = self.proc, None, False
            self._closes += 1
        if proc is not None:
            _close_child(proc)


def _close_child(proc: Child) -> None:
    """End a child process, wait for its end (10 s at most) and close its pipes."""
    end(proc)
    with contextlib.suppress(subprocess.TimeoutExpired):
        proc.wait(timeout=10)
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
RUNNING: set[Child] = set()


def _start(module: str, argv: Sequence[str], cwd: str, env: Mapping[str, str]) -> Child:
    """A child running ``module argv`` in ``cwd``: forked by the fork server, or a fresh ``python -P -m``."""
    proc = (POOL.fork(module, argv, cwd, env) or POOL.spare(module, argv, cwd, env)) if _warm_enabled() else None
    if proc is None:  # the fork server is starting (or gone), or the spares are used up: a fresh process imports
        # only what its command needs
        POOL.fill()
        return subprocess.Popen(
            [sys.executable, "-P", "-m", module, *argv], cwd=cwd, env={**_child_env(), **env},
            stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE, **_OWN_GROUP,
        )
    return proc


async def _reader(pipe: IO[bytes]) -> tuple[asyncio.StreamReader, asyncio.BaseTransport]:
    loop = asyncio.get_running_loop()
    reader = asyncio.StreamReader(limit=1 << 24)
    transport, _ = await loop.connect_read_pipe(lambda: asyncio.StreamReaderProtocol(reader), pipe)
    return reader, transport


async def _collect(proc: Child, on_progress: Callable[[dict[str, Any]], None] | None) -> tuple[
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


#: Seconds after the last command ends before a resident worker (or fork server) that has gone is started again:
#: a new Python importing scipy takes a CPU for seconds, and on a two-core laptop the browser draws the answer's
#: figures in those first moments.
REFILL_DELAY = 1.5


def _refill_if_idle() -> None:
    """Start the fork server and the resident worker where they have gone, unless a command runs again."""
    if not RUNNING:
        POOL.fill()
        resident().start_soon()


def _reap(proc: Child) -> None:
    """Wait for an ended command's process, at most :data:`REAP_WAIT` s (a slot is never held for ever)."""
    with contextlib.suppress(subprocess.TimeoutExpired):
        proc.wait(timeout=REAP_WAIT)


#: Seconds to wait for the end of a command that was ended (SIGKILL: at once, unless the machine is stalled).
REAP_WAIT = 10.0


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
            if not RUNNING:  # idle: restart what has gone, soon (not while commands run: they need the CPU)
                asyncio.get_running_loop().call_later(REFILL_DELAY, _refill_if_idle)
            if running:  # reap it (in a thread: Popen.wait blocks)
                with contextlib.suppress(asyncio.CancelledError):
                    await asyncio.shield(asyncio.get_running_loop().run_in_executor(None, _reap, proc))
            for pipe in (proc.stdout, proc.stderr):  # closed already when read to their end
                if pipe is not None:
                    with contextlib.suppress(OSError):
                        pipe.close()
    return Outcome(int(proc.returncode or 0), out.decode("utf-8", "replace"), err.decode("utf-8", "replace"))


async def run_cli(argv: Sequence[str], *, cwd: str, time_limit: float | None = None, slot: str = "short",
                  on_progress: Callable[[dict[str, Any]], None] | None = None) -> Outcome:
    """Run ``motorlab argv...`` (the CLI's own entry, :func:`motorlab.cli.main`) in a child process."""
    return await run_module("motorlab", argv, cwd=cwd, time_limit=time_limit, slot=slot, on_progress=on_progress)
