"""The app's fork server: motorlab, numpy, scipy and matplotlib imported once, each command forked from it.

``python -P -m motorlab.ui.warm --fork-server FD`` imports what the commands need, says it is ready on
the Unix socket ``FD`` (a ``SOCK_SEQPACKET`` pair of :mod:`motorlab.ui.runner`), then forks one child
per job it receives there: a JSON message ``{"id", "module": "motorlab" | "motorlab.ui.worker",
"argv": [...], "cwd", "env"}`` with two file descriptors, the write ends of the command's stdout and
stderr pipes. The child runs the job exactly as ``python -m <module> argv...`` would (in ``cwd``, the
CLI's own ``main``, its stdout, stderr and exit code) in a session of its own, and exits. The server
answers ``{"id", "pid"}`` when the child is forked and ``{"id", "exit"}`` when it has ended (its exit
code, or minus the signal that ended it). One command per process: nothing of one request survives into
another (the server itself runs none), and the app ends a command by ending its process group (the
time limit, a client that went away). A fork costs milliseconds; a new Python importing scipy costs
seconds of CPU (about 3 s on this project's 2-core build machine).

``--serve`` is the resident worker (:class:`motorlab.ui.runner.Resident`): jobs one after another in one
process, for the gains. The fork server forks it too, as the job ``{"module": "motorlab.ui.warm", "argv":
["--serve"]}`` with a third file descriptor, the read end of its stdin pipe: its imports are the server's, done
once for both (a second Python importing them took seconds of CPU at every start of the app). Without
arguments, where commands are not forked (:data:`motorlab.ui.runner.FORKING`:
not Linux), a spare: one job read from stdin, run, exit.

``-P`` keeps the folder the process starts in off ``sys.path``, so that an uploaded file named like
a module (``numpy.py``) is never imported.
"""

from __future__ import annotations

import json
import os
import sys

#: Whether :func:`preload` has run in this process (a resident forked from the fork server has its imports).
_preloaded = False


def preload() -> None:
    """Import what the app's commands use (the parser, the analyses, the report's plotting); once a process."""
    global _preloaded
    if _preloaded:
        return
    import importlib
    import pkgutil

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.figure
    import matplotlib.pyplot
    import numpy  # noqa: F401
    import scipy.linalg
    import scipy.optimize
    import scipy.signal
    import scipy.stats  # noqa: F401

    import motorlab.analyses.feedforward
    import motorlab.analyses.identify
    import motorlab.analyses.sysid_score  # a SysId file's open-loop fit (imported by the fit, not by the module)
    import motorlab.cli
    import motorlab.control
    import motorlab.io
    import motorlab.plot
    import motorlab.report.document
    import motorlab.session.characterize
    import motorlab.session.spec
    import motorlab.thermal.warning
    import motorlab.ui.worker

    motorlab.cli.build_parser()  # imports every sub-command's module and the experiment descriptions
    for command in motorlab.cli.COMMANDS:  # each command's parser, as main builds it, ready in every forked child
        motorlab.cli.build_parser(command)
    for module in pkgutil.iter_modules(motorlab.analyses.__path__):  # the analyses their commands import when run
        importlib.import_module(f"motorlab.analyses.{module.name}")  # (once here, not once per session's unit)
    from motorlab.units import registry

    registry()  # pint's unit registry: parsing its definitions takes longer than most analyses
    from motorlab.catalog import list_motors

    list_motors()  # the catalogue parsed once here (0.12–0.16 s of pint), not in every session naming its motor
    _draw()
    _preloaded = True


def _draw() -> None:
    """Draw a small figure once: matplotlib's font look-up and text layout caches filled."""
    import io

    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(2, 1.5), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.subplots()
    ax.plot([0, 1], [0, 1], label="x")
    ax.set_xlabel("time [s]")
    ax.legend()
    fig.savefig(io.BytesIO(), format="png", dpi=40)


def run(job: dict[str, object]) -> int:
    """Run one job (see the module docstring); its exit code."""
    module, argv = str(job["module"]), [str(a) for a in job["argv"]]  # type: ignore[attr-defined]
    os.chdir(str(job["cwd"]))
    os.environ.update({str(k): str(v) for k, v in dict(job.get("env") or {}).items()})  # type: ignore[call-overload]
    sys.argv = [module, *argv]
    try:
        if module == "motorlab":
            from motorlab.cli import main as cli_main

            return int(cli_main(argv) or 0)
        if module == "motorlab.ui.worker":
            from motorlab.ui.worker import main as worker_main

            return int(worker_main(argv) or 0)
        if module == "motorlab.ui.warm" and argv == ["--serve"]:  # the resident worker, forked by the fork server
            return serve()
        print(f"motorlab: error: warm worker: unknown module {module!r}", file=sys.stderr)
        return 2
    except SystemExit as exc:  # argparse's --help and its one-line errors
        return exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)


