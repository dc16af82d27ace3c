"""The ``motorlab`` command: a thin layer over the library.

Each sub-command lives in its own module of this package with ``register(subparsers)``, which adds
its parser and sets ``func(args) -> int``. Every :class:`~motorlab.errors.MotorlabError` and every
unreadable path becomes one line on stderr and exit code 2, never a traceback; anything else is a bug
and becomes one line asking for a report, exit code 1.
"""

from __future__ import annotations

import os

# One BLAS thread (set before numpy loads): motorlab's fits are tall and thin (rows × 3 to 50
# parameters), where OpenBLAS's threads only spin — on a 2-core machine they added a third to the
# CPU time of `analyze feedforward` on 2 M rows. An explicit setting of the user's is kept.
for _name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "1")

import functools  # noqa: E402
import importlib  # noqa: E402
import sys  # noqa: E402
import warnings  # noqa: E402
from collections.abc import Sequence  # noqa: E402
from typing import TextIO  # noqa: E402

from motorlab import progress  # noqa: E402
from motorlab.cli.common import EXIT_INPUT, EXIT_INTERNAL, Parser, is_numerical_failure, numerical_failure_message  # noqa: E402
from motorlab.errors import MotorlabError  # noqa: E402

#: Sub-command modules, in the order ``motorlab --help`` lists them.
COMMANDS = ("demo", "motors", "plan", "simulate", "analyze", "tune", "characterize", "acquire", "robot", "ui")


@functools.cache
def build_parser(command: str | None = None) -> Parser:
    """The top-level parser with every sub-command registered, or only ``command`` when it is one of
    :data:`COMMANDS` (``main`` passes the one given: the others' modules, such as ``tune``'s controller
    design, cost a few tenths of a second to import).

    Built once per process and command: a parser keeps nothing of a parse (every value is in the
    namespace it returns), and building one took 25–35 ms of every command (``analyze``'s thirteen
    experiments' options), paid again by each command the app forks from its fork server (which
    builds them all, :func:`motorlab.ui.warm.preload`) and by each in-process call of :func:`main`.
    """
    from motorlab import __version__

    parser = Parser(prog="motorlab", description="Characterize brushed DC gearmotors from measurements.")
    parser.add_argument("--version", action="version", version=f"motorlab {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=Parser)
    sub.required = True
    for name in (command,) if command in COMMANDS else COMMANDS:
        importlib.import_module(f"motorlab.cli.{name}").register(sub)
    return parser


def _one_line_warning(
    pending: list[str],
    message: Warning | str,
    category: type[Warning],
    filename: str,
    lineno: int,
    file: TextIO | None = None,
    line: str | None = None,
) -> None:
    """A Python warning (numpy's overflow, matplotlib's …) as one line, not two with source code.

    Kept in ``pending`` and printed when the command has finished: when it ends in a refusal, the
    warnings were symptoms of the same bad input and the refusal's one line says all.
    """
    text = " ".join(str(message).split())
    pending.append(f"motorlab: warning: {category.__name__}: {text} ({os.path.basename(filename)}:{lineno})")


def _progress_reporter() -> progress.Reporter:
    """JSON lines on stderr for the browser app (``MOTORLAB_PROGRESS=json``), else a bar on a terminal."""
    if os.environ.get("MOTORLAB_PROGRESS") == "json":
        return progress.JsonLines()
    return progress.Terminal()


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the console script; returns the exit code.

    Exit codes: 0 success; 2 input refused (a :class:`~motorlab.errors.MotorlabError`, an unreadable
    or unwritable path, an argparse error); 3 ``characterize``/``demo`` wrote their results but some
    analyses failed (each unit's status says why); 1 an internal error (a bug: one line asks for a
    report; set ``MOTORLAB_TRACEBACK=1`` to see the traceback); 130 interrupted.
    """
    given = list(sys.argv[1:] if argv is None else argv)
    nul = next((str(a) for a in given if "\0" in str(a)), None)
    if nul is not None:  # a script's argv can hold one; no file name or value can (the OS refuses it)
        print(f"motorlab: error: {nul.replace(chr(0), '?')[:80]!r}: contains a NUL byte", file=sys.stderr)
        return EXIT_INPUT
    parser = build_parser(str(given[0]) if given else None)
    args = parser.parse_args(given)
    pending: list[str] = []
    reporter = _progress_reporter()
    try:
        with warnings.catch_warnings(), progress.reporting(reporter):  # both restored when the command returns
            warnings.showwarning = functools.partial(_one_line_warning, pending)
            code = int(args.func(args) or 0)
        for line in pending:
            print(line, file=sys.stderr)
        return code
    except MotorlabError as exc:
        print(f"motorlab: error: {exc}", file=sys.stderr)
        return EXIT_INPUT
    except BrokenPipeError:
        return 0
    except OSError as exc:
        # Paths the user gave that cannot be read or written (missing folder, a file where a folder
        # should be, a full disk): the user's to fix, so one line and exit 2 like any bad input.
        where = getattr(exc, "filename", None) or ""
        reason = exc.strerror or type(exc).__name__
        print(f"motorlab: error: {where}: {reason}" if where else f"motorlab: error: {reason}", file=sys.stderr)
        return EXIT_INPUT
    except KeyboardInterrupt:
        print("motorlab: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:  # last resort: a bug must not greet the user with a traceback
        if is_numerical_failure(exc):  # absurd numbers in the input: the user's to fix (exit 2)
            print(f"motorlab: error: {numerical_failure_message(exc, args)}", file=sys.stderr)
            return EXIT_INPUT
        for line in pending:  # a bug: what numpy said on the way may help the report
            print(line, file=sys.stderr)
        if os.environ.get("MOTORLAB_TRACEBACK"):
            raise
        detail = " ".join(str(exc).split()) or "no message"
        print(
            f"motorlab: internal error: {type(exc).__name__}: {detail} "
            "(please report, with the command; MOTORLAB_TRACEBACK=1 shows where)",
            file=sys.stderr,
        )
        return EXIT_INTERNAL
    finally:
        if isinstance(reporter, progress.Terminal):
            reporter.close()


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
