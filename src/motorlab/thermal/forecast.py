"""Forecast a stall with a fitted heating model (``motorlab simulate stall --params FIT.json``).

The model is what ``motorlab analyze stall --json`` wrote: R at 25 °C, the thermal network, K and τ₀
when torque was measured, and where the fitted run started. The forecast holds a voltage on the
stalled winding (i = V/R(T_w), :func:`motorlab.thermal.network.stall_response`) and says how long the winding
takes to reach a limit, the current it holds indefinitely, and R hot against cold. Temperatures beyond
the hottest the fit saw are extrapolation, and are said to be.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from motorlab.errors import InputError, OptionError
from motorlab.thermal.network import (
    WINDING_LIMIT,
    StallRun,
    ThermalModel,
    continuous_current,
    stall_response,
    steady_stall_temperature,
    time_to_temperature,
)

#: Most samples a forecast writes.
MAX_FORECAST_SAMPLES = 2_000_000


@dataclass(frozen=True)
class StallModel:
    """A fitted stall: R₂₅ [Ω], the thermal network, K [N·m/A] and τ₀ [N·m] (NaN without torque), the
    initial winding temperature of the fitted run and the hottest winding temperature the fit saw [°C]."""

    resistance: float
    thermal: ThermalModel
    torque_constant: float = math.nan
    torque_offset: float = 0.0
    magnet_applied: bool = True
    initial_temperature: float = 25.0
    hottest: float = math.inf
    source: str = ""
    #: R_ca came from the fit's prior on the case's time constant (the run was too short to tell it).
    case_loss_from_prior: bool = False
    #: The brushes' contact at the end of the fitted run (``details["brush_contact"]`` of a lone run's fit): the
    #: resistance [Ω] the heating model did not account for then, the time it was measured at [s] and the run's
    #: set point [V]. A forecast that continues the run (at that voltage, from its start) holds it on from there.
    contact: dict[str, float] = field(default_factory=dict)
    #: Where the thermal network comes from, in words (``details["network"]`` of the fit): fitted to the run, held
    #: at the motor's other runs', or the population's winding.
    network: str = "fitted to these runs"
    #: The covariance of the logarithms of (R, R_wc, R_ca, C_w, C_c) from the fit's standard errors and correlation
    #: (empty: unknown), for the forecast's band.
    log_covariance: tuple[tuple[float, ...], ...] = ()


def load_fit(path: str | Path) -> StallModel:
    """The model of an ``analyze stall --json`` file.

    Raises
    ------
    InputError
        Not such a file (one line naming it and what is missing).
    """
    try:
        doc = json.loads(Path(path).read_text(encoding="utf-8-sig"))
    except FileNotFoundError:
        raise InputError("no such file", path=str(path)) from None
    except (ValueError, UnicodeDecodeError, IsADirectoryError):
        raise InputError("not a JSON file (give what 'motorlab analyze stall --json' wrote)", path=str(path)) from None
    if not isinstance(doc, dict) or doc.get("experiment") != "stall":
        raise InputError("not a stall fit: give what 'motorlab analyze stall --json' wrote", path=str(path))
    params, details = doc.get("parameters", {}), doc.get("details", {})
    if isinstance(details, dict) and details.get("unexplained"):
        raise InputError("no forecast from this fit: heating does not explain the run it was fitted to (its "
                         "resistance does not move as its heat makes it: brush contact, see the fit's warnings); fit a "
                         "healthy run with 'motorlab analyze stall'", path=str(path))

    def value(name: str) -> float:
        entry = params.get(name)
        v = entry.get("value") if isinstance(entry, dict) else None
        return math.nan if v is None else float(v)

    r = value("R")
    network = dict(details.get("thermal") or {})
    for name, key in (("R_wc", "winding_to_case"), ("R_ca", "case_to_ambient"), ("C_w", "winding_capacity"),
                      ("C_c", "case_capacity")):
        v = value(name)
        if math.isfinite(v):
            network[key] = v
    if not math.isfinite(r) or not network:
        raise InputError("the stall fit has no R or no thermal network", path=str(path))
    try:
        thermal = ThermalModel.from_dict(network)
    except OptionError as exc:
        raise InputError(exc.message, path=str(path)) from None
    note = str((params.get("K") or {}).get("note", ""))
    r_ca = params.get("R_ca") if isinstance(params.get("R_ca"), dict) else {}
    source = str(details.get("network") or "fitted to these runs")
    return StallModel(r, thermal, value("K"), value("tau0") if math.isfinite(value("tau0")) else 0.0,
                      "magnets' coefficient applied" in note,
                      float(details.get("initial_temperature_C") or thermal.ambient_temperature),
                      float(details.get("max_winding_temperature_C") or math.inf), str(path),
                      bool(r_ca) and not r_ca.get("determined", True) and source == "fitted to these runs",
                      _contact(details.get("brush_contact")), source, _log_covariance(doc))


#: The fit's parameters a forecast's band comes from, in the order of its correlation matrix.
BAND_PARAMETERS = ("R", "R_wc", "R_ca", "C_w", "C_c")


def _log_covariance(doc: dict[str, Any]) -> tuple[tuple[float, ...], ...]:
    """The covariance of the logarithms of :data:`BAND_PARAMETERS` from a fit file's standard errors (relative) and
    correlation; () when they are not all there (a parameter not determined counts as held: no spread)."""
    params = doc.get("parameters") or {}
    corr = ((doc.get("fit") or {}).get("correlation") or {})
    names, matrix = corr.get("names"), corr.get("matrix")
    if names != list(BAND_PARAMETERS) or not isinstance(matrix, list):
        return ()
    rel = []
    for name in BAND_PARAMETERS:
        entry = params.get(name) or {}
        value, se = entry.get("value"), entry.get("stderr")
        if (isinstance(value, int | float) and isinstance(se, int | float) and value > 0 and math.isfinite(se)
                and entry.get("determined", True) is not False):
            rel.append(float(se) / float(value))
        else:
            rel.append(0.0)
    try:
        c = np.nan_to_num(np.asarray(matrix, dtype=float)) * np.outer(rel, rel)
    except (TypeError, ValueError):
        return ()
    return tuple(tuple(float(v) for v in row) for row in c) if c.shape == (5, 5) else ()


def _contact(entry: Any) -> dict[str, float]:
    """The brushes' contact of a fit file (empty when absent or not numbers)."""
    keys = ("resistance_ohm", "from_s", "voltage_V", "relative")
    if not isinstance(entry, dict) or not all(isinstance(entry.get(k), int | float) for k in keys):
        return {}
    out = {k: float(entry[k]) for k in keys}
    return out if all(math.isfinite(v) for v in out.values()) else {}


