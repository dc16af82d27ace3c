"""The heating fit of locked-rotor runs (:mod:`motorlab.analyses.stall`): R₂₅, the thermal network, K.

Model (:mod:`motorlab.thermal.network`): each run holds its measured terminal voltage V(t) on the stalled
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
from dataclasses import dataclass, field, replace

import numpy as np

from motorlab.errors import FitError
from motorlab.estimation.least_squares import LeastSquares, fit_least_squares, fit_linear
from motorlab.thermal.network import COPPER_COEFFICIENT, ThermalModel, stall_response

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
    held: bool = False  # the network held at another fit's (the motor's other runs), not fitted to these runs
    winding_from_prior: bool = False  # R_wc·C_w held near the population's (no single network fits the run)


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
#: factor 1.50 either way (``benchmarks/bench_thermal.py --dyno DIR`` recomputes it, DIR holding kForth's exports
#: of the AndyMark 775 and BaneBots 550; and the prior of each motor from the others: 177–200 s). It replaced
#: 800 s (VEX's BAG 2 V run, where R_ca is not determined either).
PRIOR_CASE_TIME_CONSTANT = 186.0
PRIOR_LOG_SIGMA = 0.408
#: The winding's time constant R_wc·C_w a run whose own network is no motor's is held near [s], and the spread of
#: its logarithm: the geometric mean and spread of the 21 healthy runs' 120 s fits of VEX's nine motors
#: (docs/experiments/stall.md, "a winding slower than its case": 3–107 s).
PRIOR_WINDING_TIME_CONSTANT = 20.0
PRIOR_WINDING_LOG_SIGMA = 0.92
#: The heating fits stop when a step changes the cost or the (logarithmic) parameters by less than this, relative:
#: far below their standard errors (VEX's mini-CIM, CIM and BAG: K and R move in the fifth digit against scipy's
#: 1e-8), a third fewer simulations of the runs.
TOLERANCE = 1e-6


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


class _RelativeMisses:
    """The runs' relative misses of the current, (model − measured)/measured, for the shared figures and initial
    temperatures. Each run's is kept for the figures it was made with: a difference of the Jacobian in one run's
    initial temperature moves that run only, and the others' are those of the point it is taken at."""

    def __init__(self, runs: Sequence[StallData], magnet: float, ambient: float):
        self.runs, self.magnet, self.ambient = runs, magnet, ambient
        self.made: dict[tuple[int, bytes, float], np.ndarray] = {}

    def __call__(self, shared: Sequence[float], initial: Sequence[float]) -> np.ndarray:
        figures = np.asarray(shared, dtype=float).tobytes()
        parts = []
        for j, (run, t0) in enumerate(zip(self.runs, initial, strict=True)):
            key = (j, figures, t0)
            if key not in self.made:
                if len(self.made) >= 4 * len(self.runs):
                    self.made.clear()
                model = simulate_runs(shared, [t0], [run], self.magnet, self.ambient)[0][0]
                self.made[key] = (model - run.current) / run.current
            parts.append(self.made[key])
        return np.concatenate(parts)


