"""LCR-meter readings (seed 1, "LCR Meter Experiment"): winding resistance and inductance."""

from __future__ import annotations

from typing import Any

from motorlab.experiments import Experiment, Option, RigRun, Setting
from motorlab.experiments._shared import COLUMN, read_tables

OUTLIER_Z = 3.5  # as motorlab.analyses.lcr.OUTLIER_Z (checked by tests/test_experiments.py)


def run(paths: list[str], v: dict[str, Any]) -> Any:
    """Run ``motorlab analyze lcr FILE...``."""
    from motorlab.analyses.lcr import lcr

    return lcr(read_tables(paths), frequency=v["frequency"], circuit=v["circuit"], threshold=v["outlier_z"])


def characterize(ctx: Any) -> Any:
    """The session's LCR readings."""
    from motorlab.analyses.lcr import lcr

    return lcr(read_tables(ctx.files), frequency=ctx.setting("frequency"))


EXPERIMENT = Experiment(
    name="lcr",
    summary='Winding resistance and inductance from LCR-meter readings (seed 1, "LCR Meter Experiment")',
    analysis="motorlab.analyses.lcr:lcr",
    inputs="CSV of meter readings: L_uH/L_mH/L_H, Q and/or DCR_ohm (optionally frequency_Hz)",
    run=run,
    options=(
        Option("frequency", "Hz", positive=True, metavar="F",
               help="test frequency of the L/Q readings [Hz], e.g. 1000 or '1 kHz' "
                    "(default: frequency_Hz column or '# frequency_Hz:' metadata, else 1 kHz)"),
        Option("circuit", kind="choice", choices=("series", "parallel"),
               help="equivalent circuit the meter displayed (default: '# circuit:' metadata, else series)"),
        Option("outlier-z", "1", positive=True, default=OUTLIER_Z, metavar="Z",
               help=f"modified z-score above which a reading is an outlier (default {OUTLIER_Z})"),
        COLUMN,
    ),
    reports=("R", "L", "R_dc"),
    shaft="electrical (motor terminals)",
    order=10,
    settings=(Setting("frequency", "Hz", "test frequency of the L/Q readings (default: file, else 1 kHz)"),),
    contributes={"R_dc": "R", "L": "L"},
    characterize=characterize,
    rig=RigRun("lcr", "lcr.csv", order=10),
)
