"""``motorlab simulate EXPERIMENT --motor NAME [--unit-seed N] [--noise-seed N] [settings] -o FILE``.

Runs one experiment of the seeds on the virtual dynamometer (:mod:`motorlab.rig`) and writes the
file(s) a real rig gives plus ``truth.json`` beside them. ``spindown --split`` writes ``FILE`` and
``<stem>2<suffix>`` (``testFile.txt`` + ``testFile2.txt``). ``motorlab simulate session --motor NAME
--units 3 -o DIR`` writes a whole session (every experiment for several units) with its TOML file.
"""

from __future__ import annotations

import argparse
import os
from collections.abc import Callable
from typing import Any

from motorlab.cli.common import nonnegative_int, positive_int, quantity
from motorlab.cli.simulate_stall import add_stall
from motorlab.errors import OptionError

#: Sub-command help per experiment (seed section it reproduces).
_HELP = {
    "spindown": "seed 1 'Flywheel and INA219 Experiment': spin up the flywheel, coast (FTC log)",
    "spinup": "seed 1 'First Experiment': constant current into the flywheel (FTC log)",
    "free-spinup": "seed 1 'Free Motor Spin-Up': scope times of 20 rising edges (time_ms CSV)",
    "terminal": "seed 1 'Terminal Velocity': steady current and encoder frequency (CSV)",
    "lcr": "seed 1 'LCR Meter Experiment': L, Q, DCR at 10 positions, 1 kHz (CSV)",
    "torque": "seed 2 torque constant: lever arm on a scale (current_A,mass_kg CSV)",
    "amplifier": "seed 2 amplifier gain Ka (command_V,current_A CSV)",
    "tachometer": "seed 2 tachometer gain (speed_rpm,tach_voltage_V CSV)",
    "pulse": "seed 2 square-wave pulse through the amplifier, tachometer speed (CSV)",
    "transient": "voltage steps/ramps/random steps sampled at a fixed rate (CSV)",
    "sysid": "WPILib SysId quasistatic and dynamic tests (SysId JSON)",
}


def list_of(unit: str) -> Callable[[str], list[float]]:
    """argparse type: comma-separated quantities in ``unit`` (``"0.25,0.3,0.35"`` or ``"250 mA, 0.3 A"``)."""
    single = quantity(unit)

    def convert(text: str) -> list[float]:
        parts = [p for p in text.split(",") if p.strip()]
        if not parts:
            raise argparse.ArgumentTypeError("expected a comma-separated list")
        return [single(p) for p in parts]

    convert.__name__ = f"list of quantities in {unit}"
    return convert


def _common(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--motor", required=True, help="catalogue key or name, e.g. neverest40")
    parser.add_argument("--unit-seed", type=nonnegative_int, default=0,
                        help="which unit: 0 is unit A, 1 is B … (draws its true parameters; default 0)")
    parser.add_argument("--noise-seed", type=nonnegative_int, default=0,
                        help="seed of the reading noise and timing jitter (default 0)")
    parser.add_argument("-o", "--output", required=True, metavar="FILE", help="file to write")
    _gearbox_options(parser)


def _efficiency(text: str) -> str | float:
    """argparse type: ``catalog`` or an efficiency in (0, 1]."""
    if text.strip().lower() in ("catalog", "catalogue"):
        return "catalog"
    value = quantity("")(text)
    if not 0 < value <= 1:
        raise argparse.ArgumentTypeError(f"an efficiency must lie in (0, 1], got {text!r}")
    return value


def _gearbox_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--efficiency", type=_efficiency, default=None, metavar="ETA",
                        help="gearbox efficiency η in (0, 1] when the motor drives the load, or 'catalog' for the "
                        "catalogue's (derived from the sheet's stall torque); default: an ideal gearbox")
    parser.add_argument("--back-efficiency", type=_efficiency, default=None, metavar="ETA",
                        help="efficiency when the load back-drives the motor (default: --efficiency)")
    parser.add_argument("--loss-torque", type=quantity("N*m", nonnegative=True), default=None, metavar="TORQUE",
                        help="gearbox drag τ0 at the output shaft [N·m] (default: the catalogue's with "
                        "--efficiency, else 0)")


