"""The runs of the output-error fits (:mod:`motorlab.analyses.identify`, :mod:`motorlab.analyses.feedforward`).

Reading logs into runs, the checks and warnings about them, their noise levels, the window integrals
of the regression start, the panels and the :class:`~motorlab.results.FitResult` of a fit. Both fits
use these; neither imports the other for them.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np

from motorlab.errors import FitError, LogFormatError
from motorlab.estimation import output_error as _oe
from motorlab.estimation.simulator import motor_plant
from motorlab.model import PARAMETER_NAMES
from motorlab.recording import Recording
from motorlab.results import Estimate, FitResult, Panel, Series
from motorlab.units import SI_UNITS

MOTOR_NAMES = PARAMETER_NAMES  # ("K", "R", "L", "J", "b", "Tf")
#: Fewest samples a log must have to be fitted.
MIN_SAMPLES = 20


def reader_warnings(recordings: Recording | Iterable[Recording]) -> list[str]:
    """The readers' warnings (``Recording.metadata["warnings"]``) of every recording, in order, once each.

    Readers note what they repaired or dropped (a truncated last line, placeholder rows, a test of
    a SysId file that is empty) with the file and line; every analysis passes these on first in
    its :class:`~motorlab.results.FitResult` warnings, so that nothing dropped goes unsaid.
    """
    recs = [recordings] if isinstance(recordings, Recording) else list(recordings)
    out: list[str] = []
    for rec in recs:
        for text in rec.metadata.get("warnings", []) or []:
            if str(text) not in out:
                out.append(str(text))
    return out



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

    def plant(self, p: np.ndarray) -> _oe.StatePlant:
        return motor_plant(*(float(v) for v in p))

    def initial(self, p: np.ndarray, log: _oe.Log, speed: float) -> np.ndarray:
        assert log.current is not None
        return np.array([float(log.current[0]), speed])


def prepare_runs(
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


def estimate(name: str, value: float, stderr: float, *, determined: bool = True, note: str = "") -> Estimate:
    return Estimate(name, float(value), float(stderr), SI_UNITS[name], determined, note)


def _one_time_axis(spans: list[tuple[float, float]]) -> bool:
    """Whether runs spanning these (first, last) times follow one another on one time axis (pieces of one log)."""
    return all(b[0] > a[1] for a, b in itertools.pairwise(spans))


def fit_panels(logs: list[_oe.Log], fit: _oe.Fit, *, title: str, length: str = "rad") -> list[Panel]:
    """Measured against simulated angle (or distance, ``length="m"``), speed and current.

    Against the log's own time when the runs follow one another on it (one log, or the pieces of one log
    cut by a span left out); else runs end to end.
    """
    panels = []
    if length == "m":
        signals = [("position", "position", "x [m]"), ("speed", "speed", "v [m/s]")]
    else:
        signals = [("position", "angle", "θ [rad]"), ("speed", "speed", "ω [rad/s]")]
    if any(log.current is not None for log in logs) and "current" in fit.simulations[0]:
        signals.append(("current", "current", "i [A]"))
    for key, label, y_label in signals:
        xs, data, model, times = [], [], [], []
        t_offset = 0.0
        for log, sim in zip(logs, fit.simulations, strict=True):
            xs.append(log.time + t_offset)
            times.append(log.time + log.start)
            if key == "speed":
                data.append(measured_speed(log))
            elif key == "current" and log.current is not None:
                data.append(log.current)
            else:
                data.append(log.position)
            model.append(sim[key])
            t_offset += float(log.time[-1]) + log.dt
        in_order = _one_time_axis([(log.start, log.start + float(log.time[-1])) for log in logs])
        x = np.concatenate(times if in_order else xs)
        panels.append(
            Panel(
                title=f"{title}: measured and simulated {label}",
                x_label="time in the log [s]" if in_order else "time (runs end to end) [s]",
                y_label=y_label,
                data=Series(x, np.concatenate(data), "measured" if key != "speed" else "measured (differenced)"),
                model=Series(x, np.concatenate(model), "simulated", kind="model"),
                time=np.concatenate(times),
            )
        )
    return panels


def fit_result(
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


def noise_warning(fit: _oe.Fit, *, rms_text: str) -> list[str]:
    """The warning to give when the uncertainties had to come from the residuals or could not be given
    (empty otherwise)."""
    if fit.not_minimum:
        return [f"no standard errors: {fit.not_minimum}; the values are the lowest cost found from "
                f"{_oe.RESTARTS + 1} starts, not a verified minimum"]
    if not fit.noise_model.startswith("Newey"):
        return []
    return [
        f"the measured noise does not explain the residuals (residual RMS {rms_text}; {fit.noise_model}): "
        "uncertainties come from the residuals"
    ]
