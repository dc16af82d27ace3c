"""``motorlab robot pull|record|push|emulate``: the robot link over Wi-Fi (docs/robot.md)."""

from __future__ import annotations

import argparse
import contextlib
import math
import signal
import sys
import tempfile
import threading
from pathlib import Path
from typing import Any

from motorlab.cli.common import EXIT_PARTIAL, print_json, quantity
from motorlab.robot import DEFAULT_DASHBOARD_PORT, DEFAULT_HOST, DEFAULT_HTTP_PORT, RobotLinkError

#: FTC Dashboard versions ``robot emulate`` plays (motorlab.robot.emulator.DASHBOARD_VERSIONS; kept here so
#: that the parser does not import the emulator).
DASHBOARD_VERSIONS = ("0.4.10", "0.4.11", "0.4.12", "0.4.13", "0.4.14", "0.4.15", "0.4.16", "0.4.17", "0.5.0",
                      "0.5.1", "0.6.0")


def _port(text: str) -> int:
    if not text.strip().isdigit() or not 0 < int(text) < 65536:
        raise argparse.ArgumentTypeError(f"{text!r} is not a port number (1-65535)")
    return int(text)


def _host(text: str) -> str:
    if not text or any(c in text for c in "/\\@ ?#") or text.startswith("-"):
        raise argparse.ArgumentTypeError(f"{text!r} is not a host name or address (give it like 192.168.43.1)")
    return text


