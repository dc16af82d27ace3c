"""Every parameter an analysis or ``tune`` reports, named in words with its symbol and SI unit.

The key is the name in results (``analyze --json``'s ``parameters``, ``results.json``, ``tune``'s
gains); docs/glossary.md is the same list for people. The browser app shows results as
"Back-EMF constant K" with these, never a bare key.
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
    "kF": _P("Velocity feedforward (hub F)", "F", ""),
}


def describe(key: str) -> dict[str, Any]:
    """The description of ``key`` as JSON (the key itself as the name when it is not listed)."""
    found = PARAMETERS.get(key)
    return found.to_dict() if found is not None else {"name": key, "symbol": key, "unit": ""}
