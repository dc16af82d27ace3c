"""The fair score of a feedforward gain set on a SysId log: open-loop simulation from the logged voltage.

Each test (both sides of a drivetrain count as tests of their own) is simulated from the voltage it
logged, held per row, starting from the logged speed at the test's first row:

    kA·dv/dt = V − kS·sgn(v) − kV·v,      dx/dt = v,      x(t₀) = logged first position,

and the score is the RMSE, over every row of every test, of (a) the simulated speed against the
logged speed and (b) the simulated position against the logged position
(``shared/data/real/sysid/README.md``). The simulation is exact for a voltage held between rows: the
speed relaxes exponentially towards (V − kS·s)/kV with τ = kA/kV between sign events, and a shaft
that reaches zero speed stays at rest while |V| ≤ kS (static friction), so no step size enters the
score. A negative kS (as some teams' own fits give) simply pushes away from rest.

The score sees only (kS, kV, kA): it is what a three-gain feedforward pasted into robot code does
with the logged commands. :func:`fit_gains` finds the three gains that minimise it (an output-error
fit, each score weighed by its own size) — see docs/real-logs.md.
"""

from __future__ import annotations

import itertools
import math
import os
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np

from motorlab import progress
from motorlab.errors import FitError, OptionError
from motorlab.recording import Recording

#: kS [V], kV, kA as a sequence or an array.
Gains = Sequence[float] | np.ndarray

#: Largest exponent range handled in one vectorised block of the linear recursion: the exponentials
#: are taken about the block's middle, e^(±650) within a double's range (e^709) with room for the speeds.
_BLOCK_EXPONENT = 1300.0
#: A step of at least this many time constants settles within itself (e^(−400) is below a double's precision).
_STIFF_EXPONENT = 400.0


@dataclass(frozen=True)
class ScoreTest:
    """One test of one side: time [s], held voltage [V], logged position and speed (SI: rad or m)."""

    name: str
    time: np.ndarray
    voltage: np.ndarray
    position: np.ndarray
    velocity: np.ndarray
    start: float = 0.0  # the log's own time of the first row [s] (``time`` counts from it)


@dataclass(frozen=True)
class Score:
    """RMSE of the open-loop simulation against the logged speed [unit/s] and position [unit]."""

    speed: float
    position: float

    def ratio(self, other: Score) -> tuple[float, float]:
        """(speed, position) RMSE of this score over ``other``'s."""
        return self.speed / other.speed, self.position / other.position


def score_tests(recordings: Recording | Iterable[Recording]) -> list[ScoreTest]:
    """The tests of SysId recordings (one per ``Recording.split()`` part) as :class:`ScoreTest`.

    Raises
    ------
    OptionError
        A part without ``voltage``, ``position`` and ``velocity`` or with fewer than 3 rows.
    """
    recs = [recordings] if isinstance(recordings, Recording) else list(recordings)
    tests = []
    for rec in recs:
        for part in rec.split():
            if not part.has("voltage", "position", "velocity") or len(part) < 3:
                raise OptionError(f"{part.source or 'recording'}: the score needs voltage, position and velocity rows")
            name = part.metadata.get("segment") or part.source
            tests.append(ScoreTest(str(name), part.time - part.time[0], part["voltage"], part["position"],
                                   part["velocity"], float(part.time[0])))
    return tests


def file_tests(path: str | os.PathLike[str]) -> list[ScoreTest]:
    """The tests of a SysId or frc-characterization JSON file in the file's own units (rows × unitsPerRotation).

    Both sides of a drivetrain are read, each test and side one :class:`ScoreTest`.
    """
    from motorlab.io import read_any

    rec = read_any(path, side="both")
    unit = float(rec.metadata.get("si_per_unit", 1.0))
    return [ScoreTest(t.name, t.time, t.voltage, t.position / unit, t.velocity / unit) for t in score_tests(rec)]


def score_file(path: str | os.PathLike[str], gains: Gains) -> Score:
    """The fair score of (kS [V], kV [V/(unit/s)], kA [V/(unit/s²)]), in the file's own units, on a JSON log."""
    return score(gains, file_tests(path))


def _linear_steps(
    v0: float, dt: np.ndarray, u: np.ndarray, tau: float
) -> tuple[np.ndarray, np.ndarray, tuple[np.ndarray, np.ndarray, np.ndarray | None] | None]:
    """Speeds after each step and the distance of each step of τ·v' = u − v from v0 (no sign event), and what
    their sensitivities reuse (:func:`_block_sensitivity`): dt/τ, e^(−dt/τ) and the block's e^c (None without τ)."""
    if tau <= 0.0:
        v = u.copy()
        return v, u * dt, None
    x = dt / tau
    a = np.exp(-x)  # (−dt/τ is −(dt/τ) exactly)
    if dt.size == 1:  # one step (possibly of many time constants): directly
        v_end = a * v0 + (1.0 - a) * u
        return v_end, u * dt + (v0 - u) * tau * (1.0 - a), (x, a, None)
    c = np.concatenate([[0.0], np.cumsum(x)])
    c -= 0.5 * c[-1]  # about the middle: e^c stays within range over a block of Σ dt/τ ≤ _BLOCK_EXPONENT
    # v_i = e^(−c_i)·(v0·e^(c_0) + Σ_{j<i} (e^(c_{j+1}) − e^(c_j))·u_j): v_{j+1} = a_j·v_j + (1 − a_j)·u_j
    e = np.exp(c)
    acc = v0 * e[0] + np.cumsum((e[1:] - e[:-1]) * u)
    v = acc / e[1:]
    v_start = np.concatenate([[v0], v[:-1]])
    return v, u * dt + (v_start - u) * tau * (1.0 - a), (x, a, e)


