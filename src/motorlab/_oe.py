"""A fast simulator for output-error fitting: a linear plant with Coulomb friction and stiction.

The optimisers of :mod:`motorlab.identify` and :mod:`motorlab.feedforward` simulate the same log
hundreds of times with changing parameters, so the simulator must take a few milliseconds for 30 000
samples. :mod:`motorlab.simulate` is general (several drives, crossovers); this one handles only what
the fits need: a voltage held over each sample (zero-order hold) driving a linear plant

    x' = A·x + b_V·V + b_F·s,      θ' = ω = x[w],      s = sgn(ω)

where ``x`` is (i, ω) for the full motor model or (ω) for the feedforward model, and s is the
friction sign. At rest the shaft stays at rest while the drive acceleration |(A·x + b_V·V)[w]| does not
exceed the friction level F = −b_F[w] (stiction at the Coulomb level).

Method
------
Between events (speed reaching zero, break-away) the plant is linear time-invariant with a held input,
so a stretch of samples is propagated exactly (matrix exponential of the augmented system) as a second-
order recursion run by :func:`scipy.signal.lfilter`. An event is detected on the grid, its time inside
the step found by linear interpolation of the speed (or of the drive margin for a break-away), and the
step finished in the new regime with two fractional-step propagations. The located event time varies
continuously with the parameters, so the simulated outputs do too, which finite-difference Jacobians
need; no smoothing of sgn(ω) is required.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy import linalg, signal

_MIN_CHUNK = 64


@dataclass(frozen=True)
class StatePlant:
    """Continuous-time plant ``x' = A·x + b_V·V + b_F·sgn(ω)``.

    Parameters
    ----------
    a
        State matrix (n × n), n = 1 (ω) or 2 (i, ω) [1/s and mixed SI].
    b_drive
        Input vector of the applied voltage (n,).
    b_friction
        Input vector of the friction sign (n,); ``-b_friction[w]`` is the friction level F [rad/s²].
    w
        Index of the speed ω in the state.
    """

    a: np.ndarray
    b_drive: np.ndarray
    b_friction: np.ndarray
    w: int

    @property
    def n(self) -> int:
        return int(self.a.shape[0])

    @property
    def friction(self) -> float:
        return float(-self.b_friction[self.w])


@dataclass(frozen=True)
class _Discrete:
    """ZOH discretisation of one regime over one step: x⁺ = Ad·x + bv·V + c, θ⁺ = θ + hx·x + hv·V + hc."""

    ad: np.ndarray
    bv: np.ndarray
    c: np.ndarray
    hx: np.ndarray
    hv: float
    hc: float


def motor_plant(K: float, R: float, L: float, J: float, b: float, Tf: float) -> StatePlant:
    """The full model ``L·di/dt = V − R·i − K·ω``, ``J·dω/dt = K·i − b·ω − Tf·sgn(ω)``; state (i, ω)."""
    a = np.array([[-R / L, -K / L], [K / J, -b / J]])
    return StatePlant(a, np.array([1.0 / L, 0.0]), np.array([0.0, -Tf / J]), 1)


def feedforward_plant(kS: float, kV: float, kA: float) -> StatePlant:
    """The feedforward model ``V = kS·sgn(ω) + kV·ω + kA·α``; state (ω)."""
    return StatePlant(np.array([[-kV / kA]]), np.array([1.0 / kA]), np.array([-kS / kA]), 0)


def _regime(plant: StatePlant, s: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(A, b_V, const) of regime s: moving with sign s = ±1, or stuck (s = 0: ω frozen at 0)."""
    if s != 0:
        return plant.a, plant.b_drive, s * plant.b_friction
    a = plant.a.copy()
    a[plant.w, :] = 0.0
    a[:, plant.w] = 0.0
    bv = plant.b_drive.copy()
    bv[plant.w] = 0.0
    return a, bv, np.zeros(plant.n)


class _Modal:
    """Eigen-decomposition of one regime's A for fast ZOH matrices at any step length.

    e^{Aτ} = P·e^{Λτ}·P⁻¹, ∫₀^τ e^{As} ds = P·τφ₁(Λτ)·P⁻¹ and ∫₀^τ∫₀^s e^{Ar} dr ds = P·τ²φ₂(Λτ)·P⁻¹ with
    φ₁(z) = (e^z − 1)/z, φ₂(z) = (e^z − 1 − z)/z²: a few small numpy operations instead of a general
    matrix exponential (which dominated the run time at events). Near-repeated eigenvalues (critical
    damping, where P is ill-conditioned) fall back to :func:`scipy.linalg.expm`.
    """

    def __init__(self, plant: StatePlant, s: int):
        self.plant = plant
        self.s = s
        a, self.bv, self.c = _regime(plant, s)
        self.a = a
        lam, vec = np.linalg.eig(a)
        spread = float(np.max(np.abs(lam))) if lam.size else 0.0
        self.ok = lam.size < 2 or bool(abs(lam[0] - lam[1]) > 1e-6 * spread)
        if self.ok:
            self.lam = lam
            self.vec = vec
            inv = np.linalg.inv(vec)
            self.pb = inv @ self.bv
            self.pc = inv @ self.c
            self.inv = inv
            self.row = vec[plant.w]

    def discrete(self, tau: float) -> _Discrete:
        if not self.ok:
            return _discretise_expm(self.plant, self.s, tau)
        z = self.lam * tau
        small = np.abs(z) < 1e-4
        zs = np.where(small, 1.0, z)
        e = np.exp(z)
        phi1 = np.where(small, 1.0 + z / 2.0 + z * z / 6.0, np.expm1(zs) / zs)
        phi2 = np.where(small, 0.5 + z / 6.0 + z * z / 24.0, (np.expm1(zs) - zs) / (zs * zs))
        vec, inv = self.vec, self.inv
        ad = ((vec * e) @ inv).real
        bv = (vec @ (tau * phi1 * self.pb)).real
        c = (vec @ (tau * phi1 * self.pc)).real
        moving = 1.0 if self.s != 0 else 0.0
        hx = moving * ((self.row * (tau * phi1)) @ inv).real
        hv = moving * float((self.row @ (tau * tau * phi2 * self.pb)).real)
        hc = moving * float((self.row @ (tau * tau * phi2 * self.pc)).real)
        return _Discrete(ad, bv, c, hx, hv, hc)


def _discretise_expm(plant: StatePlant, s: int, tau: float) -> _Discrete:
    n = plant.n
    a, bv, c = _regime(plant, s)
    m = np.zeros((n + 3, n + 3))
    m[:n, :n] = a
    m[:n, n + 1] = bv
    m[:n, n + 2] = c
    if s != 0:  # θ' = ω (in the stuck regime ω = 0 and θ stays)
        m[n, plant.w] = 1.0
    phi = linalg.expm(m * tau)
    return _Discrete(
        phi[:n, :n], phi[:n, n + 1], phi[:n, n + 2], phi[n, :n], float(phi[n, n + 1]), float(phi[n, n + 2])
    )


