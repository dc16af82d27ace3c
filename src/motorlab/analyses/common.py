"""Helpers shared by the analyses: option checks, position from a recording, motion closed forms.

Small on purpose; every analysis module may use it.

- :func:`check_positive`, :func:`check_stderr`, :func:`check_finite_signals`: bad options and NaN
  become one-line :class:`~motorlab.errors.OptionError` / :class:`~motorlab.errors.LogFormatError`.
- :func:`position_of`: the encoder angle [rad] of a :class:`~motorlab.recording.Recording`, from a
  ``position`` signal or from ``counts`` and ``cpr``; works for row logs and tick-timestamp logs.
- :func:`ramp_position`, :func:`ramp_speed`, :func:`stop_time`: the exact solution of
  J·dω/dt = J·(A − γ·ω) (viscous drag γ = b/J and constant torque A = (K·i − Tf)/J), safe at γ → 0.
- :func:`speed_noise_sigma`: per-sample standard deviation σ² = σ_q² + (σ_t·ω)² of an encoder
  position (quantisation plus timing jitter), estimated from fit residuals.
- :func:`read_tables`, :func:`finite_rows`, :func:`concatenate`, :func:`metadata_quantity`,
  :func:`sources_of`, :func:`fit_straight_line`: headed-CSV tables of the bench analyses (``lcr``,
  ``torque``, ``pulse``, ``gains``).
- :func:`reader_warnings` (from :mod:`motorlab.estimation.runs`): what the readers noted (e.g. a truncated last
  line dropped), for every analysis to pass on in :attr:`FitResult.warnings <motorlab.results.FitResult.warnings>`.
- :func:`check_range`, :func:`check_cpr`, :func:`check_flat`, :func:`in_file`: refuse values outside a
  physically possible range (before they overflow), responses that carry no information, and
  name the file in a :class:`~motorlab.errors.FitError`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import optimize

from motorlab.errors import FitError, LogFormatError, OptionError
from motorlab.estimation.least_squares import LeastSquares, fit_least_squares, fit_linear, r_squared
from motorlab.estimation.runs import reader_warnings
from motorlab.io import text as _io_text
from motorlab.model import phi_functions
from motorlab.model.load import MATERIALS
from motorlab.recording import Recording

#: Mass densities of flywheel materials [kg/m³] (the one table, :data:`motorlab.model.load.MATERIALS`).
MATERIAL_DENSITY = MATERIALS


# ---- option checks -------------------------------------------------------------------------------
def check_positive(value: float | None, name: str, *, allow_none: bool = True) -> None:
    """Raise :class:`OptionError` unless ``value`` is a finite number > 0 (or None when allowed)."""
    if value is None:
        if allow_none:
            return
        raise OptionError(f"{name} is required")
    if not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
        raise OptionError(f"{name} must be a finite number > 0, got {value!r}")


def check_nonnegative(value: float | None, name: str) -> None:
    """Raise :class:`OptionError` unless ``value`` is None or a finite number ≥ 0."""
    if value is None:
        return
    if not (isinstance(value, int | float) and math.isfinite(value) and value >= 0):
        raise OptionError(f"{name} must be a finite number ≥ 0, got {value!r}")


def check_stderr(value: float | None, name: str) -> float:
    """A standard error option: None → 0 (exact); otherwise it must be finite and ≥ 0."""
    check_nonnegative(value, name)
    return 0.0 if value is None else float(value)


def check_range(value: float | None, name: str, low: float, high: float, unit: str, *, why: str = "") -> None:
    """Raise :class:`OptionError` unless ``value`` is None or a finite number in [low, high].

    Used for options whose absurd values (``--cpr 1e-300``, ``--K 1e300``) would overflow the
    arithmetic of a fit long before they could give an answer: the limits are generous physical
    bounds, not tolerances, and ``why`` says where they come from.
    """
    if value is None:
        return
    if not (isinstance(value, int | float) and math.isfinite(value) and low <= value <= high):
        text = f" [{unit}]" if unit else ""
        reason = f" ({why})" if why else ""
        raise OptionError(f"{name} must lie between {low:g} and {high:g}{text}, got {value!r}{reason}")


#: Encoder counts per revolution a real encoder can have [count/rev]: the one range of the readers
#: (:data:`motorlab.io.text.CPR_RANGE`), at least one count, at most 2³⁰.
CPR_RANGE = _io_text.CPR_RANGE


#: Generous physical limits of the quantities the analyses are given, by symbol: (lowest, highest,
#: unit). They are not tolerances: a value outside is a typo or a wrong unit (``--K 1e300``), and
#: checking up front keeps it from overflowing a fit into warnings and a non-finite result. K: a
#: coreless micro-motor has ~1e-3 V·s/rad before its gearbox, a large gearmotor a few hundred after
#: it; I: any bench supply or servo amplifier; J: a micro-motor's rotor (~1e-9 kg·m²) to seed 1's
#: flywheel reflected through 25:1 (~8 kg·m²), with margins; arm: a lever from 0.1 mm to 100 m.
LIMITS: dict[str, tuple[float, float, str]] = {
    "K": (1e-6, 1e4, "V·s/rad"),
    "I": (1e-6, 1e4, "A"),
    "J": (1e-12, 1e6, "kg·m²"),
    "b": (0.0, 1e6, "N·m·s/rad"),
    "Tf": (0.0, 1e6, "N·m"),
    "Ka": (1e-6, 1e4, "A/V"),
    "arm": (1e-4, 100.0, "m"),
    "f": (0.0, 1e8, "Hz"),
}
TORQUE_CONSTANT_RANGE = LIMITS["K"][:2]
CURRENT_RANGE = LIMITS["I"][:2]


def check_limits(value: float | None, symbol: str, name: str) -> None:
    """Raise :class:`OptionError` unless ``value`` is None or within ``LIMITS[symbol]``."""
    low, high, unit = LIMITS[symbol]
    check_range(value, name, low, high, unit, why="beyond any DC gearmotor rig")


def check_stderr_limit(value: float | None, symbol: str, name: str) -> float:
    """A standard-error option of quantity ``symbol``: None → 0 (exact); finite, ≥ 0 and within its limits."""
    se = check_stderr(value, name)
    check_range(se, name, 0.0, LIMITS[symbol][1], LIMITS[symbol][2], why="beyond any DC gearmotor rig")
    return se


def check_torque_constant(value: float | None, name: str = "the torque constant K (--K)") -> None:
    """Raise :class:`OptionError` unless ``value`` is None or within ``LIMITS["K"]``."""
    check_limits(value, "K", name)


def check_current(value: float | None, name: str = "the current (--current)") -> None:
    """Raise :class:`OptionError` unless ``value`` is None or within ``LIMITS["I"]``."""
    check_limits(value, "I", name)


def check_cpr(cpr: float | None) -> None:
    """Raise :class:`OptionError` unless ``cpr`` is None or within :data:`CPR_RANGE`."""
    check_range(cpr, "the encoder counts per revolution (--cpr)", *CPR_RANGE, "count/rev",
                why="an encoder gives at least one count per turn")


def check_flat(values: np.ndarray, what: str, *, source: str) -> None:
    """Raise :class:`FitError` naming ``source`` when every value of a response is the same.

    A response column that never changes (an unplugged sensor, a column of zeros) fits any straight
    line through a constant exactly, with zero residuals: the slope would come out as 0 ± 0, a number
    the data cannot determine.
    """
    values = np.asarray(values, dtype=float)
    if values.size >= 2 and float(np.ptp(values)) == 0.0:
        where = f"{source}: " if source else ""
        raise FitError(
            f"{where}the {what} reads {values[0]:g} in every row: a response that never changes is not a "
            "measurement (sensor unplugged or not logged?)"
        )


def in_file(exc: FitError, source: str) -> FitError:
    """``exc`` with ``source`` in front of its message (unless it already names it)."""
    text = str(exc)
    if not source or text.startswith(source):
        return exc
    return FitError(f"{source}: {text}")


def check_finite_signals(recording: Recording, names: Iterable[str]) -> None:
    """Raise :class:`LogFormatError` (file and line) at the first NaN/inf of time or a named signal."""
    arrays = [("time", recording.time)] + [(n, recording.signals[n]) for n in names if n in recording.signals]
    for name, values in arrays:
        bad = np.flatnonzero(~np.isfinite(values))
        if bad.size:
            k = int(bad[0])
            raise LogFormatError(
                f"{name} is not a finite number in sample {k + 1}",
                path=recording.source or None,
                line=recording.line_of(k),
            )


# ---- position -----------------------------------------------------------------------------------
def position_of(recording: Recording, *, cpr: float | None = None) -> tuple[np.ndarray, float]:
    """Encoder angle [rad] of every sample and the quantum (one count) [rad].

    Parameters
    ----------
    recording
        A row log (``time_ms counts voltage current``) or a tick-timestamp log (one row per count):
        both are a time and an encoder signal; what differs is only which of them is quantised.
    cpr
        Encoder counts per revolution of the shaft whose quantities are reported [count/rev]. Needed
        when the recording holds ``counts``; a ``position`` signal [rad] is used as it is.

    Returns
    -------
    position, quantum
        Angle [rad] per sample and 2π/cpr [rad] (NaN when unknown).

    Raises
    ------
    OptionError
        ``cpr`` missing (for counts) or not a positive finite number.
    LogFormatError
        The recording has neither position nor counts, or a NaN in them.
    """
    if cpr is not None:
        check_positive(cpr, "cpr (encoder counts per revolution)")
        check_cpr(cpr)
    cpr = cpr if cpr is not None else recording.metadata.get("cpr")
    if "counts" in recording.signals and cpr is not None:
        check_positive(float(cpr), "cpr (encoder counts per revolution)")
        try:
            check_cpr(float(cpr))
        except OptionError as exc:  # the file's own "# cpr:" line
            raise LogFormatError(exc.message, path=recording.source or None) from None
        check_finite_signals(recording, ["counts"])
        quantum = 2.0 * math.pi / float(cpr)
        return recording.signals["counts"] * quantum, quantum
    if "position" in recording.signals:
        check_finite_signals(recording, ["position"])
        quantum = 2.0 * math.pi / float(cpr) if cpr is not None else math.nan
        return recording.signals["position"], quantum
    if "counts" in recording.signals:
        raise OptionError("this log holds encoder counts: give the encoder's counts per revolution (--cpr)",
                          path=recording.source or None)
    recording.require("position")  # raises LogFormatError naming the file
    raise AssertionError("unreachable")  # pragma: no cover


def is_tick_log(recording: Recording) -> bool:
    """True for a tick-timestamp log (seed 1, "First Motor Test"): one row per encoder count.

    Such a log has exact positions and quantised times (the error is in time, not in angle).
    """
    if recording.metadata.get("variant") == "ticks":  # motorlab.io.read_ftc_log's two-column layout
        return True
    if recording.has("voltage") or recording.has("current") or "counts" not in recording.signals:
        return False
    steps = np.abs(np.diff(recording.signals["counts"]))
    return steps.size > 2 and bool(np.median(steps) == 1)


# ---- motion under constant torque and viscous drag ---------------------------------------------
def _phi1(x: np.ndarray) -> np.ndarray:
    """(1 − e^(−x))/x = φ₁(−x), equal to 1 at x = 0 (:func:`motorlab.model.phi_functions`)."""
    return np.real(phi_functions(-np.asarray(x, dtype=float))[1])


def _phi2(x: np.ndarray) -> np.ndarray:
    """(x − 1 + e^(−x))/x² = φ₂(−x), equal to ½ at x = 0 (:func:`motorlab.model.phi_functions`)."""
    return np.real(phi_functions(-np.asarray(x, dtype=float))[2])


def ramp_speed(tau: np.ndarray, omega0: float, gamma: float, accel: float) -> np.ndarray:
    """ω(τ) solving dω/dt = accel − γ·ω with ω(0) = ω0 [rad/s] (no clamping at zero)."""
    tau = np.asarray(tau, dtype=float)
    return omega0 * np.exp(-gamma * tau) + accel * tau * _phi1(gamma * tau)


def ramp_position(tau: np.ndarray, omega0: float, gamma: float, accel: float) -> np.ndarray:
    """θ(τ) − θ(0) for dω/dt = accel − γ·ω, ω(0) = ω0 [rad] (no clamping at zero).

    Notes
    -----
    θ(τ) = ω0·τ·φ1(γτ) + accel·τ²·φ2(γτ), with φ1(x) = (1 − e^(−x))/x and
    φ2(x) = (x − 1 + e^(−x))/x²; this is ((ω0 + c)/γ)(1 − e^(−γτ)) − c·τ with c = −accel/γ, written
    so that γ → 0 (pure Coulomb friction: θ = ω0·τ + ½·accel·τ²) needs no special case.
    """
    tau = np.asarray(tau, dtype=float)
    x = gamma * tau
    return omega0 * tau * _phi1(x) + accel * tau**2 * _phi2(x)


def stop_time(omega0: float, gamma: float, decel: float) -> float:
    """Time [s] at which a coast dω/dt = −decel − γ·ω from ω0 > 0 reaches ω = 0 (inf if never).

    τ_s = ln(1 + γ·ω0/decel)/γ, written as (ω0/decel)·ln(1 + x)/x with x = γ·ω0/decel.
    """
    if decel <= 0 or omega0 <= 0:
        return math.inf
    x = gamma * omega0 / decel
    if x <= -1.0:
        return math.inf
    ratio = 1.0 - x / 2.0 + x * x / 3.0 if abs(x) < 1e-6 else math.log1p(x) / x
    return omega0 / decel * ratio


def coast_position(tau: np.ndarray, omega0: float, gamma: float, decel: float) -> np.ndarray:
    """θ(τ) − θ(0) of a coast J·dω/dt = −b·ω − Tf (γ = b/J, decel = Tf/J) that stays at rest after ω = 0."""
    t_stop = stop_time(omega0, gamma, decel)
    return ramp_position(np.minimum(tau, t_stop), omega0, gamma, -decel)


def coast_speed(tau: np.ndarray, omega0: float, gamma: float, decel: float) -> np.ndarray:
    """ω(τ) of the coast of :func:`coast_position` (zero after the stop)."""
    t_stop = stop_time(omega0, gamma, decel)
    tau = np.asarray(tau, dtype=float)
    return np.where(tau < t_stop, ramp_speed(np.minimum(tau, t_stop), omega0, gamma, -decel), 0.0)


# ---- noise model --------------------------------------------------------------------------------
def speed_noise_sigma(residuals: np.ndarray, speed: np.ndarray, *, dof: int) -> np.ndarray:
    """Per-sample σ [rad] of an encoder position, σ² = σ_q² + (σ_t·ω)², fitted to residuals².

    Quantisation of counts gives a constant σ_q ≈ quantum/√12; timing jitter (a log whose time stamp
    is not the instant the encoder was read, or a tick log whose times are rounded to 1 ms) gives an
    error σ_t·|ω| that grows with speed. Both variances are found by non-negative least squares of the
    squared residuals on [1, ω²], then scaled so that Σ(r/σ)² = dof.
    """
    r2 = np.asarray(residuals, dtype=float) ** 2
    w2 = np.asarray(speed, dtype=float) ** 2
    design = np.column_stack([np.ones_like(w2), w2])
    scale = np.array([1.0, 1.0 / max(float(np.mean(w2)), 1e-300)])
    coef, _ = optimize.nnls(design * scale, r2)
    var = design @ (coef * scale)
    floor = 1e-3 * float(np.mean(r2)) if np.mean(r2) > 0 else 1e-300
    var = np.maximum(var, floor)
    # Rescale so the weighted residuals have unit variance per degree of freedom.
    var *= float(np.sum(r2 / var)) / max(dof, 1)
    return np.sqrt(var)


# ---- reading position logs ----------------------------------------------------------------------
def read_position_log(paths: list[str], *, cpr: float | None, current_unit: str | None = None) -> Recording:
    """Read one run: FTC OpMode log(s) (possibly split over several files) or one CSV file.

    ``current_unit`` ("A" or "mA") applies to FTC logs, whose columns carry no units.
    """
    if not paths:
        raise OptionError("give the log file(s) to analyse")
    if all(str(p).lower().endswith(".csv") for p in paths):
        if len(paths) != 1:
            raise OptionError("give one CSV file per run")
        from motorlab.io.csv_table import read_csv

        return read_csv(paths[0], cpr=cpr)
    from motorlab.io.ftc import read_ftc_log

    return read_ftc_log(paths, cpr=cpr, current_unit=current_unit)


# ---- tables of the bench analyses (lcr, torque, pulse, gains) ---------------------------------------------------


def read_tables(paths: Sequence[str]) -> list[Recording]:
    """Read headed CSV files (``motorlab.io.read_csv``), one :class:`Recording` per path.

    Raises
    ------
    LogFormatError
        If no path is given or a file cannot be read (the reader names the file and line).
    """
    from motorlab.io import read_csv  # imported here: the CLI registers parsers without reading

    if not paths:
        raise OptionError("no input file given")
    return [read_csv(path) for path in paths]


def finite_rows(recording: Recording, names: Sequence[str]) -> None:
    """Raise :class:`LogFormatError` at the first row where a named signal is not finite."""
    for name in names:
        values = recording.require(name)
        bad = np.flatnonzero(~np.isfinite(values))
        if bad.size:
            raise LogFormatError(
                f"{name} is not a finite number in this row", path=recording.source or None,
                line=recording.line_of(int(bad[0])),
            )


def concatenate(recordings: Sequence[Recording], names: Sequence[str] | None = None) -> Recording:
    """Join the rows of several recordings, keeping the named signals (checked finite first).

    ``names=None`` keeps every signal, which every recording must then have (the same columns).
    Metadata come from the first recording, except the readers' ``warnings``, which are every
    file's; ``source`` lists every file.
    """
    if not recordings:
        raise OptionError("no input file given")
    if names is None:
        names = sorted(recordings[0].signals)
        for rec in recordings[1:]:
            if set(rec.signals) != set(names):
                raise OptionError(f"{rec.source}: its columns differ from those of {recordings[0].source}")
    for rec in recordings:
        finite_rows(rec, names)
    if len(recordings) == 1:
        return recordings[0]
    signals = {name: np.concatenate([rec.require(name) for rec in recordings]) for name in names}
    index = np.arange(sum(len(rec) for rec in recordings), dtype=float)
    metadata = dict(recordings[0].metadata)
    metadata["warnings"] = reader_warnings(recordings)  # every file's, not only the first's
    return Recording(
        time=index,
        signals=signals,
        metadata=metadata,
        source=" + ".join(rec.source for rec in recordings if rec.source),
    )


def metadata_quantity(recording: Recording, keys: Sequence[str], unit: str) -> float | None:
    """A number from the file's ``# key: value`` metadata (first key present), in ``unit``."""
    from motorlab.units import parse_quantity

    for key in keys:
        if key in recording.metadata:
            try:
                return parse_quantity(recording.metadata[key], unit, name=key)
            except OptionError as exc:
                raise LogFormatError(exc.message, path=recording.source or None) from None
    return None