def fit_heating(runs: Sequence[StallData], *, magnet: float, ambient: float, winding_prior: bool = False,
                network: Sequence[float] | None = None) -> HeatFit:
    """Fit R₂₅, the thermal network and each run's initial temperature to the runs' currents.

    ``winding_prior`` adds a prior on the winding's time constant R_wc·C_w (:data:`PRIOR_WINDING_TIME_CONSTANT`),
    for a run whose best network is no motor's (a winding slower than its case). ``network`` (R_wc, R_ca, C_w, C_c)
    holds the network at another fit's (the motor's other runs): only R₂₅ and the initial temperatures are fitted.

    Raises
    ------
    FitError
        With fewer samples than parameters.
    """
    r0 = [float(r.voltage[0] / r.current[0]) for r in runs]
    reference = reference_run(runs)
    free = [j for j in range(len(runs)) if j != reference]
    start = _guess(runs, reference, ambient)
    if network is not None:
        start = [start[0], *map(float, network)]
    t0_guess = [ambient + max(r0[j] / r0[reference] - 1, 0.0) / COPPER_COEFFICIENT for j in free]
    x0 = [*np.log(start), *t0_guess]
    names = [*SHARED, *(f"T0_{j}" for j in free)]
    lo = [math.log(BOUNDS[n][0]) for n in SHARED] + [ambient - 30.0] * len(free)
    hi = [math.log(BOUNDS[n][1]) for n in SHARED] + [ambient + 250.0] * len(free)
    x0 = list(np.clip(x0, np.array(lo) + 1e-9, np.array(hi) - 1e-9))
    # the parameters fitted: all, or R₂₅ and the initial temperatures with the network held
    active = [k for k in range(len(x0)) if network is None or not 1 <= k < len(SHARED)]
    held = np.asarray(x0, dtype=float)
    picks = [decimate(r.time) for r in runs]
    thin = [StallData(r.source, r.time[p], r.voltage[p], r.current[p], None) for r, p in zip(runs, picks, strict=True)]
    groups = np.concatenate([np.full(r.time.size, j) for j, r in enumerate(thin)])

    def whole(xa: np.ndarray) -> np.ndarray:
        x = held.copy()
        x[active] = xa
        return x

    def initial_of(x: np.ndarray) -> list[float]:
        t0 = [ambient] * len(runs)
        for k, j in enumerate(free):
            t0[j] = float(x[len(SHARED) + k])
        return t0

    relative = _RelativeMisses(thin, magnet, ambient)

    def residual(xa: np.ndarray) -> np.ndarray:
        x = whole(xa)
        return relative(np.exp(x[: len(SHARED)]), initial_of(x))

    if groups.size <= len(active):
        raise FitError(f"{groups.size} healthy samples cannot determine {len(active)} parameters")
    sub = [names[k] for k in active]
    bounds = ([lo[k] for k in active], [hi[k] for k in active])
    fit = fit_least_squares(residual, [x0[k] for k in active], sub, bounds=bounds, x_scale=[1.0] * len(active),
                            covariance="hac", groups=groups, max_nfev=200 * len(x0), tolerance=TOLERANCE)
    prior = False
    if network is None:
        # R_ca "from the prior" when the runs alone cannot tell it (too short for the case to approach its steady
        # rise); the prior on the case's time constant R_ca·C_c (the population of real motors) is applied in every
        # fit, weighted as one sample of the fit's own scatter: a 120 s run determines R_ca·C_c poorly even when it
        # bounds R_ca (VEX's NeveRest 6 V: 42 s ± 8 % from its first 120 s, 253 s from its whole 300 s).
        prior = _needs_prior(fit, hi)
        weight = max(fit.rmse, 1e-4) / PRIOR_LOG_SIGMA
        w_weight = max(fit.rmse, 1e-4) / PRIOR_WINDING_LOG_SIGMA

        def with_prior(x: np.ndarray) -> np.ndarray:
            out = np.append(residual(x), weight * (x[2] + x[4] - math.log(PRIOR_CASE_TIME_CONSTANT)))
            if winding_prior:
                out = np.append(out, w_weight * (x[1] + x[3] - math.log(PRIOR_WINDING_TIME_CONSTANT)))
            return out

        fit = fit_least_squares(with_prior, list(fit.values), names, bounds=(lo, hi), x_scale=[1.0] * len(x0),
                                covariance="hac", groups=np.append(groups, [len(runs)] * (1 + winding_prior)),
                                max_nfev=200 * len(x0), tolerance=TOLERANCE)
    else:
        fit = _expand(fit, active, held, names)
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
        held=network is not None,
    )


def _expand(fit: LeastSquares, active: list[int], held: np.ndarray, names: list[str]) -> LeastSquares:
    """A fit of some parameters as one of all: the held ones at their values, standard error 0, not determined by
    these runs."""
    n = held.size
    values, stderr, cov = held.copy(), np.zeros(n), np.zeros((n, n))
    values[active], stderr[active] = fit.values, fit.stderr
    cov[np.ix_(active, active)] = fit.covariance
    corr = np.eye(n)
    corr[np.ix_(active, active)] = fit.correlation
    determined = np.zeros(n, dtype=bool)
    determined[active] = fit.determined
    jac = np.zeros((fit.jacobian.shape[0], n))
    jac[:, active] = fit.jacobian
    return replace(fit, names=list(names), values=values, stderr=stderr, covariance=cov, correlation=corr,
                   determined=determined, jacobian=jac)


