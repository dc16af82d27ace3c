"""The fits of the pulse analysis (:func:`motorlab.analyses.pulse.pulse`).

The accelerate and coast regions cut from a square-wave-driven speed trace, the three friction
models compared on the coast-downs, the joint fit of every region, and the propagation of the
amplifier's and motor's constants into J, b and Tf.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from motorlab.analyses.common import ramp_speed
from motorlab.estimation.least_squares import LeastSquares, fit_least_squares, fit_linear


@dataclass
class Region:
    """One accelerate or coast stretch: samples, held command and the torque it gives."""

    kind: str  # "accelerate" or "coast"
    pulse: int
    time: np.ndarray  # absolute [s]
    speed: np.ndarray  # [rad/s], mirrored so that pulses drive it positive
    command: float  # held command level [V]
    edge_time: float  # time of the edge that starts the region [s]
    source: str
    command_stderr: float = 0.0  # standard error of the held level read from the noisy trace [V]

    @property
    def s(self) -> np.ndarray:
        """Time since the first fitted sample [s]."""
        return self.time - self.time[0]


# ---- coast-down friction models ------------------------------------------------------------------


@dataclass
class CoastFit:
    """One friction model fitted to every coast-down: its rates, SSR and the counts behind AIC and BIC."""

    model: str
    fit: LeastSquares
    gamma: float  # b/J [1/s]
    decel: float  # (Tf − τ2)/J [rad/s²]
    ssr: float
    n: int
    k: int

    @property
    def aic(self) -> float:
        """Akaike information criterion n·ln(SSR/n) + 2k."""
        return self.n * math.log(self.ssr / self.n) + 2 * self.k

    @property
    def bic(self) -> float:
        """Bayesian information criterion n·ln(SSR/n) + k·ln(n)."""
        return self.n * math.log(self.ssr / self.n) + self.k * math.log(self.n)


def fit_coasts(coasts: list[Region], model: str, decel0: float, gamma0: float) -> CoastFit:
    """Fit dω/dt = −decel − γ·ω to every coast (shared γ, decel; one start speed per coast)."""
    n_c = len(coasts)
    w0 = [float(c.speed[0]) for c in coasts]
    use_gamma = model in ("viscous", "both")
    use_decel = model in ("coulomb", "both")

    def unpack(x: np.ndarray) -> tuple[float, float, np.ndarray]:
        j = 0
        gamma = decel = 0.0
        if use_gamma:
            gamma, j = x[j], j + 1
        if use_decel:
            decel, j = x[j], j + 1
        return gamma, decel, x[j:]

    def residual(x: np.ndarray) -> np.ndarray:
        gamma, decel, starts = unpack(x)
        return np.concatenate(
            [ramp_speed(c.s, starts[i], gamma, -decel) - c.speed for i, c in enumerate(coasts)]
        )

    x0: list[float] = []
    lo: list[float] = []
    names: list[str] = []
    if use_gamma:
        x0.append(gamma0 if model == "both" else max(gamma0, 0.1 * decel0 / max(float(np.mean(w0)), 1e-9) + gamma0))
        lo.append(0.0)
        names.append("gamma")
    if use_decel:
        x0.append(decel0)
        lo.append(-np.inf)
        names.append("decel")
    x0 += w0
    lo += [-np.inf] * n_c
    names += [f"w0_{i}" for i in range(n_c)]
    fit = fit_least_squares(residual, x0, names, bounds=(lo, [np.inf] * len(x0)))
    gamma, decel, _ = unpack(fit.values)
    ssr = float(fit.residuals @ fit.residuals)
    n = int(fit.residuals.size)
    return CoastFit(model, fit, float(gamma), float(decel), max(ssr, 1e-300), n, len(x0))


def model_sentence(table: dict[str, CoastFit], best: str) -> str:
    """The answer to the seed's question "Is the shaft friction viscous?", from the BIC of each model."""
    ordered = sorted(table.values(), key=lambda m: m.bic)
    runner_up = ordered[1]
    delta = runner_up.bic - table[best].bic
    strength = "decisively" if delta > 10 else "clearly" if delta > 6 else "weakly"
    names = {"viscous": "viscous only", "coulomb": "Coulomb only", "both": "viscous + Coulomb"}
    if best == "coulomb":
        answer = "No: the coast-downs are straight lines, the friction is Coulomb (constant torque)"
    elif best == "viscous":
        answer = "Yes: the coast-downs decay exponentially, the friction is viscous"
    else:
        answer = "Partly: the coast-downs need both viscous and Coulomb friction"
    return (
        f"Is the shaft friction viscous? {answer} (BIC {strength} favours {names[best]} over "
        f"{names[runner_up.model]}, ΔBIC = {delta:.1f})"
    )


def gamma_guess(coasts: list[Region]) -> float:
    """γ from a straight line through ln ω of each coast (viscous start value) [1/s]."""
    rates = []
    for c in coasts:
        keep = c.speed > 0.05 * np.max(c.speed)
        if np.count_nonzero(keep) > 3:
            design = np.column_stack([c.s[keep], np.ones(np.count_nonzero(keep))])
            rates.append(-fit_linear(design, np.log(c.speed[keep]), ["rate", "log0"]).values[0])
    return max(float(np.median(rates)), 1e-3) if rates else 1.0


