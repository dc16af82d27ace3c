"""``motorlab tune velocity|position``: controller gains from kS/kV/kA or from ``analyze --json`` output."""

from __future__ import annotations

import argparse
import math
from typing import Any

from motorlab.cli.common import check_figure_path, check_option, print_json, quantity
from motorlab.control.design import Feedforward
from motorlab.control.emit import LANGUAGES, emit_snippet
from motorlab.control.plant import UNIT_NAMES, MechanismUnits, Plant, load_plant
from motorlab.control.targets import TARGETS
from motorlab.control.tune import METHODS, TuneResult, tune
from motorlab.errors import OptionError


def _finite_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"{text!r} is not a finite number")
    return value


def _positive_float(text: str) -> float:
    value = _finite_float(text)
    if value <= 0:
        raise argparse.ArgumentTypeError(f"{text!r} must be positive")
    return value


def register(subparsers: Any) -> None:
    """Add the ``tune`` sub-command."""
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
    p.add_argument("loop", choices=("velocity", "position"), help="which quantity the loop controls")
    plant = p.add_argument_group("plant")
    plant.add_argument("--kv", type=_finite_float, help="velocity constant kV [V*s/unit]")
    plant.add_argument("--ka", type=_finite_float, help="acceleration constant kA [V*s^2/unit]")
    plant.add_argument("--ks", type=_finite_float, default=0.0, help="static friction voltage kS [V] (default 0)")
    plant.add_argument(
        "--params",
        action="append",
        metavar="FILE.json",
        help="motorlab analyze/characterize JSON with K, R, J (b, Tf, L) or kS, kV, kA; repeat to merge",
    )
    plant.add_argument(
        "--unit", metavar="NAME", help="which unit of a characterize results.json (required when it has several)"
    )
    plant.add_argument("--units", choices=UNIT_NAMES, default="rad", help="length unit of kV, kA, tolerances, step")
    plant.add_argument("--cpr", type=_positive_float, help="encoder counts per revolution of the shaft")
    plant.add_argument(
        "--wheel-radius", type=quantity("m", positive=True), help='lengths in metres at this radius ("2 in")'
    )
    d = p.add_argument_group("design")
    d.add_argument("--method", choices=METHODS, default="lqr", help="lqr (SysId's, default) or poles")
    d.add_argument("--qp", type=_positive_float, default=1.0, help="LQR position error tolerance [unit] (1)")
    d.add_argument("--qv", type=_positive_float, default=1.5, help="LQR velocity error tolerance [unit/s] (1.5)")
    d.add_argument("--r", type=quantity("V", positive=True), default=7.0, help="LQR control effort tolerance [V] (7)")
    d.add_argument("--period", type=quantity("s", positive=True), default=0.02, help="controller period [s] (0.02)")
    d.add_argument("--delay", type=quantity("s", nonnegative=True), default=0.0, help="measurement delay [s] (0)")
    d.add_argument("--rise-time", type=quantity("s", positive=True), help="poles: 10-90%% rise time [s]")
    d.add_argument("--overshoot", type=_finite_float, default=5.0, help="poles: largest overshoot [%%] (5)")
    o = p.add_argument_group("output")
    o.add_argument("--target", choices=TARGETS, default="volts", help="controller the gains are for (volts)")
    o.add_argument("--voltage", type=quantity("V", positive=True), default=12.0, help="supply voltage [V] (12)")
    o.add_argument("--step", type=_finite_float, help="step size [unit/s or unit] (half free speed / 1 rev)")
    o.add_argument("--json", action="store_true", help="print the result as JSON")
    o.add_argument("--plot", metavar="FILE.png", help="save step and profile responses to an image")
    o.add_argument("--emit", choices=LANGUAGES, help="print a ready-to-paste snippet in this language")
    p.set_defaults(func=run)


def plant_from_args(args: argparse.Namespace, units: MechanismUnits) -> Plant:
    """The plant from ``--params`` or ``--kv/--ka/--ks`` (converted to SI)."""
    given = args.kv is not None or args.ka is not None
    check_option(not (given and args.params), "give either --kv/--ka/--ks or --params, not both")
    if args.params:
        return load_plant(args.params, unit=args.unit)
    check_option(args.kv is not None and args.ka is not None, "give the plant: --kv and --ka, or --params FILE.json")
    # Numbers are per user unit: V·s/unit × unit/rad = V·s/rad.
    ff = Feedforward(args.ks, args.kv * units.per_radian, args.ka * units.per_radian).check_plant()
    return Plant(ff, None, "--kv/--ka/--ks")


def run(args: argparse.Namespace) -> int:
    """Run ``motorlab tune``."""
    if args.plot is not None:
        check_figure_path(args.plot)  # before the design and simulations, not after ("--plot ''" refused)
    units = MechanismUnits.from_options(args.units, cpr=args.cpr, wheel_radius=args.wheel_radius)
    if args.overshoot < 0 or args.overshoot >= 100:
        raise OptionError(f"--overshoot must be between 0 and 100 %, got {args.overshoot}")
    plant = plant_from_args(args, units)
    result = tune(
        plant,
        args.loop,
        method=args.method,
        target=args.target,
        units=units,
        qp=args.qp,
        qv=args.qv,
        r=args.r,
        period=args.period,
        delay=args.delay,
        rise_time=args.rise_time,
        overshoot=args.overshoot,
        voltage=args.voltage,
        step=args.step,
    )
    snippet = emit_snippet(result.target, args.emit) if args.emit else None
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
    lines.append(f"trapezoidal profile: largest tracking error {pr['max_tracking_error']:.4g}")
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