#: The forms of the torque model a fit chooses between: τ = K₂₅·(1 + β·(T_c − 25 °C))·i through the origin, or
#: with a torque offset τ₀ shared by the runs (an untared load cell, the lock's preload).
FORMS = ("origin", "offset")
#: Below this rise of the case temperature over the rows [K], β cannot be told from them: the magnets' own is used
#: (the correction it makes is then under |β|·ΔT, a few tenths of a percent).
BETA_SPAN = 5.0


@dataclass
class TorqueFit:
    """τ = K₂₅·(1 + β·(T_c − 25 °C))·i + τ₀: K and τ₀ with standard errors, β within the magnets' bound, and the
    torque per amp of each run under that model."""

    K: float
    K_stderr: float
    tau0: float
    tau0_stderr: float  # NaN when the form has no offset
    per_run: list[tuple[float, float, float]]  # (mean current [A], K of the run alone in the model [N·m/A], stderr)
    rmse: float
    model: list[np.ndarray | None]
    beta: float  # the temperature coefficient applied [1/K], within [magnet, 0]
    magnet: float = 0.0  # the magnets' coefficient: the bound on β [1/K]
    beta_stderr: float = math.nan  # NaN when β sits at a bound or is the magnets' own (not fitted)
    warning: str | None = None
    form: str = "origin"
    #: How the form was chosen, in words (the held-out runs' figures or the offset's z).
    selection: str = ""
    #: The between-run standard deviation of K (DerSimonian–Laird's τ) [N·m/A]; 0 when the runs agree.
    between: float = 0.0
    #: The pooled fit's K (all rows at once) and its standard error, beside the random-effects K above.
    pooled: tuple[float, float] = (math.nan, math.nan)
    refused: list[str] = field(default_factory=list)
    #: per run as ``per_run`` through the origin (τ/i, no offset taken off): what each run shows alone
    raw: list[tuple[float, float, float]] = field(default_factory=list)


@dataclass
class _Solved:
    K: float
    K_se: float
    beta: float
    beta_se: float
    tau0: float
    tau0_se: float
    resid: np.ndarray


def _solve(i: np.ndarray, tc: np.ndarray, y: np.ndarray, groups: np.ndarray, bound: float, offset: bool,
           beta: float | None = None) -> _Solved:
    """Least squares of τ = K·(1 + β·(T_c − 25))·i (+ τ₀) with β fixed, or fitted within [bound, 0] (the magnets
    weaken as they warm, by at most their material's coefficient; they never strengthen): the unconstrained fit when
    its β lies there, else the better of the two bounds (the constrained optimum of a convex quadratic lies on them)."""
    ones = [np.ones_like(i)] if offset else []
    names = ["K", "tau0"][: 1 + len(ones)]

    def fixed(b: float) -> _Solved:
        x = i * (1 + b * (tc - 25.0))
        fit = fit_linear(np.column_stack([x, *ones]), y, names, covariance="hac", groups=groups)
        t0, t0_se = (float(fit.values[1]), float(fit.stderr[1])) if offset else (0.0, math.nan)
        return _Solved(float(fit.values[0]), float(fit.stderr[0]), b, math.nan, t0, t0_se, fit.residuals)

    if beta is not None:
        return fixed(beta)
    if np.ptp(tc) < BETA_SPAN or i.size < 4 + len(ones):
        return fixed(bound)
    fit = fit_linear(np.column_stack([i, i * (tc - 25.0), *ones]), y, ["a", "c", *names[1:]], covariance="hac",
                     groups=groups)
    a, c = float(fit.values[0]), float(fit.values[1])
    if a > 0 and min(bound, 0.0) <= c / a <= max(bound, 0.0):
        grad = np.array([-c / a**2, 1 / a])
        b_se = float(np.sqrt(max(grad @ np.nan_to_num(fit.covariance[:2, :2]) @ grad, 0.0)))
        t0, t0_se = (float(fit.values[2]), float(fit.stderr[2])) if offset else (0.0, math.nan)
        return _Solved(a, float(fit.stderr[0]), c / a, b_se, t0, t0_se, fit.residuals)
    ends = [fixed(bound), fixed(0.0)]
    return min(ends, key=lambda s: float(np.sum(s.resid**2)))


