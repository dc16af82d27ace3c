"""Torque constant K from a lever arm on a scale at several currents (stall torque test).

Seed 2 ("The Motor Torque Constant") clamps a lever arm to the load and reads the force on a
postage scale at several amplifier currents; seed 1 reads a scale under its torque arm in the
flywheel experiment. Either way the torque is τ = m·g·r and the torque constant is the slope of
τ against the current, T = Km·I (seed 2) = K·i (seed 1, eq. (1)).

At the output of a gearmotor the lever feels τ = η·N·K_m·i − τ0 (:mod:`motorlab.gearbox`): with the
motor's K_m known from a back-EMF experiment and the ratio N, the slope gives the gearbox efficiency η
and the intercept the loss torque τ0, both at the OUTPUT shaft.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from motorlab.analyses.common import (
    EXACT_LINE_WARNING,
    StraightLine,
    check_limits,
    check_range,
    check_stderr_limit,
    concatenate,
    fit_straight_line,
    metadata_quantity,
    reader_warnings,
    sources_of,
)
from motorlab.errors import LogFormatError, OptionError
from motorlab.estimation.least_squares import LeastSquares, fit_linear, r_squared
from motorlab.gearbox import efficiency_estimate
from motorlab.recording import Recording
from motorlab.results import Estimate, FitResult, Panel, Series
from motorlab.units import SI_UNITS, STANDARD_GRAVITY

#: An intercept larger than this fraction of the largest measured torque (and significant) is warned.
INTERCEPT_WARNING_FRACTION = 0.03


#: Rows up to which the answer lists each row's approach direction.
ROW_DETAILS = 1000

def _torque_rows(recs: list[Recording], arm: float | None, arm_stderr: float,
                 gearbox: tuple[float, float | None, float]) -> tuple[Recording, np.ndarray, float | None]:
    """The rows joined, their torque [N·m] (a torque column, or scale mass × g × arm) and the arm used [m].

    The options are checked in this order: the arm, its standard error, the gearbox's (``gearbox`` =
    ratio, motor K, its standard error), the arm's range."""
    has_torque = all("torque" in r for r in recs)
    if has_torque:
        rec = concatenate(recs, ["current", "torque"])
        tau = rec["torque"]
        arm_used = None
    else:
        for r in recs:
            if "mass" not in r:
                raise LogFormatError(
                    "this file has no scale reading (a mass_kg or mass_g column) nor torque_Nm",
                    path=r.source or None,
                )
        rec = concatenate(recs, ["current", "mass"])
        arm_used = arm if arm is not None else metadata_quantity(recs[0], ["arm_m", "arm"], "m")
        if arm_used is None:
            raise OptionError("the lever arm length is needed to turn scale readings into torque: give --arm")
        if not arm_used > 0:
            raise OptionError(f"the lever arm must be positive, got {arm_used} m")
        tau = rec["mass"] * STANDARD_GRAVITY * arm_used
    if arm_stderr < 0:
        raise OptionError("the arm length uncertainty must not be negative")
    _check_gearbox_options(*gearbox)
    try:
        check_limits(arm_used, "arm", "the lever arm (--arm)")
    except OptionError as exc:
        if arm is not None:
            raise
        raise LogFormatError(f"the '# arm_m:' line: {exc.message}", path=recs[0].source or None) from None
    check_stderr_limit(arm_stderr, "arm", "the lever arm's standard error (--arm-stderr)")
    return rec, tau, arm_used


def _offset_warning(intercept: Estimate, tau: np.ndarray) -> list[str]:
    """A warning when the torque at zero current is significant (friction, or an untared scale)."""
    tau_span = float(np.max(np.abs(tau)))
    if (
        math.isfinite(intercept.stderr)
        and abs(intercept.value) > 3 * intercept.stderr
        and abs(intercept.value) > INTERCEPT_WARNING_FRACTION * tau_span
    ):
        return [
            f"the torque offset tau0 = {intercept.value:.3g} N·m ({100 * abs(intercept.value) / tau_span:.1f} % "
            "of the largest torque) is significant: friction/stiction holding part of the torque, or a scale "
            "not tared with the arm resting on it"
        ]
    return []


