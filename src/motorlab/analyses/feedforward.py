"""SysId-style feedforward gains by simulation: ``V = kS·sgn(ω) + kV·ω + kA·α`` (+ gravity).

WPILib SysId's tests — quasistatic voltage ramps and dynamic voltage steps, forward and backward — are
fitted here by output error: the angle is simulated from the logged voltage with

    kA·dω/dt = V − kS·sgn(ω) − kV·ω − g,     dθ/dt = ω,
    g = 0 (simple), kG (elevator), kG·cos(θ + φ) (arm),

including stiction (at rest while |V − g| ≤ kS), and compared with the encoder angle as counted. No
speed or acceleration is differentiated out of a coarse encoder, which is where SysId's ordinary least
squares loses accuracy (finite differences of a 560-count encoder logged every 10 ms are mostly
quantisation noise, and the noise sits in a regressor, which biases kA and kV towards zero).
For the arm the gravity term uses the measured angle (kG·cos(θ+φ) = a·cos θ − c·sin θ, linear in
a = kG·cos φ and c = kG·sin φ), which keeps the simulated plant linear between friction events.

The model is the DC motor with L neglected: kS = R·Tf/K [V], kV = K + R·b/K [V·s/rad], kA = R·J/K
[V·s²/rad] (:func:`motorlab.model.feedforward_from_params`). The angle alone therefore determines only
(kS, kV, kA); K, J, b, Tf need R and K from elsewhere (:func:`motor_estimates`).

References
----------
WPILib SysId documentation, "Introduction to System Identification" and "Analyzing Data"
(docs.wpilib.org); seed 1, "Equations".
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from motorlab.errors import FitError, OptionError
from motorlab.estimation import output_error as _oe
from motorlab.estimation.covariance import MAX_RELATIVE_STDERR
from motorlab.estimation.decimate import block_mean
from motorlab.estimation.runs import (
    excitation_warnings,
    fit_result,
    measured_speed,
    noise_levels,
    noise_warning,
    prepare_runs,
    read_runs,
    window_integrals,
)
from motorlab.estimation.simulator import feedforward_plant
from motorlab.model import MotorParams, params_from_feedforward
from motorlab.recording import Recording
from motorlab.results import Estimate, FitResult
from motorlab.units import SI_UNITS

MECHANISMS = ("simple", "elevator", "arm")


def params_from_gains(
    kS: float,
    kV: float,
    kA: float,
    *,
    resistance: float,
    torque_constant: float | None = None,
    inductance: float = 0.0,
) -> MotorParams:
    """Motor parameters from feedforward gains and the winding resistance.

    Parameters
    ----------
    kS, kV, kA
        Feedforward gains [V], [V·s/rad], [V·s²/rad].
    resistance
        R [Ω].
    torque_constant
        K [V·s/rad]; without it b is taken as 0 and K = kV (an upper bound on K).
    inductance
        L [H], carried through.

    Notes
    -----
    Tf = kS·K/R, b = (kV − K)·K/R, J = kA·K/R (inverse of :func:`motorlab.model.feedforward_from_params`).
    """
    if not resistance > 0:
        raise OptionError(f"resistance must be positive, got {resistance}")
    return params_from_feedforward(kS, kV, kA, R=resistance, K=torque_constant, L=inductance)


class FeedforwardModel(_oe.OEModel):
    """kA·ω' = V − kS·sgn(ω) − kV·ω − g; parameters (kS, kV, kA[, kG | a, c])."""

    uses_current = False

    def __init__(self, mechanism: str, *, lag: float = 0.0):
        self.mechanism = mechanism
        extra = {"simple": (), "elevator": ("kG",), "arm": ("kG_cos", "kG_sin")}[mechanism]
        self.names = ("kS", "kV", "kA", *extra)
        self.lag = lag

    def plant(self, p: np.ndarray) -> _oe.StatePlant:
        return feedforward_plant(float(p[0]), float(p[1]), float(p[2]))

    def drive(self, p: np.ndarray, log: _oe.Log) -> np.ndarray:
        if self.mechanism == "elevator":
            return log.grid_voltage - p[3]
        if self.mechanism == "arm":
            return log.grid_voltage - p[3] * np.cos(log.grid_angle) + p[4] * np.sin(log.grid_angle)
        return log.grid_voltage

    def initial(self, p: np.ndarray, log: _oe.Log, speed: float) -> np.ndarray:
        return np.array([speed])


#: Window lengths tried for the starting regression [s]: a short window sees a fast mechanism's
#: acceleration, a long one a flywheel's (τm = kA/kV of seconds, where the speed change over 20 ms
#: drowns in counting noise and the short-window regression puts kA near zero).
START_WINDOWS = (0.02, 0.1, 0.5, 2.0)