def gearbox_from_args(args: argparse.Namespace, motor: Any) -> Any:
    """The :class:`motorlab.gearbox.Gearbox` the options ask for (``None``: an ideal one)."""
    from dataclasses import replace

    from motorlab.gearbox import Gearbox

    if args.efficiency is None and args.back_efficiency is None and args.loss_torque is None:
        return None
    box = motor.gearbox() if args.efficiency is not None else Gearbox(ratio=motor.gear_ratio)
    if isinstance(args.efficiency, float):
        box = replace(box, efficiency=args.efficiency)
    if args.back_efficiency is not None:
        back = box.efficiency if args.back_efficiency == "catalog" else args.back_efficiency
        box = replace(box, back_efficiency=back)
    if args.loss_torque is not None:
        box = replace(box, loss_torque=args.loss_torque)
    return box


def register(subparsers: Any) -> None:
    """Add the ``simulate`` sub-command and one sub-parser per experiment."""
    parser = subparsers.add_parser(
        "simulate",
        help="run an experiment on the virtual dynamometer",
        description="Run one experiment of the seeds on a simulated unit of a catalogue motor and write "
        "the files a real rig gives, plus truth.json (true parameters, expected results, settings).",
    )
    sub = parser.add_subparsers(dest="experiment", metavar="EXPERIMENT", parser_class=type(parser))
    sub.required = True
    a = {name: sub.add_parser(name, help=text, description=text) for name, text in _HELP.items()}
    for p in a.values():
        _common(p)

    p = a["spindown"]
    p.add_argument("--voltage", type=quantity("V", positive=True), default=12.0,
                   help="supply voltage [V] (≤ 16 V: the INA219 is in circuit; default 12)")
    p.add_argument("--current-limit", type=quantity("A", positive=True), default=4.0,
                   help="supply current limit [A] (default 4)")
    p.add_argument("--on-time", type=quantity("s", positive=True), default=30.0, help="relay closed [s] (30)")
    p.add_argument("--coast-time", type=quantity("s", positive=True), default=60.0, help="coast logged [s] (60)")
    p.add_argument("--split", action="store_true",
                   help="write FILE and <stem>2<suffix> with blank lines and placeholder rows, as the OpMode")
    p.add_argument("--crlf", action="store_true", help="Windows line endings")

    p = a["spinup"]
    p.add_argument("--current", type=quantity("A"), default=2.0, help="supply current limit [A] (2)")
    p.add_argument("--voltage", type=quantity("V", positive=True), default=12.0, help="supply voltage [V] (12)")
    p.add_argument("--duration", type=quantity("s", positive=True), default=30.0, help="relay closed [s] (30)")
    p.add_argument("--coast-time", type=quantity("s", nonnegative=True), default=0.0, help="coast logged [s] (0)")

    p = a["free-spinup"]
    p.add_argument("--current", type=quantity("A"), default=0.5, help="supply current limit [A] (0.5)")
    p.add_argument("--voltage", type=quantity("V", positive=True), default=18.0, help="supply voltage [V] (18)")
    p.add_argument("--hand-speed", type=quantity("rad/s", nonnegative=True), default=None,
                   help="speed of the hand start [rad/s] (default 5 %% of the free speed)")
    p.add_argument("--edges", type=positive_int, default=20, help="rising edges recorded (20)")
    p.add_argument("--timebase", type=quantity("s", positive=True), default=None,
                   help="scope horizontal scale [s/div] (default: fine enough for the edges)")
    p.add_argument("--waveform", metavar="FILE", default=None, help="also write the Rigol waveform CSV")

    p = a["terminal"]
    p.add_argument("--currents", type=list_of("A"), default=None, help="current settings [A], comma-separated")
    p.add_argument("--voltage", type=quantity("V", positive=True), default=18.0, help="supply voltage [V] (18)")

    a["lcr"].add_argument("--positions", type=positive_int, default=10, help="shaft positions (10)")

    p = a["torque"]
    p.add_argument("--currents", type=list_of("A"), default=None, help="currents [A], comma-separated")
    p.add_argument("--arm", type=quantity("m", positive=True), default=0.15, help="lever arm [m] (0.15)")
    p.add_argument("--no-dither", action="store_true", help="no dither: stiction biases the readings")

    a["amplifier"].add_argument("--commands", type=list_of("V"), default=None, help="commands [V], comma-separated")
    a["tachometer"].add_argument("--commands", type=list_of("V"), default=None,
                                 help="amplifier commands [V], comma-separated")

    p = a["pulse"]
    p.add_argument("--amplitude", type=quantity("V", positive=True), default=1.0, help="high level [V] (1)")
    p.add_argument("--period", type=quantity("s", positive=True), default=2.0, help="period [s] (2)")
    p.add_argument("--duty", type=float, default=0.12, help="duty cycle (0.12)")
    p.add_argument("--periods", type=positive_int, default=1, help="periods recorded (1)")
    p.add_argument("--sample-interval", type=quantity("s", positive=True), default=1e-3,
                   help="scope sample interval [s] (1 ms)")
    p.add_argument("--flywheel", action="store_true", help="attach the flywheel")
    p.add_argument("--raw-tach", action="store_true", help="write tach_voltage_V instead of the speed")

    p = a["transient"]
    p.add_argument("--profile", choices=("steps", "ramps", "random"), default="steps", help="voltage profile")
    p.add_argument("--rate", type=quantity("Hz", positive=True), default=1000.0, help="sample rate [Hz] (1000)")
    p.add_argument("--duration", type=quantity("s", positive=True), default=4.0, help="length [s] (4)")
    p.add_argument("--max-voltage", type=quantity("V", positive=True), default=12.0, help="largest |V| (12)")
    p.add_argument("--no-current", action="store_true", help="do not log the current")
    p.add_argument("--flywheel", action="store_true", help="attach the flywheel")

    p = a["sysid"]
    p.add_argument("--ramp-rate", type=quantity("V/s", positive=True), default=0.25, help="quasistatic [V/s]")
    p.add_argument("--step-voltage", type=quantity("V", positive=True), default=7.0, help="dynamic step [V]")
    p.add_argument("--quasistatic-duration", type=quantity("s", positive=True), default=30.0, help="[s] (30)")
    p.add_argument("--dynamic-duration", type=quantity("s", positive=True), default=10.0, help="[s] (10)")
    p.add_argument("--no-flywheel", action="store_true", help="bare motor (kA hard to observe)")

    for p in a.values():
        p.set_defaults(func=run)

    _add_roadrunner_ramp(sub)
    _add_session(sub)
    add_stall(sub)


