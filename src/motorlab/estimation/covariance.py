"""The covariance of every fit: standard errors, the one Newey–West rule and the one "not determined" rule.

Standard errors come from the Jacobian at the optimum, scaled by the residual variance
(cov = s²·(JᵀJ)⁻¹, s² = SSR/(n − p)), as lmfit and scipy's ``curve_fit`` do. Before inverting,
the information matrix is examined through the singular values of the column-scaled Jacobian
(:func:`scaled_gram_inverse`, :data:`NULL_TOLERANCE`): a direction with (almost) no information makes the
parameters involved "not determined", reported as such rather than as noise dressed up as numbers.

Those standard errors assume independent residuals. When the residuals are serially correlated
(a tachometer's commutator ripple, a slowly wandering offset, an output-error fit's model error),
the heteroskedasticity-and-autocorrelation-consistent sandwich of Newey and West (1987) replaces
s²·(JᵀJ)⁻¹: :func:`hac_meat` (VAR(1) prewhitening, Bartlett weights, the bandwidth of Andrews (1991))
is the one rule; :func:`hac_covariance` the sandwich for least squares, and the output-error engine
builds its scores and calls :func:`hac_meat` too.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import fft as scipy_fft

from motorlab.errors import FitError

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
    cov, stderr, corr, determined, _ = covariance_and_bandwidth(
        jac, residuals, values, sigma_known=sigma_known, covariance=covariance, groups=groups
    )
    return cov, stderr, corr, determined


def covariance_and_bandwidth(
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


def output_error_covariance(
    jac: np.ndarray, res: np.ndarray, blocks: list[tuple[int, int]], n_signals: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """Covariance of the parameters that allows for correlated residuals (Newey–West).

    cov = H⁻¹·S·H⁻¹·n/(n − p) with H = JᵀJ and S the long-run covariance of the score
    g_t = Σ_signals J_tᵀ·r_t of each instant t, by the one rule of every fit
    (:func:`motorlab.estimation.covariance.hac_meat`: VAR(1) prewhitening, Andrews' bandwidth, Bartlett weights),
    no lag crossing from one run to the next. Residuals after the runs' (logged voltage samples
    against held levels) are white: each is a run of its own. For white residuals it is the usual
    s²·(JᵀJ)⁻¹.

    Returns
    -------
    cov, cov_white, null, bandwidth
        Newey–West covariance, the plain one, the parameters on a null direction, the bandwidth [samples].
    """
    n, p = jac.shape
    h_inv, null = scaled_gram_inverse(jac)
    cov_white = h_inv * float(res @ res) / max(n - p, 1)
    scores, groups = [], []
    end = 0
    for k, (start, m) in enumerate(blocks):
        g = np.zeros((m, p))
        for sgl in range(n_signals):
            sl = slice(start + sgl * m, start + (sgl + 1) * m)
            g += jac[sl] * res[sl, None]
        scores.append(g)
        groups.append(np.full(m, k))
        end = start + n_signals * m
    extra = n - end
    scores.append(jac[end:] * res[end:, None])
    groups.append(len(blocks) + np.arange(extra))
    meat, bandwidth = hac_meat(np.concatenate(scores), groups=np.concatenate(groups))
    cov = h_inv @ meat @ h_inv * (n / max(n - p, 1))
    return cov, cov_white, null, bandwidth
