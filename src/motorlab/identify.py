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
the angle responds only to kS = R·Tf/K, kV = K + R·b/K and kA = R·J/K (see :mod:`motorlab.feedforward`);
with R supplied, K and b still cannot be separated (only kV = K + R·b/K is seen), so J and Tf follow only
when K is supplied too. Parameters the data do not determine are reported as such.

References
----------
Seed 1, "Equations" (eqs. 1–4); L. Ljung, *System Identification: Theory for the User*, 2nd ed.,
ch. 7 (output-error / prediction-error methods).
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from threadpoolctl import threadpool_limits

from motorlab import _oe, held_input
from motorlab.analyses._common import reader_warnings
from motorlab.decimate import block_mean
from motorlab.errors import FitError, LogFormatError, OptionError
from motorlab.fitting import MAX_RELATIVE_STDERR
from motorlab.model import MotorParams, feedforward_from_params
from motorlab.recording import Recording
from motorlab.results import Estimate, FitResult, Panel, Series
from motorlab.units import SI_UNITS, format_unit

#: Parameters of the full model, in the order of the fit.
MOTOR_NAMES = ("K", "R", "L", "J", "b", "Tf")
#: Fewest samples a log must have to be fitted.
MIN_SAMPLES = 20


# --------------------------------------------------------------------------------------------------
# data checks shared with feedforward
# --------------------------------------------------------------------------------------------------


def check_recording(rec: Recording, *, need_current: bool = False) -> None:
    """Raise :class:`LogFormatError` for a log that cannot be fitted (naming file and line)."""
    src = rec.source or None
    for name in ("voltage", "position") + (("current",) if need_current else ()):
        rec.require(name)
    if len(rec) < MIN_SAMPLES:
        raise LogFormatError(f"{len(rec)} samples: at least {MIN_SAMPLES} are needed for a fit", path=src)
    for name in ("voltage", "position", "current"):
        if name in rec:
            bad = np.flatnonzero(~np.isfinite(rec.signals[name]))
            if bad.size:
                raise LogFormatError(f"{name} is not a finite number", path=src, line=rec.line_of(int(bad[0])))
    steps = np.diff(rec.time)
    bad = np.flatnonzero(~(steps > 0))
    if bad.size:
        raise LogFormatError("time does not increase", path=src, line=rec.line_of(int(bad[0]) + 1))


def position_resolution(rec: Recording, *, cpr: float | None = None) -> float:
    """Angle quantum [rad]: 2π/cpr, from a counts column, or the smallest step of the angle.

    Returns 0 when the angle does not look quantised.
    """
    if cpr is not None:
        return 2.0 * math.pi / cpr
    meta_cpr = rec.metadata.get("cpr")
    if meta_cpr:
        return 2.0 * math.pi / float(meta_cpr)
    pos = rec.signals["position"]
    if "counts" in rec:
        counts = rec.signals["counts"]
        nz = np.abs(counts) > 0
        if nz.any():
            return float(np.median(np.abs(pos[nz] / counts[nz])))
    steps = np.abs(np.diff(pos))
    steps = steps[steps > 1e-12 * max(float(np.max(np.abs(pos))), 1e-12)]
    if steps.size < 5:
        return 0.0
    q = float(np.min(steps))
    ratio = steps / q
    if np.mean(np.abs(ratio - np.round(ratio)) < 0.02) > 0.95:  # every step a whole number of quanta
        return q
    return 0.0


def _steps_are_multiples(position: np.ndarray, quantum: float) -> bool:
    """Whether (nearly) every step of the angle is a whole number of ``quantum``."""
    ratio = np.abs(np.diff(position)) / quantum
    return bool(ratio.size) and float(np.mean(np.abs(ratio - np.round(ratio)) < 0.02)) > 0.95


