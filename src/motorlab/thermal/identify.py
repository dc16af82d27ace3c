"""``identify --thermal``: the whole-model fit with the winding's temperature as a state.

A log long or hard enough to warm the winding is fitted by :func:`motorlab.analyses.identify.identify` as if
R were constant: R comes out as an average over a warming winding, biased high by 0.393 % per kelvin
of the mean rise and at no stated temperature. With a thermal network (given, from a stall fit, or
the catalogue's) the winding temperature is integrated along the log from its I²·R heat::

    C_w·dT_w/dt = R(T_w)·i² − (T_w − T_c)/R_wc,   C_c·dT_c/dt = (T_w − T_c)/R_wc − (T_c − T_a)/R_ca
    L·di/dt = V − R₂₅·(1 + α·(T_w − 25 °C))·i − K·ω
    J·dω/dt = K·i − b·ω − Tf·sgn(ω),              K = K₂₅·(1 + β·(T_c − 25 °C))

and the fit estimates R₂₅ and K₂₅, the values at 25 °C. How it is done (:class:`CopperDrop`,
:class:`ThermalDrive`): the temperatures are integrated from the measured current's heat (its noise
adds σ² to i², a few µA² here), the rise scaled with the fitted R₂₅ (the heat is proportional to
it). The plant's R is R₂₅ at the winding's mean temperature over the log (weighted by i²), and the
copper's drop beyond it, R₂₅·α·(T_w − T̄_w)·i, is moved to the drive like the voltage: moving the drop
of the whole rise there biased L and R (a drop proportional to the current is a resistance: as an
input held over a sample it misses how the current moves within the sample); the deviation from the
mean mostly cancels over the log. The case node warms over minutes, so within a log K holds at the
case's mean temperature: the plant's K is K₂₅·(1 + β·(T̄_c − 25 °C)). One run's initial temperature
and R₂₅ cannot be told apart (only R(T₀) is seen), so the log starts at a given temperature (the
ambient's by default). The network is taken as exact: its uncertainty is not in the standard errors.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from motorlab.errors import OptionError
from motorlab.estimation import output_error as _oe
from motorlab.results import Estimate
from motorlab.thermal.network import REFERENCE_TEMPERATURE, ThermalModel

#: The heat is integrated in bins of this length [s] (the winding's time constant is ~10–100 s).
HEAT_BIN = 0.05


def temperature_trajectory(thermal: ThermalModel, time: np.ndarray, current: np.ndarray, resistance: float,
                           initial: float) -> tuple[np.ndarray, np.ndarray]:
    """Winding and case temperatures [°C] at ``time`` [s] of a winding of R₂₅ ``resistance`` [Ω] carrying
    ``current`` [A] (held between samples), from ``initial`` [°C] (winding and case alike)."""
    t = np.asarray(time, dtype=float)
    i2 = np.asarray(current, dtype=float) ** 2
    edges = np.arange(t[0], t[-1] + HEAT_BIN, HEAT_BIN)
    # ∫i² dt per bin, from the cumulative integral. Each interval's i² is the one at its end: the logged
    # voltage holds from a sample to the next, and the current settles to it within the electrical time
    # constant L/R (~1 ms), sooner than the next sample; the value at the start would miss the heat of
    # every step up (7 % of a step-driven log's heat at 200 Hz).
    cumulative = np.concatenate([[0.0], np.cumsum(i2[1:] * np.diff(t))])
    at_edges = np.interp(edges, t, cumulative)
    mean_i2 = np.diff(at_edges) / HEAT_BIN
    tw, tc = float(initial), float(initial)
    tws, tcs = [tw], [tc]
    for q in mean_i2.tolist():
        tw_mid = tw + 0.5 * HEAT_BIN * (resistance * thermal.resistance_factor(tw) * q
                                        - (tw - tc) / thermal.winding_to_case) / thermal.winding_capacity
        tw, tc = thermal.step(tw, tc, resistance * thermal.resistance_factor(tw_mid) * q, HEAT_BIN)
        tws.append(tw)
        tcs.append(tc)
    return np.interp(t, edges, tws), np.interp(t, edges, tcs)


class CopperDrop:
    """The copper's extra drop R₂₅·α·(T_w − 25 °C)·i of each run, and the case's mean temperature.

    Parameters
    ----------
    logs
        The prepared runs (with current).
    thermal
        The network and coefficients.
    initial
        The runs' initial winding (and case) temperature [°C].
    resistance
        The R₂₅ the temperatures are first integrated with [Ω]; the rise is scaled with the fitted R₂₅.
    origin
        Where the network comes from, in words.
    """

    def __init__(self, logs: Sequence[_oe.Log], thermal: ThermalModel, initial: float, resistance: float,
                 origin: str = "given"):
        self.thermal = thermal
        self.origin = origin
        self.initial_temperature = float(initial)
        self.reference_resistance = float(resistance)
        self._drop: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        self.winding: list[np.ndarray] = []
        self.case: list[np.ndarray] = []
        total = weighted = heat = heat_rise = 0.0
        for log in logs:
            assert log.current is not None
            tw, tc = temperature_trajectory(thermal, log.time, log.current, resistance, initial)
            self.winding.append(tw)
            self.case.append(tc)
            # the grid step k is held from dt·k to dt·(k+1): its current and temperature at the middle
            mid = log.dt * (np.arange(log.n_grid) + 0.5)
            rise = np.interp(mid, log.time, tw) - REFERENCE_TEMPERATURE
            current = np.interp(mid, log.time, log.current)
            self._drop[id(log)] = (thermal.resistance_coefficient * rise, current)
            span = float(log.time[-1] - log.time[0])
            total += span
            weighted += float(np.trapezoid(tc, log.time)) if span > 0 else 0.0
            heat += float(np.sum(current**2))
            heat_rise += float(np.sum(current**2 * rise))
        #: The case's mean temperature over the runs [°C]: within a log K holds at it.
        self.case_mean = weighted / total if total > 0 else self.initial_temperature
        #: α·(T_w − 25 °C) at the winding's mean temperature (weighted by i², where the data tell R most).
        self.mean_factor = thermal.resistance_coefficient * (
            heat_rise / heat if heat > 0 else self.initial_temperature - REFERENCE_TEMPERATURE)

    def _scaled(self, factor: Any, r: float) -> Any:
        """α·(T_w − 25 °C) with the rise over the initial temperature scaled to R₂₅ = ``r`` (the heat, and so
        the rise, is proportional to R₂₅)."""
        start = self.thermal.resistance_coefficient * (self.initial_temperature - REFERENCE_TEMPERATURE)
        return start + (factor - start) * (r / self.reference_resistance)

    def at_mean(self, p: np.ndarray) -> np.ndarray:
        """The model's parameters with R and K at the winding's and the case's mean temperatures (the plant's)."""
        q = np.array(p, dtype=float, copy=True)
        q[0] *= self.constant_factor
        q[1] *= 1.0 + self._scaled(self.mean_factor, float(p[1]))
        return q

    def drop(self, p: np.ndarray, log: _oe.Log) -> np.ndarray:
        """The copper's drop beyond the plant's (R at the mean temperature) on each grid step [V]."""
        factor, current = self._drop[id(log)]
        r = float(p[1])
        return r * (self._scaled(factor, r) - self._scaled(self.mean_factor, r)) * current

    def wrap(self, model: _oe.OEModel) -> _oe.OEModel:
        """``model`` driven by its drive less the copper's extra drop."""
        return ThermalDrive(model, self)

    @property
    def constant_factor(self) -> float:
        """K(T̄_c)/K₂₅: the fit's K is K at the case's mean temperature."""
        return float(self.thermal.constant_factor(self.case_mean))

    @property
    def hottest(self) -> float:
        """The hottest winding temperature of the runs [°C]."""
        return max(float(np.max(w)) for w in self.winding)

    def details(self) -> dict[str, Any]:
        """``FitResult.details["thermal"]``."""
        return {
            "network": self.thermal.to_dict(), "network_from": self.origin,
            "initial_temperature_C": self.initial_temperature,
            "winding_end_C": [float(w[-1]) for w in self.winding], "winding_max_C": self.hottest,
            "case_mean_C": self.case_mean, "K_factor_at_case_mean": self.constant_factor,
            "uncertainty": "the network is taken as exact: its uncertainty is not in the standard errors",
        }

    def annotate(self, params: dict[str, Estimate], details: dict[str, Any], warnings: list[str]) -> None:
        """R and K's notes (at 25 °C), ``details["thermal"]`` and ``["R_temperature"]``, and what the winding did."""
        for name in ("R", "K"):
            est = params[name]
            note = "at 25 °C (the winding's temperature a state of the fit)"
            params[name] = replace(est, note=f"{note}; {est.note}" if est.note else note)
        details["R_temperature"] = ("R and K at 25 °C: the winding's temperature was integrated along the log as a "
                                    "state (R(T) = R·(1 + 0.00393·(T − 25 °C)))")
        details["thermal"] = self.details()
        rise = self.hottest - self.initial_temperature
        warnings.append(f"the winding warmed from {self.initial_temperature:.0f} to {self.hottest:.0f} °C during the "
                        f"log (network: {self.origin}), so its R rose "
                        f"{100 * self.thermal.resistance_coefficient * rise:.1f} %; R and K are given at 25 °C")


