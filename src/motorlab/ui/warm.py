"""A warm child process of the app: motorlab, numpy, scipy and matplotlib imported, waiting for one command.

``python -P -m motorlab.ui.warm`` imports what the commands need, then reads ONE job from stdin, a
JSON line ``{"module": "motorlab" | "motorlab.ui.worker", "argv": [...], "cwd": ..., "env": {...}}``,
runs it exactly as ``python -m <module> argv...`` would (in ``cwd``, the CLI's own ``main``, its
stdout, stderr and exit code) and exits. One command per process: nothing of one request survives
into another, and the app can still end a command by ending its process (the time limit, a client
that went away). :mod:`motorlab.ui.runner` keeps spares started ahead, so a request does not wait
for Python and these imports (about 1 s, more on a busy machine).

``-P`` keeps the folder the process starts in off ``sys.path``, so that an uploaded file named like
a module (``numpy.py``) is never imported.
"""

from __future__ import annotations

import json
import os
import sys


def preload() -> None:
    """Import what the app's commands use (the parser, the analyses, the report's plotting)."""
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
    from motorlab.units import registry

    registry()  # pint's unit registry: parsing its definitions takes longer than most analyses
    _draw()


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


def main() -> int:
    """Preload, wait for the job on stdin, run it (``--serve``: run jobs until stdin closes)."""
    if sys.argv[1:] == ["--serve"]:
        return serve()
    preload()
    line = sys.stdin.readline()
    if not line.strip():  # the app went away before giving a job
        return 0
    devnull = os.open(os.devnull, os.O_RDONLY)
    os.dup2(devnull, 0)  # the command reads no input, as with stdin=DEVNULL
    code = run(json.loads(line))
    sys.stdout.flush()
    sys.stderr.flush()
    # The answer is out: end now. The interpreter's own shutdown (freeing every module of numpy, scipy,
    # matplotlib and motorlab) took 0.3-1.5 s after the answer, and the app waits for the process's end (the
    # pipes closing) to answer the click. The command closed its files itself; nothing is left to run at exit.
    os._exit(code)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
