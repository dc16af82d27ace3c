"""How the measured noises reach the output-error estimates (:mod:`motorlab.estimation.output_error`).

The voltage noise propagated through the plant, the current noise, and the counting errors of a
quantised angle correlated as its phase makes them (:func:`noise_propagation_covariance`); the
first-order bias the logged voltage's noise puts on L and R (:func:`input_noise_bias`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol

import numpy as np
from scipy import linalg

from motorlab.estimation.covariance import scaled_gram_inverse
from motorlab.estimation.simulator import StatePlant, moving_step
from motorlab.model import HeldStep, first_order


class FittedRun(Protocol):
    """What the noise model reads of a run prepared for fitting (:class:`motorlab.estimation.output_error.Log`)."""

    time: np.ndarray
    dt: float
    grid_voltage: np.ndarray
    uniform: bool
    resolution: float
    reading: np.ndarray
    stale_variance: np.ndarray | None

    @property
    def n_grid(self) -> int: ...

    def at_samples(self, grid_values: np.ndarray) -> np.ndarray: ...

    def position_factor(self, sigma_position: float) -> np.ndarray: ...


class PlantFamily(Protocol):
    """What the noise model needs of a plant family (:class:`motorlab.estimation.output_error.OEModel`)."""

    uses_current: bool
    input_noise: bool

    def plant(self, p: np.ndarray) -> StatePlant: ...


def voltage_noise(log: FittedRun) -> float:
    """Sample-to-sample noise of the logged voltage, 1.4826·MAD(Δ²V)/√6 [V] (robust to steps and ramps)."""
    d2 = np.diff(log.grid_voltage, 2)
    if d2.size < 3:
        return 0.0
    return float(1.4826 * np.median(np.abs(d2 - np.median(d2))) / np.sqrt(6.0))


def _filters(d: HeldStep) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
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
    if den[2] == 0.0:  # one state (the feedforward model): (n0 + n1·z⁻¹ + n2·z⁻²)/(1 − a·z⁻¹)
        v = np.asarray(u, dtype=float)[::-1]
        w = num[0] * v
        w[1:] += num[1] * v[:-1]
        w[2:] += num[2] * v[:-2]
        return first_order(-float(den[1]), w)[::-1]
    from scipy import signal

    return signal.lfilter(num, den, u[::-1], axis=0)[::-1]


def _sample_to_grid(log: FittedRun, values: np.ndarray) -> np.ndarray:
    """Spread per-sample rows onto the N_grid + 1 grid points (the transpose of nearest-point sampling)."""
    if log.uniform:
        return values
    out = np.zeros((log.n_grid + 1, values.shape[1]))
    idx = np.clip(np.round(log.time / log.dt).astype(int), 0, log.n_grid)
    np.add.at(out, idx, values)
    return out


#: Terms of the Fourier series of the counting-error covariance (the rest is folded in by scaling).
COUNTING_HARMONICS = 32


def _counting_score(g: np.ndarray, log: FittedRun, angle: np.ndarray, sigma_position: float) -> np.ndarray:
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
    model: PlantFamily,
    p: np.ndarray,
    logs: Sequence[FittedRun],
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
        d = moving_step(plant, log.dt)
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
    d = moving_step(plant, dt)
    return np.asarray(linalg.solve_discrete_lyapunov(d.ad, np.outer(d.bv, d.bv)))


def input_noise_bias(
    jac: np.ndarray, model: PlantFamily, p: np.ndarray, logs: Sequence[FittedRun], sigma_current: float
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


def _grid_mask(log: FittedRun, moving_at_samples: np.ndarray) -> np.ndarray:
    """Per grid step: True where the simulated shaft moves (from the samples' flags)."""
    if log.uniform:
        return np.asarray(moving_at_samples[: log.n_grid], dtype=float)
    idx = np.clip(np.searchsorted(log.time, log.dt * np.arange(log.n_grid), side="right") - 1, 0, log.time.size - 1)
    return np.asarray(moving_at_samples[np.minimum(idx, moving_at_samples.size - 1)], dtype=float)
