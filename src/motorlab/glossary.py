"""Every parameter an analysis or ``tune`` reports, named in words with its symbol and SI unit.

The key is the name in results (``analyze --json``'s ``parameters``, ``results.json``, ``tune``'s
gains); docs/glossary.md is the same list for people. The browser app shows results as
"Back-EMF constant K" with these, never a bare key.

The other words the browser app shows and the experiment descriptions do not hold are here too, in one
place, served by ``GET /api/schema`` (the page keeps no copy of its own, issue 33): each choice of an option
in words (:data:`CHOICES`), the gains a target's code names (:data:`GAINS`), which measurement gives a
parameter the gains need (:data:`MEASURED_BY`) and the app's tasks (:data:`TASKS`).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any


@dataclass(frozen=True)
class Parameter:
    """A reported quantity: ``name`` in words, its ``symbol`` (as printed) and SI ``unit``."""

    name: str
    symbol: str
    unit: str

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


_P = Parameter

#: Result key -> description. ``unit`` is SI as in the JSON (``"1"`` for a pure number).
PARAMETERS: dict[str, Parameter] = {
    # the motor model
    "K": _P("Back-EMF constant", "K", "V*s/rad"),
    "R": _P("Winding resistance", "R", "ohm"),
    "R_dc": _P("DC resistance (meter's DCR)", "R_dc", "ohm"),
    "L": _P("Winding inductance", "L", "H"),
    "J": _P("Moment of inertia", "J", "kg*m^2"),
    "b": _P("Viscous friction", "b", "N*m*s/rad"),
    "Tf": _P("Coulomb friction torque", "Tf", "N*m"),
    "gamma": _P("Spin-down decay rate (b/J)", "γ", "1/s"),
    "Tf_over_J": _P("Coulomb deceleration (Tf/J)", "Tf/J", "rad/s^2"),
    "alpha": _P("Angular acceleration", "α", "rad/s^2"),
    "i": _P("Current during the spin-up", "i", "A"),
    # a motor curve (dynamometer)
    "Kt": _P("Torque per amp", "Kt", "N*m/A"),
    "Kt_over_K": _P("Torque per amp over back-EMF constant", "Kt/K", "1"),
    "I_free": _P("Free current", "I₀", "A"),
    "friction_torque": _P("Friction torque at free speed", "τ_f", "N*m"),
    # the gearbox
    "efficiency": _P("Gearbox efficiency", "η", "1"),
    "loss_torque": _P("Gearbox loss torque", "τ0", "N*m"),
    "tau0": _P("Torque offset at zero current", "τ0", "N*m"),
    "tau_h": _P("Hysteresis torque (half the up/down gap)", "τ_h", "N*m"),
    # heat (analyze stall)
    "R_wc": _P("Thermal resistance, winding to case", "R_wc", "K/W"),
    "R_ca": _P("Thermal resistance, case to ambient", "R_ca", "K/W"),
    "C_w": _P("Heat capacity of the winding", "C_w", "J/K"),
    "C_c": _P("Heat capacity of the case", "C_c", "J/K"),
    "t_limit": _P("Time stalled until the winding reaches its limit", "t_limit", "s"),
    "I_continuous": _P("Stall current held indefinitely", "I_cont", "A"),
    "R_hot": _P("Winding resistance hot", "R_hot", "ohm"),
    # seed 2's calibrations
    "Ka": _P("Amplifier gain", "Ka", "A/V"),
    "I0": _P("Amplifier offset current", "I0", "A"),
    "Kt_tach": _P("Tachometer gain", "Kt_tach", "V*s/rad"),
    "V0": _P("Tachometer offset voltage", "V0", "V"),
    # feedforward (SysId, Road Runner)
    "kS": _P("Static friction voltage", "kS", "V"),
    "kV": _P("Velocity gain", "kV", "V*s/rad"),
    "kA": _P("Acceleration gain", "kA", "V*s^2/rad"),
    "kG": _P("Gravity gain", "kG", "V"),
    "offset": _P("Arm angle offset", "φ", "rad"),
    "track_width_ticks": _P("Track width", "track width", "tick"),
    "lateral_multiplier": _P("Lateral multiplier", "lateral multiplier", "1"),
    "lateral_kA": _P("Lateral acceleration gain", "kA (lateral)", "V*s^2/rad"),
    # tune's gains (units depend on the target; see each answer's "units")
    "kP": _P("Proportional gain", "kP", ""),
    "kI": _P("Integral gain", "kI", ""),
    "kD": _P("Derivative gain", "kD", ""),
    "kF": _P("Velocity feedforward F of the FTC motor controller", "F", ""),
}


def describe(key: str) -> dict[str, Any]:
    """The description of ``key`` as JSON (the key itself as the name when it is not listed)."""
    found = PARAMETERS.get(key)
    return found.to_dict() if found is not None else {"name": key, "symbol": key, "unit": ""}


#: Option name -> {choice: the choice in words}, as a form's menu shows it (a choice not listed shows as is).
CHOICES: dict[str, dict[str, str]] = {
    "loop": {"velocity": "speed (velocity loop)", "position": "position (position loop)"},
    "method": {"lqr": "LQR (as WPILib SysId)", "poles": "pole placement"},
    "units": {"rad": "radians", "rotations": "rotations", "degrees": "degrees", "ticks": "encoder ticks",
              "m": "metres", "ft": "feet", "in": "inches"},
    "mechanism": {"simple": "none (flywheel, drivetrain)", "elevator": "elevator (constant gravity)",
                  "arm": "arm (gravity × cos angle)"},
    "side": {"both": "both sides", "left": "left side", "right": "right side"},
    "circuit": {"series": "series", "parallel": "parallel"},
    "friction": {"auto": "automatic", "viscous": "viscous only (b)", "coulomb": "Coulomb only (Tf)",
                 "both": "viscous and Coulomb (b and Tf)"},
    "magnet": {"ferrite": "ferrite", "ndfeb": "neodymium (NdFeB)"},
    "current-unit": {"A": "amperes", "mA": "milliamperes"},
}

#: Gains a target's code names that :data:`PARAMETERS` does not (Road Runner's, CTRE's and REV's names).
GAINS: dict[str, str] = {
    "P": "Proportional gain", "I": "Integral gain", "D": "Derivative gain", "F": "Feedforward gain",
    "axialGain": "Axial position gain", "axialVelGain": "Axial velocity gain",
    "lateralGain": "Lateral position gain", "lateralVelGain": "Lateral velocity gain",
    "headingGain": "Heading gain", "headingVelGain": "Heading velocity gain",
    "turnGain": "Turn gain", "turnVelGain": "Turn velocity gain", "inPerTick": "Inches per tick",
}

#: Parameter -> the measurement that gives it (the gains step offers it when the model lacks the parameter).
MEASURED_BY: dict[str, str] = {
    "K": "a spin-down log (or a free spin-up or terminal-speed run)",
    "R": "an LCR meter table (or a terminal-speed run)",
    "J": "a spin-down with the flywheel's inertia given (or a free spin-up)",
    "kV": "a SysId file or a Road Runner ramp",
    "kA": "a SysId file or a Road Runner ramp",
}


@dataclass(frozen=True)
class Task:
    """One task of the browser app's first screen: ``title`` as the student would say it, ``short`` for the
    tab's title and ``needs``, the files it takes."""

    title: str
    short: str
    needs: str

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