def _add_session(sub: Any) -> None:
    """``motorlab simulate session``: a whole simulated session (:func:`run_session`)."""
    session = sub.add_parser("session", help="a whole session: every experiment for several units",
                             description="Write a simulated session folder (data files, truth.json and "
                             "the session TOML) for several units of one motor.")
    session.add_argument("--motor", required=True, help="catalogue key or name")
    session.add_argument("--units", type=positive_int, default=3, help="number of units (3: A, B, C)")
    session.add_argument("--seed", type=nonnegative_int, default=0, help="noise seed (0)")
    session.add_argument("-o", "--output", required=True, metavar="DIR", help="folder to write")
    session.add_argument("--worn", metavar="UNIT", help="make one unit worn: its viscous friction b multiplied")
    session.add_argument("--wear", type=quantity("", positive=True), default=2.0, metavar="FACTOR",
                         help="factor applied to the worn unit's b (default 2)")
    session.add_argument("--efficiency", type=_efficiency, default=None, metavar="ETA",
                         help="'catalog' (each unit's gearbox drawn around the catalogue's) or one efficiency "
                         "for every unit; default: ideal gearboxes")
    session.add_argument("--worn-efficiency", type=quantity("", positive=True), default=1.0, metavar="FACTOR",
                         help="factor applied to the worn unit's gearbox efficiency (default 1)")
    session.set_defaults(func=run_session)


