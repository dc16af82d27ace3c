"""Whole-model output-error identification from ordinary logs (docs/identify.md)."""

from __future__ import annotations

from typing import Any

from motorlab.errors import OptionError
from motorlab.experiments import KNOWN, Experiment, FromSession, Option, RigRun, Setting
from motorlab.experiments._shared import COLUMN, EXCLUDE, noted, spans, without_spans

PARAMETERS = ("K", "R", "L", "J", "b", "Tf")


def thermal_motors() -> list[str]:
    """The catalogue's motors with thermal figures (``data/thermal.toml``)."""
    import tomllib
    from importlib import resources

    text = resources.files("motorlab").joinpath("data/thermal.toml").read_text(encoding="utf-8")
    return [m for family in tomllib.loads(text).get("families", {}).values() for m in family.get("motors", ())]


def run(paths: list[str], v: dict[str, Any]) -> Any:
    """Run ``motorlab analyze identify FILE...``; a JSON file's cpr counts per logged rotation."""
    from motorlab.analyses.common import check_cpr
    from motorlab.analyses.feedforward import apply_cpr
    from motorlab.analyses.identify import identify
    from motorlab.estimation.runs import read_runs

    cpr = v["cpr"]
    check_cpr(cpr)  # any positive number of counts (537.7), within physical bounds
    runs = read_runs(paths, cpr=cpr)
    if spans(v) and (v["thermal"] or v["thermal_fit"]):
        raise OptionError("time spans cannot be left out of a fit of the winding's temperature (the heat of the "
                          "whole log warms it): fit without the temperature, or without the spans")
    # an output-error fit simulates each run from its voltage: a span left out cuts the run in two
    runs, left = without_spans(runs, v, split=True)
    json_runs = [r for r in runs if r.metadata.get("format") in ("sysid-json", "frc-char-json")]
    if json_runs and cpr is not None:  # a JSON file logs its own units: cpr counts per logged rotation
        apply_cpr(json_runs, cpr)
        cpr = None  # the readers of counts logs keep theirs in metadata["cpr"]
    from motorlab.thermal.warning import add_heat_warning

    network = None
    if v["thermal_fit"]:  # the network a stall run measured (analyze stall --json)
        from motorlab.thermal.forecast import load_fit

        network = load_fit(v["thermal_fit"][0]).thermal
    resistance, torque_constant = v["resistance"], v["torque_constant"]
    known = v.get(KNOWN) or {}
    if resistance is None and not all(run.has("current") for run in runs) and "R" in known:
        # a session's log without current: the unit's R (and K, to separate K from b) from its other experiments
        resistance = known["R"].value
        torque_constant = known["K"].value if "K" in known else torque_constant
    result = identify(runs, resistance=resistance, torque_constant=torque_constant, cpr=cpr,
                      use_current=v["use_current"], thermal=v["thermal"] or network is not None, motor=v["motor"],
                      network=network, initial_temperature=v["initial_temperature"])
    if v["thermal"] or network is not None:  # the heat is in the model: its figure is among the warnings already
        return noted(result, left)
    return noted(add_heat_warning(result, runs, resistance=v["resistance"]), left)


def session(ctx: Any) -> FromSession:
    """The session's logs; the heat setting, and R and K from the unit for a log without current."""
    heat = str(ctx.setting("thermal") or "").strip()
    thermal = bool(heat) and heat.lower() not in ("no", "false")
    return FromSession(
        {"cpr": ctx.cpr, "exclude": ctx.setting("exclude"), "thermal": thermal,
         # heat: "yes", or the catalogue motor whose figures to use
         "motor": heat if thermal and heat.lower() not in ("yes", "true") else None,
         "initial_temperature": ctx.setting("initial_temperature")},
        known={name: est for name in ("R", "K") if (est := ctx.estimate(name)) is not None},
    )


EXPERIMENT = Experiment(
    name="identify",
    title="Whole motor model from one log",
    summary="Whole-model identification from ordinary logs: applied voltage, encoder angle, maybe current",
    analysis="motorlab.analyses.identify:identify",
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
        Option("thermal", kind="flag", default=False, label="Fit the winding's temperature",
               help="R and K at 25 °C, with the winding's temperature integrated from the log's heat as a state of the "
                    "model (needs the current)"),
        Option("motor", kind="choice", choices=tuple(thermal_motors()), metavar="NAME",
               label="Motor whose thermal figures to use",
               help="with the winding's temperature: the catalogue's thermal network of this motor; without it, the "
                    "one the log names, else a 550-size motor's"),
        Option("thermal-fit", kind="files", metavar="FIT.json", label="Stall fit whose thermal network to use",
               help="with the winding's temperature: the network a stall run measured (the JSON that analyze stall "
                    "writes), instead of the catalogue's"),
        Option("initial-temperature", "degC", metavar="CELSIUS", label="Winding temperature at the start",
               help="with the winding's temperature: in °C, the winding's and case's at the log's start; without "
                    "it, the ambient's"),
        EXCLUDE, COLUMN,
    ),
    reports=PARAMETERS,
    settings=(
        Setting("thermal", "str", "fit the winding's temperature as a state: \"yes\" (the network of the motor the "
                "log names), or the catalogue motor whose thermal figures to use"),
        Setting("initial_temperature", "float", "with thermal: the winding's temperature at the log's start [°C]"),
    ),
    shaft="output shaft, with what the log drove; friction and inertia as the motor's torque sees them",
    order=70,
    contributes={name: name for name in PARAMETERS},
    session=session,
    rig=RigRun("transient", "transient.csv", order=100),
)