def torque(
    recordings: Recording | Sequence[Recording],
    *,
    arm: float | None = None,
    arm_stderr: float = 0.0,
    ratio: float = 1.0,
    motor_constant: float | None = None,
    motor_constant_stderr: float = 0.0,
) -> FitResult:
    """Torque constant K [N·m/A] = [V·s/rad] from rows of current and scale reading.

    Parameters
    ----------
    recordings
        One or more recordings with ``current`` [A] and either ``mass`` [kg] (columns ``mass_kg``
        or ``mass_g``; the scale reading) or ``torque`` [N·m] (column ``torque_Nm``).
    arm
        Lever arm: distance from the shaft axis to the point resting on the scale [m]. Defaults to
        the ``# arm_m:`` metadata of the first file. Not needed when the files hold torque.
    arm_stderr
        Standard uncertainty of the arm length [m]; its relative part is added in quadrature to
        the relative standard error of K (it scales every torque alike, so the fit cannot see it).
    ratio
        Gear ratio N between the motor shaft and the lever's (output) shaft [-].
    motor_constant
        The motor's back-EMF constant K_m at the MOTOR shaft [V·s/rad] (a back-EMF experiment at
        the output gives N·K_m: divide by N). With it the result also holds ``efficiency`` η =
        slope/(N·K_m) and ``loss_torque`` τ0 = −intercept; with a single current η cannot be
        separated from τ0 and both are "not determined" (``apparent_efficiency`` τ/(N·K_m·I) is given).
    motor_constant_stderr
        Standard error of ``motor_constant`` [V·s/rad], propagated into η's.

    Returns
    -------
    FitResult
        ``K`` [V·s/rad] (the slope), ``tau0`` [N·m] (the intercept, a torque offset) and, when
        the currents were approached from both sides, ``tau_h`` [N·m] (the friction held by the
        stalled shaft: half-width of the hysteresis loop); the torque-vs-current panel and warnings.

    Raises
    ------
    OptionError
        If masses are given without an arm length, or the arm is not positive.
    LogFormatError
        If current or mass/torque is missing or a row is not finite.
    FitError
        With fewer than two rows or a single current.

    Notes
    -----
    τ = m·g·r with g = 9.80665 m/s² (standard gravity: the scale is calibrated in mass), and the
    fit is τ = K·i + τ0 by ordinary least squares. The intercept τ0 is reported rather than forced
    to zero: a scale that was not tared with the arm resting on it, or stiction/friction holding
    part of the torque (seed 2 suggests a 0.25 V, 30 Hz dither against it), shows up there.
    The stalled shaft creeps a little towards each new balance, so the friction it holds opposes
    that creep: a current reached from below reads low, one reached from above reads high. The
    rows are taken in the order they were measured (each file from rest); when some currents were
    approached from below and some from above (a sweep up and back down), the fit is
    τ = K·i + τ0 − d·τ_h, with d = +1 for a current larger than the one before (or the first) and
    −1 for a smaller one: the hysteresis is then fitted instead of being left in the residuals.
    A current of the wrong polarity gives a negative slope; K is then reported as its magnitude
    with a warning. The torque measured at the output of a gearbox includes gearbox losses, so
    this K can be lower than the back-EMF K (seed 1, "Experimental Notes").

    References
    ----------
    Seed 2 (MIT 2.010 Lab 2), "The Motor Torque Constant"; seed 1, "Flywheel and INA219 Experiment"
    (scale readings) and eq. (1).
    """
    recs = [recordings] if isinstance(recordings, Recording) else list(recordings)
    if not recs:
        raise OptionError("no recording given")
    gearbox = (ratio, motor_constant, motor_constant_stderr)
    rec, tau, arm_used = _torque_rows(recs, arm, arm_stderr, gearbox)
    current = rec["current"]
    sources = sources_of(recs)
    if motor_constant is not None and one_operating_current(current):
        return _single_current(rec, tau, recs, arm_used, arm_stderr, ratio, motor_constant, motor_constant_stderr)
    line = fit_straight_line(current, tau, source=" + ".join(sources), what="current",
                             response="scale reading" if arm_used is not None else "torque")
    approach = np.concatenate([approach_direction(r["current"]) for r in recs])
    fit, model_tau, r2, hysteresis = _fit_line(current, tau, approach, line)
    est = fit.estimates({"slope": "N*m/A", "intercept": "N*m", "tau_h": "N*m"})
    parameters, warnings = _parameters(est, hysteresis, arm_used, arm_stderr, gearbox)
    warnings.extend(_fit_warnings(int(current.size), line.exact, est["intercept"], tau, motor_constant is None))
    return FitResult(
        experiment="torque",
        parameters=parameters,
        correlation=fit.correlation,
        correlation_names=["K", "tau0", "tau_h"] if hysteresis else ["K", "tau0"],
        rmse=float(np.sqrt(np.mean((tau - model_tau) ** 2))),
        rmse_unit="N*m",
        r2=r2,
        n_points=int(current.size),
        panels=[_panel(current, tau, model_tau, parameters["K"].value, arm_used)],
        warnings=reader_warnings(recs) + warnings,
        details=_details(approach, hysteresis, arm_used, gearbox),
        sources=sources,
    )