def compare_friction_models(coasts: list[Region], a2: float) -> tuple[dict[str, CoastFit], str]:
    """Fit the three friction models to the coast-downs; returns them by name and the best by BIC."""
    decel0 = max(-a2, 1e-6)
    coulomb = fit_coasts(coasts, "coulomb", decel0, 0.0)
    gamma0 = gamma_guess(coasts)
    viscous = fit_coasts(coasts, "viscous", decel0, gamma0)
    both_start = min(gamma0, 0.5 * decel0 / max(float(np.mean([c.speed[0] for c in coasts])), 1e-9))
    both = fit_coasts(coasts, "both", coulomb.decel, max(both_start, 1e-3))
    both_alt = fit_coasts(coasts, "both", max(decel0 * 0.1, 1e-6), gamma0)
    if both_alt.ssr < both.ssr:
        both = both_alt
    table = {"viscous": viscous, "coulomb": coulomb, "both": both}
    best = min(table, key=lambda m: table[m].bic)
    return table, best


# ---- the fit of every region and the uncertainty of the inputs -------------------------------------


def joint_fit(
    regions: list[Region], gain: float, j0: float, tf0: float, b0: float, with_b: bool, with_tf: bool
) -> LeastSquares:
    """One fit of every region: shared J (and b, Tf), one start speed per region."""
    names = ["J"] + (["b"] if with_b else []) + (["Tf"] if with_tf else [])
    scale = np.array([j0] + ([max(b0, j0 * 0.1)] if with_b else []) + ([max(abs(tf0), gain * 0.01)] if with_tf else []))

    def unpack(x: np.ndarray) -> tuple[float, float, float, np.ndarray]:
        j = x[0] * scale[0]
        k = 1
        b = tf = 0.0
        if with_b:
            b, k = x[k] * scale[k], k + 1
        if with_tf:
            tf, k = x[k] * scale[k], k + 1
        return j, b, tf, x[k:]

    def model(x: np.ndarray) -> np.ndarray:
        j, b, tf, starts = unpack(x)
        return np.concatenate(
            [ramp_speed(r.s, starts[i], b / j, (gain * r.command - tf) / j) for i, r in enumerate(regions)]
        )

    data = np.concatenate([r.speed for r in regions])
    x0 = [1.0] + ([max(b0, 1e-6 * j0) / scale[1]] if with_b else []) + ([tf0 / scale[-1]] if with_tf else [])
    x0 += [float(r.speed[0]) for r in regions]
    lo = [1e-9] + ([0.0] if with_b else []) + ([-np.inf] if with_tf else []) + [-np.inf] * len(regions)
    hi = [np.inf] * len(x0)
    # The tachometer's commutator ripple (seed 2's trace shows it) makes neighbouring residuals
    # alike: independent-residual standard errors would be several times too small, so the
    # covariance is the Newey–West sandwich, with lags kept within each region.
    groups = np.concatenate([np.full(r.time.size, i) for i, r in enumerate(regions)])
    fit = fit_least_squares(
        lambda x: model(x) - data, x0, names + [f"w0_{i}" for i in range(len(regions))], bounds=(lo, hi),
        covariance="hac", groups=groups,
    )
    # Back to physical units: values, standard errors and covariance of the scaled parameters.
    full_scale = np.concatenate([scale, np.ones(len(regions))])
    fit.values = fit.values * full_scale
    fit.stderr = fit.stderr * full_scale
    fit.covariance = fit.covariance * np.outer(full_scale, full_scale)
    return fit


def propagate_inputs(
    cov: np.ndarray,
    names: list[str],
    values: np.ndarray,
    *,
    gain: tuple[float, float],
    offset: tuple[float, float],
    correlation: float,
    torque_constant: tuple[float, float],
    levels: tuple[float, float, float, float],
) -> np.ndarray:
    """Add the uncertainty of Ka, I0, Km and the held levels to the covariance of (J[, b][, Tf]).

    First order. The data fix the accelerations A1,2 = (u·V1,2 + c − Tf)/J and γ = b/J, with
    u = Ka·Km, c = Km·I0 and V1, V2 the held command levels. Hence J = u·(V1 − V2)/(A1 − A2) and
    b = γ·J are proportional to u and to V1 − V2, and Tf = u·V2 + c − J·A2:
    ∂J/∂Ka = J/Ka, ∂J/∂Km = J/Km, ∂J/∂V1 = −∂J/∂V2 = J/(V1 − V2) (b alike);
    ∂Tf/∂Ka = (Tf − Km·I0)/Ka, ∂Tf/∂I0 = Km, ∂Tf/∂Km = Tf/Km, ∂Tf/∂V1 = −A2·J/(V1 − V2),
    ∂Tf/∂V2 = u + A2·J/(V1 − V2).
    """
    (ka, ka_se), (i0, i0_se), (km, km_se) = gain, offset, torque_constant
    v1, v1_se, v2, v2_se = levels
    u = ka * km
    inputs = np.diag([ka_se**2, i0_se**2, km_se**2, v1_se**2, v2_se**2])
    inputs[0, 1] = inputs[1, 0] = correlation * ka_se * i0_se
    if not inputs.any():
        return cov
    j = float(values[names.index("J")])
    tf = float(values[names.index("Tf")]) if "Tf" in names else 0.0
    a2 = (u * v2 - tf) / j  # the coast's acceleration at zero speed
    dv = v1 - v2
    grad = np.zeros((len(names), 5))
    for k, name in enumerate(names):
        v = float(values[k])
        if name in ("J", "b"):
            grad[k] = [v / ka, 0.0, v / km, v / dv, -v / dv]
        elif name == "Tf":
            grad[k] = [(v - km * i0) / ka, km, v / km, -a2 * j / dv, u + a2 * j / dv]
    return cov + grad @ inputs @ grad.T
