"""Which analysis a log most likely records: the proposal the app and ``motorlab robot pull`` make.

A proposal, not a verdict: the format (:func:`motorlab.io.detect_format`), the signals the log has and
the experiment its own header names decide it; the person changes it when it is wrong.
"""

from __future__ import annotations

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


def propose(fmt: str, signals: Sequence[str], declared: str | None = None) -> str:
    """The experiment a log of this format with these signals most likely records (a proposal).

    ``declared`` is the experiment the file's own header names (``# experiment: transient``), which
    wins over guessing from the signals.
    """
    from motorlab.experiments import all_experiments

    if declared:
        declared = BY_HEADER.get(declared, declared)
        if declared in all_experiments():
            return declared
    if fmt == "datalogger":
        return propose_datalogger(signals)
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