def _held_out(i: np.ndarray, tc: np.ndarray, y: np.ndarray, groups: np.ndarray, bound: float, offset: bool) -> float:
    """Leave-one-run-out error of a form: each run's torque predicted by the form fitted to the other runs, as the
    RMS of (prediction − τ)/RMS(τ) over the run, then the RMS over the runs (each run weighs alike)."""
    scores = []
    for g in np.unique(groups):
        out = groups == g
        train = ~out
        s = _solve(i[train], tc[train], y[train], groups[train], bound, offset)
        pred = s.K * (1 + s.beta * (tc[out] - 25.0)) * i[out] + s.tau0
        scores.append(float(np.sqrt(np.mean((pred - y[out]) ** 2) / np.mean(y[out] ** 2))))
    return float(np.sqrt(np.mean(np.square(scores))))


def random_effects(values: Sequence[float], stderr: Sequence[float]) -> tuple[float, float, float, float]:
    """DerSimonian–Laird random-effects mean of per-run estimates: (mean, its standard error, the between-run
    standard deviation τ, Cochran's Q). τ² = max(0, (Q − (k − 1))/(Σw − Σw²/Σw)), w = 1/s²; the mean weighs each
    run by 1/(s² + τ²), so runs that disagree beyond their standard errors widen the mean's (DerSimonian & Laird,
    Controlled Clinical Trials 7 (1986) 177–188)."""
    k = np.asarray(values, dtype=float)
    s = np.maximum(np.asarray(stderr, dtype=float), 1e-12 * np.maximum(np.abs(k), 1e-30))
    w = 1 / s**2
    fixed = float(np.sum(w * k) / np.sum(w))
    q = float(np.sum(w * (k - fixed) ** 2))
    c = float(np.sum(w) - np.sum(w**2) / np.sum(w))
    tau2 = max(0.0, (q - (k.size - 1)) / c) if k.size > 1 and c > 0 else 0.0
    ws = 1 / (s**2 + tau2)
    return float(np.sum(ws * k) / np.sum(ws)), float(1 / math.sqrt(np.sum(ws))), math.sqrt(tau2), q


