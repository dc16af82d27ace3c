"""A motor curve (steady speed, torque and current at one voltage) → K, Kt, R, the free current, friction.

Dynamometers and datasheets give a motor's steady-state curve from stall (speed 0) to free speed
(torque 0) at one terminal voltage V (VEX Robotics' exports: ``Speed (RPM),Torque (N·m),Current (A),…``
at 12 V). Each row is a steady state of L·di/dt = V − R·i − K·ω, J·dω/dt = Kt·i − b·ω − Tf, so

* electrically, V = R·I + K·ω at every row: R and K by least squares over the rows (R from the
  stall end, K from the free-speed end: the back-EMF constant);
* mechanically, τ = Kt·I − Tf − b·ω at the shaft. At one voltage ω is itself linear in I
  (ω = (V − R·I)/K), so the curve's torque is a straight line in the current,
  τ = (Kt + b·R/K)·I − (Tf + b·V/K): its slope is the torque per amp ``Kt`` (Kt itself when the
  friction is Coulomb, Kt + b·R/K when it is viscous), and where it crosses τ = 0 is the **free
  current** I₀, whose torque Kt·I₀ is the friction at free speed. Coulomb and viscous friction
  cannot be told apart at one voltage; curves at several voltages (files, or a voltage column that
  varies) separate them: τ = Kt·I − Tf − b·ω is then fitted with all three.

``Kt/K`` compares the torque per amp with the back-EMF constant; in SI they are the same constant
for an ideal motor, so a ratio below 1 is torque lost inside the motor at high current (brush
drop, armature reaction, iron losses) and, on a gearmotor, part of what a gearbox efficiency
would otherwise be blamed for (docs/gearbox.md).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from motorlab.analyses.common import reader_warnings, sources_of
from motorlab.errors import FitError, LogFormatError, OptionError
from motorlab.estimation.decimate import consecutive
from motorlab.estimation.least_squares import LeastSquares, fit_linear, r_squared
from motorlab.recording import Recording
from motorlab.results import Estimate, FitResult, Panel, Series
from motorlab.units import SI_UNITS

#: Voltages that span more than this fraction of their mean are several curves: Tf and b separate.
VOLTAGE_SPAN = 0.05
#: Residuals below this fraction of the response's range: the rows were drawn on a line between two points.
INTERPOLATED = 1e-4
#: |Kt/K − 1| above this (and beyond two standard errors) is worth a warning.
RATIO_WARNING = 0.05


#: Highest terminal voltage a curve can be given at [V]: brushed DC motors run from a few volts to a few hundred.
MAX_VOLTAGE = 1000.0
#: Most rows a curve is fitted at: a longer one (a dynamometer logging every sample) is reduced to means of
#: neighbouring rows (VEX's curves have ~100).
MAX_ROWS = 20_000


def curve(recordings: Recording | Sequence[Recording], *, voltage: float | None = None) -> FitResult:
    """K, Kt, R, the free current and the friction of a bare motor from its steady-state curve(s).

    Parameters
    ----------
    recordings
        One or more curves: rows of ``current`` [A], ``torque`` [N·m] and ``speed`` or ``velocity``
        [rad/s] at the motor shaft, and ``voltage`` [V] when the file has it.
    voltage
        The terminal voltage of every row [V], for files without a voltage column (VEX's curves are
        at 12 V). Refused when a file has one. Without either, a file with supplied power and
        current (VEX's exports) gives it as their ratio, when that is one value (within 1 %).

    Returns
    -------
    FitResult
        ``K`` [V·s/rad] (back-EMF), ``R`` [Ω], ``Kt`` [N·m/A] (torque per amp), ``Kt_over_K``,
        ``I_free`` [A] (current at zero torque), ``friction_torque`` [N·m] (at free speed), ``b`` and
        ``Tf`` (determined only with several voltages; otherwise their bounds in the notes); two
        panels (current against speed with the back-EMF model; torque against current) with residuals.

    Raises
    ------
    LogFormatError
        A file without current (some exports log torque only), torque or speed, or without a voltage
        column when ``voltage`` is not given.
    OptionError
        ``voltage`` not positive, above :data:`MAX_VOLTAGE`, or given for a file that has a voltage column.
    FitError
        Fewer than three rows, or rows that do not span speed and current.
    """
    recs = [recordings] if isinstance(recordings, Recording) else list(recordings)
    if not recs:
        raise OptionError("no curve given")
    if voltage is not None and not (math.isfinite(voltage) and voltage > 0):
        raise OptionError(f"the voltage (--voltage) must be positive, got {voltage!r}")
    if voltage is not None and voltage > MAX_VOLTAGE:
        raise OptionError(f"the voltage (--voltage) {voltage:.4g} V is above {MAX_VOLTAGE:g} V, beyond any brushed "
                          "DC motor's: give the voltage the curve was measured at, in volts")
    notes: list[str] = []
    current, torque, speed, volts = _rows(recs, voltage, notes)
    source = " + ".join(sources_of(recs))
    group = math.ceil(current.size / MAX_ROWS)
    if group > 1:  # means of neighbouring rows lie on the same lines; their scatter gives the same uncertainty
        notes.append(f"{source}: {current.size:,} rows fitted as {math.ceil(current.size / group):,} means of "
                     f"{group} neighbouring rows")
        current, torque, speed, volts = (consecutive(x, group, np.mean) for x in (current, torque, speed, volts))
    if current.size < 3:
        raise FitError(f"{source}: a curve needs at least three rows, found {current.size}")
    for values, what in ((speed, "speed"), (current, "current")):
        if float(np.ptp(values)) <= 1e-9 * max(float(np.max(np.abs(values))), 1e-300):
            raise FitError(f"{source}: the {what} is the same in every row: this is not a motor curve "
                           "(from stall to free speed)")
    several = float(np.ptp(volts)) > VOLTAGE_SPAN * float(np.mean(volts))
    electrical = fit_linear(np.column_stack([current, speed]), volts, ["R", "K"])
    if several:
        mechanical = fit_linear(np.column_stack([current, -np.ones_like(current), -speed]), torque, ["Kt", "Tf", "b"])
    else:
        mechanical = fit_linear(np.column_stack([current, np.ones_like(current)]), torque, ["Kt", "c"])
    parameters = _parameters(electrical, mechanical, several, speed, volts)
    model_current = (volts - parameters["K"].value * speed) / parameters["R"].value
    model_torque = _model_torque(mechanical, current, speed, several)
    warnings = reader_warnings(recs) + notes + _warnings(parameters, electrical, mechanical, volts, torque, several)
    return FitResult(
        experiment="curve",
        parameters=parameters,
        correlation=mechanical.correlation,
        correlation_names=["Kt", "Tf", "b"] if several else ["Kt", "friction_torque"],
        rmse=float(np.sqrt(np.mean((torque - model_torque) ** 2))),
        rmse_unit="N*m",
        r2=r_squared(torque, model_torque),
        n_points=int(current.size),
        panels=_panels(current, torque, speed, model_current, model_torque, parameters),
        warnings=warnings,
        details=_details(current, torque, speed, volts, electrical, several),
        sources=sources_of(recs),
    )


def _voltage_from_power(rec: Recording, notes: list[str]) -> np.ndarray:
    """The terminal voltage of a curve without a voltage column: its supplied power / current when it has
    both (VEX's exports: ``Supplied Power (W)`` = 12 V × current), held at one value; else a refusal."""
    current = rec["current"]
    if "input_power" in rec and np.all(current > 0):
        ratio = rec["input_power"] / current
        level = float(np.median(ratio))
        if level > 0 and float(np.max(np.abs(ratio - level))) <= 0.01 * level:
            notes.append(f"{rec.source}: no voltage column; the voltage is the supplied power / current, {level:.4g} V "
                         "in every row (give --voltage to set it)")
            return np.full(len(rec), level)
    raise LogFormatError("this curve has no voltage column: give the voltage it was measured at with --voltage "
                         "(VEX's curves: 12 V)", path=rec.source or None)


def _rows(recs: list[Recording], voltage: float | None, notes: list[str]) -> tuple[np.ndarray, ...]:
    """Current, torque, speed and the voltage of every row, joined over the files (one-line errors); what
    was inferred goes into ``notes``."""
    parts: list[list[np.ndarray]] = [[], [], [], []]
    for rec in recs:
        have = ", ".join(sorted(rec.signals)) or "nothing"
        if "current" not in rec:
            raise LogFormatError(
                f"this curve has no current (it has: {have}): K, Kt and R need the current at each speed; "
                "if a column holds it, map it with --column \"HEADER=current\"", path=rec.source or None)
        for name in ("torque",):
            rec.require(name)
        speed_name = "speed" if "speed" in rec else "velocity" if "velocity" in rec else None
        if speed_name is None:
            raise LogFormatError(f"this curve has no speed (it has: {have}); if a column holds it, map it with "
                                 "--column \"HEADER=speed [rpm]\"", path=rec.source or None)
        if "voltage" in rec and voltage is not None:
            raise OptionError(f"{rec.source}: the file has a voltage column; leave out --voltage")
        if "voltage" in rec:
            volts = rec["voltage"]
        elif voltage is None:
            volts = _voltage_from_power(rec, notes)
        else:
            volts = np.full(len(rec), float(voltage))
        current = rec["current"]
        if np.all(current == 0):
            raise LogFormatError("the current is 0 in every row: this run logged no current", path=rec.source or None)
        for k, values in enumerate((current, rec["torque"], np.abs(rec[speed_name]), volts)):
            parts[k].append(np.asarray(values, dtype=float))
    out = tuple(np.concatenate(p) for p in parts)
    bad = next((k for k, values in enumerate(out) if not np.all(np.isfinite(values))), None)
    if bad is not None:
        raise LogFormatError(f"a {('current', 'torque', 'speed', 'voltage')[bad]} value is not finite",
                             path=recs[0].source or None)
    return out


def _ratio(num: Estimate, den: Estimate) -> tuple[float, float]:
    value = num.value / den.value
    return value, abs(value) * math.hypot(num.stderr / num.value, den.stderr / den.value)


def _parameters(electrical: LeastSquares, mechanical: LeastSquares, several: bool, speed: np.ndarray,
                volts: np.ndarray) -> dict[str, Estimate]:
    """K, R, Kt, Kt/K, the free current and the friction (b and Tf when several voltages separate them)."""
    el = electrical.estimates({"R": "ohm", "K": SI_UNITS["K"]},
                              notes={"R": "from V = R·I + K·ω over the rows (the stall end)",
                                     "K": "back-EMF constant from V = R·I + K·ω (the free-speed end)"})
    mech_units = {"Kt": "N*m/A", "Tf": "N*m", "b": "N*m*s/rad", "c": "N*m"}
    me = mechanical.estimates({k: mech_units[k] for k in mechanical.names})
    kt_note = ("torque per amp, from τ = Kt·I − Tf − b·ω" if several else
               "torque per amp: the slope of torque vs current (Kt + b·R/K if the friction is viscous)")
    kt = Estimate("Kt", me["Kt"].value, me["Kt"].stderr, "N*m/A", me["Kt"].determined, kt_note)
    ratio, ratio_se = _ratio(kt, el["K"])
    out = {"K": el["K"], "R": el["R"], "Kt": kt,
           "Kt_over_K": Estimate("Kt_over_K", ratio, ratio_se, "1", True, "torque per amp over the back-EMF constant")}
    omega_free = float(np.max(speed))
    v_mean = float(np.mean(volts))
    if several:
        tf, b = me["Tf"], me["b"]
        friction = tf.value + b.value * omega_free
        cov = mechanical.covariance
        se = math.sqrt(max(cov[1, 1] + omega_free**2 * cov[2, 2] + 2 * omega_free * cov[1, 2], 0.0))
        out["friction_torque"] = Estimate("friction_torque", friction, se, "N*m", True,
                                          f"Tf + b·ω at the highest speed ({omega_free:.4g} rad/s)")
        out["I_free"] = _free_current(friction, se, kt)
        out["b"] = Estimate("b", b.value, b.stderr, "N*m*s/rad", b.determined, "viscous friction (curves at "
                            "several voltages)")
        out["Tf"] = Estimate("Tf", tf.value, tf.stderr, "N*m", tf.determined, "Coulomb friction")
        return out
    c = me["c"]
    loss = Estimate("friction_torque", -c.value, c.stderr, "N*m", c.determined,
                        "friction torque at free speed (Kt·I₀: minus the torque at zero current)")
    out["friction_torque"] = loss
    out["I_free"] = _free_current(loss.value, loss.stderr, kt, mechanical)
    bound = f"at one voltage ({v_mean:.3g} V) Coulomb and viscous friction cannot be told apart"
    out["b"] = Estimate("b", math.nan, math.nan, "N*m*s/rad", False,
                        f"not determined: {bound}; all viscous it would be {loss.value / omega_free:.3g} "
                        "N·m·s/rad (friction torque / free speed)")
    out["Tf"] = Estimate("Tf", math.nan, math.nan, "N*m", False,
                         f"not determined: {bound}; all Coulomb it would be {loss.value:.3g} N·m")
    return out


def _free_current(friction: float, friction_se: float, kt: Estimate, fit: LeastSquares | None = None) -> Estimate:
    """I₀ = friction / Kt (the current at zero torque), with its standard error (delta method)."""
    value = friction / kt.value
    if fit is not None:  # I₀ = −c/a from τ = a·I + c: the covariance of a and c
        a, c = fit.values
        cov = fit.covariance
        var = cov[1, 1] / a**2 + c**2 * cov[0, 0] / a**4 - 2 * c * cov[0, 1] / a**3
        se = math.sqrt(max(var, 0.0))
    else:
        se = abs(value) * math.hypot(friction_se / friction if friction else 0.0, kt.stderr / kt.value)
    return Estimate("I_free", value, se, "A", True, "free current: the current at zero torque")


def _model_torque(fit: LeastSquares, current: np.ndarray, speed: np.ndarray, several: bool) -> np.ndarray:
    if several:
        kt, tf, b = fit.values
        return kt * current - tf - b * speed
    slope, intercept = fit.values
    return slope * current + intercept


def _warnings(parameters: dict[str, Estimate], electrical: LeastSquares, mechanical: LeastSquares,
              volts: np.ndarray, torque: np.ndarray, several: bool) -> list[str]:
    """What the figures need said: interpolated rows, Kt/K away from 1, a fit that does not hold."""
    out: list[str] = []
    el_rms = float(np.sqrt(np.mean(electrical.residuals**2)))
    me_rms = float(np.sqrt(np.mean(mechanical.residuals**2)))
    torque_span = float(np.ptp(torque))
    if me_rms <= INTERPOLATED * torque_span and el_rms <= INTERPOLATED * float(np.mean(volts)):
        out.append(f"the rows lie on straight lines (torque residual {me_rms:.2g} N·m, voltage residual "
                   f"{el_rms:.2g} V): the curve was drawn between its measured free and stall points, so the "
                   "standard errors reflect the file's rounding, not the measurement's uncertainty")
    elif el_rms > 0.02 * float(np.mean(volts)):
        out.append(f"V = R·I + K·ω misses the voltage by {el_rms:.3g} V RMS (over 2 %): the rows are not steady "
                   "states at the voltage given (a supply that sagged, a winding that heated along the curve?)")
    ratio = parameters["Kt_over_K"]
    if abs(ratio.value - 1) > RATIO_WARNING and abs(ratio.value - 1) > 2 * ratio.stderr:
        where = "below" if ratio.value < 1 else "above"
        cause = ("torque lost inside the motor at high current: brush contact drop, armature reaction, iron "
                 "losses — or a torque sensor reading low" if ratio.value < 1 else
                 "viscous friction makes the slope Kt + b·R/K, or the speed or torque is mis-scaled")
        out.append(f"Kt/K = {ratio.value:.3f}: the torque per amp is {100 * abs(ratio.value - 1):.0f} % {where} the "
                   f"back-EMF constant ({cause})")
    if not several:
        out.append(f"one voltage ({float(np.mean(volts)):.3g} V): the friction at free speed is measured, but not "
                   "how it splits into Coulomb (Tf) and viscous (b) parts — curves at other voltages would tell")
    return out


def _panels(current: np.ndarray, torque: np.ndarray, speed: np.ndarray, model_current: np.ndarray,
            model_torque: np.ndarray, parameters: dict[str, Estimate]) -> list[Panel]:
    """Current against speed with the back-EMF model; torque against current with its line."""
    order = np.argsort(speed)
    k, r = parameters["K"].value, parameters["R"].value
    kt = parameters["Kt"].value
    rpm = 30.0 / math.pi
    return [
        Panel(title="Current vs speed: V = R·I + K·ω", x_label="speed [rpm]", y_label="current [A]",
              data=Series(speed[order] * rpm, current[order], "curve rows", "data"),
              model=Series(speed[order] * rpm, model_current[order], f"model: K = {k:.4g} V·s/rad, R = {r:.4g} Ω",
                           "model")),
        Panel(title="Torque vs current", x_label="current [A]", y_label="torque [N·m]",
              data=Series(current[np.argsort(current)], torque[np.argsort(current)], "curve rows", "data"),
              model=Series(current[np.argsort(current)], model_torque[np.argsort(current)],
                           f"fit: Kt = {kt:.4g} N·m/A", "model")),
    ]


def _details(current: np.ndarray, torque: np.ndarray, speed: np.ndarray, volts: np.ndarray,
             electrical: LeastSquares, several: bool) -> dict[str, object]:
    """The curve's ends as measured (free speed, stall torque and current) and the voltage."""
    free, stall = int(np.argmax(speed)), int(np.argmin(speed))
    power = torque * speed
    return {
        "voltage_V": float(np.mean(volts)), "several_voltages": several,
        "free_speed_rad_per_s": float(speed[free]), "free_speed_rpm": float(speed[free] * 30 / math.pi),
        "free_current_row_A": float(current[free]),
        "stall_torque_Nm": float(torque[stall]), "stall_current_A": float(current[stall]),
        "peak_output_power_W": float(np.max(power)),
        "voltage_residual_rms_V": float(np.sqrt(np.mean(electrical.residuals**2))),
        "shafts": "motor shaft (a bare motor on the dynamometer)",
    }
