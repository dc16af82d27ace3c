"""The LQR's tolerances (Bryson's rule) in physical terms, so that units never change a design.

SysId's defaults (qp = 1, qv = 1.5, r = 7 V) are numbers in whatever length unit the analysis used: the
same motor gets another controller in radians, rotations, ticks or metres of a wheel. :func:`tune`
(:mod:`motorlab.control.tune`) instead scales each default to the mechanism itself:

* velocity tolerance qv = :data:`VELOCITY_FRACTION` of the free speed (V − kS)/kV at the supply voltage;
* position tolerance qp = the distance that velocity tolerance covers in one time constant τ = kA/kV
  (qp = qv·τ);
* effort tolerance r = :data:`EFFORT_FRACTION` of the supply voltage (SysId's 7 V of its 12 V).

All three are the same physical quantities whatever unit the gains are printed in, so the design, and
every dimensionless figure of it (Road Runner's axialGain·s, axialVelGain), is the same. They are also
the motor's own scales: in time measured in τ, speed in free speeds and voltage in supply voltages every
motor's LQR problem is the same one (up to kS and the sampling), so the default loop is about three
times as fast as the motor alone, for a small gearmotor as for a flywheel (docs/control.md).

A tolerance the user gives keeps its units: a plain number is in the length unit in use (``--units``,
metres with a wheel radius), a text is read with pint (``"2 deg"``, ``"0.5 in"``, ``"30 rpm"``,
``"0.2 m/s"``, ``"100 ticks"``, ``"3 V"``), and a percentage (``"5 %"``) is a fraction of the scale above.
"""

from __future__ import annotations

import contextlib
import math
import re
from dataclasses import dataclass
from typing import Any

from motorlab.control.loop import Feedforward
from motorlab.control.plant import MechanismUnits
from motorlab.errors import OptionError

#: Default velocity tolerance: this fraction of the free speed (V − kS)/kV at the supply voltage.
VELOCITY_FRACTION = 0.2
#: Default position tolerance: the velocity tolerance held for this many time constants kA/kV.
POSITION_TIME_CONSTANTS = 1.0
#: Default effort tolerance: this fraction of the supply voltage (SysId's 7 V at 12 V).
EFFORT_FRACTION = 7.0 / 12.0

_TWO_PI = 2 * math.pi
_PERCENT = re.compile(r"^\s*([^%]*?)\s*(%|percent)\s*$", re.IGNORECASE)
_TICKS = re.compile(r"\b(ticks?|counts?|ct)\b", re.IGNORECASE)


@dataclass(frozen=True)
class Tolerances:
    """The LQR's tolerances in SI, with the scales they are fractions of.

    Attributes
    ----------
    qp
        Position tolerance [rad].
    qv
        Velocity tolerance [rad/s].
    r
        Effort tolerance [V].
    free_speed
        (V − kS)/kV at the supply voltage [rad/s].
    voltage
        Supply voltage [V].
    """

    qp: float
    qv: float
    r: float
    free_speed: float
    voltage: float

    def settings(self, units: MechanismUnits) -> dict[str, float]:
        """The tolerances for reports: in the user's length unit, and as fractions of their scales."""
        n = units.per_radian
        return {
            "qp": self.qp * n, "qv": self.qv * n, "r": self.r,
            "qp_revolutions": self.qp / _TWO_PI,
            "qv_of_free_speed": self.qv / self.free_speed,
            "r_of_voltage": self.r / self.voltage,
        }



def describe_settings(settings: dict[str, float]) -> str:
    """A design's tolerances (:meth:`Tolerances.settings`) in words: "position 4.7 % of a revolution, ..."."""
    parts = []
    for key, what, scale in (("qp_revolutions", "position", "a revolution"), ("qv_of_free_speed", "velocity",
                             "the free speed"), ("r_of_voltage", "effort", "the supply voltage")):
        if key in settings:
            fraction = settings[key]
            parts.append(f"{what} {_pct(fraction)} of {scale}" if math.isfinite(fraction) else f"{what} not limited")
    return ", ".join(parts)


