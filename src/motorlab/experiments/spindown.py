"""Spin-down of a flywheel (seed 1, "First Experiment"): K from the generated voltage, b and Tf."""

from __future__ import annotations

from typing import Any

from motorlab.experiments import Experiment, FromSession, Option, RigRun, Setting
from motorlab.experiments._shared import COLUMN, CPR, CURRENT_UNIT, EXCLUDE, INERTIA, inertia_of, noted, without_spans


def run(paths: list[str], v: dict[str, Any]) -> Any:
    """Read the log(s) (one run, possibly split over several files) and fit the spin-down."""
    from motorlab.analyses import common
    from motorlab.analyses.spindown import spindown

    recording = common.read_position_log(paths, cpr=v["cpr"], current_unit=v["current_unit"])
    inertia, inertia_se = inertia_of(v)
    # the coast's model is a closed form in time: samples in a span left out are simply not fitted
    (recording,), left = without_spans([recording], v, split=False)
    return noted(spindown(recording, cpr=v["cpr"], inertia=inertia, inertia_stderr=inertia_se, cutoff=v["cutoff"],
                          guard=v["guard"]), left)


def session(ctx: Any) -> FromSession:
    """The session's spin-down: the flywheel's inertia from the rig, the cut-off if given."""
    inertia, inertia_se = ctx.loaded_inertia()
    return FromSession({"cpr": ctx.cpr, "inertia": inertia, "inertia_stderr": inertia_se,
                        "cutoff": ctx.setting("cutoff"), "exclude": ctx.setting("exclude")})


EXPERIMENT = Experiment(
    name="spindown",
    title="Flywheel spin-down",
    summary="Spin-down of a flywheel: K from the coasting back-EMF, viscous and Coulomb friction from the coast",
    analysis="motorlab.analyses.spindown:spindown",
    inputs="FTC OpMode log(s) of one run (time, encoder counts, bus voltage, shunt current) or a CSV "
           "(time_s, position, voltage_V, current_A)",
    run=run,
    options=(
        CPR, CURRENT_UNIT, *INERTIA,
        Option("cutoff", "s", label="Instant the power was cut",
               help="when the relay opened, in the log's time; left empty: found from the current"),
        Option("guard", "s", nonnegative=True, default=0.1, label="Time left out after the cut",
               help="samples this long after the cut-off are not fitted (the current decaying)"),
        EXCLUDE, COLUMN,
    ),
    reports=("K", "gamma", "Tf_over_J", "J", "b", "Tf"),
    shaft="output + flywheel, coasting: gearbox back-driven, physical torques",
    order=20,
    settings=(Setting("cutoff", "s", "instant the relay opened (default: found from the current dropping to zero)"),),
    contributes={"K": "K"},
    loaded=True,
    session=session,
    rig=RigRun("spindown", "spindown.txt", {"voltage": 12.0, "current_limit": 4.0}, order=20),
)