def _add_roadrunner_ramp(sub: Any) -> None:
    """``motorlab simulate roadrunner-ramp``: Road Runner's ramp loggers (:func:`run_roadrunner_ramp`)."""
    ramp = sub.add_parser("roadrunner-ramp", help="Road Runner 1.0's ramp logger on a simulated mecanum drive "
                          "(its JSON)", description="Simulate one of Road Runner's ramp loggers (ForwardRampLogger, "
                          "LateralRampLogger, AngularRampLogger) on a mecanum drive with 8192-count dead wheels "
                          "whose 16-bit velocities wrap, a 10-40 ms bulk-read loop and a sagging battery, and write "
                          "the JSON file the OpMode saves, plus truth.json (kS, kV, kA at the dead-wheel encoder).")
    ramp.add_argument("--kind", choices=("forward", "lateral", "angular"), default="forward",
                      help="which ramp (forward)")
    ramp.add_argument("--seed", type=nonnegative_int, default=0, help="noise and loop-timing seed (0)")
    ramp.add_argument("-o", "--output", required=True, metavar="FILE.json", help="file to write")
    ramp.set_defaults(func=run_roadrunner_ramp)


def _settings(args: argparse.Namespace) -> dict[str, Any]:
    """The experiment method's keyword settings from the parsed options."""
    e = args.experiment
    if e == "spindown":
        return {"voltage": args.voltage, "current_limit": args.current_limit, "on_time": args.on_time,
                "coast_time": args.coast_time, "split": args.split, "crlf": args.crlf}
    if e == "spinup":
        return {"current": args.current, "voltage": args.voltage, "duration": args.duration,
                "coast_time": args.coast_time}
    if e == "free-spinup":
        return {"current": args.current, "voltage": args.voltage, "hand_speed": args.hand_speed,
                "edges": args.edges, "timebase": args.timebase, "waveform": args.waveform}
    if e == "terminal":
        return {"currents": args.currents, "voltage": args.voltage}
    if e == "lcr":
        return {"positions": args.positions}
    if e == "torque":
        return {"currents": args.currents, "arm": args.arm, "dither": not args.no_dither}
    if e in ("amplifier", "tachometer"):
        return {"commands": args.commands}
    if e == "pulse":
        return {"amplitude": args.amplitude, "period": args.period, "duty": args.duty, "periods": args.periods,
                "sample_interval": args.sample_interval, "flywheel": args.flywheel, "raw_tach": args.raw_tach}
    if e == "transient":
        return {"profile": args.profile, "rate": args.rate, "duration": args.duration,
                "max_voltage": args.max_voltage, "include_current": not args.no_current, "flywheel": args.flywheel}
    if e == "sysid":
        return {"ramp_rate": args.ramp_rate, "step_voltage": args.step_voltage,
                "quasistatic_duration": args.quasistatic_duration, "dynamic_duration": args.dynamic_duration,
                "flywheel": not args.no_flywheel}
    raise OptionError(f"unknown experiment {e!r}")  # pragma: no cover - argparse restricts the choices


def check_voltage(voltage: float, name: str) -> None:
    """Refuse a drive voltage beyond :data:`motorlab.model.MAX_VOLTAGE` (the simulation would overflow)."""
    from motorlab.model import MAX_VOLTAGE

    if not abs(voltage) <= MAX_VOLTAGE:
        raise OptionError(f"{name} must be at most {MAX_VOLTAGE:g} V, got {voltage:g} V "
                          "(no brushed DC gearmotor runs on more)")


