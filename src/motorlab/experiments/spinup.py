"""Spin-up of a flywheel at constant current (seed 1, "First Experiment"): K = J·α/i."""

from __future__ import annotations

from typing import Any

from motorlab.errors import OptionError
from motorlab.experiments import FITS, Experiment, FromSession, Option, RigRun, Setting
from motorlab.experiments._shared import COLUMN, CPR, CURRENT_UNIT, EXCLUDE, INERTIA, inertia_of, noted, without_spans


def run(paths: list[str], v: dict[str, Any]) -> Any:
    """Read the spin-up log (and the spin-down log, if given) and fit K."""
    from motorlab.analyses import common
    from motorlab.analyses.spinup import spinup

    inertia, inertia_se = inertia_of(v)
    if inertia is None:
        raise OptionError("the spin-up needs the inertia: give --inertia or the flywheel disc")
    recording = common.read_position_log(paths, cpr=v["cpr"], current_unit=v["current_unit"])
    (recording,), left = without_spans([recording], v, split=False)  # of the spin-up log, not the spin-down's
    # a session gives its spin-down's fit (the one on the same rig) instead of a file
    spindown_result = None if v["b"] is not None or v["Tf"] is not None else (v.get(FITS) or {}).get("spindown")
    if v["spindown"]:
        if v["b"] is not None or v["Tf"] is not None:
            raise OptionError("give the friction either with --spindown or with --b/--Tf, not both")
        from motorlab.analyses.spindown import spindown

        coast = common.read_position_log(v["spindown"], cpr=v["cpr"], current_unit=v["current_unit"])
        spindown_result = spindown(coast, cpr=v["cpr"])
    from motorlab.thermal.warning import add_heat_warning

    result = spinup(
        recording, inertia=inertia, inertia_stderr=inertia_se, cpr=v["cpr"],
        viscous_friction=v["b"], viscous_friction_stderr=v["b_stderr"],
        coulomb_friction=v["Tf"], coulomb_friction_stderr=v["Tf_stderr"],
        spindown_result=spindown_result, start=v["start"], end=v["end"],
    )
    return noted(add_heat_warning(result, [recording]), left)


def session(ctx: Any) -> FromSession:
    """The session's spin-up: the friction of its spin-down, corrected for the gearbox when it can be."""
    if ctx.session.rig.flywheel is None:  # the session validation refuses this; kept for library callers
        raise OptionError("the spin-up needs the flywheel's inertia: add [rig.flywheel]")
    inertia, inertia_se = ctx.loaded_inertia()
    values = {"cpr": ctx.cpr, "inertia": inertia, "inertia_stderr": inertia_se, "exclude": ctx.setting("exclude"),
              "start": ctx.setting("start"), "end": ctx.setting("end")}
    friction = ctx.motoring_friction()
    if friction is None:
        spindown = ctx.fits.get("spindown")
        return FromSession(values, fits={} if spindown is None else {"spindown": spindown})
    b, b_se, tf, tf_se, eta = friction
    note = (f"friction from the spin-down corrected for the gearbox (η = {eta:.3g}, back-driving efficiency taken "
            "equal): the coasting flywheel back-drives the gearbox and sees the motor's friction ÷ η, the motor "
            "driving it passes only η of it; this K is the output's Kt = η·Ke (docs/gearbox.md)")
    return FromSession({**values, "b": b, "b_stderr": b_se, "Tf": tf, "Tf_stderr": tf_se}, notes=(note,))


EXPERIMENT = Experiment(
    name="spinup",
    title="Flywheel spin-up at constant current",
    summary="Spin-up of a known flywheel at constant current: K = J·α/i, corrected for friction",
    analysis="motorlab.analyses.spinup:spinup",
    inputs="FTC OpMode log(s) of one run (time, encoder counts, bus voltage, shunt current) or a CSV",
    run=run,
    options=(
        CPR, CURRENT_UNIT, *INERTIA,
        Option("b", "N*m*s/rad", nonnegative=True, label="Viscous friction",
               help="b, if known; or give the spin-down log"),
        Option("b-stderr", "N*m*s/rad", nonnegative=True, label="Uncertainty of the viscous friction",
               help="standard error of b"),
        Option("Tf", "N*m", nonnegative=True, label="Coulomb friction", help="Tf, if known; or give the spin-down log"),
        Option("Tf-stderr", "N*m", nonnegative=True, label="Uncertainty of the Coulomb friction",
               help="standard error of Tf"),
        Option("spindown", kind="files", metavar="FILE", label="Spin-down log of the same rig",
               help="the friction is taken from it (a run split over several files: give them all)"),
        Option("start", "s", label="Start of the constant current",
               help="in the log's time; left empty: found from the current"),
        Option("end", "s", label="End of the constant current",
               help="in the log's time; left empty: found from the current"),
        EXCLUDE, COLUMN,
    ),
    reports=("K", "alpha", "i"),
    shaft="output + flywheel, motor driving: K = Kt through the gearbox",
    order=90,
    settings=(
        Setting("start", "s", "start of the constant-current phase (default: found from the current)"),
        Setting("end", "s", "end of the constant-current phase (default: found from the current)"),
        Setting("current", "A", "supply current limit during the spin-up (checked against the supply)"),
    ),
    contributes={"K": "K"},
    loaded=True,
    session=session,
    rig=RigRun("spinup", "spinup.txt", order=60),
)
