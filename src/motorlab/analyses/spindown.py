"""Spin-down of a flywheel: K from the coasting back-EMF, viscous and Coulomb friction from the coast.

Seed 1, "Flywheel and INA219 Experiment": the motor drives the flywheel from a bench supply, then a
relay opens and the flywheel coasts while the FTC OpMode logs encoder counts, the INA219 bus voltage
and the shunt current. During the coast there is no current, so

    J·dω/dt = −b·ω − Tf          (γ = b/J, Tf/J: both friction terms)
    V = K·ω                       (the bus voltage is the back-EMF)

The seed fits P(t) = P∞ − B·e^(−γ(t−30)), the special case Tf = 0, and then K to a 15-point
average of the bus voltage against the derivative of that fit. Here position is fitted with both
friction terms, and the bus voltage jointly with it (weighted by σ's estimated from the data), so
that neither quantisation nor the voltage noise biases K.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import stats

from motorlab.analyses import common
from motorlab.errors import FitError, OptionError
from motorlab.estimation.decimate import block_mean
from motorlab.estimation.least_squares import LeastSquares, fit_least_squares, fit_linear, r_squared
from motorlab.recording import Recording
from motorlab.results import Estimate, FitResult, Panel, Series
from motorlab.units import SI_UNITS

#: Units of every parameter of the coast fit.
_UNITS = {"theta0": "rad", "omega0": "rad/s", "gamma": "1/s", "Tf_over_J": "rad/s^2", "K": "V*s/rad"}
#: Fewer coast samples than this is an error; fewer than _FEW_SAMPLES a warning.
_MIN_SAMPLES = 8
_FEW_SAMPLES = 30
#: A coast moving fewer counts than this is not a coast.
_MIN_COUNTS = 20


def find_cutoff(time: np.ndarray, current: np.ndarray, *, source: str = "") -> tuple[int | None, float]:
    """Index of the first sample after the relay opened, and the instant [s] it opened.

    The relay-off instant is where the shunt current drops to (sensor noise around) zero for good:
    the last sample whose |current| exceeds a threshold set from the end of the log (which must be
    a coast) marks the end of the powered phase.

    Returns
    -------
    first, t_off
        ``first`` is None when the log has no powered phase at all (then the whole log is a coast);
        ``t_off`` is midway between the last powered and the first unpowered sample.

    Raises
    ------
    FitError
        When the current never drops to zero: the relay never opened, there is no coast.
    """
    i_abs = np.abs(current)
    n = i_abs.size
    i_on = float(np.percentile(i_abs, 95))
    tail = i_abs[-max(5, n // 20):]
    tail_level = float(np.median(tail))
    noise = 1.4826 * float(np.median(np.abs(tail - tail_level)))
    if i_on < 0.02:
        return None, float(time[0])
    if tail_level > max(0.1 * i_on, 0.02):
        raise FitError(
            f"{source}: no coast found: the current never drops to zero (median {tail_level:.3g} A at the "
            "end of the log); give --cutoff if the relay opened anyway"
        )
    threshold = max(tail_level + 6.0 * noise, 0.02 * i_on, 0.005)
    on = np.flatnonzero(i_abs > threshold)
    if on.size == 0:
        return None, float(time[0])
    last_on = int(on[-1])
    if last_on >= n - 1:
        raise FitError(f"{source}: no coast found: the current is still flowing in the last sample")
    return last_on + 1, 0.5 * float(time[last_on] + time[last_on + 1])


def _check_no_current_after(
    time: np.ndarray, current: np.ndarray, t_start: float, cutoff: float, *, path: str | None
) -> None:
    """Refuse a given cut-off after which the motor is still driven (three or more powered samples).

    The powered level is the one :func:`find_cutoff` uses: above 2 % of the drive current and six
    noise σ's above the zero read at the end of the log. A coast model fitted to a powered run gives
    numbers that look like results (the QA run: K = 1.29 against 0.70, γ < 0) instead of an error.
    """
    i_abs = np.abs(current)
    i_on = float(np.percentile(i_abs, 95))
    if i_on < 0.02:
        return  # no powered phase in the log at all
    tail = i_abs[-max(5, i_abs.size // 20):]
    tail_level = float(np.median(tail))
    noise = 1.4826 * float(np.median(np.abs(tail - tail_level)))
    threshold = max(tail_level + 6.0 * noise, 0.02 * i_on, 0.005)
    powered = np.flatnonzero((time >= t_start) & (i_abs > threshold))
    if powered.size >= 3:
        raise OptionError(
            f"the current still flows after the cut-off (--cutoff) {cutoff:g} s: {powered.size} samples up to "
            f"{float(time[powered[-1]]):g} s carry up to {float(np.max(i_abs[powered])):.3g} A; the relay opened "
            "later (leave --cutoff out to find it from the current)",
            path=path,
        )


def _initial_guess(tau: np.ndarray, theta: np.ndarray) -> list[tuple[float, float, float]]:
    """Starting (ω0, γ, Tf/J) guesses from block-averaged finite-difference speeds."""
    n = tau.size
    blocks = max(4, min(40, n // 5))
    edges = np.linspace(0, n - 1, blocks + 1).astype(int)
    edges = np.unique(edges)
    t_mid = 0.5 * (tau[edges[1:]] + tau[edges[:-1]])
    dt = np.diff(tau[edges])
    speed = np.diff(theta[edges]) / np.where(dt > 0, dt, np.inf)
    omega0 = max(float(speed[0]), 1e-6)
    duration = float(tau[-1] - tau[0]) or 1.0
    guesses = []
    if speed.size >= 3:
        accel = np.diff(speed) / np.diff(t_mid)
        w_mid = 0.5 * (speed[1:] + speed[:-1])
        design = np.column_stack([w_mid, np.ones_like(w_mid)])
        coef, *_ = np.linalg.lstsq(design, -accel, rcond=None)
        guesses.append((omega0, max(float(coef[0]), 0.0), max(float(coef[1]), 0.0)))
    # Pure viscous (the seed's exponential) and pure Coulomb (linear speed decay) starts.
    guesses.append((omega0, 1.0 / duration, 0.0))
    guesses.append((omega0, 0.0, omega0 / duration))
    return guesses


def _find_coast(
    recording: Recording, theta_all: np.ndarray, *, cutoff: float | None, guard: float, tick_log: bool,
    has_current: bool, warnings: list[str],
) -> tuple[np.ndarray, float, bool]:
    """The coast's sample indices (after the relay opened plus ``guard``, until the count last
    changed), the cut-off instant [s] and whether the shaft stopped before the log ended."""
    source = recording.source or "log"
    t_all = recording.time
    n_all = t_all.size
    if cutoff is not None:
        t_off = float(cutoff)
        first = int(np.searchsorted(t_all, t_off, side="left"))
        if has_current:
            _check_no_current_after(t_all, recording.signals["current"], t_off + guard, cutoff,
                                    path=recording.source or None)
    elif has_current:
        first_or_none, t_off = find_cutoff(t_all, recording.signals["current"], source=source)
        if first_or_none is None:
            first = 0
            warnings.append("the current is zero throughout: the whole log is taken as the coast")
        else:
            first = first_or_none
    else:
        raise FitError(f"{source}: the log has no current to find the relay-off instant: give --cutoff")
    start = int(np.searchsorted(t_all, t_all[min(first, n_all - 1)] + guard, side="left")) if first < n_all else n_all
    if start >= n_all - 1:
        raise FitError(f"{source}: no coast found: the log ends at the cut-off ({t_off:.3f} s)")
    moving = np.flatnonzero(np.abs(np.diff(theta_all[start:])) > 0) + start + 1
    if moving.size == 0:
        raise FitError(f"{source}: no coast found: the shaft does not turn after the cut-off ({t_off:.3f} s)")
    stop = int(moving[-1])  # last sample at which the count still changed
    stopped = stop < n_all - 1 and not tick_log
    idx = np.arange(start, stop + 1)
    if idx.size < _MIN_SAMPLES:
        raise FitError(f"{source}: only {idx.size} samples in the coast: too few for a spin-down fit")
    if idx.size < _FEW_SAMPLES:
        warnings.append(f"only {idx.size} samples in the coast: the estimates are fragile")
    if not stopped:
        warnings.append("the shaft had not stopped at the end of the log (fine: the whole coast is used)")
    if has_current:
        coast_current = float(np.mean(np.abs(recording.signals["current"][idx])))
        i_on = float(np.percentile(np.abs(recording.signals["current"]), 95))
        if coast_current > max(0.05 * i_on, 0.02):
            warnings.append(f"the mean current during the coast is {coast_current:.3g} A, not zero")
    return idx, t_off, stopped


@dataclass
class _Coast:
    """The joint fit of the coast (position and bus voltage, each in units of its noise)."""

    joint: LeastSquares
    sigma_theta: np.ndarray
    sigma_v: float
    run: Callable[[dict[int, float], np.ndarray], LeastSquares]
    n_names: int

    def compare_nested(self) -> dict[str, Any]:
        """F-tests and AIC of the fits without the Coulomb (viscous_only) or viscous (coulomb_only) term."""
        chi2_full = float(self.joint.residuals @ self.joint.residuals)
        n_res = self.joint.residuals.size
        p_full = self.n_names
        comparison: dict[str, Any] = {}
        for label, k_fixed in (("viscous_only", 3), ("coulomb_only", 2)):
            x0 = self.joint.values.copy()
            x0[k_fixed] = 0.0
            nested = self.run({k_fixed: 0.0}, x0)
            chi2 = float(nested.residuals @ nested.residuals)
            f_stat = max(chi2 - chi2_full, 0.0) / (chi2_full / max(n_res - p_full, 1))
            comparison[label] = {
                "chi2": chi2,
                "F": f_stat,
                "p_value": float(stats.f.sf(f_stat, 1, max(n_res - p_full, 1))),
                "delta_AIC": _aic(chi2, n_res, p_full - 1) - _aic(chi2_full, n_res, p_full),
            }
        comparison["both"] = {"chi2": chi2_full, "AIC": _aic(chi2_full, n_res, p_full)}
        return comparison


def _fit_coast(tau: np.ndarray, theta: np.ndarray, voltage: np.ndarray | None, source: str) -> _Coast:
    """Stage 1 fits the position alone, stage 2 K from the bus voltage against its model speed; then
    both jointly, weighted by their noise (refined once from the joint fit's own residuals)."""

    def position_model(x: np.ndarray) -> np.ndarray:
        return x[0] + common.coast_position(tau, x[1], x[2], x[3])

    def speed_model(x: np.ndarray) -> np.ndarray:
        return common.coast_speed(tau, x[1], x[2], x[3])

    best: LeastSquares | None = None
    for omega0, gamma0, decel0 in _initial_guess(tau, theta):
        try:
            fit = fit_least_squares(
                lambda x: position_model(x) - theta, [0.0, omega0, gamma0, decel0],
                ["theta0", "omega0", "gamma", "Tf_over_J"],
            )
        except FitError as exc:
            raise common.in_file(exc, source) from None
        if best is None or float(fit.residuals @ fit.residuals) < float(best.residuals @ best.residuals):
            best = fit
    assert best is not None
    x_pos = best.values
    sigma_theta = common.speed_noise_sigma(best.residuals, speed_model(x_pos), dof=best.dof)

    # ---- stage 2: the bus voltage against the model speed; then the joint weighted fit -------------
    if voltage is not None:
        k_fit = fit_linear(speed_model(x_pos)[:, None], voltage, ["K"])
        sigma_v = max(float(np.sqrt(np.sum(k_fit.residuals**2) / k_fit.dof)), 1e-12)
        x_start = np.append(x_pos, k_fit.values[0])
    else:
        sigma_v = math.nan
        x_start = x_pos
    names = ["theta0", "omega0", "gamma", "Tf_over_J"] + (["K"] if voltage is not None else [])

    def make_residual(fixed: dict[int, float]) -> Any:
        free = [k for k in range(len(names)) if k not in fixed]

        def full(xf: np.ndarray) -> np.ndarray:
            x = np.empty(len(names))
            x[free] = xf
            for k, v in fixed.items():
                x[k] = v
            return x

        def residual(xf: np.ndarray) -> np.ndarray:
            x = full(xf)
            r = (position_model(x) - theta) / sigma_theta
            if voltage is not None:
                r = np.concatenate([r, (x[4] * speed_model(x) - voltage) / sigma_v])
            return r

        return residual, free

    def run(fixed: dict[int, float], x0: np.ndarray) -> LeastSquares:
        residual, free = make_residual(fixed)
        try:
            return fit_least_squares(residual, x0[free], [names[k] for k in free], sigma_known=True)
        except FitError as exc:
            raise common.in_file(exc, source) from None

    joint = run({}, x_start)
    # Refine the σ's once from the joint fit's own residuals, then refit.
    n_pos = tau.size
    pos_res = joint.residuals[:n_pos] * sigma_theta
    sigma_theta = common.speed_noise_sigma(pos_res, speed_model(joint.values), dof=max(n_pos - 4, 1))
    if voltage is not None:
        v_res = joint.residuals[n_pos:] * sigma_v
        sigma_v = max(float(np.sqrt(np.sum(v_res**2) / max(v_res.size - 1, 1))), 1e-12)
    joint = run({}, joint.values)
    return _Coast(joint, sigma_theta, sigma_v, run, len(names))


def spindown(
    recording: Recording,
    *,
    cpr: float | None = None,
    inertia: float | None = None,
    inertia_stderr: float | None = None,
    cutoff: float | None = None,
    guard: float = 0.1,
) -> FitResult:
    """Fit the coast of a flywheel spin-down: K, γ = b/J and Tf/J (b and Tf when J is known).

    Parameters
    ----------
    recording
        FTC log of the run (``time``, ``counts`` or ``position``, ``voltage`` = INA219 bus voltage,
        ``current`` = shunt current), or a tick-timestamp log (then only γ and Tf/J).
    cpr
        Encoder counts per revolution of the counted shaft [count/rev] (when the log holds counts).
    inertia
        Total inertia at the encoder shaft (flywheel reflected through the gearbox) [kg·m²]; gives
        b = γ·J [N·m·s/rad] and Tf = (Tf/J)·J [N·m].
    inertia_stderr
        Standard error of ``inertia`` [kg·m²], propagated into b and Tf (default: exact).
    cutoff
        Instant the relay opened [s]; by default found from the current dropping to zero.
    guard
        Samples within this time after the cut-off are left out (relay bounce, inductive tail) [s].

    Returns
    -------
    FitResult
        Parameters ``K`` [V·s/rad] (when the log has a bus voltage), ``gamma`` [1/s],
        ``Tf_over_J`` [rad/s²], and with ``inertia`` also ``J``, ``b``, ``Tf``. ``details`` holds the
        model comparison (viscous only, Coulomb only, both) with an F-test and AIC.

    Raises
    ------
    OptionError
        Impossible ``cpr``, ``inertia``, ``inertia_stderr``, ``cutoff`` or ``guard``; a ``cutoff``
        outside the log's time span, or one after which the current still flows (naming the file).
    LogFormatError
        NaN in the log, or no encoder signal.
    FitError
        No coast in the log (the current never drops, or the shaft does not turn after the cut-off),
        or too few coast samples.

    Notes
    -----
    With c = Tf/b the coast is ω(τ) = (ω0 + c)·e^(−γτ) − c until ω = 0 and the shaft then stays at
    rest; its position θ(τ) = θ0 + ((ω0 + c)/γ)(1 − e^(−γτ)) − c·τ is what the encoder measures, so
    every sample is used as it is (no differentiated or smoothed speed). Position residuals are
    weighted by σ² = σ_q² + (σ_t·ω)² (count quantisation and timing jitter, estimated from the
    residuals); the bus voltage V = K·ω(τ) enters the same fit with its own σ, so the voltage noise
    does not bias K and the uncertainty of ω is propagated. Samples after the shaft stopped are left
    out. The seed's model P(t) = P∞ − B·e^(−γ(t−30)) is the case Tf = 0; the Coulomb term is kept
    when an F-test of the nested models rejects Tf = 0.

    References
    ----------
    Seed 1, "Flywheel and INA219 Experiment", "Data Analysis" steps 3–7; "Noisy Bus Voltage Data".
    """
    recording = block_mean(recording)  # a 2M-row log: block means, not 2M-point fits
    source = recording.source or "log"
    inertia_se = _checked_options(guard=guard, inertia=inertia, inertia_stderr=inertia_stderr, cutoff=cutoff)
    theta_all, quantum = _encoder_angles(recording, cpr=cpr, cutoff=cutoff, source=source)
    warnings: list[str] = common.reader_warnings(recording)
    tick_log = common.is_tick_log(recording)
    has_current = "current" in recording.signals and not tick_log

    # ---- the coast: after the relay opened (plus a guard), until the shaft stopped -----------------
    idx, t_off, stopped = _find_coast(recording, theta_all, cutoff=cutoff, guard=guard, tick_log=tick_log,
                                      has_current=has_current, warnings=warnings)
    t, tau, theta, direction = _coast_angles(recording.time, theta_all, idx, quantum, source)
    voltage = _coast_voltage(recording, idx, tick_log=tick_log, warnings=warnings)

    # ---- stages 1 and 2: position only, then the bus voltage; then the joint weighted fit ----------
    coast = _fit_coast(tau, theta, voltage, source)
    joint, x = coast.joint, coast.joint.values
    comparison = coast.compare_nested()
    estimates = joint.estimates(_UNITS)
    support = _friction_support(estimates["Tf_over_J"], estimates["gamma"], comparison, warnings)
    omega = common.coast_speed(tau, x[1], x[2], x[3])
    warnings.extend(_short_coast_warning(omega, x))
    model_theta = x[0] + common.coast_position(tau, x[1], x[2], x[3])
    details = _details(t, x, t_off, stopped, direction, tick_log, comparison, support, coast.sigma_theta, quantum)
    return FitResult(
        experiment="spindown",
        parameters=_parameters(estimates, joint, voltage is not None, inertia, inertia_se),
        correlation=joint.correlation,
        correlation_names=list(joint.names),
        rmse=float(np.sqrt(np.mean((theta - model_theta) ** 2))),
        rmse_unit="rad",
        r2=r_squared(theta, model_theta),
        n_points=int(tau.size),
        panels=_panels(t, theta, model_theta, x, omega, voltage),
        warnings=warnings,
        details={**details, **_voltage_details(voltage, coast.sigma_v, x, omega)},
        sources=[recording.source] if recording.source else [],
    )


def _checked_options(*, guard: float, inertia: float | None, inertia_stderr: float | None,
                     cutoff: float | None) -> float:
    """Refuse an impossible guard, inertia, inertia standard error or cut-off; the inertia's standard
    error (0 if not given)."""
    common.check_nonnegative(guard, "guard")
    common.check_positive(inertia, "inertia")
    common.check_limits(inertia, "J", "the inertia (--inertia)")
    inertia_se = common.check_stderr_limit(inertia_stderr, "J", "the inertia's standard error (--inertia-stderr)")
    if cutoff is not None and not math.isfinite(cutoff):
        raise OptionError(f"cutoff must be a finite time in seconds, got {cutoff!r}")
    return inertia_se


def _encoder_angles(recording: Recording, *, cpr: float | None, cutoff: float | None,
                    source: str) -> tuple[np.ndarray, float]:
    """The encoder angle of every sample [rad] and one count [rad] (NaN when unknown).

    Raises
    ------
    LogFormatError
        NaN in the log, or no encoder signal.
    FitError
        Too few samples.
    OptionError
        Impossible ``cpr``; a ``cutoff`` outside the log's time span.
    """
    common.check_finite_signals(recording, ["counts", "position", "voltage", "current"])
    theta_all, quantum = common.position_of(recording, cpr=cpr)
    t_all = recording.time
    if t_all.size < _MIN_SAMPLES:
        raise FitError(f"{source}: {t_all.size} samples are too few for a spin-down fit")
    if cutoff is not None and not float(t_all[0]) <= cutoff <= float(t_all[-1]):
        # Before the log starts the powered run would be fitted as a coast (K = 1.30 against 0.70
        # and Tf/J < 0 in the QA run); after it ends there is nothing to fit.
        raise OptionError(f"the cut-off (--cutoff) {cutoff:g} s lies outside the log's time span "
                          f"{float(t_all[0]):g} s to {float(t_all[-1]):g} s", path=recording.source or None)
    return theta_all, quantum


def _coast_angles(t_all: np.ndarray, theta_all: np.ndarray, idx: np.ndarray, quantum: float,
                  source: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """The coast's times [s], times since its start τ [s], angle turned since its start [rad] (positive
    in the direction of the coast) and that direction (±1).

    Raises
    ------
    FitError
        A coast turning fewer than ``_MIN_COUNTS`` encoder counts.
    """
    start, stop = int(idx[0]), int(idx[-1])
    t = t_all[idx]
    tau = t - t[0]
    direction = 1.0 if theta_all[stop] >= theta_all[start] else -1.0
    theta = direction * (theta_all[idx] - theta_all[start])
    span = float(theta[-1])
    if math.isfinite(quantum) and span < _MIN_COUNTS * quantum:
        raise FitError(
            f"{source}: no coast found: the shaft turns only {span / quantum:.0f} counts after the cut-off"
        )
    return t, tau, theta, direction


def _coast_voltage(recording: Recording, idx: np.ndarray, *, tick_log: bool,
                   warnings: list[str]) -> np.ndarray | None:
    """The bus voltage during the coast, signed to be positive on the whole [V]; None (with a warning)
    when the log has none (a tick-timestamp log never has)."""
    if "voltage" not in recording.signals or tick_log:
        warnings.append("the log has no bus voltage: K is not estimated")
        return None
    raw_v = recording.signals["voltage"][idx]
    return (1.0 if float(np.sum(raw_v)) >= 0 else -1.0) * raw_v


def _short_coast_warning(omega: np.ndarray, x: np.ndarray) -> list[str]:
    """A warning when the speed fell by less than 20 % during the coast."""
    if omega[-1] > 0.8 * x[1]:
        return [
            f"coast too short: the speed fell by only {100 * (1 - omega[-1] / x[1]):.0f} %; "
            "gamma and Tf/J are poorly separated"
        ]
    return []


def _parameters(estimates: dict[str, Estimate], joint: LeastSquares, has_voltage: bool, inertia: float | None,
                inertia_se: float) -> dict[str, Estimate]:
    """K (with a bus voltage), γ and Tf/J; with the inertia also J, b and Tf."""
    parameters = {name: estimates[name] for name in (["K"] if has_voltage else []) + ["gamma", "Tf_over_J"]}
    if inertia is not None:
        parameters.update(_friction_from_inertia(joint, inertia, inertia_se))
    return parameters


def _voltage_details(voltage: np.ndarray | None, sigma_v: float, x: np.ndarray, omega: np.ndarray) -> dict[str, Any]:
    """The bus voltage's σ, the rms of its residuals and its sample count (none without a voltage)."""
    if voltage is None:
        return {}
    return {
        "sigma_voltage_V": sigma_v,
        "voltage_rmse_V": float(np.sqrt(np.mean((voltage - x[4] * omega) ** 2))),
        "n_voltage": int(voltage.size),
    }


def _friction_support(decel: Estimate, gamma_est: Estimate, comparison: dict[str, Any],
                      warnings: list[str]) -> tuple[bool, bool]:
    """Whether the Coulomb and the viscous terms are supported (F-test p < 0.01 and over 3 standard
    errors); a warning for each that is not."""
    z_decel = decel.value / decel.stderr if decel.stderr > 0 else math.inf
    coulomb_supported = comparison["viscous_only"]["p_value"] < 0.01 and z_decel > 3.0
    z_gamma = gamma_est.value / gamma_est.stderr if gamma_est.stderr > 0 else math.inf
    viscous_supported = comparison["coulomb_only"]["p_value"] < 0.01 and z_gamma > 3.0
    if not coulomb_supported:
        warnings.append(
            f"the data do not support a Coulomb friction term (F-test p = "
            f"{comparison['viscous_only']['p_value']:.2g}, Tf/J = {z_decel:.1f} standard errors): "
            "the seed's pure exponential fits as well"
        )
    if not viscous_supported:
        warnings.append(
            f"the data do not support a viscous friction term (F-test p = "
            f"{comparison['coulomb_only']['p_value']:.2g}, gamma = {z_gamma:.1f} standard errors)"
        )
    return bool(coulomb_supported), bool(viscous_supported)


def _details(t: np.ndarray, x: np.ndarray, t_off: float, stopped: bool, direction: float, tick_log: bool,
             comparison: dict[str, Any], support: tuple[bool, bool], sigma_theta: np.ndarray,
             quantum: float) -> dict[str, Any]:
    """The spin-down's ``details`` (the coast, its initial speed and stop, the model comparison)."""
    return {
        "cutoff_s": t_off,
        "coast_start_s": float(t[0]),
        "coast_end_s": float(t[-1]),
        "stopped": bool(stopped),
        "omega0_rad_per_s": float(x[1]),
        "stop_time_s": float(t[0] + common.stop_time(x[1], x[2], x[3])),
        "direction": int(direction),
        "tick_log": bool(tick_log),
        "model_comparison": comparison,
        "coulomb_supported": support[0],
        "viscous_supported": support[1],
        "sigma_position_rad": [float(sigma_theta.min()), float(sigma_theta.max())],
        "quantum_rad": quantum,
    }


def _panels(t: np.ndarray, theta: np.ndarray, model_theta: np.ndarray, x: np.ndarray, omega: np.ndarray,
            voltage: np.ndarray | None) -> list[Panel]:
    """Position, speed (display only), bus voltage and back-EMF against the fitted coast."""
    panels = [
        Panel(
            "Coast: position", "time [s]", "position since the coast began [rad]",
            data=Series(t, theta, "encoder"), model=Series(t, model_theta, "model", kind="model"), time=t,
        )
    ]
    mid = 0.5 * (t[1:] + t[:-1])
    dt = np.diff(t)
    ok = dt > 0
    fd_speed = np.diff(theta)[ok] / dt[ok]
    panels.append(
        Panel(
            "Coast: speed", "time [s]", "speed [rad/s]",
            data=Series(mid[ok], fd_speed, "finite-difference speed (display only; not fitted)"),
            model=Series(mid[ok], common.coast_speed(mid[ok] - t[0], x[1], x[2], x[3]), "model", kind="model"),
            time=mid[ok],  # a difference of two samples: selected, both go
        )
    )
    if voltage is not None:
        k = x[4]
        panels.append(
            Panel(
                "Coast: bus voltage", "time [s]", "bus voltage [V]",
                data=Series(t, voltage, "INA219 bus voltage"), model=Series(t, k * omega, "K·ω", kind="model"),
                time=t,
            )
        )
        order = np.argsort(omega)
        panels.append(
            Panel(
                "Back-EMF", "model speed [rad/s]", "bus voltage [V]",
                data=Series(omega[order], voltage[order], "INA219 bus voltage"),
                model=Series(omega[order], k * omega[order], "V = K·ω", kind="model"), time=t[order],
            )
        )

    return panels


def _aic(chi2: float, n: int, p: int) -> float:
    """Akaike's criterion n·ln(χ²/n) + 2p of a least-squares fit."""
    return n * math.log(max(chi2, 1e-300) / n) + 2 * p


def _friction_from_inertia(fit: LeastSquares, inertia: float, inertia_se: float) -> dict[str, Estimate]:
    """J, b = γ·J and Tf = (Tf/J)·J with first-order propagation of the fit's and J's uncertainties."""
    k_g, k_a = fit.names.index("gamma"), fit.names.index("Tf_over_J")
    gamma, decel = fit.values[k_g], fit.values[k_a]
    var_g, var_a = fit.covariance[k_g, k_g], fit.covariance[k_a, k_a]
    b_se = math.sqrt(inertia**2 * var_g + gamma**2 * inertia_se**2)
    tf_se = math.sqrt(inertia**2 * var_a + decel**2 * inertia_se**2)
    note_j = "given" + ("" if inertia_se > 0 else " (taken as exact)")
    return {
        "J": Estimate("J", inertia, inertia_se, SI_UNITS["J"], note=note_j),
        "b": Estimate("b", gamma * inertia, b_se, SI_UNITS["b"], bool(fit.determined[k_g])),
        "Tf": Estimate("Tf", decel * inertia, tf_se, SI_UNITS["Tf"], bool(fit.determined[k_a])),
    }
