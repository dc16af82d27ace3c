"""Spin-up of a known flywheel at constant current: K = J·α/i, corrected for friction.

Seed 1, "First Experiment": drive the motor from a current-limited supply into a flywheel of known
inertia J and measure the angular acceleration α; then τ = J·α (5) and K = τ/i (1). The seed ignores
friction. Here, when the friction of the same rig is known (from a spin-down, or given), the exact
solution of

    J·dω/dt = K·i − b·ω − Tf

is fitted to the encoder position during the constant-current phase, and the uncertainties of J, b
and Tf are propagated into K.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from motorlab.analyses import common
from motorlab.errors import FitError, OptionError
from motorlab.estimation.decimate import block_mean
from motorlab.estimation.least_squares import LeastSquares, r_squared
from motorlab.recording import Recording
from motorlab.results import Estimate, FitResult, Panel, Series
from motorlab.units import SI_UNITS, format_percent

_MIN_SAMPLES = 8
#: Relative scatter of the current above which a warning says it was not constant.
_CURRENT_TOLERANCE = 0.02


def constant_current_phase(time: np.ndarray, current: np.ndarray, *, source: str = "") -> tuple[int, int]:
    """First and last index of the constant-current (supply in CC) phase of a spin-up.

    The phase begins at the first sample carrying at least half the plateau current and ends before
    the first run of three samples that leave the plateau band (the supply crossing over to constant
    voltage, or the relay opening).

    Raises
    ------
    FitError
        When the log has no current flowing.
    """
    i_abs = np.abs(current)
    i_top = float(np.percentile(i_abs, 95))
    if i_top < 0.02:
        raise FitError(f"{source}: no spin-up found: no current flows in this log")
    plateau = float(np.median(i_abs[i_abs > 0.5 * i_top]))
    first = int(np.flatnonzero(i_abs > 0.5 * plateau)[0])
    spread = 1.4826 * float(np.median(np.abs(i_abs[i_abs > 0.5 * i_top] - plateau)))
    band = max(0.02 * plateau, 4.0 * spread, 0.005)
    outside = np.abs(i_abs[first:] - plateau) > band
    # End before three consecutive samples outside the band (isolated spikes are noise).
    run = outside[:-2] & outside[1:-1] & outside[2:] if outside.size >= 3 else outside
    leave = np.flatnonzero(run)
    last = first + int(leave[0]) - 1 if leave.size else time.size - 1
    return first, max(last, first)


def spinup(
    recording: Recording,
    *,
    inertia: float,
    inertia_stderr: float | None = None,
    cpr: float | None = None,
    viscous_friction: float | None = None,
    viscous_friction_stderr: float | None = None,
    coulomb_friction: float | None = None,
    coulomb_friction_stderr: float | None = None,
    spindown_result: FitResult | None = None,
    start: float | None = None,
    end: float | None = None,
) -> FitResult:
    """Fit K from a constant-current spin-up of a flywheel of known inertia.

    Parameters
    ----------
    recording
        FTC log of the run (``time``, ``counts`` or ``position``, ``current``); a coast after the
        spin-up is ignored.
    inertia
        Total inertia at the encoder shaft [kg·m²].
    inertia_stderr
        Its standard error [kg·m²] (default: exact).
    cpr
        Encoder counts per revolution of the counted shaft [count/rev].
    viscous_friction, coulomb_friction
        b [N·m·s/rad] and Tf [N·m] of the rig, if known (default: none, the seed's K = J·α/i).
    viscous_friction_stderr, coulomb_friction_stderr
        Their standard errors [N·m·s/rad], [N·m] (default: exact).
    spindown_result
        A :func:`~motorlab.analyses.spindown.spindown` result of the same rig: its γ = b/J and Tf/J
        (with their covariance) are used instead of b and Tf.
    start, end
        Limits of the constant-current phase [s] (default: found from the current).

    Returns
    -------
    FitResult
        ``K`` [V·s/rad], ``alpha`` (the acceleration at zero speed, (K·i − Tf)/J) [rad/s²] and the
        mean current ``i`` [A]; ``details`` holds the current's stability.

    Raises
    ------
    OptionError
        Impossible inertia, friction or limits (``start`` not before ``end``, or outside the log's
        time span), or friction given twice.
    LogFormatError
        NaN in the log, no encoder signal or no current.
    FitError
        No current flows, or too few samples in the constant-current phase.

    Notes
    -----
    With γ = b/J and A = (K·i − Tf)/J, ω(τ) = ω0·e^(−γτ) + (A/γ)(1 − e^(−γτ)) and
    θ(τ) = θ0 + ω0·τ·φ1(γτ) + A·τ²·φ2(γτ) (φ1(x) = (1 − e^(−x))/x, φ2(x) = (x − 1 + e^(−x))/x²,
    both finite at γ = 0, where this is θ0 + ω0·τ + ½·α·τ²). θ0 and ω0 are free (the log's first
    powered sample is not the instant the relay closed). Known inputs enter as priors so that their
    uncertainties reach K. The current i is the mean shunt current over the phase, less the sensor's
    zero offset read while the relay is open (samples before or after the spin-up, if any).

    References
    ----------
    Seed 1, "First Experiment", equations (1), (3) and (5).
    """
    recording = block_mean(recording)  # a 2M-row log: block means, not 2M-point fits
    source = recording.source or "log"
    inertia_se, b_se, tf_se = _check_options(
        inertia=inertia, inertia_stderr=inertia_stderr, viscous_friction=viscous_friction,
        viscous_friction_stderr=viscous_friction_stderr, coulomb_friction=coulomb_friction,
        coulomb_friction_stderr=coulomb_friction_stderr, spindown_result=spindown_result, start=start, end=end,
    )
    warnings: list[str] = common.reader_warnings(recording)
    phase = _phase(recording, cpr=cpr, start=start, end=end, source=source)
    if phase.i_std > _CURRENT_TOLERANCE * phase.i_mean:
        warnings.append(
            f"the current was not constant during the spin-up: {phase.i_mean:.4g} A ± "
            f"{format_percent(phase.i_std / phase.i_mean, '.1f')}"
        )
    # Friction: priors on (b, Tf), or on (gamma, Tf/J) from a spin-down.
    if spindown_result is not None:
        mode = "gamma"
        f_mean, f_cov = _spindown_prior(spindown_result)
    else:
        mode = "b"
        f_mean = np.array([viscous_friction or 0.0, coulomb_friction or 0.0])
        f_cov = np.diag([b_se**2, tf_se**2])
        if viscous_friction is None and coulomb_friction is None:
            warnings.append(
                "no friction given (--b, --Tf or --spindown): K = J·α/i ignores friction and is biased low"
            )
    fit, x_full = _fit(phase, mode, f_mean, f_cov, inertia=inertia, inertia_se=inertia_se, source=source)
    return _result(recording, phase, fit, x_full, mode=mode, f_mean=f_mean, warnings=warnings)


_UNITS = {"theta0": "rad", "omega0": "rad/s", "K": SI_UNITS["K"], "J": SI_UNITS["J"], "f1": "", "f2": "", "i": "A"}
#: Parameters of the spin-up fit, in the order of its parameter vector x.
_PARAMETERS = ("theta0", "omega0", "K", "J", "f1", "f2", "i")


@dataclass
class _Phase:
    """The constant-current phase of a spin-up, signed so that the shaft turns forward."""

    t: np.ndarray  # [s]
    tau: np.ndarray  # time since the phase began [s]
    theta: np.ndarray  # position since the phase began [rad]
    i_samples: np.ndarray  # current [A]
    i_mean: float  # mean current less the sensor's zero offset [A]
    i_se: float  # its standard error [A]
    i_std: float  # scatter of the current [A]
    offset: float  # the sensor's zero offset [A]
    offset_samples: int  # samples (relay open) it was read from


def _check_options(
    *,
    inertia: float,
    inertia_stderr: float | None,
    viscous_friction: float | None,
    viscous_friction_stderr: float | None,
    coulomb_friction: float | None,
    coulomb_friction_stderr: float | None,
    spindown_result: FitResult | None,
    start: float | None,
    end: float | None,
) -> tuple[float, float, float]:
    """Raise :class:`OptionError` for impossible options; returns the standard errors of J, b and Tf."""
    common.check_positive(inertia, "inertia", allow_none=False)
    common.check_limits(inertia, "J", "the inertia (--inertia)")
    inertia_se = common.check_stderr_limit(inertia_stderr, "J", "the inertia's standard error (--inertia-stderr)")
    common.check_nonnegative(viscous_friction, "viscous friction b")
    common.check_nonnegative(coulomb_friction, "Coulomb friction Tf")
    common.check_limits(viscous_friction, "b", "the viscous friction b (--b)")
    common.check_limits(coulomb_friction, "Tf", "the Coulomb friction Tf (--Tf)")
    b_se = common.check_stderr_limit(viscous_friction_stderr, "b", "the standard error of b (--b-stderr)")
    tf_se = common.check_stderr_limit(coulomb_friction_stderr, "Tf", "the standard error of Tf (--Tf-stderr)")
    if spindown_result is not None and (viscous_friction is not None or coulomb_friction is not None):
        raise OptionError("give the friction either from a spin-down or as b/Tf, not both")
    for value, name in ((start, "start (--start)"), (end, "end (--end)")):
        if value is not None and not math.isfinite(value):
            raise OptionError(f"the {name} must be a finite time in seconds, got {value!r}")
    if start is not None and end is not None and not start < end:
        raise OptionError(f"the start (--start {start:g} s) is not before the end (--end {end:g} s) of the "
                          "constant-current phase")
    return inertia_se, b_se, tf_se


def _phase(recording: Recording, *, cpr: float | None, start: float | None, end: float | None, source: str) -> _Phase:
    """The constant-current phase (found from the current, or between ``start`` and ``end`` [s]) and its current."""
    common.check_finite_signals(recording, ["counts", "position", "current"])
    theta_all, _quantum = common.position_of(recording, cpr=cpr)
    current_all = recording.require("current")
    t_all = recording.time
    span = f"{float(t_all[0]):g} s to {float(t_all[-1]):g} s" if t_all.size else "empty"
    for value, name in ((start, "start (--start)"), (end, "end (--end)")):
        if value is not None and t_all.size and not float(t_all[0]) <= value <= float(t_all[-1]):
            raise OptionError(f"the {name} {value:g} s lies outside the log's time span {span}",
                              path=recording.source or None)

    first, last = constant_current_phase(t_all, current_all, source=source)
    if start is not None:
        first = int(np.searchsorted(t_all, start, side="left"))
    if end is not None:
        last = int(np.searchsorted(t_all, end, side="right")) - 1
    idx = np.arange(first, last + 1)
    if idx.size < _MIN_SAMPLES:
        raise FitError(f"{source}: only {idx.size} samples at constant current: too few for a spin-up fit")
    t = t_all[idx]
    tau = t - t[0]
    direction = 1.0 if theta_all[idx[-1]] >= theta_all[idx[0]] else -1.0
    theta = direction * (theta_all[idx] - theta_all[idx[0]])
    i_samples = direction * current_all[idx]
    i_std = float(np.std(i_samples, ddof=1))
    # The sensor's zero offset (seed 1's log reads −0.001 A with the relay open) is a bias of K·i:
    # remove it when the log has samples with the relay open, before or after the spin-up.
    outside = np.ones(t_all.size, dtype=bool)
    outside[max(first - 1, 0):last + 2] = False
    off = outside & (np.abs(current_all) < 0.05 * float(np.mean(np.abs(current_all[idx]))))
    offset, offset_se = 0.0, 0.0
    if off.any():
        offset = float(np.mean(direction * current_all[off]))
        spread = float(np.std(current_all[off], ddof=1)) if off.sum() >= 3 else i_std
        offset_se = spread / math.sqrt(int(off.sum()))
    i_mean = float(np.mean(i_samples)) - offset
    i_se = math.hypot(i_std / math.sqrt(i_samples.size), offset_se)
    if i_mean <= 0:
        raise FitError(f"{source}: the current and the motion have opposite signs: not a spin-up")
    return _Phase(t, tau, theta, i_samples, i_mean, i_se, i_std, offset, int(off.sum()))


def _rates(x: np.ndarray, mode: str) -> tuple[float, float]:
    """γ [1/s] and A = (K·i − Tf)/J [rad/s²] of parameter vector x, friction as (b, Tf) or (γ, Tf/J) (``mode``)."""
    k, j, f1, f2, i = x[2], x[3], x[4], x[5], x[6]
    if mode == "gamma":
        return f1, k * i / j - f2
    return f1 / j, (k * i - f2) / j


def _position(x: np.ndarray, tau: np.ndarray, mode: str) -> np.ndarray:
    """Model position θ(τ) [rad] of parameter vector x."""
    gamma, accel = _rates(x, mode)
    return x[0] + common.ramp_position(tau, x[1], gamma, accel)


def _fit(
    phase: _Phase, mode: str, f_mean: np.ndarray, f_cov: np.ndarray, *, inertia: float, inertia_se: float, source: str
) -> tuple[LeastSquares, np.ndarray]:
    """Fit θ(τ) to the phase with J, the friction and i as priors; returns the fit and the full parameter vector."""
    tau, theta, i_mean = phase.tau, phase.theta, phase.i_mean
    names = list(_PARAMETERS)
    # Starting values: a quadratic fit gives α, hence K.
    quad = np.polyfit(tau, theta, 2)
    alpha0 = 2.0 * quad[0]
    x0 = np.array([quad[2], quad[1], 0.0, inertia, f_mean[0], f_mean[1], i_mean])
    gamma0, _ = _rates(np.concatenate([x0[:2], [1.0], x0[3:]]), mode)
    tf_over_j = f_mean[1] if mode == "gamma" else f_mean[1] / inertia
    x0[2] = max(inertia * (alpha0 + gamma0 * quad[1] + tf_over_j) / i_mean, 1e-9)
    priors = [
        common.Prior(["J"], np.array([inertia]), np.array([[inertia_se**2]])),
        common.Prior(["f1", "f2"], f_mean, f_cov),
        common.Prior(["i"], np.array([i_mean]), np.array([[phase.i_se**2]])),
    ]
    # Stage 1 with unit weights gives the residuals from which the position σ's are estimated.
    sigma = np.ones_like(theta)
    try:
        fit, x_full = common.fit_with_priors(lambda x: (_position(x, tau, mode) - theta) / sigma, x0, names, priors)
        res = _position(x_full, tau, mode) - theta
        speed = common.ramp_speed(tau, x_full[1], *_rates(x_full, mode))
        sigma = common.speed_noise_sigma(res, speed, dof=max(theta.size - 3, 1))
        fit, x_full = common.fit_with_priors(lambda x: (_position(x, tau, mode) - theta) / sigma, x_full, names,
                                             priors)
    except FitError as exc:
        raise common.in_file(exc, source) from None
    return fit, x_full


def _result(
    recording: Recording,
    phase: _Phase,
    fit: LeastSquares,
    x_full: np.ndarray,
    *,
    mode: str,
    f_mean: np.ndarray,
    warnings: list[str],
) -> FitResult:
    """K, α and i of the fitted spin-up, with its panels and details."""
    t, theta, i_mean = phase.t, phase.theta, phase.i_mean
    est = fit.estimates({n: _UNITS[n] for n in fit.names})
    alpha = _rates(x_full, mode)[1]
    alpha_se = common.derived_stderr(fit, x_full, list(_PARAMETERS), lambda x: _rates(x, mode)[1])
    parameters: dict[str, Estimate] = {
        "K": est["K"],
        "alpha": Estimate("alpha", alpha, alpha_se, "rad/s^2", note="acceleration at zero speed, (K·i − Tf)/J"),
        "i": Estimate("i", i_mean, phase.i_se, "A", note="mean current during the spin-up"),
    }
    model_theta = _position(x_full, phase.tau, mode)
    model_speed = common.ramp_speed(phase.tau, x_full[1], *_rates(x_full, mode))
    details: dict[str, Any] = {
        "start_s": float(t[0]),
        "end_s": float(t[-1]),
        "current_mean_A": i_mean,
        "current_offset_A": phase.offset,
        "current_offset_samples": phase.offset_samples,
        "current_std_A": phase.i_std,
        "current_relative_scatter": phase.i_std / i_mean,
        "friction_from": "spindown" if mode == "gamma" else ("given" if f_mean.any() else "none"),
        "gamma_1_per_s": float(_rates(x_full, mode)[0]),
        "omega_end_rad_per_s": float(model_speed[-1]),
    }
    return FitResult(
        experiment="spinup",
        parameters=parameters,
        correlation=fit.correlation,
        correlation_names=list(fit.names),
        rmse=float(np.sqrt(np.mean((theta - model_theta) ** 2))),
        rmse_unit="rad",
        r2=r_squared(theta, model_theta),
        n_points=int(theta.size),
        panels=_panels(phase, model_theta, x_full, mode),
        warnings=warnings,
        details=details,
        sources=[recording.source] if recording.source else [],
    )


def _panels(phase: _Phase, model_theta: np.ndarray, x_full: np.ndarray, mode: str) -> list[Panel]:
    """Position, speed and current of the phase against the model."""
    t, theta = phase.t, phase.theta
    mid = 0.5 * (t[1:] + t[:-1])
    dt = np.diff(t)
    ok = dt > 0
    return [
        Panel("Spin-up: position", "time [s]", "position since the spin-up began [rad]",
              data=Series(t, theta, "encoder"), model=Series(t, model_theta, "model", kind="model"), time=t),
        Panel("Spin-up: speed", "time [s]", "speed [rad/s]",
              data=Series(mid[ok], np.diff(theta)[ok] / dt[ok], "finite-difference speed (display only)"),
              model=Series(mid[ok], common.ramp_speed(mid[ok] - t[0], x_full[1], *_rates(x_full, mode)), "model",
                           kind="model"), time=mid[ok]),
        Panel("Spin-up: current", "time [s]", "current [A]", data=Series(t, phase.i_samples, "shunt current"),
              model=Series(t, np.full_like(t, phase.i_mean), "mean", kind="model"), time=t),
    ]


def _spindown_prior(result: FitResult) -> tuple[np.ndarray, np.ndarray]:
    """(γ, Tf/J) of a spin-down result and their covariance (correlation kept)."""
    if "gamma" not in result or "Tf_over_J" not in result:
        raise OptionError("the spin-down result has no gamma and Tf_over_J")
    g, a = result["gamma"], result["Tf_over_J"]
    rho = 0.0
    if result.correlation is not None and {"gamma", "Tf_over_J"} <= set(result.correlation_names):
        names = result.correlation_names
        rho = float(result.correlation[names.index("gamma"), names.index("Tf_over_J")])
        rho = rho if math.isfinite(rho) else 0.0
    se = np.array([g.stderr, a.stderr])
    se = np.where(np.isfinite(se), se, 0.0)
    cov = np.array([[se[0] ** 2, rho * se[0] * se[1]], [rho * se[0] * se[1], se[1] ** 2]])
    return np.array([g.value, a.value]), cov
