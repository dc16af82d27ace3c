"""``motorlab ui [--port P] [--host H] [--no-browser]``: the local browser app (docs/ui.md)."""

from __future__ import annotations

import argparse
from typing import Any

from motorlab.cli.common import positive_int


def register(subparsers: Any) -> None:
    """Add the ``ui`` sub-command."""
    p = subparsers.add_parser(
        "ui",
        help="a local browser app: drop logs, see the fits, copy the gains",
        description="Serve the motorlab app on this machine and open it in the browser. It binds 127.0.0.1 "
        "unless --host says otherwise; another host prints a warning and the URL carries a token.",
    )
    p.add_argument("--port", type=positive_int, default=8765, help="TCP port (default 8765)")
    p.add_argument("--host", default="127.0.0.1", help="address to bind (default 127.0.0.1: this machine only)")
    p.add_argument("--no-browser", action="store_true", help="print the URL, do not open a browser")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Serve until interrupted."""
    from motorlab.ui.app import serve

    serve(host=args.host, port=args.port, open_browser=not args.no_browser)
    return 0
