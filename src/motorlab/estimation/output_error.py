"""The output-error fitting engine shared by identify and feedforward.

Logs prepared for fitting (:class:`Log`), the model interface (:class:`OEModel`), the fit
(:func:`fit_output_error`: bounded Levenberg–Marquardt, covariance with correlated residuals and the
propagation of the measured noises, the errors-in-variables bias). The simulator they run is
:mod:`motorlab.estimation.simulator`, the noise model :mod:`motorlab.estimation.noise`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from motorlab.estimation.covariance import output_error_covariance
from motorlab.estimation.levenberg_marquardt import Solution, levenberg_marquardt
from motorlab.estimation.noise import input_noise_bias, noise_propagation_covariance
from motorlab.estimation.simulator import Perturbed, StatePlant, sensitivities, simulate

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
    start: float = 0.0  # the log's own time of the first sample [s] (``time`` counts from it)

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
    return Log(t, dt, grid_v, grid_theta, pos, cur, uniform, resolution, moving, source, reading, weight,
               start=float(time[0]))


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


#: Rows per block when looking for the rows where the shaft turns fast enough to show stale frames.
STALE_BLOCK = 20


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
    # Fast rows by blocks of 20, not by a running mean: a 7-row mean centred on a repeated row of a
    # 0, 3, 0, 3 … pattern holds four 3s (fast), centred on a 3 three (slow), so only repeated rows
    # were picked, z came out 1 and P at its cap (0.2 s for a 0.02 s refresh: kV 25σ off).
    n_blocks = counts.size // STALE_BLOCK
    blocks = counts[: n_blocks * STALE_BLOCK].reshape(n_blocks, STALE_BLOCK)
    fast = blocks[blocks.mean(axis=1) >= 1.5]
    if fast.size < 20:
        return 0.0
    repeated = float(np.mean(fast < 0.5))
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
    bandwidth: float  # of the Newey–West covariance [samples]
    noise_model: str
    bias_correction: np.ndarray  # subtracted from the model parameters (errors in the input variable)
    nfev: int
    success: bool
    message: str
    jacobian: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))  # of the weighted residuals (SI)
    #: Why the cost is not smooth around the end point ("" when it is: the Jacobian, and every
    #: standard error from it, can be trusted); see :func:`smoothness`.
    not_minimum: str = ""
    cost: float = math.nan  # Σ of the squared weighted residuals at the end point (before any bias removal)


class OEModel:
    """What :func:`fit_output_error` needs from a model (subclassed by identify and feedforward)."""

    names: tuple[str, ...] = ()
    uses_current: bool = False
    #: Lag τ [s] of the logged angle behind the simulated one (stale status frames, see
    #: :func:`stale_frame_period`): the angle compared is θ(t) − τ·ω(t).
    lag: float = 0.0
    #: The simulation is driven by the logged voltage sample by sample, so it carries that voltage's
    #: noise (errors in the input variable). False for an input model with its own parameters
    #: (held levels estimated from all their samples, :mod:`motorlab.estimation.held_input`).
    input_noise: bool = True

    def switches(self, p: np.ndarray, log: Log) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """Drive switches inside grid steps (see :func:`simulate`), or None."""
        return None

    def extra_residuals(self, p: np.ndarray) -> np.ndarray:
        """Weighted residuals appended after the signals' (e.g. logged voltage samples against held levels)."""
        return np.zeros(0)

    def local_start(self, j: int) -> tuple[int, int] | None:
        """(run, first grid step) of the only stretch parameter j affects, or None (it affects everything: a global
        parameter, which :func:`smoothness` probes).

        Its Jacobian column is then simulated from that step on, restarted from the state the current simulation
        has there (full-model state (i, ω) on a uniform grid only): hundreds of held levels and switch instants cost
        their own stretches, not a pass of the whole log each.
        """
        return None

    def plant(self, p: np.ndarray) -> StatePlant:  # pragma: no cover - abstract
        raise NotImplementedError

    def drive(self, p: np.ndarray, log: Log) -> np.ndarray:
        """Effective voltage on the grid (the applied voltage less gravity terms) [V]."""
        return log.grid_voltage

    def initial(self, p: np.ndarray, log: Log, speed: float) -> np.ndarray:  # pragma: no cover
        raise NotImplementedError