def data_warnings(rec: Recording, resolution: float) -> tuple[list[str], bool]:
    """Warnings about a log before fitting, and whether its angle counts against the voltage.

    Checks encoder overflow (a jump of ≥ 2¹⁵ counts, or of more than a quarter of the whole travel
    between two samples), a saturated current (many samples at the same extreme value) and the sign of
    motion against the sign of the voltage (an encoder counting backwards).
    """
    warnings: list[str] = []
    name = rec.source or "log"
    pos = rec.signals["position"]
    volt = rec.signals["voltage"]
    step = np.diff(pos)
    if resolution > 0:
        big = np.flatnonzero(np.abs(step) >= 2**15 * resolution)
        if big.size:
            warnings.append(
                f"{name}: the encoder jumps by {step[big[0]] / resolution:.0f} counts at sample {big[0] + 1}: "
                "counter overflow? (the fit will be wrong across it)"
            )
    if step.size > 10:
        typical = float(np.percentile(np.abs(step), 99)) + 1e-300
        jumps = np.flatnonzero(np.abs(step) > max(50.0 * typical, 0.25 * float(np.ptp(pos))))
        if jumps.size and not any("jumps" in w for w in warnings):
            warnings.append(f"{name}: the angle jumps at sample {jumps[0] + 1}: encoder overflow or glitch?")
    if "current" in rec:
        cur = rec.signals["current"]
        for extreme in (float(np.max(cur)), float(np.min(cur))):
            if extreme == 0:
                continue
            at = np.abs(cur - extreme) <= 1e-9 * abs(extreme)
            if at.sum() >= max(5, 0.02 * cur.size):
                warnings.append(
                    f"{name}: the current sits at {extreme:.4g} A for {int(at.sum())} samples: saturated sensor "
                    "or a current-limited supply (the model assumes neither)"
                )
    # direction: speed from angle differences against the voltage
    work = float(np.sum(volt[:-1] * step))
    reversed_ = work < 0 and abs(work) > 0.2 * float(np.sum(np.abs(volt[:-1] * step)))
    if reversed_:
        warnings.append(
            f"{name}: the angle decreases while the voltage is positive: the encoder counts against the "
            "motor's direction (A/B swapped or a reversed motor); the angle was negated for the fit"
        )
    return warnings, reversed_


def excitation_warnings(logs: list[_oe.Log], speed_sims: list[np.ndarray]) -> list[str]:
    """Warnings about excitation: speed range for kS vs kV, acceleration events for kA."""
    warnings = []
    speeds = np.concatenate([np.abs(s) for s in speed_sims])
    moving = speeds[speeds > 0.02 * (float(np.max(speeds)) + 1e-300)]
    if moving.size < 10 or float(np.percentile(moving, 90)) < 2.0 * float(np.percentile(moving, 10)):
        warnings.append(
            "too little excitation to separate kS from kV: the motor ran at nearly one speed; "
            "add a slow quasistatic ramp (or steps of several sizes)"
        )
    return warnings


def measured_speed(log: _oe.Log) -> np.ndarray:
    """Speed from angle differences over about ±5 ms (or ±2 samples), for plots only [rad/s]."""
    h = max(2, round(0.005 / log.dt))
    t, p = log.time, log.position
    idx = np.arange(t.size)
    hi = np.minimum(idx + h, t.size - 1)
    lo = np.maximum(idx - h, 0)
    return (p[hi] - p[lo]) / (t[hi] - t[lo])


def noise_levels(logs: list[_oe.Log], *, with_current: bool) -> dict[str, float]:
    """Weights of the signals: σ of the angle (quantisation q/√12 or the sample-to-sample noise) and current.

    Sample-to-sample noise is 1.4826·MAD(Δ²x)/√6, robust to steps in the signal.
    """

    def hf(x: np.ndarray) -> float:
        d2 = np.diff(x, 2)
        return float(1.4826 * np.median(np.abs(d2 - np.median(d2))) / math.sqrt(6.0))

    q = max(log.resolution for log in logs)
    pos_noise = max(hf(log.position) for log in logs)
    span = max(float(np.ptp(log.position)) for log in logs)
    sigma = {"position": max(q / math.sqrt(12.0), pos_noise, 1e-9 * span, 1e-12)}
    if with_current:
        cur = [log.current for log in logs if log.current is not None]
        span_i = max(float(np.ptp(c)) for c in cur)
        sigma["current"] = max(max(hf(c) for c in cur), 1e-4 * span_i, 1e-9)
    return sigma