def _fit_line(
    current: np.ndarray, tau: np.ndarray, approach: np.ndarray, line: StraightLine
) -> tuple[LeastSquares, np.ndarray, float, bool]:
    """The fit, its model torque, R² and whether the hysteresis τ_h was fitted.

    With at least four rows, two or more of them approached from below and two or more from above,
    τ = K·i + τ0 − d·τ_h is fitted; otherwise the straight line ``line`` is kept.
    """
    hysteresis = int(np.count_nonzero(approach > 0)) >= 2 and int(np.count_nonzero(approach < 0)) >= 2
    if hysteresis and current.size >= 4:
        design = np.column_stack([current, np.ones_like(current), -approach])
        fit = fit_linear(design, tau, ["slope", "intercept", "tau_h"])
        model_tau = design @ fit.values
        return fit, model_tau, r_squared(tau, model_tau), True
    return line.fit, line.model, line.r2, False


def _parameters(
    est: dict[str, Estimate], hysteresis: bool, arm_used: float | None, arm_stderr: float,
    gearbox: tuple[float, float | None, float],
) -> tuple[dict[str, Estimate], list[str]]:
    """K (the slope's magnitude, the arm's uncertainty added), tau0, the gearbox's efficiency and
    loss torque (with ``gearbox`` = ratio, motor K, its standard error, when the motor K is given) and
    tau_h (when fitted); the warnings about them (a reversed polarity, an impossible gearbox)."""
    ratio, motor_constant, motor_constant_stderr = gearbox
    warnings: list[str] = []
    slope, intercept = est["slope"], est["intercept"]
    if slope.value < 0:
        warnings.append(
            "torque falls as the current rises: the current polarity is reversed relative to the arm; "
            "K is reported as the magnitude of the slope"
        )
    k_value = abs(slope.value)
    k_stderr = slope.stderr
    if arm_used is not None and arm_stderr > 0 and math.isfinite(k_stderr):
        k_stderr = k_value * math.hypot(k_stderr / k_value, arm_stderr / arm_used)
    parameters = {
        "K": Estimate("K", k_value, k_stderr, SI_UNITS["K"], slope.determined, "slope of torque vs current"),
        "tau0": Estimate(
            "tau0", intercept.value, intercept.stderr, "N*m", True,
            "torque at zero current (intercept)",
        ),
    }
    if motor_constant is not None:
        parameters["K"] = replace(parameters["K"], note="Kt at the lever's (output) shaft: slope of torque vs current")
        parameters.update(_gearbox_estimates(parameters["K"], intercept, arm_used, arm_stderr, ratio,
                                             motor_constant, motor_constant_stderr))
        warnings.extend(_unphysical_gearbox(parameters["efficiency"], parameters["loss_torque"]))
    if hysteresis:
        h = est["tau_h"]
        parameters["tau_h"] = Estimate(
            "tau_h", h.value, h.stderr, "N*m", h.determined,
            "friction held by the stalled shaft (half-width of the up/down hysteresis)",
        )
    return parameters, warnings


def _fit_warnings(n_rows: int, exact: bool, intercept: Estimate, tau: np.ndarray, offset: bool) -> list[str]:
    """Warnings about the fit itself: no uncertainty from two rows or from rows exactly on the line,
    and a significant torque offset (``offset``: not when a gearbox is given, whose loss torque the
    offset is)."""
    out: list[str] = []
    if n_rows == 2:
        out.append("only two rows: the line passes through both, so no uncertainty can be estimated")
    elif exact:
        out.append(EXACT_LINE_WARNING)
    if offset:
        out.extend(_offset_warning(intercept, tau))
    return out


