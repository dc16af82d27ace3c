"""Tachometer gain (seed 2, "Tachometer Gain Constant"): Kt_tach from speed and tachometer voltage."""

from __future__ import annotations

from typing import Any

from motorlab.experiments import Experiment, Option, RigRun, Setting
from motorlab.experiments._shared import read_tables


def run(paths: list[str], v: dict[str, Any]) -> Any:
    """Run ``motorlab analyze tachometer FILE...``."""
    from motorlab.analyses.gains import tachometer

    return tachometer(read_tables(paths), nominal=v["nominal"])


def characterize(ctx: Any) -> Any:
    """The session's tachometer rows."""
    from motorlab.analyses.gains import tachometer

    return tachometer(read_tables(ctx.files), nominal=ctx.setting("nominal"))


EXPERIMENT = Experiment(
    name="tachometer",
    summary='Tachometer gain Kt_tach from speed and tachometer voltage (seed 2, "Tachometer Gain Constant")',
    analysis="motorlab.analyses.gains:tachometer",
    inputs="CSV of speed (speed_rpm or speed_rad_per_s) and tach_voltage_V",
    run=run,
    options=(
        Option("nominal", "V*s/rad", positive=True, metavar="GAIN",
               help="nominal gain to compare with [V*s/rad], e.g. '0.03 V*s/rad' or '3.1 V/(1000*rpm)'"),
    ),
    reports=("Kt_tach", "V0"),
    shaft="electrical",
    order=50,
    settings=(Setting("nominal", "V*s/rad", "nominal tachometer gain to compare with"),),
    characterize=characterize,
    rig=RigRun("tachometer", "tachometer.csv", order=80),
)
