"""Simulation of the DC motor model under the drives the seeds use.

Model (SI, at the encoder's shaft)::

    L·di/dt = V − R·i − K·ω
    J·dω/dt = K·i − b·ω − Tf·sgn(ω)        with stiction: ω = 0 stays while |K·i| ≤ Tf

Drives: an ideal voltage source, an ideal current source (seed 2's servo amplifier), a bench supply
with constant-voltage/constant-current crossover that cannot sink current (seed 1's supply), and an
open circuit (relay off: i = 0, terminal voltage K·ω).

Method
------
Between events the model is linear time-invariant with a held (zero-order-hold) input, so each step is
propagated *exactly* with the matrix exponential of the augmented system (no stiffness problem however
small L/R is). Long stretches are computed at once as a rational filter
(:func:`motorlab.model.propagate`, the fits' simulator's too), which is what makes a 300 000-step run
take milliseconds. Events — the
speed reaching zero (stop or reversal), break-away from rest, the supply crossing over between
constant voltage and constant current, the supply ceasing to source current — are detected on the
grid and then located exactly inside their step by root finding on the continuous solution; the step
is finished in the new regime. A motor held by Coulomb friction therefore stops exactly and stays
stopped, with no chatter.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import numpy as np
from scipy import linalg, optimize

from motorlab.errors import OptionError
from motorlab.gearbox import Drivetrain
from motorlab.model import HeldStep, MotorParams, phi_functions, propagate
from motorlab.model.drives import (  # noqa: F401 - the drives are part of this module's API
    MODE_CURRENT,
    MODE_OPEN,
    MODE_VOLTAGE,
    BenchSupply,
    CurrentDrive,
    Drive,
    OpenCircuit,
    Signal,
    VoltageDrive,
)
from motorlab.model.grid import OutputGrid, drive_schedule, drive_values


@dataclass(frozen=True)
class State:
    """Motor state: winding current [A], shaft speed [rad/s], shaft angle [rad]; with a thermal model,
    the winding and case temperatures [°C] (None: the ambient)."""

    current: float = 0.0
    speed: float = 0.0
    position: float = 0.0
    winding_temperature: float | None = None
    case_temperature: float | None = None


@dataclass
class Simulation:
    """A simulated run on the grid ``time = k·dt``.

    Attributes
    ----------
    time
        [s], ``n + 1`` points.
    current, speed, position, voltage
        Winding current [A], shaft speed [rad/s], shaft angle [rad], terminal voltage [V] at each
        grid point (for a held drive, the value that applies from that point on).
    mode
        Electrical regime of the step starting at each grid point: :data:`MODE_VOLTAGE`,
        :data:`MODE_CURRENT` or :data:`MODE_OPEN` (the last entry repeats the one before).
    params
        The motor simulated.
    events
        ``(time, description)`` of every located event (stops, break-aways, CV/CC crossovers).
    winding_temperature, case_temperature
        With a thermal model, the temperatures [°C] at each grid point (else None).
    """

    time: np.ndarray
    current: np.ndarray
    speed: np.ndarray
    position: np.ndarray
    voltage: np.ndarray
    mode: np.ndarray
    params: MotorParams
    events: list[tuple[float, str]] = field(default_factory=list)
    winding_temperature: np.ndarray | None = None
    case_temperature: np.ndarray | None = None

    def final_state(self) -> State:
        """The state at the last grid point (to continue a simulation)."""
        if self.winding_temperature is None or self.case_temperature is None:
            return State(float(self.current[-1]), float(self.speed[-1]), float(self.position[-1]))
        return State(float(self.current[-1]), float(self.speed[-1]), float(self.position[-1]),
                     float(self.winding_temperature[-1]), float(self.case_temperature[-1]))

    def sample(self, times: np.ndarray) -> dict[str, np.ndarray]:
        """Linear interpolation of current, speed, position and voltage at arbitrary ``times`` [s]."""
        t = np.asarray(times, dtype=float)
        return {
            name: np.interp(t, self.time, getattr(self, name))
            for name in ("current", "speed", "position", "voltage")
        }


# --------------------------------------------------------------------------------------------------
# Regimes: the electrical drive ("V", "I", "O") times the friction state s ∈ {+1, −1, 0 (stuck)}.
# Each regime is a linear system x' = A·x + B·[d, 1] in its own states (a subset of i, ω), plus θ.
# --------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Regime:
    kind: str  # "V" voltage source, "I" current source, "O" open circuit
    s: int  # friction sign while moving; 0 when stuck
    flow: int = 1  # +1 the motor drives the load through the gearbox, −1 the load drives the motor


@dataclass(frozen=True)
class _Linear:
    """Discretised regime: states are ``names`` (subset of "i", "w"); θ handled by the extra row."""

    names: tuple[str, ...]
    a: np.ndarray  # continuous (n, n)
    b: np.ndarray  # continuous (n, 2): columns for the drive value d and the constant 1
    ad: np.ndarray  # exact discrete (n, n)
    bd: np.ndarray  # exact discrete (n, 2)
    theta_x: np.ndarray  # Δθ = theta_x·x_k + theta_u·u_k
    theta_u: np.ndarray
    modal: tuple[np.ndarray, np.ndarray, np.ndarray] | None  # (eigvals of ad, W, W⁻¹)
    lam: np.ndarray | None = None  # eigenvalues of a (when diagonalisable)


def _continuous(p: MotorParams, reg: _Regime) -> tuple[tuple[str, ...], np.ndarray, np.ndarray]:
    K, R, L, J, b, Tf = p.K, p.R, p.L, p.J, p.b, p.Tf
    fr = -reg.s * Tf / J
    if reg.s == 0:  # stuck: only the winding current can move (voltage drive with L > 0)
        if reg.kind == "V" and L > 0:
            return ("i",), np.array([[-R / L]]), np.array([[1 / L, 0.0]])
        return (), np.zeros((0, 0)), np.zeros((0, 2))
    if reg.kind == "V":
        if L > 0:
            a = np.array([[-R / L, -K / L], [K / J, -b / J]])
            bm = np.array([[1 / L, 0.0], [0.0, fr]])
            return ("i", "w"), a, bm
        return ("w",), np.array([[-(K * K / R + b) / J]]), np.array([[K / (R * J), fr]])
    if reg.kind == "I":
        return ("w",), np.array([[-b / J]]), np.array([[K / J, fr]])
    return ("w",), np.array([[-b / J]]), np.array([[0.0, fr]])


def _phi(lam: np.ndarray, tau: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """e^(λτ), ∫₀^τ e^(λs) ds = τ·φ₁(λτ) and ∫₀^τ of that = τ²·φ₂(λτ) (:func:`motorlab.model.phi_functions`)."""
    e, phi1, phi2 = phi_functions(np.asarray(lam) * tau)
    return e, tau * phi1, tau * tau * phi2


def _modal_maps(
    lin_a: np.ndarray, lin_b: np.ndarray, names: tuple[str, ...], lam: np.ndarray, w: np.ndarray,
    winv: np.ndarray, tau: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Exact ZOH maps over ``tau`` from the eigen-decomposition: x⁺ = Ad·x + Bd·u, Δθ = θx·x + θu·u."""
    e, phi1, phi2 = _phi(lam, tau)
    ad = np.real((w * e) @ winv)
    bd = np.real((w * phi1) @ winv @ lin_b)
    if "w" in names:
        row = w[names.index("w")]
        theta_x = np.real((row * phi1) @ winv)
        theta_u = np.real((row * phi2) @ winv @ lin_b)
    else:
        theta_x, theta_u = np.zeros(len(names)), np.zeros(2)
    return ad, bd, theta_x, theta_u