def window_integrals(log: _oe.Log, width: int) -> dict[str, np.ndarray]:
    """Integrals and differences over windows of ``width`` samples (half-overlapping), for the start.

    ``int_v`` = ∫V dt (V held), ``int_i`` = ∫i dt (trapezoid), ``d_theta``, ``d_i``, ``d_omega`` (from
    angles smoothed over the window), ``int_sign`` = ∫sgn(ω̂) dt, ``int_one`` = window duration,
    ``int_cos``/``int_sin`` of the measured angle.
    """
    t, p = log.time, log.position
    n = t.size
    width = max(2, min(width, n // 3))
    starts = np.arange(0, n - width, max(1, width // 2))
    ends = starts + width
    dtk = np.diff(t)
    v = np.interp(t[:-1], log.dt * np.arange(log.n_grid), log.grid_voltage) if not log.uniform else log.grid_voltage
    cum_v = np.concatenate([[0.0], np.cumsum(v[: n - 1] * dtk)])
    h = max(1, width // 2)
    idx = np.arange(n)
    hi = np.minimum(idx + h, n - 1)
    lo = np.maximum(idx - h, 0)
    w_hat = (p[hi] - p[lo]) / (t[hi] - t[lo])
    dead = 2.0 * max(log.resolution, 1e-12) / (t[hi] - t[lo])
    s_hat = np.where(np.abs(w_hat) > dead, np.sign(w_hat), 0.0)
    cum_s = np.concatenate([[0.0], np.cumsum(0.5 * (s_hat[1:] + s_hat[:-1]) * dtk)])
    cum_c = np.concatenate([[0.0], np.cumsum(0.5 * (np.cos(p[1:]) + np.cos(p[:-1])) * dtk)])
    cum_sn = np.concatenate([[0.0], np.cumsum(0.5 * (np.sin(p[1:]) + np.sin(p[:-1])) * dtk)])
    out = {
        "int_v": cum_v[ends] - cum_v[starts],
        "d_theta": p[ends] - p[starts],
        "d_omega": w_hat[ends] - w_hat[starts],
        "int_sign": cum_s[ends] - cum_s[starts],
        "int_one": t[ends] - t[starts],
        "int_cos": cum_c[ends] - cum_c[starts],
        "int_sin": cum_sn[ends] - cum_sn[starts],
    }
    if log.current is not None:
        i = log.current
        cum_i = np.concatenate([[0.0], np.cumsum(0.5 * (i[1:] + i[:-1]) * dtk)])
        out["int_i"] = cum_i[ends] - cum_i[starts]
        out["d_i"] = i[ends] - i[starts]
    return out


def _stack(parts: list[dict[str, np.ndarray]], key: str) -> np.ndarray:
    return np.concatenate([p[key] for p in parts])


def regression_start(logs: list[_oe.Log]) -> np.ndarray:
    """(K, R, L, J, b, Tf) from the windowed-integral regressions of the module docstring.

    Raises
    ------
    FitError
        If the regressions give no positive K, R or J (no motion, no current, no voltage).
    """
    parts = [window_integrals(log, max(4, round(0.01 / log.dt))) for log in logs]
    y = _stack(parts, "int_v")
    a = np.column_stack([_stack(parts, "int_i"), _stack(parts, "d_i"), _stack(parts, "d_theta")])
    (r, ell, k), *_ = np.linalg.lstsq(a, y, rcond=None)
    if not (k > 0 and r > 0):  # L confounded with the rest: drop it
        (r, k), *_ = np.linalg.lstsq(a[:, [0, 2]], y, rcond=None)
        ell = 0.0
    if not (k > 0 and r > 0):
        raise FitError("cannot find a starting point: the voltage is not explained by R·i + K·ω")
    y2 = _stack(parts, "d_omega")
    a2 = np.column_stack([_stack(parts, "int_i"), -_stack(parts, "d_theta"), -_stack(parts, "int_sign")])
    (c1, c2, c3), *_ = np.linalg.lstsq(a2, y2, rcond=None)
    if not c1 > 0:
        raise FitError("cannot find a starting point: the angle does not respond to the current")
    j = k / c1
    dt = min(log.dt for log in logs)
    return np.array([k, r, max(ell, r * dt), j, max(c2 * j, 1e-3 * k * k / r), max(c3 * j, 0.0)])


class MotorModel(_oe.OEModel):
    """The full model with current measured: state (i, ω), parameters (K, R, L, J, b, Tf)."""

    names = MOTOR_NAMES
    uses_current = True

    def plant(self, p: np.ndarray) -> _oe.Plant:
        return _oe.motor_plant(*(float(v) for v in p))

    def initial(self, p: np.ndarray, log: _oe.Log, speed: float) -> np.ndarray:
        assert log.current is not None
        return np.array([float(log.current[0]), speed])


def _prepare(
    recordings: Sequence[Recording], *, cpr: float | None, with_current: bool
) -> tuple[list[_oe.Log], list[str]]:
    logs = []
    warnings = reader_warnings(recordings)  # what the readers repaired or dropped comes first
    for rec in recordings:
        check_recording(rec, need_current=with_current)
    quanta = [position_resolution(rec, cpr=cpr) for rec in recordings]
    common = min((q for q in quanta if q > 0), default=0.0)
    for rec, q in zip(recordings, quanta, strict=True):
        if q == 0.0 and common > 0 and _steps_are_multiples(rec.signals["position"], common):
            # a fast run may never move by a single count: take the quantum of the other runs
            q = common
        warns, reversed_ = data_warnings(rec, q)
        warnings.extend(warns)
        pos = -rec.signals["position"] if reversed_ else rec.signals["position"]
        current = rec.signals["current"] if with_current else None
        logs.append(_oe.prepare_log(rec.time, rec.signals["voltage"], pos, current, resolution=q, source=rec.source))
    return logs, warnings


def _estimate(name: str, value: float, stderr: float, *, determined: bool = True, note: str = "") -> Estimate:
    return Estimate(name, float(value), float(stderr), SI_UNITS[name], determined, note)


def fit_panels(logs: list[_oe.Log], fit: _oe.Fit, *, title: str, length: str = "rad") -> list[Panel]:
    """Measured against simulated angle (or distance, ``length="m"``), speed and current, runs end to end."""
    panels = []
    if length == "m":
        signals = [("position", "position", "x [m]"), ("speed", "speed", "v [m/s]")]
    else:
        signals = [("position", "angle", "θ [rad]"), ("speed", "speed", "ω [rad/s]")]
    if any(log.current is not None for log in logs) and "current" in fit.simulations[0]:
        signals.append(("current", "current", "i [A]"))
    for key, label, y_label in signals:
        xs, data, model = [], [], []
        t_offset = 0.0
        for log, sim in zip(logs, fit.simulations, strict=True):
            xs.append(log.time + t_offset)
            if key == "speed":
                data.append(measured_speed(log))
            elif key == "current" and log.current is not None:
                data.append(log.current)
            else:
                data.append(log.position)
            model.append(sim[key])
            t_offset += float(log.time[-1]) + log.dt
        x = np.concatenate(xs)
        panels.append(
            Panel(
                title=f"{title}: measured and simulated {label}",
                x_label="time (runs end to end) [s]",
                y_label=y_label,
                data=Series(x, np.concatenate(data), "measured" if key != "speed" else "measured (differenced)"),
                model=Series(x, np.concatenate(model), "simulated", kind="model"),
            )
        )
    return panels


@threadpool_limits.wrap(limits=1, user_api="blas")  # tall-skinny products: threads only contend (15× on a busy box)
def identify(
    recordings: Recording | Sequence[Recording],
    *,
    resistance: float | None = None,
    torque_constant: float | None = None,
    cpr: float | None = None,
    use_current: bool = True,
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
    Input model (:mod:`motorlab.held_input`, ``details["input_model"]``): a drive that holds levels
    is fitted with each level estimated from all its samples jointly with the model and each switch
    instant located inside its sample interval (nuisance parameters); switches found on the sample
    instants are fixed there. ``details["cramer_rao_bound"]``: the Cramér–Rao bound of this log
    with those nuisance parameters, and each standard error over it (also in each estimate's note).

    Otherwise the logged voltage's noise reaches the simulated current (errors in the input variable): the
    current is weighted by its measured noise plus that, and the first-order bias it causes (mostly
    in L and R) is removed (:func:`motorlab._oe.input_noise_bias`). Standard errors propagate the
    measured noises — voltage through the plant, current, and counting errors correlated as a
    quantiser of unknown phase makes them — through the linearised fit
    (:func:`motorlab._oe.noise_propagation_covariance`); the Newey–West covariance of the residuals
    is used when these noises do not explain the residuals.
    """
    recordings = [block_mean(r) for r in ([recordings] if isinstance(recordings, Recording) else recordings)]
    recs = [recordings] if isinstance(recordings, Recording) else list(recordings)
    if not recs:
        raise OptionError("no recordings to identify")
    for name, value in (("resistance", resistance), ("torque constant", torque_constant), ("cpr", cpr)):
        if value is not None and not (math.isfinite(value) and value > 0):
            raise OptionError(f"{name} must be a positive number, got {value}")
    with_current = use_current and all("current" in r for r in recs)
    if not with_current:
        return _identify_without_current(recs, resistance=resistance, torque_constant=torque_constant, cpr=cpr,
                                         note_missing=use_current and any("current" in r for r in recs))
    logs, warnings = _prepare(recs, cpr=cpr, with_current=True)
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
    sigma = noise_levels(logs, with_current=True)
    current_noise = sigma["current"]
    # The simulated current carries the logged voltage's noise filtered by the winding (errors in the
    # input variable): weight the current by the noise its residual really has, measurement and input.
    gain = float(_oe.input_noise_gain(MotorModel().plant(np.clip(p0, lower, upper)), dt)[0, 0])
    voltage_noise = max(_oe.voltage_noise(log) for log in logs)
    sigma["current"] = math.sqrt(current_noise**2 + voltage_noise**2 * gain)

    def sample_held(start: np.ndarray) -> _oe.Fit:
        return _oe.fit_output_error(MotorModel(), logs, np.clip(start, lower, upper), lower=lower, upper=upper,
                                    scale=scale, sigma=sigma, current_noise=current_noise)

    fit, input_details = _input_model(recs, logs, sample_held, np.clip(p0, lower, upper), lower=lower, upper=upper,
                                      scale=scale, sigma_position=sigma["position"], current_noise=current_noise)
    if input_details["model"] != "sample-held":
        sigma["current"] = current_noise
    values = fit.values[:6]
    cov = fit.covariance[:6, :6]
    stderr = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    params: dict[str, Estimate] = {}
    for k, name in enumerate(MOTOR_NAMES):
        determined = not fit.null[k] and stderr[k] <= MAX_RELATIVE_STDERR * abs(values[k])
        note = ""
        if name == "L" and (values[k] <= 1.01 * lower[2] or values[k] < 3.0 * stderr[k]):
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
        params[name] = _estimate(name, values[k], stderr[k], determined=determined, note=note)
    if not fit.success:
        warnings.append(f"the optimiser stopped early: {fit.message}")
    warnings.extend(_oe.noise_warning(fit, rms_text=f"{fit.residual_rms['position']:.3g} rad"))
    warnings.extend(excitation_warnings(logs, [s["speed"] for s in fit.simulations]))
    for symbol, given, index in (("R", resistance, 1), ("K", torque_constant, 0)):
        if given is not None:  # the current log determines it: say so, and how far the given value is
            warnings.append(
                f"the given {symbol} = {given:.4g} {format_unit(SI_UNITS[symbol])} was not used: with a current "
                f"column {symbol} is fitted ({values[index]:.4g}, {100 * (values[index] / given - 1):+.1f} % "
                "from the given value); "
                "--no-current fits without the current and uses it"
            )
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(stderr, stderr)
    np.fill_diagonal(corr, 1.0)
    motor = MotorParams(*(float(v) for v in np.maximum(values, [1e-12, 1e-12, 0, 1e-12, 0, 0])))
    details: dict[str, Any] = {
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
        "input_model": input_details,
    }
    _bound_details(fit, logs, params, details, weight_current=sigma["current"], current_noise=current_noise)
    return _result("identify", params, corr, list(MOTOR_NAMES), logs, fit, warnings, details)


def _input_model(
    recs: list[Recording], logs: list[_oe.Log], sample_held: Callable[[np.ndarray], _oe.Fit], p0: np.ndarray, *,
    lower: np.ndarray, upper: np.ndarray, scale: np.ndarray, sigma_position: float, current_noise: float,
) -> tuple[_oe.Fit, dict[str, Any]]:
    """Refit with held levels and switch instants as nuisance parameters when the drive holds levels.

    The voltage of every run is tested for held levels (:func:`motorlab.held_input.detect_held`);
    then the model is fitted with each switch instant free inside its sample interval. When every
    located switch sits on its sample instant (within 3σ) the switch instants are fixed there: with
    exact levels that is the sample-held fit (``sample_held(start)``, also used when the drive does not
    hold levels); with noisy levels the levels stay free.
    Returns the fit to report and ``details["input_model"]``.
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
    model = held_input.HeldMotorModel(logs, helds, free_switch=True)
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
        fixed = held_input.HeldMotorModel(logs, helds, free_switch=False)
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
            params[name] = _estimate(name, est.value, est.stderr, note=text)


def _result(
    experiment: str,
    params: dict[str, Estimate],
    corr: np.ndarray,
    names: list[str],
    logs: list[_oe.Log],
    fit: _oe.Fit,
    warnings: list[str],
    details: dict[str, Any],
    *,
    length: str = "rad",
) -> FitResult:
    """The FitResult of an output-error fit; ``length`` is the unit of the logged position ("rad" or "m")."""
    pos = np.concatenate([log.position for log in logs])
    sim = np.concatenate([s["position"] for s in fit.simulations])
    sst = float(np.sum((pos - pos.mean()) ** 2))
    r2 = 1.0 - float(np.sum((pos - sim) ** 2)) / sst if sst > 0 else math.nan
    speed_rms = float(np.sqrt(np.mean(np.concatenate(
        [(measured_speed(log) - s["speed"]) ** 2 for log, s in zip(logs, fit.simulations, strict=True)]))))
    details["residual_rms"]["speed (differenced)"] = speed_rms
    details["residual_rms_units"]["speed (differenced)"] = f"{length}/s"
    return FitResult(
        experiment=experiment,
        parameters=params,
        correlation=corr,
        correlation_names=names,
        rmse=fit.residual_rms["position"],
        rmse_unit=length,
        r2=r2,
        n_points=int(sum(log.time.size for log in logs)),
        panels=fit_panels(logs, fit, title=experiment, length=length),
        warnings=warnings,
        details=details,
        sources=list(dict.fromkeys(log.source for log in logs if log.source)),
    )


def _identify_without_current(
    recs: list[Recording],
    *,
    resistance: float | None,
    torque_constant: float | None,
    cpr: float | None,
    note_missing: bool,
) -> FitResult:
    from motorlab import feedforward

    result = feedforward.feedforward(recs, cpr=cpr)
    result.experiment = "identify"
    if note_missing:
        result.warnings.append("not every run has a current column: the current was not used")
    result.parameters.update(
        feedforward.motor_estimates(result, resistance=resistance, torque_constant=torque_constant)
    )
    result.check_physics()
    return result


# --------------------------------------------------------------------------------------------------
# motorlab analyze identify
# --------------------------------------------------------------------------------------------------


def add_arguments(parser: argparse.ArgumentParser, experiment: str) -> None:
    """Options of ``motorlab analyze identify``."""
    from motorlab.cli.common import quantity

    parser.add_argument("--cpr", type=quantity("count", positive=True),
                        help="encoder counts per revolution at the shaft (537.7 too)")
    parser.add_argument("--R", dest="resistance", type=quantity("ohm", positive=True),
                        help="winding resistance, if known (needed without current) [Ω]")
    parser.add_argument("--K", dest="torque_constant", type=quantity("V*s/rad", positive=True),
                        help="torque constant, if known (separates K from b without current) [V·s/rad]")
    parser.add_argument("--no-current", dest="use_current", action="store_false",
                        help="ignore a current column (fit voltage and angle only)")


def read_runs(paths: list[str], *, cpr: float | None) -> list[Recording]:
    """Read every file with :func:`motorlab.io.read_any`, one recording per test segment.

    ``cpr`` goes to the readers that convert counts (FTC log, CSV); formats that log angles (SysId
    JSON in rotations, .wpilog) do not take it, and the fit uses it for the angle quantum instead.
    """
    import inspect

    from motorlab import io as mio

    runs: list[Recording] = []
    for path in paths:
        takes_cpr = "cpr" in inspect.signature(mio.READERS[mio.detect_format(path)]).parameters
        rec = mio.read_any(path, cpr=cpr if takes_cpr else None)
        runs.extend(rec.split())
    return runs


def from_cli(experiment: str, paths: list[str], args: argparse.Namespace) -> FitResult:
    """Run ``motorlab analyze identify FILE...``."""
    from motorlab.analyses._common import check_cpr

    cpr = getattr(args, "cpr", None)
    check_cpr(cpr)  # any positive number of counts (537.7), within physical bounds
    runs = read_runs(paths, cpr=cpr)
    json_runs = [r for r in runs if r.metadata.get("format") in ("sysid-json", "frc-char-json")]
    if json_runs and cpr is not None:  # a JSON file logs its own units: cpr counts per logged rotation
        from motorlab.feedforward import apply_cpr

        apply_cpr(json_runs, cpr)
        cpr = None  # the readers of counts logs keep theirs in metadata["cpr"]
    return identify(runs, resistance=getattr(args, "resistance", None),
                    torque_constant=getattr(args, "torque_constant", None), cpr=cpr,
                    use_current=getattr(args, "use_current", True))