@dataclass
class _Run:
    """A simulation of one log on its grid: its inputs, its states and angle, and its trace (for sensitivities)."""

    inputs: Perturbed
    states: np.ndarray
    theta: np.ndarray
    trace: list[tuple[int, int, int, int]]


def _inputs(model: OEModel, p: np.ndarray, log: Log, speed0: float) -> Perturbed:
    return Perturbed(model.plant(p), model.drive(p, log), model.initial(p, log, speed0), model.switches(p, log))


def _run_log(model: OEModel, p: np.ndarray, log: Log, speed0: float) -> _Run:
    inputs = _inputs(model, p, log, speed0)
    trace: list[tuple[int, int, int, int]] = []
    states, theta = simulate(inputs.plant, inputs.voltage, log.dt, x0=inputs.x0, theta0=0.0,
                             switches=inputs.switches, trace=trace)
    return _Run(inputs, states, theta, trace)


def _outputs(model: OEModel, log: Log, states: np.ndarray, theta: np.ndarray, offset: float,
             w: int) -> dict[str, np.ndarray]:
    """The simulated signals at the log's samples from the grid's states and angle (or their changes, offset 0;
    ``w``: the speed's index in the state)."""
    out = {
        "position": log.at_samples(theta) + offset,
        "speed": log.at_samples(states[:, w]),
    }
    if model.lag:
        out["position"] = out["position"] - model.lag * out["speed"]
    if model.uses_current:
        out["current"] = log.at_samples(states[:, 0])
    return out


def _same_inputs(a: Perturbed, b: Perturbed) -> bool:
    """Whether two simulations of a log have the same inputs (a parameter of another stretch or run moved)."""
    same_switches = (a.switches is None and b.switches is None) or (
        a.switches is not None and b.switches is not None
        and all(np.array_equal(u, v) for u, v in zip(a.switches, b.switches, strict=True)))
    return (same_switches and np.array_equal(a.x0, b.x0) and a.plant.same_as(b.plant)
            and np.array_equal(a.voltage, b.voltage))


def _simulate_log(model: OEModel, p: np.ndarray, log: Log, speed0: float, offset: float) -> dict[str, np.ndarray]:
    run = _run_log(model, p, log, speed0)
    return _outputs(model, log, run.states, run.theta, offset, run.inputs.plant.w)


#: A perturbed run has settled back onto the baseline when its current and speed differ from the
#: baseline's by less than this fraction of the largest difference seen.
SETTLED = 1e-9


def _settled_simulation(model: OEModel, p: np.ndarray, p_base: np.ndarray, log: Log, sim0: dict[str, np.ndarray],
                        k0: int, sw: tuple[np.ndarray, np.ndarray, np.ndarray] | None, x0: np.ndarray,
                        theta0: float) -> tuple[np.ndarray, np.ndarray]:
    """States and angle from grid step ``k0`` with parameters ``p`` that change the drive locally.

    A held level or a switch instant changes the drive over one segment only. Once the segment is
    over and the current and speed are back on the baseline run ``sim0`` (within :data:`SETTLED` of
    the largest difference: the electrical and mechanical transients have decayed), the rest of the
    run is the baseline's with the angle shifted by a constant: simulated in doubling chunks up to
    there, the column of a nuisance parameter costs its segment, not the rest of the log (a 50 000-sample
    log with 170 switches: minutes otherwise).
    """
    drive = model.drive(p, log)
    plant = model.plant(p)
    changed = np.flatnonzero(drive[k0:] != model.drive(p_base, log)[k0:])
    last = k0 + (int(changed[-1]) + 1 if changed.size else 0)
    base_sw = model.switches(p_base, log)
    if sw is not None and base_sw is not None:
        keep = base_sw[0] >= k0
        moved = np.flatnonzero((sw[1] != base_sw[1][keep]) | (sw[2] != base_sw[2][keep]))
        if moved.size:
            last = max(last, k0 + int(sw[0][moved[-1]]) + 1)
    n = drive.size  # steps; grid points n + 1
    out_states, out_theta = [np.asarray([x0])], [np.asarray([theta0])]
    start, chunk, peak = k0, 256, np.zeros(2)
    while start < n:
        stop = min(n, max(start + chunk, last + 1))
        part = None
        if sw is not None:
            inside = (sw[0] + k0 >= start) & (sw[0] + k0 < stop)
            part = (sw[0][inside] + k0 - start, sw[1][inside], sw[2][inside])
        states, theta = simulate(plant, drive[start:stop], log.dt, x0=out_states[-1][-1],
                                 theta0=float(out_theta[-1][-1]), switches=part)
        out_states.append(states[1:])
        out_theta.append(theta[1:])
        base = np.column_stack([sim0["current"][start:stop + 1], sim0["speed"][start:stop + 1]])
        delta = np.abs(states[:, :2] - base)
        peak = np.maximum(peak, delta.max(axis=0))
        start, chunk = stop, 2 * chunk
        if stop >= last and np.all(delta[-1] <= SETTLED * peak):
            break
    states, theta = np.concatenate(out_states), np.concatenate(out_theta)
    if start < n:  # settled: the baseline's run from here on, the angle shifted by what the change left
        shift = theta[-1] - sim0["position"][start]
        tail = np.column_stack([sim0["current"][start + 1:], sim0["speed"][start + 1:]])
        if states.shape[1] > 2:
            tail = np.column_stack([tail, np.zeros((tail.shape[0], states.shape[1] - 2))])
        states = np.concatenate([states, tail])
        theta = np.concatenate([theta, sim0["position"][start + 1:] + shift])
    return states, theta


