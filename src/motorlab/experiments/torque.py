"""Stall torque on a lever and scale (seed 1): the torque constant K."""

from __future__ import annotations

from typing import Any

from motorlab.experiments import Experiment, FromSession, Option, RigRun
from motorlab.experiments._shared import COLUMN, read_tables


def run(paths: list[str], v: dict[str, Any]) -> Any:
    """Run ``motorlab analyze torque FILE...``."""
    from motorlab.analyses.torque import torque

    return torque(read_tables(paths), arm=v["arm"], arm_stderr=v["arm_stderr"], ratio=v["ratio"],
                  motor_constant=v["motor_constant"], motor_constant_stderr=v["motor_constant_stderr"])


def session(ctx: Any) -> FromSession:
    """The session's torque rows with the rig's lever arm."""
    return FromSession({"arm": ctx.session.rig.lever_arm})


EXPERIMENT = Experiment(
    name="torque",
    title="Stall torque on a lever and scale",
    summary="Torque constant K from a lever arm on a scale at several currents (stall torque test)",
    analysis="motorlab.analyses.torque:torque",
    inputs="CSV of current_A (or current_mA) and scale readings mass_kg/mass_g (or torque_Nm)",
    run=run,
    options=(
        Option("arm", "m", positive=True, metavar="LENGTH", label="Lever arm length",
               help="from the shaft's axis to where the lever presses on the scale, e.g. 0.1 or '4 in'; left "
                    "empty: the file's '# arm_m:' line"),
        Option("arm-stderr", "m", nonnegative=True, default=0.0, metavar="LENGTH",
               label="Uncertainty of the lever arm", help="standard uncertainty of its length, added to K's"),
        Option("ratio", "", positive=True, default=1.0, metavar="N", label="Gear ratio",
               help="between the motor shaft and the lever's shaft"),
        Option("K", "V*s/rad", positive=True, dest="motor_constant", metavar="K_MOTOR",
               label="Back-EMF constant at the motor shaft",
               help="e.g. a spin-down's K ÷ the gear ratio when measured at the output: gives the gearbox's "
                    "efficiency and loss torque"),
        Option("K-stderr", "V*s/rad", nonnegative=True, default=0.0, dest="motor_constant_stderr", metavar="S",
               label="Uncertainty of that back-EMF constant", help="standard error, carried into the efficiency's"),
        COLUMN,
    ),
    reports=("K", "tau0", "tau_h", "efficiency", "loss_torque"),
    shaft="output (lever), physical torque, K = Kt = η·Ke",
    order=30,
    contributes={"K": "K"},
    loaded=True,
    session=session,
    rig=RigRun("torque", "torque.csv", order=30),
)
