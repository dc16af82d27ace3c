"""Whole-model identification from ordinary logs: applied voltage, encoder angle, maybe current.

``identify(recordings)`` fits the motor model

    L·di/dt = V − R·i − K·ω                       (4) of seed 1
    J·dω/dt = K·i − b·ω − Tf·sgn(ω)               (3) of seed 1 plus Coulomb friction

to what was measured — the encoder angle as counted (quantised) and, when logged, the winding current —
by simulating the model from the logged voltage (output error, maximum likelihood for measurement
noise). Nothing is differentiated out of the encoder. The start comes from a linear regression on
integrals over short windows, which needs no derivative either:

    ∫V dt = R·∫i dt + L·Δi + K·Δθ                  (electrical equation integrated over a window)
    Δω = (K/J)·∫i dt − (b/J)·Δθ − (Tf/J)·∫sgn(ω) dt (mechanical equation, ω from smoothed angles)

What the data determine: with current, all of K, R, L, J, b, Tf when the excitation is rich (L only
when the log is fast enough to see the current rise, τe = L/R spanning a few samples). Without current
the angle responds only to kS = R·Tf/K, kV = K + R·b/K and kA = R·J/K (see :mod:`motorlab.analyses.feedforward`);
with R supplied, K and b still cannot be separated (only kV = K + R·b/K is seen), so J and Tf follow only
when K is supplied too. Parameters the data do not determine are reported as such.

References
----------
Seed 1, "Equations" (eqs. 1–4); L. Ljung, *System Identification: Theory for the User*, 2nd ed.,
ch. 7 (output-error / prediction-error methods).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from threadpoolctl import threadpool_limits

from motorlab.errors import FitError, OptionError
from motorlab.estimation import held_input
from motorlab.estimation import output_error as _oe
from motorlab.estimation.covariance import MAX_RELATIVE_STDERR
from motorlab.estimation.decimate import driven_log
from motorlab.estimation.noise import input_noise_gain
from motorlab.estimation.noise import voltage_noise as run_voltage_noise
from motorlab.estimation.runs import (
    MOTOR_NAMES,
    MotorModel,
    estimate,
    excitation_warnings,
    fit_result,
    noise_levels,
    noise_warning,
    prepare_runs,
    regression_start,
)
from motorlab.model import MotorParams, feedforward_from_params
from motorlab.recording import Recording
from motorlab.results import Estimate, FitResult
from motorlab.thermal import identify as identify_thermal
from motorlab.thermal.network import ThermalModel
from motorlab.units import SI_UNITS, format_unit


#: Parameters of the full model, in the order of the fit.
@threadpool_limits.wrap(limits=1, user_api="blas")  # tall-skinny products: threads only contend (15× on a busy box)
def identify(
    recordings: Recording | Sequence[Recording],
    *,
    resistance: float | None = None,
    torque_constant: float | None = None,
    cpr: float | None = None,
    use_current: bool = True,
    thermal: bool = False,
    motor: str | None = None,
    network: ThermalModel | None = None,
    initial_temperature: float | None = None,
) -> FitResult:
    """Identify the motor from logs of applied voltage, encoder angle and (optionally) current.

    Parameters
    ----------
    recordings
        One or several runs of the same motor, each with ``voltage`` [V] and ``position`` [rad] (and
        ``current`` [A]); the runs are fitted together (the tests of a SysId file are separate runs:
        use ``Recording.split()``).
    resistance
        Winding resistance R [Ω], when known from elsewhere (needed without current to go from the
        feedforward gains to K, J, b, Tf).
    torque_constant
        Torque constant K [V·s/rad], when known from elsewhere (without current, separates K from b).
    cpr
        Encoder counts per revolution at the shaft [count/rev] (sets the angle quantum 2π/cpr;
        otherwise taken from the file or from the smallest step of the angle).
    use_current
        Fit the current when every run has one (False: use only voltage and angle).
    thermal, motor, network, initial_temperature
        Fit the winding's temperature as a state (needs current; :mod:`motorlab.thermal.identify`): R, K at
        25 °C; the network a catalogue ``motor``'s, one given, else the log's motor's or a 550-size one's;
        each run starts at ``initial_temperature`` [°C] (default: the ambient's).

    Returns
    -------
    FitResult
        With current: K, R, L, J, b, Tf. Without: kS, kV, kA, and R, K, J, b, Tf as far as the given
        values determine them. Panels of measured against simulated angle, speed, current; residual RMS
        per signal in ``details["residual_rms"]``; the Newey–West correlation matrix.

    Raises
    ------
    LogFormatError
        A run lacks voltage or angle, has too few samples, non-finite values or a time that does not
        increase.
    OptionError
        A non-positive resistance, torque constant or cpr.
    FitError
        No starting point can be found (no motion, no current response).

    Notes
    -----
    Input model (:mod:`motorlab.estimation.held_input`, ``details["input_model"]``): a drive that holds levels
    is fitted with each level estimated from all its samples jointly with the model and each switch
    instant located inside its sample interval (nuisance parameters); switches found on the sample
    instants are fixed there. ``details["cramer_rao_bound"]``: the Cramér–Rao bound of this log
    with those nuisance parameters, and each standard error over it (also in each estimate's note).

    Otherwise the logged voltage's noise reaches the simulated current (errors in the input variable): the current
    is weighted by its measured noise plus that, and the first-order bias it causes (mostly in L and R) is removed
    (:func:`motorlab.estimation.noise.input_noise_bias`). Standard errors propagate the measured noises —
    voltage through the plant, current, and counting errors correlated as a quantiser of unknown phase makes
    them — through the linearised fit (:func:`motorlab.estimation.noise.noise_propagation_covariance`); the
    Newey–West covariance of the residuals is used when these noises do not explain the residuals.
    """
    recs = _checked_recordings(recordings, resistance=resistance, torque_constant=torque_constant, cpr=cpr)
    with_current = use_current and all("current" in r for r in recs)
    heated = identify_thermal.wanted(thermal or network is not None, with_current=with_current)
    if not with_current:
        return _identify_without_current(recs, resistance=resistance, torque_constant=torque_constant, cpr=cpr,
                                         note_missing=use_current and any("current" in r for r in recs))
    logs, warnings = prepare_runs(recs, cpr=cpr, with_current=True)
    p0, lower, upper, scale = _start_and_bounds(logs)
    dt = min(log.dt for log in logs)
    sigma, current_noise, voltage_noise = _noise_weights(logs, np.clip(p0, lower, upper), dt)
    heat = identify_thermal.copper_drop(recs, logs, motor=motor, network=network, initial=initial_temperature,
                                        resistance=float(np.clip(p0, lower, upper)[1])) if heated else None
    wrap = heat.wrap if heat is not None else identify_thermal.unchanged

    def sample_held(start: np.ndarray) -> _oe.Fit:
        return _oe.fit_output_error(wrap(MotorModel()), logs, np.clip(start, lower, upper), lower=lower, upper=upper,
                                    scale=scale, sigma=sigma, current_noise=current_noise)

    fit, input_details = _input_model(recs, logs, sample_held, np.clip(p0, lower, upper), lower=lower, upper=upper,
                                      scale=scale, sigma_position=sigma["position"], current_noise=current_noise,
                                      wrap=wrap)
    if input_details["model"] != "sample-held":
        sigma["current"] = current_noise
    values = fit.values[:6]
    cov = fit.covariance[:6, :6]
    stderr = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    params = _motor_estimates(fit, values, stderr, l_floor=lower[2], dt=dt)
    warnings.extend(_fit_warnings(fit, logs, values, resistance=resistance, torque_constant=torque_constant))
    corr = _correlation(cov, stderr)
    details = _details(fit, values, p0, sigma, input_details, current_noise=current_noise, voltage_noise=voltage_noise)
    _bound_details(fit, logs, params, details, weight_current=sigma["current"], current_noise=current_noise)
    identify_thermal.annotate(heat, params, details, warnings)
    return fit_result("identify", params, corr, list(MOTOR_NAMES), logs, fit, warnings, details)


def _correlation(cov: np.ndarray, stderr: np.ndarray) -> np.ndarray:
    """The correlation matrix of a covariance (1 on the diagonal, NaN where a standard error is 0)."""
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(stderr, stderr)
    np.fill_diagonal(corr, 1.0)
    return corr


def _checked_recordings(recordings: Recording | Sequence[Recording], *, resistance: float | None,
                        torque_constant: float | None, cpr: float | None) -> list[Recording]:
    """The runs (long ones made affordable: :func:`motorlab.estimation.decimate.driven_log`) after checking the options.

    Raises
    ------
    OptionError
        No recordings, or a non-positive resistance, torque constant or cpr.
    """
    recordings = [driven_log(r) for r in ([recordings] if isinstance(recordings, Recording) else recordings)]
    recs = [recordings] if isinstance(recordings, Recording) else list(recordings)
    if not recs:
        raise OptionError("no recordings to identify")
    for name, value in (("resistance", resistance), ("torque constant", torque_constant), ("cpr", cpr)):
        if value is not None and not (math.isfinite(value) and value > 0):
            raise OptionError(f"{name} must be a positive number, got {value}")
    return recs


def _start_and_bounds(logs: list[_oe.Log]) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Start (:func:`regression_start`), lower and upper bounds and scale of K, R, L, J, b, Tf (SI).

    Raises
    ------
    FitError
        No starting point can be found; the message names the files.
    """
    try:
        p0 = regression_start(logs)
    except FitError as exc:  # name the file(s): the user must know which log cannot be explained
        raise FitError(f"{', '.join(dict.fromkeys(log.source for log in logs if log.source))}: {exc}") from None
    k0, r0, _, j0, _, _ = p0
    v_max = max(float(np.max(np.abs(log.grid_voltage))) for log in logs)
    dt = min(log.dt for log in logs)
    scale = np.array([k0, r0, max(p0[2], r0 * dt), j0, max(p0[4], 0.05 * k0 * k0 / r0),
                      max(p0[5], 0.01 * k0 * v_max / r0)])
    lower = np.array([1e-3 * k0, 1e-3 * r0, 1e-3 * r0 * dt, 1e-3 * j0, 0.0, 0.0])
    upper = np.array([1e3 * k0, 1e3 * r0, 1e3 * scale[2] + 1.0, 1e3 * j0, 1e3 * scale[4], 1e3 * scale[5]])
    return p0, lower, upper, scale


def _noise_weights(logs: list[_oe.Log], start: np.ndarray, dt: float) -> tuple[dict[str, float], float, float]:
    """Noise weights of angle and current, the current's measured noise [A] and the voltage's [V].

    The simulated current carries the logged voltage's noise filtered by the winding (errors in the
    input variable): the current is weighted by the noise its residual really has, measurement and
    input, the latter from the plant at ``start`` (K, R, L, J, b, Tf) and the grid step ``dt`` [s].
    """
    sigma = noise_levels(logs, with_current=True)
    current_noise = sigma["current"]
    gain = float(input_noise_gain(MotorModel().plant(start), dt)[0, 0])
    voltage_noise = max(run_voltage_noise(log) for log in logs)
    sigma["current"] = math.sqrt(current_noise**2 + voltage_noise**2 * gain)
    return sigma, current_noise, voltage_noise


def _fit_warnings(fit: _oe.Fit, logs: list[_oe.Log], values: np.ndarray, *, resistance: float | None,
                  torque_constant: float | None) -> list[str]:
    """Optimiser, noise and excitation warnings, and a note for each given R or K the fit did not use."""
    warnings = []
    if not fit.success:
        warnings.append(f"the optimiser stopped early: {fit.message}")
    warnings.extend(noise_warning(fit, rms_text=f"{fit.residual_rms['position']:.3g} rad"))
    warnings.extend(excitation_warnings(logs, [s["speed"] for s in fit.simulations]))
    for symbol, given, index in (("R", resistance, 1), ("K", torque_constant, 0)):
        if given is not None:  # the current log determines it: say so, and how far the given value is
            warnings.append(
                f"the given {symbol} = {given:.4g} {format_unit(SI_UNITS[symbol])} was not used: with a current "
                f"column {symbol} is fitted ({values[index]:.4g}, {100 * (values[index] / given - 1):+.1f} % "
                "from the given value); "
                "--no-current fits without the current and uses it"
            )
    return warnings


def _details(fit: _oe.Fit, values: np.ndarray, p0: np.ndarray, sigma: dict[str, float], input_details: dict[str, Any],
             *, current_noise: float, voltage_noise: float) -> dict[str, Any]:
    """``FitResult.details`` of the fit with current (the Cramér–Rao bound is added by :func:`_bound_details`)."""
    motor = MotorParams(*(float(v) for v in np.maximum(values, [1e-12, 1e-12, 0, 1e-12, 0, 0])[:6]))
    return {
        "method": "output error (angle and current simulated from the voltage)"
        + (", errors-in-variables bias removed" if np.any(fit.bias_correction) else "")
        + f"; input: {input_details['text']}",
        "residual_rms": {**fit.residual_rms},
        "residual_rms_units": {"position": "rad", "current": "A"},
        "noise_weights": sigma,
        "measured_noise": {"current": current_noise, "voltage": voltage_noise},
        "uncertainty": fit.noise_model,
        "input_noise_bias_removed": dict(zip(MOTOR_NAMES, fit.bias_correction[:6].tolist(), strict=True)),
        "start": dict(zip(MOTOR_NAMES, p0.tolist(), strict=True)),
        "feedforward": feedforward_from_params(motor),
        "hac_bandwidth_samples": fit.bandwidth,
        "stderr_white_residuals": dict(zip(MOTOR_NAMES, np.sqrt(np.diag(fit.covariance_white)[:6]).tolist(),
                                           strict=True)),
        "stderr_newey_west": dict(zip(MOTOR_NAMES, np.sqrt(np.diag(fit.covariance_residuals)[:6]).tolist(),
                                      strict=True)),
        "function_evaluations": fit.nfev,
        "cost": fit.cost,
        "input_model": input_details,
    }


def _motor_estimates(fit: _oe.Fit, values: np.ndarray, stderr: np.ndarray, *, l_floor: float,
                     dt: float) -> dict[str, Estimate]:
    """K, R, L, J, b, Tf with their standard errors; "not determined" on a null direction, beyond the
    relative-error bound, or (L) within 3σ of zero or at its lower bound ``l_floor`` [H]."""
    params: dict[str, Estimate] = {}
    for k, name in enumerate(MOTOR_NAMES):
        if fit.not_minimum:  # the Jacobian cannot be trusted: say so, print no standard error
            params[name] = estimate(name, values[k], math.nan, note=f"no standard error: {fit.not_minimum}")
            continue
        determined = not fit.null[k] and stderr[k] <= MAX_RELATIVE_STDERR * abs(values[k])
        note = ""
        if name == "L" and (values[k] <= 1.01 * l_floor or values[k] < 3.0 * stderr[k]):
            # L ≥ 0 is seen only through the current rise (and its small delay of the torque): an
            # estimate within 3σ of zero says only "τe is too short to see", not a value
            determined = False
        if not determined:
            note = "the data carry (almost) no information on it"
            if name == "L":
                note = (
                    f"τe = L/R is too short for samples every {1e3 * dt:.3g} ms to see the current rise "
                    f"(L < {values[k] + 2 * stderr[k]:.2g} H)"
                )
        params[name] = estimate(name, values[k], stderr[k], determined=determined, note=note)
    return params


def _input_model(
    recs: list[Recording], logs: list[_oe.Log], sample_held: Callable[[np.ndarray], _oe.Fit], p0: np.ndarray, *,
    lower: np.ndarray, upper: np.ndarray, scale: np.ndarray, sigma_position: float, current_noise: float,
    wrap: Callable[[_oe.OEModel], _oe.OEModel] = lambda model: model,
) -> tuple[_oe.Fit, dict[str, Any]]:
    """Refit with held levels and switch instants as nuisance parameters when the drive holds levels.

    The voltage of every run is tested for held levels (:func:`motorlab.estimation.held_input.detect_held`);
    then the model is fitted with each switch instant free inside its sample interval. When every
    located switch sits on its sample instant (within 3σ) the switch instants are fixed there: with
    exact levels that is the sample-held fit (``sample_held(start)``, also used when the drive does not
    hold levels); with noisy levels the levels stay free.
    ``wrap`` changes the held-level models as ``sample_held`` changes its own (the winding's heat, identify
    --thermal). Returns the fit to report and ``details["input_model"]``.
    """
    checks = [held_input.detect_held(rec.signals["voltage"], log.current) if log.uniform
              else (None, "non-uniform sample times") for rec, log in zip(recs, logs, strict=True)]
    held = [h for h, _ in checks]
    if any(h is None for h in held):
        reason = next(why for h, why in checks if h is None)
        return sample_held(p0), {"model": "sample-held", "text": f"voltage held over each sample as logged ({reason})"}
    helds = [h for h in held if h is not None]
    exact = all(h.sigma == 0 for h in helds)
    sigma = {"position": sigma_position, "current": current_noise}
    model: Any = wrap(held_input.HeldMotorModel(logs, helds, free_switch=True))
    z0, lo, hi, sc = model.start_and_bounds(p0, lower, upper, scale)
    free = _oe.fit_output_error(model, logs, z0, lower=lo, upper=hi, scale=sc, sigma=sigma,
                                current_noise=current_noise)
    if not (free.success and np.all(np.isfinite(np.diag(free.covariance)))):
        return sample_held(p0), {"model": "sample-held", "text": "voltage held over each sample as logged (the "
                                 f"held-level fit did not converge: {free.message})"}
    summary = held_input.switch_summary(model, free)
    on = held_input.on_sample_instants(summary)
    levels = "exact levels as logged" if exact else "levels estimated from all their samples with the model"
    info: dict[str, Any] = {"segments": sum(h.n_segments for h in helds), **summary,
                            "voltage_noise": max(h.sigma for h in helds)}
    if on is True and exact:
        return sample_held(free.values[:6]), {"model": "sample-held", **info,
                     "text": "held levels switching on sample instants, exact voltage: held over each sample as logged"}
    if on is True:
        fixed: Any = wrap(held_input.HeldMotorModel(logs, helds, free_switch=False))
        z1, lo1, hi1, sc1 = fixed.start_and_bounds(free.values[:6], lower, upper, scale)
        z1[6:] = [v for name, v in zip(free.names, free.values, strict=False) if name.startswith("level")]
        refit = _oe.fit_output_error(fixed, logs, z1, lower=lo1, upper=hi1, scale=sc1, sigma=sigma,
                                     current_noise=current_noise)
        return refit, {"model": "held levels, switches on sample instants", **info,
                       "text": f"held levels switching on sample instants; {levels}"}
    where = ("switch instants located inside their sample intervals from the current transients" if on is False
             else "switch instants not resolved by the data: estimated within their sample intervals (marginalised)")
    return free, {"model": "held levels, switches between samples", **info, "text": f"{where}; {levels}"}


def _bound_details(fit: _oe.Fit, logs: list[_oe.Log], params: dict[str, Estimate], details: dict[str, Any], *,
                   weight_current: float, current_noise: float) -> None:
    """The Cramér–Rao bound of this log and model in ``details`` and each determined estimate's note."""
    bound = held_input.cramer_rao(fit, logs, 6, current_factor=weight_current / current_noise)
    nuisance = details["input_model"]["model"] != "sample-held"
    details["cramer_rao_bound"] = {
        "includes": ("held levels, switch instants" if nuisance else "known input (the logged voltage taken as exact)")
        + ", angle offsets and initial speeds as nuisance parameters",
        "bound": dict(zip(MOTOR_NAMES, bound.tolist(), strict=True)),
        "stderr_over_bound": {},
    }
    for k, name in enumerate(MOTOR_NAMES):
        est = params[name]
        ratio = est.stderr / bound[k] if bound[k] > 0 else math.inf
        details["cramer_rao_bound"]["stderr_over_bound"][name] = ratio
        if est.determined and math.isfinite(ratio) and not est.note:
            text = (f"within {max(ratio, 1.0):.2g}× of the best any method could do on this log" if ratio >= 0.95 else
                    f"at the best any method could do on this log (stderr {ratio:.2g}× the Gaussian bound)")
            params[name] = estimate(name, est.value, est.stderr, note=text)


def _identify_without_current(
    recs: list[Recording],
    *,
    resistance: float | None,
    torque_constant: float | None,
    cpr: float | None,
    note_missing: bool,
) -> FitResult:
    from motorlab.analyses import feedforward

    result = feedforward.feedforward(recs, cpr=cpr)
    result.experiment = "identify"
    if note_missing:
        result.warnings.append("not every run has a current column: the current was not used")
    result.parameters.update(
        feedforward.motor_estimates(result, resistance=resistance, torque_constant=torque_constant)
    )
    result.check_physics()
    return result