@lru_cache(maxsize=256)
def _discretise(p: MotorParams, reg: _Regime, dt: float) -> _Linear:
    names, a, bm = _continuous(p, reg)
    n = len(names)
    if n:
        lam, w = np.linalg.eig(a)
        if np.linalg.cond(w) < 1e10:
            winv = np.linalg.inv(w)
            ad, bd, theta_x, theta_u = _modal_maps(a, bm, names, lam, w, winv, dt)
            return _Linear(names, a, bm, ad, bd, theta_x, theta_u, (np.exp(lam * dt), w, winv), lam)
    # Defective or empty: augment with θ (θ' = ω) and the inputs; one matrix exponential is the exact step.
    m = np.zeros((n + 3, n + 3))
    m[:n, :n] = a
    m[:n, n + 1 : n + 3] = bm
    if "w" in names:
        m[n, names.index("w")] = 1.0
    e = linalg.expm(m * dt)
    ad, bd = e[:n, :n], e[:n, n + 1 : n + 3]
    theta_x, theta_u = e[n, :n], e[n, n + 1 : n + 3]
    return _Linear(names, a, bm, ad, bd, theta_x, theta_u, None)


def _propagate_chunk(lin: _Linear, x0: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Grid states x_1..x_m (shape (m, n)) and θ increments for inputs u = (d, 1) (shape (m, 2)), by
    :func:`motorlab.model.propagate` (the one propagator of both simulators)."""
    m, n = u.shape[0], len(lin.names)
    if n == 0:
        return np.zeros((m, 0)), np.zeros(m)
    step = HeldStep(lin.ad, lin.bd[:, 0], lin.bd[:, 1], lin.theta_x, float(lin.theta_u[0]), float(lin.theta_u[1]))
    x, dtheta = propagate(step, np.asarray(x0, dtype=float), np.ascontiguousarray(u[:, 0]))
    return x[1:], dtheta


def _flow(lin: _Linear, x0: np.ndarray, u: np.ndarray, tau: float) -> tuple[np.ndarray, float]:
    """Exact state and θ increment after a time ``tau`` (0 ≤ tau ≤ dt) from ``x0`` with input ``u``."""
    n = len(lin.names)
    if n == 0:
        return np.zeros(0), 0.0
    if lin.modal is not None and lin.lam is not None:
        _, w, winv = lin.modal
        ad, bd, theta_x, theta_u = _modal_maps(lin.a, lin.b, lin.names, lin.lam, w, winv, tau)
        return ad @ x0 + bd @ u, float(theta_x @ x0 + theta_u @ u)
    m = np.zeros((n + 2, n + 2))
    m[:n, :n] = lin.a
    m[:n, n + 1] = lin.b @ u
    if "w" in lin.names:
        m[n, lin.names.index("w")] = 1.0
    e = linalg.expm(m * tau)
    x = e[:n, :n] @ x0 + e[:n, n + 1]
    dtheta = float(e[n, :n] @ x0 + e[n, n + 1]) if n else 0.0
    return x, dtheta


class _Runner:
    """Carries the full state (i, ω, θ) and the regime through a schedule of drives."""

    def __init__(self, p: MotorParams, dt: float, drivetrain: Drivetrain | None = None):
        # ``p`` is the forward equivalent; a drivetrain whose gearbox loses power switches to its
        # back-driven equivalent while the load drives the motor (motorlab.gearbox).
        self.p = p
        self.dt = dt
        self.events: list[tuple[float, str]] = []
        self.drivetrain = drivetrain if drivetrain is not None and drivetrain.switches else None
        self.p_back = self.drivetrain.backward() if self.drivetrain is not None else p

    def params_for(self, reg: _Regime) -> MotorParams:
        """The single-K equivalent of the regime's direction of power flow."""
        return self.p_back if reg.flow < 0 else self.p

    def flow_of(self, i: Any, w: Any, s: int) -> Any:
        """Gearbox power-flow indicator D (positive: the motor drives the load)."""
        assert self.drivetrain is not None
        return self.drivetrain.flow(i, w, s)

    # ---- algebraic outputs ------------------------------------------------------------------
    def current_of(self, kind: str, lin_names: tuple[str, ...], x: np.ndarray, d: float, w: float) -> float:
        if "i" in lin_names:
            return float(x[lin_names.index("i")])
        if kind == "I":
            return d
        if kind == "O":
            return 0.0
        return (d - self.p.K * w) / self.p.R  # voltage source with L = 0

    # ---- regime decisions -------------------------------------------------------------------
    def friction_state(self, kind: str, i: float, w: float) -> int:
        """s for a state: the sign of ω if moving; at rest, break away only if |K·i| > Tf."""
        if w != 0.0:
            return 1 if w > 0 else -1
        torque = self.p.K * i if kind != "O" else 0.0
        if abs(torque) > self.p.Tf:
            return 1 if torque > 0 else -1
        return 0

    def electrical(self, drive: Drive, i: float, w: float) -> tuple[str, float]:
        """Regime kind and held drive value for a bench supply given the state (others: fixed)."""
        assert isinstance(drive, BenchSupply)
        p = self.p
        emf = p.K * w
        if p.L == 0:
            ic = (drive.voltage - emf) / p.R
            if ic > drive.current_limit:
                return "I", drive.current_limit
            if ic < 0:
                return "O", 0.0
            return "V", drive.voltage
        lim = drive.current_limit
        # At a boundary, the regime is the one the state is moving into (sign of the derivative).
        if i >= lim * (1 - 1e-9) and drive.voltage - p.R * lim - emf > 0:
            return "I", lim
        if i <= lim * 1e-9 and emf >= drive.voltage:
            return "O", 0.0
        return "V", drive.voltage

    # ---- events -----------------------------------------------------------------------------
    def event_values(
        self, reg: _Regime, drive: Drive, lin: _Linear, x: np.ndarray, d: np.ndarray
    ) -> list[tuple[np.ndarray, str]]:
        """Event functions on the grid: each array turns positive when its event has occurred."""
        p = self.p
        out: list[tuple[np.ndarray, str]] = []
        n = x.shape[0]
        w = x[:, lin.names.index("w")] if "w" in lin.names else np.zeros(n)
        if "i" in lin.names:
            i = x[:, lin.names.index("i")]
        elif reg.kind == "I":
            i = d
        elif reg.kind == "O":
            i = np.zeros(n)
        else:
            i = (d - p.K * w) / p.R
        if reg.s != 0:
            out.append((-reg.s * w, "speed reached zero"))
            if self.drivetrain is not None:
                d_flow = self.flow_of(i, w, reg.s)
                if reg.flow > 0:
                    out.append((-d_flow, "gearbox back-driven"))
                else:
                    out.append((d_flow, "gearbox drives the load"))
        elif reg.kind != "O":
            out.append((np.abs(p.K * i) - p.Tf, "break-away"))
        if isinstance(drive, BenchSupply):
            lim, vset = drive.current_limit, drive.voltage
            if reg.kind == "V":
                out.append((i - lim, "supply enters constant current"))
                out.append((-i, "supply stops sourcing current"))
            elif reg.kind == "I":
                out.append((p.R * lim + p.K * w - vset, "supply enters constant voltage"))
            else:
                out.append((vset - p.K * w, "supply starts sourcing current"))
        return out

    def regime_for(
        self, drive: Drive, d_now: float, state: tuple[float, float], *, forced: str | None = None
    ) -> tuple[_Regime, float]:
        """Regime for a state; ``forced`` is the electrical regime an event just switched to."""
        i, w = state
        if isinstance(drive, BenchSupply):
            kind, d = self.electrical(drive, i, w)
            if forced in ("V", "I", "O"):
                kind = forced
                d = {"V": drive.voltage, "I": drive.current_limit, "O": 0.0}[forced]
        elif isinstance(drive, VoltageDrive):
            kind, d = "V", d_now
        elif isinstance(drive, CurrentDrive):
            kind, d = "I", d_now
        else:
            kind, d = "O", 0.0
        i_eff = i
        if kind == "I":
            i_eff = d
        elif kind == "O":
            i_eff = 0.0
        elif self.p.L == 0:
            i_eff = (d - self.p.K * w) / self.p.R
        s = self.friction_state(kind, i_eff, w)
        if forced == "break-away":
            s = 1 if self.p.K * i_eff > 0 else -1
        flow = 1
        if self.drivetrain is not None and s != 0:
            if forced in ("forward", "backward"):
                flow = 1 if forced == "forward" else -1
            else:
                flow = 1 if float(self.flow_of(i_eff, w, s)) >= 0 else -1
        return _Regime(kind, s, flow), d

    def to_local(self, reg: _Regime, lin: _Linear, i: float, w: float) -> np.ndarray:
        vals = {"i": i, "w": w}
        return np.array([vals[nm] for nm in lin.names], dtype=float)

    def from_local(self, reg: _Regime, lin: _Linear, x: np.ndarray, d: float) -> tuple[float, float]:
        w = float(x[lin.names.index("w")]) if "w" in lin.names else 0.0
        if reg.s == 0:
            w = 0.0
        return self.current_of(reg.kind, lin.names, x, d, w), w

    def event_at(
        self, reg: _Regime, drive: Drive, lin: _Linear, x0: np.ndarray, u: np.ndarray, d: float, name: str, tau: float
    ) -> float:
        """Value of the event function ``name`` a time ``tau`` into the step."""
        xt, _ = _flow(lin, x0, u, tau)
        for gv, nm in self.event_values(reg, drive, lin, xt[None, :], np.array([d])):
            if nm == name:
                return float(gv[0])
        raise KeyError(name)  # pragma: no cover

    # ---- one step with events located exactly --------------------------------------------------
    def exact_step(
        self, drive: Drive, d_drive: float, t0: float, h: float, i: float, w: float, theta: float
    ) -> tuple[float, float, float]:
        """Advance (i, ω, θ) by ``h`` seconds under ``drive`` (held value ``d_drive``), handling events."""
        remaining = h
        forced: str | None = None
        instant = 0  # events found at the very start of what remains: a guard against ping-pong
        for _ in range(64):
            reg, d = self.regime_for(drive, d_drive, (i, w), forced=forced)
            lin = _discretise(self.params_for(reg), reg, self.dt)
            x0 = self.to_local(reg, lin, i, w)
            u = np.array([d, 1.0])
            x1, dth = _flow(lin, x0, u, remaining)
            fired = [
                name
                for g, name in self.event_values(reg, drive, lin, x1[None, :], np.array([d]))
                if g[0] > 0
            ]
            if not fired or instant > 8:
                i, w = self.from_local(reg, lin, x1, d)
                return i, w, theta + dth
            # Locate the earliest event inside what remains of the step.
            best_tau, best_name = remaining, fired[0]
            for name in fired:
                g_at = functools.partial(self.event_at, reg, drive, lin, x0, u, d, name)
                if g_at(0.0) >= 0:
                    tau = 0.0
                else:
                    tau = optimize.brentq(g_at, 0.0, remaining, xtol=1e-15, rtol=1e-12, maxiter=200)
                if tau < best_tau:
                    best_tau, best_name = tau, name
            xt, dth = _flow(lin, x0, u, best_tau)
            i, w = self.from_local(reg, lin, xt, d)
            theta += dth
            instant = instant + 1 if best_tau == 0.0 else 0
            self.events.append((t0 + h - remaining + best_tau, best_name))
            remaining -= best_tau
            forced = _EVENT_REGIME[best_name]
            if best_name == "speed reached zero":
                w = 0.0
            elif best_name == "supply enters constant current" and isinstance(drive, BenchSupply):
                i = drive.current_limit
            elif best_name == "supply stops sourcing current":
                i = 0.0
            if remaining <= 1e-15 * max(h, 1.0):
                return i, w, theta
        raise RuntimeError("too many events inside one simulation step")  # pragma: no cover


#: The electrical regime (or friction transition) each event switches to.
_EVENT_REGIME: dict[str, str | None] = {
    "speed reached zero": None,
    "break-away": "break-away",
    "supply enters constant current": "I",
    "supply enters constant voltage": "V",
    "supply stops sourcing current": "O",
    "supply starts sourcing current": "V",
    "gearbox back-driven": "backward",
    "gearbox drives the load": "forward",
}


def simulate(
    params: MotorParams | Drivetrain,
    drive: Drive | Sequence[tuple[float, Drive]],
    *,
    duration: float,
    dt: float = 1e-3,
    initial: State | None = None,
    thermal_step: float = 0.05,
) -> Simulation:
    """Simulate the motor under a drive or a schedule of drives.

    Parameters
    ----------
    params
        The motor (use :meth:`MotorParams.with_load` for a flywheel through a gear ratio), or a
        :class:`~motorlab.gearbox.Drivetrain`: a gearmotor whose gearbox loses power, with its load;
        the run then switches between the forward and back-driven equivalents as the power through
        the gearbox changes direction (event "gearbox back-driven" / "gearbox drives the load").
        Speeds and angles are at the output shaft.
    drive
        One drive for the whole run, or ``[(t_start, drive), ...]`` (e.g. relay on, then
        :class:`OpenCircuit`). Start times are rounded to the grid.
    duration
        Length of the run [s].
    dt
        Grid step [s]; the dynamics are exact for held inputs whatever the step, so ``dt`` only sets
        how often the input may change and where the output is reported.
    initial
        Initial state (default: at rest, no current, at the ambient temperature).
    thermal_step
        With a thermal model (``params.thermal``), how often R and K are updated [s]: the run advances
        in stretches of this length (whole steps) with R and K at the winding's predicted midpoint
        temperature, the stretch's I²·R heat then moves the thermal network exactly. Without a thermal
        model nothing of this happens and the run is as it always was.

    Returns
    -------
    Simulation
        Arrays on the grid ``k·dt``, k = 0 … round(duration/dt) (with the temperatures when heated).

    Raises
    ------
    OptionError
        For a non-positive ``dt`` or ``duration``, an empty or unordered schedule, or a drive giving
        non-finite values.
    """
    if not (dt > 0 and math.isfinite(dt)):
        raise OptionError(f"simulation step must be positive, got {dt}")
    if not (duration > 0 and math.isfinite(duration)):
        raise OptionError(f"simulation duration must be positive, got {duration}")
    initial = initial or State()
    drivetrain = params if isinstance(params, Drivetrain) else None
    motor: MotorParams = params.forward() if isinstance(params, Drivetrain) else params
    items = drive_schedule(drive)
    n = round(duration / dt)
    grid = OutputGrid.empty(n, dt)
    runner = _Runner(motor, dt, drivetrain)
    state = (float(initial.current), float(initial.speed), float(initial.position))
    grid.current[0], grid.speed[0], grid.position[0] = state

    starts = [min(max(round(ts / dt), 0), n) for ts, _ in items]
    starts[0] = 0
    bounds = [*starts[1:], n]
    if motor.thermal is not None:
        return _simulate_heated(motor, drivetrain, items, (starts, bounds), grid, state, initial, thermal_step)
    for (_, drv), k0, k1 in zip(items, starts, bounds, strict=True):
        if k1 > k0:
            state = _run_drive(runner, drv, grid, k0, k1, state)
    mode = grid.mode
    mode[n] = mode[n - 1] if n > 0 else MODE_VOLTAGE
    # Current and terminal voltage at the segment's grid points are those of the held regime.
    _fill_outputs(runner, items, starts, bounds, grid.time, grid.current, grid.speed, grid.voltage, mode, motor)
    return Simulation(grid.time, grid.current, grid.speed, grid.position, grid.voltage, mode, motor, runner.events)


def _run_drive(
    runner: _Runner, drv: Drive, grid: OutputGrid, k0: int, k1: int, state: tuple[float, float, float]
) -> tuple[float, float, float]:
    """Advance (i, ω, θ) from grid point ``k0`` to ``k1`` under one drive, filling ``grid``.

    Event-free stretches are propagated a chunk at a time (256 steps, doubling up to 8192 while no
    event fires); the step in which an event fires is redone by :meth:`_Runner.exact_step`, which
    locates the event inside it. Returns the state at grid point ``k1``.
    """
    motor, dt, t = runner.p, runner.dt, grid.time
    cur, spd, pos, mode = grid.current, grid.speed, grid.position, grid.mode
    i, w, theta = state
    d_all = drive_values(drv, t[k0:k1])
    k = k0
    chunk = 256
    while k < k1:
        reg, d = runner.regime_for(drv, float(d_all[k - k0]), (i, w))
        lin = _discretise(runner.params_for(reg), reg, dt)
        # How far can this regime run on the grid? Constant-valued drives (bench supply) keep d.
        m = min(chunk, k1 - k)
        dvals = d_all[k - k0 : k - k0 + m].copy()
        if isinstance(drv, BenchSupply) or reg.kind == "O":
            dvals[:] = d
        u = np.column_stack([dvals, np.ones(m)])
        x0 = runner.to_local(reg, lin, i, w)
        x, dtheta = _propagate_chunk(lin, x0, u)
        # Event on the grid?  The value at grid k+j+1 belongs to the step from k+j; the drive for
        # the check at the end of step j is the one held during step j.
        first = m
        for g, _ in runner.event_values(reg, drv, lin, x, dvals):
            hits = np.flatnonzero(g > 0)
            if hits.size:
                first = min(first, int(hits[0]))
        good = first  # steps fully accepted
        if good:
            ws = x[:good, lin.names.index("w")] if "w" in lin.names else np.zeros(good)
            if reg.s == 0:
                ws = np.zeros(good)
            if "i" in lin.names:
                is_ = x[:good, lin.names.index("i")]
            elif reg.kind == "O":
                is_ = np.zeros(good)
            elif reg.kind == "I":
                is_ = dvals[:good]  # the held current of the step just finished
            else:
                is_ = (dvals[:good] - motor.K * ws) / motor.R
            sl = slice(k + 1, k + good + 1)
            spd[sl] = ws
            cur[sl] = is_
            pos[sl] = theta + np.cumsum(dtheta[:good])
            mode[k : k + good] = _MODE[reg.kind]
            i, w, theta = float(cur[k + good]), float(spd[k + good]), float(pos[k + good])
            k += good
            chunk = min(chunk * 2, 8192)
        if first < m and k < k1:
            # The event step: from grid k to k+1, located exactly.
            d_step = float(d_all[k - k0])
            mode[k] = _MODE[runner.regime_for(drv, d_step, (i, w))[0].kind]
            i, w, theta = runner.exact_step(drv, d_step, t[k], dt, i, w, theta)
            k += 1
            cur[k], spd[k], pos[k] = i, w, theta
            chunk = 256
    return i, w, theta


_MODE = {"V": MODE_VOLTAGE, "I": MODE_CURRENT, "O": MODE_OPEN}


def _fill_outputs(
    runner: _Runner,
    items: list[tuple[float, Drive]],
    starts: list[int],
    bounds: list[int],
    t: np.ndarray,
    cur: np.ndarray,
    spd: np.ndarray,
    volt: np.ndarray,
    mode: np.ndarray,
    p: MotorParams,
) -> None:
    """Terminal voltage (and the held current of current-driven steps) at every grid point."""
    n = t.size - 1
    for (_, drv), k0, k1 in zip(items, starts, bounds, strict=True):
        hi = k1 + 1 if k1 == n else k1
        if hi <= k0:
            continue
        sl = slice(k0, hi)
        d = drive_values(drv, t[sl])
        md = mode[sl]
        emf = p.K * spd[sl]
        if isinstance(drv, VoltageDrive):
            volt[sl] = d
            if p.L == 0:
                cur[sl] = (d - emf) / p.R
        elif isinstance(drv, CurrentDrive):
            cur[sl] = d
            volt[sl] = p.R * d + emf
        elif isinstance(drv, OpenCircuit):
            cur[sl] = 0.0
            volt[sl] = emf
        else:
            lim = drv.current_limit
            is_cc = md == MODE_CURRENT
            is_oc = md == MODE_OPEN
            if p.L == 0:
                cur[sl] = np.where(is_cc, lim, np.where(is_oc, 0.0, (drv.voltage - emf) / p.R))
            else:
                cur[sl] = np.where(is_cc, lim, np.where(is_oc, 0.0, cur[sl]))
            volt[sl] = np.where(is_cc, p.R * lim + emf, np.where(is_oc, emf, drv.voltage))


def _simulate_heated(
    motor: MotorParams, drivetrain: Drivetrain | None, items: list[tuple[float, Drive]],
    segments: tuple[list[int], list[int]], grid: OutputGrid, state: tuple[float, float, float], initial: State,
    thermal_step: float,
) -> Simulation:
    """:func:`simulate` with a thermal model: stretches of ``thermal_step`` at their midpoint R(T), K(T).

    The electrical and mechanical states are carried exactly across stretches; each stretch's Joule heat
    R(T)·∫i²dt advances the two-node network exactly (:meth:`ThermalModel.step`); the temperatures on the
    grid are interpolated linearly within a stretch.
    """
    from dataclasses import replace as _replace

    thermal = motor.thermal
    assert thermal is not None
    if not (thermal_step > 0 and math.isfinite(thermal_step)):
        raise OptionError(f"thermal step must be positive, got {thermal_step}")
    dt, n = float(grid.time[1] - grid.time[0]) if grid.time.size > 1 else 1.0, grid.time.size - 1
    tw = thermal.ambient_temperature if initial.winding_temperature is None else float(initial.winding_temperature)
    tc = tw if initial.case_temperature is None else float(initial.case_temperature)
    if initial.winding_temperature is None and initial.case_temperature is not None:
        tw = tc
    tw_grid, tc_grid = np.empty(n + 1), np.empty(n + 1)
    tw_grid[0], tc_grid[0] = tw, tc
    chunk = max(1, round(thermal_step / dt))
    events: list[tuple[float, str]] = []
    slope = 0.0
    for (_, drv), k0, k1 in zip(items, *segments, strict=True):
        k = k0
        while k < k1:
            kb = min(k + chunk, k1)
            h = (kb - k) * dt
            hot = motor.at_temperature(tw + 0.5 * h * slope, tc)
            train = None if drivetrain is None else _replace(
                drivetrain, motor=drivetrain.motor.at_temperature(tw + 0.5 * h * slope, tc))
            runner = _Runner(train.forward() if train is not None else hot, dt, train)
            state = _run_drive(runner, drv, grid, k, kb, state)
            if kb == n:
                grid.mode[n] = grid.mode[n - 1]
            _fill_outputs(runner, [(0.0, drv)], [k], [kb], grid.time, grid.current, grid.speed, grid.voltage,
                          grid.mode, runner.p)
            i2 = grid.current[k : kb + 1] ** 2
            power = runner.p.R * float(np.sum(0.5 * (i2[1:] + i2[:-1]))) * dt / h
            tw_new, tc_new = thermal.step(tw, tc, power, h)
            frac = np.arange(1, kb - k + 1) / (kb - k)
            tw_grid[k + 1 : kb + 1] = tw + frac * (tw_new - tw)
            tc_grid[k + 1 : kb + 1] = tc + frac * (tc_new - tc)
            slope = (tw_new - tw) / h
            tw, tc = tw_new, tc_new
            events.extend(runner.events)
            k = kb
    if n == 0:
        grid.mode[0] = MODE_VOLTAGE
    return Simulation(grid.time, grid.current, grid.speed, grid.position, grid.voltage, grid.mode, motor, events,
                      tw_grid, tc_grid)
