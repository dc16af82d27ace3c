"""Inertia J and friction from a square-wave-driven speed trace (seed 2, "Motor Mechanical Properties").

A servo amplifier (current source, I = Ka·V) drives the motor with a unipolar square wave; a
tachometer records the speed. During each pulse the shaft accelerates, between pulses it coasts
to rest. The seed takes the slopes Ω̇1 (accelerate) and Ω̇2 (coast) with scope cursors and solves
eqs. (3)–(5). Here every accelerate and coast region of every pulse is fitted, and the seed's
question "Is the shaft friction viscous?" is answered by comparing three friction models on the
coast-downs with information criteria (AIC, BIC).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from motorlab import progress
from motorlab.analyses._pulse_fit import (
    CoastFit,
    Region,
    compare_friction_models,
    joint_fit,
    model_sentence,
    propagate_inputs,
)
from motorlab.analyses.common import (
    LIMITS,
    check_range,
    check_stderr_limit,
    check_torque_constant,
    reader_warnings,
    sources_of,
)
from motorlab.errors import FitError, LogFormatError, OptionError
from motorlab.estimation.decimate import block_mean
from motorlab.estimation.least_squares import LeastSquares, fit_linear, r_squared
from motorlab.recording import Recording
from motorlab.results import Estimate, FitResult, Panel, Series
from motorlab.units import SI_UNITS

#: Default time skipped after each command edge [s] (amplifier and tachometer-filter settling).
DEFAULT_SKIP = 0.002
#: Fewest samples a region needs to be fitted.
MIN_REGION_SAMPLES = 8
#: Friction models compared on the coast-downs, in the order of the table.
FRICTION_MODELS = ("viscous", "coulomb", "both")
_MODEL_LABELS = {"viscous": "viscous", "coulomb": "Coulomb", "both": "viscous + Coulomb"}


def _noise_sigma(speed: np.ndarray) -> float:
    """Speed noise σ [rad/s] from second differences (insensitive to slopes): MAD(Δ²ω)/√6·1.4826."""
    d2 = np.diff(speed, 2)
    if d2.size < 3:
        return 0.0
    return float(1.4826 * np.median(np.abs(d2 - np.median(d2))) / math.sqrt(6.0))


def _levels(command: np.ndarray, *, source: str = "") -> tuple[np.ndarray, float, float]:
    """High/low state of the command with hysteresis, and the low and high levels [V]."""
    lo, hi = float(np.percentile(command, 2)), float(np.percentile(command, 98))
    if not hi > lo:
        where = f"{source}: " if source else ""
        raise FitError(f"{where}the command never changes: no pulses to analyse (expected a square wave)")
    up, down = lo + 0.6 * (hi - lo), lo + 0.4 * (hi - lo)
    state = np.empty(command.size, dtype=bool)
    high = bool(command[0] > 0.5 * (lo + hi))
    for k, v in enumerate(command):
        if high and v < down:
            high = False
        elif not high and v > up:
            high = True
        state[k] = high
    return state, lo, hi


def _regions(
    rec: Recording, speed_name: str, *, skip: float, tach_gain: float | None
) -> tuple[list[Region], list[str], float, np.ndarray, np.ndarray]:
    """Cut one recording into accelerate and coast regions; returns regions, warnings, σ, t, ω."""
    t = rec.time
    command = rec.require("command")
    raw = rec.require(speed_name)
    speed = raw / tach_gain if speed_name == "tach_voltage" and tach_gain is not None else raw.copy()
    for name, values in (("time", t), ("command", command), (speed_name, raw)):
        bad = np.flatnonzero(~np.isfinite(values))
        if bad.size:
            raise LogFormatError(
                f"{name} is not a finite number in this row", path=rec.source or None, line=rec.line_of(int(bad[0]))
            )
    if t.size < 3 * MIN_REGION_SAMPLES:
        raise FitError(f"{rec.source or 'recording'}: {t.size} samples are too few for a pulse response")
    steps = np.diff(t)
    if np.any(steps <= 0):
        k = int(np.flatnonzero(steps <= 0)[0]) + 1
        raise LogFormatError("time does not increase", path=rec.source or None, line=rec.line_of(k))
    if rec.metadata.get("time") == "row index":
        raise LogFormatError("the pulse analysis needs a time column (time_s or time_ms)", path=rec.source or None)
    warnings: list[str] = []
    state, _, _ = _levels(command, source=rec.source)
    change = np.flatnonzero(np.diff(state.astype(np.int8))) + 1
    rises = [int(k) for k in change if state[k]]
    falls = [int(k) for k in change if not state[k]]
    if not rises or not falls:
        raise FitError(f"{rec.source or 'recording'}: no complete pulse (a rising and a falling edge) in the command")
    # Pulse direction: torque ∝ V_high − V_low; mirror the speed so that the pulses drive it positive.
    v_high = float(np.median(command[state]))
    v_low = float(np.median(command[~state]))
    drive_sign = 1.0 if v_high > v_low else -1.0
    accel_mask = np.zeros(t.size, dtype=bool)
    for r in rises:
        f = next((f for f in falls if f > r), None)
        if f is not None:
            accel_mask[r:f] = True
    speed_sign = 1.0 if np.median(speed[accel_mask]) >= 0 else -1.0
    if speed_sign != drive_sign and np.any(accel_mask):
        warnings.append(
            f"{rec.source or 'recording'}: the speed runs opposite to the command: tachometer or motor leads "
            "reversed? The trace was analysed mirrored"
        )
    speed = speed * speed_sign
    sigma = _noise_sigma(speed)
    # The held levels are medians of a noisy scope trace: their standard error 1.2533·σ/√n
    # (the median's efficiency for Gaussian noise) is propagated into J, b and Tf.
    sigma_command = _noise_sigma(command)
    stop_level = max(5.0 * sigma, 0.02 * float(np.max(speed)))
    regions: list[Region] = []
    not_at_rest = 0
    for n, r in enumerate(rises):
        f = next((f for f in falls if f > r), None)
        if f is None:
            continue  # the record ends during a pulse
        nxt = next((k for k in rises if k > f), t.size)
        level_hi = float(np.median(command[r:f]))
        level_lo = float(np.median(command[f:nxt]))
        se_hi = 1.2533 * sigma_command / math.sqrt(max(f - r, 1))
        se_lo = 1.2533 * sigma_command / math.sqrt(max(nxt - f, 1))
        if speed[r] > stop_level:
            not_at_rest += 1
        a = np.flatnonzero((t >= t[r] + skip) & (np.arange(t.size) < f))
        c = np.arange(f, nxt)
        c = c[t[c] >= t[f] + skip]
        below = np.flatnonzero(speed[c] < stop_level)
        if below.size:
            c = c[: below[0]]
        if a.size >= MIN_REGION_SAMPLES and float(np.max(speed[a])) > stop_level:
            regions.append(Region("accelerate", n + 1, t[a], speed[a], level_hi, float(t[r]), rec.source, se_hi))
        if c.size >= MIN_REGION_SAMPLES:
            regions.append(Region("coast", n + 1, t[c], speed[c], level_lo, float(t[f]), rec.source, se_lo))
    if not_at_rest:
        warnings.append(
            f"{rec.source or 'recording'}: in {not_at_rest} pulse(s) the shaft was still turning at the rising "
            "edge (the seed lowers the duty cycle so that it comes to rest); the fit allows for it"
        )
    return regions, warnings, sigma, t, speed


# ---- the analysis -----------------------------------------------------------------------------------


def pulse(
    recordings: Recording | Sequence[Recording],
    *,
    amplifier_gain: float,
    torque_constant: float,
    amplifier_offset: float = 0.0,
    skip: float = DEFAULT_SKIP,
    tach_gain: float | None = None,
    friction: str = "auto",
    amplifier_gain_stderr: float = 0.0,
    amplifier_offset_stderr: float = 0.0,
    gain_offset_correlation: float = 0.0,
    torque_constant_stderr: float = 0.0,
) -> FitResult:
    """J and friction from the response to a square-wave current command.

    Parameters
    ----------
    recordings
        One or more recordings with ``time`` [s], ``command`` [V] (the square wave) and the speed:
        ``velocity`` or ``speed`` [rad/s], or ``tach_voltage`` [V] with ``tach_gain``.
    amplifier_gain
        Servo-amplifier gain Ka [A/V] (seed 2's ``analyze amplifier``; nominal 2 A/V).
    torque_constant
        Motor torque constant Km = K [N·m/A] (``analyze torque``).
    amplifier_offset
        Amplifier output current at zero command, I0 [A] (the intercept of ``analyze amplifier``).
        It keeps a small torque Km·I0 on during the coasts; left out, it shows up as a Tf too low
        by Km·I0.
    skip
        Time left out after each command edge [s] (amplifier and tachometer settling).
    tach_gain
        Tachometer gain Kt_tach [V·s/rad], needed only when the speed is a tachometer voltage.
    friction
        ``"auto"`` (choose by BIC on the coast-downs), ``"coulomb"`` (the seed's eq. (2)),
        ``"viscous"`` or ``"both"``: the friction model of the final fit.
    amplifier_gain_stderr, amplifier_offset_stderr
        Standard errors of Ka [A/V] and I0 [A] (``analyze amplifier``), propagated into J, b and Tf
        (default: exact). J and b scale with Ka, and Tf moves one for one with Km·I0, so on a fast
        trace these are often the largest part of the uncertainty.
    gain_offset_correlation
        Correlation of Ka and I0 from the same straight-line fit (``C(Ka, I0)`` of its report) [-].
    torque_constant_stderr
        Standard error of Km [N·m/A], propagated likewise (default: exact).

    Returns
    -------
    FitResult
        ``J`` [kg·m²], ``Tf`` [N·m] and, when viscous friction is in the model, ``b`` [N·m·s/rad]
        and ``gamma`` = b/J [1/s]. ``details["friction_models"]`` is the AIC/BIC table,
        ``details["slopes"]`` the seed's per-pulse slope method; the first warning answers the
        seed's question "Is the shaft friction viscous?".

    Raises
    ------
    OptionError
        For non-positive gains or a negative skip, or an unknown friction model.
    LogFormatError
        For a missing column, a non-finite sample or time that does not increase.
    FitError
        When the command holds no complete pulse or the regions are too short to fit.

    Notes
    -----
    The torque is τ = Km·(Ka·V + I0) (current drive, I0 the amplifier offset; below V stands for
    V + I0/Ka). With Coulomb friction only, the accelerate and coast slopes are
    Ω̇1 = (Ka·Km·V1 − Tf)/J and Ω̇2 = (Ka·Km·V2 − Tf)/J (seed 2, eqs. (3), (4);
    V2 = 0 for a unipolar wave, so Ω̇2 = −Tf/J < 0), hence J = Ka·Km·(V1 − V2)/(Ω̇1 − Ω̇2)
    (eq. (5)) and Tf = Ka·Km·V2 − J·Ω̇2. The per-pulse slopes are kept in ``details["slopes"]``.
    The reported estimates come from one fit of every region with the exact solution of
    J·dω/dt = τ − b·ω − Tf: ω(s) = ω0·e^(−γs) + (τ − Tf)/J·(1 − e^(−γs))/γ, γ = b/J, one free start
    speed per region (the first milliseconds after each edge are skipped), which reduces to the
    seed's straight lines when b = 0. A coast is fitted until the speed first falls below
    max(5σ, 2 % of the peak): once stopped, Coulomb friction holds the shaft and no model applies.
    On the coasts alone three models are compared: viscous ω = ω0·e^(−γt), Coulomb
    ω = ω0 − (Tf/J)·t, and both ω = (ω0 + c)·e^(−γt) − c with c = Tf/b; AIC = n·ln(SSR/n) + 2k and
    BIC = n·ln(SSR/n) + k·ln(n) (k counts the start speeds too). Both assume independent residuals;
    tachometer ripple correlates them and makes the criteria over-eager for the richer model.
    The standard errors of the final fit do not make that assumption: they come from the
    Newey–West (HAC) sandwich of :func:`motorlab.estimation.covariance.hac_covariance`, with lags kept within
    each region, because the tachometer's commutator ripple correlates neighbouring residuals.

    References
    ----------
    Seed 2 (MIT 2.010 Lab 2), "Motor Mechanical Properties (Shaft Inertia and Friction)", eqs. (1)–(5).
    """
    recordings = [block_mean(r) for r in ([recordings] if isinstance(recordings, Recording) else recordings)]
    calibration = _Calibration(amplifier_gain, amplifier_gain_stderr, amplifier_offset, amplifier_offset_stderr,
                               gain_offset_correlation, torque_constant, torque_constant_stderr)
    _check_options(recordings, calibration, skip=skip, tach_gain=tach_gain, friction=friction)
    gain = amplifier_gain * torque_constant  # torque per command volt [N·m/V]
    # An amplifier offset I0 acts as a command offset I0/Ka: τ = Ka·Km·(V + I0/Ka).
    return _fit_in_steps(recordings, calibration, amplifier_offset / amplifier_gain, gain=gain, skip=skip,
                         tach_gain=tach_gain, friction=friction)


def _fit_in_steps(recordings: list[Recording], calibration: _Calibration, command_offset: float, *, gain: float,
                  skip: float, tach_gain: float | None, friction: str) -> FitResult:
    """Cut the pulses, compare the friction models, fit every region: reported as three steps."""
    with progress.task("Fitting the pulse response", total=3, unit="steps", detail="cutting the pulses") as step:
        cut = _cut_recordings(recordings, command_offset, skip=skip, tach_gain=tach_gain)
        start = _slope_method(cut.accel, cut.coasts, gain)
        step.advance(detail=f"friction models on {len(cut.coasts)} coast-downs")
        table, best = compare_friction_models(cut.coasts, start.a2)
        step.advance(detail=f"every region of {len(cut.accel)} pulses")
        result = _final_fit(cut, start, table, best, gain=gain, friction=friction, calibration=calibration)
        step.advance()
    return result


@dataclass(frozen=True)
class _Calibration:
    """Amplifier and motor constants given to :func:`pulse`, with their standard errors."""

    gain: float  # Ka [A/V]
    gain_stderr: float
    offset: float  # I0 [A]
    offset_stderr: float
    correlation: float  # C(Ka, I0) [-]
    torque_constant: float  # Km [N·m/A]
    torque_constant_stderr: float


@dataclass
class _Cut:
    """Every recording cut into regions, with the traces, noise levels and warnings met on the way."""

    recordings: list[Recording]
    regions: list[Region]
    accel: list[Region]
    coasts: list[Region]
    traces: list[tuple[Recording, np.ndarray, np.ndarray]]
    sigmas: list[float]  # speed noise σ of each recording [rad/s]
    read_warnings: list[str]  # the readers' warnings, first in the result
    cut_warnings: list[str]  # what cutting the recordings noted


@dataclass
class _SlopeStart:
    """The seed's slope method (eqs. (3)–(5)): per-pulse table, median slopes and levels, J and Tf."""

    slopes: list[dict[str, float]]
    a1: float  # accelerate slope Ω̇1 [rad/s²]
    a2: float  # coast slope Ω̇2 [rad/s²]
    v1: float  # held command during the pulses [V]
    v2: float  # held command between them [V]
    j0: float  # [kg·m²]
    tf0: float  # [N·m]


def _check_options(
    recordings: list[Recording], calibration: _Calibration, *, skip: float, tach_gain: float | None, friction: str
) -> None:
    """Raise :class:`OptionError` for impossible options or no recording, in the order the CLI's user reads them."""
    amplifier_gain, torque_constant = calibration.gain, calibration.torque_constant
    amplifier_offset, gain_offset_correlation = calibration.offset, calibration.correlation
    if not (math.isfinite(amplifier_gain) and amplifier_gain > 0):
        raise OptionError(f"the amplifier gain Ka must be positive, got {amplifier_gain} A/V")
    if not (math.isfinite(torque_constant) and torque_constant > 0):
        raise OptionError(f"the torque constant Km must be positive, got {torque_constant} N·m/A")
    # Generous physical limits: Ka = 1e-300 A/V made J ~ 1e-300 kg·m² and J² underflow to 0.
    check_range(amplifier_gain, "the amplifier gain (--Ka)", *LIMITS["Ka"][:2], "A/V",
                why="seed 2's amplifier gives 2 A/V; no servo amplifier is outside this by far")
    check_torque_constant(torque_constant, "the torque constant Km (--K)")
    if not (math.isfinite(skip) and skip >= 0):
        raise OptionError(f"the time skipped after edges must be ≥ 0, got {skip} s")
    if friction not in ("auto", *FRICTION_MODELS):
        raise OptionError(f"friction model must be auto, viscous, coulomb or both, got {friction!r}")
    if tach_gain is not None and not (math.isfinite(tach_gain) and tach_gain > 0):
        raise OptionError(f"the tachometer gain must be positive, got {tach_gain} V·s/rad")
    check_range(tach_gain, "the tachometer gain (--tach-gain)", *LIMITS["K"][:2], "V·s/rad",
                why="a tachometer is a small DC generator: its gain is a motor's K")
    if not recordings:
        raise OptionError("no recording given")
    if not math.isfinite(amplifier_offset):
        raise OptionError(f"the amplifier offset must be a finite current, got {amplifier_offset} A")
    for value, what in ((calibration.gain_stderr, "Ka"), (calibration.offset_stderr, "I0"),
                        (calibration.torque_constant_stderr, "Km")):
        if not (math.isfinite(value) and value >= 0):
            raise OptionError(f"the standard error of {what} must be a finite number ≥ 0, got {value}")
    check_range(abs(amplifier_offset), "the amplifier offset (--I0) in magnitude", 0.0, LIMITS["I"][1], "A",
                why="beyond any servo amplifier")
    check_stderr_limit(calibration.gain_stderr, "Ka", "the standard error of Ka (--Ka-stderr)")
    check_stderr_limit(calibration.offset_stderr, "I", "the standard error of I0 (--I0-stderr)")
    check_stderr_limit(calibration.torque_constant_stderr, "K", "the standard error of Km (--Km-stderr)")
    if not (math.isfinite(gain_offset_correlation) and abs(gain_offset_correlation) <= 1):
        raise OptionError(f"the Ka-I0 correlation must lie in [-1, 1], got {gain_offset_correlation}")


def _cut_recordings(recs: list[Recording], command_offset: float, *, skip: float, tach_gain: float | None) -> _Cut:
    """Cut every recording into accelerate and coast regions, the command shifted by ``command_offset`` [V]."""
    regions: list[Region] = []
    read_warnings = reader_warnings(recs)
    warnings: list[str] = []
    traces = []
    sigmas = []
    for rec in recs:
        speed_name = _speed_signal(rec, tach_gain)
        rr, ww, sigma, t, speed = _regions(rec, speed_name, skip=skip, tach_gain=tach_gain)
        for region in rr:
            region.command += command_offset
        regions += rr
        warnings += ww
        sigmas.append(sigma)
        traces.append((rec, t, speed))
    accel = [r for r in regions if r.kind == "accelerate"]
    coasts = [r for r in regions if r.kind == "coast"]
    if not accel or not coasts:
        raise FitError(
            "no usable accelerate and coast regions (pulses too short, or the shaft never moves: is Ka·Km·V "
            "above the friction torque?)"
        )
    return _Cut(recs, regions, accel, coasts, traces, sigmas, read_warnings, warnings)


def _slope_method(accel: list[Region], coasts: list[Region], gain: float) -> _SlopeStart:
    """The seed's slope method, pulse by pulse (also the starting point of the fit)."""
    slopes = _slope_table(accel, coasts, gain)
    a1 = float(np.median([s["accel_slope"] for s in slopes])) if slopes else _slope(accel[0])
    a2 = float(np.median([s["coast_slope"] for s in slopes])) if slopes else _slope(coasts[0])
    v1 = float(np.median([r.command for r in accel]))
    v2 = float(np.median([r.command for r in coasts]))
    if not a1 > a2:
        raise FitError("the shaft does not accelerate faster during the pulses than between them")
    j0 = gain * (v1 - v2) / (a1 - a2)
    tf0 = gain * v2 - j0 * a2
    return _SlopeStart(slopes, a1, a2, v1, v2, j0, tf0)


def _final_fit(
    cut: _Cut,
    start: _SlopeStart,
    table: dict[str, CoastFit],
    best: str,
    *,
    gain: float,
    friction: str,
    calibration: _Calibration,
) -> FitResult:
    """Fit every region with the chosen friction model and gather the result."""
    sentence = model_sentence(table, best)
    chosen = best if friction == "auto" else friction
    if friction != "auto" and friction != best:
        sentence += f"; the final fit uses {friction} friction as asked"
    with_b = chosen in ("viscous", "both")
    # Tf stays free unless viscous-only friction was asked for: when the data prefer the viscous model
    # the fitted Tf is then small, with its standard error, rather than a bare 0.
    with_tf = friction != "viscous"
    fit = joint_fit(cut.regions, gain, start.j0, start.tf0, max(table["both"].gamma * start.j0, 0.0), with_b, with_tf)
    parameters, fitted_names, correlation = _estimates(
        fit, with_b, with_tf, calibration, _level_errors(cut.accel, cut.coasts)
    )
    all_t = np.concatenate([r.time for r in cut.regions])
    all_w = np.concatenate([r.speed for r in cut.regions])
    model_w = all_w + fit.residuals
    # The friction-model sentence goes right after what the readers noted.
    warnings = [*cut.read_warnings, sentence, *cut.cut_warnings]
    if chosen == "coulomb" and best != "coulomb":
        warnings.append("viscous friction is left out of the final fit as asked: J and Tf are biased")
    return FitResult(
        experiment="pulse",
        parameters=parameters,
        correlation=correlation,
        correlation_names=fitted_names,
        rmse=fit.rmse,
        rmse_unit="rad/s",
        r2=r_squared(all_w, model_w),
        n_points=int(all_t.size),
        panels=_panels(cut.traces, cut.regions, model_w, table, best, cut.coasts, chosen),
        warnings=warnings,
        details=_details(cut, start, table, best, chosen, gain),
        sources=sources_of(cut.recordings),
    )


def _estimates(
    fit: LeastSquares,
    with_b: bool,
    with_tf: bool,
    calibration: _Calibration,
    levels: tuple[float, float, float, float],
) -> tuple[dict[str, Estimate], list[str], np.ndarray]:
    """J, Tf (and b, γ) of the final fit, with the inputs' uncertainties added; their names and correlation."""
    units = {"J": SI_UNITS["J"], "Tf": SI_UNITS["Tf"], "b": SI_UNITS["b"]}
    est = fit.estimates({n: units.get(n, "rad/s") for n in fit.names})
    parameters: dict[str, Estimate] = {"J": est["J"]}
    if with_tf:
        parameters["Tf"] = est["Tf"]
    else:
        parameters["Tf"] = Estimate("Tf", 0.0, math.nan, SI_UNITS["Tf"], True, "fixed at 0 (viscous model)")
    if with_b:
        parameters["b"] = est["b"]
        jb = [fit.names.index("J"), fit.names.index("b")]
        cov = fit.covariance[np.ix_(jb, jb)]
        jv, bv = float(fit.values[jb[0]]), float(fit.values[jb[1]])
        grad = np.array([-(bv / jv) / jv, 1.0 / jv])  # d(b/J)/dJ written so that J² cannot underflow
        g_err = float(np.sqrt(max(grad @ cov @ grad, 0.0)))
        parameters["gamma"] = Estimate("gamma", bv / jv, g_err, SI_UNITS["gamma"], bool(est["b"].determined), "b/J")
    fitted_names = ["J"] + (["b"] if with_b else []) + (["Tf"] if with_tf else [])
    idx = [fit.names.index(n) for n in fitted_names]
    cov_out = propagate_inputs(
        fit.covariance[np.ix_(idx, idx)], fitted_names, fit.values[idx],
        gain=(calibration.gain, calibration.gain_stderr), offset=(calibration.offset, calibration.offset_stderr),
        correlation=calibration.correlation,
        torque_constant=(calibration.torque_constant, calibration.torque_constant_stderr), levels=levels,
    )
    for k, name in enumerate(fitted_names):
        old_est = parameters[name]
        parameters[name] = Estimate(name, old_est.value, float(math.sqrt(max(cov_out[k, k], 0.0))), old_est.unit,
                                    old_est.determined, old_est.note)
    with np.errstate(invalid="ignore", divide="ignore"):
        sd = np.sqrt(np.clip(np.diag(cov_out), 0.0, None))
        correlation = cov_out / np.outer(sd, sd)
    np.fill_diagonal(correlation, 1.0)
    return parameters, fitted_names, correlation


def _details(
    cut: _Cut, start: _SlopeStart, table: dict[str, CoastFit], best: str, chosen: str, gain: float
) -> dict[str, object]:
    """``details`` of the result: the friction-model table, the slope method and the trace's figures."""
    return {
        "friction_model": chosen,
        "friction_models": [
            {
                "model": m,
                "n": table[m].n,
                "k": table[m].k,
                "rms_rad_per_s": math.sqrt(table[m].ssr / table[m].n),
                "AIC": table[m].aic,
                "BIC": table[m].bic,
                "dAIC": table[m].aic - min(x.aic for x in table.values()),
                "dBIC": table[m].bic - table[best].bic,
                "gamma_per_s": table[m].gamma,
                "Tf_over_J_rad_per_s2": table[m].decel + (gain * start.v2 / start.j0),
            }
            for m in FRICTION_MODELS
        ],
        "slopes": start.slopes,
        "slope_method": {"J": start.j0, "Tf": start.tf0, "accel_slope": start.a1, "coast_slope": start.a2},
        "torque_per_volt": gain,
        "command_high_V": start.v1,
        "command_low_V": start.v2,
        "speed_noise_rad_per_s": float(np.median(cut.sigmas)),
        "pulses": len(cut.accel),
        "coasts": len(cut.coasts),
    }


def _level_errors(accel: list[Region], coasts: list[Region]) -> tuple[float, float, float, float]:
    """Mean held levels V1 (pulses) and V2 (coasts) [V] and the standard errors of those means."""
    v1 = float(np.mean([r.command for r in accel]))
    v2 = float(np.mean([r.command for r in coasts]))
    se1 = math.sqrt(sum(r.command_stderr**2 for r in accel)) / len(accel)
    se2 = math.sqrt(sum(r.command_stderr**2 for r in coasts)) / len(coasts)
    return v1, se1, v2, se2


def _speed_signal(rec: Recording, tach_gain: float | None) -> str:
    for name in ("velocity", "speed"):
        if name in rec:
            return name
    if "tach_voltage" in rec:
        if tach_gain is None:
            raise OptionError(
                f"{rec.source or 'recording'}: the speed is a tachometer voltage: give the tachometer gain "
                "(--tach-gain, from 'motorlab analyze tachometer')"
            )
        return "tach_voltage"
    have = ", ".join(sorted(rec.signals)) or "none"
    raise LogFormatError(
        f"no speed column (velocity_rad_per_s, speed_rpm or tach_voltage_V; this file has: {have})",
        path=rec.source or None,
    )


def _slope(region: Region) -> float:
    design = np.column_stack([region.s, np.ones_like(region.s)])
    return float(fit_linear(design, region.speed, ["slope", "start"]).values[0])


def _slope_table(accel: list[Region], coasts: list[Region], gain: float) -> list[dict[str, float]]:
    rows = []
    by_pulse = {(c.source, c.pulse): c for c in coasts}
    for a in accel:
        c = by_pulse.get((a.source, a.pulse))
        if c is None:
            continue
        s1, s2 = _slope(a), _slope(c)
        if not s1 > s2:
            continue
        j = gain * (a.command - c.command) / (s1 - s2)
        rows.append(
            {"pulse": a.pulse, "accel_slope": s1, "coast_slope": s2, "J": j, "Tf": gain * c.command - j * s2}
        )
    return rows


def _panels(
    traces: list[tuple[Recording, np.ndarray, np.ndarray]],
    regions: list[Region],
    model_w: np.ndarray,
    table: dict[str, CoastFit],
    best: str,
    coasts: list[Region],
    chosen: str,
) -> list[Panel]:
    panels = []
    offset = 0
    fitted = {}
    for r in regions:
        fitted[(r.source, float(r.time[0]))] = model_w[offset : offset + r.time.size]
        offset += r.time.size
    for rec, t, speed in traces:
        model_full = np.full(t.size, np.nan)
        for r in regions:
            if r.source != rec.source:
                continue
            idx = np.searchsorted(t, r.time)
            model_full[idx] = fitted[(r.source, float(r.time[0]))]
        name = rec.source.rsplit("/", 1)[-1] if rec.source else ""
        panels.append(
            Panel(
                title=f"Angular velocity vs time {name}".strip(),
                x_label="time [s]",
                y_label="angular velocity Ω [rad/s]",
                data=Series(t, speed, "tachometer", "data"),
                model=Series(t, model_full, f"fit ({_MODEL_LABELS[chosen]} friction)", "model"),
                extra=[],
            )
        )
    # Coast-downs against the three friction models, time measured from the falling edge.
    xs, ys = [], []
    models: dict[str, list[np.ndarray]] = {m: [] for m in FRICTION_MODELS}
    for c in coasts:
        xs += [c.time - c.edge_time, np.array([np.nan])]
        ys += [c.speed, np.array([np.nan])]
    for m, cf in table.items():
        off = 0
        for c in coasts:
            pred = c.speed + cf.fit.residuals[off : off + c.time.size]
            off += c.time.size
            models[m] += [pred, np.array([np.nan])]
    x = np.concatenate(xs)
    labels = {"viscous": "viscous e^(−γt)", "coulomb": "Coulomb (straight line)", "both": "viscous + Coulomb"}
    panels.append(
        Panel(
            title="Coast-downs: which friction model? (best by BIC: " + best + ")",
            x_label="time since the falling edge [s]",
            y_label="angular velocity Ω [rad/s]",
            data=Series(x, np.concatenate(ys), "coast-downs", "data"),
            model=Series(x, np.concatenate(models[best]), labels[best] + " (best)", "model"),
            extra=[Series(x, np.concatenate(models[m]), labels[m], "model") for m in FRICTION_MODELS if m != best],
        )
    )
    return panels
