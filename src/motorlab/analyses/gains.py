"""Straight-line gains of seed 2: servo-amplifier gain Ka and tachometer gain Kt_tach.

Seed 2 (MIT 2.010 Lab 2, "Amplifier Gain Constant" and "The Tachometer Gain Constant") measures
each gain at one operating point; here several rows are fitted with a straight line *with an
intercept*, so that an offset (amplifier input offset, tachometer ripple rectification, a meter
zero error) does not bias the slope and is reported instead of hidden.

The small table helpers the bench analyses share (reading several files, refusing non-finite
rows, the straight-line fit) live in :mod:`motorlab.analyses.common`; they are re-exported here
for callers that imported them from this module.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from motorlab.analyses.common import (
    EXACT_LINE_WARNING,
    StraightLine,
    concatenate,
    finite_rows,
    fit_straight_line,
    metadata_quantity,
    read_tables,
    reader_warnings,
    sources_of,
)
from motorlab.recording import Recording
from motorlab.results import Estimate, FitResult, Panel, Series
from motorlab.units import SI_UNITS, format_unit

__all__ = [
    "StraightLine", "amplifier", "concatenate", "finite_rows", "fit_straight_line", "metadata_quantity",
    "read_tables", "sources_of", "tachometer",
]

#: A measured gain further than this fraction from the nominal one (and beyond 3 standard errors)
#: is reported in a warning.
NOMINAL_TOLERANCE = 0.10

#: One-line help per experiment this module serves (the CLI lists them).

# ---- the gains --------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _GainSpec:
    """What distinguishes the two straight-line gain experiments."""

    name: str  # parameter symbol
    intercept: str  # intercept symbol
    intercept_unit: str
    x_label: str
    y_label: str
    title: str
    seed: str


_SPECS = {
    "amplifier": _GainSpec(
        "Ka", "I0", "A", "amplifier input (command) [V]", "output current [A]",
        "Amplifier output current vs input voltage", 'seed 2, "Amplifier Gain Constant Ka"',
    ),
    "tachometer": _GainSpec(
        "Kt_tach", "V0", "V", "shaft speed [rad/s]", "tachometer voltage [V]",
        "Tachometer voltage vs shaft speed", 'seed 2, "The Tachometer Gain Constant"',
    ),
}


def _gain_result(
    experiment: str, x: np.ndarray, y: np.ndarray, *, nominal: float | None, sources: list[str],
    read_warnings: list[str],
) -> FitResult:
    spec = _SPECS[experiment]
    line = fit_straight_line(x, y, source=" + ".join(sources), what=spec.x_label.split(" [")[0],
                             response=spec.y_label.split(" [")[0])
    unit = SI_UNITS[spec.name]
    params = line.fit.estimates({"slope": unit, "intercept": spec.intercept_unit})
    slope, intercept = params["slope"], params["intercept"]
    estimates = {
        spec.name: Estimate(spec.name, slope.value, slope.stderr, unit, slope.determined, slope.note),
        spec.intercept: Estimate(
            spec.intercept, intercept.value, intercept.stderr, spec.intercept_unit, True,
            "intercept of the straight line (offset)",
        ),
    }
    warnings: list[str] = list(read_warnings)
    details: dict[str, object] = {"seed": spec.seed}
    if x.size == 2:
        warnings.append("only two rows: the line passes through both, so no uncertainty can be estimated")
    elif line.exact:
        warnings.append(EXACT_LINE_WARNING)
    if math.isfinite(intercept.stderr) and abs(intercept.value) > 3 * intercept.stderr:
        x_span = float(np.max(np.abs(x)))
        share = abs(intercept.value) / max(abs(slope.value) * x_span, 1e-300)
        if share > 0.02:
            warnings.append(
                f"the intercept {spec.intercept} = {intercept.value:.3g} {format_unit(spec.intercept_unit)} "
                f"is {100 * share:.1f} % of full scale and significant: check the meter zero / offset"
            )
    if nominal is not None:
        diff = slope.value - nominal
        details["nominal"] = nominal
        details["relative_difference_from_nominal"] = diff / nominal
        k = abs(diff) / slope.stderr if math.isfinite(slope.stderr) and slope.stderr > 0 else math.inf
        if abs(diff) > NOMINAL_TOLERANCE * abs(nominal) and k > 3:
            warnings.append(
                f"{spec.name} = {slope.value:.4g} {format_unit(unit)} differs from the nominal "
                f"{nominal:.4g} by {100 * diff / nominal:+.1f} % ({k:.1f} standard errors)"
            )
    residuals = y - line.model
    panel = Panel(
        title=spec.title,
        x_label=spec.x_label,
        y_label=spec.y_label,
        data=Series(x, y, "measured", "data"),
        model=Series(x, line.model, f"fit: {spec.name} = {slope.value:.4g} {format_unit(unit)}", "model"),
    )
    return FitResult(
        experiment=experiment,
        parameters=estimates,
        correlation=line.fit.correlation,
        correlation_names=[spec.name, spec.intercept],
        rmse=float(np.sqrt(np.mean(residuals**2))),
        rmse_unit=spec.y_label.rsplit("[", 1)[1].rstrip("]"),
        r2=line.r2,
        n_points=int(x.size),
        panels=[panel],
        warnings=warnings,
        details=details,
        sources=sources,
    )


def amplifier(
    recordings: Recording | Sequence[Recording], *, nominal: float | None = None
) -> FitResult:
    """Servo-amplifier gain Ka from rows of input voltage and output current.

    Parameters
    ----------
    recordings
        One or more recordings with ``command`` [V] (column ``command_V``) and ``current`` [A]
        (``current_A`` / ``current_mA``).
    nominal
        Nominal gain to compare with (seed 2: 2 A/V) [A/V]; a warning is given when the measured
        gain is more than 10 % and 3 standard errors away.

    Returns
    -------
    FitResult
        ``Ka`` [A/V] and the intercept ``I0`` [A], fit statistics and the data-vs-line panel.

    Raises
    ------
    LogFormatError
        If a column is missing or a row is not finite.
    FitError
        With fewer than two rows or a single input voltage.

    Notes
    -----
    The amplifier is a voltage-controlled current source, I_out = Ka·V_in (seed 2). The fit is
    I = Ka·V + I0 by ordinary least squares; I0 collects input offsets and meter zero errors.

    References
    ----------
    Seed 2 (MIT 2.010 Lab 2), "Amplifier Gain Constant Ka".
    """
    recs = _as_list(recordings)
    rec = concatenate(recs, ["command", "current"])
    return _gain_result("amplifier", rec["command"], rec["current"], nominal=nominal, sources=sources_of(recs),
                        read_warnings=reader_warnings(recs))


def tachometer(
    recordings: Recording | Sequence[Recording], *, nominal: float | None = None
) -> FitResult:
    """Tachometer gain Kt_tach from rows of optical-tachometer speed and tachometer voltage.

    Parameters
    ----------
    recordings
        One or more recordings with ``speed`` [rad/s] (columns ``speed_rpm`` or
        ``speed_rad_per_s``; ``velocity`` is accepted instead) and ``tach_voltage`` [V].
    nominal
        Nominal gain from the data sheet [V·s/rad]; a warning is given when the measured gain is
        more than 10 % and 3 standard errors away.

    Returns
    -------
    FitResult
        ``Kt_tach`` [V·s/rad] and the intercept ``V0`` [V].

    Raises
    ------
    LogFormatError
        If a column is missing or a row is not finite.
    FitError
        With fewer than two rows or a single speed.

    Notes
    -----
    v_t = Kt·Ω (seed 2); the fit is v_t = Kt_tach·Ω + V0.

    References
    ----------
    Seed 2 (MIT 2.010 Lab 2), "The Tachometer Gain Constant".
    """
    recs = _as_list(recordings)
    speed_name = "speed" if all("speed" in r for r in recs) else "velocity"
    rec = concatenate(recs, [speed_name, "tach_voltage"])
    return _gain_result(
        "tachometer", rec[speed_name], rec["tach_voltage"], nominal=nominal, sources=sources_of(recs),
        read_warnings=reader_warnings(recs),
    )


def _as_list(recordings: Recording | Sequence[Recording]) -> list[Recording]:
    return [recordings] if isinstance(recordings, Recording) else list(recordings)
