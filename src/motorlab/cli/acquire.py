"""``motorlab acquire INSTRUMENT ...``: read real instruments into the files ``motorlab analyze`` reads.

- ``acquire lcr --port PORT --readings N -o FILE``: a DER EE DE-5000 LCR meter over pyserial
  (a device or a URL such as ``socket://host:port``); ``--interactive`` asks before each shaft
  position.
- ``acquire terminal|free-spinup|spindown|spinup``: the seeds' bench experiments with a
  programmable supply (Korad KA3005P, Rigol DP800) as relay and current limit and a Rigol DS1000Z
  scope, through PyVISA (``--visa-library @sim`` runs them on the shipped pyvisa-sim profiles).
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

from motorlab.cli.common import positive_int, quantity


def register(subparsers: Any) -> None:
    """Add the ``acquire`` sub-command and its instruments."""
    parser = subparsers.add_parser(
        "acquire",
        help="read real instruments (LCR meter, bench supply, scope) into motorlab's files",
        description="Read real instruments into the files motorlab analyses (see docs/acquire.md).",
    )
    sub = parser.add_subparsers(dest="instrument", metavar="INSTRUMENT", parser_class=type(parser))
    sub.required = True
    p = sub.add_parser(
        "lcr", help="DER EE DE-5000 LCR meter (ES51919) over a serial port or URL",
        description="Take readings from a DER EE DE-5000 (9600 8N1, DTR on, RTS off) and write the CSV "
        "'motorlab analyze lcr' reads. Blank, OL and '----' displays are skipped.",
    )
    p.add_argument("--port", required=True,
                   help="serial device (/dev/ttyUSB0, COM3) or pyserial URL (socket://host:port, rfc2217://…)")
    p.add_argument("--readings", type=positive_int, default=10, help="readings to take (default 10: the seed's)")
    p.add_argument("-o", "--output", required=True, metavar="FILE", help="CSV to write (must not exist)")
    p.add_argument("--interactive", action="store_true",
                   help="ask before each reading (one per shaft position); q stops early")
    p.add_argument("--kind", choices=("auto", "inductance", "dc_resistance"), default="auto",
                   help="what the file holds: L with Q, or DC resistance (default: the first reading decides)")
    p.add_argument("--timeout", type=quantity("s", positive=True), default=10.0,
                   help="longest wait for one usable reading [s] (default 10)")
    p.add_argument("--rts", choices=("on", "off"), default="off", help="RTS line (default off)")
    p.add_argument("--dtr", choices=("on", "off"), default="on", help="DTR line (default on: powers the IR cable)")
    p.set_defaults(func=run_lcr)
    try:
        from motorlab.cli.acquire_bench import register_bench
    except ImportError:  # pragma: no cover - the bench part is optional
        return
    register_bench(sub)


def run_lcr(args: argparse.Namespace) -> int:
    """Run ``motorlab acquire lcr``."""
    from rich.console import Console
    from rich.progress import Progress

    from motorlab.acquire.lcr import acquire_lcr

    console = Console(stderr=True)
    if args.interactive:
        log = acquire_lcr(args.port, args.output, readings=args.readings, interactive=True, kind=args.kind,
                          timeout=args.timeout, rts=args.rts == "on", dtr=args.dtr == "on",
                          ask=_ask, report=console.print)
    else:
        # A progress bar on a terminal only (piped or captured output gets the plain messages).
        with Progress(console=console, transient=True, disable=not console.is_terminal) as bar:
            task = bar.add_task("DE-5000 readings", total=args.readings)
            log = acquire_lcr(args.port, args.output, readings=args.readings, kind=args.kind, timeout=args.timeout,
                              rts=args.rts == "on", dtr=args.dtr == "on", report=console.print,
                              progress=lambda done, total: bar.update(task, completed=done))
    what = "L/Q" if log.kind == "inductance" else "DC resistance"
    print(f"wrote {log.rows} {what} readings to {args.output}" if log.rows else "no reading taken; nothing written")
    return 0


def _ask(prompt: str) -> str:
    print(prompt, end="", file=sys.stderr, flush=True)
    line = sys.stdin.readline()
    return line if line else "q"  # end of input stops, as 'q'