class ThermalDrive(_oe.OEModel):
    """An output-error model whose drive is less the copper's extra drop (:class:`CopperDrop`); everything
    else is the wrapped model's (a sample-held :class:`~motorlab.estimation.runs.MotorModel` or held levels)."""

    def __init__(self, inner: _oe.OEModel, heat: CopperDrop):
        self.inner = inner
        self.heat = heat
        self.names = inner.names
        self.uses_current = inner.uses_current
        self.lag = inner.lag
        self.input_noise = inner.input_noise

    def __getattr__(self, name: str) -> Any:  # the held-level model's slices, levels, start_and_bounds ...
        if name == "inner":
            raise AttributeError(name)
        return getattr(self.inner, name)

    def plant(self, p: np.ndarray) -> _oe.StatePlant:
        return self.inner.plant(self.heat.at_mean(p))

    def initial(self, p: np.ndarray, log: _oe.Log, speed: float) -> np.ndarray:
        return self.inner.initial(p, log, speed)

    def local_start(self, j: int) -> tuple[int, int] | None:
        return self.inner.local_start(j)

    def extra_residuals(self, p: np.ndarray) -> np.ndarray:
        return self.inner.extra_residuals(p)

    def drive(self, p: np.ndarray, log: _oe.Log) -> np.ndarray:
        return self.inner.drive(p, log) - self.heat.drop(p, log)

    def switches(self, p: np.ndarray, log: _oe.Log) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        sw = self.inner.switches(p, log)
        if sw is None:
            return None
        steps, fractions, before = sw
        return steps, fractions, before - self.heat.drop(p, log)[steps]


