"""Least-squares machinery shared by every analysis: estimates, standard errors, identifiability.

Standard errors come from the Jacobian at the optimum, scaled by the residual variance
(cov = s²·(JᵀJ)⁻¹, s² = SSR/(n − p)), as lmfit and scipy's ``curve_fit`` do. Before inverting,
the information matrix is examined through the singular values of the column-scaled Jacobian: a
direction with (almost) no information makes the parameters involved "not determined", reported
as such rather than as noise dressed up as numbers.

Those standard errors assume independent residuals. When the residuals are serially correlated
(a tachometer's commutator ripple, a slowly wandering offset), ``covariance="hac"`` replaces
s²·(JᵀJ)⁻¹ by the heteroskedasticity-and-autocorrelation-consistent sandwich of Newey and West
(1987) with Bartlett weights and the data-driven bandwidth of Andrews (1991); see
:func:`hac_covariance`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from scipy import fft as scipy_fft
from scipy import optimize

from motorlab.errors import FitError
from motorlab.results import Estimate

#: A parameter whose relative standard error exceeds this is reported as not determined.
MAX_RELATIVE_STDERR = 1.0
#: The one "not determined" rule of every fit: a singular value of the column-scaled Jacobian below
#: this fraction of the largest marks a direction without information (eigenvalues of the scaled
#: Gram matrix JᵀJ: the square, 1e-10). A Jacobian by forward differences of a step 1e-6 (scipy's
#: and the output-error engine's) is not more accurate than that, and a parameter on such a direction
#: has a standard error 1e5 times that of the best-determined combination (see :func:`scaled_gram_inverse`).
NULL_TOLERANCE = 1e-5
#: A parameter whose weight in a direction without information exceeds this is not determined.
NULL_LOADING = 1e-3


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


#: Covariance estimators offered by :func:`fit_least_squares` and :func:`fit_linear`.
COVARIANCES = ("standard", "hac")
#: Largest AR(1) coefficient used in the bandwidth rule (Andrews 1991 truncates near-unit roots).
_MAX_AR1 = 0.99


def _segments(n: int, groups: np.ndarray | None) -> list[np.ndarray]:
    """Index arrays of the contiguous runs of equal ``groups`` labels (one run without groups)."""
    if groups is None:
        return [np.arange(n)]
    labels = np.asarray(groups)
    if labels.shape != (n,):
        raise FitError(f"groups must label each of the {n} residuals, got shape {labels.shape}")
    cuts = np.flatnonzero(labels[1:] != labels[:-1]) + 1
    return [seg for seg in np.split(np.arange(n), cuts) if seg.size]


def _andrews_bandwidth(scores: np.ndarray, segments: list[np.ndarray]) -> float:
    """Andrews' (1991) AR(1) plug-in bandwidth for the Bartlett kernel, 1.1447·(α(1)·n)^(1/3).

    Each column of ``scores`` is approximated by an AR(1) process with coefficient ρ_a (fitted
    within segments) and, so that the rule does not depend on the units of the parameters, every
    column is given the same long-run variance: α(1) = mean over columns of 4ρ²/((1 − ρ)²(1 + ρ)²).
    """
    alphas = []
    for a in range(scores.shape[1]):
        pairs = [(scores[seg[1:], a], scores[seg[:-1], a]) for seg in segments if seg.size > 1]
        if not pairs:
            continue
        lag0 = np.concatenate([x for x, _ in pairs])
        lag1 = np.concatenate([y for _, y in pairs])
        ss = float(lag1 @ lag1)
        if lag0.size < 3 or ss <= 0:
            continue
        rho = float(np.clip((lag0 @ lag1) / ss, -_MAX_AR1, _MAX_AR1))
        alphas.append(4 * rho**2 / ((1 - rho) ** 2 * (1 + rho) ** 2))
    if not alphas:
        return 0.0
    return 1.1447 * (float(np.mean(alphas)) * scores.shape[0]) ** (1.0 / 3.0)


def hac_covariance(
    jac: np.ndarray,
    residuals: np.ndarray,
    bread: np.ndarray,
    *,
    groups: np.ndarray | None = None,
    bandwidth: float | None = None,
) -> tuple[np.ndarray, float]:
    """Newey–West covariance of least-squares estimates with serially correlated residuals.

    Parameters
    ----------
    jac
        d(residual)/d(parameter) at the optimum, shape (n, p).
    residuals
        Residuals at the optimum, shape (n,), in sample order.
    bread
        (JᵀJ)⁻¹ (a pseudo-inverse where J is rank deficient), shape (p, p).
    groups
        Optional label per residual: residuals of different contiguous runs (separate traces,
        separate regions of one trace, position and voltage blocks of a joint fit) are taken as
        uncorrelated, so no lag crosses a run boundary.
    bandwidth
        Bartlett bandwidth L [samples]; default: Andrews' (1991) AR(1) plug-in rule.

    Returns
    -------
    covariance, bandwidth
        The sandwich covariance (p, p) and the bandwidth used.

    Notes
    -----
    With scores g_t = J_tᵀ·r_t, the sandwich is B·S·B, B = (JᵀJ)⁻¹, S the long-run covariance of
    the scores (:func:`hac_meat`), times n/(n − p) for the degrees of freedom. With independent
    residuals the result is close to the usual s²·(JᵀJ)⁻¹. Under AR(1) errors with φ = 0.8 and
    n = 400 the 95 % intervals cover about 93 % (the plain ones about 45 %): tests/estimation/test_least_squares.py.
    """
    jac = np.asarray(jac, dtype=float)
    r = np.asarray(residuals, dtype=float)
    n, p = jac.shape
    meat, bandwidth = hac_meat(jac * r[:, None], groups=groups, bandwidth=bandwidth)
    return bread @ meat @ bread * (n / max(n - p, 1)), bandwidth


def hac_meat(
    scores: np.ndarray, *, groups: np.ndarray | None = None, bandwidth: float | None = None
) -> tuple[np.ndarray, float]:
    """Long-run covariance S of a series of scores (Newey–West), the one rule of every fit in motorlab.

    Parameters
    ----------
    scores
        g_t, shape (n, p), in sample order (for least squares g_t = J_tᵀ·r_t; several residuals at
        one instant, angle and current of an output-error fit, summed into one score).
    groups
        A label per score; lags never cross a change of label (independent runs).
    bandwidth
        Bartlett bandwidth L [samples]; default: Andrews' (1991) AR(1) plug-in rule.

    Returns
    -------
    meat, bandwidth
        S (p, p) and the bandwidth used.

    Notes
    -----
    S = Γ₀ + Σ_{l=1}^{⌊L⌋} (1 − l/(L+1))·(Γ_l + Γ_lᵀ), Γ_l = Σ_t g_t·g_{t−l}ᵀ (sums within runs).
    Bartlett weights keep S positive semi-definite (Newey and West 1987). The scores are first
    prewhitened with a VAR(1), g_t = A·g_{t−1} + e_t, S is estimated from e_t and recoloured,
    S = (I − A)⁻¹·S_e·(I − A)⁻ᵀ (Andrews and Monahan 1992). The bandwidth is chosen on the
    prewhitened scores. (The output-error fits used a second rule until issue 33: 3× the residuals'
    integrated autocorrelation time, no prewhitening; docs/identify.md records how their standard
    errors moved.)

    References
    ----------
    W. K. Newey and K. D. West, "A simple, positive semi-definite, heteroskedasticity and
    autocorrelation consistent covariance matrix", Econometrica 55 (1987) 703–708.
    D. W. K. Andrews, "Heteroskedasticity and autocorrelation consistent covariance matrix
    estimation", Econometrica 59 (1991) 817–858, eq. (6.2) and Table I (Bartlett kernel).
    D. W. K. Andrews and J. C. Monahan, "An improved heteroskedasticity and autocorrelation
    consistent covariance matrix estimator", Econometrica 60 (1992) 953–966.
    """
    scores = np.asarray(scores, dtype=float)
    n, p = scores.shape
    segments = _segments(n, groups)
    # Prewhitening (Andrews and Monahan 1992): fit a VAR(1) g_t = A·g_{t−1} + e_t within runs, take
    # the kernel estimate of the (nearly white) e_t and recolour it with (I − A)⁻¹. The kernel then
    # has little left to do, which repairs most of its small-sample under-coverage.
    lead = np.concatenate([seg[1:] for seg in segments if seg.size > 1] or [np.zeros(0, dtype=int)])
    lag = np.concatenate([seg[:-1] for seg in segments if seg.size > 1] or [np.zeros(0, dtype=int)])
    a_mat = np.zeros((p, p))
    if lead.size > 2 * p:
        a_mat = np.linalg.lstsq(scores[lag], scores[lead], rcond=None)[0].T
        # Keep the VAR stable: shrink it if its largest singular value is near 1 (their rule).
        top = float(np.linalg.svd(a_mat, compute_uv=False)[0]) if p else 0.0
        if top > 0.97:
            a_mat *= 0.97 / top
    white = scores.copy()
    for seg in segments:
        white[seg[1:]] = scores[seg[1:]] - scores[seg[:-1]] @ a_mat.T
    if bandwidth is None:
        bandwidth = _andrews_bandwidth(white, segments)
    longest = max((seg.size for seg in segments), default=1)
    bandwidth = float(min(max(bandwidth, 0.0), longest - 1))
    meat = _bartlett_meat(white, segments, bandwidth)
    recolour = np.linalg.pinv(np.eye(p) - a_mat)
    return recolour @ meat @ recolour.T, bandwidth


def _bartlett_meat(white: np.ndarray, segments: list[np.ndarray], bandwidth: float) -> np.ndarray:
    """Γ₀ + Σ_{l=1}^{⌊L⌋} (1 − l/(L+1))·(Γ_l + Γ_lᵀ), Γ_l summed within segments, through the FFT.

    Summing lag by lag costs ⌊L⌋·n·p² (the bandwidth reaches hundreds of lags on a tachometer trace:
    seconds, and minutes with many regions). Every Γ_l is a cross-correlation of the scores'
    columns, so the weighted sum is one product in the frequency domain: with X the DFT of a
    segment zero-padded to N ≥ m + ⌊L⌋ (no lag wraps around), Σ_l h(l)·Γ_l = Re(Xᵀ·diag(H)·X̄),
    H = DFT(h)/N of the symmetric Bartlett kernel h. Exact up to rounding, n·p² + n·p·log n.
    """
    p = white.shape[1]
    lags = math.floor(bandwidth)
    if lags <= 0:
        return white.T @ white
    meat = np.zeros((p, p))
    for seg in segments:
        block = white[seg[0] : seg[-1] + 1]  # segments are contiguous runs
        m = block.shape[0]
        top = min(lags, m - 1)
        if top <= 0:
            meat += block.T @ block
            continue
        size = _fft_size(m + top)
        kernel = np.zeros(size)
        kernel[0] = 1.0
        weights = 1.0 - np.arange(1, top + 1) / (bandwidth + 1.0)
        kernel[1 : top + 1] = weights
        kernel[size - top :] = weights[::-1]
        gain = np.fft.rfft(kernel).real / size  # the kernel is real and even: so is its transform
        gain[1 : (size + 1) // 2] *= 2.0  # rfft keeps one of each pair of conjugate bins
        spectrum = np.fft.rfft(block, n=size, axis=0)
        re, im = spectrum.real, spectrum.imag
        meat += re.T @ (gain[:, None] * re) + im.T @ (gain[:, None] * im)
    return 0.5 * (meat + meat.T)


def _fft_size(n: int) -> int:
    """The smallest 2^a·3^b·5^c ≥ n (a fast FFT length)."""
    return int(scipy_fft.next_fast_len(n, real=True))


def covariance_from_jacobian(
    jac: np.ndarray,
    residuals: np.ndarray,
    values: np.ndarray,
    *,
    sigma_known: bool = False,
    covariance: str = "standard",
    groups: np.ndarray | None = None,
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
    covariance
        ``"standard"`` (the above) or ``"hac"``: the Newey–West sandwich of :func:`hac_covariance`
        for serially correlated residuals (``sigma_known`` does not matter then).
    groups
        Run labels for ``"hac"`` (see :func:`hac_covariance`).
    """
    cov, stderr, corr, determined, _ = _covariance(
        jac, residuals, values, sigma_known=sigma_known, covariance=covariance, groups=groups
    )
    return cov, stderr, corr, determined


