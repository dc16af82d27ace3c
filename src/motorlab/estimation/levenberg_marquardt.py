"""Bounded Levenberg–Marquardt for the output-error fits (:mod:`motorlab.estimation.output_error`): few parameters,
many residuals in units of their noise, a Jacobian that costs a simulation per parameter."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from motorlab import progress

#: Levenberg–Marquardt stops where the Gauss–Newton step would lower χ² (residuals in units of their noise) by
#: less than this: the point is then within 0.1 standard errors of the minimum, jointly in all parameters (a
#: further Jacobian, a full simulation per parameter, would move the estimates by less than that).
CHI2_TOLERANCE = 1e-2


def _gauss_newton_decrease(h: np.ndarray, g: np.ndarray) -> float:
    """gᵀH⁻¹g: what the Gauss–Newton step lowers the cost ‖r‖² by (H = JᵀJ, g = Jᵀr; a pseudo-inverse on a
    null direction); infinite when it cannot be computed."""
    if g.size == 0:
        return 0.0
    with np.errstate(all="ignore"):
        try:
            step = np.linalg.lstsq(h, g, rcond=None)[0]
        except np.linalg.LinAlgError:
            return math.inf
        value = float(g @ step)
    return value if math.isfinite(value) else math.inf


@dataclass
class Solution:
    """Where the solver stopped: the point, its residuals and Jacobian, evaluations, and why it stopped."""

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
    chi2_tol: float = CHI2_TOLERANCE,
) -> Solution:
    """Bounded Levenberg–Marquardt on the normal equations (p × p), steps projected onto the bounds.

    The problems here have few parameters and many residuals: forming JᵀJ costs a matrix product,
    where a trust-region solver's SVD of the tall Jacobian (scipy's ``trf``) costs far more on a busy
    machine. Stops when an accepted step lowers the cost by less than ``ftol`` relative (with residuals
    in units of their noise that is far below one unit of χ²), or when the Gauss–Newton step from the
    point reached would lower it by less than ``chi2_tol`` (:data:`CHI2_TOLERANCE`; residuals in units of
    their noise: the point is then within √chi2_tol standard errors of the minimum, jointly), without
    taking that step.
    """
    x = np.clip(x0, lower, upper)
    r = fun(x)
    cost = float(r @ r)
    nfev = 1
    j = jac(x)
    mu = 1e-3
    message = "maximum number of iterations reached"
    success = False
    with progress.task("Fitting the model", total=max_iterations, unit="iterations") as report:
        for _ in range(max_iterations):
            report.advance(detail=f"χ² {cost:.6g}")
            g = j.T @ r
            h = j.T @ j
            diag = np.diag(h).copy()
            diag = np.where(diag > 0, diag, 1.0)
            # Parameters held at a bound by the gradient stay there (active set): a step computed for all
            # and then clipped would crawl along the bound (a switch on its sample instant, f = 1).
            free = ~(((x <= lower) & (g > 0)) | ((x >= upper) & (g < 0)))
            if _gauss_newton_decrease(h[np.ix_(free, free)], g[free]) < chi2_tol:
                message = "within the tolerance of the minimum (the next step would lower χ² by less than " \
                          f"{chi2_tol:g})"
                success = True
                break
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
    return Solution(x, r, j, nfev, success, message)
