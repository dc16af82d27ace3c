"""Where a locked-rotor run stops being a healthy stall, and why (:mod:`motorlab.analyses.stall`).

A healthy stall at a held voltage has a current that only falls as the copper warms, and a torque
per amp that changes slowly. A run is cut at its first sample that breaks this, and the break is
named from what the voltage, current and torque do there:

- supply cut: the voltage falls to ~0 (a few mV) and the current to 0 (the test stopped);
- open winding: the current falls to 0 while the voltage holds;
- supply current limit: the voltage sags below its set point while the current stays flat at the
  limit (100.0x, 120.03, 140.03 A on VEX's dynamometer);
- shorted turns: the current rises while the voltage holds (and the torque per amp drops);
- torque collapse: the torque per amp collapses while the current stays high.

A run that starts at the supply's current limit (the voltage still rising to its set point while the
cold winding draws more than the limit) is not cut there: the measured voltage drives the model.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Relative rise of the current above its running minimum, at held voltage, that marks shorted
#: turns when the torque per amp drops with it (VEX's healthy runs wobble by up to ~4 %: brush contact).
CURRENT_RISE = 0.05
#: The same without a torque column to confirm it.
CURRENT_RISE_ALONE = 0.06
#: Drop of the torque per amp below its recent median that confirms shorted turns [-].
TORQUE_PER_AMP_DROP = 0.05
#: Drop of the torque per amp that is a torque collapse on its own [-].
TORQUE_COLLAPSE = 0.25
#: A current below this fraction of the run's first is no current [-].
NO_CURRENT = 0.02
#: Voltage below this fraction of the set point: the supply sags (current limit) [-].
VOLTAGE_SAG = 0.98


@dataclass(frozen=True)
class Cut:
    """The end of a run's healthy part: ``index`` is the first sample left out (``None``: healthy to the end)."""

    index: int | None
    time: float | None
    cause: str
    detail: str
    later: tuple[str, ...] = ()


def set_point(voltage: np.ndarray) -> float:
    """The supply's set point [V]: the most frequent voltage (to 10 mV) among those within 5 % of the largest."""
    v = np.round(np.asarray(voltage, dtype=float), 2)
    top = float(np.max(v))
    near = v[v >= 0.95 * top]
    values, counts = np.unique(near, return_counts=True)
    return float(values[int(np.argmax(counts))])


def first_full_sample(current: np.ndarray) -> int:
    """The first sample whose current has finished rising (the supply switches on during the first; rows
    logged before it, at no current, are skipped)."""
    i = np.abs(np.asarray(current, dtype=float))
    if i.size == 0 or not np.max(i) > 0:
        return 0
    on = int(np.flatnonzero(i > NO_CURRENT * float(np.max(i)))[0])
    head = i[on : on + 5]
    peak = float(np.max(head))
    return on + int(np.flatnonzero(head >= 0.97 * peak)[0])


def find_cut(time: np.ndarray, current: np.ndarray, voltage: np.ndarray, torque: np.ndarray | None,
             start: int, v_set: float) -> Cut:
    """The first sample after ``start`` at which the run is no longer a healthy stall, and its cause."""
    i = np.asarray(current, dtype=float)
    v = np.asarray(voltage, dtype=float)
    q = None if torque is None else np.asarray(torque, dtype=float)
    i0 = float(i[start])
    reached = bool(v[start] >= 0.995 * v_set)
    run_min = i0
    ratios: list[float] = []
    rise_count = 0
    for k in range(start + 1, i.size):
        cause = _cause(k, i, v, q, i0, v_set, reached, run_min, ratios)
        if cause is None and q is None and i[k] > (1 + CURRENT_RISE_ALONE) * run_min:
            rise_count += 1
            if rise_count >= 2:
                k -= 1
                cause = ("shorted turns", f"the current rises to {i[k]:.4g} A, {100 * (i[k] / run_min - 1):.0f} % "
                         f"above its lowest {run_min:.4g} A, while the voltage holds at {v[k]:.4g} V")
        elif cause is None:
            rise_count = 0
        if cause is not None:
            return Cut(k, float(time[k]), cause[0], cause[1], _later(k, i, v, v_set, time))
        if v[k] >= 0.995 * v_set:
            reached = True
        if reached:  # the lowest current so far, of a 3-sample running median (a one-sample dip is a flicker)
            run_min = min(run_min, _median(i[max(start, k - 2) : k + 1].tolist()))
        if q is not None and i[k] > 0:
            ratios.append(float(q[k] / i[k]))
    return Cut(None, None, "", "")