def _covariance(
    jac: np.ndarray,
    residuals: np.ndarray,
    values: np.ndarray,
    *,
    sigma_known: bool,
    covariance: str,
    groups: np.ndarray | None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float | None]:
    """:func:`covariance_from_jacobian` plus the HAC bandwidth (None for the standard covariance)."""
    n, p = jac.shape
    dof = max(n - p, 1)
    scale = np.where(np.abs(values) > 0, np.abs(values), 1.0)
    cov, in_null = scaled_gram_inverse(jac)
    bandwidth = None
    if covariance == "hac":
        cov, bandwidth = hac_covariance(jac, residuals, cov, groups=groups)
    elif covariance == "standard":
        s2 = 1.0 if sigma_known else float(residuals @ residuals) / dof
        cov = cov * s2
    else:
        raise ValueError(f"unknown covariance {covariance!r}; choose one of {COVARIANCES}")
    stderr = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    stderr = np.where(in_null, np.inf, stderr)
    with np.errstate(invalid="ignore", divide="ignore"):
        d = np.sqrt(np.diag(cov))
        corr = cov / np.outer(d, d)
    corr[in_null, :] = np.nan
    corr[:, in_null] = np.nan
    np.fill_diagonal(corr, 1.0)
    determined = ~in_null & (stderr <= MAX_RELATIVE_STDERR * scale)
    return cov, stderr, corr, determined, bandwidth


