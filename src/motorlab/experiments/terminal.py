"""Steady free running at several currents (seed 1): b and Tf from K·I = b·ω + Tf."""

from __future__ import annotations

from typing import Any

from motorlab.errors import OptionError
from motorlab.experiments import Experiment, FromSession, Option, RigRun, Setting, stderr_or_none
from motorlab.experiments._shared import COLUMN, CPR


def _read(paths: list[str], cpr: float | None) -> Any:
    from motorlab.analyses.common import concatenate
    from motorlab.io.csv_table import read_csv

    recordings = [read_csv(p, cpr=cpr) for p in paths]
    return recordings[0] if len(recordings) == 1 else concatenate(recordings)


def run(paths: list[str], v: dict[str, Any]) -> Any:
    """Read the rows (CSV files, concatenated) and fit b (and Tf)."""
    from motorlab.analyses.terminal import terminal

    if not paths:
        raise OptionError("give the CSV file(s) of steady currents and frequencies")
    from motorlab.thermal.warning import add_heat_warning

    rows = _read(paths, v["cpr"])
    result = terminal(
        rows, torque_constant=v["K"], cpr=v["cpr"], torque_constant_stderr=v["K_stderr"],
        coulomb_friction=v["Tf"], coulomb_friction_stderr=v["Tf_stderr"], current_stderr=v["current_stderr"],
        frequency_stderr=v["frequency_stderr"],
    )
    # Seed 1 waits at each setting for the terminal velocity: about half a minute per reading.
    return add_heat_warning(result, rows if isinstance(rows, list) else [rows], hold=30.0)


def session(ctx: Any) -> FromSession:
    """The session's terminal rows with the unit's K."""
    k = ctx.require("K", "b = (K·I − Tf)/ω")
    return FromSession({"cpr": ctx.cpr, "K": k.value, "K_stderr": stderr_or_none(k),
                        "current_stderr": ctx.setting("current_stderr")})


EXPERIMENT = Experiment(
    name="terminal",
    title="Terminal speed at constant currents",
    summary="Terminal (steady) speed at constant current: viscous friction b and Coulomb friction Tf",
    analysis="motorlab.analyses.terminal:terminal",
    inputs="CSV rows of steady current and speed (current_A with speed_rpm, velocity or frequency_Hz)",
    run=run,
    options=(
        CPR,
        Option("K", "V*s/rad", positive=True, required=True, label="Torque constant",
               help="K of this motor (from a spin-down or a torque test); V·s/rad = N·m/A"),
        Option("K-stderr", "V*s/rad", nonnegative=True, label="Uncertainty of the torque constant",
               help="standard error of K"),
        Option("Tf", "N*m", nonnegative=True, label="Coulomb friction", help="Tf, if known: then only b is fitted"),
        Option("Tf-stderr", "N*m", nonnegative=True, label="Uncertainty of the Coulomb friction",
               help="standard error of Tf"),
        Option("current-stderr", "A", nonnegative=True, label="Uncertainty of one current reading",
               help="used when the rows show no scatter (a single row)"),
        Option("frequency-stderr", "Hz", nonnegative=True, label="Uncertainty of one frequency reading",
               help="the counter's resolution; used with the current's uncertainty"),
        COLUMN,
    ),
    reports=("b", "Tf"),
    shaft="output shaft of the bare gearmotor; friction and inertia as the motor's torque sees them",
    order=100,
    settings=(Setting("current_stderr", "A", "standard error of one current reading"),),
    contributes={"b": "b", "Tf": "Tf"},
    session=session,
    rig=RigRun("terminal", "terminal.csv", order=40),
)