def _seconds(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of seconds") from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"{text!r} must be a positive number of seconds")
    return value


def _address(p: argparse.ArgumentParser, *, http: bool = False, dashboard: bool = False) -> None:
    p.add_argument("--host", type=_host, default=DEFAULT_HOST,
                   help=f"the robot's address, the only one contacted ({DEFAULT_HOST}: a Control Hub; 192.168.49.1: "
                        "a phone)")
    if http:
        p.add_argument("--http-port", type=_port, default=DEFAULT_HTTP_PORT,
                       help=f"the robot controller's web server port ({DEFAULT_HTTP_PORT})")
    if dashboard:
        p.add_argument("--dashboard-port", type=_port, default=DEFAULT_DASHBOARD_PORT,
                       help=f"FTC Dashboard's WebSocket port ({DEFAULT_DASHBOARD_PORT})")
    p.add_argument("--timeout", type=_seconds, default=5.0, help="seconds to wait for each answer (5)")


def register(subparsers: Any) -> None:
    """Add the ``robot`` sub-command: pull, record, push, emulate."""
    parser = subparsers.add_parser(
        "robot", help="the robot link: pull its logs, record a run through FTC Dashboard, write gains back",
        description="Talk to an FTC robot over its Wi-Fi (only the address given): Road Runner's files and "
                    "motorlab's logs over HTTP, FTC Dashboard's WebSocket for runs and @Config fields "
                    "(docs/robot.md).")
    sub = parser.add_subparsers(dest="action", metavar="ACTION", parser_class=type(parser))
    sub.required = True
    p = sub.add_parser("pull", help="bring back Road Runner's tuning files, FlightRecorder logs and motorlab's logs",
                       description="Download every file the robot serves, byte for byte under its own name "
                                   "(DIR/tuning/<type>/, DIR/logs/, DIR/motorlab/), and propose each one's analysis.")
    _address(p, http=True)
    p.add_argument("-o", "--output", required=True, metavar="DIR", help="folder to write into (made if missing)")
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    p.set_defaults(func=run_pull)

    p = sub.add_parser("record", help="init and start an OpMode through FTC Dashboard and record its telemetry",
                       description="Init and start the OpMode named (this command is the start button), record "
                                   "its telemetry with the battery voltage into a CSV motorlab reads, and stop it "
                                   "after --seconds, at Ctrl-C, or when the connection drops.")
    _address(p, http=True, dashboard=True)
    p.add_argument("--opmode", required=True, metavar="NAME", help="the OpMode, as the Driver Station lists it")
    p.add_argument("--seconds", type=_seconds, default=30.0, help="stop after this many seconds (30; at most 600)")
    p.add_argument("--cpr", type=quantity("dimensionless", positive=True),
                   help="encoder counts per revolution, written into the log for analyze")
    p.add_argument("-o", "--output", required=True, metavar="LOG.csv", help="the log to write")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    p.set_defaults(func=run_record)

    _register_push(sub)
    p = sub.add_parser("emulate", help="an emulated robot on 127.0.0.1 (Road Runner routes, motorlab logs, Dashboard)",
                       description="Serve an emulated robot on 127.0.0.1 for demos and tests: Road Runner's "
                                   "HTTP routes, motorlab's log handler and FTC Dashboard's WebSocket.")
    p.add_argument("--http-port", type=_port, default=DEFAULT_HTTP_PORT, help="web server port (8080)")
    p.add_argument("--dashboard-port", type=_port, default=DEFAULT_DASHBOARD_PORT, help="Dashboard port (8000)")
    p.add_argument("--serve", metavar="DIR", help="serve DIR/tuning/<type>/*.json, DIR/logs/*, DIR/motorlab/* "
                                                 "(default: simulated files)")
    p.add_argument("--seconds", type=_seconds, default=600.0, help="stop by itself after this many seconds (600)")
    p.add_argument("--dashboard-version", default="0.6.0", choices=DASHBOARD_VERSIONS,
                   help="the FTC Dashboard version to behave as (0.6.0; teams run 0.4.x and 0.5.0 most)")
    p.add_argument("--disabled", action="store_true", help="a Dashboard disabled on the robot (its menu's "
                                                           "\"Disable Dashboard\")")
    p.set_defaults(func=run_emulate)


def _register_push(sub: Any) -> None:
    p = sub.add_parser("push", help="write a fit's gains into the robot's @Config fields (and --restore them)",
                       description="Read the robot's @Config tree through FTC Dashboard, find the target's fields, "
                                   "show old and new values, write only those after confirmation, read them back, "
                                   "and keep the old values for --restore.")
    _address(p, dashboard=True)
    p.add_argument("--params", action="append", metavar="FIT.json", help="motorlab analyze/characterize JSON")
    p.add_argument("--target", choices=("roadrunner", "pedro", "ftc-pidf"), help="whose fields the gains go to")
    p.add_argument("--config", action="append", metavar="PATH",
                   help="the fields: NAME=CLASS.FIELD.leaf (e.g. kS=MyDrive.PARAMS.kS) or a node CLASS.FIELD")
    p.add_argument("--cpr", type=quantity("dimensionless", positive=True),
                   help="encoder counts per revolution (roadrunner: gains per tick)")
    p.add_argument("--wheel-radius", type=quantity("m", positive=True), help="wheel radius (pedro: inches)")
    p.add_argument("--unit", metavar="NAME", help="which unit of a characterize results.json")
    p.add_argument("--voltage", type=quantity("V", positive=True), default=12.0, help="nominal battery voltage (12)")
    p.add_argument("--state", metavar="FILE",
                   help="where the old values are kept (FIT.robot-push.json beside --params)")
    p.add_argument("--yes", action="store_true", help="write without asking")
    p.add_argument("--while-running", action="store_true", help="write even while an OpMode runs (confirmed)")
    p.add_argument("--restore", action="store_true", help="put back the values the last push replaced")
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    p.set_defaults(func=run_push)


def run_pull(args: argparse.Namespace) -> int:
    """Run ``motorlab robot pull``: 0 every file came, 3 (partial) some failed (each named on stderr in one
    line), 2 nothing could be pulled."""
    from motorlab.robot.pull import pull

    result = pull(args.host, args.output, http_port=args.http_port, timeout=args.timeout)
    for line in result.failed:
        print(f"motorlab: not pulled: {line}", file=sys.stderr)
    code = EXIT_PARTIAL if result.failed else 0
    if args.json:
        print_json(result.to_dict())
        return code
    for f in result.files:
        print(f"{f.path}  {f.size} bytes  ({'already there' if f.status == 'same' else f.status})")
        if f.command:
            print(f"    {f.experiment}: {f.command}")
        if f.note:
            print(f"    note: {f.note}")
    for line in result.missing:
        print(f"note: {line}")
    if not result.files:
        print(f"nothing to pull from {result.address}")
    if result.failed:
        print(f"{len(result.files)} files pulled, {len(result.failed)} not (named above): exit code 3 (partial)")
    return code


def run_record(args: argparse.Namespace) -> int:
    """Run ``motorlab robot record``: Ctrl-C stops the OpMode at once and keeps what was recorded."""
    from motorlab.robot.record import RAMP_LOGGERS, Recorder, latest_ramp_name, write_log

    ramp_kind = RAMP_LOGGERS.get(args.opmode)
    before = latest_ramp_name(args.host, args.http_port, ramp_kind, timeout=args.timeout) if ramp_kind else None
    recorder = Recorder(args.host, args.dashboard_port, args.opmode, seconds=args.seconds, timeout=args.timeout)
    outcome: dict[str, Any] = {}
    done = threading.Event()  # not Thread.join: a join interrupted by Ctrl-C can return early afterwards (CPython)

    def work() -> None:
        try:
            outcome["data"] = recorder.run()
        except BaseException as exc:  # handed to the main thread
            outcome["error"] = exc
        finally:
            done.set()

    # Ctrl-C stops the robot even in a process started with SIGINT ignored (a script's background job,
    # where Python leaves it ignored): `kill -INT` is then the way to stop it, and it must work.
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.default_int_handler)
    thread = threading.Thread(target=work, name="motorlab-record", daemon=True)
    print(f"recording {args.opmode!r} on {args.host}:{args.dashboard_port} for up to {args.seconds:g} s "
          "(Ctrl-C stops the robot)", file=sys.stderr)
    thread.start()
    try:
        while not done.wait(0.05):
            pass
    except KeyboardInterrupt:
        recorder.stop("Ctrl-C")
        done.wait(RECONNECT_WAIT)
    if not done.is_set():
        raise RobotLinkError("the recorder did not finish after Ctrl-C: THE OPMODE MAY STILL BE RUNNING, press STOP "
                             "on the Driver Station")
    if "error" in outcome:
        raise outcome["error"]
    data = outcome["data"]
    if data.still_running:  # said first: writing the log may fail (no telemetry) and must not hide it
        print("motorlab: error: the OpMode may still be running: press STOP on the Driver Station "
              f"({data.stop_reason})", file=sys.stderr)
    elif ramp_kind and not data.rows:
        return _ramp_file(args, data, ramp_kind, before)
    summary = write_log(data, args.output, host=f"{args.host}:{args.dashboard_port}", cpr=args.cpr)
    if args.json:
        print_json({"output": args.output, **summary})
    else:
        print(f"{args.output}: {summary['rows']} rows; columns " +
              ", ".join(f"{k!r} -> {c}" for k, c in summary["columns"].items()) + f"; {summary['stop_reason']}")
        for key, value in summary["skipped"].items():
            print(f"note: telemetry key {key!r} is not a number ({value!r}): left out")
        print(f"analyse with: motorlab analyze feedforward {args.output}" + ("" if args.cpr else " --cpr N"))
    return 2 if data.still_running else 0