#: Columns carried through one pass of :func:`sensitivities` (a log of 50,000 samples holds 0.8 MB of changes per
#: column, each pass a few times that: a held-level fit with hundreds of switches is done in batches).
SENSITIVITY_BATCH = 32


class _Problem:
    """The weighted residuals of :func:`fit_output_error` and their Jacobian, in scaled unknowns.

    The unknowns are z = x / x_scale with x = (model parameters, one angle offset per run, one initial
    speed per run that starts moving); ``z0``, ``lower_z``, ``upper_z`` are the start and bounds.
    """

    def __init__(self, model: OEModel, logs: list[Log], p0: np.ndarray, *, lower: np.ndarray, upper: np.ndarray,
                 scale: np.ndarray, sigma: dict[str, float]):
        self.model, self.logs, self.sigma = model, logs, sigma
        self.n_model = p0.size
        self.speed_logs = speed_logs = [k for k, log in enumerate(logs) if log.moving_at_start]
        self.names = list(model.names) + [f"theta0[{k}]" for k in range(len(logs))] + [
            f"omega0[{k}]" for k in speed_logs]
        self.signals = ["position"] + (["current"] if model.uses_current else [])
        # nuisance starting values
        offsets0 = np.array([log.position[0] for log in logs])
        speeds0 = np.array([initial_speed_guess(logs[k]) for k in speed_logs])
        speed_scale = np.maximum(np.abs(speeds0), 1.0)
        pos_scale = np.array([max(float(np.ptp(log.position)), 1.0) for log in logs])
        self.x_scale = x_scale = np.concatenate([scale, pos_scale, speed_scale])
        self.factors = [log.position_factor(sigma["position"]) for log in logs]
        self.row_starts = np.cumsum([0] + [log.time.size * len(self.signals) for log in logs])
        self._last: dict[str, Any] = {}
        z0 = np.concatenate([p0, offsets0, speeds0]) / x_scale
        self.lower_z = np.concatenate([lower / scale, np.full(len(logs) + len(speed_logs), -np.inf)])
        self.upper_z = np.concatenate([upper / scale, np.full(len(logs) + len(speed_logs), np.inf)])
        finite = np.isfinite(self.lower_z)
        z0 = np.where(finite, np.maximum(z0, np.where(finite, self.lower_z, 0.0) + 1e-6), z0)
        self.z0 = np.minimum(z0, self.upper_z)

    def unpack(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(model parameters, angle offsets, initial speeds) in SI from the scaled unknowns."""
        x = z * self.x_scale
        n_model, n_logs = self.n_model, len(self.logs)
        return x[:n_model], x[n_model : n_model + n_logs], x[n_model + n_logs :]

    def speed_of(self, k: int, speeds: np.ndarray) -> float:
        """Initial speed of run k (0 for a run that starts at rest) [rad/s]."""
        return float(speeds[self.speed_logs.index(k)]) if k in self.speed_logs else 0.0

    def residual_parts(self, p: np.ndarray, offsets: np.ndarray, speeds: np.ndarray, *,
                       runs: list[_Run] | None = None) -> tuple[np.ndarray, list]:
        """Weighted residuals (per run: angle, then current) and the simulations (their grid runs appended to
        ``runs`` when given)."""
        parts = []
        sims = []
        for k in range(len(self.logs)):
            part, sim = self.log_residuals(k, p, offsets, speeds, runs=runs)
            parts += part
            sims.append(sim)
        parts.append(self.model.extra_residuals(p))
        return np.concatenate(parts), sims

    def log_residuals(
        self, k: int, p: np.ndarray, offsets: np.ndarray, speeds: np.ndarray, *, runs: list[_Run] | None = None
    ) -> tuple[list[np.ndarray], dict[str, np.ndarray]]:
        """Weighted residuals of run k (angle, then current) and its simulation."""
        model, log = self.model, self.logs[k]
        run = _run_log(model, p, log, self.speed_of(k, speeds))
        if runs is not None:
            runs.append(run)
        sim = _outputs(model, log, run.states, run.theta, float(offsets[k]), run.inputs.plant.w)
        return self.weighted(k, sim), sim

    def weighted(self, k: int, sim: dict[str, np.ndarray], *, change: bool = False) -> list[np.ndarray]:
        """Run k's weighted residuals of a simulation, or (``change``) how they change with a change of the
        simulation."""
        log = self.logs[k]
        parts = [(sim["position"] - (0.0 if change else log.position)) * self.factors[k]]
        if self.model.uses_current:
            assert log.current is not None
            parts.append((sim["current"] - (0.0 if change else log.current)) / self.sigma["current"])
        return parts

    def last_simulations(self) -> list[dict[str, np.ndarray]]:
        """The simulations of the point :meth:`fun` evaluated last."""
        return list(self._last["sims"])

    def restore(self, kept: dict[str, Any], z: np.ndarray) -> None:
        """Make z the point :meth:`fun` evaluated last: from ``kept`` (a copy of its cache) when that was z's, else
        by simulating it."""
        if "z" in kept and np.array_equal(kept["z"], z):
            self._last.clear()
            self._last.update(kept)
        else:
            self.fun(z)

    def fun(self, z: np.ndarray) -> np.ndarray:
        """Weighted residuals at z."""
        last = self._last
        # least_squares asks for the Jacobian at the point it has just evaluated: keep that residual
        if "z" in last and np.array_equal(last["z"], z):
            return last["r"]
        p, offsets, speeds = self.unpack(z)
        runs: list[_Run] = []
        r, sims = self.residual_parts(p, offsets, speeds, runs=runs)
        last["z"] = z.copy()
        last["r"] = r
        last["sims"] = sims
        last["runs"] = runs
        return r

    def local_column(self, zj: np.ndarray, k: int, k0: int, r0: np.ndarray) -> np.ndarray:
        """Residuals with log k re-simulated from grid step k0 (the parameter changed acts from there)."""
        model, sigma, row_starts = self.model, self.sigma, self.row_starts
        p, offsets, _ = self.unpack(zj)
        log = self.logs[k]
        sim0 = self._last["sims"][k]
        sw = model.switches(p, log)
        if sw is not None:
            keep = sw[0] >= k0
            sw = (sw[0][keep] - k0, sw[1][keep], sw[2][keep])
        x0 = np.array([sim0["current"][k0], sim0["speed"][k0]])
        states, theta = _settled_simulation(model, p, self.unpack(self._last["z"])[0], log, sim0, k0, sw, x0,
                                            float(sim0["position"][k0] - offsets[k]))
        r = r0.copy()
        rs, m = int(row_starts[k]), log.time.size
        assert log.current is not None
        r[rs + k0 : rs + m] = (theta + offsets[k] - log.position[k0:]) * self.factors[k][k0:]
        r[rs + m + k0 : rs + 2 * m] = (states[:, 0] - log.current[k0:]) / sigma["current"]
        r[int(row_starts[-1]) :] = model.extra_residuals(p)
        return r

    def jac(self, z: np.ndarray) -> np.ndarray:
        """Jacobian of the weighted residuals in z: forward differences of 1e-6 in the scaled unknowns, the
        simulations' changes from their sensitivities (:meth:`sensitivity_columns`; when the columns are more than
        one pass holds, a held level or a switch instant, which acts on a stretch, re-simulates that stretch alone,
        :meth:`local_column`), the angle offsets' columns analytic."""
        logs, n_model = self.logs, self.n_model
        r0 = self.fun(z)
        cols = np.empty((r0.size, z.size))
        moved: dict[int, tuple[float, np.ndarray]] = {}
        # held levels and switch instants join the one pass while it holds every column; beyond, each costs its stretch
        stretches = z.size - len(logs) > SENSITIVITY_BATCH
        for j in range(z.size):
            if n_model <= j < n_model + len(logs):
                continue
            h = 1e-6 * max(abs(z[j]), 1.0)
            if z[j] + h > self.upper_z[j]:
                h = -h
            zj = z.copy()
            zj[j] += h
            loc = self.model.local_start(j) if j < n_model else None
            if (stretches and loc is not None and logs[loc[0]].uniform and self.model.uses_current
                    and not self.model.lag):
                cols[:, j] = (self.local_column(zj, loc[0], loc[1], r0) - r0) / h
                continue
            moved[j] = (h, zj)
        self.sensitivity_columns(moved, r0, cols)
        # angle offsets: residual of log k's angle rises 1/σ per unit offset
        start = 0
        for k, log in enumerate(logs):
            col = np.zeros(r0.size)
            m = log.time.size
            col[start : start + m] = self.x_scale[n_model + k] * self.factors[k]
            cols[:, n_model + k] = col
            start += m * len(self.signals)
        return cols

    def sensitivity_columns(self, moved: dict[int, tuple[float, np.ndarray]], r0: np.ndarray,
                            cols: np.ndarray) -> None:
        """Fill ``cols[:, j]`` = (r(z_j) − r0)/h for each ``j: (h, z_j)`` of ``moved``: per log, the changes of its
        run from :func:`motorlab.estimation.simulator.sensitivities` (all columns in one pass; a column that
        changes the run's sequence of regimes is simulated), the extra residuals computed."""
        model, n_model, n_logs = self.model, self.n_model, len(self.logs)
        runs: list[_Run] = self._last["runs"]
        extra = slice(int(self.row_starts[-1]), r0.size)
        for j, (h, zj) in moved.items():
            cols[:, j] = 0.0
            if j < n_model:
                cols[extra, j] = (model.extra_residuals(self.unpack(zj)[0]) - r0[extra]) / h
        for k, log in enumerate(self.logs):
            rows = slice(int(self.row_starts[k]), int(self.row_starts[k + 1]))
            run = runs[k]
            columns: dict[int, Perturbed] = {}
            for j, (_, zj) in moved.items():
                if j >= n_model + n_logs and self.speed_logs[j - n_model - n_logs] != k:
                    continue  # another run's initial speed
                p, _, speeds = self.unpack(zj)
                inputs = _inputs(model, p, log, self.speed_of(k, speeds))
                if not _same_inputs(inputs, run.inputs):
                    columns[j] = inputs
            names = list(columns)
            memo: dict[int, Any] = {}  # the run's switch and event steps, differentiated once for every batch
            for first in range(0, len(names), SENSITIVITY_BATCH):
                batch = names[first : first + SENSITIVITY_BATCH]
                found = sensitivities(run.inputs.plant, run.inputs.voltage, log.dt, run.states, run.theta, run.trace,
                                      run.inputs.switches, [columns[j] for j in batch], memo=memo)
                for c, j in enumerate(batch):
                    h, zj = moved[j]
                    if found is None:
                        p, offsets, speeds = self.unpack(zj)
                        change = np.concatenate(self.log_residuals(k, p, offsets, speeds)[0]) - r0[rows]
                    else:
                        sim = _outputs(model, log, found[0][:, :, c], found[1][:, c], 0.0, run.inputs.plant.w)
                        change = np.concatenate(self.weighted(k, sim, change=True))
                    cols[rows, j] = change / h

    def blocks(self) -> list[tuple[int, int]]:
        """Residual series per log, as (first row, samples) of its (time, signal) block."""
        blocks = []
        start = 0
        for log in self.logs:
            m = log.time.size
            blocks.append((start, m))
            start += m * len(self.signals)
        return blocks

    def residual_rms(self, sims: list[dict[str, np.ndarray]]) -> dict[str, float]:
        """RMS of simulated − measured per signal over all runs (unweighted)."""
        rms: dict[str, float] = {}
        for name in self.signals:
            err = np.concatenate(
                [sims[k][name] - (log.position if name == "position" else log.current)
                 for k, log in enumerate(self.logs)]
            )  # type: ignore[operator]
            rms[name] = float(np.sqrt(np.mean(err**2)))
        return rms


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
    forward differences, the simulations' changes from their sensitivities (one pass for all the parameters); the
    angle offsets enter linearly (analytic column).
    Covariance: see :func:`motorlab.estimation.covariance.output_error_covariance`.
    """
    problem = _Problem(model, logs, p0, lower=lower, upper=upper, scale=scale, sigma=sigma)
    x_scale = problem.x_scale
    sol, not_minimum = _converged(problem, max_nfev)
    p = problem.unpack(sol.x)[0]
    res, sims = problem.fun(sol.x), problem.last_simulations()  # the end point's, kept by _converged
    jx = sol.jac / x_scale  # d residual / d parameter (SI)
    # residual series per log, as (time, signal) blocks for the long-run covariance
    blocks = problem.blocks()
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
    bias = np.zeros(values.size)
    if model.uses_current and model.input_noise and 0.5 <= ratio <= 2.0:
        # The logged voltage's noise reaches the simulated current (errors in the input variable) and
        # biases L and R: remove the first-order bias (see input_noise_bias). Only when the residuals
        # look like that noise: real ripple on the voltage is input the motor saw, and biases nothing.
        bias = input_noise_bias(jx, model, p, logs, sigma["current"])
        if np.all(np.isfinite(bias)) and np.all(values - bias >= problem.lower_z * x_scale) and np.any(bias):
            values = values - bias
            res, sims = problem.residual_parts(*problem.unpack(values / x_scale))
        else:
            bias = np.zeros(values.size)
    cov_hac, cov_white, null, bandwidth = output_error_covariance(jx, res, blocks, len(problem.signals))
    if ratio <= 2.0:  # the measured noises explain the residuals
        cov_full = cov_prop * max(1.0, ratio)  # never below what the residuals themselves show
        noise_model = "measured noise propagated (voltage, counting" + (", current)" if model.uses_current else ")")
    else:
        cov_full = cov_hac
        noise_model = f"Newey–West (residuals {math.sqrt(ratio):.3g}× larger than the measured noise explains)"
    if not_minimum:  # a Jacobian taken across a cliff: no standard error, and no claim of "not determined"
        cov_full = np.full_like(cov_full, np.nan)
        null = np.zeros_like(null)
        noise_model = f"none: {not_minimum}"
    return Fit(
        values=values,
        names=problem.names,
        not_minimum=not_minimum,
        cost=float(sol.fun @ sol.fun),
        covariance=cov_full,
        covariance_white=cov_white,
        covariance_residuals=cov_hac,
        null=null,
        residual_rms=problem.residual_rms(sims),
        simulations=sims,
        bandwidth=bandwidth,
        noise_model=noise_model,
        bias_correction=bias[: problem.n_model],
        jacobian=jx,
        nfev=int(sol.nfev),
        success=bool(sol.success),
        message=str(sol.message),
    )


#: A probe's secant may differ from the Jacobian's column by this fraction of the column's norm at a
#: smooth end point (curvature over one standard error and the kinks of located stiction events
#: stay far below it; a cliff or a Jacobian taken across one is far above).
SECANT_TOLERANCE = 0.5
#: Restarts from the probe points when the end point is not a smooth minimum.
RESTARTS = 2


def smoothness(problem: _Problem, sol: Solution) -> tuple[str, np.ndarray | None]:
    """Whether the cost is smooth around the end point, and a better start when a probe found one.

    The Jacobian of a simulation with friction events is by forward differences of 1e-6: across a
    stiction decision that flips (a break-away at a ripple peak, a clipped input) it is meaningless,
    and so is every standard error computed from it. Each global model parameter (one that acts on
    the whole run, not a held level or switch instant) is probed one standard error (white, in the
    scaled unknowns; between 1e-3 and 0.1 of its scale) to either side: the change of the residuals
    there must agree with the Jacobian's prediction, ‖r(z ± δ) − r(z) ∓ J·δ‖ ≤ tol·‖J·δ‖
    (:data:`SECANT_TOLERANCE`), and neither probe may lower the cost.

    Returns
    -------
    reason, restart
        "" for a smooth minimum, else the words for why not; where to restart: the probe point with
        the lowest cost when it is below the end point's, else the first probe across a break (the
        other side of a cliff), else None.
    """
    z, r, j = sol.x, sol.fun, sol.jac
    kept = dict(problem._last)  # the end point's simulations, when the fit's last step evaluated it
    cost = float(r @ r)
    n_model = problem.n_model
    glob = [k for k in range(n_model) if problem.model.local_start(k) is None]
    if not glob:
        return "", None
    h = j.T @ j
    try:
        white = np.sqrt(np.clip(np.diag(np.linalg.pinv(h, hermitian=True)), 0.0, None))
    except np.linalg.LinAlgError:
        white = np.full(z.size, np.inf)
    problems: list[str] = []
    best, best_cost, across = None, cost, None
    for k in glob:
        step = float(np.clip(np.nan_to_num(white[k], nan=0.1, posinf=0.1), 1e-3, 0.1)) * max(abs(z[k]), 1.0)
        for sign in (1.0, -1.0):
            zk = z.copy()
            zk[k] = np.clip(z[k] + sign * step, problem.lower_z[k], problem.upper_z[k])
            delta = zk[k] - z[k]
            if delta == 0.0:
                continue
            rk = problem.fun(zk)
            ck = float(rk @ rk) if np.all(np.isfinite(rk)) else math.inf
            predicted = j[:, k] * delta
            err = float(np.linalg.norm(rk - r - predicted)) if math.isfinite(ck) else math.inf
            if err > SECANT_TOLERANCE * float(np.linalg.norm(predicted)):
                name = problem.names[k]
                problems.append(f"{name} {'+' if sign > 0 else '−'}{abs(delta * problem.x_scale[k]):.2g}: "
                                f"cost {ck:.4g} against {cost:.4g}")
                across = zk if across is None else across
            if ck < best_cost * (1.0 - 1e-9):
                best, best_cost = zk, ck
    problem.restore(kept, z)  # leave the problem's cache at the end point
    reason = ""
    if problems:
        reason = ("the cost is not smooth around the end point (a stiction decision or a clipped input flips "
                  "within one standard error: " + "; ".join(problems[:3]) + ")")
    elif best is not None:
        reason = f"a probe one standard error away lowers the cost ({best_cost:.6g} against {cost:.6g})"
    return reason, best if best is not None else across


def _converged(problem: _Problem, max_iterations: int) -> tuple[Solution, str]:
    """Levenberg–Marquardt from the problem's start, restarted where the end point is not a smooth minimum.

    After each run :func:`smoothness` probes the end point; where a probe lowers the cost, or the cost
    is not smooth there (the Jacobian taken across a stiction decision that flips), the fit restarts
    from that probe point, the other side of the break, and failing that from 5 % to either side of
    the end point in every global parameter (up to :data:`RESTARTS` rounds), and the run with the
    lowest cost is kept. Returns that run and the reason its end point is still not a smooth
    minimum ("" when it is).
    """
    sol = levenberg_marquardt(problem.fun, problem.jac, problem.z0, problem.lower_z, problem.upper_z,
                              max_iterations=max_iterations)
    if max_iterations == 0:  # the Jacobian at a given point (a Cramér–Rao bound), no fit
        return sol, ""
    reason, restart = smoothness(problem, sol)
    for _ in range(RESTARTS):
        if not reason:
            break
        better = None
        for start in ([restart] if restart is not None else []) + _both_sides(problem, sol):
            other = levenberg_marquardt(problem.fun, problem.jac, start, problem.lower_z, problem.upper_z,
                                        max_iterations=max_iterations)
            if float(other.fun @ other.fun) < float(sol.fun @ sol.fun):
                better = other
                break
        if better is None:
            break
        sol = better
        reason, restart = smoothness(problem, sol)
    problem.fun(sol.x)
    return sol, reason


def _both_sides(problem: _Problem, sol: Solution) -> list[np.ndarray]:
    """Starts 5 % to either side of the end point in every global model parameter (within the bounds)."""
    glob = np.array([k for k in range(problem.n_model) if problem.model.local_start(k) is None], dtype=int)
    starts = []
    for sign in (1.0, -1.0):
        z = sol.x.copy()
        z[glob] = np.clip(z[glob] * (1.0 + sign * 0.05), problem.lower_z[glob], problem.upper_z[glob])
        starts.append(z)
    return starts
