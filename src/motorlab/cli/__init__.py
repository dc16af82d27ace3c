"""The ``motorlab`` command: a thin layer over the library.

Each sub-command lives in its own module of this package with ``register(subparsers)``, which adds
its parser and sets ``func(args) -> int``. Every :class:`~motorlab.errors.MotorlabError` and every
unreadable path becomes one line on stderr and exit code 2, never a traceback.
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Sequence

from motorlab.cli.common import EXIT_INPUT, Parser
from motorlab.errors import MotorlabError

#: Sub-command modules, in the order ``motorlab --help`` lists them.
COMMANDS = ("demo", "motors", "plan", "simulate", "analyze", "tune", "characterize")


def build_parser() -> Parser:
    """The top-level parser with every sub-command registered."""
    from motorlab import __version__

    parser = Parser(prog="motorlab", description="Characterize brushed DC gearmotors from measurements.")
    parser.add_argument("--version", action="version", version=f"motorlab {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=Parser)
    sub.required = True
    for name in COMMANDS:
        try:
            module = importlib.import_module(f"motorlab.cli.{name}")
        except ModuleNotFoundError as exc:  # TODO(lead): remove once every command module exists
            if exc.name == f"motorlab.cli.{name}":
                continue
            raise
        module.register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the console script; returns the exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except MotorlabError as exc:
        print(f"motorlab: error: {exc}", file=sys.stderr)
        return EXIT_INPUT
    except (FileNotFoundError, IsADirectoryError, PermissionError, NotADirectoryError) as exc:
        where = getattr(exc, "filename", None) or ""
        reason = exc.strerror or type(exc).__name__
        print(f"motorlab: error: {where}: {reason}" if where else f"motorlab: error: {reason}", file=sys.stderr)
        return EXIT_INPUT
    except KeyboardInterrupt:
        print("motorlab: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
