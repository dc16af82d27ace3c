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
from motorlab.cli.simulate import list_of
from motorlab.errors import OptionError


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
                   help="what the file holds: L with Q, or DC resistance (default auto: L/Q if the meter gives any)")
    p.add_argument("--timeout", type=quantity("s", positive=True), default=10.0,
                   help="longest wait for one usable reading [s] (default 10)")
    p.add_argument("--rts", choices=("on", "off"), default="off", help="RTS line (default off)")
    p.add_argument("--dtr", choices=("on", "off"), default="on", help="DTR line (default on: powers the IR cable)")
    p.set_defaults(func=run_lcr)
    _register_bench(sub)


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


_BENCH_HELP = {
    "terminal": "seed 1 'Terminal Velocity': steady current (supply) and encoder frequency (scope) per setting",
    "free-spinup": "seed 1 'Free Motor Spin-Up': rising-edge times of channel B from the scope's single sweep",
    "spindown": "seed 1 'Flywheel and INA219': the supply as relay, on then off; logs the supply's readback",
    "spinup": "seed 1 'First Experiment': constant current from the supply as relay; logs its readback",
}


def _register_bench(sub: Any) -> None:
    parsers = {}
    for name, text in _BENCH_HELP.items():
        p = sub.add_parser(name, help=text, description=text + ". Outputs off on Ctrl-C or any error.")
        p.add_argument("--supply", choices=("korad", "dp800"), required=True,
                       help="supply model: Korad KA3005P class or Rigol DP800 class")
        p.add_argument("--supply-resource", default=None, metavar="RES",
                       help="its VISA resource, e.g. ASRL/dev/ttyACM0::INSTR or TCPIP0::192.168.1.20::INSTR")
        p.add_argument("--channel", type=positive_int, default=1, help="DP800 output channel (default 1)")
        p.add_argument("--simulate", action="store_true",
                       help="rehearse on the shipped pyvisa-sim profiles instead of hardware (needs motorlab[sim])")
        p.add_argument("--ina219", choices=("yes", "no"), default=None,
                       help="an INA219 is in circuit: refuse more than 16 V (default: yes for spindown/spinup)")
        p.add_argument("--cpr", type=quantity("1", positive=True), default=None,
                       help="encoder counts per revolution, written as '# cpr:' for the analyses")
        p.add_argument("--motor", default=None, help="catalogue key, written as '# motor:'")
        p.add_argument("-o", "--output", required=True, metavar="FILE", help="CSV to write (must not exist)")
        p.set_defaults(func=run_bench)
        parsers[name] = p
    for name in ("terminal", "free-spinup"):
        parsers[name].add_argument("--scope", default=None, metavar="RES", help="DS1000Z VISA resource")
        parsers[name].add_argument("--scope-channel", type=positive_int, default=1,
                                   help="scope channel on the encoder's channel B (default 1)")
        parsers[name].add_argument("--voltage", type=quantity("V", positive=True), default=18.0,
                                   help="supply voltage [V] (default 18, the seed's)")
    p = parsers["terminal"]
    p.add_argument("--currents", type=list_of("A"), required=True, help="current settings [A], comma-separated")
    p.add_argument("--settle", type=quantity("s", positive=True), default=3.0, help="wait per setting [s] (3)")
    p.add_argument("--samples", type=positive_int, default=5, help="readings averaged per setting (5)")
    p = parsers["free-spinup"]
    p.add_argument("--current", type=quantity("A", positive=True), default=0.5, help="current limit [A] (0.5)")
    p.add_argument("--edges", type=positive_int, default=20, help="rising edges after the trigger edge (20)")
    p.add_argument("--timebase", type=quantity("s", positive=True), default=0.2, help="[s/div] (0.2)")
    p.add_argument("--level", type=quantity("V"), default=1.5, help="trigger level [V] (1.5)")
    p.add_argument("--wait", type=quantity("s", positive=True), default=30.0, help="longest wait for the trigger [s]")
    p.add_argument("--waveform", default=None, metavar="FILE", help="also write the waveform (Rigol CSV)")
    for name in ("spindown", "spinup"):
        p = parsers[name]
        p.add_argument("--voltage", type=quantity("V", positive=True), default=12.0, help="supply voltage [V] (12)")
        coast = 60.0 if name == "spindown" else 0.0
        p.add_argument("--coast-time", type=quantity("s", nonnegative=True), default=coast,
                       help="time logged after the output goes off [s]")
        p.add_argument("--poll", type=quantity("s", positive=True), default=0.1, help="supply readback interval [s]")
    parsers["spindown"].add_argument("--current-limit", type=quantity("A", positive=True), default=4.0,
                                     help="current limit [A] (4)")
    parsers["spindown"].add_argument("--on-time", type=quantity("s", positive=True), default=30.0,
                                     help="output on [s] (30)")
    parsers["spinup"].add_argument("--current", type=quantity("A", positive=True), default=2.0,
                                   help="current limit [A] (2)")
    parsers["spinup"].add_argument("--duration", type=quantity("s", positive=True), default=30.0,
                                   help="output on [s] (30)")