def fit_torque(runs: Sequence[StallData], case: Sequence[np.ndarray], magnet: float, *, offset: bool | None = None,
               beta: float | None = None, back_emf: tuple[float, float] | None = None) -> TorqueFit | None:
    """The torque constant from the runs' torque and current (None when no run measured torque).

    ``magnet`` is the magnets' coefficient, the bound on β (fitted within [magnet, 0] unless ``beta`` fixes it).
    ``offset`` None chooses the form: through the origin, or with a shared offset τ₀ (only when two runs or more
    span half the current range), by the held-out runs (three runs or more: the form that predicts each run's
    torque from the others' best) or, with two runs, by the offset's z (kept when ≥ 3; the caller widens its
    standard error with the heating model's first, :func:`motorlab.analyses.stall`). A form whose K lies above
    ``back_emf`` (the motor's back-EMF constant and its standard error, from a curve or a spin-down) by more than
    their combined uncertainty is refused, and said. K is the random-effects mean (DerSimonian–Laird) of the runs'
    K in the chosen form; the pooled fit's is kept beside it."""
    with_torque = [(run, tc) for run, tc in zip(runs, case, strict=True) if run.torque is not None]
    if not with_torque:
        return None
    i = np.concatenate([r.current for r, _ in with_torque])
    tc = np.concatenate([t for _, t in with_torque])
    y = np.concatenate([r.torque for r, _ in with_torque if r.torque is not None])
    groups = np.concatenate([np.full(r.current.size, j) for j, (r, _) in enumerate(with_torque)])
    # τ₀ only when two runs or more span at least half the current range: the contrast between runs at different
    # currents determines it. Over one run it is nearly collinear with K (the run's current and its case
    # temperature fall together) and takes K wherever the model's small systematic errors lead.
    x = i * (1 + magnet * (tc - 25.0))
    wide = len(with_torque) >= 2 and np.ptp(x) >= 0.5 * np.max(x)
    forms = [f for f in FORMS if (f == "offset") == bool(offset)] if offset is not None else (
        list(FORMS) if wide else ["origin"])
    solved = {f: _solve(i, tc, y, groups, magnet, f == "offset", beta) for f in forms}
    selection = ""
    if len(forms) > 1 and len(with_torque) >= 3:
        cv = {f: _held_out(i, tc, y, groups, magnet, f == "offset") for f in forms}
        order = sorted(forms, key=lambda f: cv[f])
        selection = (f"form chosen by the held-out runs (each run's torque predicted from the others): "
                     f"{'; '.join(f'{_FORM_WORDS[f]} misses by {100 * cv[f]:.2g} % RMS' for f in forms)}")
    elif len(forms) > 1:
        s = solved["offset"]
        order = ["offset", "origin"] if abs(s.tau0) > 3 * s.tau0_se else ["origin", "offset"]
        selection = (f"form chosen by the offset's z (two runs; the held-out test needs three): τ₀ = {s.tau0:.3g} ± "
                     f"{s.tau0_se:.1g} N·m, {abs(s.tau0) / s.tau0_se:.1f} standard errors")
    else:
        order = forms
    refused: list[str] = []
    chosen = order[0]
    if back_emf is not None and math.isfinite(back_emf[0]):
        ke, ke_se = back_emf
        fine = [f for f in order if solved[f].K - ke <= math.hypot(solved[f].K_se, ke_se if math.isfinite(ke_se)
                                                                      else 0.0)]
        for f in order:
            if f not in fine:
                refused.append(f"{_FORM_WORDS[f]} gives K = {solved[f].K:.4g} N·m/A, above the motor's back-EMF "
                               f"constant {ke:.4g} V·s/rad (which no shaft's torque per amp exceeds): refused")
            else:
                break
        chosen = fine[0] if fine else order[0]
    elif chosen == "offset" and "origin" in solved:
        # K above every run's own torque per amp (a negative τ₀) claims a motor stronger than any row shows: only a
        # back-EMF constant can confirm it; without one the form is refused (the rows contradict it)
        own = [r[1] for r in _per_run(with_torque, solved["offset"].beta, 0.0)]
        if solved["offset"].K > max(own):
            refused.append(f"{_FORM_WORDS['offset']} gives K = {solved['offset'].K:.4g} N·m/A with τ₀ = "
                           f"{solved['offset'].tau0:.3g} N·m, above every run's own torque per amp ({min(own):.4g}–"
                           f"{max(own):.4g}): the rows contradict it, and no back-EMF constant (a curve, "
                           "--back-emf) is given that could confirm it: refused")
            chosen = "origin"
    s = solved[chosen]
    warning = _beta_words(s, magnet) if beta is None else None
    per_run = _per_run(with_torque, s.beta, s.tau0)
    raw = _per_run(with_torque, s.beta, 0.0)
    usable = [r for r in per_run if math.isfinite(r[2])]
    if usable:
        k, k_se, between, _ = random_effects([r[1] for r in usable], [r[2] for r in usable])
    else:
        k, k_se, between = s.K, s.K_se, 0.0
    model: list[np.ndarray | None] = []
    for run, t in zip(runs, case, strict=True):
        model.append(None if run.torque is None else k * run.current * (1 + s.beta * (t - 25.0)) + s.tau0)
    resid = y - (k * i * (1 + s.beta * (tc - 25.0)) + s.tau0)
    return TorqueFit(k, k_se, s.tau0, s.tau0_se, per_run, float(np.sqrt(np.mean(resid**2))), model, s.beta, magnet,
                     s.beta_se, warning, chosen, selection, between, (s.K, s.K_se), refused, raw)


_FORM_WORDS = {"origin": "τ = K·i (no offset)", "offset": "τ = K·i + τ₀ (a shared torque offset)"}


def _beta_words(s: _Solved, bound: float) -> str | None:
    """A sentence when β is not the magnets' own: fitted between it and 0, or at 0 (the torque per amp does not fall
    as the case warms)."""
    if s.beta == bound:
        return None
    if s.beta == 0.0:
        return (f"the torque per amp does not fall as the case warms, as the magnets' {100 * bound:+.2f} %/K would "
                "make it (the current's own effect on the torque per amp as it falls, or a torque sensor that drifts "
                "as it warms): K is the torque per amp the rows show, with no temperature correction (β fitted within "
                f"[{100 * bound:+.2f}, 0] %/K, the magnets' bound, sits at 0)")
    return (f"the torque per amp falls {100 * s.beta:+.3f} ± {100 * s.beta_se:.2f} %/K with the case temperature "
            f"(fitted within the magnets' bound [{100 * bound:+.2f}, 0] %/K); K at 25 °C applies it")