@dataclass
class Forecast:
    """A forecast stall: samples, the answers and the warnings."""

    time: np.ndarray
    current: np.ndarray
    torque: np.ndarray
    winding_temperature: np.ndarray
    case_temperature: np.ndarray
    answers: dict[str, Any] = field(default_factory=dict)
    warnings: list[str] = field(default_factory=list)
    #: The band of the current: ± 2 standard errors from the fit's covariance of R and the network [A].
    current_low: np.ndarray = field(default_factory=lambda: np.zeros(0))
    current_high: np.ndarray = field(default_factory=lambda: np.zeros(0))

    def columns(self) -> dict[str, np.ndarray]:
        """The CSV columns ``time_s, current_A, torque_Nm, winding_temperature_C, case_temperature_C`` (the band,
        :attr:`current_low` and :attr:`current_high`, is in the answers and the JSON)."""
        return {"time_s": self.time, "current_A": self.current, "torque_Nm": self.torque,
                "winding_temperature_C": self.winding_temperature, "case_temperature_C": self.case_temperature}


def forecast(model: StallModel, voltage: float, duration: float, *, initial_temperature: float | None = None,
             sample_interval: float = 0.1, limit: float = WINDING_LIMIT, rise: float = 100.0) -> Forecast:
    """The fitted motor stalled at ``voltage`` [V] for ``duration`` [s], from the fitted run's start.

    Raises
    ------
    OptionError
        A voltage, duration, interval or temperature out of range.
    """
    if not (math.isfinite(voltage) and 0 < voltage <= 1000):
        raise OptionError(f"the voltage (--voltage) must lie in (0, 1000] V, got {voltage!r}")
    if not (math.isfinite(duration) and duration > 0):
        raise OptionError(f"the duration (--duration) must be positive, got {duration!r} s")
    if not (math.isfinite(sample_interval) and sample_interval > 0):
        raise OptionError(f"the sample interval must be positive, got {sample_interval!r} s")
    if duration / sample_interval > MAX_FORECAST_SAMPLES:
        raise OptionError(f"{duration / sample_interval:.3g} samples is more than {MAX_FORECAST_SAMPLES:,}: "
                          "shorten --duration or lengthen --sample-interval")
    t0 = model.initial_temperature if initial_temperature is None else float(initial_temperature)
    if not (math.isfinite(t0) and -60 <= t0 <= 400):
        raise OptionError(f"the initial temperature must lie between −60 and 400 °C, got {t0!r}")
    n = math.floor(duration / sample_interval + 1e-9)
    t = np.append(np.arange(n + 1) * sample_interval, duration) if n * sample_interval < duration else (
        np.arange(n + 1) * sample_interval)
    contact = model.contact if initial_temperature is None and model.contact and abs(
        voltage - model.contact["voltage_V"]) <= 0.01 * model.contact["voltage_V"] else {}
    run = _response(model, t, float(voltage), t0, contact)
    if math.isfinite(model.torque_constant):
        beta = model.thermal.magnet_coefficient if model.magnet_applied else 0.0
        torque = model.torque_constant * (1 + beta * (run.case_temperature - 25.0)) * run.current + model.torque_offset
    else:
        torque = np.full(t.size, np.nan)
    out = Forecast(t, run.current, torque, run.winding_temperature, run.case_temperature)
    spread = _current_stderr(model, t, float(voltage), t0, contact, run.current)
    out.current_low, out.current_high = run.current - 2 * spread, run.current + 2 * spread
    out.answers = stall_answers(model, voltage, limit=limit, rise=rise, initial_temperature=t0)
    hottest = float(np.max(run.winding_temperature))
    if hottest > model.hottest + 1:
        out.warnings.append(f"the forecast reaches {hottest:.0f} °C, {hottest - model.hottest:.0f} K beyond the "
                            f"hottest winding temperature the fit saw ({model.hottest:.0f} °C): extrapolated")
    if model.case_loss_from_prior:
        out.warnings.append(_case_loss_band(model, t, voltage, t0, run.current, contact))
    if model.network != "fitted to these runs":
        band = _winding_band(model, t, voltage, t0, run.current, contact)
        out.warnings.append(f"the thermal network of this forecast is {model.network}, not the fitted run's own "
                            f"(no single network fits it): {band}")
    if contact and abs(contact["relative"]) >= 0.01 and t[-1] > contact["from_s"]:
        out.warnings.append(
            f"the fitted run's resistance ended {100 * contact['relative']:+.1f} % "
            f"({1e3 * contact['resistance_ohm']:+.3g} mΩ) off the heating model over its last seconds (to "
            f"{contact['from_s']:.0f} s): the brushes' contact, which moves in steps heat does not make; the forecast "
            "holds it on from there (not at another voltage or start)")
    if limit > model.hottest + 1:
        out.warnings.append(f"the time to {limit:g} °C extrapolates the fit {limit - model.hottest:.0f} K beyond the "
                            f"hottest winding temperature it saw ({model.hottest:.0f} °C)")
    return out


