"""LCR-meter readings (seed 1, "LCR Meter Experiment"): winding resistance and inductance."""

from __future__ import annotations

from typing import Any

from motorlab.experiments import Experiment, FromSession, Option, RigRun, Setting
from motorlab.experiments._shared import COLUMN, read_tables

OUTLIER_Z = 3.5  # as motorlab.analyses.lcr.OUTLIER_Z (checked by tests/experiments/test_registry.py)


def run(paths: list[str], v: dict[str, Any]) -> Any:
    """Run ``motorlab analyze lcr FILE...``."""
    from motorlab.analyses.lcr import lcr

    return lcr(read_tables(paths), frequency=v["frequency"], circuit=v["circuit"], threshold=v["outlier_z"])


def session(ctx: Any) -> FromSession:
    """The session's LCR readings, at the frequency its table gives."""
    return FromSession({"frequency": ctx.setting("frequency")})


EXPERIMENT = Experiment(
    name="lcr",
    title="LCR-meter readings",
    summary='Winding resistance and inductance from LCR-meter readings (seed 1, "LCR Meter Experiment")',
    analysis="motorlab.analyses.lcr:lcr",
    inputs="CSV of meter readings: L_uH/L_mH/L_H, Q and/or DCR_ohm (optionally frequency_Hz)",
    run=run,
    options=(
        Option("frequency", "Hz", positive=True, metavar="F", label="Test frequency",
               help="of the L and Q readings, e.g. 1000 or '1 kHz'; left empty: the file's frequency_Hz "
                    "column or '# frequency_Hz:' line, else 1 kHz"),
        Option("circuit", kind="choice", choices=("series", "parallel"), label="Equivalent circuit",
               help="the one the meter displayed; left empty: the file's '# circuit:' line, else series"),
        Option("outlier-z", "1", positive=True, default=OUTLIER_Z, metavar="Z", label="Outlier threshold",
               help="a reading whose modified z-score is above this is left out as an outlier"),
        COLUMN,
    ),
    reports=("R", "L", "R_dc"),
    shaft="electrical (motor terminals)",
    order=10,
    settings=(Setting("frequency", "Hz", "test frequency of the L/Q readings (default: file, else 1 kHz)"),),
    contributes={"R_dc": "R", "L": "L"},
    session=session,
    rig=RigRun("lcr", "lcr.csv", order=10),
)
