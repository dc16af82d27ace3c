"""``motorlab motors [KEY]``: list the motor catalogue, or show one motor with its sources."""

from __future__ import annotations

import argparse
import math
from typing import Any

from motorlab.catalog import Motor, list_motors
from motorlab.cli.common import print_json, quantity
from motorlab.units import format_unit

RPM_PER_RAD_S = 60.0 / (2.0 * math.pi)


def register(subparsers: Any) -> None:
    """Add the ``motors`` sub-command."""
    parser = subparsers.add_parser(
        "motors",
        help="list the motor catalogue or show one motor",
        description="List the catalogue of FTC-legal gearmotors (figures at the output shaft, nominal "
        "voltage), or show one motor with the source of every figure and its nominal model parameters.",
    )
    parser.add_argument("key", nargs="?", help="motor key or name, e.g. neverest40 or 'NeveRest 40'")
    parser.add_argument(
        "--voltage",
        type=quantity("V", positive=True),
        default=None,
        help="supply voltage for the derived figures (default: the motor's nominal voltage)",
    )
    parser.add_argument("--json", action="store_true", help="machine-readable output")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Print the table or one motor; errors are raised as OptionError (exit code 2)."""
    if args.key is None:
        motors = list_motors()
        if args.json:
            print_json([m.to_dict() for m in motors])
        else:
            _print_table(motors)
        return 0
    motor = Motor.from_catalog(args.key)
    voltage = motor.nominal_voltage if args.voltage is None else args.voltage
    params = motor.nominal_params()
    figures = params.figures(voltage)
    # The model's stall torque and power are before the gearbox's efficiency; at the output they are η times them.
    eta = motor.gearbox().efficiency
    figures["stall torque at the output (× gearbox η)"] = (eta * figures["stall torque"][0], "N*m")
    figures["peak power at the output (× gearbox η)"] = (eta * figures["peak power"][0], "W")
    if args.json:
        out = motor.to_dict()
        out["nominal_params"] = {
            name: {"value": value, "unit": unit}
            for (name, value), unit in zip(params.to_dict().items(), params.units().values(), strict=True)
        }
        out["figures"] = {
            "voltage": {"value": voltage, "unit": "V"},
            **{name: {"value": _finite(v), "unit": u} for name, (v, u) in figures.items()},
        }
        print_json(out)
    else:
        _print_one(motor, voltage, params.to_dict(), params.units(), figures)
    return 0


def _finite(value: float) -> float | None:
    return value if math.isfinite(value) else None


def _mark(motor: Motor, name: str, text: str) -> str:
    """Append a '?' to figures that could not be confirmed."""
    return text + "?" if name in motor.unconfirmed else text


def _print_table(motors: list[Motor]) -> None:
    from rich.console import Console
    from rich.table import Table

    table = Table(title="Motor catalogue (output shaft, nominal voltage; ? = unconfirmed)")
    for header in ("key", "name", "ratio", "cpr", "V", "free rpm", "stall N·m", "stall A", "free A"):
        table.add_column(header, justify="left" if header in ("key", "name") else "right")
    for m in motors:
        table.add_row(
            m.key,
            m.name,
            _mark(m, "gear_ratio", f"{m.gear_ratio:.4g}"),
            _mark(m, "cpr", f"{m.cpr:g}"),
            _mark(m, "nominal_voltage", f"{m.nominal_voltage:g}"),
            _mark(m, "free_speed", f"{m.free_speed * RPM_PER_RAD_S:.0f}"),
            _mark(m, "stall_torque", f"{m.stall_torque:.3g}"),
            _mark(m, "stall_current", f"{m.stall_current:g}"),
            _mark(m, "free_current", f"{m.free_current:g}"),
        )
    Console(width=160).print(table)


def _print_one(
    motor: Motor,
    voltage: float,
    params: dict[str, float],
    units: dict[str, str],
    figures: dict[str, tuple[float, str]],
) -> None:
    from rich.console import Console
    from rich.markup import escape
    from rich.table import Table

    console = Console(width=160)
    console.print(f"[bold]{motor.key}[/bold]: {escape(motor.name)}")
    sheet = Table(title="Data-sheet figures (output shaft)")
    for header in ("figure", "value", "confirmed", "source"):
        sheet.add_column(header)
    rows = [
        ("gear_ratio", f"{motor.gear_ratio:.6g}:1"),
        ("cpr", f"{motor.cpr:g} counts/rev"),
        ("nominal_voltage", f"{motor.nominal_voltage:g} V"),
        ("free_speed", f"{motor.free_speed:.4g} rad/s ({motor.free_speed * RPM_PER_RAD_S:.4g} rpm)"),
        ("stall_torque", f"{motor.stall_torque:.4g} N·m"),
        ("stall_current", f"{motor.stall_current:.4g} A"),
        ("free_current", f"{motor.free_current:.4g} A"),
    ]
    if motor.motor_cpr is not None:
        rows.append(("motor_cpr", f"{motor.motor_cpr:g} counts/rev"))
    if motor.motor_free_speed is not None:
        rows.append(("motor_free_speed", f"{motor.motor_free_speed * RPM_PER_RAD_S:.5g} rpm"))
    if motor.inductance is not None:
        rows.append(("inductance", f"{motor.inductance * 1e6:.4g} µH"))
    for name, text in rows:
        confirmed = "no" if name in motor.unconfirmed else "yes"
        sheet.add_row(name, text, confirmed, escape(motor.sources.get(name, "")))
    console.print(sheet)
    derived = Table(title="WPILib-style derivations")
    derived.add_column("constant")
    derived.add_column("value", justify="right")
    derived.add_row("R = V/I_stall", f"{motor.resistance:.4g} Ω")
    derived.add_row("Kt = τ_stall/I_stall", f"{motor.torque_constant:.4g} N·m/A")
    derived.add_row("Ke = (V − R·I_free)/ω_free", f"{motor.back_emf_constant:.4g} V·s/rad")
    derived.add_row("Kt/Ke (gearbox efficiency at stall)", f"{motor.gearbox_efficiency_at_stall:.2f}")
    box = motor.gearbox()
    derived.add_row("gearbox η = τ_stall/(Ke·I_stall − Tf)", f"{box.efficiency:.3f}")
    derived.add_row("gearbox loss torque τ0 (assumed ½ of Tf·η)", f"{box.loss_torque:.3g} N·m")
    console.print(derived)
    nominal = Table(title="Nominal model parameters (assumptions: docs/catalog.md)")
    nominal.add_column("parameter")
    nominal.add_column("value", justify="right")
    for name, value in params.items():
        nominal.add_row(name, f"{value:.4g} {format_unit(units[name])}")
    console.print(nominal)
    fig = Table(title=f"Model figures at {voltage:g} V")
    fig.add_column("figure")
    fig.add_column("value", justify="right")
    for name, (value, unit) in figures.items():
        shown = "" if unit == "1" else " " + format_unit(unit)
        fig.add_row(name, f"{value:.4g}{shown}")
    console.print(fig)
    if motor.note:
        console.print(f"[italic]Note:[/italic] {escape(motor.note)}")
