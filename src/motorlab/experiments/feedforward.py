"""SysId-style feedforward gains kS, kV, kA (+ gravity) by simulation (docs/feedforward.md)."""

from __future__ import annotations

from typing import Any

from motorlab.errors import OptionError
from motorlab.experiments import Experiment, FromSession, Option, RigRun, stderr_or_none
from motorlab.experiments._shared import COLUMN, EXCLUDE, noted, spans, without_spans

#: as motorlab.analyses.feedforward.MECHANISMS (tests/experiments/test_registry.py)
MECHANISMS = ("simple", "elevator", "arm")
#: frc-characterization units (motorlab.io.frc_json.UNITS), as its --units choices.
UNIT_CHOICES = ("Meters", "Feet", "Inches", "Radians", "Rotations", "Degrees")


def run(paths: list[str], v: dict[str, Any]) -> Any:
    """Run ``motorlab analyze feedforward FILE...`` (Road Runner's lateral/angular ramps too)."""
    from motorlab.analyses.feedforward import feedforward, motor_estimates, read_tests

    cpr = v["cpr"]
    if v["torque_constant"] is not None and v["resistance"] is None:
        raise OptionError("the torque constant (--K) turns the gains into motor parameters only with the "
                          "resistance (--R): give both, or neither")
    runs = read_tests(paths, cpr=cpr, side=v["side"], units=v["units"])
    if spans(v) and any(r.metadata.get("ramp") in ("lateral", "angular") for r in runs):
        raise OptionError("time spans can be left out of a forward ramp only (a lateral or angular ramp is read as "
                          "a whole): fit the forward ramp alone with them, then the others without")
    # an output-error fit simulates each run from its voltage: a span left out cuts the run in two
    runs, left = without_spans(runs, v, split=True)
    json_only = any(run.metadata.get("format") in ("sysid-json", "frc-char-json") for run in runs)
    if any(r.metadata.get("ramp") in ("lateral", "angular") for r in runs):  # Road Runner's other ramps
        from motorlab.analyses.roadrunner import from_runs

        result = from_runs(runs, cpr=cpr, mechanism=v["mechanism"])
    else:
        result = feedforward(runs, mechanism=v["mechanism"], cpr=None if json_only else cpr)
    if any(str(r.metadata.get("format", "")).startswith("roadrunner") for r in runs):
        # Road Runner's files: the gains are per angle of the encoder whose cpr was given (a dead wheel
        # or a drive motor's output), driving the whole robot: no SysId mechanism, no motor shaft.
        result.details["shaft"] = ("the encoder whose cpr was given (dead wheel or drive motor output), driving "
                                   "the whole robot; volts = power × battery")
    if json_only and cpr is not None:
        result.details["cpr"] = {"given": cpr, "note": "counts per logged rotation: the position quantum is "
                                 "one rotation (unitsPerRotation) / cpr"}
    if v["resistance"] is not None:
        result.parameters.update(motor_estimates(
            result, resistance=v["resistance"], resistance_stderr=v["resistance_stderr"] or 0.0,
            torque_constant=v["torque_constant"], torque_constant_stderr=v["torque_constant_stderr"] or 0.0,
        ))
    from motorlab.thermal.warning import add_heat_warning

    return noted(add_heat_warning(result, runs, resistance=v["resistance"]), left)


def session(ctx: Any) -> FromSession:
    """The session's SysId log; R and K from the unit turn the gains into motor parameters."""
    # A SysId JSON file holds angles already (no counts; its rotations need not be the motor's):
    # the session's cpr is not applied to it. Both sides of a drivetrain are fitted.
    json_only = all(p.lower().endswith(".json") for p in ctx.files)
    r, k = ctx.estimate("R"), ctx.estimate("K")
    return FromSession({
        "cpr": None if json_only else ctx.cpr, "exclude": ctx.setting("exclude"),
        "R": None if r is None else r.value, "R_stderr": None if r is None else stderr_or_none(r),
        "K": None if r is None or k is None else k.value,
        "K_stderr": None if r is None or k is None else stderr_or_none(k),
    })


EXPERIMENT = Experiment(
    name="feedforward",
    title="Feedforward gains kS, kV, kA (SysId, Road Runner)",
    summary="SysId-style feedforward gains by simulation: ``V = kS·sgn(ω) + kV·ω + kA·α`` (+ gravity)",
    analysis="motorlab.analyses.feedforward:feedforward",
    inputs="WPILib SysId JSON or .wpilog, frc-characterization JSON, Road Runner ramps, FTC logs, CSV",
    run=run,
    options=(
        Option("cpr", "count", positive=True, label="Encoder counts per revolution",
               help="at the shaft the encoder turns with (537.7 is fine; 8192 for a REV Through Bore dead "
                    "wheel); for a SysId or frc-characterization file, counts per rotation the file logs"),
        Option("mechanism", kind="choice", choices=MECHANISMS, default="simple", label="Mechanism",
               help="the gravity term: none (simple), kG (elevator), kG·cos(θ+φ) (arm)"),
        Option("R", "ohm", positive=True, dest="resistance", label="Winding resistance",
               help="if known (an LCR reading): turns the gains into K, J, b, Tf"),
        Option("R-stderr", "ohm", nonnegative=True, dest="resistance_stderr",
               label="Uncertainty of the winding resistance", help="standard error of R; left empty: exact"),
        Option("K", "V*s/rad", positive=True, dest="torque_constant", label="Back-EMF constant",
               help="if known (a spin-down): separates K from b in kV; needs the resistance too"),
        Option("K-stderr", "V*s/rad", nonnegative=True, dest="torque_constant_stderr",
               label="Uncertainty of the back-EMF constant", help="standard error of K; left empty: exact"),
        Option("side", kind="choice", choices=("both", "left", "right"), default="both",
               label="Drivetrain side", help="of a drivetrain log: both sides' tests together (as SysId), or one"),
        Option("units", kind="choice", choices=UNIT_CHOICES, label="Unit of a frc-characterization file",
               help="for a file without a 'units' key; left empty: that tool's template units (Feet; Degrees "
                    "for an arm)"),
        EXCLUDE, COLUMN,
    ),
    reports=("kS", "kV", "kA", "kG"),
    shaft="output shaft, with the mechanism the test drove",
    order=80,
    # A SysId log is usually taken on a mechanism: its J, b, Tf are reported, not the motor's.
    contributes={},
    session=session,
    # Long enough for the flywheel's mechanical time constant (≈ 37 s through a NeveRest 40's lossy
    # gearbox): SysId's dynamic test must approach steady state or kV and kA are confounded.
    rig=RigRun("sysid", "sysid.json", {"quasistatic_duration": 60.0, "dynamic_duration": 40.0}, order=110),
)
