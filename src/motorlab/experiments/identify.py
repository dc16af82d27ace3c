"""Whole-model output-error identification from ordinary logs (docs/identify.md)."""

from __future__ import annotations

from typing import Any

from motorlab.experiments import Experiment, Option, RigRun
from motorlab.experiments._shared import COLUMN

PARAMETERS = ("K", "R", "L", "J", "b", "Tf")


def run(paths: list[str], v: dict[str, Any]) -> Any:
    """Run ``motorlab analyze identify FILE...``; a JSON file's cpr counts per logged rotation."""
    from motorlab.analyses._common import check_cpr
    from motorlab.feedforward import apply_cpr
    from motorlab.identify import identify, read_runs

    cpr = v["cpr"]
    check_cpr(cpr)  # any positive number of counts (537.7), within physical bounds
    runs = read_runs(paths, cpr=cpr)
    json_runs = [r for r in runs if r.metadata.get("format") in ("sysid-json", "frc-char-json")]
    if json_runs and cpr is not None:  # a JSON file logs its own units: cpr counts per logged rotation
        apply_cpr(json_runs, cpr)
        cpr = None  # the readers of counts logs keep theirs in metadata["cpr"]
    from motorlab.analyses._heat import add_heat_warning

    result = identify(runs, resistance=v["resistance"], torque_constant=v["torque_constant"], cpr=cpr,
                      use_current=v["use_current"])
    return add_heat_warning(result, runs, resistance=v["resistance"])


def characterize(ctx: Any) -> Any:
    """The session's logs; without current, R and K come from what the unit has measured."""
    from motorlab.identify import identify, read_runs

    cpr = ctx.cpr
    runs = read_runs(ctx.files, cpr=cpr)
    if all(run.has("current") for run in runs):
        return identify(runs, cpr=cpr)
    # Without current the feedforward gains need R (and K to separate K from b) from elsewhere.
    r, k = ctx.estimate("R"), ctx.estimate("K")
    return identify(
        runs, cpr=cpr, resistance=None if r is None else r.value, torque_constant=None if k is None else k.value
    )


EXPERIMENT = Experiment(
    name="identify",
    title="Whole motor model from one log",
    summary="Whole-model identification from ordinary logs: applied voltage, encoder angle, maybe current",
    analysis="motorlab.identify:identify",
    inputs="logs of applied voltage and encoder angle, maybe current: FTC log, CSV, SysId JSON, .wpilog",
    run=run,
    options=(
        Option("cpr", "count", positive=True, label="Encoder counts per revolution",
               help="at the shaft the encoder turns with (537.7 is fine)"),
        Option("R", "ohm", positive=True, dest="resistance", label="Winding resistance",
               help="if known (an LCR reading); needed when the log has no current"),
        Option("K", "V*s/rad", positive=True, dest="torque_constant", label="Back-EMF constant",
               help="if known (a spin-down); separates K from b when the log has no current"),
        Option("no-current", kind="flag", default=True, dest="use_current", label="Ignore the current column",
               help="fit the voltage and the angle only"),
        COLUMN,
    ),
    reports=PARAMETERS,
    shaft="output, what the log drove, per unit of K·i",
    order=70,
    contributes={name: name for name in PARAMETERS},
    characterize=characterize,
    rig=RigRun("transient", "transient.csv", order=100),
)
