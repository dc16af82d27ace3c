"""Stall torque on a lever and scale (seed 1): the torque constant K."""

from __future__ import annotations

from typing import Any

from motorlab.experiments import Experiment, Option, RigRun
from motorlab.experiments._shared import COLUMN, read_tables


def run(paths: list[str], v: dict[str, Any]) -> Any:
    """Run ``motorlab analyze torque FILE...``."""
    from motorlab.analyses.torque import torque

    return torque(read_tables(paths), arm=v["arm"], arm_stderr=v["arm_stderr"], ratio=v["ratio"],
                  motor_constant=v["motor_constant"], motor_constant_stderr=v["motor_constant_stderr"])


def characterize(ctx: Any) -> Any:
    """The session's torque rows with the rig's lever arm."""
    from motorlab.analyses.torque import torque

    return torque(read_tables(ctx.files), arm=ctx.session.rig.lever_arm)


EXPERIMENT = Experiment(
    name="torque",
    summary="Torque constant K from a lever arm on a scale at several currents (stall torque test)",
    analysis="motorlab.analyses.torque:torque",
    inputs="CSV of current_A (or current_mA) and scale readings mass_kg/mass_g (or torque_Nm)",
    run=run,
    options=(
        Option("arm", "m", positive=True, metavar="LENGTH",
               help="lever arm from the shaft axis to the scale contact [m], e.g. 0.1 or '4 in' "
                    "(default: '# arm_m:' in the file)"),
        Option("arm-stderr", "m", nonnegative=True, default=0.0, metavar="LENGTH",
               help="standard uncertainty of the arm length [m], added to K's standard error"),
        Option("ratio", "", positive=True, default=1.0, metavar="N",
               help="gear ratio between the motor shaft and the lever's shaft (default 1)"),
        Option("K", "V*s/rad", positive=True, dest="motor_constant", metavar="K_MOTOR",
               help="the motor's back-EMF constant at the MOTOR shaft [V·s/rad] (e.g. from spindown, ÷ N if "
                    "measured at the output): reports the gearbox efficiency and loss torque"),
        Option("K-stderr", "V*s/rad", nonnegative=True, default=0.0, dest="motor_constant_stderr", metavar="S",
               help="standard error of --K [V·s/rad], propagated into the efficiency's"),
        COLUMN,
    ),
    reports=("K", "tau0", "tau_h", "efficiency", "loss_torque"),
    shaft="output (lever), physical torque, K = Kt = η·Ke",
    order=30,
    contributes={"K": "K"},
    loaded=True,
    characterize=characterize,
    rig=RigRun("torque", "torque.csv", order=30),
)
