"""``motorlab simulate stall``: a locked-rotor run on the virtual dynamometer, or a fitted model's forecast.

``--motor NAME -o RUN.csv``: the virtual dynamometer holds the shaft of a simulated unit and a voltage on
it while the winding heats (``time_s,voltage_V,current_A,torque_Nm`` and truth.json).
``--params FIT.json -o OUT.csv``: the model ``motorlab analyze stall --json`` fitted, stalled at
``--voltage`` for ``--duration`` from where the fitted run started (``time_s, current_A, torque_Nm,
winding_temperature_C, case_temperature_C``), with the answers: how long until the winding reaches
150 °C, the current held indefinitely for a 100 K rise, R hot against cold.
"""

from __future__ import annotations

import argparse
import math
from typing import Any

from motorlab.cli.common import nonnegative_int, print_json, quantity
from motorlab.errors import OptionError


def add_stall(sub: Any) -> None:
    """The ``stall`` sub-command of ``motorlab simulate``."""
    p = sub.add_parser(
        "stall", help="a locked-rotor run that heats (virtual dynamometer, --motor) or a fitted model's forecast "
        "(--params FIT.json)",
        description="With --motor: the virtual dynamometer holds the shaft and a voltage while the winding heats. "
        "With --params: the stall model 'motorlab analyze stall --json' fitted, stalled at --voltage.")
    p.add_argument("--params", metavar="FIT.json", help="what 'motorlab analyze stall --json' wrote")
    p.add_argument("--motor", help="catalogue key or name: simulate a run on the virtual dynamometer instead")
    p.add_argument("--voltage", type=quantity("V", positive=True), default=12.0, help="held voltage [V] (12)")
    p.add_argument("--duration", type=quantity("s", positive=True), default=60.0, help="length [s] (60)")
    p.add_argument("--initial-temperature", type=quantity("degC"), default=None, metavar="CELSIUS",
                   help="the winding's temperature at the start [°C] (default: where the fitted run started; "
                   "on the virtual dynamometer, 25 °C)")
    p.add_argument("--sample-interval", type=quantity("s", positive=True), default=None,
                   help="time between rows [s] (forecast 0.1 s; the virtual dynamometer 0.35 s as VEX's)")
    p.add_argument("--limit", type=quantity("degC"), default=150.0, metavar="CELSIUS",
                   help="the winding temperature of the 'how long' answer [°C] (150)")
    p.add_argument("--rise", type=quantity("K", positive=True), default=100.0,
                   help="the winding rise of the 'held indefinitely' answer [K] (100)")
    p.add_argument("--current-limit", type=quantity("A", positive=True), default=100.0,
                   help="the virtual dynamometer's supply current limit [A] (100)")
    p.add_argument("--unit-seed", type=nonnegative_int, default=0, help="which simulated unit (0: A)")
    p.add_argument("--noise-seed", type=nonnegative_int, default=0, help="seed of the reading noise (0)")
    p.add_argument("--json", action="store_true", help="print the answers as JSON")
    p.add_argument("-o", "--output", required=True, metavar="FILE.csv", help="file to write")
    p.set_defaults(func=run_stall)


def run_stall(args: argparse.Namespace) -> int:
    """Write the run or the forecast, print the answers."""
    from motorlab.io.output import check_not_inputs

    if (args.params is None) == (args.motor is None):
        raise OptionError("give either --params FIT.json (forecast a fitted model) or --motor NAME (simulate a run)")
    if args.params is not None:
        check_not_inputs([args.output], [args.params], option="-o")
        return _forecast(args)
    return _virtual(args)


def _forecast(args: argparse.Namespace) -> int:
    from motorlab.io.csv_table import write_csv
    from motorlab.thermal.forecast import answers_text, forecast, load_fit

    model = load_fit(args.params)
    out = forecast(model, args.voltage, args.duration, initial_temperature=args.initial_temperature,
                   sample_interval=args.sample_interval or 0.1, limit=args.limit, rise=args.rise)
    columns = out.columns()
    if not math.isfinite(model.torque_constant):
        columns.pop("torque_Nm")
    write_csv(args.output, columns, metadata={"experiment": "stall forecast", "voltage_V": args.voltage,
                                              "fit": args.params.replace(":", "_")})
    if args.json:
        print_json({"output": args.output, "answers": out.answers, "warnings": out.warnings,
                    "final": {"current_A": float(out.current[-1]), "current_low_A": float(out.current_low[-1]),
                              "current_high_A": float(out.current_high[-1]),
                              "winding_temperature_C": float(out.winding_temperature[-1])}})
        return 0
    band = 0.5 * float(out.current_high[-1] - out.current_low[-1])
    print(f"stall forecast at {args.voltage:g} V for {args.duration:g} s: wrote {args.output} "
          f"(current {out.current[0]:.4g} -> {out.current[-1]:.4g} ± {band:.2g} A, 2 standard errors of the fit; "
          "winding "
          f"{out.winding_temperature[0]:.0f} -> {out.winding_temperature[-1]:.0f} °C)")
    for line in answers_text(out.answers):
        print(f"  {line}")
    for text in out.warnings:
        print(f"warning: {text}")
    return 0


def _virtual(args: argparse.Namespace) -> int:
    from motorlab.catalog import Motor
    from motorlab.rig import VirtualRig

    motor = Motor.from_catalog(args.motor)
    rig = VirtualRig(motor, unit_seed=args.unit_seed, noise_seed=args.noise_seed)
    settings: dict[str, Any] = {"voltage": args.voltage, "duration": args.duration,
                                "current_limit": args.current_limit, "initial_temperature": args.initial_temperature}
    if args.sample_interval is not None:
        settings["sample_interval"] = args.sample_interval
    result = rig.stall(args.output, **settings)
    print(f"stall: {rig.motor.key} unit {rig.unit}: wrote {result.paths[0]}; truth in {result.truth_path}")
    return 0