def serve() -> int:
    """Preload, say ``ready``, then run jobs one after another: a JSON line in, a JSON line out.

    The resident worker of :mod:`motorlab.ui.runner` for the gains (pure computations on typed
    numbers, recomputed at each change of an option): ``{"code", "stdout", "stderr"}`` per job, what
    the command printed caught as text. The environment, working folder and pyplot's figures are put
    back after each job; the app ends the process (and starts another) when a job runs past its limit.
    """
    import contextlib
    import io
    import tempfile

    import matplotlib.pyplot as plt

    preload()
    answers = sys.stdout
    answers.write("ready\n")
    answers.flush()
    home, environment = tempfile.gettempdir(), dict(os.environ)
    for line in sys.stdin:
        if not line.strip():
            continue
        out, err = io.StringIO(), io.StringIO()
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                code = run(json.loads(line))
            except Exception as exc:  # a bug in one job must not end the worker
                print(f"motorlab: internal error: {type(exc).__name__}: {exc}", file=sys.stderr)
                code = 1
        os.environ.clear()
        os.environ.update(environment)
        os.chdir(home)
        plt.close("all")
        answers.write(json.dumps({"code": code, "stdout": out.getvalue(), "stderr": err.getvalue()}) + "\n")
        answers.flush()
    return 0


def _forked(job: dict[str, object], fds: list[int], inherited: list[int]) -> None:
    """In the forked child: a session of its own, the command's pipes as stdout and stderr (and stdin when a third
    descriptor came with the job, else nothing to read), run, exit."""
    import contextlib
    import signal

    code = 1
    try:
        signal.set_wakeup_fd(-1)
        signal.signal(signal.SIGCHLD, signal.SIG_DFL)
        for fd in inherited:
            os.close(fd)
        os.setsid()  # a process group of its own: ending the command ends what it started
        stdin = fds[2] if len(fds) > 2 else os.open(os.devnull, os.O_RDONLY)
        for target, fd in enumerate([stdin, fds[0], fds[1]]):
            os.dup2(fd, target)
            os.close(fd)
        code = run(job)
    except BaseException as exc:  # the child ends here: it never returns into the server's loop
        print(f"motorlab: internal error: {type(exc).__name__}: {exc}", file=sys.stderr)
    finally:
        with contextlib.suppress(Exception):
            sys.stdout.flush()
            sys.stderr.flush()
        # The answer is out: end now. The interpreter's own shutdown (freeing every module of numpy, scipy,
        # matplotlib and motorlab) took 0.3-1.5 s after the answer, and the app waits for the process's end to
        # answer the click. The command closed its files itself; nothing is left to run at exit.
        os._exit(code)


def fork_server(fd: int) -> int:
    """Preload, say ``ready`` on the socket ``fd``, then fork a child per job (see the module docstring) until
    the app closes its end."""
    import selectors
    import signal
    import socket

    preload()
    sock = socket.socket(fileno=fd)
    wake_r, wake_w = os.pipe()
    os.set_blocking(wake_w, False)
    signal.signal(signal.SIGCHLD, lambda *_: None)  # a child's end wakes the loop (the handler only has to exist)
    signal.set_wakeup_fd(wake_w)
    children: dict[int, object] = {}  # pid -> the job's id
    sock.sendall(b'{"ready": true}')
    selector = selectors.DefaultSelector()
    selector.register(sock, selectors.EVENT_READ)
    selector.register(wake_r, selectors.EVENT_READ)
    while True:
        for key, _ in selector.select():
            if key.fileobj is not sock:
                os.read(wake_r, 4096)
                continue
            message, fds, _, _ = socket.recv_fds(sock, 1 << 20, 3)
            if not message:  # the app closed its end: its commands were ended by it
                return 0
            job = json.loads(message)
            pid = os.fork()
            if pid == 0:
                _forked(job, fds, [sock.fileno(), wake_r, wake_w])
            for passed in fds:
                os.close(passed)
            children[pid] = job["id"]
            sock.sendall(json.dumps({"id": job["id"], "pid": pid}).encode())
        while children:
            try:
                pid, status = os.waitpid(-1, os.WNOHANG)
            except ChildProcessError:
                break
            if pid == 0:
                break
            if pid in children:
                ident = children.pop(pid)
                sock.sendall(json.dumps({"id": ident, "exit": os.waitstatus_to_exitcode(status)}).encode())


def one_job() -> int:
    """A spare, where commands are not forked: preload, wait for one job on stdin, run it, exit."""
    preload()
    line = sys.stdin.readline()
    if not line.strip():  # the app went away before giving a job
        return 0
    devnull = os.open(os.devnull, os.O_RDONLY)
    os.dup2(devnull, 0)  # the command reads no input, as with stdin=DEVNULL
    code = run(json.loads(line))
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)  # at once, as a forked child does (:func:`_forked`)


def main() -> int:
    """``--fork-server FD`` (the app's commands, Linux), ``--serve`` (its resident worker), or a spare."""
    if len(sys.argv) == 3 and sys.argv[1] == "--fork-server":
        return fork_server(int(sys.argv[2]))
    if sys.argv[1:] == ["--serve"]:
        return serve()
    if not sys.argv[1:]:
        return one_job()
    print("usage: python -P -m motorlab.ui.warm [--fork-server FD | --serve]", file=sys.stderr)
    return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
