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

    import motorlab.characterize
    import motorlab.cli
    import motorlab.control
    import motorlab.feedforward
    import motorlab.identify
    import motorlab.io
    import motorlab.plot
    import motorlab.report
    import motorlab.session
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


def main() -> int:
    """Preload, wait for the job on stdin, run it."""
    preload()
    line = sys.stdin.readline()
    if not line.strip():  # the app went away before giving a job
        return 0
    devnull = os.open(os.devnull, os.O_RDONLY)
    os.dup2(devnull, 0)  # the command reads no input, as with stdin=DEVNULL
    code = run(json.loads(line))
    sys.stdout.flush()
    sys.stderr.flush()
    return code


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