def _ramp_file(args: argparse.Namespace, data: Any, kind: str, before: str | None) -> int:
    """Road Runner's ramp loggers send no telemetry: bring the file they saved when stopped."""
    from motorlab.robot.record import fetch_ramp_file

    folder = Path(args.output).parent
    path = fetch_ramp_file(args.host, args.http_port, kind, before, folder, timeout=args.timeout)
    print(f"{args.opmode} sends no telemetry to FTC Dashboard; {data.stop_reason}; its ramp file, saved on the "
          f"robot when it stopped: {path} ({path.stat().st_size} bytes, byte for byte)")
    print(f"analyse with: motorlab analyze feedforward {path} --cpr N")
    return 0


#: Seconds the main thread waits for the recorder after Ctrl-C (stop sent, last batch, log).
RECONNECT_WAIT = 5.0


def _table(changes: list[Any], old_label: str = "on the robot", new_label: str = "new") -> str:
    width = max(len(c.path) for c in changes)
    lines = [f"{'field':<{width}}  {old_label:>22}  {new_label:>22}"]
    lines += [f"{c.path:<{width}}  {c.old!s:>22}  {c.new!r:>22}" for c in changes]
    return "\n".join(lines)


def _confirm(question: str, yes: bool) -> None:
    if yes:
        return
    if not sys.stdin.isatty():
        raise RobotLinkError("nothing written: confirm with --yes (no terminal to ask on)")
    answer = input(f"{question} [y/N] ").strip().lower()
    if answer not in ("y", "yes"):
        raise RobotLinkError("nothing written (not confirmed)")