def _median(values: list[float]) -> float:
    """The median of a few numbers (numpy's costs ~100 µs a call, which a 2 M-sample run pays per sample)."""
    ordered = sorted(values)
    half = len(ordered) // 2
    return float(ordered[half]) if len(ordered) % 2 else 0.5 * (ordered[half - 1] + ordered[half])


def _cause(k: int, i: np.ndarray, v: np.ndarray, q: np.ndarray | None, i0: float, v_set: float, reached: bool,
           run_min: float, ratios: list[float]) -> tuple[str, str] | None:
    """The cause that sample ``k`` breaks the stall with, as (short name, what the signals do), or None."""
    if abs(i[k]) < NO_CURRENT * i0:
        if v[k] < 0.05 * v_set:
            return "supply cut", f"the voltage falls to {v[k]:.3g} V and the current to {i[k]:.3g} A"
        return "open winding", f"the current falls to {i[k]:.3g} A while the voltage holds at {v[k]:.4g} V"
    if reached and v[k] < VOLTAGE_SAG * v_set:
        return ("supply current limit", f"the current is held at {i[k]:.5g} A while the voltage sags to "
                f"{v[k]:.4g} V, below its {v_set:.4g} V set point")
    recent = _median(ratios[-5:]) if ratios else float("nan")
    ratio = float(q[k] / i[k]) if q is not None and i[k] > 0 else float("nan")
    # Shorted turns: the current up and the torque per amp down, at this sample and the next (a brush
    # contact that flickers for one sample is not a failure).
    nxt = min(k + 1, i.size - 1)
    ratio_next = float(q[nxt] / i[nxt]) if q is not None and i[nxt] > 0 else float("nan")
    if (reached and min(i[k], i[nxt]) > (1 + CURRENT_RISE) * run_min
            and max(ratio, ratio_next) < (1 - TORQUE_PER_AMP_DROP) * recent):
        return ("shorted turns", f"the current rises to {i[k]:.4g} A, {100 * (i[k] / run_min - 1):.0f} % above its "
                f"lowest {run_min:.4g} A, at a held {v[k]:.4g} V, and the torque per amp drops "
                f"{100 * (1 - ratio / recent):.0f} %")
    if ratio < (1 - TORQUE_COLLAPSE) * recent:
        return ("torque collapse", f"the torque per amp drops {100 * (1 - ratio / recent):.0f} % "
                f"({recent:.3g} -> {ratio:.3g} N·m/A) while the current stays at {i[k]:.4g} A")
    return None


def _later(k: int, i: np.ndarray, v: np.ndarray, v_set: float, time: np.ndarray) -> tuple[str, ...]:
    """What the rest of the run shows after the cut, in order: the current limit, the supply cut, 0 A."""
    i_ref = float(np.max(np.abs(i[: k + 1]))) if k >= 0 else 1.0
    found: list[tuple[float, str]] = []
    rest = np.arange(k + 1, i.size)
    sag = rest[(v[rest] < VOLTAGE_SAG * v_set) & (v[rest] > 0.05 * v_set) & (i[rest] > NO_CURRENT * i_ref)]
    if sag.size:
        j = int(sag[0])
        found.append((float(time[j]), f"the supply's current limit at {time[j]:.1f} s ({i[j]:.5g} A, {v[j]:.4g} V)"))
    off = rest[(np.abs(i[rest]) < NO_CURRENT * i_ref)]
    if off.size:
        j = int(off[0])
        what = "the supply cut" if v[j] < 0.05 * v_set else "no current at a held voltage (open winding)"
        found.append((float(time[j]), f"{what} at {time[j]:.1f} s"))
    return tuple(text for _, text in sorted(found))
