"""Which analysis a log most likely records: the proposal the app and ``motorlab robot pull`` make.

A proposal, not a verdict: the format (:func:`motorlab.io.detect_format`), the signals the log has and
the experiment its own header names decide it; the person changes it when it is wrong.
"""

from __future__ import annotations

import re
from collections.abc import Sequence

#: Format -> experiment proposed when the signals do not say more.
BY_FORMAT = {
    "sysid-json": "feedforward",
    "frc-char-json": "feedforward",
    "wpilog": "feedforward",
    "roadrunner-ramp": "feedforward",
    "roadrunner-log": "feedforward",
}

#: Signal present -> experiment (first match wins): what a table of that quantity is measured for.
BY_SIGNAL = (
    ("inductance", "lcr"),
    ("torque", "torque"),
    ("mass", "torque"),
    ("tach_voltage", "tachometer"),
    ("speed", "terminal"),
)

#: Experiment names the virtual rig and motorlab's robot code write into a log's header, where they
#: differ from the analysis that reads the log.
BY_HEADER = {"transient": "identify", "sysid": "feedforward", "quasistatic": "feedforward",
             "dynamic": "feedforward"}


def propose(fmt: str, signals: Sequence[str], declared: str | None = None, *, timed: bool = True) -> str:
    """The experiment a log of this format with these signals most likely records (a proposal).

    ``declared`` is the experiment the file's own header names (``# experiment: transient``), which
    wins over guessing from the signals. ``timed`` is False for a table without a time column (its
    rows are points of a curve, not samples of a run: ``metadata["time"] == "row index"``).
    """
    from motorlab.experiments import all_experiments

    if declared:
        declared = BY_HEADER.get(declared, declared)
        if declared in all_experiments():
            return declared
    if fmt == "datalogger":
        return propose_datalogger(signals)
    dyno = propose_dynamometer(signals, timed=timed)
    if dyno is not None:
        return dyno
    if fmt in BY_FORMAT:
        return BY_FORMAT[fmt]
    for signal, experiment in BY_SIGNAL:
        if signal in signals:
            return experiment
    if "position" in signals or "counts" in signals:
        return "spindown" if "current" in signals else "identify"
    return "spindown"


# ---- FTC SDK Datalogger files (motorlab.io.datalogger; issue 32) ---------------------------------------------


def propose_datalogger(signals: Sequence[str]) -> str:
    """The experiment of an FTC SDK Datalogger file: what its fields measure, else a mechanism's feedforward.

    A Datalogger file is a robot's own log of its mechanisms (an intake, a drive: velocity, battery, the
    power), so the gains kS, kV, kA are what it is for; what it lacks for them (the voltage applied, an
    encoder position, the counts per revolution) is said in words when it is read and analysed
    (``Recording.metadata["lacks"]``, the reader's ``cpr`` refusal).
    """
    for signal, experiment in BY_SIGNAL:
        if signal in signals:
            return experiment
    return "feedforward"


# --- dynamometer exports (issue 31, point 5) ----------------------------------------------------------------
# A dynamometer's export is what it is: a locked-rotor run (time, current, voltage and torque of a held shaft,
# VEX's ``<motor>-locked-rotor-data-<V>v-<date>.csv``) is the stall analysis, a motor curve (steady speed,
# torque and current from stall to free speed, one row a point, VEX's ``<motor>-motor-curve-data-<date>.csv``)
# the curve analysis; neither is a lever arm on a scale (``torque``), which has no time and no speed.

#: Experiments of a bench's dynamometer, and the task of the app they belong to.
BENCH_EXPERIMENTS = ("stall", "curve")

#: VEX's name of a locked-rotor run: the motor, then the run's voltage and date (``775pro-locked-rotor-data-4v``).
_LOCKED_ROTOR = re.compile(r"^(?P<motor>.+?)[-_ ]locked[-_ ]rotor", re.IGNORECASE)


def propose_dynamometer(signals: Sequence[str], *, timed: bool) -> str | None:
    """``"stall"`` for a locked-rotor run, ``"curve"`` for a motor curve, None for anything else.

    A motor curve has speed and torque as points (no time column); a locked-rotor run has time,
    current, voltage and torque and no speed (the shaft is held).
    """
    has = set(signals)
    if {"speed", "torque"} <= has and not timed:
        return "curve"
    if {"current", "voltage", "torque"} <= has and timed and not has & {"speed", "position", "velocity"}:
        return "stall"
    return None


def run_group(experiment: str, file_name: str) -> str | None:
    """Which runs are fitted together, as ``motorlab analyze stall A.csv B.csv C.csv`` does: the stall runs of
    one motor (VEX's file names name it: ``775pro-locked-rotor-data-4v-…`` → ``775pro``; other names: every
    stall run of the upload). None: one fit per file."""
    if experiment != "stall":
        return None
    found = _LOCKED_ROTOR.match(file_name.replace("\\", "/").rsplit("/", 1)[-1])
    return f"stall:{found.group('motor').lower()}" if found else "stall"


def task_of(experiment: str) -> str | None:
    """The app's task a proposed experiment belongs to when its format does not say (None: the caller decides)."""
    return "bench" if experiment in BENCH_EXPERIMENTS else None
