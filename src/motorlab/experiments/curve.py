"""A motor curve from a dynamometer or a datasheet: K, Kt, R, the free current and the friction."""

from __future__ import annotations

from typing import Any

from motorlab.experiments import Experiment, FromSession, Option, Setting
from motorlab.experiments._shared import COLUMN, read_tables


def run(paths: list[str], v: dict[str, Any]) -> Any:
    """Run ``motorlab analyze curve CURVE.csv...``."""
    from motorlab.analyses.curve import curve

    return curve(read_tables(paths), voltage=v["voltage"])


def session(ctx: Any) -> FromSession:
    """The session's curve of the bare motor, at the voltage its table gives (or its voltage column)."""
    return FromSession({"voltage": ctx.setting("voltage")})


EXPERIMENT = Experiment(
    name="curve",
    title="Motor curve (dynamometer or datasheet)",
    summary="K, torque per amp Kt, R, free current and friction from a steady-state motor curve at one voltage",
    analysis="motorlab.analyses.curve:curve",
    inputs="CSV rows of steady speed, torque and current from stall to free speed (a dynamometer's export "
           "such as VEX's 'Speed (RPM),Torque (N·m),Current (A),…', or speed_rpm, torque_Nm, current_A), "
           "with a voltage column or --voltage",
    run=run,
    options=(
        Option("voltage", "V", positive=True, metavar="VOLTS", label="Terminal voltage of the curve",
               help="the voltage every row was measured at, e.g. 12 for VEX's curves; needed when the file "
                    "has no voltage column nor supplied power"),
        COLUMN,
    ),
    reports=("K", "R", "Kt", "Kt_over_K", "I_free", "friction_torque", "b", "Tf"),
    shaft="motor shaft of the bare motor (no gearbox), physical torque",
    order=120,
    settings=(Setting("voltage", "V", "terminal voltage of the curve (when the file has no voltage column)"),),
    session=session,
)