def _per_run(runs: Sequence[tuple[StallData, np.ndarray]], beta: float,
             offset: float) -> list[tuple[float, float, float]]:
    """(mean current [A], K of the run [N·m/A], its HAC standard error) per run: (τ − offset) against
    x = i·(1 + β·(T_c − 25 °C)), with a term i·(i₀ − i) when the run's torque per amp rises as its current falls
    (:func:`_drift`): K is then the run's torque per amp at its start, the rise left out."""
    out = []
    for run, t in runs:
        assert run.torque is not None
        x = run.current * (1 + beta * (t - 25.0))
        y = run.torque - offset
        if x.size < 4:
            out.append((float(np.mean(run.current)), float(np.sum(x * y) / np.sum(x * x)), math.nan))
            continue
        drift = _drift(run.current, t, x, y)
        if drift is None:
            fit = fit_linear(x[:, None], y, ["K"], covariance="hac")
            drift = (float(fit.values[0]), float(fit.stderr[0]), 0.0)
        out.append((float(np.mean(run.current)), drift[0], drift[1]))
    return out


def _drift(i: np.ndarray, tc: np.ndarray, x: np.ndarray, y: np.ndarray) -> tuple[float, float, float] | None:
    """(K, its standard error, γ [N·m/A²]) of y = K·x + γ·i·(i₀ − i), i₀ the run's first current, when the case warms
    by :data:`BETA_SPAN` or more and γ > 0: the torque per amp rises as the current falls through the run (the
    current's own effect: less armature reaction, a larger share of brush friction, or a torque sensor drifting as
    it warms). Magnets only weaken as they warm, so the rise is not K: K is the run's torque per amp at its start.
    None otherwise."""
    if np.ptp(tc) < BETA_SPAN:
        return None
    fit = fit_linear(np.column_stack([x, i * (i[0] - i)]), y, ["K", "gamma"], covariance="hac")
    if not fit.values[1] > 0:
        return None
    return float(fit.values[0]), float(fit.stderr[0]), float(fit.values[1])


def _listing(rows: Sequence[tuple[float, float, float]]) -> str:
    return ", ".join(f"{r[1]:.4g} ± {r[2]:.1g} at {r[0]:.3g} A" for r in rows)


def current_dependence(tq: TorqueFit) -> str | None:
    """The runs' K beside the joint one, in words (None for one run): whether they disagree beyond their standard
    errors (then K's standard error includes the between-run scatter) with the likely cause from how K goes with
    the current; the form kept and why; a refused form."""
    rows = sorted((r for r in tq.per_run if math.isfinite(r[2])), key=lambda r: r[0])
    parts = []
    if tq.form == "offset":
        parts.append(f"the torque reads {tq.tau0:.3g} ± {tq.tau0_stderr:.1g} N·m at zero current (the intercept of the "
                     "runs' torque against their current): an untared load cell or the lock's preload on the torque "
                     "channel, or the curve of saturation; K is the slope")
    if tq.selection:
        parts.append(tq.selection)
    parts.extend(tq.refused)
    if len(rows) >= 2:
        how = " once the offset is taken off" if tq.form == "offset" else ""
        if tq.between > 0:
            lo, hi = min(rows, key=lambda r: r[1]), max(rows, key=lambda r: r[1])
            trend = float(np.corrcoef([r[0] for r in rows], [r[1] for r in rows])[0, 1]) if len(rows) > 2 else (
                1.0 if rows[-1][1] > rows[0][1] else -1.0)
            cause = ("falling as the current rises: saturation of the iron (armature reaction) at high current"
                     if trend < 0 else "rising with the current: brush friction taking a larger share of the torque "
                     "at low current")
            parts.append(f"the torque per amp changes between runs beyond its uncertainty{how}, from {lo[1]:.4g} to "
                         f"{hi[1]:.4g} N·m/A ({100 * (hi[1] - lo[1]) / lo[1]:.0f} %), {cause}; each run's K, by mean "
                         f"current: {_listing(rows)}; K = {tq.K:.4g} ± {tq.K_stderr:.2g} N·m/A is their random-effects "
                         f"mean (DerSimonian–Laird: a between-run spread of {tq.between:.2g} N·m/A is in its standard "
                         "error)")
        else:
            parts.append(f"each run's K{how}, by mean current: {_listing(rows)}: they agree within their standard "
                         f"errors; K = {tq.K:.4g} ± {tq.K_stderr:.2g} N·m/A is their inverse-variance mean")
    return "; ".join(parts) if parts else None
