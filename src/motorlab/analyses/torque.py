"""Torque constant K from a lever arm on a scale at several currents (stall torque test).

Seed 2 ("The Motor Torque Constant") clamps a lever arm to the load and reads the force on a
postage scale at several amplifier currents; seed 1 reads a scale under its torque arm in the
flywheel experiment. Either way the torque is τ = m·g·r and the torque constant is the slope of
τ against the current, T = Km·I (seed 2) = K·i (seed 1, eq. (1)).
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Sequence

import numpy as np

from motorlab.analyses._common import (
    EXACT_LINE_WARNING,
    check_limits,
    check_stderr_limit,
    concatenate,
    fit_straight_line,
    metadata_quantity,
    read_tables,
    reader_warnings,
    sources_of,
)
from motorlab.errors import LogFormatError, OptionError
from motorlab.fitting import fit_linear, r_squared
from motorlab.recording import Recording
from motorlab.results import Estimate, FitResult, Panel, Series
from motorlab.units import SI_UNITS, STANDARD_GRAVITY

#: An intercept larger than this fraction of the largest measured torque (and significant) is warned.
INTERCEPT_WARNING_FRACTION = 0.03


def torque(
    recordings: Recording | Sequence[Recording],
    *,
    arm: float | None = None,
    arm_stderr: float = 0.0,
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
    warnings: list[str] = []
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
    try:
        check_limits(arm_used, "arm", "the lever arm (--arm)")
    except OptionError as exc:
        if arm is not None:
            raise
        raise LogFormatError(f"the '# arm_m:' line: {exc.message}", path=recs[0].source or None) from None
    check_stderr_limit(arm_stderr, "arm", "the lever arm's standard error (--arm-stderr)")
    current = rec["current"]
    sources = sources_of(recs)
    line = fit_straight_line(current, tau, source=" + ".join(sources), what="current",
                             response="scale reading" if arm_used is not None else "torque")
    approach = np.concatenate([approach_direction(r["current"]) for r in recs])
    hysteresis = int(np.count_nonzero(approach > 0)) >= 2 and int(np.count_nonzero(approach < 0)) >= 2
    if hysteresis and current.size >= 4:
        design = np.column_stack([current, np.ones_like(current), -approach])
        fit = fit_linear(design, tau, ["slope", "intercept", "tau_h"])
        model_tau = design @ fit.values
        r2 = r_squared(tau, model_tau)
    else:
        hysteresis = False
        fit, model_tau, r2 = line.fit, line.model, line.r2
    est = fit.estimates({"slope": "N*m/A", "intercept": "N*m", "tau_h": "N*m"})
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
    if hysteresis:
        h = est["tau_h"]
        parameters["tau_h"] = Estimate(
            "tau_h", h.value, h.stderr, "N*m", h.determined,
            "friction held by the stalled shaft (half-width of the up/down hysteresis)",
        )
    if current.size == 2:
        warnings.append("only two rows: the line passes through both, so no uncertainty can be estimated")
    elif line.exact:
        warnings.append(EXACT_LINE_WARNING)
    tau_span = float(np.max(np.abs(tau)))
    if (
        math.isfinite(intercept.stderr)
        and abs(intercept.value) > 3 * intercept.stderr
        and abs(intercept.value) > INTERCEPT_WARNING_FRACTION * tau_span
    ):
        warnings.append(
            f"the torque offset tau0 = {intercept.value:.3g} N·m ({100 * abs(intercept.value) / tau_span:.1f} % "
            "of the largest torque) is significant: friction/stiction holding part of the torque, or a scale "
            "not tared with the arm resting on it"
        )
    details: dict[str, object] = {"g": STANDARD_GRAVITY, "approach": [int(d) for d in approach],
                                  "hysteresis_fitted": hysteresis}
    if arm_used is not None:
        details["arm_m"] = arm_used
    panel = Panel(
        title="Torque vs current",
        x_label="current [A]",
        y_label="torque τ = m·g·r [N·m]" if arm_used is not None else "torque [N·m]",
        data=Series(current, tau, "scale readings", "data"),
        model=Series(current, model_tau, f"fit: K = {k_value:.4g} N·m/A", "model"),
    )
    return FitResult(
        experiment="torque",
        parameters=parameters,
        correlation=fit.correlation,
        correlation_names=["K", "tau0", "tau_h"] if hysteresis else ["K", "tau0"],
        rmse=float(np.sqrt(np.mean((tau - model_tau) ** 2))),
        rmse_unit="N*m",
        r2=r2,
        n_points=int(current.size),
        panels=[panel],
        warnings=reader_warnings(recs) + warnings,
        details=details,
        sources=sources,
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


def add_arguments(parser: argparse.ArgumentParser, experiment: str) -> None:
    """Options of ``motorlab analyze torque``."""
    from motorlab.cli.common import quantity

    parser.add_argument(
        "--arm", type=quantity("m", positive=True), default=None, metavar="LENGTH",
        help="lever arm from the shaft axis to the scale contact [m], e.g. 0.1 or '4 in' "
        "(default: '# arm_m:' in the file)",
    )
    parser.add_argument(
        "--arm-stderr", type=quantity("m", nonnegative=True), default=0.0, metavar="LENGTH",
        help="standard uncertainty of the arm length [m], added to K's standard error",
    )


def from_cli(experiment: str, paths: list[str], args: argparse.Namespace) -> FitResult:
    """Run ``motorlab analyze torque FILE...``."""
    return torque(read_tables(paths), arm=args.arm, arm_stderr=args.arm_stderr)