def check_sizes(args: argparse.Namespace) -> None:
    """Refuse settings whose run would be absurdly large (or its voltages absurd), naming the options.

    The limits are :data:`motorlab.rig.base.MAX_SAMPLES` (simulator steps, logged samples) and
    :data:`~motorlab.rig.base.MAX_READINGS` (readings taken by hand). ``--on-time 1e9`` asked the
    simulator for 7 TiB and ``--positions 1e8`` hung; the rig checks its simulations too, but here
    the message can name the options to change.

    Raises
    ------
    OptionError
        A setting that would exceed a limit.
    """
    from motorlab.rig.base import MAX_READINGS, check_size
    from motorlab.rig.virtual import FLYWHEEL_DT

    e = args.experiment
    ms = f"{FLYWHEEL_DT * 1e3:g} ms"
    if e == "spindown":
        check_size((args.on_time + args.coast_time) / FLYWHEEL_DT,
                   f"simulator steps of {ms} (--on-time + --coast-time)", hint="seed 1 runs 30 s + 60 s")
    elif e == "spinup":
        check_size((args.duration + args.coast_time) / FLYWHEEL_DT,
                   f"simulator steps of {ms} (--duration + --coast-time)", hint="seed 1 runs 30 s")
    elif e == "free-spinup":
        check_size(args.edges, "rising edges (--edges)", limit=MAX_READINGS, hint="seed 1 records 20")
    elif e == "lcr":
        check_size(args.positions, "shaft positions (--positions)", limit=MAX_READINGS, hint="seed 1 takes ten")
    elif e in ("terminal", "torque") and args.currents is not None:
        check_size(len(args.currents), "currents (--currents)", limit=MAX_READINGS)
    elif e in ("amplifier", "tachometer") and args.commands is not None:
        check_size(len(args.commands), "commands (--commands)", limit=MAX_READINGS)
    elif e == "pulse":
        check_size(args.period * args.periods / args.sample_interval,
                   "scope samples (--period × --periods / --sample-interval)", hint="a scope holds 12 Mpts at most")
    elif e == "transient":
        check_voltage(args.max_voltage, "the largest voltage (--max-voltage)")
        check_size(args.rate * args.duration, "samples (--rate × --duration)",
                   hint="1 kHz or 10 kHz for a few seconds is plenty")
    elif e == "sysid":
        check_voltage(args.step_voltage, "the dynamic step (--step-voltage)")
        check_voltage(args.ramp_rate * args.quasistatic_duration,
                      "the end of the quasistatic ramp (--ramp-rate × --quasistatic-duration)")
        from motorlab.rig.instruments import Instruments

        period = Instruments().controller.log_period
        check_size(max(args.quasistatic_duration, args.dynamic_duration) / period,
                   f"rows per test, one every {period * 1e3:g} ms (--quasistatic-duration, --dynamic-duration)",
                   hint="SysId's defaults are tens of seconds")


def run(args: argparse.Namespace) -> int:
    """Run the experiment; print the files written (errors: MotorlabError -> exit code 2)."""
    from motorlab.catalog import Motor
    from motorlab.rig import VirtualRig

    check_sizes(args)
    motor = Motor.from_catalog(args.motor)
    rig = VirtualRig(motor, unit_seed=args.unit_seed, noise_seed=args.noise_seed,
                     gearbox=gearbox_from_args(args, motor))
    result = rig.run(args.experiment, args.output, **_settings(args))
    files = " + ".join(str(p) for p in result.paths)
    print(f"{args.experiment}: {rig.motor.key} unit {rig.unit}: wrote {files}; truth in {result.truth_path}")
    return 0


def run_roadrunner_ramp(args: argparse.Namespace) -> int:
    """Write a simulated Road Runner ramp log (:func:`motorlab.rig.ftc.simulate_ramp`) and its truth."""
    from motorlab.rig.base import write_truth
    from motorlab.rig.ftc import simulate_ramp

    if not str(args.output).lower().endswith(".json"):
        raise OptionError(f"-o {args.output}: Road Runner's ramp logs are .json files")
    truth = simulate_ramp(args.output, kind=args.kind, seed=args.seed)
    where = write_truth(args.output, {"experiment": "roadrunner-ramp", "kind": args.kind, "seed": args.seed,
                                      "files": [os.path.basename(args.output)], "expected": truth})
    print(f"roadrunner-ramp: {args.kind} ramp: wrote {args.output}; truth in {where} "
          f"(analyse with --cpr {truth['cpr']:g})")
    return 0


def run_session(args: argparse.Namespace) -> int:
    """Write a simulated session with :func:`motorlab.session.spec.write_simulated_session`."""
    from motorlab.session.simulated import write_simulated_session

    degrade = {args.worn: {"b": args.wear, "efficiency": args.worn_efficiency}} if args.worn else None
    result = write_simulated_session(args.motor, units=args.units, out_dir=args.output, seed=args.seed,
                                     degrade=degrade, gearbox=args.efficiency)
    print(f"session: wrote {result}")
    return 0