#: Currents that span less than this fraction of their mean are one operating point: a line through
#: them cannot separate its slope (η) from its intercept (τ0); the meter's scatter would set both.
ONE_CURRENT_SPAN = 0.05


def one_operating_current(current: np.ndarray) -> bool:
    """Whether the rows' currents are one operating point (their span below :data:`ONE_CURRENT_SPAN`)."""
    magnitude = np.abs(current)
    return bool(np.ptp(magnitude) <= ONE_CURRENT_SPAN * float(np.mean(magnitude)))


def _details(approach: np.ndarray, hysteresis: bool, arm_used: float | None,
             gearbox: tuple[float, float | None, float]) -> dict[str, object]:
    """The torque analysis's ``details``: g, how many rows were approached from below (+1), from above
    (−1) or neither (0), each row's direction for a table of up to :data:`ROW_DETAILS` rows (a longer one
    would put a number per row into the answer), whether the hysteresis was fitted, the gearbox's
    figures (when the motor K is given) and the arm used."""
    ratio, motor_constant, motor_constant_stderr = gearbox
    counts = {name: int(np.count_nonzero(approach == d)) for name, d in (("below", 1), ("above", -1), ("neither", 0))}
    details: dict[str, object] = {"g": STANDARD_GRAVITY, "approach_counts": counts, "hysteresis_fitted": hysteresis}
    if approach.size <= ROW_DETAILS:
        details["approach"] = [int(d) for d in approach]
    if motor_constant is not None:
        details.update(_gearbox_details(ratio, motor_constant, motor_constant_stderr))
    if arm_used is not None:
        details["arm_m"] = arm_used
    return details


def _panel(current: np.ndarray, tau: np.ndarray, model_tau: np.ndarray, k_value: float,
           arm_used: float | None) -> Panel:
    """Torque against current, with the fitted line."""
    return Panel(
        title="Torque vs current",
        x_label="current [A]",
        y_label="torque τ = m·g·r [N·m]" if arm_used is not None else "torque [N·m]",
        data=Series(current, tau, "scale readings", "data"),
        model=Series(current, model_tau, f"fit: K = {k_value:.4g} N·m/A", "model"),
    )


def _check_gearbox_options(ratio: float, motor_constant: float | None, motor_constant_stderr: float) -> None:
    if not (math.isfinite(ratio) and ratio > 0):
        raise OptionError(f"the gear ratio (--ratio) must be positive, got {ratio}")
    check_range(ratio, "the gear ratio (--ratio)", 1e-4, 1e4, "", why="a gearbox reduces by at most a few thousand")
    if motor_constant is None and (ratio != 1.0 or motor_constant_stderr != 0.0):
        given = "the gear ratio (--ratio)" if ratio != 1.0 else "K's standard error (--K-stderr)"
        raise OptionError(f"{given} is used only with the motor's K (--K), to report the gearbox efficiency: "
                          "give --K, or leave it out")
    if motor_constant is not None and not (math.isfinite(motor_constant) and motor_constant > 0):
        raise OptionError(f"the motor's K (--K) must be positive, got {motor_constant} V·s/rad")
    if not (math.isfinite(motor_constant_stderr) and motor_constant_stderr >= 0):
        raise OptionError(f"K's standard error (--K-stderr) must not be negative, got {motor_constant_stderr}")


def _gearbox_details(ratio: float, motor_constant: float, motor_constant_stderr: float) -> dict[str, object]:
    return {"ratio": ratio, "K_motor": motor_constant, "K_motor_stderr": motor_constant_stderr,
            "Ke_output": ratio * motor_constant,
            "shafts": "K, loss_torque: output (lever) shaft; K_motor: motor shaft; Ke_output = N·K_motor"}


def _gearbox_estimates(
    slope: Estimate, intercept: Estimate, arm: float | None, arm_stderr: float, ratio: float,
    motor_constant: float, motor_constant_stderr: float,
) -> dict[str, Estimate]:
    """η = Kt/(N·K_m) and τ0 = −intercept (output shaft), each with its standard error."""
    ke_out = ratio * motor_constant
    eta = efficiency_estimate(slope.value, slope.stderr, ke_out, ratio * motor_constant_stderr)
    if not slope.determined:
        eta = replace(eta, determined=False, note="not determined: the slope is not")
    tau0_se = intercept.stderr
    if arm is not None and arm_stderr > 0 and math.isfinite(tau0_se):
        tau0_se = math.hypot(tau0_se, intercept.value * arm_stderr / arm)
    loss = Estimate("loss_torque", -intercept.value, tau0_se, "N*m", intercept.determined,
                    "gearbox loss torque τ0 at the output shaft (minus the intercept)")
    return {"efficiency": eta, "loss_torque": loss}