def scaled_gram_inverse(jac: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(JᵀJ)⁻¹ with the directions that carry no information dropped, and which parameters are not determined.

    The one "not determined" rule of every fit (:data:`NULL_TOLERANCE`): the columns of J are
    scaled to unit norm (so the rule does not depend on the parameters' units), the singular values
    of the scaled J below NULL_TOLERANCE of the largest are dropped (a pseudo-inverse), and every
    parameter that loads on a dropped direction (by more than :data:`NULL_LOADING`) is returned
    as not determined, so no variance is silently set to zero.

    Returns
    -------
    inverse, null
        The pseudo-inverse (p, p) in the parameters' own units, and a bool per parameter.
    """
    jac = np.asarray(jac, dtype=float)
    p = jac.shape[1]
    col = np.linalg.norm(jac, axis=0)
    col = np.where(col > 0, col, 1.0)
    js = jac / col
    # The eigenvalues of the scaled Gram matrix are the squared singular values (and resolve them to
    # 1e-8 of the largest, below the rule's 1e-5); forming it costs one product, an SVD of a tall J more.
    eig, vec = np.linalg.eigh(js.T @ js)
    eig = np.clip(eig, 0.0, None)
    keep = eig > NULL_TOLERANCE**2 * float(eig.max() if eig.size and eig.max() > 0 else 1.0)
    null_dirs = vec[:, ~keep].T
    null = (np.abs(null_dirs) > NULL_LOADING).any(axis=0) if null_dirs.size else np.zeros(p, dtype=bool)
    inv_eig = np.where(keep, 1.0 / np.where(keep, eig, 1.0), 0.0)
    return ((vec * inv_eig) @ vec.T) / np.outer(col, col), null


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
        for serially correlated residuals; see :func:`hac_covariance`).
    groups
        For ``"hac"``: a label per residual; lags never cross a change of label.

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
        residual, start, bounds=(lo, hi), x_scale=x_scale, max_nfev=max_nfev, method="trf", loss=loss
    )
    cov, stderr, corr, determined, bandwidth = _covariance(
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
        ``"standard"`` or ``"hac"`` (serially correlated residuals; see :func:`hac_covariance`).
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
    cov, stderr, corr, determined, bandwidth = _covariance(
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