def regression_start(logs: list[_oe.Log], mechanism: str, *, lag: float = 0.0) -> np.ndarray:
    """(kS, kV, kA[, ...]) from ∫V dt = kS·∫sgn(ω̂) dt + kV·Δθ + kA·Δω̂ (+ gravity) over windows.

    The regression is run with each window length of :data:`START_WINDOWS` and the start whose
    simulated angle (offsets removed, residuals weighted as the fit weights them) is closest to the
    measured one is kept. ``lag`` [s]: see :attr:`motorlab.estimation.output_error.OEModel.lag`.

    Raises
    ------
    FitError
        When no regression gives positive kV and kA (no motion, or motion against the voltage).
    """
    model = FeedforwardModel(mechanism, lag=lag)
    best: tuple[float, np.ndarray] | None = None
    error: FitError | None = None
    for window in START_WINDOWS:
        try:
            beta = _window_regression(logs, mechanism, window)
        except FitError as exc:
            error = exc
            continue
        cost = 0.0
        for log in logs:
            speed = _oe.initial_speed_guess(log) if log.moving_at_start else 0.0
            sim = _oe._simulate_log(model, beta, log, speed, 0.0)
            weight = log.position_factor(max(log.resolution, 1e-9) / math.sqrt(12.0)) ** 2
            with np.errstate(over="ignore", invalid="ignore"):  # a start that runs away costs inf: not kept
                miss = sim["position"] - log.position
                cost += float(np.sum(weight * (miss - np.average(miss, weights=weight)) ** 2))
        if math.isfinite(cost) and (best is None or cost < best[0]):
            best = (cost, beta)
    if best is None:
        raise error or FitError("cannot find a starting point: the model simulated from every regression start "
                                "runs beyond any finite angle (check the log's time, voltage and position columns)")
    return best[1]


def _window_regression(logs: list[_oe.Log], mechanism: str, window: float) -> np.ndarray:
    parts = [window_integrals(log, max(4, round(window / log.dt))) for log in logs]

    def stack(key: str) -> np.ndarray:
        return np.concatenate([p[key] for p in parts])

    cols = [stack("int_sign"), stack("d_theta"), stack("d_omega")]
    if mechanism == "elevator":
        cols.append(stack("int_one"))
    elif mechanism == "arm":
        cols += [stack("int_cos"), -stack("int_sin")]
    design = np.column_stack(cols)
    y = stack("int_v")
    beta, *_ = np.linalg.lstsq(design, y, rcond=None)
    # Poor excitation makes columns collinear: drop kS (steps at one voltage), then kA (ramps only)
    # and start from kS = 0 or a 50 ms mechanical time constant; the output-error fit takes over.
    for dropped in ((0,), (2,), (0, 2)):
        if beta[1] > 0 and beta[2] > 0:
            break
        keep = [k for k in range(design.shape[1]) if k not in dropped]
        sub, *_ = np.linalg.lstsq(design[:, keep], y, rcond=None)
        beta = np.zeros(design.shape[1])
        beta[keep] = sub
        if 2 in dropped:
            beta[2] = 0.05 * beta[1]
    if not (beta[1] > 0 and beta[2] > 0):
        raise FitError("cannot find a starting point: the motion does not follow the voltage (kV or kA ≤ 0)")
    beta[0] = max(beta[0], 0.0)
    return beta


def sysid_ols(recordings: Sequence[Recording], *, mechanism: str = "simple") -> dict[str, float]:
    """WPILib SysId's ordinary least squares (the published method), as a baseline.

    Acceleration from finite differences of the speed is regressed on [ω, V, sgn ω] (and 1 for an
    elevator, cos θ for an arm): α = c₁·ω + c₂·V + c₃·sgn ω (+ c₄), giving kA = 1/c₂, kV = −c₁/c₂,
    kS = −c₃/c₂, kG = −c₄/c₂. The speed is the logged one when the file has it, otherwise the
    difference of successive angles; samples at rest (ω = 0) are dropped, as SysId does.

    Returns
    -------
    dict
        ``kS`` [V], ``kV`` [V·s/rad], ``kA`` [V·s²/rad] (and ``kG`` [V]).
    """
    rows = []
    for rec in recordings:
        t = rec.time
        dt = np.diff(t)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):  # repeated times: rows dropped below
            if "velocity" in rec:
                w = rec.signals["velocity"]
            else:
                w = np.concatenate([[0.0], np.diff(rec.signals["position"]) / dt])
            acc = np.diff(w) / dt
        v = rec.signals["voltage"][:-1]
        ws = w[:-1]
        keep = (ws != 0) & np.isfinite(ws) & np.isfinite(acc) & (dt > 0)
        cols = [ws, v, np.sign(ws)]
        if mechanism == "elevator":
            cols.append(np.ones_like(ws))
        elif mechanism == "arm":
            cols.append(np.cos(rec.signals["position"][:-1]))
        rows.append((np.column_stack(cols)[keep], acc[keep]))
    a = np.concatenate([r[0] for r in rows])
    y = np.concatenate([r[1] for r in rows])
    if y.size < a.shape[1] or not np.all(np.isfinite(a)):
        raise FitError("too few moving samples for the SysId regression")
    c, *_ = np.linalg.lstsq(a, y, rcond=None)
    if c[1] == 0 or not np.all(np.isfinite(c)):
        raise FitError("the SysId regression does not determine kA (the voltage explains no acceleration)")
    out = {"kS": -c[2] / c[1], "kV": -c[0] / c[1], "kA": 1.0 / c[1]}
    if mechanism != "simple":
        out["kG"] = -c[3] / c[1]
    return {k: float(v) for k, v in out.items()}


