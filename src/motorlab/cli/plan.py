"""``motorlab plan``: seed 1's flywheel rig design calculation for a catalogue motor."""

from __future__ import annotations

import argparse
import math
from typing import Any

from motorlab.catalog import Motor
from motorlab.cli.common import print_json, quantity
from motorlab.model.load import MATERIALS
from motorlab.rig.plan import plan_rig
from motorlab.units import format_unit

SECTION_TITLES = {
    "motor": "Motor (nominal, output shaft)",
    "target": "Target (constant torque, seed 1 eq. (5))",
    "flywheel": "Flywheel",
    "times": "Expected times (rig = motor + disc·N²)",
    "encoder": "Encoder against the log period",
    "sensors": "Sensors",
}


def register(subparsers: Any) -> None:
    """Add the ``plan`` sub-command."""
    parser = subparsers.add_parser(
        "plan",
        help="design a flywheel spin-up rig for a motor (seed 1, 'First Experiment')",
        description="The inertia a motor needs to reach a fraction of its free speed in a given time at a "
        "given current, the disc and gear ratio that give it, expected spin-up and coast times, encoder "
        "count rates against the log period, and sensor range checks.",
    )
    parser.add_argument("--motor", required=True, help="catalogue key or name (see `motorlab motors`)")
    parser.add_argument("--current", type=quantity("A", positive=True), help="drive current (default: stall/2)")
    parser.add_argument("--fraction", type=float, default=0.5, help="fraction of free speed to reach (default 0.5)")
    parser.add_argument("--time", type=quantity("s", positive=True), default=5.0, help="time to reach it (default 5 s)")
    parser.add_argument("--material", choices=sorted(MATERIALS), default="steel", help="disc material")
    parser.add_argument("--radius", type=quantity("m", positive=True), default=0.075, help="disc radius (0.075 m)")
    parser.add_argument(
        "--thickness", type=quantity("m", positive=True), default=0.05, help="disc thickness (0.05 m)"
    )
    parser.add_argument(
        "--ratio", type=quantity("", positive=True), default=1.0, help="step-up ratio motor→disc (default 1)"
    )
    parser.add_argument("--voltage", type=quantity("V", positive=True), help="supply voltage (default: nominal)")
    parser.add_argument(
        "--log-period", type=quantity("s", positive=True), default=0.1, help="log period (default 100 ms)"
    )
    parser.add_argument(
        "--free-speed", type=quantity("rad/s", positive=True), help="override the catalogue's free speed"
    )
    parser.add_argument(
        "--stall-torque", type=quantity("N*m", positive=True), help="override the catalogue's stall torque"
    )
    parser.add_argument("--arm", type=quantity("m", positive=True), help="torque-arm length to the scale")
    parser.add_argument("--scale-max", type=quantity("kg", positive=True), help="scale capacity")
    parser.add_argument(
        "--shunt", type=quantity("ohm", positive=True), default=0.1, help="INA219 shunt (default 0.1 ohm)"
    )
    parser.add_argument("--identification-log", action="store_true",
                        help="also recommend the rate, excitation and length of a log for `analyze identify` "
                        "(Cramér–Rao bound at the nominal model)")
    parser.add_argument("--json", action="store_true", help="machine-readable output")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Compute and print the plan."""
    motor = Motor.from_catalog(args.motor)
    plan = plan_rig(
        motor,
        current=args.current,
        fraction=args.fraction,
        time=args.time,
        material=args.material,
        radius=args.radius,
        thickness=args.thickness,
        ratio=args.ratio,
        voltage=args.voltage,
        log_period=args.log_period,
        free_speed=args.free_speed,
        stall_torque=args.stall_torque,
        lever_arm=args.arm,
        scale_capacity=args.scale_max,
        shunt_resistance=args.shunt,
    )
    ident = None
    if getattr(args, "identification_log", False):
        from motorlab.rig.plan import plan_identification_log

        ident = plan_identification_log(motor.nominal_params(), voltage=args.voltage or motor.nominal_voltage,
                                        cpr=motor.cpr)
    if args.json:
        print_json({**plan.to_dict(), **({"identification_log": ident} if ident else {})})
        return 0
    from rich.console import Console
    from rich.markup import escape
    from rich.table import Table

    console = Console(width=120)
    console.print(f"[bold]Rig plan for {escape(motor.name)}[/bold] ({motor.key})")
    for section, figures in plan.figures.items():
        table = Table(title=SECTION_TITLES.get(section, section), title_justify="left", show_header=False)
        table.add_column("figure")
        table.add_column("value", justify="right")
        table.add_column("unit")
        for fig in figures.values():
            table.add_row(escape(fig.label), _format(fig.value), _unit(fig.unit))
        console.print(table)
    for warning in plan.warnings:
        console.print(f"[yellow]warning:[/yellow] {escape(warning)}")
    if ident:
        console.print(f"identification log: {escape(ident['recommendation'])}")
    return 0


def _unit(unit: str) -> str:
    """Display form of a unit string ("kg/m^3" -> "kg/m³"; dimensionless -> "")."""
    return "" if unit == "1" else format_unit(unit).replace("^3", "³")


def _format(value: float) -> str:
    if math.isinf(value):
        return "never"
    return f"{value:.4g}"