def _propagate(d: _Discrete, x0: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """States x_0..x_M and θ increments for held inputs v_0..v_{M-1}, starting from x0.

    The recursion x⁺ = Ad·x + e with e = bv·v + c is run as a rational filter in z⁻¹ (one or two
    poles); the initial state enters as an input at step −1, so every call starts exactly at x0.
    """
    n = x0.size
    m = v.size
    e = np.empty((n, m + 2))
    e[:, 0] = x0
    e[:, 1 : m + 1] = d.bv[:, None] * v[None, :] + d.c[:, None]
    e[:, m + 1] = 0.0
    if n == 1:
        x = signal.lfilter([0.0, 1.0], [1.0, -d.ad[0, 0]], e[0])[1:, None]
    else:
        (a11, a12), (a21, a22) = d.ad
        den = [1.0, -(a11 + a22), a11 * a22 - a12 * a21]
        e0, e1 = e
        u0 = np.zeros(m + 2)
        u1 = np.zeros(m + 2)
        # X0 = z⁻¹[(1 − a22 z⁻¹)E0 + a12 z⁻¹ E1]/det,  X1 = z⁻¹[a21 z⁻¹ E0 + (1 − a11 z⁻¹)E1]/det
        u0[1:] = e0[:-1]
        u0[2:] += -a22 * e0[:-2] + a12 * e1[:-2]
        u1[1:] = e1[:-1]
        u1[2:] += -a11 * e1[:-2] + a21 * e0[:-2]
        x = np.empty((m + 1, 2))
        x[:, 0] = signal.lfilter([1.0], den, u0)[1:]
        x[:, 1] = signal.lfilter([1.0], den, u1)[1:]
    dtheta = x[:-1] @ d.hx + d.hv * v + d.hc
    return x, dtheta


def _flow(d: _Discrete, x: np.ndarray, v: float) -> tuple[np.ndarray, float]:
    """One (fractional) step."""
    return d.ad @ x + d.bv * v + d.c, float(d.hx @ x + d.hv * v + d.hc)


def _locate(fun: Callable[[float], float], f0: float, f1: float, *, iterations: int = 10) -> float:
    """Fraction of a step where ``fun`` (value f0 at 0, f1 at 1, opposite signs) crosses zero.

    Regula falsi with the Illinois modification: the first guess is the linear interpolation, and a
    few refinements on the continuous solution make the event time exact to far below a step, so the
    speed set to zero at a stop is not off by α·(interpolation error).
    """
    a, b, fa, fb = 0.0, 1.0, f0, f1
    if fa == 0.0:
        return 0.0
    if fb == fa or fa * fb > 0:
        return 1.0 if fa * fb > 0 else 0.0
    c = a
    side = 0
    tol = 1e-12 * (abs(f0) + abs(f1))
    for _ in range(iterations):
        c = (a * fb - b * fa) / (fb - fa)
        fc = fun(c)
        if fc == 0.0:
            return c
        if fc * fb < 0:
            a, fa = b, fb
            side_new = 1
        else:
            side_new = -1
            fa = 0.5 * fa if side == -1 else fa
        b, fb = c, fc
        side = side_new
        if abs(fc) < tol:
            break
    return min(max(c, 0.0), 1.0)


def simulate(
    plant: StatePlant,
    voltage: np.ndarray,
    dt: float,
    *,
    x0: np.ndarray | None = None,
    theta0: float = 0.0,
    switches: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Simulate the plant on a uniform grid.

    Parameters
    ----------
    plant
        The linear plant with friction.
    voltage
        Applied voltage held over each step, N values [V].
    dt
        Grid step [s].
    x0
        Initial state (default: at rest).
    theta0
        Initial angle [rad].
    switches
        Drive switches inside steps: (step indices k, increasing; fractions f in [0, 1]; voltage
        before). Step k holds the voltage before for f·dt, then ``voltage[k]`` (a drive switching
        between the logger's samples); each such step is propagated exactly in two parts.

    Returns
    -------
    states, theta
        States at the N + 1 grid points (shape (N + 1, n)) and the angle [rad] (N + 1,).
    """
    voltage = np.asarray(voltage, dtype=float)
    n_steps = voltage.size
    n = plant.n
    w = plant.w
    f_level = plant.friction
    x = np.zeros(n) if x0 is None else np.asarray(x0, dtype=float).copy()
    states = np.empty((n_steps + 1, n))
    theta = np.empty(n_steps + 1)
    states[0] = x
    theta[0] = theta0
    cache: dict[int, _Discrete] = {}
    modal: dict[int, _Modal] = {}

    def mdl(s: int) -> _Modal:
        if s not in modal:
            modal[s] = _Modal(plant, s)
        return modal[s]

    def disc(s: int) -> _Discrete:
        if s not in cache:
            cache[s] = mdl(s).discrete(dt)
        return cache[s]

    def drive(xs: np.ndarray, v: np.ndarray | float) -> np.ndarray | float:
        # acceleration the drive would give at rest (ω = 0): row w of A·x + b_V·V without the ω term
        acc = xs @ plant.a[w] - (xs[..., w] * plant.a[w, w]) + plant.b_drive[w] * v
        return acc

    def new_mode(xs: np.ndarray, v: float) -> int:
        acc = float(drive(xs, v))
        return 0 if abs(acc) <= f_level else (1 if acc > 0 else -1)

    k = 0
    th = float(theta0)
    mode = int(np.sign(x[w])) if x[w] != 0 else (new_mode(x, voltage[0]) if n_steps else 0)
    chunk = _MIN_CHUNK
    sw_steps, sw_frac, sw_before = switches if switches is not None else (np.zeros(0, int), (), ())
    sw = 0
    while k < n_steps:
        while sw < len(sw_steps) and sw_steps[sw] < k:
            sw += 1
        if sw < len(sw_steps) and sw_steps[sw] == k:
            frac_sw = float(sw_frac[sw])
            x, dth1, mode = _advance(x, mode, float(sw_before[sw]), frac_sw * dt, mdl, drive, new_mode, f_level, w)
            x, dth2, mode = _advance(x, mode, float(voltage[k]), (1.0 - frac_sw) * dt, mdl, drive, new_mode,
                                     f_level, w)
            th += dth1 + dth2
            k += 1
            states[k] = x
            theta[k] = th
            chunk = _MIN_CHUNK
            continue
        stop = min(n_steps, k + chunk, int(sw_steps[sw]) if sw < len(sw_steps) else n_steps)
        v = voltage[k:stop]
        d = disc(mode)
        xs, dth = _propagate(d, x, v)
        if mode != 0:
            bad = np.flatnonzero(mode * xs[1:, w] <= 0.0)
        else:
            # break-away at the start of a step (input change) or inside it (current rising)
            margin_start = np.abs(drive(xs[:-1], v)) - f_level
            margin_end = np.abs(drive(xs[1:], v)) - f_level
            bad = np.flatnonzero((margin_start > 0) | (margin_end > 0))
        if bad.size == 0:
            states[k + 1 : stop + 1] = xs[1:]
            theta[k + 1 : stop + 1] = th + np.cumsum(dth)
            th = float(theta[stop])
            x = xs[-1].copy()
            k = stop
            chunk = min(2 * chunk, 1 << 16)
            continue
        j = int(bad[0])  # the event happens inside step k + j
        if j:
            states[k + 1 : k + j + 1] = xs[1 : j + 1]
            theta[k + 1 : k + j + 1] = th + np.cumsum(dth[:j])
            th = float(theta[k + j])
            x = xs[j].copy()
        k += j
        vk = float(voltage[k])
        x_start = x

        def event_value(frac: float, _mode: int = mode, _x: np.ndarray = x_start, _v: float = vk) -> float:
            xm, _ = _flow(mdl(_mode).discrete(frac * dt), _x, _v)
            if _mode != 0:
                return float(xm[w])
            return abs(float(drive(xm, _v))) - f_level

        if mode != 0:
            frac = _locate(event_value, float(x[w]), float(xs[j + 1, w]))
        else:
            m0 = float(margin_start[j])
            frac = 0.0 if m0 > 0 else _locate(event_value, m0, float(margin_end[j]))
        frac = min(max(frac, 0.0), 1.0)
        x_mid, dth_mid = _flow(mdl(mode).discrete(frac * dt), x, vk) if frac > 0 else (x, 0.0)
        if mode != 0:
            x_mid = x_mid.copy()
            x_mid[w] = 0.0
        if mode == 0:  # break-away located: move in the direction of the drive (its margin is ~0 here)
            nxt = 1 if float(drive(x_mid, vk)) > 0 else -1
        else:
            nxt = new_mode(x_mid, vk)
        if nxt == mode:  # interpolation put the event at the very end: finish the step in the old regime
            nxt = 0 if mode != 0 else nxt
        x_end, dth_end = _flow(mdl(nxt).discrete((1.0 - frac) * dt), x_mid, vk) if frac < 1 else (x_mid, 0.0)
        if nxt != 0 and nxt * x_end[w] < 0:  # numerically impossible reversal: hold at rest
            x_end = x_mid
            dth_end = 0.0
            nxt = 0
        th += dth_mid + dth_end
        x = np.asarray(x_end, dtype=float).copy()
        k += 1
        states[k] = x
        theta[k] = th
        mode = nxt
        chunk = _MIN_CHUNK
    return states, theta


def _advance(x: np.ndarray, mode: int, v: float, tau: float, mdl: Callable[[int], _Modal],
             drive: Callable[..., Any], new_mode: Callable[[np.ndarray, float], int], f_level: float,
             w: int) -> tuple[np.ndarray, float, int]:
    """Propagate a part of a step (length τ, voltage v held) exactly, with at most one friction event."""
    if tau <= 0.0:
        return x, 0.0, mode
    if mode == 0 and abs(float(drive(x, v))) > f_level:  # break-away at once (the drive just changed)
        mode = 1 if float(drive(x, v)) > 0 else -1
    x1, d1 = _flow(mdl(mode).discrete(tau), x, v)
    if mode != 0:
        if mode * x1[w] > 0:
            return x1, d1, mode
        f0, f1 = float(x[w]), float(x1[w])
    else:
        f1 = abs(float(drive(x1, v))) - f_level
        if f1 <= 0:
            return x1, d1, 0
        f0 = abs(float(drive(x, v))) - f_level

    def event_value(frac: float) -> float:
        xm, _ = _flow(mdl(mode).discrete(frac * tau), x, v)
        return float(xm[w]) if mode != 0 else abs(float(drive(xm, v))) - f_level

    frac = _locate(event_value, f0, f1)
    x_mid, d_mid = _flow(mdl(mode).discrete(frac * tau), x, v) if frac > 0 else (x, 0.0)
    if mode != 0:
        x_mid = x_mid.copy()
        x_mid[w] = 0.0
        nxt = new_mode(x_mid, v)
    else:
        nxt = 1 if float(drive(x_mid, v)) > 0 else -1
    x_end, d_end = _flow(mdl(nxt).discrete((1.0 - frac) * tau), x_mid, v) if frac < 1 else (x_mid, 0.0)
    if nxt != 0 and nxt * x_end[w] < 0:  # numerically impossible reversal: hold at rest
        return x_mid, d_mid, 0
    return np.asarray(x_end, dtype=float), d_mid + d_end, nxt


# --------------------------------------------------------------------------------------------------
# Output-error fitting engine shared by identify and feedforward
# --------------------------------------------------------------------------------------------------


@dataclass
class Log:
    """One run prepared for fitting.

    The simulation runs on a uniform grid of step ``dt`` starting at the first sample; the voltage
    of each grid step is the last logged voltage at or before it (zero-order hold). When the samples
    are themselves uniform the grid is the samples.

    ``reading`` numbers the runs of identical consecutive angle readings (a shaft at rest, or turning
    less than one count between samples) and ``position_weight`` is 1/√m for each of the m samples
    of a run: the m readings of one count carry the information of one reading (they share one
    quantisation error), not of m independent ones. Without it a stretch at rest, with its single
    quantisation error repeated hundreds of times, outweighs the motion and biases friction
    (docs/identify.md, "Quantised angle").
    """

    time: np.ndarray  # sample times from 0 [s]
    dt: float
    grid_voltage: np.ndarray  # held voltage per grid step (N_grid) [V]
    grid_angle: np.ndarray  # measured angle held on the grid (N_grid) [rad], for gravity terms
    position: np.ndarray  # measured angle at the samples [rad]
    current: np.ndarray | None  # measured current at the samples [A]
    uniform: bool
    resolution: float  # position quantum [rad] (0 if unknown)
    moving_at_start: bool
    source: str = ""
    reading: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))  # run index per sample
    position_weight: np.ndarray = field(default_factory=lambda: np.ones(0))  # 1/√(run length) per sample
    stale_variance: np.ndarray | None = None  # variance of stale status frames per sample [rad²]

    def position_factor(self, sigma_position: float) -> np.ndarray:
        """Weight of each angle residual: 1/√(run length) over the angle noise of the sample [1/rad]."""
        if self.stale_variance is None:
            return self.position_weight / sigma_position
        return self.position_weight / np.sqrt(sigma_position**2 + self.stale_variance)

    @property
    def n_grid(self) -> int:
        return int(self.grid_voltage.size)

    def at_samples(self, grid_values: np.ndarray) -> np.ndarray:
        """Grid-point values (N_grid + 1) at the sample times."""
        if self.uniform:
            return grid_values[: self.time.size]
        return np.interp(self.time, self.dt * np.arange(grid_values.size), grid_values)


def prepare_log(
    time: np.ndarray,
    voltage: np.ndarray,
    position: np.ndarray,
    current: np.ndarray | None,
    *,
    resolution: float,
    source: str = "",
) -> Log:
    """Put one run on a simulation grid (see :class:`Log`)."""
    t = np.asarray(time, dtype=float) - float(time[0])
    steps = np.diff(t)
    dt = float(np.median(steps))
    uniform = bool(np.all(np.abs(steps - dt) <= 1e-3 * dt))
    if not uniform and np.all(np.abs(steps - dt) <= 0.2 * dt):
        # rows jittered about a fixed period: the mean step, or the grid would drift from the rows
        # (the median of jittered steps is off by ~σ/√n, a whole step after a few thousand rows)
        dt = float(t[-1]) / steps.size
    if uniform:
        grid_v = np.asarray(voltage[:-1], dtype=float)
    else:
        n_grid = int(np.ceil(t[-1] / dt - 1e-9))
        # each row's voltage holds until the next row: the step's voltage is the mean of that
        # staircase over the step (its integral is piecewise linear, so interpolation is exact),
        # not the row nearest the step's middle, which is off by up to half a row period when the
        # rows are irregular (an FTC loop of 10-40 ms)
        v = np.asarray(voltage, dtype=float)
        integral = np.concatenate([[0.0], np.cumsum(v[:-1] * steps)])
        edges = np.interp(dt * np.arange(n_grid + 1), t, integral, right=np.nan)
        edges = np.where(np.isnan(edges), integral[-1] + v[-1] * (dt * np.arange(n_grid + 1) - t[-1]), edges)
        grid_v = np.diff(edges) / dt
    grid_theta = grid_angle(t, np.asarray(position, dtype=float), dt, grid_v.size)
    # Moving at the first sample: the angle changes by more than two quanta within the first samples.
    # Three samples: a step applied right after the first row must not count as motion at the start.
    head = position[:3]
    moving = bool(np.ptp(head) > 2.0 * max(resolution, 1e-12)) if head.size > 1 else False
    cur = None if current is None else np.asarray(current, dtype=float)
    pos = np.asarray(position, dtype=float)
    reading, weight = reading_runs(pos)
    return Log(t, dt, grid_v, grid_theta, pos, cur, uniform, resolution, moving, source, reading, weight)


def grid_angle(time: np.ndarray, position: np.ndarray, dt: float, n_grid: int, *, lag: float = 0.0) -> np.ndarray:
    """Measured angle at the middle of each grid step, for gravity terms [rad].

    The angle at the middle of the step (interpolated between the readings around it) is the step's
    mean angle to first order; the angle at the start of the step would put the gravity term dt/2
    behind the motion, a shift of ω·dt/2 that biases an arm's offset, kS and kV by several standard
    errors. ``lag`` [s]: the readings lag the shaft by it (stale status frames), so the angle at
    t is read at t + lag.
    """
    return np.interp(dt * np.arange(n_grid) + 0.5 * dt + lag, time - time[0], position)


def reading_runs(position: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Run index of each sample among runs of identical consecutive readings, and weights 1/√(run length)."""
    position = np.asarray(position, dtype=float)
    if position.size == 0:
        return np.zeros(0, dtype=np.int64), np.ones(0)
    reading = np.concatenate([[0], np.cumsum(position[1:] != position[:-1])]).astype(np.int64)
    length = np.bincount(reading)
    return reading, 1.0 / np.sqrt(length[reading])


def stale_frame_period(log: Log) -> float:
    """Refresh period of the angle when the log repeats stale status frames [s], or 0.

    A motor controller sends its position every few milliseconds and the logging loop records the
    latest value it has, so at speed some rows repeat the previous angle although the shaft turned
    several counts. (Without stale frames a shaft turning at least one count per row never repeats a
    reading.) The fraction z of repeated rows where the shaft turns ≥ 1.5 counts per row gives
    the period P = dt/(1 − z) (every other row repeated: P = 2·dt). The logged angle is then
    θ(t − d) with d spread over [0, P): a lag of mean P/2. The first row showing a new reading
    places its frame within one row period (a scatter of (ω·dt)²/12 per reading), and the frames'
    phase, one per run, shifts the whole run's lag by up to ±dt/2 (see
    :func:`noise_propagation_covariance`).
    """
    q = log.resolution
    if q <= 0 or log.position.size < 30:
        return 0.0
    counts = np.abs(np.diff(log.position)) / q
    mean = np.convolve(counts, np.ones(7) / 7.0, mode="same")
    fast = mean >= 1.5
    if int(np.sum(fast)) < 20:
        return 0.0
    repeated = float(np.mean(counts[fast] < 0.5))
    if repeated < 0.2:
        return 0.0
    return log.dt / max(1.0 - repeated, 0.05)


def initial_speed_guess(log: Log) -> float:
    """Speed at the first sample from a straight line through the first samples [rad/s]."""
    m = max(3, min(10, log.position.size // 20))
    return float(np.polyfit(log.time[:m], log.position[:m], 1)[0])


@dataclass
class Fit:
    """Outcome of :func:`fit_output_error` (all in the model's own parameters)."""

    values: np.ndarray  # model parameters then nuisance parameters
    names: list[str]
    covariance: np.ndarray  # of the model parameters (HAC)
    covariance_white: np.ndarray  # plain s²·(JᵀJ)⁻¹, for comparison
    covariance_residuals: np.ndarray  # Newey–West from the residuals, for comparison
    null: np.ndarray  # bool per model parameter: loads on a direction without information
    residual_rms: dict[str, float]
    simulations: list[dict[str, np.ndarray]]
    bandwidth: int
    noise_model: str
    bias_correction: np.ndarray  # subtracted from the model parameters (errors in the input variable)
    nfev: int
    success: bool
    message: str
    jacobian: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))  # of the weighted residuals (SI)


class OEModel:
    """What :func:`fit_output_error` needs from a model (subclassed by identify and feedforward)."""

    names: tuple[str, ...] = ()
    uses_current: bool = False
    #: Lag τ [s] of the logged angle behind the simulated one (stale status frames, see
    #: :func:`stale_frame_period`): the angle compared is θ(t) − τ·ω(t).
    lag: float = 0.0
    #: The simulation is driven by the logged voltage sample by sample, so it carries that voltage's
    #: noise (errors in the input variable). False for an input model with its own parameters
    #: (held levels estimated from all their samples, :mod:`motorlab.held_input`).
    input_noise: bool = True

    def switches(self, p: np.ndarray, log: Log) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """Drive switches inside grid steps (see :func:`simulate`), or None."""
        return None

    def extra_residuals(self, p: np.ndarray) -> np.ndarray:
        """Weighted residuals appended after the signals' (e.g. logged voltage samples against held levels)."""
        return np.zeros(0)

    def local_start(self, j: int) -> tuple[int, int] | None:
        """(run, first grid step) of the only stretch parameter j affects, or None (it affects everything).

        Its Jacobian column is then simulated from that step on, restarted from the state the
        current simulation has there (full-model state (i, ω) on a uniform grid only).
        """
        return None

    def plant(self, p: np.ndarray) -> StatePlant:  # pragma: no cover - abstract
        raise NotImplementedError

    def drive(self, p: np.ndarray, log: Log) -> np.ndarray:
        """Effective voltage on the grid (the applied voltage less gravity terms) [V]."""
        return log.grid_voltage

    def initial(self, p: np.ndarray, log: Log, speed: float) -> np.ndarray:  # pragma: no cover
        raise NotImplementedError


def _simulate_log(model: OEModel, p: np.ndarray, log: Log, speed0: float, offset: float) -> dict[str, np.ndarray]:
    plant = model.plant(p)
    states, theta = simulate(plant, model.drive(p, log), log.dt, x0=model.initial(p, log, speed0), theta0=0.0,
                             switches=model.switches(p, log))
    out = {
        "position": log.at_samples(theta) + offset,
        "speed": log.at_samples(states[:, plant.w]),
    }
    if model.lag:
        out["position"] = out["position"] - model.lag * out["speed"]
    if model.uses_current:
        out["current"] = log.at_samples(states[:, 0])
    return out


def fit_output_error(
    model: OEModel,
    logs: list[Log],
    p0: np.ndarray,
    *,
    lower: np.ndarray,
    upper: np.ndarray,
    scale: np.ndarray,
    sigma: dict[str, float],
    current_noise: float = 0.0,
    max_nfev: int = 60,
) -> Fit:
    """Output-error least squares of measured angle (and current) against the simulated ones.

    Parameters
    ----------
    model
        The plant family.
    logs
        Runs fitted together (shared model parameters; per run an angle offset, and an initial
        speed for runs that start moving).
    p0, lower, upper, scale
        Start, bounds and typical magnitude of the model parameters (SI).
    sigma
        Noise level used to weight each signal: ``{"position": [rad], "current": [A]}`` (for the
        current, the measurement noise and the voltage noise the simulation carries, see
        :func:`input_noise_gain`).
    current_noise
        Measurement noise of the current alone [A], for the propagated covariance.

    Notes
    -----
    Residuals are (simulated − measured)/σ per signal. The Jacobian of the model parameters is by
    forward differences of the simulation; the angle offsets enter linearly (analytic column).
    Covariance: see :func:`hac_covariance`.
    """
    n_model = p0.size
    speed_logs = [k for k, log in enumerate(logs) if log.moving_at_start]
    names = list(model.names) + [f"theta0[{k}]" for k in range(len(logs))] + [f"omega0[{k}]" for k in speed_logs]
    signals = ["position"] + (["current"] if model.uses_current else [])
    # nuisance starting values
    offsets0 = np.array([log.position[0] for log in logs])
    speeds0 = np.array([initial_speed_guess(logs[k]) for k in speed_logs])
    speed_scale = np.maximum(np.abs(speeds0), 1.0)
    pos_scale = np.array([max(float(np.ptp(log.position)), 1.0) for log in logs])
    x_scale = np.concatenate([scale, pos_scale, speed_scale])

    def unpack(z: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        x = z * x_scale
        return x[:n_model], x[n_model : n_model + len(logs)], x[n_model + len(logs) :]

    def speed_of(k: int, speeds: np.ndarray) -> float:
        return float(speeds[speed_logs.index(k)]) if k in speed_logs else 0.0

    factors = [log.position_factor(sigma["position"]) for log in logs]

    def residual_parts(p: np.ndarray, offsets: np.ndarray, speeds: np.ndarray) -> tuple[np.ndarray, list]:
        parts = []
        sims = []
        for k, log in enumerate(logs):
            sim = _simulate_log(model, p, log, speed_of(k, speeds), float(offsets[k]))
            sims.append(sim)
            parts.append((sim["position"] - log.position) * factors[k])
            if model.uses_current:
                assert log.current is not None
                parts.append((sim["current"] - log.current) / sigma["current"])
        parts.append(model.extra_residuals(p))
        return np.concatenate(parts), sims

    last: dict[str, Any] = {}

    def fun(z: np.ndarray) -> np.ndarray:
        # least_squares asks for the Jacobian at the point it has just evaluated: keep that residual
        if "z" in last and np.array_equal(last["z"], z):
            return last["r"]
        p, offsets, speeds = unpack(z)
        r, sims = residual_parts(p, offsets, speeds)
        last["z"] = z.copy()
        last["r"] = r
        last["sims"] = sims  # type: ignore[assignment]
        return r

    row_starts = np.cumsum([0] + [log.time.size * len(signals) for log in logs])

    def local_column(zj: np.ndarray, k: int, k0: int, r0: np.ndarray) -> np.ndarray:
        """Residuals with log k re-simulated from grid step k0 (the parameter changed acts from there)."""
        p, offsets, _ = unpack(zj)
        log = logs[k]
        sim0 = last["sims"][k]  # type: ignore[index]
        sw = model.switches(p, log)
        if sw is not None:
            keep = sw[0] >= k0
            sw = (sw[0][keep] - k0, sw[1][keep], sw[2][keep])
        x0 = np.array([sim0["current"][k0], sim0["speed"][k0]])
        states, theta = simulate(model.plant(p), model.drive(p, log)[k0:], log.dt, x0=x0,
                                 theta0=float(sim0["position"][k0] - offsets[k]), switches=sw)
        r = r0.copy()
        rs, m = int(row_starts[k]), log.time.size
        assert log.current is not None
        r[rs + k0 : rs + m] = (theta + offsets[k] - log.position[k0:]) * factors[k][k0:]
        r[rs + m + k0 : rs + 2 * m] = (states[:, 0] - log.current[k0:]) / sigma["current"]
        r[int(row_starts[-1]) :] = model.extra_residuals(p)
        return r

    def jac(z: np.ndarray) -> np.ndarray:
        r0 = fun(z)
        cols = np.empty((r0.size, z.size))
        for j in range(z.size):
            if n_model <= j < n_model + len(logs):
                continue
            h = 1e-6 * max(abs(z[j]), 1.0)
            if z[j] + h > upper_z[j]:
                h = -h
            zj = z.copy()
            zj[j] += h
            loc = model.local_start(j) if j < n_model else None
            if loc is not None and logs[loc[0]].uniform and model.uses_current and not model.lag:
                cols[:, j] = (local_column(zj, loc[0], loc[1], r0) - r0) / h
                continue
            p, offsets, speeds = unpack(zj)
            cols[:, j] = (residual_parts(p, offsets, speeds)[0] - r0) / h
        # angle offsets: residual of log k's angle rises 1/σ per unit offset
        start = 0
        for k, log in enumerate(logs):
            col = np.zeros(r0.size)
            m = log.time.size
            col[start : start + m] = x_scale[n_model + k] * factors[k]
            cols[:, n_model + k] = col
            start += m * len(signals)
        return cols

    z0 = np.concatenate([p0, offsets0, speeds0]) / x_scale
    lower_z = np.concatenate([lower / scale, np.full(len(logs) + len(speed_logs), -np.inf)])
    upper_z = np.concatenate([upper / scale, np.full(len(logs) + len(speed_logs), np.inf)])
    finite = np.isfinite(lower_z)
    z0 = np.where(finite, np.maximum(z0, np.where(finite, lower_z, 0.0) + 1e-6), z0)
    z0 = np.minimum(z0, upper_z)

    sol = levenberg_marquardt(fun, jac, z0, lower_z, upper_z, max_iterations=max_nfev)
    p, offsets, speeds = unpack(sol.x)
    res, sims = residual_parts(p, offsets, speeds)
    jz = sol.jac
    jx = jz / x_scale  # d residual / d parameter (SI)
    # residual series per log, as (time, signal) blocks for the long-run covariance
    blocks = []
    start = 0
    for log in logs:
        m = log.time.size
        blocks.append((start, m))
        start += m * len(signals)
    values = sol.x * x_scale
    # The residual is made of the logged voltage's noise run through the plant (integrated twice into
    # the angle: a random walk no stationary residual model captures), counting noise and current
    # noise. Propagate them, unless the residuals are more than twice what they explain: then the
    # model misses something real (a load, a delay, stale samples) and only the residuals say how
    # uncertain the fit is. Residuals well below the prediction (the propagation is conservative for
    # stale status frames; or what looked like voltage noise is real ripple the motor saw) keep the
    # propagated, larger, uncertainty.
    cov_prop, predicted = noise_propagation_covariance(jx, model, p, logs, sims, blocks, sigma,
                                                       current_noise=current_noise)
    actual = float(np.mean(res**2))
    ratio = actual / predicted if predicted > 0 else math.inf
    explained = ratio <= 2.0
    bias = np.zeros(values.size)
    if model.uses_current and model.input_noise and 0.5 <= ratio <= 2.0:
        # The logged voltage's noise reaches the simulated current (errors in the input variable) and
        # biases L and R: remove the first-order bias (see input_noise_bias). Only when the residuals
        # look like that noise: real ripple on the voltage is input the motor saw, and biases nothing.
        bias = input_noise_bias(jx, model, p, logs, sigma["current"])
        if np.all(np.isfinite(bias)) and np.all(values - bias >= lower_z * x_scale) and np.any(bias):
            values = values - bias
            p, offsets, speeds = unpack(values / x_scale)
            res, sims = residual_parts(p, offsets, speeds)
        else:
            bias = np.zeros(values.size)
    cov_hac, cov_white, null, bandwidth = hac_covariance(jx, res, blocks, len(signals), values)
    if explained:
        cov_full = cov_prop * max(1.0, ratio)  # never below what the residuals themselves show
        noise_model = "measured noise propagated (voltage, counting" + (", current)" if model.uses_current else ")")
    else:
        cov_full = cov_hac
        noise_model = f"Newey–West (residuals {math.sqrt(ratio):.3g}× larger than the measured noise explains)"
    rms: dict[str, float] = {}
    for name in signals:
        err = np.concatenate(
            [sims[k][name] - (log.position if name == "position" else log.current) for k, log in enumerate(logs)]
        )  # type: ignore[operator]
        rms[name] = float(np.sqrt(np.mean(err**2)))
    return Fit(
        values=values,
        names=names,
        covariance=cov_full,
        covariance_white=cov_white,
        covariance_residuals=cov_hac,
        null=null,
        residual_rms=rms,
        simulations=sims,
        bandwidth=bandwidth,
        noise_model=noise_model,
        bias_correction=bias[:n_model],
        jacobian=jx,
        nfev=int(sol.nfev),
        success=bool(sol.success),
        message=str(sol.message),
    )


def integrated_autocorrelation(x: np.ndarray) -> float:
    """τ = 1 + 2·Σρ_l summed until ρ first drops below zero [samples]."""
    x = np.asarray(x, dtype=float) - float(np.mean(x))
    n = x.size
    if n < 4 or not np.any(x):
        return 1.0
    f = np.fft.rfft(x, 2 * n)
    acf = np.fft.irfft(f * np.conj(f))[:n]
    acf = acf / acf[0]
    neg = np.flatnonzero(acf[1:] <= 0.0)
    stop = int(neg[0]) + 1 if neg.size else n
    return float(1.0 + 2.0 * np.sum(acf[1:stop]))


def noise_warning(fit: Fit, *, rms_text: str) -> list[str]:
    """The warning to give when the uncertainties had to come from the residuals (empty otherwise)."""
    if not fit.noise_model.startswith("Newey"):
        return []
    return [
        f"the measured noise does not explain the residuals (residual RMS {rms_text}; {fit.noise_model}): "
        "uncertainties come from the residuals"
    ]


#: Eigenvalues of the column-scaled Gram matrix JᵀJ below this fraction of the largest carry no
#: information (a scaled condition number of J above ~1e5): finite-difference Jacobians of a
#: simulation with events are not more accurate than that, and a parameter on such a direction has
#: a relative standard error far above 100 % anyway.
INFO_TOLERANCE = 1e-10


def scaled_gram_inverse(jac: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(JᵀJ)⁻¹ through the eigen-decomposition of the column-scaled Gram matrix, and the null mask.

    Directions with (almost) no information are dropped (pseudo-inverse) and every parameter that
    loads on one is returned as ``null`` (not determined), so no variance is silently set to zero.
    """
    p = jac.shape[1]
    col = np.linalg.norm(jac, axis=0)
    col = np.where(col > 0, col, 1.0)
    js = jac / col
    eig, vec = np.linalg.eigh(js.T @ js)
    eig = np.clip(eig, 0.0, None)
    keep = eig > INFO_TOLERANCE * float(eig.max() if eig.size else 1.0)
    null_dirs = vec[:, ~keep].T
    null = (np.abs(null_dirs) > 1e-3).any(axis=0) if null_dirs.size else np.zeros(p, dtype=bool)
    inv_eig = np.where(keep, 1.0 / np.where(keep, eig, 1.0), 0.0)
    return ((vec * inv_eig) @ vec.T) / np.outer(col, col), null


def hac_covariance(
    jac: np.ndarray, res: np.ndarray, blocks: list[tuple[int, int]], n_signals: int, values: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """Covariance of the parameters that allows for correlated residuals (Newey–West).

    cov = H⁻¹·S·H⁻¹ with H = JᵀJ and S the long-run covariance of the score g_t = Σ_signals J_tᵀ·r_t,
    S = Σ_{|l|≤M} (1 − |l|/(M+1))·Γ_l (Bartlett weights), summed over runs. For white residuals it is
    the usual s²·(JᵀJ)⁻¹. The bandwidth M is three times the largest integrated autocorrelation time
    of the residuals (quantised angles at rest, stale samples and voltage noise integrated twice
    make position residuals strongly correlated), at most half of each run.

    Returns
    -------
    cov, cov_white, null, bandwidth
        Newey–West covariance, the plain one, the parameters on a null direction, M [samples].

    References
    ----------
    W. K. Newey and K. D. West, "A simple, positive semi-definite, heteroskedasticity and
    autocorrelation consistent covariance matrix", Econometrica 55 (1987) 703–708.
    """
    n, p = jac.shape
    h_inv, null = scaled_gram_inverse(jac)
    cov_white = h_inv * float(res @ res) / max(n - p, 1)
    # One bandwidth per run: three integrated autocorrelation times of its residuals, at most half
    # the run (quasistatic ramps have far longer correlation than short dynamic steps).
    s_mat = np.zeros((p, p))
    bandwidth = 0
    for start, m in blocks:
        tau = max(
            integrated_autocorrelation(res[start + sgl * m : start + (sgl + 1) * m]) for sgl in range(n_signals)
        )
        band = int(min(max(3.0 * tau, 1.0), max(m // 2, 1)))
        bandwidth = max(bandwidth, band)
        weights = 1.0 - np.abs(np.arange(-band, band + 1)) / (band + 1.0)
        g = np.zeros((m, p))
        for sgl in range(n_signals):
            sl = slice(start + sgl * m, start + (sgl + 1) * m)
            g += jac[sl] * res[sl, None]
        kg = signal.fftconvolve(g, weights[:, None], mode="same", axes=0) if band > 0 else g
        s_mat += g.T @ kg
    s_mat = 0.5 * (s_mat + s_mat.T) * n / max(n - p, 1)
    cov = h_inv @ s_mat @ h_inv
    return cov, cov_white, null, bandwidth


@dataclass
class _Solution:
    x: np.ndarray
    fun: np.ndarray
    jac: np.ndarray
    nfev: int
    success: bool
    message: str


def levenberg_marquardt(
    fun: Callable[[np.ndarray], np.ndarray],
    jac: Callable[[np.ndarray], np.ndarray],
    x0: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    *,
    max_iterations: int = 60,
    ftol: float = 1e-7,
) -> _Solution:
    """Bounded Levenberg–Marquardt on the normal equations (p × p), steps projected onto the bounds.

    The problems here have few parameters and many residuals: forming JᵀJ costs a matrix product,
    where a trust-region solver's SVD of the tall Jacobian (scipy's ``trf``) costs far more on a busy
    machine. Stops when an accepted step lowers the cost by less than ``ftol`` relative (with residuals
    in units of their noise that is far below one unit of χ²).
    """
    x = np.clip(x0, lower, upper)
    r = fun(x)
    cost = float(r @ r)
    nfev = 1
    j = jac(x)
    mu = 1e-3
    message = "maximum number of iterations reached"
    success = False
    for _ in range(max_iterations):
        g = j.T @ r
        h = j.T @ j
        diag = np.diag(h).copy()
        diag = np.where(diag > 0, diag, 1.0)
        # Parameters held at a bound by the gradient stay there (active set): a step computed for all
        # and then clipped would crawl along the bound (a switch on its sample instant, f = 1).
        free = ~(((x <= lower) & (g > 0)) | ((x >= upper) & (g < 0)))
        accepted = False
        for _ in range(12):
            step = np.zeros_like(x)
            try:
                step[free] = -np.linalg.solve((h + mu * np.diag(diag))[np.ix_(free, free)], g[free])
            except np.linalg.LinAlgError:
                mu *= 10.0
                continue
            x_new = np.clip(x + step, lower, upper)
            r_new = fun(x_new)
            nfev += 1
            cost_new = float(r_new @ r_new) if np.all(np.isfinite(r_new)) else np.inf
            if cost_new < cost:
                accepted = True
                break
            mu *= 4.0
        if not accepted:
            message = "no step lowers the cost"
            success = True  # at a (local) minimum to the precision of the simulation
            break
        drop = (cost - cost_new) / max(cost, 1e-300)
        x, r, cost = x_new, r_new, cost_new
        j = jac(x)
        mu = max(mu / 3.0, 1e-9)
        if drop < ftol:
            message = "relative cost reduction below tolerance"
            success = True
            break
    return _Solution(x, r, j, nfev, success, message)



def voltage_noise(log: Log) -> float:
    """Sample-to-sample noise of the logged voltage, 1.4826·MAD(Δ²V)/√6 [V] (robust to steps and ramps)."""
    d2 = np.diff(log.grid_voltage, 2)
    if d2.size < 3:
        return 0.0
    return float(1.4826 * np.median(np.abs(d2 - np.median(d2))) / np.sqrt(6.0))


def _filters(d: _Discrete) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rational filters (in z⁻¹) from a held voltage perturbation δV_k to the states and angle increments.

    Returns (numerators of each state (n × 3), numerator of the angle increment hx·x_k + hv·δV_k (3,),
    common denominator (3,)); x_k depends on δV_j for j < k only (the leading coefficient is zero).
    """
    if d.ad.shape[0] == 1:
        den = np.array([1.0, -d.ad[0, 0], 0.0])
        states = np.array([[0.0, d.bv[0], 0.0]])
    else:
        (a11, a12), (a21, a22) = d.ad
        b0, b1 = d.bv
        den = np.array([1.0, -(a11 + a22), a11 * a22 - a12 * a21])
        # X = (zI − Ad)⁻¹·bv·E: X0 = [z⁻¹b0 + z⁻²(a12·b1 − a22·b0)]/det, X1 = [z⁻¹b1 + z⁻²(a21·b0 − a11·b1)]/det
        states = np.array([[0.0, b0, a12 * b1 - a22 * b0], [0.0, b1, a21 * b0 - a11 * b1]])
    increment = d.hx @ states + d.hv * den
    return states, increment, den


def _adjoint(num: np.ndarray, den: np.ndarray, u: np.ndarray) -> np.ndarray:
    """a_k = Σ_{m≥0} h(m)·u_{k+m} for the impulse response h of num/den (filtering backwards in time)."""
    return signal.lfilter(num, den, u[::-1], axis=0)[::-1]


def _sample_to_grid(log: Log, values: np.ndarray) -> np.ndarray:
    """Spread per-sample rows onto the N_grid + 1 grid points (the transpose of nearest-point sampling)."""
    if log.uniform:
        return values
    out = np.zeros((log.n_grid + 1, values.shape[1]))
    idx = np.clip(np.round(log.time / log.dt).astype(int), 0, log.n_grid)
    np.add.at(out, idx, values)
    return out


#: Terms of the Fourier series of the counting-error covariance (the rest is folded in by scaling).
COUNTING_HARMONICS = 32


def _counting_score(g: np.ndarray, log: Log, angle: np.ndarray, sigma_position: float) -> np.ndarray:
    """Covariance of Σ_t g_t·e_t for the counting errors e_t of one run (g in 1/rad) [score units].

    A quantised angle θ reads ⌊(θ + φ)/q⌋·q with an unknown phase φ, so two errors are not
    independent: over φ, cov(e_s, e_t) = q²·B₂(frac((θ_t − θ_s)/q))/2 with B₂(u) = u² − u + 1/6 (a
    shaft at rest repeats one error; a speed of a whole number of counts per sample repeats it too,
    which white counting noise would miss). With B₂(frac u)/2 = Σ_k cos(2πku)/(2π²k²) the double sum
    is Σ_k |Σ_t g_t·exp(2πikθ_t/q)|²·q²/(2π²k²), a few harmonics of the simulated angle θ_t.
    Without a known quantum the errors of a run of identical readings are taken as one white error
    of σ = ``sigma_position``.
    """
    q = log.resolution
    if q <= 0:
        runs = np.zeros((int(log.reading[-1]) + 1, g.shape[1]))
        np.add.at(runs, log.reading, g)
        return sigma_position**2 * (runs.T @ runs)
    angle = np.asarray(angle, dtype=float)
    if log.stale_variance is not None:
        # stale frames: the rows of one reading repeat one sample of the angle, and its error
        first = np.flatnonzero(np.diff(np.concatenate([[-1], log.reading])))
        angle = angle[first][log.reading]
    phase = (2.0 * np.pi / q) * (angle - float(angle[0]))
    k = np.arange(1, COUNTING_HARMONICS + 1)
    waves = np.exp(1j * np.outer(k, phase))  # K × m
    sums = waves @ g  # K × P
    weights = q**2 / (2.0 * np.pi**2 * k**2)
    weights *= (np.pi**2 / 6.0) / float(np.sum(1.0 / k**2))  # keep the total variance q²/12
    return (sums.real.T * weights) @ sums.real + (sums.imag.T * weights) @ sums.imag


def noise_propagation_covariance(
    jac: np.ndarray,
    model: OEModel,
    p: np.ndarray,
    logs: list[Log],
    sims: list[dict[str, np.ndarray]],
    blocks: list[tuple[int, int]],
    sigma: dict[str, float],
    *,
    current_noise: float = 0.0,
) -> tuple[np.ndarray, float]:
    """Covariance of the estimates from the noise the data carry, propagated through the linearised fit.

    Three independent noises make the residual: white noise of the measured level σ_V on the logged
    voltage (the plant was driven by the true voltage, the fit by the logged one: errors in the input
    variable), run through the plant linearised about the fit (the angle does not move while the
    simulated shaft is at rest) into the simulated angle and current; counting noise of σ = the angle
    weight, correlated as the phase of a quantised angle makes them (:func:`_counting_score`); stale
    status frames (:func:`stale_frame_period`); with current, white current noise of ``current_noise``.
    The estimate moves by δ = (JᵀJ)⁻¹·Jᵀ·δr, δr
    the weighted residual perturbation, so cov(δ) = (JᵀJ)⁻¹·S·(JᵀJ)⁻¹ with S the covariance of the
    score Jᵀ·δr, computed exactly: for the voltage noise S = σ_V²·AᵀA, A the Jacobian filtered
    backwards in time through the plant's impulse responses (the adjoint system).

    Returns
    -------
    cov, predicted
        The covariance of all fitted parameters, and the mean square weighted residual this noise
        predicts (to check that it explains the residuals).
    """
    n, n_par = jac.shape
    score = np.zeros((n_par, n_par))
    expected_square = 0.0
    plant = model.plant(p)
    sigma_position = sigma["position"]
    for (start, m), log, sim in zip(blocks, logs, sims, strict=True):
        j_pos = jac[start : start + m]
        f = log.position_factor(sigma_position)
        g = j_pos * f[:, None]
        score += _counting_score(g, log, sim["position"], sigma_position)
        expected_square += float(np.sum(f**2)) * sigma_position**2
        if log.stale_variance is not None:
            # stale status frames: one timing error per reading, of variance (ω·dt)²/12
            runs = np.zeros((int(log.reading[-1]) + 1, n_par))
            np.add.at(runs, log.reading, g)
            first = np.flatnonzero(np.diff(np.concatenate([[-1], log.reading])))
            score += (runs.T * log.stale_variance[first]) @ runs
            expected_square += float(np.sum(f**2 * log.stale_variance))
            # The frames keep one phase through a run, so its lag is P/2 only on average: the rows
            # where a new reading appears place each frame within one row period, a lag error of
            # variance dt²/12 shared by the whole run (a systematic shift of −δτ·ω).
            shift = g.T @ sim["speed"]
            score += (log.dt**2 / 12.0) * np.outer(shift, shift)
        j_cur = jac[start + m : start + 2 * m] if model.uses_current else None
        if j_cur is not None:
            ratio = current_noise / sigma["current"]
            score += ratio**2 * (j_cur.T @ j_cur)
            expected_square += m * ratio**2
        sig_v = voltage_noise(log) if model.input_noise else 0.0
        if sig_v <= 0:
            continue
        d = _Modal(plant, 1).discrete(log.dt)
        states, increment, den = _filters(d)
        mask = _grid_mask(log, np.abs(sim["speed"]) > 0)
        # angle: Σ_t c_t·θ_t = Σ_j mask_j·inc_j·C_j with C_j = Σ_{t>j} c_t, c_t = J_t·w_t/σ
        c_grid = _sample_to_grid(log, g)
        tail = np.cumsum(c_grid[::-1], axis=0)[::-1]  # Σ_{t≥j}
        u = mask[:, None] * tail[1 : log.n_grid + 1]
        a = _adjoint(increment, den, u)
        gain = float(np.sum(increment) / np.sum(den))  # angle per volt per step at low frequency
        moving_steps = np.concatenate([[0.0], np.cumsum(mask)])
        expected_square += sig_v**2 * gain**2 * float(np.sum(f**2 * log.at_samples(moving_steps)))
        if j_cur is not None:
            ci_grid = _sample_to_grid(log, j_cur / sigma["current"])
            a = a + _adjoint(states[0], den, ci_grid)[: log.n_grid]
            p00 = float(linalg.solve_discrete_lyapunov(d.ad, np.outer(d.bv, d.bv))[0, 0])
            expected_square += m * sig_v**2 * p00 / sigma["current"] ** 2
        score += sig_v**2 * (a.T @ a)
    end = blocks[-1][0] + blocks[-1][1] * (2 if model.uses_current else 1) if blocks else 0
    extra = jac[end:]  # rows of unit-variance white residuals (logged voltage samples against held levels)
    score += extra.T @ extra
    expected_square += extra.shape[0]
    h_inv, _ = scaled_gram_inverse(jac)
    return h_inv @ score @ h_inv, expected_square / max(n, 1)


def input_noise_gain(plant: StatePlant, dt: float) -> np.ndarray:
    """Stationary covariance of the state per unit variance of white noise on the held voltage [state²/V²].

    P = Ad·P·Adᵀ + bv·bvᵀ (discrete Lyapunov equation of the moving regime): the current the model
    simulates from a logged voltage with noise σ_V carries σ_V²·P[i, i] of it, sample by sample.
    """
    d = _Modal(plant, 1).discrete(dt)
    return np.asarray(linalg.solve_discrete_lyapunov(d.ad, np.outer(d.bv, d.bv)))


def input_noise_bias(
    jac: np.ndarray, model: OEModel, p: np.ndarray, logs: list[Log], sigma_current: float
) -> np.ndarray:
    """First-order bias of the output-error estimate from white noise on the logged voltage (current channel).

    The simulated current carries the voltage noise filtered by the plant, so the expected cost gains
    N(p) = Σ_runs n·σ_V²·P_ii(p)/σ_i² (:func:`input_noise_gain`), which depends on the parameters
    (mostly L and R: a slower or more resistive winding passes less of the noise) and pulls the
    minimum away from the truth by −½·(JᵀJ)⁻¹·∇N. Returns that shift for every parameter (model
    parameters first; ∇N is zero for the nuisance ones); subtract it from the estimate.

    References
    ----------
    T. Söderström, *Errors-in-Variables Methods in System Identification*, Springer 2018, ch. 7
    (bias-compensated least squares).
    """
    n_model = p.size

    def noise_cost(q: np.ndarray) -> float:
        total = 0.0
        plant = model.plant(q)
        for log in logs:
            sig_v = voltage_noise(log)
            if sig_v > 0:
                total += log.time.size * sig_v**2 * float(input_noise_gain(plant, log.dt)[0, 0])
        return total / sigma_current**2

    base = noise_cost(p)
    grad = np.zeros(jac.shape[1])
    if base == 0.0:
        return grad
    for k in range(n_model):
        h = 1e-5 * max(abs(float(p[k])), 1e-12)
        q = p.copy()
        q[k] += h
        grad[k] = (noise_cost(q) - base) / h
    return -0.5 * scaled_gram_inverse(jac)[0] @ grad


def _grid_mask(log: Log, moving_at_samples: np.ndarray) -> np.ndarray:
    """Per grid step: True where the simulated shaft moves (from the samples' flags)."""
    if log.uniform:
        return np.asarray(moving_at_samples[: log.n_grid], dtype=float)
    idx = np.clip(np.searchsorted(log.time, log.dt * np.arange(log.n_grid), side="right") - 1, 0, log.time.size - 1)
    return np.asarray(moving_at_samples[np.minimum(idx, moving_at_samples.size - 1)], dtype=float)
