"""Square-wave pulse responses (seed 2, "Motor Mechanical Properties"): J, b and Tf."""

from __future__ import annotations

import math
from typing import Any

from motorlab.errors import LogFormatError, OptionError
from motorlab.experiments import Experiment, FromSession, Option, RigRun, Setting, stderr_or_none
from motorlab.experiments._shared import COLUMN

DEFAULT_SKIP = 0.002  # as motorlab.analyses.pulse.DEFAULT_SKIP (checked by tests/experiments/test_registry.py)
FRICTION_MODELS = ("viscous", "coulomb", "both")  # as motorlab.analyses.pulse.FRICTION_MODELS


def run(paths: list[str], v: dict[str, Any]) -> Any:
    """Run ``motorlab analyze pulse FILE...``: Ka from the option or the file's ``# Ka_A_per_V:`` line."""
    from motorlab.analyses.common import LIMITS, check_range, metadata_quantity, read_tables
    from motorlab.analyses.pulse import pulse

    recs = read_tables(paths)
    ka = v["amplifier_gain"]
    if ka is None:
        ka = metadata_quantity(recs[0], ["Ka_A_per_V", "Ka"], "A/V")
        if ka is None:
            raise OptionError("give the amplifier gain --Ka [A/V] (measure it with 'motorlab analyze amplifier')")
        try:
            check_range(ka, "the amplifier gain", *LIMITS["Ka"][:2], "A/V", why="no servo amplifier is outside this")
        except OptionError as exc:
            raise LogFormatError(f"the '# Ka_A_per_V:' line: {exc.message}", path=recs[0].source or None) from None
    return pulse(
        recs, amplifier_gain=ka, torque_constant=v["torque_constant"], amplifier_offset=v["amplifier_offset"],
        skip=v["skip"], tach_gain=v["tach_gain"], friction=v["friction"],
        amplifier_gain_stderr=v["amplifier_gain_stderr"], amplifier_offset_stderr=v["amplifier_offset_stderr"],
        torque_constant_stderr=v["torque_constant_stderr"], gain_offset_correlation=v["gain_offset_correlation"],
    )


def session(ctx: Any) -> FromSession:
    """The session's pulse responses with the unit's K and the amplifier's and tachometer's fits."""
    k = ctx.require("K", "the torque is Ka·K·V")
    values: dict[str, Any] = {"Km": k.value, "Km_stderr": stderr_or_none(k) or 0.0,
                              "Ka": ctx.setting("amplifier_gain"), "tach_gain": ctx.setting("tach_gain")}
    notes: list[str] = []
    if values["Ka"] is None:
        fit = ctx.fits.get("amplifier")
        if fit is None or "Ka" not in fit:
            raise OptionError("needs the amplifier gain: run the amplifier experiment or set amplifier_gain")
        values.update(Ka=fit["Ka"].value, Ka_stderr=stderr_or_none(fit["Ka"]) or 0.0)
        # The amplifier's zero offset I0 (its fit's intercept) drives the motor too: Tf is biased without it.
        if "I0" in fit:
            values.update(I0=fit["I0"].value, I0_stderr=stderr_or_none(fit["I0"]) or 0.0)
            names = fit.correlation_names
            if fit.correlation is not None and "Ka" in names and "I0" in names:
                rho = float(fit.correlation[names.index("Ka"), names.index("I0")])
                values["Ka_I0_correlation"] = rho if math.isfinite(rho) else 0.0
        notes.append("the amplifier gain Ka and offset I0 are the unit's amplifier experiment's")
    if values["tach_gain"] is None and "tachometer" in ctx.fits and "Kt_tach" in ctx.fits["tachometer"]:
        values["tach_gain"] = ctx.fits["tachometer"]["Kt_tach"].value
    return FromSession(values, notes=tuple(notes))


EXPERIMENT = Experiment(
    name="pulse",
    title="Square-wave pulse responses",
    summary='Inertia J and friction from a square-wave-driven speed trace (seed 2, "Motor Mechanical Properties")',
    analysis="motorlab.analyses.pulse:pulse",
    inputs="CSV of time_s, command_V and speed (speed_rad_per_s, speed_rpm or tach_voltage_V)",
    run=run,
    options=(
        Option("Ka", "A/V", positive=True, dest="amplifier_gain", metavar="GAIN", label="Amplifier gain",
               help="the servo amplifier's Ka (measure it with the amplifier experiment); left empty: the "
                    "file's '# Ka_A_per_V:' line"),
        Option("I0", "A", default=0.0, dest="amplifier_offset", metavar="CURRENT", label="Amplifier offset current",
               help="the amplifier's output at zero command (the intercept I0 of the amplifier experiment)"),
        Option("Km", "N*m/A", positive=True, required=True, dest="torque_constant", aliases=("K",), metavar="K",
               label="Torque constant", help="the motor's K (from the torque test)"),
        Option("Ka-stderr", "A/V", nonnegative=True, default=0.0, dest="amplifier_gain_stderr", metavar="GAIN",
               label="Uncertainty of the amplifier gain", help="standard error of Ka, carried into J, b and Tf"),
        Option("I0-stderr", "A", nonnegative=True, default=0.0, dest="amplifier_offset_stderr", metavar="CURRENT",
               label="Uncertainty of the offset current", help="standard error of I0, carried into Tf"),
        Option("Km-stderr", "N*m/A", nonnegative=True, default=0.0, dest="torque_constant_stderr",
               aliases=("K-stderr",), metavar="K", label="Uncertainty of the torque constant",
               help="standard error of K, carried into the results"),
        Option("Ka-I0-correlation", "", default=0.0, dest="gain_offset_correlation", metavar="RHO",
               label="Correlation of the amplifier gain and offset",
               help="between −1 and 1, as the amplifier experiment's fit gives it; carried into Tf"),
        Option("skip", "s", nonnegative=True, default=DEFAULT_SKIP, metavar="TIME", label="Time left out after an edge",
               help="samples this long after each command edge are not fitted"),
        Option("tach-gain", "V*s/rad", positive=True, metavar="GAIN", label="Tachometer gain",
               help="when the file holds the tachometer voltage instead of a speed"),
        Option("friction", kind="choice", choices=("auto", *FRICTION_MODELS), default="auto",
               label="Friction model", help="of the final fit; auto: the one the coast-downs support best (BIC)"),
        COLUMN,
    ),
    reports=("J", "Tf", "b", "gamma"),
    shaft="output shaft of the bare gearmotor; friction and inertia as the motor's torque sees them",
    order=60,
    settings=(
        Setting("amplifier_gain", "A/V", "amplifier gain Ka (default: from the amplifier experiment)"),
        Setting("tach_gain", "V*s/rad", "tachometer gain (default: from the tachometer experiment)"),
    ),
    contributes={"J": "J", "b": "b", "Tf": "Tf"},
    session=session,
    rig=RigRun("pulse", "pulse.csv", order=90),
)