def sources_of(recordings: Sequence[Recording]) -> list[str]:
    """The file names of ``recordings``, in order, without duplicates."""
    out: list[str] = []
    for rec in recordings:
        for part in rec.source.split(" + ") if rec.source else []:
            if part not in out:
                out.append(part)
    return out


@dataclass
class StraightLine:
    """A fitted ``y = slope·x + intercept`` with its least-squares details."""

    fit: LeastSquares
    x: np.ndarray
    y: np.ndarray
    model: np.ndarray
    r2: float
    #: True when the rows lie exactly on the line (more than two rows, zero residuals): the
    #: standard errors are then NaN, not 0.
    exact: bool = False

    @property
    def slope(self) -> float:
        """The slope [y-unit per x-unit]."""
        return float(self.fit.values[0])

    @property
    def intercept(self) -> float:
        """The intercept [y-unit]."""
        return float(self.fit.values[1])


def fit_straight_line(
    x: np.ndarray, y: np.ndarray, *, source: str = "", what: str = "x", response: str = "response"
) -> StraightLine:
    """Ordinary least squares ``y = slope·x + intercept`` with standard errors.

    Raises
    ------
    FitError
        With fewer than two rows, when every row has the same ``x`` (no slope to see) or the same
        ``y`` (a flat response, e.g. a column of zeros: nothing was measured).
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    where = f"{source}: " if source else ""
    if x.size < 2:
        raise FitError(f"{where}{x.size} row(s): a straight line needs at least two rows with different {what}")
    if np.ptp(x) == 0:
        raise FitError(f"{where}every row has the same {what}: a slope needs at least two different values")
    check_flat(y, response, source=source)
    design = np.column_stack([x, np.ones_like(x)])
    fit = fit_linear(design, y, ["slope", "intercept"])
    model = design @ fit.values
    exact = x.size > 2 and no_scatter(y, model)
    if exact:
        # Zero residuals give s² = 0 and so "± 0": not a precise result but one whose scatter
        # cannot be seen (readings rounded to a coarse display, or made up).
        fit.stderr = np.full(2, math.nan)
        fit.covariance = np.full((2, 2), math.nan)
    return StraightLine(fit=fit, x=x, y=y, model=model, r2=r_squared(y, model), exact=exact)


#: Warning of an analysis whose rows lie exactly on its straight line (see :func:`fit_straight_line`).
EXACT_LINE_WARNING = (
    "the rows lie exactly on a straight line: there is no scatter to estimate the uncertainty from "
    "(readings rounded to a coarse display?)"
)


def no_scatter(y: np.ndarray, model: np.ndarray) -> bool:
    """True when ``y − model`` is zero up to rounding of the arithmetic (an exact fit: s² = 0)."""
    y = np.asarray(y, dtype=float)
    scale = float(np.max(np.abs(y))) if y.size else 0.0
    return bool(np.all(np.abs(y - model) <= 1e-12 * max(scale, 1e-300)))


# ---- fits with known inputs that carry an uncertainty ---------------------------------------------
@dataclass
class Prior:
    """Known value(s) of some fit parameters with their covariance (a measurement made elsewhere).

    A prior with zero variance fixes the parameter; otherwise it adds the residual
    L⁻¹·(x − mean) (L the Cholesky factor of ``covariance``) so that its uncertainty is propagated
    into every other estimate, correlations included.
    """

    names: list[str]
    mean: np.ndarray
    covariance: np.ndarray


def fit_with_priors(
    data_residual: Callable[[np.ndarray], np.ndarray],
    x0: np.ndarray,
    names: list[str],
    priors: list[Prior],
) -> tuple[LeastSquares, np.ndarray]:
    """Least squares of ``data_residual(x)`` (already divided by its σ) plus prior residuals.

    Returns the fit over the free parameters (``sigma_known`` covariance) and the full parameter
    vector at the optimum (fixed parameters included).
    """
    x_full = np.array(x0, dtype=float)
    fixed: dict[int, float] = {}
    blocks: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
    for prior in priors:
        index = np.array([names.index(n) for n in prior.names])
        mean = np.asarray(prior.mean, dtype=float)
        cov = np.atleast_2d(np.asarray(prior.covariance, dtype=float))
        var = np.diag(cov)
        for k, m, v in zip(index, mean, var, strict=True):
            x_full[k] = m
            if v <= 0:
                fixed[int(k)] = float(m)
        keep = var > 0
        if keep.any():
            chol = np.linalg.cholesky(cov[np.ix_(keep, keep)])
            blocks.append((index[keep], mean[keep], np.linalg.inv(chol)))
    free = [k for k in range(len(names)) if k not in fixed]

    def full(xf: np.ndarray) -> np.ndarray:
        x = x_full.copy()
        x[free] = xf
        return x

    def residual(xf: np.ndarray) -> np.ndarray:
        x = full(xf)
        parts = [data_residual(x)] + [inv_l @ (x[index] - mean) for index, mean, inv_l in blocks]
        return np.concatenate(parts)

    fit = fit_least_squares(residual, x_full[free].tolist(), [names[k] for k in free], sigma_known=True)
    return fit, full(fit.values)


def derived_stderr(fit: LeastSquares, x_full: np.ndarray, names: list[str],
                   func: Callable[[np.ndarray], float]) -> float:
    """Standard error of ``func(x_full)`` by first-order propagation of the fit's covariance."""
    free = [names.index(n) for n in fit.names]
    grad = np.empty(len(free))
    for j, k in enumerate(free):
        h = 1e-6 * max(abs(x_full[k]), 1e-12)
        up, down = x_full.copy(), x_full.copy()
        up[k] += h
        down[k] -= h
        grad[j] = (func(up) - func(down)) / (2 * h)
    return float(math.sqrt(max(grad @ fit.covariance @ grad, 0.0)))


#: Per-reading tables in ``details`` list at most this many rows (a table of a hand-run experiment
#: has ten; a two-million-row log listed row by row would cost gigabytes and say nothing).
MAX_LISTED_ROWS = 1000


def listed_rows(count: int, row: Callable[[int], dict[str, Any]]) -> list[dict[str, Any]] | str:
    """``[row(0), …, row(count − 1)]``, or a note when there are more than :data:`MAX_LISTED_ROWS`."""
    if count > MAX_LISTED_ROWS:
        return f"not listed: {count} readings (more than {MAX_LISTED_ROWS})"
    return [row(k) for k in range(count)]
