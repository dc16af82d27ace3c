"""The report's thermal section: each unit's stall fit in words (:mod:`motorlab.report.document`)."""

from __future__ import annotations

import html
import math
from typing import Any


def _e(text: Any) -> str:
    return html.escape(str(text), quote=True)


def _value(est: Any, digits: str = ".3g") -> str:
    if est is None or not est.determined or not math.isfinite(est.value):
        return "not determined"
    if not math.isfinite(est.stderr):
        return f"{est.value:{digits}}"
    return f"{est.value:{digits}} ± {est.stderr:.2g}"


def thermal_section(result: Any) -> str:
    """``<section id="thermal">``: R at 25 °C, R hot, time to 150 °C at 12 V, the current held, the cuts."""
    rows, notes = [], []
    for name, unit in result.units.items():
        fit = unit.fits.get("stall")
        if fit is None:
            continue
        p = fit.parameters
        t_lim = p.get("t_limit")
        lim_text = ("never" if t_lim is not None and t_lim.determined and math.isinf(t_lim.value)
                    else _value(t_lim, ".1f") + " s")
        rows.append("<tr>" + "".join(f"<td>{_e(c)}</td>" for c in (
            unit.spec.display_name, _value(p.get("R"), ".4g") + " Ω", _value(p.get("R_hot"), ".4g") + " Ω",
            lim_text, _value(p.get("I_continuous")) + " A", _value(p.get("R_wc")) + " K/W",
            _value(p.get("C_w")) + " J/K")) + "</tr>")
        notes += [f"Unit {unit.spec.display_name}: {w}" for w in fit.warnings
                  if "cut at" in w or "extrapolates" in w or "does not explain" in w]
        del name
    if not rows:
        return ""
    head = "".join(f"<th>{h}</th>" for h in ("unit", "R at 25 °C", "R at 150 °C", "stalled at 12 V until 150 °C",
                                              "stall current held (100 K rise)", "R winding→case", "C winding"))
    items = "".join(f"<li>{_e(n)}</li>" for n in notes)
    return ('<section id="thermal"><h2>Heat: how long a stalled motor lasts</h2>'
            '<p>From each unit\'s stall run (analyze stall): the winding\'s resistance at 25 °C and hot, how long '
            'a stall at 12 V takes to bring the winding from 25 °C to 150 °C (enamel of class F/H), and the stall '
            'current the motor holds indefinitely with its winding 100 K above the air.</p>'
            f"<table><thead><tr>{head}</tr></thead><tbody>{''.join(rows)}</tbody></table>"
            + (f"<ul>{items}</ul>" if items else "") + "</section>")
