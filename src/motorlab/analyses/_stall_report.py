"""What :mod:`motorlab.analyses.stall` reports: the run table, the answers teams want, estimates, panels."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from motorlab.analyses._stall_fit import (
    PRIOR_CASE_TIME_CONSTANT,
    SHARED,
    HeatFit,
    StallData,
    TorqueFit,
    simulate_runs,
)
from motorlab.results import Estimate, Panel, Series
from motorlab.thermal.network import ThermalModel, continuous_current, steady_stall_temperature, time_to_temperature

#: Most current-vs-time panels drawn (one per run).
MAX_PANELS = 8

_UNITS = {"R": "ohm", "R_wc": "K/W", "R_ca": "K/W", "C_w": "J/K", "C_c": "J/K"}
_NOTES = {
    "R": "winding resistance at 25 °C",
    "R_wc": "thermal resistance winding -> case",
    "R_ca": "thermal resistance case -> ambient",
    "C_w": "heat capacity of the winding (armature)",
    "C_c": "heat capacity of the case (housing, magnets)",
}


def run_rows(runs: Sequence[Any], used: list[int], fitted: list[int],
             heat: HeatFit) -> tuple[list[dict[str, Any]], list[str]]:
    """One row per file (set point, cut, temperatures) and the warnings naming each cut."""
    rows, warnings = [], []
    shared = [heat.values[n] for n in SHARED]
    for k, run in enumerate(runs):
        j = used.index(k) if k in used else None
        pos = fitted.index(j) if j is not None and j in fitted else None
        t0 = heat.initial[pos] if pos is not None else None
        t_cut = None
        if t0 is not None and run.cut.index is not None:
            sl = slice(run.start, run.cut.index + 1)
            data = StallData(run.source, run.time[sl] - run.switch_on, run.voltage[sl], run.current[sl], None)
            t_cut = float(simulate_runs(shared, [t0], [data], heat.thermal.magnet_coefficient,
                                        heat.thermal.ambient_temperature)[0][1][-1])
        rows.append({
            "file": run.source.replace("\\", "/").rsplit("/", 1)[-1],
            "set point (V)": run.set_point,
            "first full sample (s)": float(run.time[run.start]),
            "healthy samples": int(max(run.end - run.start, 0)),
            "cut (s)": run.cut.time,
            "cause": run.cut.cause or "healthy to the end",
            "initial winding temperature (°C)": t0,
            "winding at the cut (°C)": t_cut,
            "fit RMS (%)": None if pos is None else 100 * heat.run_rms[pos],
            "heating explains it": pos is not None,
        })
        if run.cut.index is not None:
            where = f"; the winding was at about {t_cut:.0f} °C" if t_cut is not None else ""
            later = f"; afterwards: {', '.join(run.cut.later)}" if run.cut.later else ""
            warnings.append(f"{rows[-1]['file']}: cut at {run.cut.time:.1f} s: {run.cut.cause} ({run.cut.detail})"
                            f"{where}{later}")
    return rows, warnings


def _propagate(heat: HeatFit, func: Callable[[list[float]], float]) -> float:
    """Standard error of ``func(shared)`` from the covariance of the logarithms of the shared parameters."""
    base = [heat.values[n] for n in SHARED]
    f0 = func(base)
    if not math.isfinite(f0) or heat.log_covariance.size == 0:
        return math.nan
    grad = np.zeros(len(SHARED))
    for k in range(len(SHARED)):
        step = 1e-4
        x = list(base)
        x[k] = base[k] * math.exp(step)
        grad[k] = (func(x) - f0) / step
    cov = np.nan_to_num(heat.log_covariance)
    return float(math.sqrt(max(float(grad @ cov @ grad), 0.0)))


def _thermal_of(heat: HeatFit, shared: list[float]) -> ThermalModel:
    th = heat.thermal
    return ThermalModel(shared[1], shared[2], shared[3], shared[4], th.magnet_coefficient,
                        th.resistance_coefficient, th.ambient_temperature)


def answers(heat: HeatFit, opts: dict[str, Any]) -> tuple[dict[str, Estimate], list[str]]:
    """How long a stall takes to reach the limit, the current held indefinitely, R hot against cold."""
    v, limit, rise = float(opts["answer_voltage"]), float(opts["limit"]), float(opts["rise"])
    ambient = heat.thermal.ambient_temperature
    hottest = float(max(float(np.max(w)) for w in heat.winding))
    out: dict[str, Estimate] = {}
    warnings: list[str] = []

    def t_limit(s: list[float]) -> float:
        return time_to_temperature(s[0], _thermal_of(heat, s), v, limit)

    def i_cont(s: list[float]) -> float:
        return continuous_current(s[0], _thermal_of(heat, s), rise)[0]

    base = [heat.values[n] for n in SHARED]
    t = t_limit(base)
    if math.isfinite(t):
        out["t_limit"] = Estimate(
            "t_limit", t, _propagate(heat, t_limit), "s", True,
            f"time a stall at {v:g} V takes to bring the winding from {ambient:g} to {limit:g} °C")
    else:
        settle = steady_stall_temperature(base[0], heat.thermal, v)
        out["t_limit"] = Estimate("t_limit", math.inf, math.nan, "s", True,
                                  f"never: a stall at {v:g} V settles at {settle:.0f} °C, below {limit:g} °C")
    i = i_cont(base)
    i_se = _propagate(heat, i_cont)
    told = math.isfinite(i_se) and i_se < i
    out["I_continuous"] = Estimate(
        "I_continuous", i, i_se, "A", told,
        f"stall current held indefinitely with the winding {rise:g} K above ambient"
        + ("" if told else ": needs R_ca, which runs this short cannot tell"))
    r_hot = base[0] * heat.thermal.resistance_factor(limit)
    out["R_hot"] = Estimate(
        "R_hot", r_hot, heat.stderr["R"] * heat.thermal.resistance_factor(limit), "ohm", True,
        f"winding resistance at {limit:g} °C ({100 * (r_hot / base[0] - 1):.0f} % above R at 25 °C)")
    for what, temp in ((f"the time to {limit:g} °C", limit), (f"the current for a {rise:g} K rise", ambient + rise)):
        if temp > hottest + 1:
            warnings.append(f"{what} extrapolates the heating model {temp - hottest:.0f} K beyond the hottest "
                            f"winding temperature the fit saw ({hottest:.0f} °C)")
    return out, warnings


def parameters_of(heat: HeatFit, torque: TorqueFit | None, extra: dict[str, Estimate]) -> dict[str, Estimate]:
    """K and τ₀ (with torque), R₂₅ and the network, then the answers."""
    out: dict[str, Estimate] = {}
    if torque is not None:
        note = (f"torque per amp at 25 °C (the magnets' coefficient applied at the case temperature: "
                f"{100 * torque.beta:+.3g} %/K, within the magnets' [{100 * torque.magnet:+.2g}, 0] %/K)" if torque.beta
                else "torque per amp the rows show, at the runs' temperatures (see the warnings)")
        if len(torque.per_run) > 1:
            note += (f"; the random-effects mean of {len(torque.per_run)} runs' K (DerSimonian–Laird"
                     + (f": their spread {torque.between:.2g} N·m/A is in the standard error)" if torque.between
                        else ": they agree)"))
        if not torque.K > 0:  # never printed silently: a torque against the current is positive
            note = ("not determined: the fit gives a torque per amp that is not positive (the runs' torque and "
                    "current disagree: another shaft, a sensor's sign or offset)")
        out["K"] = Estimate("K", torque.K, torque.K_stderr, "N*m/A", bool(torque.K > 0), note)
        if math.isfinite(torque.tau0_stderr):
            out["tau0"] = Estimate("tau0", torque.tau0, torque.tau0_stderr, "N*m", True,
                                   "torque at zero current (a sensor offset, friction held, or saturation's curve)")
    for k, name in enumerate(SHARED):
        determined = bool(heat.fit.determined[k]) and math.isfinite(heat.stderr[name])
        note = _NOTES[name] if determined else _NOTES[name] + ": the runs are too short to tell it"
        if heat.held and name != "R":
            determined = False
            note = _NOTES[name] + ": held at the network of the motor's other runs (not fitted to these)"
        elif heat.winding_from_prior and name in ("R_wc", "C_w"):
            determined = False
            note = (_NOTES[name] + ": the run alone needs a winding slower than its case; its time constant R_wc·C_w "
                    "is held near the population's")
        elif name == "R_ca" and heat.prior:
            determined = False
            note = (_NOTES[name] + f": the runs are too short to tell it; {heat.values[name]:.3g} K/W comes from a "
                    f"prior on the case's time constant R_ca·C_c ≈ {PRIOR_CASE_TIME_CONSTANT:.0f} s (real motors' "
                    "population; used by forecasts)")
        out[name] = Estimate(name, heat.values[name], heat.stderr[name], _UNITS[name], determined, note)
    out.update(extra)
    return out


def make_panels(runs: Sequence[Any], used: list[int], fitted: list[int], heat: HeatFit,
                torque: TorqueFit | None) -> list[Panel]:
    """Current against time with the fit and the cut marked, per run; the winding temperature estimated."""
    panels: list[Panel] = []
    temps: list[Series] = []
    for pos, j in enumerate(fitted):
        run = runs[used[j]]
        d = run.data()
        t = d.time + d.offset
        name = run.source.replace("\\", "/").rsplit("/", 1)[-1]
        temps.append(Series(t, heat.winding[pos], f"{name}: winding", kind="model"))
        if len(panels) >= MAX_PANELS:
            continue
        extra = []
        rest = slice(run.end, None)
        if run.time[rest].size:
            extra.append(Series(run.time[rest], run.current[rest], "after the cut (not fitted)", kind="data"))
        if run.cut.index is not None:
            extra.append(Series(np.array([run.cut.time]), np.array([run.current[run.cut.index]]),
                                f"cut at {run.cut.time:.1f} s: {run.cut.cause}", kind="data"))
        panels.append(Panel(f"{name}: current at {run.set_point:.4g} V", "time [s]", "current [A]",
                            data=Series(t, d.current, "measured"),
                            model=Series(t, heat.model_current[pos], "heating model"), extra=extra))
    panels.append(Panel("winding temperature (estimated)", "time [s]", "temperature [°C]", extra=temps))
    return panels