def run_push(args: argparse.Namespace) -> int:
    """Run ``motorlab robot push``."""
    from motorlab.robot.dashboard import Dashboard
    from motorlab.robot.push import LIFETIME, apply, prepare, restore, state_path, target_values

    state = state_path(args.params, args.state)
    if args.restore:
        with Dashboard(args.host, args.dashboard_port, timeout=args.timeout) as dash:
            def ask(changes: list[Any]) -> bool:
                print(_table(changes, "pushed", "to restore").replace(" new", " old"), file=sys.stderr)
                _confirm("Put these old values back on the robot?", args.yes)
                return True

            changes = restore(dash, state, while_running=args.while_running, confirm=ask)
        if args.json:
            print_json({"restored": [c.to_dict() for c in changes]})
        else:
            print("restored, read back and checked: " + ", ".join(f"{c.path} = {c.old!r}" for c in changes))
        return 0
    if not args.params or not args.target:
        raise RobotLinkError("give --params FIT.json and --target roadrunner|pedro|ftc-pidf (or --restore)")
    gains = target_values(args.params, args.target, cpr=args.cpr, wheel_radius=args.wheel_radius, unit=args.unit,
                          voltage=args.voltage)
    with Dashboard(args.host, args.dashboard_port, timeout=args.timeout) as dash:
        plan = prepare(dash, args.target, gains, args.config)
        if not args.json:
            print(_table(plan.changes))
        if plan.running:
            if not args.while_running:
                raise RobotLinkError(f"an OpMode is active on the robot ({plan.running}): stop it first, or add "
                                     "--while-running to write while it runs")
            _confirm(f"{plan.running} is running on the robot. Write anyway?", args.yes)
        _confirm(f"Write these {len(plan.changes)} values to the robot?", args.yes)
        apply(dash, plan, state, while_running=args.while_running)
    if args.json:
        print_json({**plan.to_dict(), "state": str(state), "verified": True})
        return 0
    print(f"written, read back and checked; old values kept in {state} (motorlab robot push --restore)")
    for line in plan.notes + gains.notes:
        print(f"note: {line}")
    print(f"note: {LIFETIME}")
    print(gains.snippet, end="" if gains.snippet.endswith("\n") else "\n")
    return 0


def run_emulate(args: argparse.Namespace) -> int:
    """Run ``motorlab robot emulate`` until its time is up or Ctrl-C."""
    from motorlab.robot.emulator import EmulatedRobot

    with tempfile.TemporaryDirectory(prefix="motorlab-robot-") as tmp:
        files = _served(Path(args.serve)) if args.serve else _demo_files(Path(tmp))
        robot = EmulatedRobot(files, http_port=args.http_port, dashboard_port=args.dashboard_port,
                              dashboard_version=args.dashboard_version, enabled=not args.disabled,
                              lifetime=args.seconds, max_requests=1_000_000)
        with robot:
            print(f"emulated robot on 127.0.0.1: web server :{robot.http_port}, FTC Dashboard "
                  f"{args.dashboard_version}{' (disabled)' if args.disabled else ''} :{robot.dashboard_port}; "
                  f"stops after {args.seconds:g} s or at Ctrl-C", file=sys.stderr)
            with contextlib.suppress(KeyboardInterrupt):
                robot._stopped.wait(args.seconds)
    return 0


def _served(folder: Path) -> Any:
    from motorlab.robot.emulator import TUNING_TYPES, RobotFiles

    if not folder.is_dir():
        raise RobotLinkError(f"{folder}: not a folder")
    tuning = {t: sorted((folder / "tuning" / t).glob("*.json")) for t in TUNING_TYPES}
    return RobotFiles({t: f for t, f in tuning.items() if f},
                      sorted(p for p in (folder / "logs").glob("*") if p.is_file()),
                      sorted(p for p in (folder / "motorlab").glob("*") if p.is_file()))


def _demo_files(folder: Path) -> Any:
    from motorlab.rig.ftc import simulate_flight_log, simulate_ramp
    from motorlab.robot.emulator import RobotFiles

    (folder / "forward-ramp").mkdir()
    ramp = folder / "forward-ramp" / "1732521600000.json"
    simulate_ramp(ramp, kind="forward", seed=1)
    (folder / "logs").mkdir()
    log = folder / "logs" / "2026_11_25__10_31_07_123__AutoOpMode.log"
    simulate_flight_log(log, seed=1)
    return RobotFiles({"forward-ramp": [ramp]}, [log], [])