def _settings(args: argparse.Namespace) -> dict[str, Any]:
    name = args.instrument
    ina = (name in ("spindown", "spinup")) if args.ina219 is None else args.ina219 == "yes"
    common: dict[str, Any] = {"voltage": args.voltage, "ina219": ina}
    if name == "terminal":
        return {**common, "currents": args.currents, "settle": args.settle, "samples": args.samples}
    if name == "free-spinup":
        return {**common, "current": args.current, "edges": args.edges, "timebase": args.timebase,
                "level": args.level, "wait": args.wait, "waveform": args.waveform}
    if name == "spindown":
        return {**common, "current_limit": args.current_limit, "on_time": args.on_time,
                "coast_time": args.coast_time, "poll": args.poll}
    return {**common, "current": args.current, "duration": args.duration, "coast_time": args.coast_time,
            "poll": args.poll}


def run_bench(args: argparse.Namespace) -> int:
    """Run ``motorlab acquire terminal|free-spinup|spindown|spinup``."""
    from rich.console import Console
    from rich.progress import Progress

    from motorlab.acquire.bench import BenchRig
    from motorlab.acquire.lcr import check_new_output
    from motorlab.acquire.scpi import SIM_RESOURCES, SUPPLIES, RigolDP800, RigolDS1000Z, open_instrument

    check_new_output(args.output)
    if args.instrument == "free-spinup" and args.waveform:
        check_new_output(args.waveform)
    library = "@sim" if args.simulate else "@py"
    supply_res = args.supply_resource or (SIM_RESOURCES[args.supply] if args.simulate else None)
    if supply_res is None:
        raise OptionError("--supply-resource: give the supply's VISA resource (or --simulate to rehearse)")
    scope_res = getattr(args, "scope", None) or (SIM_RESOURCES["ds1000z"] if args.simulate else None)
    if args.instrument in ("terminal", "free-spinup") and scope_res is None:
        raise OptionError("--scope: give the scope's VISA resource (or --simulate to rehearse)")
    handle = open_instrument(supply_res, library=library, terminated=args.supply != "korad")
    supply = RigolDP800(handle, channel=args.channel) if args.supply == "dp800" else SUPPLIES[args.supply](handle)
    scope = None
    console = Console(stderr=True)
    try:
        if scope_res is not None and args.instrument in ("terminal", "free-spinup"):
            scope = RigolDS1000Z(open_instrument(scope_res, library=library), channel=args.scope_channel)
        with Progress(console=console, transient=True, disable=not console.is_terminal) as bar:
            task = bar.add_task(args.instrument, total=None)

            def progress(what: str, done: float, total: float) -> None:
                bar.update(task, description=what, completed=done, total=total)

            rig = BenchRig(supply, scope, cpr=args.cpr, motor=args.motor, progress=progress, report=console.print)
            run = rig.run(args.instrument, args.output, **_settings(args))
    finally:
        supply.close()
        if scope is not None:
            scope.close()
    print("wrote " + ", ".join(str(p) for p in run.paths))
    return 0
