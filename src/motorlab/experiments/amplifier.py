"""Servo-amplifier gain (seed 2, "Amplifier Gain"): Ka from command voltage and output current."""

from __future__ import annotations

from typing import Any

from motorlab.experiments import Experiment, Option, RigRun, Setting
from motorlab.experiments._shared import read_tables


def run(paths: list[str], v: dict[str, Any]) -> Any:
    """Run ``motorlab analyze amplifier FILE...``."""
    from motorlab.analyses.gains import amplifier

    return amplifier(read_tables(paths), nominal=v["nominal"])


def characterize(ctx: Any) -> Any:
    """The session's amplifier rows."""
    from motorlab.analyses.gains import amplifier

    return amplifier(read_tables(ctx.files), nominal=ctx.setting("nominal"))


EXPERIMENT = Experiment(
    name="amplifier",
    summary='Servo-amplifier gain Ka from command voltage and output current (seed 2, "Amplifier Gain")',
    analysis="motorlab.analyses.gains:amplifier",
    inputs="CSV of command_V and current_A (or current_mA)",
    run=run,
    options=(
        Option("nominal", "A/V", positive=True, metavar="GAIN",
               help="nominal gain to compare with [A/V], e.g. '2 A/V' (seed 2)"),
    ),
    reports=("Ka", "I0"),
    shaft="electrical",
    order=40,
    settings=(Setting("nominal", "A/V", "nominal amplifier gain to compare with"),),
    characterize=characterize,
    rig=RigRun("amplifier", "amplifier.csv", order=70),
)
