"""The heating fit of locked-rotor runs (:mod:`motorlab.analyses.stall`): R₂₅, the thermal network, K.

Model (:mod:`motorlab.thermal`): each run holds its measured terminal voltage V(t) on the stalled
winding, i = V/R(T_w), the heat V·i flows through winding → case → ambient. Shared by all runs:
R₂₅, R_wc, R_ca, C_w, C_c; each run has its own initial temperature T₀ (winding and case alike: a
motor that rested), except the reference run (the coolest: lowest V/I at its first full sample), which
starts at the ambient temperature — one run's T₀ and R₂₅ cannot be told apart (only R(T₀) is seen).
Residuals are relative, (i_model − i)/i, so runs at 10 A and at 90 A weigh alike; the covariance is
Newey–West (HAC) per run, as the residuals of a real run are serially correlated.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from motorlab.errors import FitError
from motorlab.fitting import LeastSquares, fit_least_squares, fit_linear
from motorlab.thermal import COPPER_COEFFICIENT, ThermalModel, stall_response

#: Names of the shared parameters, in the fit's order (fitted as logarithms).
SHARED = ("R", "R_wc", "R_ca", "C_w", "C_c")
#: Bounds of the shared parameters [Ω, K/W, K/W, J/K, J/K]: any motor from a micro-motor to a CIM.
BOUNDS = {"R": (1e-3, 1e3), "R_wc": (1e-3, 100.0), "R_ca": (1e-2, 300.0), "C_w": (0.05, 2e4), "C_c": (0.1, 2e5)}


@dataclass
class StallData:
    """One run's healthy part: times [s] since the supply switched on (the run's first row), voltage [V],
    current [A], torque [N·m] or None; ``offset`` is the file's time of that first row [s]."""

    source: str
    time: np.ndarray
    voltage: np.ndarray
    current: np.ndarray
    torque: np.ndarray | None
    offset: float = 0.0  # the run's own time of its first full sample [s]


@dataclass
class HeatFit:
    """The outcome of :func:`fit_heating`."""

    values: dict[str, float]
    stderr: dict[str, float]
    initial: list[float]  # T₀ of each run [°C]
    initial_stderr: list[float]
    reference: int
    fit: LeastSquares
    thermal: ThermalModel
    model_current: list[np.ndarray]
    winding: list[np.ndarray]
    case: list[np.ndarray]
    run_rms: list[float]  # relative RMS residual per run [-]
    log_covariance: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    prior: bool = False  # R_ca from the prior on the case's time constant (the runs could not tell it)


def _thermal(values: Sequence[float], magnet: float, ambient: float) -> ThermalModel:
    return ThermalModel(winding_to_case=values[1], case_to_ambient=values[2], winding_capacity=values[3],
                        case_capacity=values[4], magnet_coefficient=magnet, ambient_temperature=ambient)