def _response(model: StallModel, t: np.ndarray, voltage: float, t0: float, contact: dict[str, float]) -> StallRun:
    """The stall of the fitted model at ``voltage`` from ``t0``; with ``contact``, its resistance in series from
    the time it was measured at (the run continued as it ended)."""
    volts = np.full(t.size, voltage)
    if not contact or t[-1] <= contact["from_s"]:
        return stall_response(model.resistance, model.thermal, t, volts, winding=t0)
    k = int(np.searchsorted(t, contact["from_s"]))
    first = stall_response(model.resistance, model.thermal, t[: k + 1], volts[: k + 1], winding=t0)
    rest = stall_response(model.resistance, model.thermal, t[k:], volts[k:],
                          winding=float(first.winding_temperature[-1]), case=float(first.case_temperature[-1]),
                          series_resistance=contact["resistance_ohm"])
    return replace(rest, time=t, current=np.concatenate([first.current[:k], rest.current]),
                   winding_temperature=np.concatenate([first.winding_temperature[:k], rest.winding_temperature]),
                   case_temperature=np.concatenate([first.case_temperature[:k], rest.case_temperature]))


def _current_stderr(model: StallModel, t: np.ndarray, voltage: float, t0: float, contact: dict[str, float],
                    current: np.ndarray) -> np.ndarray:
    """The standard error of the forecast current at each time [A]: the delta method over the logarithms of R and
    the network with the fit's covariance (zeros when the fit file has none)."""
    if not model.log_covariance:
        return np.zeros(t.size)
    cov = np.asarray(model.log_covariance, dtype=float)
    step = 1e-3
    grads = []
    for k, name in enumerate(BAND_PARAMETERS):
        if cov[k, k] <= 0:
            grads.append(np.zeros(t.size))
            continue
        th = model.thermal
        moved = {"R_wc": "winding_to_case", "R_ca": "case_to_ambient", "C_w": "winding_capacity",
                 "C_c": "case_capacity"}
        if name == "R":
            m = replace(model, resistance=model.resistance * math.exp(step))
        else:
            m = replace(model, thermal=replace(th, **{moved[name]: getattr(th, moved[name]) * math.exp(step)}))
        grads.append((_response(m, t, voltage, t0, contact).current - current) / step)
    g = np.asarray(grads)
    return np.sqrt(np.maximum(np.einsum("it,ij,jt->t", g, cov, g), 0.0))


