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
from dataclasses import dataclass

import numpy as np
from scipy import linalg, signal

_MIN_CHUNK = 64


@dataclass(frozen=True)
class Plant:
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


def motor_plant(K: float, R: float, L: float, J: float, b: float, Tf: float) -> Plant:
    """The full model ``L·di/dt = V − R·i − K·ω``, ``J·dω/dt = K·i − b·ω − Tf·sgn(ω)``; state (i, ω)."""
    a = np.array([[-R / L, -K / L], [K / J, -b / J]])
    return Plant(a, np.array([1.0 / L, 0.0]), np.array([0.0, -Tf / J]), 1)


def feedforward_plant(kS: float, kV: float, kA: float) -> Plant:
    """The feedforward model ``V = kS·sgn(ω) + kV·ω + kA·α``; state (ω)."""
    return Plant(np.array([[-kV / kA]]), np.array([1.0 / kA]), np.array([-kS / kA]), 0)


def _regime(plant: Plant, s: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
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

    def __init__(self, plant: Plant, s: int):
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


def _discretise_expm(plant: Plant, s: int, tau: float) -> _Discrete:
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
    plant: Plant, voltage: np.ndarray, dt: float, *, x0: np.ndarray | None = None, theta0: float = 0.0
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
    while k < n_steps:
        stop = min(n_steps, k + chunk)
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


# --------------------------------------------------------------------------------------------------
# Output-error fitting engine shared by identify and feedforward
# --------------------------------------------------------------------------------------------------


@dataclass
class Log:
    """One run prepared for fitting.

    The simulation runs on a uniform grid of step ``dt`` starting at the first sample; the voltage
    of each grid step is the last logged voltage at or before it (zero-order hold). When the samples
    are themselves uniform the grid is the samples.
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
    if uniform:
        grid_v = np.asarray(voltage[:-1], dtype=float)
        grid_theta = np.asarray(position[:-1], dtype=float)
    else:
        n_grid = int(np.ceil(t[-1] / dt - 1e-9))
        tg = dt * np.arange(n_grid)
        idx = np.clip(np.searchsorted(t, tg + 1e-9 * dt, side="right") - 1, 0, t.size - 1)
        grid_v = np.asarray(voltage, dtype=float)[idx]
        grid_theta = np.asarray(position, dtype=float)[idx]
    # Moving at the first sample: the angle changes by more than two quanta within the first samples.
    head = position[: max(3, min(10, position.size // 20))]
    moving = bool(np.ptp(head) > 2.0 * max(resolution, 1e-12)) if head.size > 1 else False
    cur = None if current is None else np.asarray(current, dtype=float)
    pos = np.asarray(position, dtype=float)
    return Log(t, dt, grid_v, grid_theta, pos, cur, uniform, resolution, moving, source)


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
    null: np.ndarray  # bool per model parameter: loads on a direction without information
    residual_rms: dict[str, float]
    simulations: list[dict[str, np.ndarray]]
    bandwidth: int
    noise_model: str
    nfev: int
    success: bool
    message: str


class OEModel:
    """What :func:`fit_output_error` needs from a model (subclassed by identify and feedforward)."""

    names: tuple[str, ...] = ()
    uses_current: bool = False

    def plant(self, p: np.ndarray) -> Plant:  # pragma: no cover - abstract
        raise NotImplementedError

    def drive(self, p: np.ndarray, log: Log) -> np.ndarray:
        """Effective voltage on the grid (the applied voltage less gravity terms) [V]."""
        return log.grid_voltage

    def initial(self, p: np.ndarray, log: Log, speed: float) -> np.ndarray:  # pragma: no cover
        raise NotImplementedError


def _simulate_log(model: OEModel, p: np.ndarray, log: Log, speed0: float, offset: float) -> dict[str, np.ndarray]:
    plant = model.plant(p)
    states, theta = simulate(plant, model.drive(p, log), log.dt, x0=model.initial(p, log, speed0), theta0=0.0)
    out = {
        "position": log.at_samples(theta) + offset,
        "speed": log.at_samples(states[:, plant.w]),
    }
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
        Noise level used to weight each signal: ``{"position": [rad], "current": [A]}``.

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

    def residual_parts(p: np.ndarray, offsets: np.ndarray, speeds: np.ndarray) -> tuple[np.ndarray, list]:
        parts = []
        sims = []
        for k, log in enumerate(logs):
            sim = _simulate_log(model, p, log, speed_of(k, speeds), float(offsets[k]))
            sims.append(sim)
            parts.append((sim["position"] - log.position) / sigma["position"])
            if model.uses_current:
                assert log.current is not None
                parts.append((sim["current"] - log.current) / sigma["current"])
        return np.concatenate(parts), sims

    last: dict[str, np.ndarray] = {}

    def fun(z: np.ndarray) -> np.ndarray:
        # least_squares asks for the Jacobian at the point it has just evaluated: keep that residual
        if "z" in last and np.array_equal(last["z"], z):
            return last["r"]
        p, offsets, speeds = unpack(z)
        r = residual_parts(p, offsets, speeds)[0]
        last["z"] = z.copy()
        last["r"] = r
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
            p, offsets, speeds = unpack(zj)
            cols[:, j] = (residual_parts(p, offsets, speeds)[0] - r0) / h
        # angle offsets: residual of log k's angle rises 1/σ per unit offset
        start = 0
        for k, log in enumerate(logs):
            col = np.zeros(r0.size)
            m = log.time.size
            col[start : start + m] = x_scale[n_model + k] / sigma["position"]
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
    cov_hac, cov_white, null, bandwidth = hac_covariance(jx, res, blocks, len(signals), sol.x * x_scale)
    cov_full = cov_hac
    noise_model = "Newey–West"
    if not model.uses_current:
        # Angle only: the residual is dominated by the logged voltage's noise integrated by the plant
        # (a random walk no stationary residual model captures) plus counting noise. Propagate both.
        cov_prop, predicted = noise_propagation_covariance(jx, model, p, logs, sims, blocks, sigma["position"])
        actual = float(np.mean(res**2))
        if actual <= 2.0 * predicted:
            cov_full = cov_prop
            noise_model = "voltage noise propagated + counting noise"
        else:
            # the residuals are larger than the measured noise explains: the model misses something
            # real (a load, a delay, stale samples), and only the residuals themselves say how much
            noise_model = (
                f"Newey–West (residuals {math.sqrt(actual / predicted):.3g}× larger than the measured noise explains)"
            )
    rms: dict[str, float] = {}
    for name in signals:
        err = np.concatenate(
            [sims[k][name] - (log.position if name == "position" else log.current) for k, log in enumerate(logs)]
        )  # type: ignore[operator]
        rms[name] = float(np.sqrt(np.mean(err**2)))
    return Fit(
        values=sol.x * x_scale,
        names=names,
        covariance=cov_full,
        covariance_white=cov_white,
        null=null,
        residual_rms=rms,
        simulations=sims,
        bandwidth=bandwidth,
        noise_model=noise_model,
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


def hac_covariance(
    jac: np.ndarray, res: np.ndarray, blocks: list[tuple[int, int]], n_signals: int, values: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """Covariance of the parameters that allows for correlated residuals (Newey–West).

    cov = H⁻¹·S·H⁻¹ with H = JᵀJ and S the long-run covariance of the score g_t = Σ_signals J_tᵀ·r_t,
    S = Σ_{|l|≤M} (1 − |l|/(M+1))·Γ_l (Bartlett weights), summed over runs. For white residuals it is
    the usual s²·(JᵀJ)⁻¹. The bandwidth M is three times the largest integrated autocorrelation time
    of the residuals (quantised angles at rest, stale samples and voltage noise integrated twice
    make position residuals strongly correlated), at most a third of the shortest run.

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
    # Information through the eigen-decomposition of the column-scaled Gram matrix JᵀJ (p × p: cheap,
    # and the same null directions as motorlab.fitting's SVD of the scaled Jacobian).
    col = np.linalg.norm(jac, axis=0)
    col = np.where(col > 0, col, 1.0)
    js = jac / col
    eig, vec = np.linalg.eigh(js.T @ js)
    eig = np.clip(eig, 0.0, None)
    keep = eig > (1e-9) ** 2 * float(eig.max() if eig.size else 1.0)
    null_dirs = vec[:, ~keep].T
    null = (np.abs(null_dirs) > 1e-3).any(axis=0) if null_dirs.size else np.zeros(p, dtype=bool)
    inv_eig = np.where(keep, 1.0 / np.where(keep, eig, 1.0), 0.0)
    h_inv = ((vec * inv_eig) @ vec.T) / np.outer(col, col)
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
        accepted = False
        for _ in range(12):
            try:
                step = -np.linalg.solve(h + mu * np.diag(diag), g)
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


def noise_propagation_covariance(
    jac: np.ndarray,
    model: OEModel,
    p: np.ndarray,
    logs: list[Log],
    sims: list[dict[str, np.ndarray]],
    blocks: list[tuple[int, int]],
    sigma_position: float,
    *,
    draws: int = 200,
    seed: int = 0,
) -> tuple[np.ndarray, float]:
    """Covariance of the estimates from the noise the data carry, by a linearised parametric bootstrap.

    Each draw adds white noise of the measured level to the logged voltage (the plant was driven by
    the true voltage, the fit by the logged one), runs it through the plant linearised about the fit
    (zero while the simulated shaft is at rest), adds white angle noise of σ = the angle weight
    (counting noise q/√12 or the measured sample noise), and maps the resulting angle error through
    the linearised estimator δ = (JᵀJ)⁻¹·Jᵀ·e/σ. The spread of δ over the draws is the covariance;
    the mean of (e/σ)² is returned too, to check that this noise explains the residuals. Draws use
    ``np.random.default_rng(seed)``, so results are reproducible.
    """
    rng = np.random.default_rng(seed)
    n, n_par = jac.shape
    draws = int(max(50, min(draws, 4_000_000 // max(n, 1))))
    jte = np.zeros((n_par, draws))
    square_sum = 0.0
    plant = model.plant(p)
    for (start, m), log, sim in zip(blocks, logs, sims, strict=True):
        sig_v = voltage_noise(log)
        err = sigma_position * rng.standard_normal((m, draws))
        if sig_v > 0:
            d = _Modal(plant, 1).discrete(log.dt)
            dv = sig_v * rng.standard_normal((log.n_grid, draws))
            # state response x⁺ = Ad·x + bv·δV and angle increments hx·x + hv·δV, all draws at once
            x = np.zeros((plant.n, draws))
            xs = np.empty((log.n_grid, plant.n, draws))
            if plant.n == 1:
                xs[:, 0, :] = signal.lfilter([0.0, d.bv[0]], [1.0, -d.ad[0, 0]], dv, axis=0)
            else:  # pragma: no cover - the angle-only models are first order
                for k in range(log.n_grid):
                    xs[k] = x
                    x = d.ad @ x + d.bv[:, None] * dv[k]
            inc = np.einsum("i,kid->kd", d.hx, xs) + d.hv * dv
            moving = np.abs(sim["speed"]) > 0
            theta = np.vstack([np.zeros((1, draws)), np.cumsum(inc * _grid_mask(log, moving)[:, None], axis=0)])
            err += log.at_samples(theta) if log.uniform else np.column_stack(
                [log.at_samples(theta[:, b]) for b in range(draws)]
            )
        jte += jac[start : start + m].T @ (err / sigma_position)
        square_sum += float(np.sum((err / sigma_position) ** 2)) / draws
    h_inv = np.linalg.pinv(jac.T @ jac)
    delta = h_inv @ jte
    delta -= delta.mean(axis=1, keepdims=True)
    return delta @ delta.T / (draws - 1), square_sum / max(n, 1)


def _grid_mask(log: Log, moving_at_samples: np.ndarray) -> np.ndarray:
    """Per grid step: True where the simulated shaft moves (from the samples' flags)."""
    if log.uniform:
        return np.asarray(moving_at_samples[: log.n_grid], dtype=float)
    idx = np.clip(np.searchsorted(log.time, log.dt * np.arange(log.n_grid), side="right") - 1, 0, log.time.size - 1)
    return np.asarray(moving_at_samples[np.minimum(idx, moving_at_samples.size - 1)], dtype=float)
