"""Fitted values that break physics are never printed silently.

Every :class:`~motorlab.results.FitResult` passes through :func:`check_signs` when it is made: a
parameter that must be positive (K, R, L, J, b, Tf, kS, kV, kA …) and comes out negative gets a
warning naming the likely cause; when the user's own options (estimates marked ``note="given"``)
are what push it below zero, and clearly so, the result is refused with an :class:`OptionError`
that names those options.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import TYPE_CHECKING

from motorlab.errors import OptionError
from motorlab.units import format_unit

if TYPE_CHECKING:
    from motorlab.results import Estimate

#: Parameter -> (likely cause of a negative value, the given parameters that can force it below zero).
MUST_BE_POSITIVE: dict[str, tuple[str, tuple[str, ...]]] = {
    "K": ("the log is not this experiment's (the speed does not rise under a steady current), or the "
          "encoder or the current is reversed", ()),
    "R": ("the leads or the meter are reversed, or the current and voltage columns are swapped", ()),
    "R_dc": ("the meter's zero offset (null the leads first)", ()),
    "L": ("the meter's zero offset or open/short compensation", ()),
    "J": ("friction given too large, or a log that is not a spin-up or coast", ("b", "Tf", "K")),
    "b": ("Coulomb friction Tf given or fitted too large, K given too large, or too narrow a speed range",
          ("Tf", "K", "R", "J")),
    "Tf": ("viscous friction b given too large, or speeds that do not reach low enough", ("b", "K", "J")),
    "gamma": ("the shaft speeds up while it should coast (a drive left on?)", ()),
    "Tf_over_J": ("the coast does not slow down as friction would (a drive left on?)", ()),
    "kS": ("too narrow a voltage range (kS is the voltage at zero speed)", ()),
    "kV": ("the encoder or the voltage is reversed", ()),
    "kA": ("the encoder or the voltage is reversed, or the dynamic tests are missing", ()),
}

#: A negative value farther than this many standard errors below zero is "clearly" negative.
SIGNIFICANT = 2.0


def _given(parameters: Mapping[str, Estimate]) -> dict[str, Estimate]:
    return {name: est for name, est in parameters.items() if est.note.strip().lower().startswith("given")}


def _show(est: Estimate) -> str:
    se = f" ± {est.stderr:.2g}" if math.isfinite(est.stderr) and est.stderr > 0 else ""
    return f"{est.value:.4g}{se} {format_unit(est.unit)}"


def check_signs(parameters: Mapping[str, Estimate]) -> list[str]:
    """Warnings for parameters fitted negative that physics wants positive.

    Parameters
    ----------
    parameters
        The estimates of a fit, by symbol.

    Returns
    -------
    list of str
        One warning per negative parameter, with the likely cause.

    Raises
    ------
    OptionError
        A parameter clearly negative (more than :data:`SIGNIFICANT` standard errors below zero)
        because of values the user gave (``note="given"``) that can force it there: the options
        contradict the data.
    """
    given = _given(parameters)
    warnings = []
    for name, est in parameters.items():
        if name not in MUST_BE_POSITIVE or name in given or not est.determined:
            continue
        if not (math.isfinite(est.value) and est.value < 0):
            continue
        cause, forced_by = MUST_BE_POSITIVE[name]
        clear = not math.isfinite(est.stderr) or est.value < -SIGNIFICANT * est.stderr
        culprits = [g for g in forced_by if g in given]
        if clear and culprits:
            options = ", ".join(f"{g} = {_show(given[g])}" for g in culprits)
            raise OptionError(
                f"with the given {options}, {name} comes out negative ({_show(est)}), which no motor has: "
                f"the given value contradicts the data (likely cause: {cause})"
            )
        tail = "" if clear else ", though within its uncertainty of zero"
        warnings.append(f"{name} is fitted negative ({_show(est)}), which no motor has{tail}: likely cause: {cause}")
    return warnings