def feedforward(
    recordings: Recording | Sequence[Recording],
    *,
    mechanism: str = "simple",
    cpr: float | None = None,
) -> FitResult:
    """Fit kS, kV, kA (and kG) to SysId-style tests by output error.

    Parameters
    ----------
    recordings
        The tests (one recording per test: ``Recording.split()`` of a SysId file), each with
        ``voltage`` [V] and ``position`` [rad] (or [m] for a drivetrain; the gains then come per metre).
    mechanism
        ``"simple"`` (flywheel, shooter), ``"elevator"`` (constant gravity kG [V]) or ``"arm"``
        (kG·cos(θ + φ), θ the angle as counted, φ [rad] from the encoder's zero to horizontal, fitted;
        the position must then be the arm's angle, not a distance).
    cpr
        Encoder counts per revolution [count/rev] (angle quantum 2π/cpr).

    Returns
    -------
    FitResult
        ``kS`` [V], ``kV`` [V·s/rad], ``kA`` [V·s²/rad] (``kG`` [V], ``offset`` [rad]); per metre
        ([V·s/m], [V·s²/m]) when every run logs a distance; panels of measured against simulated
        angle and speed; the SysId OLS estimates in ``details["sysid_ols"]``.

    Raises
    ------
    LogFormatError
        A test lacks voltage or angle, is too short, or holds non-finite values.
    OptionError
        An unknown mechanism, a non-positive cpr, or an arm whose position is a distance.
    FitError
        The motion does not follow the voltage.

    Notes
    -----
    Standard errors: the measured noises (logged voltage, counting, stale status frames) propagated
    through the linearised fit (:func:`motorlab.estimation.noise.noise_propagation_covariance`); the Newey–West
    covariance of the residuals when these do not explain the residuals (docs/feedforward.md).
    For the arm, gravity over each step acts at the measured angle at the step's middle
    (:func:`motorlab.estimation.output_error.grid_angle`), and φ's variance includes q²/12 for the encoder's quantiser
    phase (q = 2π/cpr), which no fit can resolve.
    """
    recs = _checked_recordings(recordings, mechanism=mechanism, cpr=cpr)
    logs, warnings = prepare_runs(recs, cpr=cpr, with_current=False)
    period = _stale_frames(logs, mechanism)
    try:
        p0 = regression_start(logs, mechanism, lag=0.5 * period)
    except FitError as exc:  # name the file(s): the user must know which log cannot be explained
        raise FitError(f"{', '.join(dict.fromkeys(log.source for log in logs if log.source))}: {exc}") from None
    lower, upper, scale = _bounds(p0, logs)
    model = FeedforwardModel(mechanism, lag=0.5 * period)
    sigma = noise_levels(logs, with_current=False)
    fit = _oe.fit_output_error(model, logs, np.clip(p0, lower, upper), lower=lower, upper=upper, scale=scale,
                               sigma=sigma)
    linear = all(rec.metadata.get("position_unit") == "m" for rec in recs)
    names, values, params, corr = _gain_estimates(fit, model, logs, linear=linear)
    if not fit.success:
        warnings.append(f"the optimiser stopped early: {fit.message}")
    warnings.extend(_noise_warning(recs, logs, fit, length="m" if linear else "rad"))
    warnings.extend(_gain_warnings(logs, fit, values, corr))
    details: dict[str, Any] = {
        "method": "output error (angle simulated from the voltage)",
        "uncertainty": fit.noise_model,
        "mechanism": mechanism,
        "residual_rms": {**fit.residual_rms},
        "residual_rms_units": {"position": "m" if linear else "rad"},
        "noise_weights": sigma,
        "start": dict(zip(model.names, p0.tolist(), strict=True)),
        "hac_bandwidth_samples": fit.bandwidth,
        "function_evaluations": fit.nfev,
    }
    if period > 0:
        details["status_frames"] = {"period_s": period, "lag_s": 0.5 * period}
    own = file_units(recs)
    if own is not None:
        details["file_units"] = own
    try:
        details["sysid_ols"] = sysid_ols(recs, mechanism=mechanism)
    except (FitError, np.linalg.LinAlgError, ZeroDivisionError):
        details["sysid_ols"] = None
    result = fit_result("feedforward", params, corr, names, logs, fit, warnings, details,
                        length="m" if linear else "rad")
    if mechanism == "simple" and fit.noise_model.startswith("Newey") and all("velocity" in rec for rec in recs):
        _report_open_loop(result, recs, length=result.rmse_unit)  # real logs: docs/real-logs.md
    return result


