"""Fleet statistics: mean ± spread of each parameter over the units of one model, and the units that stand out.

Seed 1's "Final Calculated Parameters" lists AM 40 B with b = 0.56 against 0.23 and 0.018 for its
siblings, and nobody remarks on it. :func:`fleet_summary` answers "which of our motors is worn?".

The outlier rule (robust z-score on logarithms)
----------------------------------------------
Motor parameters are positive and vary multiplicatively (a worn gearbox doubles b; the virtual
rig draws units log-normally), so the test works on y = ln x. For one parameter of one model with
estimates x_i (standard errors σ_i) on n ≥ 3 units::

    m    = median(y)                                    the fleet's centre (breakdown point ½)
    sMAD = 1.4826 · median(|y − m|)                     robust spread (σ for normal data)
    s    = f_p                      if n < 5            the healthy spread f_p (a MAD of 3–4 points is noise)
    s    = max(sMAD, f_p)           if n ≥ 5            never below the healthy spread
    z_i  = (y_i − m) / sqrt(s² + (σ_i/x_i)²)            a unit's distance in combined spreads

and unit i is flagged when |z_i| > ``threshold`` (default 4). Iglewicz and Hoaglin cut modified
z-scores at 3.5; with three units a healthy unit's distance from the median (itself a draw) is
wider than one spread, and 3.5 flags about 1 healthy fleet of three in 55 over six parameters
(simulated with the floor equal to the true spread); 4 flags about 1 in 350, 4.5 about 1 in 1700.
Why each piece:

- With three units the MAD rests on one difference: tiny by chance when two units happen to agree,
  and inflated by the worn unit itself (which then hides behind the spread it creates — a doubled b
  in three units was found only about half the time with max(sMAD, f_p)). Below five units the
  spread is therefore the healthy spread alone; from five on the MAD may widen it. f_p is the relative unit-to-unit
  spread a healthy population shows (:data:`HEALTHY_SPREAD`, equal to the spreads the virtual
  rig draws units with, ``motorlab.rig.units.UnitSpread``), so that a healthy draw is not
  mistaken for wear. A session may give its own (``[fleet.spread]``).
- σ_i/x_i (the relative standard error, the standard error of ln x) keeps a poorly measured unit
  from being flagged for its own measurement noise.
- The centre includes the unit itself: with three units the median of the two others is their
  mean, which a single worn unit drags halfway, making its healthy siblings look like outliers.
- A parameter with a zero or negative estimate on some unit is tested on x itself, with
  s = max(1.4826·MAD(x), f_p·|median(x)|).

What it can and cannot see: a change is detectable when ln(change) is well above the threshold
times f_p. With the rig's default spread of b (10 %, from seed 1's sibling units), a doubled b
(ln 2 = 6.9 f_p) in a fleet of three is flagged in about 95 % of simulated fleets and no healthy
fleet of 200 raised a flag (``tests/session/test_fleet.py``); with a 25 % spread doubling would be only
2.8 spreads and could not be told from a healthy draw.

The message compares the unit with the median of its siblings (the others), which reads naturally:
"b is 2.1× the median of its siblings".

References
----------
B. Iglewicz and D. C. Hoaglin, *How to Detect and Handle Outliers* (ASQC, 1993): the modified
z-score 0.6745·(x − median)/MAD and its cut-off 3.5.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from motorlab.results import Estimate
from motorlab.units import format_unit

#: Relative unit-to-unit spread (σ of ln x) of healthy units of one model, per parameter [-].
#: Friction and resistance vary most (grease, gear mesh, brush contact); K and L follow the magnet
#: and winding and vary least (seed 1, "Final Calculated Parameters"). Equal to the defaults of
#: ``motorlab.rig.units.UnitSpread`` (a test checks it), so that a healthy simulated unit is not
#: mistaken for wear.
HEALTHY_SPREAD: dict[str, float] = {"K": 0.03, "R": 0.10, "L": 0.08, "J": 0.05, "b": 0.10, "Tf": 0.10}

#: Below this many units the spread is the healthy spread alone (the MAD of fewer points is noise).
MIN_UNITS_FOR_MAD = 5

#: Default spread floor for parameters not listed in :data:`HEALTHY_SPREAD` [-].
DEFAULT_HEALTHY_SPREAD = 0.10

#: |z| above which a unit stands out.
DEFAULT_THRESHOLD = 4.0

#: 1/Φ⁻¹(3/4): makes the MAD a consistent estimate of σ for normal data.
MAD_SCALE = 1.4826

#: Fewest units for which the outlier test is meaningful.
MIN_UNITS = 3


@dataclass(frozen=True)
class Outlier:
    """One unit whose parameter stands out from its siblings.

    Attributes
    ----------
    unit
        The unit's name.
    parameter
        Symbol (``"b"``).
    value
        The unit's estimate [SI unit of the parameter].
    sibling_median
        Median of the other units' estimates [same unit].
    z
        Robust z-score (see the module's rule).
    unit_str
        SI unit of the parameter.
    """

    unit: str
    parameter: str
    value: float
    sibling_median: float
    z: float
    unit_str: str = ""

    @property
    def ratio(self) -> float:
        """value / median of the siblings (NaN if the median is 0)."""
        return self.value / self.sibling_median if self.sibling_median != 0 else math.nan

    def message(self) -> str:
        """``"b is 2.1× the median of its siblings (z = +6.8)"``."""
        if math.isfinite(self.ratio) and self.ratio > 0:
            how = f"{self.ratio:.2g}× the median of its siblings"
        else:
            how = f"{self.value:.4g} {format_unit(self.unit_str)} against a sibling median of {self.sibling_median:.4g}"
        return f"{self.parameter} is {how} (z = {self.z:+.1f})"


@dataclass
class ParameterStats:
    """One parameter over the units of one model."""

    parameter: str
    unit: str
    values: dict[str, float]
    stderrs: dict[str, float]
    mean: float
    std: float
    median: float
    spread: float
    z: dict[str, float] = field(default_factory=dict)

    @property
    def n(self) -> int:
        """Number of units with a determined estimate."""
        return len(self.values)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary (SI)."""
        return {
            "unit": self.unit,
            "n": self.n,
            "mean": _finite(self.mean),
            "std": _finite(self.std),
            "median": _finite(self.median),
            "spread": _finite(self.spread),
            "z": {k: _finite(v) for k, v in self.z.items()},
        }


@dataclass
class FleetSummary:
    """Mean ± spread per parameter and the units that stand out, for one model."""

    model: str
    parameters: dict[str, ParameterStats]
    outliers: list[Outlier]
    threshold: float
    notes: list[str] = field(default_factory=list)

    @property
    def tested(self) -> bool:
        """True when the outlier test ran on at least one parameter (it needs three units)."""
        return any(stats.z for stats in self.parameters.values())

    def verdict(self) -> str:
        """One sentence: who stands out, that nobody does, or that no test could run."""
        if self.outliers:
            return "; ".join(f"unit {o.unit} stands out: {o.message()}" for o in self.outliers)
        if not self.tested:
            return f"no outlier test: it needs at least {MIN_UNITS} units with estimates of a parameter"
        return f"no unit stands out (|z| ≤ {self.threshold:g})"

    def outliers_of(self, unit: str) -> list[Outlier]:
        """The outliers of one unit."""
        return [o for o in self.outliers if o.unit == unit]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary."""
        return {
            "model": self.model,
            "threshold": self.threshold,
            "parameters": {k: v.to_dict() for k, v in self.parameters.items()},
            "outliers": [
                {
                    "unit": o.unit,
                    "parameter": o.parameter,
                    "value": o.value,
                    "sibling_median": o.sibling_median,
                    "ratio": _finite(o.ratio),
                    "z": o.z,
                    "message": o.message(),
                }
                for o in self.outliers
            ],
            "notes": list(self.notes),
        }


def robust_z(values: np.ndarray, stderrs: np.ndarray, *, relative_floor: float) -> tuple[np.ndarray, float, float]:
    """Robust z-scores of ``values`` (see the module docstring for the rule).

    Parameters
    ----------
    values
        One estimate per unit [any unit].
    stderrs
        Their standard errors [same unit]; NaN is taken as 0.
    relative_floor
        Healthy unit-to-unit spread, σ of ln x [-].

    Returns
    -------
    z, median, spread
        The z-scores, the centre (median of x) and the spread used (relative when the test ran on
        logarithms, else in the unit of x).
    """
    x = np.asarray(values, dtype=float)
    sigma = np.nan_to_num(np.asarray(stderrs, dtype=float), nan=0.0)
    if np.all(x > 0):
        y = np.log(x)
        sigma_y = sigma / x
        floor = relative_floor
    else:
        y, sigma_y = x, sigma
        floor = relative_floor * abs(float(np.median(x)))
    m = float(np.median(y))
    s_mad = MAD_SCALE * float(np.median(np.abs(y - m)))
    s = floor if x.size < MIN_UNITS_FOR_MAD else max(s_mad, floor)
    denom = np.sqrt(s**2 + sigma_y**2)
    with np.errstate(divide="ignore", invalid="ignore"):
        z = np.where(denom > 0, (y - m) / denom, 0.0)
    return z, float(np.median(x)), s


def fleet_summary(
    estimates: Mapping[str, Mapping[str, Estimate]],
    *,
    model: str = "",
    threshold: float = DEFAULT_THRESHOLD,
    healthy_spread: Mapping[str, float] | None = None,
    parameters: tuple[str, ...] = ("J", "b", "Tf", "K", "R", "L"),
) -> FleetSummary:
    """Fleet statistics and outliers for the units of one model.

    Parameters
    ----------
    estimates
        Unit name -> parameter symbol -> :class:`Estimate` (SI). Undetermined or missing estimates
        are left out of that parameter's statistics.
    model
        Name of the model, for the report.
    threshold
        |z| above which a unit is flagged [-].
    healthy_spread
        Healthy spread (σ of ln x) per parameter; missing ones default to :data:`HEALTHY_SPREAD`.
    parameters
        The parameters to examine, in report order.

    Returns
    -------
    FleetSummary
        Per parameter: mean, sample standard deviation, median, spread used and each unit's z;
        the outliers sorted by |z|, largest first.

    Notes
    -----
    With fewer than three units per parameter no unit is flagged (two disagreeing units cannot
    say which of them is off); the summary says so in ``notes``.
    """
    floors = {**HEALTHY_SPREAD, **(healthy_spread or {})}
    stats: dict[str, ParameterStats] = {}
    outliers: list[Outlier] = []
    notes: list[str] = []
    for name in parameters:
        usable = {
            unit: est
            for unit, params in estimates.items()
            if (est := params.get(name)) is not None and est.determined and math.isfinite(est.value)
        }
        if not usable:
            continue
        units = list(usable)
        x = np.array([usable[u].value for u in units])
        sigma = np.array([usable[u].stderr for u in units])
        unit_str = next(iter(usable.values())).unit
        mean = float(np.mean(x))
        std = float(np.std(x, ddof=1)) if x.size > 1 else math.nan
        entry = ParameterStats(
            parameter=name,
            unit=unit_str,
            values=dict(zip(units, x.tolist(), strict=True)),
            stderrs=dict(zip(units, sigma.tolist(), strict=True)),
            mean=mean,
            std=std,
            median=float(np.median(x)),
            spread=math.nan,
        )
        stats[name] = entry
        if x.size < MIN_UNITS:
            notes.append(f"{name}: only {x.size} unit(s) with an estimate; no outlier test")
            continue
        z, median, spread = robust_z(x, sigma, relative_floor=floors.get(name, DEFAULT_HEALTHY_SPREAD))
        entry.median, entry.spread = median, spread
        entry.z = dict(zip(units, z.tolist(), strict=True))
        for k, unit in enumerate(units):
            if abs(z[k]) > threshold:
                siblings = np.delete(x, k)
                outliers.append(Outlier(unit, name, float(x[k]), float(np.median(siblings)), float(z[k]), unit_str))
    outliers.sort(key=lambda o: -abs(o.z))
    return FleetSummary(model=model, parameters=stats, outliers=outliers, threshold=threshold, notes=notes)


def _finite(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None
