"""Free spin-up at constant current timed by a scope (seed 1): the bare gearmotor's J."""

from __future__ import annotations

from typing import Any

from motorlab.errors import OptionError
from motorlab.experiments import Experiment, FromSession, Option, RigRun, Setting, stderr_or_none
from motorlab.experiments._shared import CPR


def run(paths: list[str], v: dict[str, Any]) -> Any:
    """Read the edge times (one file) and fit J."""
    from motorlab.analyses.free_spinup import free_spinup, read_edges

    if len(paths) != 1:
        raise OptionError(f"free-spinup analyses one file of edge times, got {len(paths)}")
    return free_spinup(
        read_edges(paths[0]), torque_constant=v["K"], current=v["current"], cpr=v["cpr"],
        edges_per_revolution=v["edges_per_rev"], torque_constant_stderr=v["K_stderr"],
        current_stderr=v["current_stderr"], viscous_friction=v["b"], viscous_friction_stderr=v["b_stderr"],
        coulomb_friction=v["Tf"], coulomb_friction_stderr=v["Tf_stderr"],
    )


def session(ctx: Any) -> FromSession:
    """The session's free spin-up with the unit's K, b and Tf known so far."""
    k = ctx.require("K", "the torque is K·I")
    b, tf = ctx.estimate("b"), ctx.estimate("Tf")
    return FromSession({
        "cpr": ctx.cpr, "K": k.value, "K_stderr": stderr_or_none(k),
        "current": ctx.setting("current"), "current_stderr": ctx.setting("current_stderr"),
        "edges_per_rev": ctx.setting("edges_per_revolution"),
        "b": None if b is None else max(b.value, 0.0), "b_stderr": None if b is None else stderr_or_none(b),
        "Tf": None if tf is None else max(tf.value, 0.0), "Tf_stderr": None if tf is None else stderr_or_none(tf),
    })


EXPERIMENT = Experiment(
    name="free-spinup",
    title="Free spin-up of the bare motor",
    summary="Free spin-up of the bare motor at constant current: the armature inertia J from encoder edge times",
    analysis="motorlab.analyses.free_spinup:free_spinup",
    inputs="scope cursor times (time_ms or time_s, one rising edge per row) or a Rigol waveform export",
    run=run,
    options=(
        CPR,
        Option("edges-per-rev", "", positive=True, label="Rising edges per revolution",
               help="edges the scope timed per turn; left empty: cpr/4 (one channel, every fourth count)"),
        Option("K", "V*s/rad", positive=True, required=True, label="Torque constant",
               help="K of this motor (from a spin-down or a torque test); V·s/rad = N·m/A"),
        Option("K-stderr", "V*s/rad", nonnegative=True, label="Uncertainty of the torque constant",
               help="standard error of K"),
        Option("current", "A", positive=True, required=True, label="Constant current",
               help='the current the supply held during the spin-up, e.g. "0.5 A"'),
        Option("current-stderr", "A", nonnegative=True, label="Uncertainty of the current",
               help="standard error of the current"),
        Option("b", "N*m*s/rad", nonnegative=True, label="Viscous friction",
               help="b, if known (a terminal-speed test)"),
        Option("b-stderr", "N*m*s/rad", nonnegative=True, label="Uncertainty of the viscous friction",
               help="standard error of b"),
        Option("Tf", "N*m", nonnegative=True, label="Coulomb friction", help="Tf, if known (a terminal-speed test)"),
        Option("Tf-stderr", "N*m", nonnegative=True, label="Uncertainty of the Coulomb friction",
               help="standard error of Tf"),
    ),
    reports=("J", "alpha"),
    shaft="output shaft of the bare gearmotor; friction and inertia as the motor's torque sees them",
    order=110,
    settings=(
        Setting("current", "A", "constant current driving the free motor (required)", required=True),
        Setting("current_stderr", "A", "standard error of that current"),
        Setting("edges_per_revolution", "float", "rising edges per revolution (default cpr/4: one channel)"),
    ),
    contributes={"J": "J"},
    session=session,
    rig=RigRun("free-spinup", "free_spinup.csv", {"current": 0.5}, order=50),
)