def _unphysical_gearbox(eta: Estimate, loss: Estimate) -> list[str]:
    """Warnings for an efficiency above 1 or a negative loss torque beyond two standard errors."""
    out = []
    if eta.determined and eta.value - 2 * eta.stderr > 1:
        out.append(f"the efficiency {eta.value:.3g} ± {eta.stderr:.2g} exceeds 1, which no gearbox does: check the "
                   "arm length, the gear ratio (--ratio) and that --K is at the MOTOR shaft (Ke at the output ÷ N)")
    if loss.determined and loss.value + 2 * loss.stderr < 0:
        out.append(f"the loss torque {loss.value:.3g} ± {loss.stderr:.2g} N·m is negative, which no gearbox gives: "
                   "a scale not tared with the arm resting on it?")
    return out


def _single_current(
    rec: Recording, tau: np.ndarray, recs: list[Recording], arm: float | None, arm_stderr: float,
    ratio: float, motor_constant: float, motor_constant_stderr: float,
) -> FitResult:
    """One current: τ = η·N·K·I − τ0 cannot separate η from τ0; only their combination is measured."""
    current = np.abs(rec["current"])
    i0 = float(np.mean(current))
    n = int(tau.size)
    mean = float(np.mean(tau))
    se = float(np.std(tau, ddof=1) / math.sqrt(n)) if n > 1 else math.nan
    if arm is not None and arm_stderr > 0 and math.isfinite(se):
        se = math.hypot(se, mean * arm_stderr / arm)
    ke_out = ratio * motor_constant
    apparent = efficiency_estimate(mean / i0, se / i0, ke_out, ratio * motor_constant_stderr,
                                   note=f"apparent efficiency τ/(N·K·I) at {i0:.3g} A: η − τ0/(N·K·I), "
                                   "a lower bound on η")
    apparent = replace(apparent, name="apparent_efficiency")
    undetermined = "not determined: one current cannot separate the efficiency from the loss torque"
    parameters = {
        "K": Estimate("K", math.nan, math.nan, SI_UNITS["K"], False, undetermined),
        "efficiency": Estimate("efficiency", math.nan, math.nan, "1", False, undetermined),
        "loss_torque": Estimate("loss_torque", math.nan, math.nan, "N*m", False, undetermined),
        "apparent_efficiency": apparent,
    }
    panel = Panel(title="Torque vs current", x_label="current [A]", y_label="torque [N·m]",
                  data=Series(current, tau, "scale readings", "data"),
                  model=Series(current, np.full_like(tau, mean), "mean torque", "model"))
    return FitResult(
        experiment="torque", parameters=parameters, correlation=None, correlation_names=[],
        rmse=float(np.sqrt(np.mean((tau - mean) ** 2))), rmse_unit="N*m", r2=math.nan, n_points=n,
        panels=[panel],
        warnings=[*reader_warnings(recs), f"every row is at one current ({i0:.3g} A, spread under "
                  f"{100 * ONE_CURRENT_SPAN:g} %): the efficiency and the loss torque are not determined "
                  "separately (measure at several currents)"],
        details={"g": STANDARD_GRAVITY, **({"arm_m": arm} if arm is not None else {}),
                 **_gearbox_details(ratio, motor_constant, motor_constant_stderr)},
        sources=sources_of(recs),
    )


def approach_direction(current: np.ndarray) -> np.ndarray:
    """+1 for a row whose |current| is larger than the row before (the first row: from rest), −1
    for a smaller one; a repeated current keeps the direction of the row before."""
    magnitude = np.abs(np.asarray(current, dtype=float))
    out = np.ones(magnitude.size)
    previous = 0.0
    for k, value in enumerate(magnitude):
        if value != previous:
            out[k] = 1.0 if value > previous else -1.0
        elif k:
            out[k] = out[k - 1]
        previous = float(value)
    return out