def simulate_gains(ks: float, kv: float, ka: float, test: ScoreTest) -> tuple[np.ndarray, np.ndarray]:
    """Simulated speed and position at the test's rows (see the module notes)."""
    speed, position, _ = _simulate(ks, kv, ka, test, sensitivity=False)
    return speed, position


def simulate_sensitivity(
    ks: float, kv: float, ka: float, test: ScoreTest
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`simulate_gains` with the derivatives of the speed and position, each (3 × rows), in
    (kS, ln kV, ln kA): the sensitivity equations of the same exact solution, see :func:`_block_sensitivity`."""
    speed, position, derivatives = _simulate(ks, kv, ka, test, sensitivity=True)
    assert derivatives is not None
    return speed, position, derivatives[0], derivatives[1]


def _simulate(
    ks: float, kv: float, ka: float, test: ScoreTest, *, sensitivity: bool
) -> tuple[np.ndarray, np.ndarray, tuple[np.ndarray, np.ndarray] | None]:
    """Speed, position and (with ``sensitivity``) their derivatives in (kS, ln kV, ln kA)."""
    t, volts = test.time, test.voltage
    n = t.size
    dt = np.diff(t)
    tau = ka / kv
    speed = np.zeros(n)
    step_dist = np.zeros(max(n - 1, 0))
    speed[0] = test.velocity[0]
    d_speed = np.zeros((3, n if sensitivity else 0))  # (kS, ln kV, ln kA) × rows
    d_dist = np.zeros((3, max(n - 1, 0) if sensitivity else 0))
    threshold = max(ks, 0.0)
    ordered = bool(np.all(dt >= 0.0))  # (readers refuse time going backwards; the score does not rely on it)
    k = 0
    while k < n - 1:
        v = speed[k]
        if v == 0.0:
            free = np.flatnonzero(np.abs(volts[k:n - 1]) > threshold)
            if free.size == 0:
                break  # at rest to the end
            k += int(free[0])  # speed and distance stay 0 until then
            s = math.copysign(1.0, volts[k])
        else:
            s = math.copysign(1.0, v)
        stop, stiff = n - 1, False
        if tau > 0:  # one block at a time: the exponentials stay within range
            if ordered:  # Σ dt/τ from row k is (t − t_k)/τ: the block's end found by bisection
                span = int(np.searchsorted(t, t[k] + _BLOCK_EXPONENT * tau)) - k - 1
            else:
                span = _block_span(dt, k, tau)
            stiff = dt[k] >= _STIFF_EXPONENT * tau  # rows each of many time constants: each settles
            stop = min(n - 1, k + (_stiff_span(dt, k, tau) if stiff else max(span, 1)))
        u = (volts[k:stop] - ks * s) / kv
        shared = None
        if stiff:
            v_new, dist = _stiff_block(v, dt[k:stop], u, tau)
        else:
            v_new, dist, shared = _linear_steps(v, dt[k:stop], u, tau)
        if sensitivity:
            w_new, dd = _block_sensitivity(v, d_speed[:, k], dt[k:stop], u, tau, s / kv, v_new, stiff, shared)
        cross = np.flatnonzero(s * v_new <= 0.0)
        j = int(cross[0]) if cross.size else stop - k
        speed[k + 1:k + j + 1] = v_new[:j]
        step_dist[k:k + j] = dist[:j]
        if sensitivity:
            d_speed[:, k + 1:k + j + 1] = w_new[:, :j]
            d_dist[:, k:k + j] = dd[:, :j]
        k += j
        if not cross.size:
            continue
        stop_args = (speed[k], dt[k], volts[k], s, ks, kv, ka)
        speed[k + 1], step_dist[k] = _stop_within_step(*_stop_inputs(*stop_args))
        if sensitivity:
            d_speed[:, k + 1], d_dist[:, k] = _stop_sensitivity(d_speed[:, k], *stop_args)
        k += 1
    position = test.position[0] + np.concatenate([[0.0], np.cumsum(step_dist)])
    if not sensitivity:
        return speed, position, None
    return speed, position, (d_speed, np.concatenate([np.zeros((3, 1)), np.cumsum(d_dist, axis=1)], axis=1))


def _stop_inputs(
    v: float, dt: float, volts: float, s: float, ks: float, kv: float, ka: float
) -> tuple[float, float, float, float, float, float, float, float]:
    """The arguments of :func:`_stop_within_step` for the step from speed ``v`` in direction ``s``."""
    return v, (volts - ks * s) / kv, dt, ka / kv, volts, ks, kv, max(ks, 0.0)


def _stop_sensitivity(
    w: np.ndarray, v: float, dt: float, volts: float, s: float, ks: float, kv: float, ka: float
) -> tuple[np.ndarray, np.ndarray]:
    """Derivatives of :func:`_stop_within_step`'s speed and distance in (kS, ln kV, ln kA), the step's
    starting speed carrying its own derivatives ``w``: central differences of the closed form."""
    d_speed, d_dist = np.zeros(3), np.zeros(3)
    base = np.array([ks, math.log(kv), math.log(ka) if ka > 0 else 0.0])
    for i in range(3 if ka > 0 else 2):  # (without inertia kA has no effect)
        h = 1e-6 * max(abs(base[i]), 1.0)
        ends = []
        for sign in (1.0, -1.0):
            p = base.copy()
            p[i] += sign * h
            ends.append(_stop_within_step(*_stop_inputs(v + sign * h * w[i], dt, volts, s, p[0], math.exp(p[1]),
                                                        math.exp(p[2]) if ka > 0 else 0.0)))
        d_speed[i] = (ends[0][0] - ends[1][0]) / (2 * h)
        d_dist[i] = (ends[0][1] - ends[1][1]) / (2 * h)
    return d_speed, d_dist


def _block_sensitivity(
    v0: float, w0: np.ndarray, dt: np.ndarray, u: np.ndarray, tau: float, s_kv: float, v: np.ndarray, stiff: bool,
    shared: tuple[np.ndarray, np.ndarray, np.ndarray | None] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Derivatives in (kS, ln kV, ln kA), each (3 × steps), of a block's speeds ``v`` and step distances
    (:func:`_linear_steps`), from the block's first speed ``v0`` and its derivatives ``w0``.

    Differentiating v_{j+1} = a_j·v_j + (1 − a_j)·u_j, a_j = e^(−dt_j/τ), u_j = (V_j − kS·s)/kV, τ = kA/kV
    gives the same recursion for the derivative w: w_{j+1} = a_j·w_j + b_j with
    b_j = ∂a_j·(v_j − u_j) + (1 − a_j)·∂u_j, ∂u = (−s/kV, −u, 0), ∂a = a·dt/τ·(0, −1, 1); it is summed
    as :func:`_linear_steps` sums the speeds (about the block's middle). The distance
    d_j = u_j·dt_j + (v_j − u_j)·τ·(1 − a_j) is differentiated term by term (∂τ = τ·(0, −1, 1)).
    ``shared``: dt/τ, a and the block's e^c as :func:`_linear_steps` computed them (the same numbers, not again).
    """
    m = dt.size
    du = np.empty((3, m))
    du[0], du[1], du[2] = -s_kv, -u, 0.0
    if tau <= 0.0:
        return du, du * dt
    if shared is None:
        x = dt / tau
        a, e = np.exp(-x), None
    else:
        x, a, e = shared
    one_a = 1.0 - a
    v_before = np.concatenate([[v0], v[:-1]]) - u
    if stiff:  # each step settles: its start is the previous step's settled speed (as _stiff_block)
        q = np.concatenate([[v0], u[:-1]]) - u
        w_start = np.concatenate([w0[:, None], du[:, :-1]], axis=1)
        g = a * x * q
        w = a * w_start + one_a * du
        w[1] -= g
        w[2] += g
    else:
        g = a * x * v_before
        bias = one_a * du
        bias[1] -= g
        bias[2] += g
        if m == 1:
            w = a * w0[:, None] + bias
        else:
            if e is None:
                c = np.concatenate([[0.0], np.cumsum(x)])
                c -= 0.5 * c[-1]
                e = np.exp(c)
            w = (w0[:, None] * e[0] + np.cumsum(bias * e[1:], axis=1)) / e[1:]
    q = v_before
    r = tau * one_a
    h = q * (r - tau * a * x)
    w_start = np.concatenate([w0[:, None], w[:, :-1]], axis=1)
    dd = du * dt + (w_start - du) * r
    dd[1] -= h
    dd[2] += h
    return w, dd


def _block_span(dt: np.ndarray, k: int, tau: float) -> int:
    """Steps from ``k`` until Σ dt/τ reaches :data:`_BLOCK_EXPONENT` (the remaining steps if never).

    The running sum is taken over a window that grows until it holds the answer, not over every
    remaining step (on a long log of short time constants that was n²/block work). A running sum is
    summed in order, so each window's sums are those of the whole: the same answer.
    """
    window = 4096
    while True:
        part = np.cumsum(dt[k : k + window] / tau)
        span = int(np.searchsorted(part, _BLOCK_EXPONENT))
        if span < part.size or k + window >= dt.size:
            return span
        window *= 4


def _stiff_span(dt: np.ndarray, k: int, tau: float) -> int:
    """Steps from ``k`` (at least 1) each of at least :data:`_STIFF_EXPONENT` time constants."""
    window = 4096
    while True:
        short = np.flatnonzero(dt[k : k + window] < _STIFF_EXPONENT * tau)
        if short.size or k + window >= dt.size:
            return max(int(short[0]) if short.size else dt.size - k, 1)
        window *= 4


def _stiff_block(v0: float, dt: np.ndarray, u: np.ndarray, tau: float) -> tuple[np.ndarray, np.ndarray]:
    """:func:`_linear_steps` over steps each of at least :data:`_STIFF_EXPONENT` time constants, at once.

    Each step's speed is a·v_start + (1 − a)·u with a = e^(−dt/τ) ≤ e^(−400): the step's start enters
    only through a, so taking the previous step's start as its settled speed u changes a result by
    a², below the smallest double — the same speeds and distances as step by step, without a Python
    step per row (a fit that drives kA towards 0 on a long log did that: minutes).
    """
    a = np.exp(-dt / tau)
    v_start = np.concatenate([[v0], u[:-1]])
    v = a * v_start + (1.0 - a) * u
    v_start[1:] = v[:-1]
    return v, u * dt + (v_start - u) * tau * (1.0 - a)


def _stop_within_step(
    v: float, u: float, dt: float, tau: float, volts: float, ks: float, kv: float, threshold: float
) -> tuple[float, float]:
    """(speed at the step's end, distance) when the speed reaches zero inside a step."""
    ratio = (v - u) / -u if u != 0 else math.inf  # ≤ 1: the speed already at or past zero (a derivative's nudge)
    t0 = 0.0 if tau <= 0 or ratio <= 1.0 else dt if u == 0 else min(dt, tau * math.log(ratio))
    dist = 0.0 if tau <= 0 else u * t0 + (v - u) * tau * (1.0 - math.exp(-t0 / tau))
    rest = dt - t0
    if rest <= 0 or abs(volts) <= threshold:
        return 0.0, dist
    s = math.copysign(1.0, volts)  # static friction overcome: off in the voltage's direction
    u2 = (volts - ks * s) / kv
    if tau <= 0:
        return u2, dist + u2 * rest
    decay = math.exp(-rest / tau)
    return u2 * (1.0 - decay), dist + u2 * rest - u2 * tau * (1.0 - decay)


def residuals(gains: Gains, tests: Sequence[ScoreTest]) -> tuple[np.ndarray, np.ndarray]:
    """Simulated minus logged speed and position, all tests' rows one after the other."""
    ks, kv, ka = (float(g) for g in gains[:3])
    if not (kv > 0 and ka >= 0 and math.isfinite(ks)):
        raise OptionError(f"the score needs kV > 0 and kA ≥ 0, got kS={ks:g}, kV={kv:g}, kA={ka:g}")
    rs, rp = [], []
    for test in tests:
        speed, position = simulate_gains(ks, kv, ka, test)
        rs.append(speed - test.velocity)
        rp.append(position - test.position)
    return np.concatenate(rs), np.concatenate(rp)


@dataclass(frozen=True)
class _Simulation:
    """The tests simulated at one point p = (kS, ln kV, ln kA): speed and position residuals (all rows),
    their derivatives (3 × rows each) and the score."""

    speed: np.ndarray
    position: np.ndarray
    d_speed: np.ndarray
    d_position: np.ndarray
    score: Score


class _Simulations:
    """The last few :class:`_Simulation` of :func:`fit_gains`, by point: a round of the reweighted fit
    starts where the last one ended, with new weights on the same residuals (one simulation less a round)."""

    KEEP = 3

    def __init__(self, tests: Sequence[ScoreTest]):
        self.tests = tests
        self.kept: dict[bytes, _Simulation] = {}

    def at(self, p: np.ndarray) -> _Simulation:
        key = np.asarray(p, dtype=float).tobytes()
        if key in self.kept:
            self.kept[key] = self.kept.pop(key)  # the most recently used is kept longest
            return self.kept[key]
        ks, kv, ka = (float(g) for g in _gains(p))
        if not (kv > 0 and ka >= 0 and math.isfinite(ks)):
            raise OptionError(f"the score needs kV > 0 and kA ≥ 0, got kS={ks:g}, kV={kv:g}, kA={ka:g}")
        parts = [simulate_sensitivity(ks, kv, ka, test) for test in self.tests]
        rs = np.concatenate([sp - t.velocity for (sp, _, _, _), t in zip(parts, self.tests, strict=True)])
        rp = np.concatenate([po - t.position for (_, po, _, _), t in zip(parts, self.tests, strict=True)])
        sim = _Simulation(rs, rp, np.concatenate([d for _, _, d, _ in parts], axis=1),
                          np.concatenate([d for _, _, _, d in parts], axis=1), Score(rms(rs), rms(rp)))
        if len(self.kept) >= self.KEEP:
            del self.kept[next(iter(self.kept))]
        self.kept[key] = sim
        return sim


def score(gains: Gains, tests: Sequence[ScoreTest]) -> Score:
    """The fair score of (kS [V], kV [V·s/unit], kA [V·s²/unit]) on the tests (units as the tests')."""
    rs, rp = residuals(gains, tests)
    return Score(rms(rs), rms(rp))


def rms(values: np.ndarray) -> float:
    """√(mean(x²)) without overflowing on huge residuals (scaled by the largest; inf or NaN as they come)."""
    x = np.asarray(values, dtype=float)
    if x.size == 0:
        return math.nan
    peak = float(np.max(np.abs(x)))
    if peak == 0.0 or not math.isfinite(peak):
        return peak
    return peak * float(np.sqrt(np.mean(np.square(x / peak))))


#: Weight of the position score against the speed score in :func:`fit_gains` (on the log scale).
#: The feedforward is a speed model (kV·v + kA·a): a position error is the time integral of the speed
#: errors, dominated by the long quasistatic tests where small kS/kV offsets accumulate, so it
#: re-counts the speed residuals; it is given a quarter of the speed's weight. Chosen on the five
#: shared logs (0.1 to 0.4 all beat the teams' gains on both scores there), see docs/real-logs.md.
POSITION_WEIGHT = 0.25


@dataclass
class GainFit:
    """Outcome of :func:`fit_gains`: gains (kS [V], kV [V·s/unit], kA [V·s²/unit]) and their HAC covariance."""

    gains: np.ndarray
    covariance: np.ndarray
    score: Score
    bandwidth: float
    nfev: int


def _objective(sc: Score, weight: float) -> float:
    return math.log(sc.speed) + weight * math.log(sc.position)


def fit_gains(
    tests: Sequence[ScoreTest],
    starts: Sequence[Gains],
    *,
    position_weight: float = POSITION_WEIGHT,
    rounds: int = 6,
) -> GainFit:
    """The (kS, kV, kA) that minimise log RMSE_speed + w·log RMSE_position of the score.

    Output error: every test is simulated from its logged voltage and first row, and the residuals
    are those of the score. Each step weighs the speed and position residuals by the inverse of
    their RMSE at the current gains (a round of iteratively reweighted least squares to first order,
    :func:`_reweighted_fit`, whose fixed point minimises the criterion: each score counts by its relative
    change, independent of units).
    Every start is tried and the best end kept. On a long log (more than :data:`COARSE_ROWS` rows)
    with several starts, each start is first fitted to every k-th row only (the simulation stays
    exact for the voltage held over k rows, so that fit ends near the full one) and only the start
    whose end is best there is fitted to every row: one full fit, not one per start. The covariance
    is the Newey–West sandwich of the
    weighted residuals at the optimum (:func:`motorlab.estimation.covariance.hac_covariance`, runs of one test and
    one signal taken as uncorrelated): the residuals of real logs are dominated by unmodelled,
    serially correlated effects, not by measurement noise.

    Raises
    ------
    FitError
        When no gains with kV > 0 and kA ≥ 0 simulate the tests.
    """
    points = [np.array([float(g[0]), math.log(max(g[1], 1e-9)), math.log(max(g[2], 1e-9))]) for g in starts]
    rows = sum(t.time.size for t in tests)
    nfev = 0
    with progress.task("Fitting the open-loop gains", total=len(points), unit="starts") as report:
        if len(points) > 1 and rows > COARSE_ROWS:
            k = math.ceil(rows / COARSE_ROWS)
            sparse = _Simulations([_every(t, k) for t in tests])
            ends = [_reweighted_fit(sparse, x, position_weight, rounds) for x in points]
            nfev += sum(e[3] for e in ends)
            scores = [e[0] for e in ends]
            if any(math.isfinite(v) for v in scores):
                points = [points[int(np.nanargmin(np.where(np.isfinite(scores), scores, np.nan)))]]
                report.update(len(starts) - 1, detail="the best start on every k-th row")
        sims = _Simulations(tests)
        best: tuple[float, np.ndarray, Score] | None = None
        for number, x in enumerate(points):
            report.advance(detail=f"start {number + 1} of {len(points)}")
            value, end, current, n = _reweighted_fit(sims, x, position_weight, rounds)
            nfev += n
            if math.isfinite(value) and (best is None or value < best[0]):
                best = (value, end, current)
    if best is None:
        raise FitError("no three gains simulate these tests")
    gains = _gains(best[1])
    cov, bandwidth = _hac(gains, tests, best[2], position_weight)
    return GainFit(gains, cov, best[2], bandwidth, nfev)


#: Above this many rows, :func:`fit_gains` ranks its starts on every k-th row (k from this) first.
COARSE_ROWS = 20_000


def _every(test: ScoreTest, k: int) -> ScoreTest:
    """``test``'s every k-th row from the first (the simulation holds each kept row's voltage to the next)."""
    return ScoreTest(test.name, test.time[::k], test.voltage[::k], test.position[::k], test.velocity[::k],
                     test.start)


def _reweighted_fit(
    sims: _Simulations, x: np.ndarray, weight: float, rounds: int
) -> tuple[float, np.ndarray, Score, int]:
    """(criterion, p, score, evaluations) at the minimum of the criterion from p = (kS, ln kV, ln kA) = ``x``.

    Levenberg–Marquardt on F(p) = ln RMSE_speed + w·ln RMSE_position itself: its gradient is
    ∇F = (ws²·D_sᵀr_s + wp²·D_pᵀr_p)/n with ws = 1/RMSE_speed, wp² = w/RMSE_position² at p (the score's
    residuals r and their sensitivities D, one simulation), and the step solves the Gauss–Newton system
    of those weights, (ws²·D_sᵀD_s + wp²·D_pᵀD_p)/n. Each step is one round of the iteratively
    reweighted least squares (weights from the last point) solved to first order, so the fixed point is
    the same, reached with one simulation a step instead of a least-squares solve a round. Stops when a
    step lowers F by less than :data:`CRITERION_TOLERANCE` (F is on the log scale: a relative change of
    the RMSEs) or no step lowers it; at most ``rounds`` × :data:`STEPS_PER_ROUND` steps.
    """
    sim = sims.at(x)
    value = _objective(sim.score, weight)
    nfev = 1
    if not math.isfinite(value):
        return value, x, sim.score, nfev
    mu = 1e-3
    for _ in range(rounds * STEPS_PER_ROUND):
        ws2, wp2 = 1.0 / sim.score.speed**2, weight / sim.score.position**2
        n = sim.speed.size
        grad = (ws2 * (sim.d_speed @ sim.speed) + wp2 * (sim.d_position @ sim.position)) / n
        hess = (ws2 * (sim.d_speed @ sim.d_speed.T) + wp2 * (sim.d_position @ sim.d_position.T)) / n
        diag = np.diag(hess).copy()
        diag = np.where(diag > 0, diag, 1.0)
        accepted = False
        for _ in range(12):
            try:
                step = -np.linalg.solve(hess + mu * np.diag(diag), grad)
            except np.linalg.LinAlgError:
                mu *= 10.0
                continue
            x_new = x + step
            try:
                new = sims.at(x_new)
            except (OptionError, OverflowError):  # kV or kA beyond a double (a step far outside): a shorter step
                mu *= 4.0
                continue
            nfev += 1
            value_new = _objective(new.score, weight) if new.score.speed > 0 and new.score.position > 0 else math.inf
            if value_new < value:
                accepted = True
                break
            mu *= 4.0
        if not accepted:
            break
        drop = value - value_new
        x, sim, value = x_new, new, value_new
        mu = max(mu / 3.0, 1e-9)
        if drop < CRITERION_TOLERANCE:
            break
    return value, x, sim.score, nfev


#: :func:`_reweighted_fit` stops when a step lowers ln RMSE_speed + w·ln RMSE_position by less than this.
CRITERION_TOLERANCE = 1e-8
#: Steps of :func:`_reweighted_fit` per round of ``rounds``.
STEPS_PER_ROUND = 5


def _hac(gains: np.ndarray, tests: Sequence[ScoreTest], sc: Score, weight: float) -> tuple[np.ndarray, float]:
    """Newey–West covariance of the gains from the weighted score residuals (sensitivity Jacobian)."""
    from motorlab.estimation.covariance import hac_covariance

    ws, wp = 1.0 / sc.speed, math.sqrt(weight) / sc.position
    # kA driven to nothing (exp(ln kA) underflowed on a log too short to show inertia): the smallest positive one
    gains = np.array([gains[0], gains[1], max(float(gains[2]), np.finfo(float).tiny)])
    sim = _Simulations(tests).at(np.array([gains[0], math.log(gains[1]), math.log(gains[2])]))
    r0 = np.concatenate([ws * sim.speed, wp * sim.position])
    jac = np.concatenate([ws * sim.d_speed, wp * sim.d_position], axis=1).T
    jac /= np.array([1.0, gains[1], gains[2]])  # d/d(ln g) = g·d/dg
    sizes = [t.time.size for t in tests]
    labels = np.concatenate([np.full(n, i) for i, n in enumerate(sizes)] +
                            [np.full(n, len(sizes) + i) for i, n in enumerate(sizes)])
    bread = np.linalg.pinv(jac.T @ jac)
    return hac_covariance(jac, r0, bread, groups=labels)


def _gains(p: np.ndarray) -> np.ndarray:
    return np.array([p[0], math.exp(p[1]), math.exp(p[2])])


def test_direction(name: str) -> int:
    """+1 for a forward test, −1 for a backward one, 0 when the name does not say."""
    from motorlab.io.frc_json import test_kind

    return int(test_kind(name)["direction"])


def speed_lag(gains: Gains, tests: Sequence[ScoreTest], *, max_rows: int = 40) -> tuple[float, float]:
    """(lag [s], RMSE ratio) of the logged speed behind the simulated one: the row shift that fits best.

    The ratio is the speed RMSE with the best shift over the RMSE without (1 when no shift helps).
    A logged speed that is the motor controller's filtered estimate (a TalonFX averages over about
    100 ms) or a stale status frame lags the shaft by tens of milliseconds.
    """
    sims = [simulate_gains(gains[0], gains[1], gains[2], t)[0] for t in tests]
    errors = []
    with np.errstate(over="ignore", invalid="ignore"):  # absurd speeds: an infinite error, not a warning
        for k in range(max_rows + 1):  # a test shorter than the shift adds nothing (not a mismatched slice)
            num = sum(float(np.sum((t.velocity[k:] - s[: max(s.size - k, 0)]) ** 2))
                      for t, s in zip(tests, sims, strict=True))
            den = sum(max(t.time.size - k, 0) for t in tests)
            errors.append(math.sqrt(num / den) if den else math.inf)
    best = int(np.argmin(errors))
    dt = float(np.median(np.concatenate([np.diff(t.time) for t in tests])))
    ratio = errors[best] / errors[0] if 0 < errors[0] < math.inf else 1.0
    return best * dt, ratio


def residual_diagnostics(gains: Gains, tests: Sequence[ScoreTest]) -> dict[str, float]:
    """What the score residuals look like: speed lag, direction asymmetry and position drift.

    Returns
    -------
    dict
        ``lag_s`` and ``lag_rmse_ratio`` (:func:`speed_lag`); ``asymmetry``: mean speed residual of
        the forward tests minus the backward tests' (signed by direction), over the speed RMSE
        (a kS or kV that differs by direction shows as a persistent offset of opposite sign);
        ``drift``: share of the position residual's variance in the quasistatic tests explained by a
        straight line in time (slip, turning, friction changing along the run).
    """
    lag, ratio = speed_lag(gains, tests)
    rs_all, _ = residuals(gains, tests)
    rms_all = rms(rs_all) or 1.0
    by_dir: dict[int, list[float]] = {1: [], -1: []}
    explained, total = 0.0, 0.0
    for test in tests:
        speed, position = simulate_gains(gains[0], gains[1], gains[2], test)
        d = test_direction(test.name)
        if d:
            by_dir[d].append(float(np.mean(d * (speed - test.velocity))))
        if test.name.startswith(("slow", "quasistatic")):
            rp = position - test.position
            trend = np.polyval(np.polyfit(test.time, rp, 1), test.time)
            explained += float(np.sum((trend - rp.mean()) ** 2))
            total += float(np.sum((rp - rp.mean()) ** 2))
    asym = (np.mean(by_dir[1]) - np.mean(by_dir[-1])) / rms_all if by_dir[1] and by_dir[-1] else 0.0
    return {"lag_s": lag, "lag_rmse_ratio": ratio, "asymmetry": float(asym),
            "drift": explained / total if total > 0 else 0.0}


def describe_residuals(diag: dict[str, float]) -> str:
    """One phrase naming the effects the residuals look like (empty when none stands out)."""
    parts = []
    if diag["lag_s"] > 0 and diag["lag_rmse_ratio"] < 0.9:
        parts.append(f"lag (the logged motion trails the simulation by {1e3 * diag['lag_s']:.0f} ms: a filtered or "
                     "stale reading)")
    ks_f, ks_b = diag.get("kS_forward", math.nan), diag.get("kS_backward", math.nan)
    kv_f, kv_b = diag.get("kV_forward", math.nan), diag.get("kV_backward", math.nan)
    split = abs(ks_f - ks_b) > max(0.5 * abs(diag.get("kS", 0.0)), 0.02) or abs(kv_f / kv_b - 1) > 0.03
    if abs(diag["asymmetry"]) > 0.2:
        parts.append(f"asymmetry (forward and backward tests miss in opposite senses, {abs(diag['asymmetry']):.2f}× "
                     "the speed RMSE: kS or kV differ by direction)")
    elif split:  # NaN compares False: no per-direction gains, no claim
        parts.append(f"asymmetry (the forward tests alone give kS {ks_f:.3g} V, kV {kv_f:.4g}; the backward ones kS "
                     f"{ks_b:.3g} V, kV {kv_b:.4g}: friction differs by direction)")
    if diag["drift"] > 0.5:
        parts.append(f"drift (a straight line in time explains {100 * diag['drift']:.0f} % of the position "
                     "residual along the runs: slip, turning or friction changing along the run)")
    return "; ".join(parts)


def position_residual_diagnostics(
    runs: Iterable[tuple[np.ndarray, np.ndarray, np.ndarray, int]],
) -> dict[str, float]:
    """:func:`residual_diagnostics` of a position-only fit: runs of (time, measured − simulated, speed, direction).

    A reading late by d is θ(t − d) ≈ θ(t) − ω·d, so a lag shows as a residual proportional to −ω:
    d = −Σr·ω/Σω², and ``lag_rmse_ratio`` = √(1 − share of the residual it explains).
    """
    rw = ww = rr = 0.0
    n = 0
    by_dir: dict[int, list[float]] = {1: [], -1: []}
    explained = total = 0.0
    for time, res, speed, direction in runs:
        rw += float(np.sum(res * speed))
        ww += float(np.sum(speed * speed))
        rr += float(np.sum(res * res))
        n += res.size
        if direction:
            by_dir[direction].append(float(np.mean(direction * res)))
        if time.size > 2:
            trend = np.polyval(np.polyfit(time, res, 1), time)
            explained += float(np.sum((trend - res.mean()) ** 2))
            total += float(np.sum((res - res.mean()) ** 2))
    lag = -rw / ww if ww > 0 else 0.0
    share = rw * rw / (ww * rr) if ww > 0 and rr > 0 else 0.0
    rms_res = math.sqrt(rr / max(n, 1)) or 1.0
    asym = (np.mean(by_dir[1]) - np.mean(by_dir[-1])) / rms_res if by_dir[1] and by_dir[-1] else 0.0
    return {"lag_s": max(lag, 0.0), "lag_rmse_ratio": math.sqrt(max(1.0 - share, 0.0)), "asymmetry": float(asym),
            "drift": explained / total if total > 0 else 0.0}


def score_panels(gains: Gains, tests: Sequence[ScoreTest], *, title: str, length: str = "rad") -> list:
    """Logged against open-loop simulated speed and position, tests end to end (score residuals beneath)."""
    from motorlab.results import Panel, Series

    sims = [simulate_gains(gains[0], gains[1], gains[2], t) for t in tests]
    offsets = np.cumsum([0.0] + [float(t.time[-1]) + 0.01 for t in tests[:-1]])
    in_order = all(b.start > a.start + float(a.time[-1]) for a, b in itertools.pairwise(tests))
    if in_order:  # one log (or its pieces, a span left out): against its own time
        offsets = np.array([t.start for t in tests])
    x = np.concatenate([t.time + o for t, o in zip(tests, offsets, strict=True)])
    panels = []
    for k, (label, y_label) in enumerate([("speed", f"v [{length}/s]"), ("position", f"x [{length}]")]):
        data = np.concatenate([t.velocity if k == 0 else t.position for t in tests])
        model = np.concatenate([s[k] for s in sims])
        panels.append(Panel(title=f"{title}: logged and open-loop simulated {label} (the score)",
                            x_label="time in the log [s]" if in_order else "time (tests end to end) [s]",
                            y_label=y_label,
                            data=Series(x, data, "logged"), model=Series(x, model, "simulated", kind="model"),
                            time=np.concatenate([t.time + t.start for t in tests])))
    return panels


#: Weights tried, in order, when the fit is worse than the reference on one score (see :func:`open_loop_gains`).
LOWER_WEIGHTS = (0.1, 0.03, 0.0)
HIGHER_WEIGHTS = (0.5, 1.0, 2.0, 4.0)
#: How much worse than the reference either score may be before the weight moves.
REFERENCE_TOLERANCE = 0.01


def open_loop_gains(
    tests: Sequence[ScoreTest], starts: Sequence[Gains], *, reference: Score | None = None
) -> dict:
    """The gains of :func:`fit_gains` with what is reported beside them.

    ``reference``: the score of SysId's own regression (what teams paste). With w = 1/4 the fit can
    trade one score for the other; when it ends worse than the reference on one score by more than
    :data:`REFERENCE_TOLERANCE` while better on the other, the weight moves towards the score that
    lost (w from :data:`LOWER_WEIGHTS` or :data:`HIGHER_WEIGHTS`, each fit started from the last)
    until both are at least as good — the gains then dominate the published method. If no weight
    achieves that, the one whose worse ratio is smallest is kept.

    Returns
    -------
    dict
        ``fit`` (:class:`GainFit`), ``position_weight``, ``by_direction`` ({"forward"|"backward":
        (kS, kV, kA)} fitted to that direction's tests alone, when both are present), ``by_side``
        ({"left side"|"right side": ...} for a drivetrain read with both sides),
        ``diagnostics`` (:func:`residual_diagnostics`) and ``description`` (:func:`describe_residuals`).
    """
    weight = POSITION_WEIGHT
    fit = fit_gains(tests, starts, position_weight=weight)
    if reference is not None and math.isfinite(reference.speed * reference.position):
        limit = 1.0 + REFERENCE_TOLERANCE

        def worst(f: GainFit) -> float:
            return max(f.score.speed / reference.speed, f.score.position / reference.position)

        speed_lost = fit.score.speed > limit * reference.speed
        position_lost = fit.score.position > limit * reference.position
        if speed_lost != position_lost:
            best = (worst(fit), weight, fit)
            for w in LOWER_WEIGHTS if speed_lost else HIGHER_WEIGHTS:
                trial = fit_gains(tests, [best[2].gains], position_weight=w)
                if worst(trial) < best[0]:
                    best = (worst(trial), w, trial)
                if worst(trial) <= limit:
                    break
            _, weight, fit = best
    by_direction = _subset_gains(tests, fit.gains, weight, {"forward": lambda t: test_direction(t.name) == 1,
                                                            "backward": lambda t: test_direction(t.name) == -1})
    by_side = _subset_gains(tests, fit.gains, weight, {"left side": lambda t: t.name.endswith("#left"),
                                                       "right side": lambda t: t.name.endswith("#right")})
    diag = residual_diagnostics(fit.gains, tests)
    diag["kS"] = float(fit.gains[0])
    if len(by_direction) == 2:
        diag.update(kS_forward=by_direction["forward"][0], kS_backward=by_direction["backward"][0],
                    kV_forward=by_direction["forward"][1], kV_backward=by_direction["backward"][1])
    return {"fit": fit, "position_weight": weight, "by_direction": by_direction, "by_side": by_side,
            "diagnostics": diag, "description": describe_residuals(diag)}


def _subset_gains(
    tests: Sequence[ScoreTest], start: np.ndarray, weight: float, subsets: dict
) -> dict[str, list[float]]:
    """Gains fitted to each subset of the tests (a proper, non-empty one), from the pooled gains."""
    out: dict[str, list[float]] = {}
    for label, keep in subsets.items():
        part = [t for t in tests if keep(t)]
        if part and len(part) < len(tests):
            try:
                out[label] = fit_gains(part, [start], position_weight=weight, rounds=3).gains.tolist()
            except (FitError, OptionError):
                continue
    return out