def _pct(fraction: float) -> str:
    return f"{100 * fraction:.3g} %"


def design_tolerances(
    feedforward: Feedforward,
    voltage: float,
    units: MechanismUnits,
    *,
    qp: float | str | None = None,
    qv: float | str | None = None,
    r: float | str | None = None,
) -> Tolerances:
    """The tolerances of a design: each one the user's, or the physical default.

    Parameters
    ----------
    feedforward
        The plant (SI), for its free speed.
    voltage
        Supply voltage [V].
    units
        The user's length unit: a plain number given for ``qp``, ``qv`` is in it.
    qp, qv, r
        None for the default (module docstring); a number (``qp`` [unit], ``qv`` [unit/s], ``r`` [V]);
        or a text with a unit or a percentage.

    Returns
    -------
    Tolerances

    Raises
    ------
    OptionError
        When the motor cannot move at ``voltage``, or for a tolerance that is not a positive quantity
        of the right kind (a length without a wheel radius, ticks without counts per revolution ...).
    """
    free = feedforward.free_speed(voltage)
    if not free > 0:
        raise OptionError(f"at {voltage:g} V the motor cannot overcome kS = {feedforward.kS:.3g} V")
    scales = {"qp": _TWO_PI, "qv": free, "r": voltage}
    qv_default = VELOCITY_FRACTION * free
    defaults = {"qp": POSITION_TIME_CONSTANTS * feedforward.time_constant * qv_default, "qv": qv_default,
                "r": EFFORT_FRACTION * voltage}
    values = {}
    for name, given in (("qp", qp), ("qv", qv), ("r", r)):
        value = defaults[name] if given is None else _parse(given, name, units, scales[name])
        if not value > 0:  # also NaN; inf is allowed: that error is not penalised
            raise OptionError(f"--{name} must be a positive tolerance, got {given!r}")
        values[name] = value
    return Tolerances(values["qp"], values["qv"], values["r"], free, voltage)


def _parse(given: Any, name: str, units: MechanismUnits, scale: float) -> float:
    """One user tolerance in SI (rad, rad/s or V); see :func:`design_tolerances`."""
    label = f"--{name}"
    if isinstance(given, bool):
        raise OptionError(f"{label}: expected a number or a quantity, got {given!r}")
    if isinstance(given, int | float):
        return _plain(float(given), name, units)
    text = str(given).strip()
    try:
        return _plain(float(text), name, units)
    except ValueError:
        pass
    percent = _PERCENT.match(text)
    if percent:
        try:
            return float(percent.group(1)) / 100.0 * scale
        except ValueError:
            raise OptionError(f"{label}: {text!r} is not a percentage") from None
    from motorlab.units import parse_quantity

    if name == "r":
        return parse_quantity(text, "V", name=label)
    per_time = "/s" if name == "qv" else ""
    if _TICKS.search(text):
        if units.cpr is None:
            raise OptionError(f"{label}: {text!r} counts encoder ticks: give the encoder's counts per revolution")
        counts = parse_quantity(_TICKS.sub("count", text), f"count{per_time}", name=label)
        return counts * _TWO_PI / units.cpr
    from motorlab.units import registry

    quantity: Any = None
    with contextlib.suppress(Exception):  # pint's many error types: parse_quantity below says what is wrong
        quantity = registry().Quantity(text)
    length = f"[length]{'/[time]' if per_time else ''}"
    if quantity is not None and hasattr(quantity, "check") and quantity.check(length):
        if units.metres is None:
            raise OptionError(f"{label}: {text!r} is a length at a wheel: give the wheel radius too")
        return parse_quantity(text, f"m{per_time}", name=label) / units.metres
    return parse_quantity(text, f"rad{per_time}", name=label)


def _plain(value: float, name: str, units: MechanismUnits) -> float:
    """A plain number: volts for ``r``, else the user's length unit (per second for ``qv``)."""
    if math.isnan(value):
        raise OptionError(f"--{name}: {value!r} is not a number")
    return value if name == "r" else units.to_si(value)
