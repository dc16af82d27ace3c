"""Least-squares fits shared by every analysis: estimates with standard errors and identifiability.

:func:`fit_least_squares` (nonlinear, scipy's trust-region reflective) and :func:`fit_linear` return a
:class:`LeastSquares` whose covariance, standard errors and "not determined" flags come from
:mod:`motorlab.estimation.covariance` (the plain s²·(JᵀJ)⁻¹, or with ``covariance="hac"`` the Newey–West
sandwich for serially correlated residuals).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from scipy import optimize

from motorlab.errors import FitError
from motorlab.estimation.covariance import COVARIANCES, covariance_and_bandwidth
from motorlab.results import Estimate


@dataclass
class LeastSquares:
    """Outcome of :func:`fit_least_squares` / :func:`fit_linear`."""

    names: list[str]
    values: np.ndarray
    stderr: np.ndarray
    covariance: np.ndarray
    correlation: np.ndarray
    determined: np.ndarray
    residuals: np.ndarray
    jacobian: np.ndarray
    dof: int
    success: bool
    message: str
    #: Bartlett bandwidth (lags) of the HAC covariance, None for the standard one.
    bandwidth: float | None = None

    @property
    def rmse(self) -> float:
        """Root-mean-square of the residuals (in the residuals' own units)."""
        return float(np.sqrt(np.mean(self.residuals**2))) if self.residuals.size else math.nan

    def estimates(self, units: dict[str, str], *, notes: dict[str, str] | None = None) -> dict[str, Estimate]:
        """Estimates for every fitted parameter, with the units given by name."""
        notes = notes or {}
        out = {}
        for k, name in enumerate(self.names):
            determined = bool(self.determined[k])
            note = notes.get(name, "")
            if not determined and not note:
                note = "the data carry (almost) no information on it"
            out[name] = Estimate(name, float(self.values[k]), float(self.stderr[k]), units[name], determined, note)
        return out


def fit_least_squares(
    residual: Callable[[np.ndarray], np.ndarray],
    x0: Sequence[float],
    names: Sequence[str],
    *,
    bounds: tuple[Sequence[float], Sequence[float]] | None = None,
    sigma_known: bool = False,
    x_scale: str | Sequence[float] = "jac",
    max_nfev: int | None = None,
    loss: str = "linear",
    covariance: str = "standard",
    groups: np.ndarray | None = None,
    tolerance: float = 1e-8,
) -> LeastSquares:
    """Minimise ``sum(residual(x)**2)`` with scipy's trust-region least squares.

    Parameters
    ----------
    residual
        ``residual(x) -> r`` (already divided by the σ's when ``sigma_known``).
    x0
        Starting values.
    names
        One name per parameter.
    bounds
        Lower and upper bounds (scipy's convention).
    sigma_known
        Residuals are normalised by known σ's: covariance (JᵀJ)⁻¹ without the s² scale.
    x_scale, max_nfev, loss
        Passed to :func:`scipy.optimize.least_squares`.
    covariance
        ``"standard"`` (independent residuals) or ``"hac"`` (Newey–West with Andrews' bandwidth,
        for serially correlated residuals; see :func:`motorlab.estimation.covariance.hac_covariance`).
    groups
        For ``"hac"``: a label per residual; lags never cross a change of label.
    tolerance
        Stop when a step changes the cost or the parameters by less than this, relative (scipy's ``ftol`` and
        ``xtol``; its default 1e-8).

    Raises
    ------
    FitError
        If the residual function returns non-finite values at the start point.
    ValueError
        For an unknown ``covariance``.
    """
    if covariance not in COVARIANCES:
        raise ValueError(f"unknown covariance {covariance!r}; choose one of {COVARIANCES}")
    start = np.asarray(x0, dtype=float)
    r0 = residual(start)
    if not np.all(np.isfinite(r0)):
        raise FitError("the model gives non-finite residuals at the starting guess")
    if r0.size < start.size:
        raise FitError(f"{r0.size} data points cannot determine {start.size} parameters")
    lo, hi = bounds if bounds is not None else (-np.inf, np.inf)
    sol = optimize.least_squares(
        residual, start, bounds=(lo, hi), x_scale=x_scale, max_nfev=max_nfev, method="trf", loss=loss,
        ftol=tolerance, xtol=tolerance,
    )
    cov, stderr, corr, determined, bandwidth = covariance_and_bandwidth(
        sol.jac, sol.fun, sol.x, sigma_known=sigma_known, covariance=covariance, groups=groups
    )
    if sol.fun.size == sol.x.size and not sigma_known:  # no residual degrees of freedom: scatter unknown
        stderr = np.full(sol.x.size, np.nan)
    return LeastSquares(
        names=list(names),
        values=sol.x,
        stderr=stderr,
        covariance=cov,
        correlation=corr,
        determined=determined,
        residuals=sol.fun,
        jacobian=sol.jac,
        dof=max(sol.fun.size - start.size, 1),
        success=bool(sol.success),
        message=str(sol.message),
        bandwidth=bandwidth,
    )


def fit_linear(
    design: np.ndarray,
    y: np.ndarray,
    names: Sequence[str],
    *,
    weights: np.ndarray | None = None,
    covariance: str = "standard",
    groups: np.ndarray | None = None,
) -> LeastSquares:
    """Ordinary (or weighted) linear least squares ``y ≈ design @ beta`` with standard errors.

    Parameters
    ----------
    design
        Regressor matrix, shape (n, p).
    y
        Observations, shape (n,).
    names
        One name per column.
    weights
        Optional 1/σ per observation; the covariance is then still scaled by the residual variance.
    covariance
        ``"standard"`` or ``"hac"`` (serially correlated residuals; see
        :func:`motorlab.estimation.covariance.hac_covariance`).
    groups
        For ``"hac"``: a label per observation; lags never cross a change of label.

    Raises
    ------
    FitError
        Fewer observations than parameters.
    ValueError
        For an unknown ``covariance``.
    """
    if covariance not in COVARIANCES:
        raise ValueError(f"unknown covariance {covariance!r}; choose one of {COVARIANCES}")
    design = np.asarray(design, dtype=float)
    y = np.asarray(y, dtype=float)
    if design.ndim == 1:
        design = design[:, None]
    n, p = design.shape
    if n < p:
        raise FitError(f"{n} data points cannot determine {p} parameters")
    w = np.ones(n) if weights is None else np.asarray(weights, dtype=float)
    a = design * w[:, None]
    beta, *_ = np.linalg.lstsq(a, y * w, rcond=None)
    res = (a @ beta) - y * w
    cov, stderr, corr, determined, bandwidth = covariance_and_bandwidth(
        a, res, beta, sigma_known=False, covariance=covariance, groups=groups
    )
    # An exact fit (no residual degrees of freedom, or residuals at rounding level) says nothing about
    # the scatter: the uncertainty is unknown, not zero.
    exact = n == p or float(np.max(np.abs(res), initial=0.0)) <= 1e-12 * max(float(np.max(np.abs(y * w))), 1e-300)
    if exact:
        stderr = np.full(p, np.nan)
    return LeastSquares(
        names=list(names),
        values=beta,
        stderr=stderr,
        covariance=cov,
        correlation=corr,
        determined=determined,
        residuals=res / w,
        jacobian=a,
        dof=max(n - p, 1),
        success=True,
        message="linear least squares",
        bandwidth=bandwidth,
    )


def r_squared(y: np.ndarray, model: np.ndarray) -> float:
    """Coefficient of determination 1 − SSR/SST (NaN when y is constant)."""
    y = np.asarray(y, dtype=float)
    sst = float(np.sum((y - y.mean()) ** 2))
    if sst == 0:
        return math.nan
    return 1.0 - float(np.sum((y - model) ** 2)) / sst
