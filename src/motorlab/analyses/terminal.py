"""Terminal (steady) speed at constant current: viscous friction b and Coulomb friction Tf.

Seed 1, "Terminal Velocity Experiment": the bare motor runs on a constant current until its speed
stops rising; the oscilloscope's frequency counter gives the frequency f of one encoder channel and
the supply's display the current I. At steady state the torque K·I balances the friction:

    K·I = b·ω + Tf,   ω = 2π·4·f/cpr
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from motorlab.analyses import common
from motorlab.errors import FitError, LogFormatError, OptionError
from motorlab.estimation.least_squares import fit_linear, r_squared
from motorlab.recording import Recording
from motorlab.results import Estimate, FitResult, Panel, Series
from motorlab.units import SI_UNITS

#: Speeds spreading less than this fraction of their mean count as one operating point.
_MIN_SPREAD = 0.01


def speeds_of(recording: Recording, *, cpr: float | None = None) -> np.ndarray:
    """Shaft speed [rad/s] of every row: from ``frequency`` (one encoder channel) and cpr, or a speed column.

    Raises
    ------
    OptionError
        A frequency column without ``cpr``.
    LogFormatError
        No frequency or speed column.
    """
    if "frequency" in recording.signals:
        from_file = cpr is None
        if cpr is None:
            cpr = recording.metadata.get("cpr")
        if cpr is None:
            raise OptionError("the rows hold encoder channel frequencies and the file has no '# cpr:' line: give "
                              "the counts per revolution (--cpr)", path=recording.source or None)
        common.check_positive(float(cpr), "cpr (encoder counts per revolution)")
        try:
            common.check_cpr(float(cpr))
        except OptionError as exc:
            if not from_file:
                raise
            raise LogFormatError(f"the '# cpr:' line: {exc.message}", path=recording.source or None) from None
        # One cycle of one channel spans four quadrature counts (seed 1, step 2).
        return 2.0 * math.pi * 4.0 * recording.signals["frequency"] / float(cpr)
    for name in ("speed", "velocity"):
        if name in recording.signals:
            return np.asarray(recording.signals[name], dtype=float)
    recording.require("frequency")
    raise AssertionError("unreachable")  # pragma: no cover


def terminal(
    recording: Recording,
    *,
    torque_constant: float,
    cpr: float | None = None,
    torque_constant_stderr: float | None = None,
    coulomb_friction: float | None = None,
    coulomb_friction_stderr: float | None = None,
    current_stderr: float | None = None,
    frequency_stderr: float | None = None,
) -> FitResult:
    """Viscous (and Coulomb) friction from steady speeds at constant currents.

    Parameters
    ----------
    recording
        One row per operating point: ``current`` [A] and ``frequency`` [Hz] of one encoder channel
        (or ``speed``/``velocity`` [rad/s]).
    torque_constant
        K [V·s/rad] = [N·m/A] at the counted shaft.
    cpr
        Encoder counts per revolution [count/rev] (needed with frequencies).
    torque_constant_stderr
        Standard error of K [V·s/rad], propagated into b and Tf (default: exact).
    coulomb_friction, coulomb_friction_stderr
        A known Tf [N·m] (and its standard error): then only b is fitted.
    current_stderr
        Standard error of one current reading [A] (the ammeter's resolution and accuracy), used
        when the rows leave no scatter to estimate it from (a single row, or exact repeats).
        Without it, b from such rows is reported with its uncertainty as unknown.
    frequency_stderr
        Standard error of one frequency reading [Hz] (the counter's resolution), propagated
        alongside ``current_stderr`` in the same cases (default: exact).

    Returns
    -------
    FitResult
        ``b`` [N·m·s/rad] and, with two or more distinct currents and speeds, ``Tf`` [N·m].

    Raises
    ------
    OptionError
        Missing or impossible K or cpr.
    LogFormatError
        NaN in the rows, no current or no speed.
    FitError
        No row, or no row where the motor turned. Rows at zero speed (stiction held the shaft)
        are left out with a warning.

    Notes
    -----
    The seed writes the steady state as "ω = Ke·J/b", which is garbled (J does not enter a steady
    state): it is ω = (K·I − Tf)/b. With several currents the current is regressed on the speed,
    I = (b/K)·ω + Tf/K, by ordinary least squares: the frequency counter reads to ~0.02 % while the
    supply's ammeter reads to ~1 mA and ±0.2 %, so the errors are in I and the small error in ω is
    neglected. K's uncertainty is then propagated (it scales b and Tf alike). With a single
    operating point (one row, rows whose speeds differ by less than 1 %, or rows that all read the
    same current) b and Tf cannot be separated: b = (K·I − Tf)/ω, and without Tf the Coulomb
    friction is folded into b. Its standard error is then the scatter of the per-row values
    b_k = (K·I_k − Tf)/ω_k when the rows differ, else first-order propagation of the given reading
    uncertainties, σ_b² = ((I·σ_K)² + (K·σ_I)² + σ_Tf² + (b·σ_ω)²)/ω²; with neither it is unknown
    (NaN), never a bare 0.

    References
    ----------
    Seed 1, "Terminal Velocity Experiment", "Data Analysis" steps 1–3.
    """
    source = recording.source or "rows"
    k_se, tf_se, f_se = _checked_options(torque_constant, cpr, torque_constant_stderr, coulomb_friction,
                                         coulomb_friction_stderr, current_stderr, frequency_stderr)
    common.check_finite_signals(recording, ["current", "frequency", "speed", "velocity"])
    current = np.abs(recording.require("current"))
    omega = np.abs(speeds_of(recording, cpr=cpr))
    omega_se = _frequency_stderr_as_speed(recording, cpr, f_se, given=frequency_stderr is not None, source=source)
    if current.size == 0:
        raise FitError(f"{source}: no rows")
    K = torque_constant
    warnings: list[str] = common.reader_warnings(recording)
    current, omega = _turning_rows(current, omega, source, warnings)
    spread, one_current, several = _operating_points(current, omega)
    if several and coulomb_friction is None:
        parameters, correlation, correlation_names, model_current = _fit_b_and_tf(
            omega, current, K=K, k_se=k_se, source=source, warnings=warnings)
    else:
        parameters, model_current = _fit_b(
            current, omega, K=K, coulomb_friction=coulomb_friction, k_se=k_se, tf_se=tf_se, i_se=current_stderr,
            omega_se=omega_se, points=(spread, one_current, several), warnings=warnings,
        )
        correlation, correlation_names = None, []
    return _result(recording, current, omega, model_current, parameters, correlation, correlation_names, warnings)


def _frequency_stderr_as_speed(recording: Recording, cpr: float | None, f_se: float, *, given: bool,
                               source: str) -> float:
    """One frequency reading's standard error as a speed [rad/s] (0 when not given).

    Raises
    ------
    OptionError
        A frequency standard error ``given`` for rows that hold speeds.
    """
    if given and "frequency" not in recording.signals:
        raise OptionError(f"{source}: the rows hold speeds, not frequencies: the frequency's standard error "
                          "does not apply")
    # One frequency reading's standard error as a speed [rad/s]: ω = 2π·4·f/cpr (speeds_of).
    omega_se = 0.0
    if f_se > 0:
        omega_se = 2.0 * math.pi * 4.0 * f_se / float(cpr if cpr is not None else recording.metadata["cpr"])
    return omega_se


def _turning_rows(current: np.ndarray, omega: np.ndarray, source: str,
                  warnings: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """The rows where the motor turned (a warning names those left out).

    Raises
    ------
    FitError
        When the motor turned in no row.
    """
    at_rest = omega <= 0
    if np.all(at_rest):
        raise FitError(f"{source}: the motor did not turn in any row (zero speed): raise the current")
    if np.any(at_rest):
        # A shaft held by stiction only says K·I ≤ Tf: no speed to balance, so the row is left out.
        rows = ", ".join(f"{k + 1} ({current[k]:.3g} A)" for k in np.flatnonzero(at_rest))
        warnings.append(f"rows {rows} have zero speed (stiction held the shaft, K·I ≤ Tf): left out")
        current, omega = current[~at_rest], omega[~at_rest]
    return current, omega


def _operating_points(current: np.ndarray, omega: np.ndarray) -> tuple[float, bool, bool]:
    """The relative spread of the speeds, whether every row reads one current, and whether the rows
    span several operating points (so that b and Tf can be separated)."""
    spread = float(np.ptp(omega) / np.mean(omega))
    one_current = current.size >= 2 and float(np.ptp(current)) == 0.0
    several = current.size >= 2 and spread >= _MIN_SPREAD and not one_current
    return spread, one_current, several


def _result(recording: Recording, current: np.ndarray, omega: np.ndarray, model_current: np.ndarray,
            parameters: dict[str, Estimate], correlation: np.ndarray | None, correlation_names: list[str],
            warnings: list[str]) -> FitResult:
    """The terminal analysis's result: the rows in ``details`` and the current-vs-speed panel."""
    details: dict[str, Any] = {
        "rows": common.listed_rows(
            current.size, lambda k: {"current_A": float(current[k]), "speed_rad_per_s": float(omega[k])}
        )
    }
    order = np.argsort(omega)
    panels = [
        Panel("Terminal speed: friction", "speed [rad/s]", "current [A]",
              data=Series(omega[order], current[order], "steady current"),
              model=Series(omega[order], model_current[order], "(b·ω + Tf)/K", kind="model")),
    ]
    return FitResult(
        experiment="terminal",
        parameters=parameters,
        correlation=correlation,
        correlation_names=correlation_names,
        rmse=float(np.sqrt(np.mean((current - model_current) ** 2))),
        rmse_unit="A",
        r2=r_squared(current, model_current) if current.size > 2 else math.nan,
        n_points=int(current.size),
        panels=panels,
        warnings=warnings,
        details=details,
        sources=[recording.source] if recording.source else [],
    )


def _checked_options(torque_constant: float, cpr: float | None, torque_constant_stderr: float | None,
                     coulomb_friction: float | None, coulomb_friction_stderr: float | None,
                     current_stderr: float | None, frequency_stderr: float | None) -> tuple[float, float, float]:
    """Refuse impossible options; the standard errors of K, Tf and one frequency reading (0 if not given)."""
    common.check_positive(torque_constant, "K (torque constant)", allow_none=False)
    common.check_positive(cpr, "cpr (encoder counts per revolution)")
    common.check_cpr(cpr)
    common.check_torque_constant(torque_constant)
    k_se = common.check_stderr_limit(torque_constant_stderr, "K", "the standard error of K (--K-stderr)")
    common.check_nonnegative(coulomb_friction, "Coulomb friction Tf")
    common.check_limits(coulomb_friction, "Tf", "the Coulomb friction Tf (--Tf)")
    tf_se = common.check_stderr_limit(coulomb_friction_stderr, "Tf", "the standard error of Tf (--Tf-stderr)")
    common.check_nonnegative(current_stderr, "standard error of the current")
    common.check_stderr_limit(current_stderr, "I", "the standard error of the current (--current-stderr)")
    f_se = common.check_stderr_limit(frequency_stderr, "f", "the standard error of the frequency (--frequency-stderr)")
    return k_se, tf_se, f_se


def _fit_b_and_tf(omega: np.ndarray, current: np.ndarray, *, K: float, k_se: float, source: str,
                  warnings: list[str]) -> tuple[dict[str, Estimate], np.ndarray, list[str], np.ndarray]:
    """b and Tf from the straight line I = (b/K)·ω + Tf/K, K's uncertainty propagated; the model current."""
    # I = β1·ω + β0 with β1 = b/K, β0 = Tf/K.
    line = common.fit_straight_line(omega, current, source=source, what="speed", response="current")
    fit = line.fit
    (beta1, beta0), cov = fit.values, fit.covariance
    if current.size == 2:
        warnings.append("two rows determine b and Tf exactly: their uncertainty cannot be estimated")
        cov = np.full((2, 2), np.nan)
    elif line.exact:
        warnings.append(common.EXACT_LINE_WARNING)
    b = K * beta1
    tf = K * beta0
    b_se = math.sqrt(K**2 * cov[0, 0] + beta1**2 * k_se**2)
    tf_se_out = math.sqrt(K**2 * cov[1, 1] + beta0**2 * k_se**2)
    cov_bt = K**2 * cov[0, 1] + beta1 * beta0 * k_se**2
    parameters: dict[str, Estimate] = {}
    parameters["b"] = Estimate("b", b, b_se, SI_UNITS["b"], bool(fit.determined[0]))
    parameters["Tf"] = Estimate("Tf", tf, tf_se_out, SI_UNITS["Tf"], bool(fit.determined[1]))
    rho = cov_bt / (b_se * tf_se_out) if b_se > 0 and tf_se_out > 0 else math.nan
    correlation = np.array([[1.0, rho], [rho, 1.0]])
    if tf < 0:
        warnings.append(f"the fitted Coulomb friction is negative ({tf:.3g} N·m): check the rows")
    model_current = beta1 * omega + beta0
    return parameters, correlation, ["b", "Tf"], model_current

def _fit_b(
    current: np.ndarray, omega: np.ndarray, *, K: float, coulomb_friction: float | None, k_se: float, tf_se: float,
    i_se: float | None, omega_se: float, points: tuple[float, bool, bool], warnings: list[str],
) -> tuple[dict[str, Estimate], np.ndarray]:
    """b with Tf given (taken as 0 when not, at one operating point) and the model current.

    ``points`` is the speeds' spread, whether the rows read one current and whether they span
    several operating points (:func:`_operating_points`).
    """
    spread, one_current, several = points
    tf = coulomb_friction or 0.0
    if several:
        b, b_se = _b_through_origin(current, omega, K=K, tf=tf, k_se=k_se, tf_se=tf_se, warnings=warnings)
    else:
        b, b_se = _one_operating_point(
            current, omega, K=K, tf=tf, k_se=k_se, tf_se=tf_se, i_se=i_se, omega_se=omega_se,
            warnings=warnings,
        )
        warnings.extend(_one_point_warnings(current, spread, one_current=one_current,
                                            given_tf=coulomb_friction is not None))
    parameters: dict[str, Estimate] = {"b": Estimate("b", b, b_se, SI_UNITS["b"])}
    if coulomb_friction is not None:
        parameters["Tf"] = Estimate("Tf", tf, tf_se, SI_UNITS["Tf"], note="given")
    return parameters, (b * omega + tf) / K


def _b_through_origin(current: np.ndarray, omega: np.ndarray, *, K: float, tf: float, k_se: float, tf_se: float,
                      warnings: list[str]) -> tuple[float, float]:
    """b from (K·I − Tf) = b·ω through the origin over several operating points, and its standard error."""
    fit = fit_linear(omega[:, None], K * current - tf, ["b"])
    b = float(fit.values[0])
    var_fit = float(fit.covariance[0, 0])
    if common.no_scatter(K * current - tf, b * omega):
        var_fit = math.nan
        warnings.append(common.EXACT_LINE_WARNING)
    # K and Tf errors move every row alike: propagate them through b = (K·Ī − Tf)·ω̄/ω̄².
    w2 = float(np.sum(omega**2))
    db_dk = float(np.sum(current * omega)) / w2
    db_dtf = -float(np.sum(omega)) / w2
    return b, math.sqrt(var_fit + db_dk**2 * k_se**2 + db_dtf**2 * tf_se**2)


def _one_point_warnings(current: np.ndarray, spread: float, *, one_current: bool, given_tf: bool) -> list[str]:
    """Why b and Tf cannot be separated from these rows (one operating point)."""
    out: list[str] = []
    if one_current and spread >= _MIN_SPREAD:
        out.append(
            f"every row reads the same current ({current[0]:.4g} A) while the speeds differ by "
            f"{100 * spread:.2g} %: b and Tf cannot be separated; rows treated as repeats of one "
            "operating point (measure at several currents)"
        )
    elif current.size >= 2:
        out.append(
            f"the rows span only {100 * spread:.2g} % in speed: b and Tf cannot be separated; "
            "rows treated as repeats of one operating point"
        )
    if not given_tf:
        out.append(
            "one operating point: Coulomb friction is folded into b (b = K·I/ω); "
            "measure at several currents to separate b and Tf"
        )
    return out


def _one_operating_point(
    current: np.ndarray, omega: np.ndarray, *, K: float, tf: float, k_se: float, tf_se: float,
    i_se: float | None, omega_se: float, warnings: list[str],
) -> tuple[float, float]:
    """b = (K·Ī − Tf)/ω̄ of rows that repeat one operating point, and its standard error (NaN if unknown).

    The scatter of the per-row b_k measures the reading errors when the rows differ; K's and Tf's
    errors are common to every row and are added to it. Rows that leave no scatter (one row, exact
    repeats) need the readings' standard errors: without ``i_se`` the uncertainty is unknown.
    """
    i_mean = float(np.mean(current))
    w_mean = float(np.mean(omega))
    b = (K * i_mean - tf) / w_mean
    common_var = ((i_mean * k_se) ** 2 + tf_se**2) / w_mean**2
    per_row = (K * current - tf) / omega
    n = current.size
    scatter = float(np.std(per_row, ddof=1)) / math.sqrt(n) if n > 1 else 0.0
    if scatter > 0:
        return b, math.sqrt(scatter**2 + common_var)
    if i_se is None:
        what = "one row" if n == 1 else f"{n} identical rows"
        warnings.append(
            f"{what}: the uncertainty of b cannot be estimated without the readings' standard errors "
            "(give --current-stderr, and --frequency-stderr, --K-stderr)"
        )
        return b, math.nan
    reading_var = ((K * i_se) ** 2 + (b * omega_se) ** 2) / w_mean**2 / n
    return b, math.sqrt(reading_var + common_var)