def simulate_runs(shared: Sequence[float], initial: Sequence[float], runs: Sequence[StallData], magnet: float,
                  ambient: float) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Model current, winding and case temperatures of each run (heating from the supply's switch-on at
    time 0, before the first full sample)."""
    th = _thermal(shared, magnet, ambient)
    out = []
    for run, t0 in zip(runs, initial, strict=True):
        lead = run.time.size and run.time[0] > 0
        time = np.concatenate([[0.0], run.time]) if lead else run.time
        volts = np.concatenate([run.voltage[:1], run.voltage]) if lead else run.voltage
        r = stall_response(shared[0], th, time, volts, winding=t0)
        k = 1 if lead else 0
        out.append((r.current[k:], r.winding_temperature[k:], r.case_temperature[k:]))
    return out


#: The fit keeps every sample of a run's first seconds, then one sample each time the run's time has grown
#: by this fraction (the heating slows as the run goes on): ~150 samples for a 300 s run.
DECIMATE_GROWTH = 0.03
#: ... and every sample while the run is younger than this [s].
DECIMATE_DENSE = 5.0


def decimate(time: np.ndarray) -> np.ndarray:
    """Indices of the samples the heating fit uses (all of the first seconds, then geometrically sparser)."""
    keep = [0]
    nxt = 0.0
    for k, t in enumerate(time.tolist()):
        if k and t >= nxt:
            keep.append(k)
        if k == 0 or t >= nxt:
            nxt = t + max(DECIMATE_GROWTH * t, 0.0) if t >= DECIMATE_DENSE else 0.0
    if keep[-1] != time.size - 1:
        keep.append(time.size - 1)
    return np.asarray(keep, dtype=int)


def _guess(runs: Sequence[StallData], reference: int, ambient: float) -> list[float]:
    """Starting values: R from the reference run's first sample, C_w from the hottest run's first seconds."""
    ref = runs[reference]
    r25 = float(ref.voltage[0] / ref.current[0]) / (1 + COPPER_COEFFICIENT * (ambient - 25.0))
    c_w = 50.0
    best = max(runs, key=lambda r: float(r.voltage[0] * r.current[0]))
    k = int(np.searchsorted(best.time, min(best.time[-1], 5.0)))
    if k >= 2:
        res = best.voltage[: k + 1] / best.current[: k + 1]
        slope = float(np.polyfit(best.time[: k + 1], res, 1)[0])
        if slope > 0:
            c_w = float(best.voltage[0] * best.current[0]) * COPPER_COEFFICIENT * float(res[0]) / slope
    c_w = float(np.clip(c_w, 1.0, 5e3))
    return [r25, 0.5, 2.0, c_w, 6.0 * c_w]


#: The case's time constant R_ca·C_c the prior (in every fit) pulls towards [s], and the
#: prior's spread (the standard deviation of its logarithm): an empirical prior, the geometric mean and spread
#: of R_ca·C_c over a population of real motors, the 14 healthy 2–7.2 V locked-rotor runs of eight motors
#: (VEX's dynamometer exports of the mini-CIM, BAG, AndyMark 9015, 775pro, AndyMark 775, BaneBots 550, CIM and
#: NeveRest) whose whole run (up to 300 s) determines R_ca, each fitted alone: 80–358 s, geometric mean 186 s, a
#: factor 1.50 either way (``benchmarks/bench_thermal.py`` recomputes it, and the prior of each motor from the
#: others: 177–200 s). It replaced 800 s (VEX's BAG 2 V run, where R_ca is not determined either).
PRIOR_CASE_TIME_CONSTANT = 186.0
PRIOR_LOG_SIGMA = 0.408


def _needs_prior(fit: LeastSquares, hi: Sequence[float]) -> bool:
    """R_ca is undetermined, uncertain by more than a factor e, or at its upper bound."""
    k = SHARED.index("R_ca")
    return bool(not fit.determined[k] or not fit.stderr[k] < 1.0 or fit.values[k] > hi[k] - 0.05)


#: A run needs this many healthy samples to be the reference (its first sample must be a settled one).
REFERENCE_SAMPLES = 30


def reference_run(runs: Sequence[StallData]) -> int:
    """The coolest run: the lowest V/I at its first full sample among runs of at least
    :data:`REFERENCE_SAMPLES` healthy samples (else among all)."""
    r0 = np.array([float(r.voltage[0] / r.current[0]) for r in runs])
    long_enough = np.array([r.time.size >= REFERENCE_SAMPLES for r in runs])
    if long_enough.any():
        r0 = np.where(long_enough, r0, np.inf)
    return int(np.argmin(r0))


def fit_heating(runs: Sequence[StallData], *, magnet: float, ambient: float) -> HeatFit:
    """Fit R₂₅, the thermal network and each run's initial temperature to the runs' currents.

    Raises
    ------
    FitError
        With fewer samples than parameters.
    """
    r0 = [float(r.voltage[0] / r.current[0]) for r in runs]
    reference = reference_run(runs)
    free = [j for j in range(len(runs)) if j != reference]
    start = _guess(runs, reference, ambient)
    t0_guess = [ambient + max(r0[j] / r0[reference] - 1, 0.0) / COPPER_COEFFICIENT for j in free]
    x0 = [*np.log(start), *t0_guess]
    names = [*SHARED, *(f"T0_{j}" for j in free)]
    lo = [math.log(BOUNDS[n][0]) for n in SHARED] + [ambient - 30.0] * len(free)
    hi = [math.log(BOUNDS[n][1]) for n in SHARED] + [ambient + 250.0] * len(free)
    x0 = list(np.clip(x0, np.array(lo) + 1e-9, np.array(hi) - 1e-9))
    picks = [decimate(r.time) for r in runs]
    thin = [StallData(r.source, r.time[p], r.voltage[p], r.current[p], None) for r, p in zip(runs, picks, strict=True)]
    meas = [r.current for r in thin]
    groups = np.concatenate([np.full(r.time.size, j) for j, r in enumerate(thin)])

    def initial_of(x: np.ndarray) -> list[float]:
        t0 = [ambient] * len(runs)
        for k, j in enumerate(free):
            t0[j] = float(x[len(SHARED) + k])
        return t0

    def residual(x: np.ndarray) -> np.ndarray:
        sims = simulate_runs(np.exp(x[: len(SHARED)]), initial_of(x), thin, magnet, ambient)
        return np.concatenate([(s[0] - m) / m for s, m in zip(sims, meas, strict=True)])

    if groups.size <= len(x0):
        raise FitError(f"{groups.size} healthy samples cannot determine {len(x0)} parameters")
    fit = fit_least_squares(residual, x0, names, bounds=(lo, hi), x_scale=[1.0] * len(x0), covariance="hac",
                            groups=groups, max_nfev=200 * len(x0))
    # R_ca "from the prior" when the runs alone cannot tell it (too short for the case to approach its steady
    # rise); the prior on the case's time constant R_ca·C_c (the population of real motors) is applied in every
    # fit, weighted as one sample of the fit's own scatter: a 120 s run determines R_ca·C_c poorly even when it
    # bounds R_ca (VEX's NeveRest 6 V: 42 s ± 8 % from its first 120 s, 253 s from its whole 300 s).
    prior = _needs_prior(fit, hi)
    weight = max(fit.rmse, 1e-4) / PRIOR_LOG_SIGMA

    def with_prior(x: np.ndarray) -> np.ndarray:
        return np.append(residual(x), weight * (x[2] + x[4] - math.log(PRIOR_CASE_TIME_CONSTANT)))

    fit = fit_least_squares(with_prior, list(fit.values), names, bounds=(lo, hi), x_scale=[1.0] * len(x0),
                            covariance="hac", groups=np.append(groups, len(runs)), max_nfev=200 * len(x0))
    shared = np.exp(fit.values[: len(SHARED)])
    t0 = initial_of(fit.values)
    sims = simulate_runs(shared, t0, runs, magnet, ambient)
    se_log = fit.stderr[: len(SHARED)]
    t0_se = [0.0] * len(runs)
    for k, j in enumerate(free):
        t0_se[j] = float(fit.stderr[len(SHARED) + k])
    rms = [float(np.sqrt(np.mean(((s[0] - r.current) / r.current) ** 2))) for s, r in zip(sims, runs, strict=True)]
    return HeatFit(
        prior=prior,
        values=dict(zip(SHARED, map(float, shared), strict=True)),
        stderr={n: float(v * s) for n, v, s in zip(SHARED, shared, se_log, strict=True)},
        initial=t0, initial_stderr=t0_se, reference=reference, fit=fit,
        thermal=_thermal(shared, magnet, ambient),
        model_current=[s[0] for s in sims], winding=[s[1] for s in sims], case=[s[2] for s in sims],
        run_rms=rms, log_covariance=fit.covariance[: len(SHARED), : len(SHARED)],
    )


@dataclass
class TorqueFit:
    """τ = K₂₅·(1 + β·(T_c − 25 °C))·i + τ₀: K and τ₀ with standard errors, and per-run torque per amp."""

    K: float
    K_stderr: float
    tau0: float
    tau0_stderr: float
    per_run: list[tuple[float, float, float]]  # (mean current [A], torque per amp [N·m/A], its stderr) per run
    rmse: float
    model: list[np.ndarray | None]
    beta: float  # the magnets' coefficient applied [1/K] (0: not applied, see ``warning``)
    warning: str | None = None
    #: per run as ``per_run``, of (τ − τ₀)/i: the torque per amp once the offset is taken off (τ₀ fitted)
    per_run_net: list[tuple[float, float, float]] = field(default_factory=list)


def _beta_check(i: np.ndarray, tc: np.ndarray, y: np.ndarray, groups: np.ndarray, beta: float) -> str | None:
    """None when the torque per amp falls with the case temperature as the magnets' β says (or the runs do
    not warm the case enough to tell); else why β is not applied."""
    if np.ptp(tc) < 10.0 or i.size < 6:
        return None
    design = np.column_stack([i, i * (tc - 25.0), np.ones_like(i)])
    fit = fit_linear(design, y, ["a", "c", "tau0"], covariance="hac", groups=groups)
    a, c = fit.values[0], fit.values[1]
    cov = fit.covariance[:2, :2]
    grad = np.array([-c / a**2, 1 / a])
    se = float(np.sqrt(max(grad @ cov @ grad, 0.0)))
    fitted = c / a
    if abs(fitted - beta) <= 3 * se + 5e-4:
        return None
    return (f"the torque per amp does not follow the magnets' {100 * beta:+.2f} %/K with the case temperature: "
            f"these runs give {100 * fitted:+.2f} ± {100 * se:.2f} %/K (the current's own effect on the torque "
            "per amp, or a torque sensor that drifts as it warms); K is fitted at the runs' temperatures, without the "
            "magnets' coefficient")


def fit_torque(runs: Sequence[StallData], case: Sequence[np.ndarray], magnet: float, *, offset: bool = True,
               check: bool = True) -> TorqueFit | None:
    """The torque constant from the runs' torque and current (None when no run measured torque).

    ``offset=False`` never fits τ₀; ``check=False`` applies ``magnet`` as it is (no test of the magnets'
    coefficient against the runs)."""
    with_torque = [(run, tc) for run, tc in zip(runs, case, strict=True) if run.torque is not None]
    if not with_torque:
        return None
    i = np.concatenate([r.current for r, _ in with_torque])
    tc = np.concatenate([t for _, t in with_torque])
    y = np.concatenate([r.torque for r, _ in with_torque if r.torque is not None])
    groups = np.concatenate([np.full(r.current.size, j) for j, (r, _) in enumerate(with_torque)])
    warning = _beta_check(i, tc, y, groups, magnet) if check else None
    beta = 0.0 if warning else magnet
    x = i * (1 + beta * (tc - 25.0))
    per_run = _per_run(with_torque, beta, 0.0)
    # τ = K·i at a held shaft; the intercept τ₀ (sensor offset, friction held, the curvature of saturation)
    # only when two runs or more span at least half the current range: the contrast between runs at different
    # currents determines it. Over one run it is nearly collinear with K (the run's current and its case
    # temperature fall together) and takes K wherever the model's small systematic errors lead; a per-run
    # offset would make every run such a case (on VEX's exports, K from the runs' own slopes scatters by a
    # factor of 2, from 40 % below to 35 % above the makers' figures).
    wide = offset and len(with_torque) >= 2 and np.ptp(x) >= 0.5 * np.max(x)
    design = np.column_stack([x, np.ones_like(x)]) if wide else x[:, None]
    fit = fit_linear(design, y, ["K", "tau0"][: design.shape[1]], covariance="hac", groups=groups)
    tau0, tau0_se = (float(fit.values[1]), float(fit.stderr[1])) if wide else (0.0, math.nan)
    model: list[np.ndarray | None] = []
    for run, t in zip(runs, case, strict=True):
        model.append(None if run.torque is None else fit.values[0] * run.current * (1 + beta * (t - 25.0)) + tau0)
    resid = y - (fit.values[0] * x + tau0)
    return TorqueFit(float(fit.values[0]), float(fit.stderr[0]), tau0, tau0_se,
                     per_run, float(np.sqrt(np.mean(resid**2))), model, beta, warning,
                     _per_run(with_torque, beta, tau0) if wide else [])


def _per_run(runs: Sequence[tuple[StallData, np.ndarray]], beta: float,
             offset: float) -> list[tuple[float, float, float]]:
    """(mean current [A], mean of (τ − offset)/(i·(1 + β·(T_c − 25 °C))) [N·m/A], its standard error) per run."""
    out = []
    for run, t in runs:
        assert run.torque is not None
        k = (run.torque - offset) / (run.current * (1 + beta * (t - 25.0)))
        n_eff = max(k.size / 10.0, 1.0)  # neighbouring samples are far from independent
        out.append((float(np.mean(run.current)), float(np.mean(k)),
                    float(np.std(k, ddof=1) / math.sqrt(n_eff)) if k.size > 1 else math.nan))
    return out


def _spread(per_run: Sequence[tuple[float, float, float]]) -> tuple[list[tuple[float, float, float]], bool]:
    """The runs sorted by current, and whether their torque per amp differs beyond its uncertainty (and 3 %)."""
    rows = sorted((r for r in per_run if math.isfinite(r[2])), key=lambda r: r[0])
    if len(rows) < 2:
        return rows, False
    lo, hi = min(rows, key=lambda r: r[1]), max(rows, key=lambda r: r[1])
    diff = hi[1] - lo[1]
    return rows, bool(diff > 3 * math.hypot(lo[2], hi[2]) and diff > 0.03 * abs(lo[1]))


def _listing(rows: Sequence[tuple[float, float, float]]) -> str:
    return ", ".join(f"{r[1]:.4g} at {r[0]:.3g} A" for r in rows)


def current_dependence(tq: TorqueFit) -> str | None:
    """A sentence when the torque per amp of the runs differs beyond its uncertainty (else None), with the
    likely cause from how it goes with the current; when the runs determine a torque offset τ₀ (the torque
    read at zero current), what it is and whether it accounts for the difference."""
    rows, differs = _spread(tq.per_run)
    offset = bool(tq.per_run_net) and abs(tq.tau0) > 3 * tq.tau0_stderr
    if not offset:
        return _dependence(rows) if differs else None
    net, still = _spread(tq.per_run_net)
    text = (f"the torque reads {tq.tau0:.3g} ± {tq.tau0_stderr:.1g} N·m at zero current (the intercept of the runs' "
            "torque against their current): an untared load cell or the lock's preload on the torque channel, or the "
            "curve of saturation; K is the slope")
    if still:
        return f"{text}; {_dependence(net, ' once that offset is taken off')}"
    if differs:
        text += (f"; their torque per amp τ/i ({_listing(rows)}) changes with the current as such an offset makes it, "
                 f"and agrees once it is taken off ({_listing(net)})")
    return text


def _dependence(rows: Sequence[tuple[float, float, float]], how: str = "") -> str:
    lo, hi = min(rows, key=lambda r: r[1]), max(rows, key=lambda r: r[1])
    diff = hi[1] - lo[1]
    trend = float(np.corrcoef([r[0] for r in rows], [r[1] for r in rows])[0, 1]) if len(rows) > 2 else (
        1.0 if rows[-1][1] > rows[0][1] else -1.0)
    cause = ("falling as the current rises: saturation of the iron (armature reaction) at high current" if trend < 0
             else "rising with the current: brush friction taking a larger share of the torque at low current")
    return (f"the torque per amp changes between runs beyond its uncertainty{how}, from {lo[1]:.4g} ± {lo[2]:.1g} to "
            f"{hi[1]:.4g} ± {hi[2]:.1g} N·m/A ({100 * diff / lo[1]:.0f} %; by mean current: {_listing(rows)}), "
            f"{cause}; K above is the fit over all currents")
