"""Least-squares machinery shared by every analysis: estimates, standard errors, identifiability.

Standard errors come from the Jacobian at the optimum, scaled by the residual variance
(cov = s²·(JᵀJ)⁻¹, s² = SSR/(n − p)), as lmfit and scipy's ``curve_fit`` do. Before inverting,
the information matrix is examined through the singular values of the column-scaled Jacobian: a
direction with (almost) no information makes the parameters involved "not determined", reported
as such rather than as noise dressed up as numbers.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from scipy import optimize

from motorlab.errors import FitError
from motorlab.results import Estimate

#: A parameter whose relative standard error exceeds this is reported as not determined.
MAX_RELATIVE_STDERR = 1.0
#: Singular values of the scaled Jacobian below this fraction of the largest mark no information.
SINGULAR_TOLERANCE = 1e-9


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


def covariance_from_jacobian(
    jac: np.ndarray, residuals: np.ndarray, values: np.ndarray, *, sigma_known: bool = False
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Covariance, standard errors, correlation and a determined-mask from a Jacobian.

    Parameters
    ----------
    jac
        d(residual)/d(parameter), shape (n, p).
    residuals
        Residuals at the optimum, shape (n,).
    values
        Parameter values (used to scale columns for the identifiability test).
    sigma_known
        If True the residuals are already divided by their known standard deviations and the
        covariance is (JᵀJ)⁻¹ unscaled; otherwise it is scaled by s² = SSR/(n − p).
    """
    n, p = jac.shape
    dof = max(n - p, 1)
    scale = np.where(np.abs(values) > 0, np.abs(values), 1.0)
    col_norm = np.linalg.norm(jac, axis=0)
    col_norm = np.where(col_norm > 0, col_norm, 1.0)
    js = jac / col_norm
    _, s, vt = np.linalg.svd(js, full_matrices=False)
    tol = SINGULAR_TOLERANCE * (s[0] if s.size and s[0] > 0 else 1.0)
    keep = s > tol
    inv_s2 = np.where(keep, 1.0 / np.where(keep, s, 1.0) ** 2, 0.0)
    cov_scaled = (vt.T * inv_s2) @ vt
    cov = cov_scaled / np.outer(col_norm, col_norm)
    s2 = 1.0 if sigma_known else float(residuals @ residuals) / dof
    cov = cov * s2
    # Parameters that load on a null direction are not determined.
    null_dirs = vt[~keep]
    in_null = (np.abs(null_dirs) > 1e-3).any(axis=0) if null_dirs.size else np.zeros(p, dtype=bool)
    stderr = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    stderr = np.where(in_null, np.inf, stderr)
    with np.errstate(invalid="ignore", divide="ignore"):
        d = np.sqrt(np.diag(cov))
        corr = cov / np.outer(d, d)
    corr[in_null, :] = np.nan
    corr[:, in_null] = np.nan
    np.fill_diagonal(corr, 1.0)
    determined = ~in_null & (stderr <= MAX_RELATIVE_STDERR * scale)
    return cov, stderr, corr, determined


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
) -> LeastSquares:
    """Minimise ``sum(residual(x)**2)`` with scipy's trust-region least squares.

    Raises
    ------
    FitError
        If the residual function returns non-finite values at the start point.
    """
    x0 = np.asarray(x0, dtype=float)
    r0 = residual(x0)
    if not np.all(np.isfinite(r0)):
        raise FitError("the model gives non-finite residuals at the starting guess")
    if r0.size < x0.size:
        raise FitError(f"{r0.size} data points cannot determine {x0.size} parameters")
    lo, hi = bounds if bounds is not None else (-np.inf, np.inf)
    sol = optimize.least_squares(
        residual, x0, bounds=(lo, hi), x_scale=x_scale, max_nfev=max_nfev, method="trf", loss=loss
    )
    cov, stderr, corr, determined = covariance_from_jacobian(sol.jac, sol.fun, sol.x, sigma_known=sigma_known)
    return LeastSquares(
        names=list(names),
        values=sol.x,
        stderr=stderr,
        covariance=cov,
        correlation=corr,
        determined=determined,
        residuals=sol.fun,
        jacobian=sol.jac,
        dof=max(sol.fun.size - x0.size, 1),
        success=bool(sol.success),
        message=str(sol.message),
    )


def fit_linear(
    design: np.ndarray, y: np.ndarray, names: Sequence[str], *, weights: np.ndarray | None = None
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
    """
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
    cov, stderr, corr, determined = covariance_from_jacobian(a, res, beta)
    if n == p:  # exact fit: no residual degrees of freedom, uncertainty unknown
        stderr = np.full(p, np.nan)
    return LeastSquares(
        names=list(names),
        values=beta,
        stderr=stderr,
        covariance=cov,
        correlation=corr,
        determined=determined | (n == p),
        residuals=res / w,
        jacobian=a,
        dof=max(n - p, 1),
        success=True,
        message="linear least squares",
    )


def r_squared(y: np.ndarray, model: np.ndarray) -> float:
    """Coefficient of determination 1 − SSR/SST (NaN when y is constant)."""
    y = np.asarray(y, dtype=float)
    sst = float(np.sum((y - y.mean()) ** 2))
    if sst == 0:
        return math.nan
    return 1.0 - float(np.sum((y - model) ** 2)) / sst
