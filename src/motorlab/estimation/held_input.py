"""What a log's samples say about the drive between them: held levels, switch instants, and the bound.

A logger sees the voltage only at its samples. A drive that holds levels (a relay, a bench supply, a
motor controller's set-points) and switches when it likes, not when the logger samples, leaves two
unknowns per level that the sample-held model of :mod:`motorlab.estimation.output_error` gets wrong:

- the switch instant s_j, somewhere in the sample interval before the first sample showing the new
  level (the sample-held model puts it at that sample: up to one period late, dt/2 on average,
  which pulls L by several percent when τe = L/R spans a few samples);
- the level u_j itself, of which each noisy sample is a measurement (errors in the input variable:
  driving the simulation by every noisy sample injects the noise into the simulated current).

:class:`HeldMotorModel` makes both parameters of the fit (nuisance parameters): the simulation holds
u_{j−1} for the fraction f_j of the switch step and u_j after it (exact zero-order-hold solution in
two parts, :func:`motorlab.estimation.output_error.simulate`), and the logged samples of segment j enter as one
residual √n_j·(u_j − V̄_j)/σ_V (their sufficient statistic under white noise). The switch instant is
then located by the current transient that follows it, and the level by its samples and the motor's
response together (maximum likelihood, Söderström 2018, ch. 7).

:func:`cramer_rao` gives the Cramér–Rao lower bound of the model parameters with the nuisance
parameters estimated too (the information matrix of the weighted outputs, inverted whole).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

from motorlab.estimation import output_error as _oe
from motorlab.estimation.covariance import scaled_gram_inverse
from motorlab.estimation.simulator import motor_plant

#: A jump between two samples larger than this many standard deviations of the sample-to-sample
#: difference starts a new held level.
JUMP_SIGMAS = 8.0
#: Correlation (in standard errors) between the voltage's scatter about its levels and the current's
#: next step above which the scatter is real input the motor saw (ripple), not measurement noise.
RIPPLE_Z = 5.0
#: A segment splits in two where the difference of the two means is this many standard errors
#: (binary segmentation, for jumps too small to stand out between two samples).
SPLIT_SIGMAS = 6.0


def _split_small_jumps(v: np.ndarray, first: np.ndarray, sigma: float) -> np.ndarray:
    """Binary segmentation: split each segment where its two halves' means differ by > SPLIT_SIGMAS σ.

    For a split after k of n samples the statistic is |c_k|·√(n/(k·(n − k)))/σ, c_k the cumulative
    sum of the segment's deviations from its mean (CUSUM); the largest is tested.
    """
    bounds = [*first.tolist(), v.size]
    stack = list(itertools.pairwise(bounds))
    found = set(first.tolist())
    while stack and len(found) <= v.size / 20:
        lo, hi = stack.pop()
        n = hi - lo
        if n < 4:
            continue
        c = np.cumsum(v[lo:hi] - np.mean(v[lo:hi]))[:-1]
        k = np.arange(1, n)
        stat = np.abs(c) * np.sqrt(n / (k * (n - k))) / sigma
        best = int(np.argmax(stat))
        if stat[best] > SPLIT_SIGMAS:
            cut = lo + best + 1
            found.add(cut)
            stack += [(lo, cut), (cut, hi)]
    return np.array(sorted(found), dtype=np.int64)


@dataclass(frozen=True)
class HeldInput:
    """The held levels of one log: segment j holds samples ``first[j]`` to ``first[j + 1] − 1``."""

    first: np.ndarray  # first sample of each segment (first[0] = 0)
    mean: np.ndarray  # sample mean of each segment [V]
    count: np.ndarray  # samples per segment
    sigma: float  # white noise of the logged voltage about its levels [V] (0: exact)

    @property
    def n_segments(self) -> int:
        return int(self.first.size)


def detect_held(voltage: np.ndarray, current: np.ndarray | None) -> tuple[HeldInput | None, str]:
    """Whether the logged voltage is held levels plus white measurement noise, and the levels.

    Returns (the levels or None, the reason). A log is held when its jumps (> :data:`JUMP_SIGMAS`
    standard deviations of the sample-to-sample difference, and a few smaller ones found by binary
    segmentation) split it into segments of 20 samples or more on average, within which the voltage
    scatters as white noise of the size its differences show, and (with current) that scatter does
    not drive the current (then it is ripple the motor saw).
    """
    v = np.asarray(voltage, dtype=float)
    d = np.diff(v)
    mad = float(1.4826 * np.median(np.abs(d - np.median(d))))
    scale = max(float(np.max(np.abs(v))), 1e-12)
    exact = mad <= 1e-12 * scale
    jumps = np.flatnonzero(np.abs(d) > (1e-9 * scale if exact else JUMP_SIGMAS * mad))
    first = np.concatenate([[0], jumps + 1]).astype(np.int64)
    if not exact and first.size <= v.size / 20:
        split = _split_small_jumps(v, first, mad / math.sqrt(2.0))
        if split.size - first.size > max(2.0, 0.25 * first.size):  # mostly gradual change: a ramp, not levels
            return None, "the voltage changes gradually (many small steps): not held levels"
        first = split
    if first.size > v.size / 20:
        return None, "the voltage is not held between switches (ramp, PWM average or fast changes)"
    seg = np.repeat(np.arange(first.size), np.diff(np.concatenate([first, [v.size]])))
    count = np.bincount(seg)
    mean = np.bincount(seg, weights=v) / count
    dev = v - mean[seg]
    dof = v.size - first.size
    sigma = 0.0 if exact else float(np.sqrt(np.sum(dev**2) / max(dof, 1)))
    if not exact and sigma > 1.5 * mad / math.sqrt(2.0):
        return None, "the voltage drifts within its levels: not held levels with white noise"
    if not exact and current is not None:
        inner = np.flatnonzero(seg[:-1] == seg[1:])  # steps inside a segment
        e = dev[inner]
        di = np.diff(np.asarray(current, dtype=float))[inner]
        di = di - np.mean(di)
        rho = float(np.sum(e * di) / math.sqrt(float(np.sum(e**2) * np.sum(di**2)) + 1e-300))
        if rho * math.sqrt(inner.size) > RIPPLE_Z:
            return None, "the voltage's scatter drives the current: it is ripple the motor saw, used as logged"
    return HeldInput(first, mean, count, sigma), "held levels"


class HeldMotorModel(_oe.OEModel):
    """The motor driven by held levels with switch instants inside sample intervals (nuisance parameters).

    Parameters after (K, R, L, J, b, Tf), log by log: the levels u_j [V] when the voltage is noisy
    (exact levels are taken as logged), then the switch fractions f_j ∈ [0, 1] of the step before
    the first sample showing level j (f = 1: on the sample instant) when ``free_switch``.
    """

    uses_current = True
    input_noise = False

    def __init__(self, logs: list[_oe.Log], held: list[HeldInput], *, free_switch: bool):
        from motorlab.model import PARAMETER_NAMES as MOTOR_NAMES  # identify's names; no import back to it

        self.held = held
        self.free_switch = free_switch
        self.index = {id(log): k for k, log in enumerate(logs)}
        names = list(MOTOR_NAMES)
        self.slices: list[tuple[slice, slice]] = []
        for k, h in enumerate(held):
            n_lev = h.n_segments if h.sigma > 0 else 0
            n_sw = h.n_segments - 1 if free_switch else 0
            lev = slice(len(names), len(names) + n_lev)
            names += [f"level[{k}][{j}]" for j in range(n_lev)]
            sw = slice(len(names), len(names) + n_sw)
            names += [f"switch[{k}][{j + 1}]" for j in range(n_sw)]
            self.slices.append((lev, sw))
        self.names = tuple(names)
        self.steps = [np.searchsorted(h.first, np.arange(1, logs[k].n_grid + 1), side="right") - 1
                      for k, h in enumerate(held)]

    def local_start(self, j: int) -> tuple[int, int] | None:
        for k, (lev, sw) in enumerate(self.slices):
            for part in (lev, sw):
                if part.start <= j < part.stop:
                    seg = j - part.start + (1 if part is sw else 0)
                    return k, max(int(self.held[k].first[seg]) - 1, 0)
        return None

    def plant(self, p: np.ndarray) -> _oe.StatePlant:
        return motor_plant(*(float(v) for v in p[:6]))

    def initial(self, p: np.ndarray, log: _oe.Log, speed: float) -> np.ndarray:
        assert log.current is not None
        return np.array([float(log.current[0]), speed])

    def levels(self, p: np.ndarray, k: int) -> np.ndarray:
        lev, _ = self.slices[k]
        return p[lev] if lev.stop > lev.start else self.held[k].mean

    def fractions(self, p: np.ndarray, k: int) -> np.ndarray:
        _, sw = self.slices[k]
        return p[sw] if sw.stop > sw.start else np.ones(self.held[k].n_segments - 1)

    def drive(self, p: np.ndarray, log: _oe.Log) -> np.ndarray:
        k = self.index[id(log)]
        return self.levels(p, k)[self.steps[k]]

    def switches(self, p: np.ndarray, log: _oe.Log) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        k = self.index[id(log)]
        lev = self.levels(p, k)
        return self.held[k].first[1:] - 1, self.fractions(p, k), lev[:-1]

    def extra_residuals(self, p: np.ndarray) -> np.ndarray:
        parts = [np.sqrt(h.count) * (self.levels(p, k) - h.mean) / h.sigma
                 for k, h in enumerate(self.held) if h.sigma > 0]
        return np.concatenate(parts) if parts else np.zeros(0)

    def start_and_bounds(self, p0: np.ndarray, lower: np.ndarray, upper: np.ndarray, scale: np.ndarray,
                         fractions: list[np.ndarray] | None = None) -> tuple[np.ndarray, ...]:
        """Start, bounds and scale of every parameter (model ones given; levels at their means, f at ½)."""
        z = [p0[:6]]
        lo = [lower[:6]]
        hi = [upper[:6]]
        sc = [scale[:6]]
        for k, h in enumerate(self.held):
            lev, sw = self.slices[k]
            n_lev, n_sw = lev.stop - lev.start, sw.stop - sw.start
            z += [h.mean[:n_lev], (fractions[k] if fractions is not None else np.full(n_sw, 0.5))[:n_sw]]
            lo += [np.full(n_lev, -np.inf), np.zeros(n_sw)]
            hi += [np.full(n_lev, np.inf), np.ones(n_sw)]
            sc += [np.full(n_lev, max(float(np.max(np.abs(h.mean))), 1.0)), np.ones(n_sw)]
        return tuple(np.concatenate(a) for a in (z, lo, hi, sc))


def switch_summary(model: HeldMotorModel, fit: _oe.Fit) -> dict[str, float]:
    """How the fitted switch instants sit in their sample intervals: counts and the median standard error."""
    frac, err = [], []
    stderr = np.sqrt(np.clip(np.diag(fit.covariance), 0.0, None))
    for _, sw in model.slices:
        frac.append(fit.values[sw])
        err.append(stderr[sw])
    f = np.concatenate(frac) if frac else np.zeros(0)
    e = np.concatenate(err) if err else np.zeros(0)
    off = (1.0 - f) > 3.0 * e + 0.02
    return {
        "switches": int(f.size),
        "between_samples": int(np.sum(off)),
        "median_stderr_fraction": float(np.median(e)) if e.size else math.nan,
    }


def on_sample_instants(summary: dict[str, float]) -> bool | None:
    """True if the switches fall on sample instants, False if between them, None if the data cannot tell.

    One switch clearly off its sample instant (beyond 3σ + 0.02 of the interval) is enough to say the
    drive is not synchronised with the logger: fixing that switch on a sample instant would bias L
    and R (their information is in the current transient right after it). Among many switches a few
    such outliers are expected by chance (about 0.1 % at 3σ), hence the allowance of 1 %.
    """
    n = summary["switches"]
    if n == 0 or not summary["median_stderr_fraction"] < 0.25:
        return None
    return bool(summary["between_samples"] <= math.floor(0.01 * n))


def cramer_rao(fit: _oe.Fit, logs: list[_oe.Log], n_model: int, *, current_factor: float = 1.0) -> np.ndarray:
    """Cramér–Rao lower bound of the first ``n_model`` parameters' standard errors, nuisance parameters included.

    Fisher information JᵀJ of this log's weighted residuals at the fitted model, inverted whole (so
    the model parameters pay for what the held levels, switch instants, angle offsets and initial
    speeds take): the current samples white with their measured noise (``current_factor`` undoes a
    weight that included more than it), the logged voltage samples of each held level white with
    their noise, and the encoder angle in the usual Gaussian approximation of its counting error,
    q²/12 per distinct reading (a run of m identical readings counted once). That approximation is
    not exact for a quantiser (its errors repeat at rest and are bounded), so a fit's standard error
    can come out slightly below this bound for the friction parameters.
    """
    jac = np.array(fit.jacobian, copy=True)
    start = 0
    for log in logs:
        m = log.time.size
        jac[start + m : start + 2 * m] *= current_factor
        start += 2 * m
    h_inv, _ = scaled_gram_inverse(jac)
    return np.sqrt(np.clip(np.diag(h_inv)[:n_model], 0.0, None))
