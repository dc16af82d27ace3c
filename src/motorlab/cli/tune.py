"""``motorlab tune velocity|position``: controller gains from kS/kV/kA or from ``analyze --json`` output."""

from __future__ import annotations

import argparse
import math
from typing import Any

from motorlab.cli.analyze import add_options
from motorlab.cli.common import check_figure_path, check_option, print_json
from motorlab.control.design import Feedforward
from motorlab.control.emit import LANGUAGES, emit_snippet
from motorlab.control.plant import MechanismUnits, Plant, load_plant
from motorlab.control.targets import TARGET_INFO
from motorlab.control.tolerances import describe_settings
from motorlab.control.tune import DesignRequest, TuneResult, tune
from motorlab.errors import OptionError
from motorlab.experiments._commands import command_options


def register(subparsers: Any) -> None:
    """Add the ``tune`` sub-command: its options from :func:`motorlab.experiments._commands.command_options`."""
    p = subparsers.add_parser(
        "tune",
        help="controller gains (LQR as WPILib SysId, or pole placement) checked in closed-loop simulation",
        description=(
            "Design feedback gains for a velocity or position loop from the feedforward model "
            "(--kv/--ka/--ks, in volts and the unit given by --units) or from motorlab analyze --json "
            "output (--params), convert them to a controller's units (--target), simulate the closed "
            "loop on the motor model and report rise time, overshoot, settling time and steady-state error."
        ),
    )
    o = add_options(p, command_options("tune"))["output"]
    o.add_argument("--json", action="store_true", help="print the result as JSON")
    o.add_argument("--plot", metavar="FILE.png", help="save step and profile responses to an image")
    o.add_argument("--emit", choices=LANGUAGES, help="print a ready-to-paste snippet in this language")
    p.set_defaults(func=run)


def plant_from_args(args: argparse.Namespace) -> tuple[Plant, MechanismUnits]:
    """The plant from ``--params`` or ``--kv/--ka/--ks`` (converted to SI), and the user's length unit.

    The unit is ``--units``, else the one of the file the results were fitted from (kV per foot for a
    SysId file in Feet), else radians (metres for results fitted to distances).
    """
    given = args.kv is not None or args.ka is not None
    check_option(not (given and args.params), "give either --kv/--ka/--ks or --params, not both")
    if args.params:
        plant = load_plant(args.params, unit=args.unit)
        return plant, plant.units(args.units, cpr=args.cpr, wheel_radius=args.wheel_radius)
    units = MechanismUnits.from_options(args.units or "rad", cpr=args.cpr, wheel_radius=args.wheel_radius)
    check_option(args.kv is not None and args.ka is not None, "give the plant: --kv and --ka, or --params FILE.json")
    # Numbers are per user unit: V·s/unit × unit/rad = V·s/rad.
    ff = Feedforward(args.ks, args.kv * units.per_radian, args.ka * units.per_radian).check_plant()
    return Plant(ff, None, "--kv/--ka/--ks"), units


def run(args: argparse.Namespace) -> int:
    """Run ``motorlab tune``."""
    if args.plot is not None:
        check_figure_path(args.plot)  # before the design and simulations, not after ("--plot ''" refused)
    if args.overshoot < 0 or args.overshoot >= 100:
        raise OptionError(f"--overshoot must be between 0 and 100 %, got {args.overshoot}")
    plant, units = plant_from_args(args)
    request = DesignRequest(
        args.loop,
        method=args.method,
        target=args.target,
        units=units,
        qp=args.qp,
        qv=args.qv,
        r=args.r,
        period=TARGET_INFO[args.target].period if args.period is None else args.period,
        delay=TARGET_INFO[args.target].delay if args.delay is None else args.delay,
        rise_time=args.rise_time,
        overshoot=args.overshoot,
        voltage=args.voltage,
    )
    result = tune(plant, request, step=args.step)
    snippet = emit_snippet(result.target, args.emit, drive=args.drive) if args.emit else None
    if args.plot is not None:
        import matplotlib

        matplotlib.use("Agg")
        fig = result.plot()
        fig.savefig(args.plot, dpi=110)
    if args.json:
        out = result.to_dict()
        if snippet is not None:
            out["snippet"] = snippet
        print_json(out)
    elif snippet is not None:
        print(snippet, end="")
    else:
        print(format_result(result))
    return 0


def _fmt(value: float | None, unit: str = "", scale: float = 1.0) -> str:
    if value is None or not math.isfinite(value):
        return "not reached"
    return f"{value * scale:.4g}{(' ' + unit) if unit else ''}"


def format_result(result: TuneResult) -> str:
    """The plain-text report of ``motorlab tune``."""
    d = result.to_dict()
    u = d["units"]
    lines = [f"{d['loop']} loop, {d['method']} design, target {d['target']} (period {result.gains.period:g} s)"]
    if result.gains.method == "lqr":
        lines.append(f"design:      tolerances of {describe_settings(result.gains.settings)}")
    lines.append("gains:       " + ", ".join(f"{k} = {v:.6g} {u.get(k, '')}" for k, v in d["gains"].items()))
    lines.append("feedforward: " + ", ".join(f"{k} = {v:.6g} {u.get(k, '')}" for k, v in d["feedforward"].items()))
    r = d["response"]
    lines.append(
        f"simulated step of {d['step']['size']:.4g} {u['velocity'] if d['loop'] == 'velocity' else u['position']} "
        f"on the {d['design']['simulated_on']} model: rise time {_fmt(r['rise_time'], 'ms', 1e3)}, "
        f"overshoot {_fmt(r['overshoot'], '%')}, settling time {_fmt(r['settling_time'], 'ms', 1e3)}, "
        f"steady-state error {_fmt(r['steady_state_error'], u['steady_state_error'])}"
    )
    pr = d["profile"]
    tracked = u["velocity"] if d["loop"] == "velocity" else u["position"]
    lines.append(f"{'velocity ramp' if d['loop'] == 'velocity' else 'trapezoidal profile'}: largest tracking error "
                 f"{pr['max_tracking_error']:.4g} {tracked}")
    mp = d["max_profile"]
    pos = u["position"]
    lines.append(
        f"fastest profile at {mp['voltage']:g} V ({100 * mp['headroom']:.0f} % kept for feedback): "
        f"max velocity {mp['max_velocity']:.4g} {pos}/s, max acceleration {mp['max_acceleration']:.4g} {pos}/s^2 "
        f"(free speed {mp['free_speed']:.4g} {pos}/s, acceleration from rest {mp['stall_acceleration']:.4g} {pos}/s^2)"
    )
    lines.extend(f"conversion: {c}" for c in d["conversion"])
    lines.extend(f"note: {n}" for n in d["notes"])
    lines.extend(f"warning: {w}" for w in d["warnings"])
    return "\n".join(lines)
