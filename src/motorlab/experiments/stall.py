"""Locked-rotor (stall) runs: K, R at 25 °C and the winding's thermal network."""

from __future__ import annotations

from typing import Any

from motorlab.experiments import Experiment, FromSession, Option, RigRun, Setting
from motorlab.experiments._shared import COLUMN
from motorlab.thermal.network import MAGNET_COEFFICIENTS


def read_runs(paths: list[str]) -> list[Any]:
    """One recording per file: a headed CSV (``time_s,voltage_V,current_A,torque_Nm``) or a dynamometer
    export with worded headers (``Time,Amps,Volts,Torque 6V (N · m)``, :mod:`motorlab.io.headers`); a motor
    curve among them (``Speed (RPM),Torque (N·m),Current (A),…``) bounds K by its back-EMF constant."""
    from motorlab.analyses.common import read_tables

    return list(read_tables(paths))


def run(paths: list[str], v: dict[str, Any]) -> Any:
    """Run ``motorlab analyze stall FILE...``."""
    from motorlab.analyses.stall import stall

    network, source = _network(v["network"])
    return stall(read_runs([*paths, *(v["curve"] or [])]), voltage=v["voltage"], magnet=v["magnet"],
                 magnet_coefficient=v["magnet_coefficient"], ambient=v["ambient"], until=v["until"],
                 answer_voltage=v["answer_voltage"], limit=v["limit"], rise=v["rise"], back_emf=v["back_emf"],
                 network=network, network_source=source)


def _network(paths: list[str] | None) -> tuple[Any, str]:
    """The thermal network of a stall fit (``--network FIT.json``) and where it comes from, in words."""
    if not paths:
        return None, ""
    from motorlab.thermal.forecast import load_fit

    if len(paths) > 1:
        from motorlab.errors import OptionError

        raise OptionError("give one fit as --network (the fit of the motor's other runs)")
    model = load_fit(paths[0])
    name = paths[0].replace("\\", "/").rsplit("/", 1)[-1]
    return model.thermal, f"the fit {name}"


def session(ctx: Any) -> FromSession:
    """The session's stall runs (voltage, magnet and ambient from the session's table)."""
    return FromSession({"voltage": ctx.setting("voltage"), "magnet": ctx.setting("magnet"),
                        "ambient": ctx.setting("ambient"), "back_emf": ctx.setting("back_emf")})


EXPERIMENT = Experiment(
    name="stall",
    title="Locked rotor (stall) runs and heat",
    summary="Locked rotor: K, R at 25 °C and the winding's heating (thermal network) from stall runs at held "
            "voltages; runs that end in a failure or at a limit of the rig are cut and named",
    analysis="motorlab.analyses.stall:stall",
    inputs="CSV of time_s, current_A, voltage_V and torque_Nm when measured, or a dynamometer export "
           "(Time,Amps,Volts,Torque (N · m)); one file per run (voltage)",
    run=run,
    options=(
        Option("voltage", "V", positive=True, metavar="VOLTS", label="Supply voltage",
               help="for files without a voltage column"),
        Option("magnet", kind="choice", choices=tuple(MAGNET_COEFFICIENTS), default="ferrite", label="Magnet material",
               help="ferrite (K changes by −0.002 per kelvin) or ndfeb (−0.0012 per kelvin)"),
        Option("magnet-coefficient", "1/K", dest="magnet_coefficient", metavar="BETA",
               label="Magnets' temperature coefficient", help="on K, instead of the material's, e.g. -0.0019"),
        Option("ambient", "degC", default=25.0, metavar="CELSIUS", label="Ambient temperature",
               help="in °C; the coolest run starts at it"),
        Option("until", "s", positive=True, metavar="SECONDS", label="Fit up to",
               help="fit only each run's samples up to this time (forecast the rest with simulate stall)"),
        Option("answer-voltage", "V", positive=True, default=12.0, metavar="VOLTS", label="Stall voltage asked about",
               help="the voltage of the 'how long can it stay stalled' answer"),
        Option("limit", "degC", default=150.0, metavar="CELSIUS", label="Winding temperature limit",
               help="in °C, the temperature of that answer"),
        Option("rise", "K", positive=True, default=100.0, metavar="KELVIN", label="Allowed winding rise",
               help="of the 'current held indefinitely' answer"),
        Option("curve", kind="files", metavar="CURVE.csv", label="The motor's curve",
               help="its back-EMF constant bounds K: no shaft's torque per amp exceeds it (a curve given among the "
                    "runs counts too)"),
        Option("back-emf", "V*s/rad", dest="back_emf", positive=True, metavar="KE",
               label="The motor's back-EMF constant", help="instead of a curve (from a spin-down or a datasheet): "
               "bounds K"),
        Option("network", kind="files", metavar="FIT.json", label="Thermal network of the motor's other runs",
               help="a stall fit (as JSON) of the same motor's other runs: its network is held and only R and the "
                    "start temperatures are fitted (a run no single network fits)"),
        COLUMN,
    ),
    reports=("K", "tau0", "R", "R_wc", "R_ca", "C_w", "C_c", "t_limit", "I_continuous", "R_hot"),
    shaft="the stalled shaft where torque is measured (a bare motor: the motor shaft); R at 25 °C",
    order=35,
    settings=(
        Setting("voltage", "V", "the supply's voltage, for files without a voltage column"),
        Setting("magnet", "str", "magnet material: ferrite (default) or ndfeb"),
        Setting("ambient", "float", "ambient temperature [°C] (default 25)"),
        Setting("back_emf", "V*s/rad", "the motor's back-EMF constant (its curve's K): bounds the stall K"),
    ),
    session=session,
    rig=RigRun("stall", "stall.csv", settings={"voltage": 6.0, "duration": 120.0}, order=35),
)