def file_units(recs: Sequence[Recording]) -> dict[str, Any] | None:
    """The length unit the files were logged in (a SysId file's ``units``, ``unitsPerRotation``), or None.

    The fit runs in SI (rad, or m for a file in Meters, Feet or Inches); the gains of a team's code are in
    the file's own unit (kV per foot for a file in Feet), which ``tune`` reads from here
    (:func:`motorlab.control.plant.load_plant`). None when the files carry no units or differ.
    """
    from motorlab.io.frc_json import GAIN_UNITS

    own = [(rec.metadata.get("units"), rec.metadata.get("unitsPerRotation")) for rec in recs]
    units, per = own[0]
    if any(o != own[0] for o in own) or not isinstance(units, str) or units.lower() not in GAIN_UNITS:
        return None
    return {"units": units, "unitsPerRotation": per, "length_unit": GAIN_UNITS[units.lower()]}


def _checked_recordings(recordings: Recording | Sequence[Recording], *, mechanism: str,
                        cpr: float | None) -> list[Recording]:
    """The tests (block-averaged, :func:`motorlab.estimation.decimate.block_mean`) after checking the options.

    Raises
    ------
    OptionError
        An unknown mechanism, a non-positive cpr, no recordings, or an arm whose position is a distance.
    """
    recordings = [block_mean(r) for r in ([recordings] if isinstance(recordings, Recording) else recordings)]
    if mechanism not in MECHANISMS:
        raise OptionError(f"mechanism must be one of {', '.join(MECHANISMS)}, got {mechanism!r}")
    if cpr is not None:
        from motorlab.analyses.common import check_cpr

        check_cpr(cpr)  # within what an encoder can have, as every reader and analysis checks
    recs = [recordings] if isinstance(recordings, Recording) else list(recordings)
    if not recs:
        raise OptionError("no recordings to fit")
    if mechanism == "arm":
        for rec in recs:  # kG·cos(θ + φ) needs the arm's angle, not a distance
            if rec.metadata.get("position_unit") == "m":
                raise OptionError(
                    f"{rec.source or 'recording'}: mechanism 'arm' needs the arm's angle, but the position is "
                    "logged as a distance (m); log the arm angle (rotations, radians or degrees)"
                )
    return recs


def _stale_frames(logs: list[_oe.Log], mechanism: str) -> float:
    """Refresh period of stale status frames [s] (0 without), with their effect set on the logs in place.

    Stale status frames (SysId logs of CAN motor controllers): the logged angle is θ(t − d) with d
    spread over one refresh period P, a lag of P/2 on average; the first row showing a new reading
    places its frame within one row period dt, a scatter of (ω·dt)²/12 per reading about the lag
    (``Log.stale_variance``; the frames' phase, shared by a whole run, is in the propagated
    covariance). For an arm, gravity acts at the shaft's angle, which the readings show P/2 late
    (``Log.grid_angle``).
    """
    # The lag is not fitted: it trades off against kA (a first-order lag and a delay look alike at
    # 10 ms sampling) and would take kA's information with it.
    # The median of the tests that show stale frames: one misread test must not set every test's lag.
    periods = [p for p in (_oe.stale_frame_period(log) for log in logs) if p > 0]
    period = float(np.median(periods)) if periods else 0.0
    if period > 0:
        for log in logs:
            log.stale_variance = (measured_speed(log) * log.dt) ** 2 / 12.0
            if mechanism == "arm":  # gravity acts at the shaft's angle, which the readings show P/2 late
                log.grid_angle = _oe.grid_angle(log.time, log.position, log.dt, log.n_grid, lag=0.5 * period)
    return period