def network_for(recordings: Sequence[Any], *, motor: str | None = None,
                network: ThermalModel | None = None) -> tuple[ThermalModel, str]:
    """The thermal network for ``identify --thermal`` and where it comes from.

    A network given wins; then the catalogue's for ``motor``, or for the motor a file names in its
    metadata (the virtual dynamometer's logs do); else the 550-size estimate of FTC gearmotors.

    Raises
    ------
    OptionError
        An unknown catalogue motor.
    """
    from motorlab.catalog import Motor
    from motorlab.errors import InputError
    from motorlab.thermal.network import DEFAULT_NETWORK

    if network is not None:
        return network, "given"
    if motor is not None:
        try:
            thermal = Motor.from_catalog(motor).thermal_model()
            return thermal, f"the catalogue's estimate for {motor} (data/thermal.toml)"
        except InputError as exc:
            raise OptionError(f"--motor {motor}: {exc.message}") from None
    named = {str(rec.metadata.get("motor")) for rec in recordings if rec.metadata.get("motor")}
    if len(named) == 1:
        key = named.pop()
        try:
            return Motor.from_catalog(key).thermal_model(), (f"the catalogue's estimate for {key}, the motor the log "
                                                             "names (data/thermal.toml)")
        except InputError:
            pass
    return DEFAULT_NETWORK, "the 550-size estimate of FTC gearmotors (data/thermal.toml, can550); give --motor"


def wanted(thermal: bool, *, with_current: bool) -> bool:
    """Whether to fit the winding's temperature; refused without current (its heat is I²·R).

    Raises
    ------
    OptionError
        Asked for without the current of every run.
    """
    if thermal and not with_current:
        raise OptionError("the winding's temperature (--thermal) needs the current of every run: its I²·R heat "
                          "warms the winding (drop --no-current, or log the current)")
    return thermal


def annotate(heat: CopperDrop | None, params: dict[str, Estimate], details: dict[str, Any],
             warnings: list[str]) -> None:
    """:meth:`CopperDrop.annotate` when the winding's temperature was fitted (``heat`` not None)."""
    if heat is not None:
        heat.annotate(params, details, warnings)


def unchanged(model: _oe.OEModel) -> _oe.OEModel:
    """The model as it is (no heat)."""
    return model


def copper_drop(recordings: Sequence[Any], logs: Sequence[_oe.Log], *, motor: str | None,
                network: ThermalModel | None, initial: float | None, resistance: float) -> CopperDrop:
    """The :class:`CopperDrop` of ``logs``: the network (:func:`network_for`), the initial temperature (the
    ambient's by default) checked, the temperatures integrated with R₂₅ = ``resistance`` [Ω].

    Raises
    ------
    OptionError
        An unknown motor or an initial temperature out of range.
    """
    thermal, origin = network_for(recordings, motor=motor, network=network)
    t0 = thermal.ambient_temperature if initial is None else float(initial)
    if not (math.isfinite(t0) and -40 <= t0 <= 200):
        raise OptionError(f"the initial winding temperature must lie between −40 and 200 °C, got {initial!r}")
    return CopperDrop(logs, thermal, t0, resistance, origin)
