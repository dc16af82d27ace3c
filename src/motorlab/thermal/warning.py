"""The heat warning of the analyses that fit a warm motor as if it were cool (identify, terminal, spinup,
feedforward): a log whose I²·R energy warms the winding by more than 10 K
(:func:`motorlab.thermal.network.heat_warning`)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from motorlab.thermal.network import heat_warning

#: Resistance assumed when neither the fit nor the log tells it [Ω]: a NeveRest's winding (12 V / 11.5 A).
TYPICAL_RESISTANCE = 1.04


def _resistance(result: Any, recordings: Sequence[Any], given: float | None) -> tuple[float, str]:
    """R for the warning and where it comes from: given, fitted, V/I of the log (an upper bound) or typical."""
    if given is not None and math.isfinite(given) and given > 0:
        return float(given), "given"
    est = result.parameters.get("R") if hasattr(result, "parameters") else None
    if est is not None and est.determined and math.isfinite(est.value) and est.value > 0:
        return float(est.value), "fitted"
    ratios = []
    for rec in recordings:
        if "current" in rec and "voltage" in rec:
            i, v = np.abs(np.asarray(rec["current"], float)), np.abs(np.asarray(rec["voltage"], float))
            big = i > 0.3 * np.max(i) if i.size and np.max(i) > 0 else np.zeros(i.size, bool)
            if np.count_nonzero(big) >= 3:
                ratios.append(float(np.median(v[big] / i[big])))
    if ratios:
        return min(ratios), "V/I of the log, an upper bound"
    return TYPICAL_RESISTANCE, "not known here: a NeveRest's winding"


def add_heat_warning(result: Any, recordings: Sequence[Any], *, resistance: float | None = None,
                     hold: float | None = None) -> Any:
    """Append the heat warning of ``recordings`` to ``result.warnings`` (when a log warms the winding > 10 K).

    ``hold`` [s]: rows without a time axis (steady readings) are each taken as held that long.
    """
    r, source = _resistance(result, recordings, resistance)
    for rec in recordings:
        if "current" not in rec:
            continue
        current = np.asarray(rec["current"], dtype=float)
        time = np.arange(current.size) * hold if hold is not None else np.asarray(rec.time, dtype=float)
        name = str(rec.source or "this log").replace("\\", "/").rsplit("/", 1)[-1]
        note = source + (f"; each reading taken as held {hold:g} s" if hold is not None else "")
        text = heat_warning(time, current, r, what=name, resistance_note=note)
        if text and text not in result.warnings:
            result.warnings.append(text)
    return result