def _bounds(p0: np.ndarray, logs: list[_oe.Log]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Lower and upper bounds and scale of (kS, kV, kA[, gravity terms]) about the start ``p0``."""
    v_max = max(float(np.max(np.abs(log.grid_voltage))) for log in logs)
    ks0, kv0, ka0 = p0[:3]
    scale = np.concatenate([[max(ks0, 0.01 * v_max), kv0, ka0], np.full(p0.size - 3, max(0.05 * v_max, 0.1))])
    lower = np.concatenate([[0.0, 1e-3 * kv0, 1e-3 * ka0], np.full(p0.size - 3, -10.0 * v_max)])
    upper = np.concatenate([[v_max, 1e3 * kv0, max(1e3 * ka0, 100.0 * kv0)], np.full(p0.size - 3, 10.0 * v_max)])
    return lower, upper, scale


def _gain_estimates(fit: _oe.Fit, model: FeedforwardModel, logs: list[_oe.Log], *,
                    linear: bool) -> tuple[list[str], np.ndarray, dict[str, Estimate], np.ndarray]:
    """Names, values, estimates and correlation matrix of the reported gains.

    For the arm, (a, c) are reported as kG and the offset φ (:func:`_arm_gravity`); ``linear``: the
    positions are distances [m], so the gains come per metre.
    """
    m = len(model.names)
    values = fit.values[:m].copy()
    cov = fit.covariance[:m, :m].copy()
    names = list(model.names[:m])
    if model.mechanism == "arm":  # report kG = hypot(a, c) and φ = atan2(c, a) (delta method)
        values, cov = _arm_gravity(values, cov, max(log.resolution for log in logs))
        names[3:5] = ["kG", "offset"]
    stderr = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    params: dict[str, Estimate] = {}
    units = {**SI_UNITS, "offset": "rad"}
    if linear:  # a drivetrain or an elevator logged in metres: the gains come per metre
        units.update(kV="V*s/m", kA="V*s^2/m")
    for k, name in enumerate(names):
        determined = not fit.null[min(k, fit.null.size - 1)] and stderr[k] <= MAX_RELATIVE_STDERR * abs(values[k])
        if name in ("kG", "offset") and not fit.null[k]:
            determined = bool(np.isfinite(stderr[k]))
        note = "" if determined else "the data carry (almost) no information on it"
        if fit.not_minimum:  # the Jacobian cannot be trusted: say so, print no standard error
            determined, note = True, f"no standard error: {fit.not_minimum}"
        params[name] = Estimate(name, float(values[k]), float(stderr[k]), units[name], determined, note)
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(stderr, stderr)
    np.fill_diagonal(corr, 1.0)
    return names, values, params, corr


def _arm_gravity(values: np.ndarray, cov: np.ndarray, resolution: float) -> tuple[np.ndarray, np.ndarray]:
    """(a, c) of kG·cos(θ + φ) = a·cos θ − c·sin θ as kG = hypot(a, c) and φ = atan2(c, a), with their
    covariance by the delta method; φ's variance gains q²/12 for the encoder's quantiser phase."""
    m = values.size
    a, c = values[3], values[4]
    k_g = math.hypot(a, c)
    grad = np.zeros((m, m))
    grad[:3, :3] = np.eye(3)
    if k_g > 0:
        grad[3, 3:5] = [a / k_g, c / k_g]
        grad[4, 3:5] = [-c / k_g**2, a / k_g**2]
    values = values.copy()
    values[3], values[4] = k_g, math.atan2(c, a)
    cov = grad @ cov @ grad.T
    # The counted angle is the shaft's to within one count, with an unknown quantiser phase shared
    # by all tests (one encoder): φ, relative to the shaft's angle, is uncertain by q/√12 more.
    cov[4, 4] += resolution**2 / 12.0
    return values, cov


def _report_open_loop(result: FitResult, recs: list[Recording], *, length: str) -> None:
    """Replace kS, kV, kA by the gains that best simulate the logs open loop (real logs; docs/real-logs.md).

    Called when the motor model leaves residuals the measured noise does not explain (real robots:
    commanded, not applied, voltage; filtered and stale speeds; slip, backlash, direction-dependent
    friction). The three gains a user pastes into a feedforward are then those that minimise the
    open-loop simulation error of the logged speed and position (:func:`motorlab.analyses.sysid_score.fit_gains`),
    with Newey–West standard errors from the residuals' correlation; the motor-model fit, the gains
    of each direction and what the residuals look like are reported besides.
    """
    from motorlab.analyses import sysid_score

    tests = sysid_score.score_tests(recs)
    names = ("kS", "kV", "kA")
    starts = [[max(result.value(n), 1e-6) if n == "kA" else result.value(n) for n in names]]
    ols = result.details.get("sysid_ols")
    reference = None
    if ols and ols["kV"] > 0 and ols["kA"] > 0:
        starts.append([max(ols["kS"], 0.0), ols["kV"], ols["kA"]])
        reference = sysid_score.score([ols["kS"], ols["kV"], ols["kA"]], tests)
    try:
        out = sysid_score.open_loop_gains(tests, starts, reference=reference)
    except (FitError, OptionError) as exc:
        result.warnings.append(f"the open-loop fit of the three gains failed ({exc}); the motor-model fit is reported")
        return
    fit = out["fit"]
    stderr = np.sqrt(np.clip(np.diag(fit.covariance), 0.0, None))
    result.details["physics_fit"] = {n: {"value": result.value(n), "stderr": result[n].stderr} for n in names}
    for k, name in enumerate(names):
        old = result.parameters[name]
        ok = bool(np.isfinite(stderr[k]) and stderr[k] <= MAX_RELATIVE_STDERR * abs(fit.gains[k]))
        result.parameters[name] = Estimate(name, float(fit.gains[k]), float(stderr[k]), old.unit, ok,
                                           "" if ok else "the data carry (almost) no information on it")
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = fit.covariance / np.outer(stderr, stderr)
    np.fill_diagonal(corr, 1.0)
    result.correlation, result.correlation_names = corr, list(names)
    result.details.update({
        "method": "open-loop output error: kS, kV, kA minimise log RMSE(speed) + "
                  f"{out['position_weight']:g}·log RMSE(position) of the simulation from the logged voltage",
        "position_weight": out["position_weight"],
        "uncertainty": f"Newey–West from the residuals' correlation (bandwidth {fit.bandwidth:.1f} rows)",
        "open_loop_score": {"speed": fit.score.speed, "position": fit.score.position,
                            "units": {"speed": f"{length}/s", "position": length}},
        "by_direction": {d: dict(zip(names, g, strict=True)) for d, g in out["by_direction"].items()},
        "by_side": {d: dict(zip(names, g, strict=True)) for d, g in out["by_side"].items()},
        "gains_by_tests": _gain_rows(fit.gains, out, result.details["physics_fit"], length),
        "residual_diagnostics": out["diagnostics"],
    })
    about_model = ("the measured noise does not explain", "the optimiser stopped early", "kS and kV are",
                   "no acceleration event")
    result.details["physics_fit_warnings"] = [w for w in result.warnings if w.startswith(about_model)]
    result.warnings[:] = [w for w in result.warnings if not w.startswith(about_model)]
    looks = out["description"] or "no single effect (lag, asymmetry, drift) stands out"
    result.warnings.append(
        "the motor model leaves residuals the measured noise does not explain: kS, kV, kA are the gains that best "
        "simulate the logged speed and position open loop, with standard errors from the residuals' correlation "
        f"(Newey–West); the residuals look like: {looks}"
    )
    if fit.gains[0] < 0:
        result.warnings.append(f"kS = {fit.gains[0]:.3g} V is negative: no static friction explains it; the logs "
                               "move at voltages below what the model expects (check the voltage log's offset)")
    _, rp = sysid_score.residuals(fit.gains, tests)
    position = np.concatenate([t.position for t in tests])
    sst = float(np.sum((position - position.mean()) ** 2))
    result.rmse, result.r2 = fit.score.position, 1.0 - float(np.sum(rp**2)) / sst if sst > 0 else math.nan
    for panel in result.panels:  # what follows the score's panels is the motor-model fit's
        panel.title = panel.title.replace("feedforward:", "motor-model fit (angle only):", 1)
    result.panels[:0] = sysid_score.score_panels(fit.gains, tests, title="feedforward", length=length)


def _gain_rows(gains: np.ndarray, out: dict[str, Any], physics: dict[str, Any], length: str) -> list[dict[str, Any]]:
    """One row per gain set for the human output: pooled (reported), per direction, per side, motor model."""
    units = ("kS [V]", f"kV [V·s/{length}]", f"kA [V·s²/{length}]")
    rows = [{"tests": "all (reported)", **dict(zip(units, gains.tolist(), strict=True))}]
    for label, g in {**out["by_direction"], **out["by_side"]}.items():
        rows.append({"tests": f"{label} only", **dict(zip(units, g, strict=True))})
    rows.append({"tests": "motor model (angle only)",
                 **{u: physics[n]["value"] for u, n in zip(units, ("kS", "kV", "kA"), strict=True)}})
    return rows


def _noise_warning(recs: list[Recording], logs: list[_oe.Log], fit: _oe.Fit, *, length: str) -> list[str]:
    """The motor-model fit's noise warning (if any), saying what the residuals look like."""
    noise = noise_warning(fit, rms_text=f"{fit.residual_rms['position']:.3g} {length}")
    if noise and fit.noise_model.startswith("Newey"):
        look = _residual_look(recs, logs, fit) or "no single effect (lag, asymmetry, drift) stands out"
        noise[0] += f"; the residuals look like: {look}"
    return noise


def _residual_look(recs: list[Recording], logs: list[_oe.Log], fit: _oe.Fit) -> str:
    """Lag, asymmetry or drift in the angle residuals of the motor-model fit (:mod:`motorlab.analyses.sysid_score`)."""
    from motorlab.analyses import sysid_score
    from motorlab.io.frc_json import test_kind

    runs = []
    for rec, log, sim in zip(recs, logs, fit.simulations, strict=True):
        name = str(rec.metadata.get("segment") or "")
        direction = int(test_kind(name)["direction"]) if name else int(np.sign(np.mean(log.grid_voltage)))
        runs.append((log.time, log.position - sim["position"], sim["speed"], direction))
    return sysid_score.describe_residuals(sysid_score.position_residual_diagnostics(runs))


def _gain_warnings(logs: list[_oe.Log], fit: _oe.Fit, values: np.ndarray, corr: np.ndarray) -> list[str]:
    warnings = []
    ks_rel = math.sqrt(max(float(fit.covariance[0, 0]), 0.0)) / max(abs(values[0]), 1e-300)
    if abs(corr[0, 1]) > 0.99 or ks_rel > 0.25:
        warnings.append(
            f"kS and kV are {abs(corr[0, 1]):.3f} correlated: too little excitation to separate static "
            "friction from viscous; run a slow quasistatic ramp from rest"
        )
    else:
        warnings.extend(excitation_warnings(logs, [s["speed"] for s in fit.simulations]))
    # an acceleration event: somewhere kA·α is a sizeable part of the applied voltage
    k_a = values[2]
    peak = 0.0
    for log, sim in zip(logs, fit.simulations, strict=True):
        if log.time.size > 2:
            peak = max(peak, float(np.max(np.abs(k_a * np.gradient(sim["speed"], log.time)))))
    v_max = max(float(np.max(np.abs(log.grid_voltage))) for log in logs)
    if peak < 0.1 * v_max:
        warnings.append(
            f"no acceleration event: kA·α never exceeds {100 * peak / max(v_max, 1e-12):.1f} % of the voltage, so "
            "kA rests on small accelerations (trust it as far as its standard error says); a dynamic (step) "
            "test or faster changes of the voltage determine it better"
        )
    return warnings


def motor_estimates(
    result: FitResult,
    *,
    resistance: float | None,
    torque_constant: float | None,
    resistance_stderr: float = 0.0,
    torque_constant_stderr: float = 0.0,
) -> dict[str, Estimate]:
    """R, K, J, b, Tf from fitted gains, as far as the given R (and K) determine them.

    Without R nothing follows. With R only, kV = K + R·b/K cannot be split: K and b are not
    determined, and J = kA·K/R, Tf = kS·K/R are only bounded (K ≤ kV since b ≥ 0). With R and K:
    J = kA·K/R, b = (kV − K)·K/R, Tf = kS·K/R. Standard errors to first order from those of the gains
    and of the given R and K [Ω], [V·s/rad] (independent measurements: another experiment's):
    σJ/J = √((σkA/kA)² + (σK/K)² + (σR/R)²), likewise Tf, and
    σb² = (K/R)²·σkV² + ((kV − 2K)/R)²·σK² + (b/R)²·σR² (K enters b twice).
    """
    ks, kv, ka = (result.parameters[n] for n in ("kS", "kV", "kA"))
    out: dict[str, Estimate] = {}

    def undetermined(name: str, note: str) -> Estimate:
        return Estimate(name, math.nan, math.nan, SI_UNITS[name], False, note)

    if resistance is None:
        for name in ("K", "R", "J", "b", "Tf"):
            out[name] = undetermined(name, "needs the winding resistance R (--R) or a current log")
        return out
    r, sr, sk = resistance, float(resistance_stderr or 0.0), float(torque_constant_stderr or 0.0)
    out["R"] = Estimate("R", r, sr, SI_UNITS["R"], True, "given")
    if torque_constant is None:
        out["K"] = undetermined("K", f"only kV = K + R·b/K is seen; K ≤ {kv.value:.4g} V·s/rad (supply --K or current)")
        out["b"] = undetermined("b", "only kV = K + R·b/K is seen (supply --K or a current log)")
        out["J"] = undetermined("J", f"J = kA·K/R needs K; J ≤ kA·kV/R = {ka.value * kv.value / r:.4g} kg·m²")
        out["Tf"] = undetermined("Tf", f"Tf = kS·K/R needs K; Tf ≤ kS·kV/R = {ks.value * kv.value / r:.4g} N·m")
        return out
    k = torque_constant
    out["K"] = Estimate("K", k, sk, SI_UNITS["K"], True, "given")

    def product(gain: Estimate) -> tuple[float, float]:  # gain·K/R and its standard error
        value = gain.value * k / r
        rel = math.sqrt((gain.stderr / gain.value) ** 2 + (sk / k) ** 2 + (sr / r) ** 2) if gain.value else math.inf
        return value, abs(value) * rel if gain.value else gain.stderr * k / r

    j_value, j_se = product(ka)
    out["J"] = Estimate("J", j_value, j_se, SI_UNITS["J"], ka.determined)
    b_value = (kv.value - k) * k / r
    b_se = math.sqrt((k / r * kv.stderr) ** 2 + ((kv.value - 2 * k) / r * sk) ** 2 + (b_value / r * sr) ** 2)
    b_ok = kv.determined and b_se <= MAX_RELATIVE_STDERR * abs(b_value)
    out["b"] = Estimate("b", b_value, b_se, SI_UNITS["b"], bool(b_ok),
                        "" if b_ok else "kV − K is within the noise of kV and K")
    tf_value, tf_se = product(ks)
    out["Tf"] = Estimate("Tf", tf_value, tf_se, SI_UNITS["Tf"], ks.determined)
    return out


# --------------------------------------------------------------------------------------------------
# motorlab analyze feedforward
# --------------------------------------------------------------------------------------------------


def read_tests(paths: list[str], *, cpr: float | None, side: str = "both", units: str | None = None) -> list[Recording]:
    """Read the files, one recording per test (and per drivetrain side), for :func:`feedforward`.

    SysId and frc-characterization JSON files carry their own units: ``side`` and ``units`` go to
    their readers, and a ``cpr`` becomes the file's position quantum, one count = one logged
    rotation / cpr (:func:`apply_cpr`). Other formats get ``cpr`` in their reader
    (:func:`motorlab.estimation.runs.read_runs`).
    """
    from motorlab import io as mio

    runs: list[Recording] = []
    for path in paths:
        fmt = mio.detect_format(path)
        if fmt in ("sysid-json", "frc-char-json"):  # (its reader directly: a large file is not detected twice)
            parts = mio.READERS[fmt](path, side=side, units=units).split()
            if cpr is not None:
                apply_cpr(parts, cpr)
            runs.extend(parts)
        else:
            runs.extend(read_runs([path], cpr=cpr))
    return runs


def apply_cpr(recordings: Sequence[Recording], cpr: float) -> None:
    """Set the position quantum of JSON tests from ``cpr`` [count/rotation of the logged shaft], in place.

    The quantum is ``rotation_si/cpr`` (metres for a drivetrain logged in metres, radians for angles)
    and is stored as the equivalent ``metadata["cpr"]`` = 2π/quantum the fit reads.

    Raises
    ------
    OptionError
        The file logs a length without ``unitsPerRotation`` (a rotation's length is unknown), or its
        positions move by steps finer than one count (the cpr does not fit the file).
    """
    from motorlab.analyses.common import check_cpr

    check_cpr(cpr)
    finest, n_fine = math.inf, 0
    for rec in recordings:
        rotation = rec.metadata.get("rotation_si")
        if rotation is None:
            raise OptionError(
                f"--cpr {cpr:g}: {rec.source} logs {rec.metadata.get('units')} without unitsPerRotation, so a count "
                "cannot be turned into a distance; leave --cpr out (the quantum is then read from the steps)"
            )
        steps = np.abs(np.diff(rec.signals["position"]))
        fine = steps[(steps > 1e-12 * rotation) & (steps < 0.5 * rotation / cpr)]
        n_fine += fine.size
        finest = min(finest, float(np.min(fine)) if fine.size else math.inf)
        rec.metadata["cpr"] = 2.0 * math.pi * cpr / rotation
        rec.metadata["cpr_given"] = cpr
    if n_fine >= 3:  # a few: JSON rounding of a position can split one count over two rows
        rec = recordings[0]
        raise OptionError(
            f"--cpr {cpr:g}: {rec.source} moves by steps as small as {finest:.3g} {rec.metadata.get('position_unit')}"
            f" ({n_fine} steps finer than half a count): this cpr does not fit (give the counts per logged rotation, "
            "gearing included)"
        )