#: The spread of the prior on the case's time constant (a factor either way), as the fit uses it (the
#: population's, :data:`motorlab.analyses._stall_fit.PRIOR_LOG_SIGMA`, rounded).
CASE_PRIOR_FACTOR = 1.5


def _case_loss_band(model: StallModel, t: np.ndarray, voltage: float, t0: float, current: np.ndarray,
                    contact: dict[str, float]) -> str:
    """What the forecast's current would be at its end with the case's loss to ambient R_ca a factor
    :data:`CASE_PRIOR_FACTOR` either way (the fit took R_ca from a prior: its runs were too short)."""
    ends = []
    for factor in (1 / CASE_PRIOR_FACTOR, CASE_PRIOR_FACTOR):
        th = replace(model.thermal, case_to_ambient=model.thermal.case_to_ambient * factor)
        ends.append(float(_response(replace(model, thermal=th), t, float(voltage), t0, contact).current[-1]))
    return (f"the case's loss to ambient (R_ca = {model.thermal.case_to_ambient:.3g} K/W) was not determined by the "
            f"fitted run, too short for the case to settle (a prior on the case's time constant, or a bound, set it): "
            f"with R_ca {CASE_PRIOR_FACTOR:g} times smaller or larger the current at {float(t[-1]):.0f} s would be "
            f"{min(ends):.4g}–{max(ends):.4g} A instead of {float(current[-1]):.4g} A; fit a longer run to pin it")


def _winding_band(model: StallModel, t: np.ndarray, voltage: float, t0: float, current: np.ndarray,
                  contact: dict[str, float]) -> str:
    """The forecast's current at its end with the winding's time constant (its heat capacity C_w) a factor
    :data:`WINDING_BAND_FACTOR` either way: the band of a network not fitted to the run."""
    ends = []
    for factor in (1 / WINDING_BAND_FACTOR, WINDING_BAND_FACTOR):
        th = replace(model.thermal, winding_capacity=model.thermal.winding_capacity * factor)
        ends.append(float(_response(replace(model, thermal=th), t, float(voltage), t0, contact).current[-1]))
    return (f"with the winding's heat capacity {WINDING_BAND_FACTOR:g} times smaller or larger the current at "
            f"{float(t[-1]):.0f} s would be {min(ends):.4g}–{max(ends):.4g} A instead of {float(current[-1]):.4g} A")


#: The factor either way on the winding's heat capacity of a forecast whose network is not the run's own.
WINDING_BAND_FACTOR = 2.0


def stall_answers(model: StallModel, voltage: float, *, limit: float = WINDING_LIMIT, rise: float = 100.0,
                  initial_temperature: float | None = None) -> dict[str, Any]:
    """Time to ``limit`` at ``voltage``, the settling temperature, the current held for a ``rise``, R hot/cold."""
    th = model.thermal
    start = th.ambient_temperature if initial_temperature is None else initial_temperature
    t_lim = time_to_temperature(model.resistance, th, voltage, limit, winding=start)
    i_cont, v_cont = continuous_current(model.resistance, th, rise)
    return {
        "voltage_V": voltage,
        "initial_temperature_C": start,
        "limit_C": limit,
        "time_to_limit_s": t_lim if math.isfinite(t_lim) else None,
        "settles_at_C": steady_stall_temperature(model.resistance, th, voltage),
        "rise_K": rise,
        "continuous_current_A": i_cont,
        "continuous_voltage_V": v_cont,
        "R_cold_ohm": model.resistance * th.resistance_factor(th.ambient_temperature),
        "R_hot_ohm": model.resistance * th.resistance_factor(limit),
        "ambient_C": th.ambient_temperature,
    }


def answers_text(a: dict[str, Any]) -> list[str]:
    """The answers in words."""
    t = a["time_to_limit_s"]
    first = (f"stalled at {a['voltage_V']:g} V from {a['initial_temperature_C']:.0f} °C, the winding reaches "
             f"{a['limit_C']:g} °C after {t:.1f} s" if t is not None else
             f"stalled at {a['voltage_V']:g} V the winding never reaches {a['limit_C']:g} °C: it settles at "
             f"{a['settles_at_C']:.0f} °C")
    return [
        first,
        f"held indefinitely with the winding {a['rise_K']:g} K above a {a['ambient_C']:g} °C ambient: a stall current "
        f"of {a['continuous_current_A']:.3g} A ({a['continuous_voltage_V']:.3g} V at the terminals)",
        f"R hot against cold: {a['R_hot_ohm']:.4g} Ω at {a['limit_C']:g} °C against {a['R_cold_ohm']:.4g} Ω at "
        f"{a['ambient_C']:g} °C (+{100 * (a['R_hot_ohm'] / a['R_cold_ohm'] - 1):.0f} %)",
    ]