#: The app's tasks (ui/static/js/tasks.js lists their steps; these are their words).
TASKS: dict[str, Task] = {
    "drive": Task("Tune a Road Runner or Pedro Pathing drive", "Drive",
                  "The files Road Runner's ramp loggers save (ForwardRampLogger …, .json) or its FlightRecorder "
                  "logs (.log)."),
    "mechanism": Task("Tune a mechanism: flywheel, arm, elevator or drivetrain", "Mechanism",
                      "A WPILib SysId file (.json, .wpilog) or an FTC OpMode log (a spin-down), with an LCR table "
                      "when you have one."),
    "bench": Task("Characterise motors on a bench", "Bench",
                  "A session: its .toml file with its logs chosen together, its folder, or a .zip of the folder; "
                  "or a dynamometer's runs (locked-rotor runs, a motor curve: VEX's exports), fitted together."),
    "expert": Task("Analyse one experiment", "One experiment",
                   "For instructors and experts: any log of a bench experiment (LCR table, spin-down, torque on "
                   "a lever, terminal speed …)."),
}


#: Words of the analyses' messages a student does not use, and what the page says instead (pattern, words): the
#: page shows every warning, note and progress line through these (the CLI and the report keep the terms an
#: expert looks up). Patterns are regular expressions (JavaScript's and Python's alike), applied in order.
PLAIN_WORDS: tuple[tuple[str, str], ...] = (
    (r"Newey(?:[–-]| and )West(?: covariance| sandwich)?", "allowing for noise that lingers from sample to sample"),
    (r"χ²", "misfit"),
    (r"\bfrom a prior on\b", "from a typical value of"),
    (r"\ba prior on\b", "a typical value of"),
    (r"\bthe prior\b", "typical motors"),
    (r"\bprior\b", "typical value"),
    (r"\bthe seeds' experiments\b", "the bench experiments"),
    (r"\bthe seeds'", "the reference documents'"),
    (r"\bseeds\b", "reference documents"),
    (r"per unit of K·i", "as the motor's torque sees them"),
    (r"K·i", "the motor's torque"),
)


def plain_words(text: str) -> str:
    """``text`` with :data:`PLAIN_WORDS` applied (what the page shows)."""
    import re

    for pattern, words in PLAIN_WORDS:
        text = re.sub(pattern, words, text)
    return text


def choice_words(option: str, choice: str) -> str:
    """A choice of ``option`` in words (the choice itself when :data:`CHOICES` has none)."""
    return CHOICES.get(option, {}).get(choice, choice)
