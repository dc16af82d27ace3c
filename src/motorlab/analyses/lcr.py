"""Winding resistance and inductance from LCR-meter readings (seed 1, "LCR Meter Experiment").

With the motor off its load, an LCR meter (DER EE DE-5000, Auto LCR mode at 1 kHz) reads the
inductance L and quality factor Q at several shaft positions, then the DC resistance (DCR mode) at
several positions. Each L/Q reading gives a series resistance R = 2π·f·L/Q; the analysis averages
R, L and R_dc, with standard errors of the mean, after setting aside brush-contact outliers found
by a robust test (median and median absolute deviation).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from motorlab.analyses import common
from motorlab.analyses.common import finite_rows, metadata_quantity, reader_warnings, sources_of
from motorlab.errors import FitError, LogFormatError, OptionError
from motorlab.recording import Recording
from motorlab.results import Estimate, FitResult, Panel, Series
from motorlab.units import SI_UNITS

#: Default test frequency of the DE-5000 in the seed's set-up [Hz].
DEFAULT_FREQUENCY = 1000.0
#: Modified z-score above which a reading is an outlier (Iglewicz & Hoaglin's 3.5).
OUTLIER_Z = 3.5
#: Smallest outlier threshold accepted. At 1, a third of normal readings are already set aside; it
#: also guarantees that at least half the readings (those within one MAD of the median) are kept.
MIN_OUTLIER_Z = 1.0
#: Test frequencies [Hz] refused outright: no LCR meter or impedance analyser measures L and Q
#: outside this range, so such a value is a wrong unit or a typo (and 2πfL/Q would overflow).
FREQUENCY_LIMITS = (1.0, 1e8)
#: Test frequencies [Hz] of common LCR meters (the seed's DE-5000: 100 Hz–100 kHz; bench meters
#: such as Keysight's E4980A: 20 Hz–2 MHz); outside it a warning asks to check the unit.
FREQUENCY_USUAL = (20.0, 2e6)


def robust_outliers(values: np.ndarray, *, threshold: float = OUTLIER_Z) -> np.ndarray:
    """Mask of outliers by the modified z-score 0.6745·|x − median|/MAD > ``threshold``.

    Parameters
    ----------
    values
        Readings (any unit).
    threshold
        Modified z-score limit [-]; 3.5 is the usual choice.

    Returns
    -------
    numpy.ndarray
        Boolean mask, True for outliers. Fewer than three readings are never flagged.

    Notes
    -----
    The median and the MAD are not dragged by the outliers themselves, unlike the mean and the
    standard deviation (one 3.65 Ω reading among ten of about 1.6 Ω moves the mean by 0.2 Ω and
    inflates the standard deviation so much that a 3-σ test keeps it). When more than half the
    readings are equal (display resolution), the MAD is zero and the mean absolute deviation
    (×1.2533) is used instead.

    References
    ----------
    B. Iglewicz and D. C. Hoaglin, *How to Detect and Handle Outliers*, ASQC, 1993.
    """
    x = np.asarray(values, dtype=float)
    if x.size < 3:
        return np.zeros(x.size, dtype=bool)
    med = float(np.median(x))
    dev = np.abs(x - med)
    mad = float(np.median(dev))
    if mad > 0:
        z = 0.6745 * dev / mad
    else:
        mean_ad = float(np.mean(dev))
        if mean_ad == 0:
            return np.zeros(x.size, dtype=bool)
        z = dev / (1.253314 * mean_ad)
    return z > threshold


def _mean_estimate(name: str, values: np.ndarray, unit: str, note: str) -> Estimate:
    n = values.size
    mean = float(np.mean(values))
    stderr = float(np.std(values, ddof=1) / math.sqrt(n)) if n > 1 else math.nan
    return Estimate(name, mean, stderr, unit, True, note)


def _frequency_of(recording: Recording, frequency: float | None) -> tuple[np.ndarray, str]:
    n = len(recording)
    if frequency is not None:
        return np.full(n, frequency), "option"
    low, high = FREQUENCY_LIMITS
    if "frequency" in recording:
        finite_rows(recording, ["frequency"])
        values = recording["frequency"]
        bad = np.flatnonzero((values < low) | (values > high))
        if bad.size:
            raise LogFormatError(
                f"test frequency {values[bad[0]]:g} Hz is outside {low:g} Hz–{high:g} Hz, where no LCR meter "
                "measures (a wrong unit?)", path=recording.source or None, line=recording.line_of(int(bad[0])),
            )
        return values, "column"
    meta = metadata_quantity(recording, ["frequency_Hz", "frequency"], "Hz")
    if meta is not None:
        if not low <= meta <= high:
            raise LogFormatError(
                f"the '# frequency_Hz:' line gives {meta:g} Hz, outside {low:g} Hz–{high:g} Hz, where no LCR "
                "meter measures (a wrong unit?)", path=recording.source or None,
            )
        return np.full(n, meta), "metadata"
    return np.full(n, DEFAULT_FREQUENCY), "default"


def check_frequency(frequency: float | None) -> None:
    """Raise :class:`OptionError` for a test frequency no LCR meter uses (see :data:`FREQUENCY_LIMITS`)."""
    if frequency is None:
        return
    low, high = FREQUENCY_LIMITS
    if not (math.isfinite(frequency) and frequency > 0):
        raise OptionError(f"the test frequency (--frequency) must be positive, got {frequency} Hz")
    if not low <= frequency <= high:
        raise OptionError(
            f"the test frequency (--frequency) {frequency:g} Hz is outside {low:g} Hz–{high:g} Hz, where no LCR "
            "meter measures (the seed's DE-5000 uses 100 Hz–100 kHz): a wrong unit?"
        )


def _only_one(what: str, recs: list[Recording], rows: list[np.ndarray]) -> LogFormatError:
    """The error for a single reading, naming the file(s) it came from (and its line, for one file)."""
    holders = [rec for rec, r in zip(recs, rows, strict=True) if r.size]
    path = " + ".join(rec.source for rec in holders if rec.source) or None
    line = holders[0].line_of(0) if len(holders) == 1 else None
    return LogFormatError(
        f"only one {what} reading: the seed takes ten, at different shaft positions (R and L vary with the "
        "commutator position, so one reading has no uncertainty)", path=path, line=line,
    )


@dataclass
class _Rows:
    """The readings of every file: L/Q with their test frequencies, and DC resistances."""

    l_rows: list[np.ndarray]
    q_rows: list[np.ndarray]
    f_rows: list[np.ndarray]
    dcr_rows: list[np.ndarray]
    freq_origin: set[str]
    circuit: str
    l_recs: list[Recording]
    dcr_recs: list[Recording]


@dataclass
class _Fit:
    """What the L/Q and the DC-resistance parts add to the result."""

    parameters: dict[str, Estimate] = field(default_factory=dict)
    details: dict[str, object] = field(default_factory=dict)
    panels: list[Panel] = field(default_factory=list)
    rmse: float = math.nan
    correlation: np.ndarray | None = None
    correlation_names: list[str] = field(default_factory=list)
    n_points: int = 0


def _collect(recs: list[Recording], frequency: float | None, circuit: str | None) -> _Rows:
    """Check every file's readings and gather them (frequency and circuit from options or metadata)."""
    l_rows: list[np.ndarray] = []
    q_rows: list[np.ndarray] = []
    f_rows: list[np.ndarray] = []
    dcr_rows: list[np.ndarray] = []
    freq_origin = set()
    circuits = set()
    l_recs: list[Recording] = []
    dcr_recs: list[Recording] = []
    for rec in recs:
        has_lq = rec.has("inductance", "quality_factor")
        has_dcr = "dc_resistance" in rec
        if not (has_lq or has_dcr):
            have = ", ".join(sorted(rec.signals)) or "none"
            raise LogFormatError(
                f"no LCR readings: expected L_uH and Q columns and/or DCR_ohm (this file has: {have})",
                path=rec.source or None,
            )
        if has_lq:
            finite_rows(rec, ["inductance", "quality_factor"])
            _positive(rec, "inductance")
            _positive(rec, "quality_factor")
            f, origin = _frequency_of(rec, frequency)
            freq_origin.add(origin)
            l_rows.append(rec["inductance"])
            q_rows.append(rec["quality_factor"])
            f_rows.append(f)
            l_recs.append(rec)
            circuits.add(_circuit_of(rec, circuit))
        if has_dcr:
            finite_rows(rec, ["dc_resistance"])
            _positive(rec, "dc_resistance")
            dcr_rows.append(rec["dc_resistance"])
            dcr_recs.append(rec)
    if len(circuits) > 1:
        raise OptionError("the files disagree on the meter's equivalent circuit (series/parallel): give --circuit")
    return _Rows(l_rows, q_rows, f_rows, dcr_rows, freq_origin, circuits.pop() if circuits else "series",
                 l_recs, dcr_recs)



def _fit_lq(rows: _Rows, threshold: float, fit: _Fit, warnings: list[str]) -> None:
    """R = 2πfL/Q (outliers excluded) and L from the L/Q readings, with their panels."""
    l_rows, q_rows, f_rows, l_recs = rows.l_rows, rows.q_rows, rows.f_rows, rows.l_recs
    circ, freq_origin, parameters, details = rows.circuit, rows.freq_origin, fit.parameters, fit.details
    inductance = np.concatenate(l_rows)
    q = np.concatenate(q_rows)
    f = np.concatenate(f_rows)
    if inductance.size < 2:
        raise _only_one("L/Q", l_recs, l_rows)
    if np.ptp(f) > 1e-6 * float(np.max(f)):
        # R = 2πfL/Q grows with f (eddy currents, skin effect): readings at several test frequencies
        # averaged together describe no frequency (a meter switched from 1 kHz to 10 kHz mid-run).
        found = ", ".join(_freq_text(np.array([v])) for v in np.unique(f))
        raise FitError(f"the L/Q readings were taken at several test frequencies ({found}): analyse each "
                       "frequency's readings on their own")
    low, high = FREQUENCY_USUAL
    if np.any((f < low) | (f > high)):
        warnings.append(
            f"test frequency {_freq_text(f)} is outside the {low:g} Hz–{high / 1e6:g} MHz of common LCR "
            "meters: check its unit"
        )
    if circ == "parallel":
        # Parallel Lp with Q = Rp/(ωLp) is the same impedance as Ls = Lp·Q²/(1+Q²) in series with Rs.
        inductance = inductance * q**2 / (1 + q**2)
    r_rows = 2 * math.pi * f * inductance / q
    r_out = robust_outliers(r_rows, threshold=threshold)
    kept = ~r_out
    parameters["R"] = _mean_estimate(
        "R", r_rows[kept], SI_UNITS["R"], f"2πfL/Q at {_freq_text(f)} (includes AC losses)"
    )
    l_note = "mean over shaft positions" + (" (series equivalent)" if circ == "parallel" else "")
    parameters["L"] = _mean_estimate("L", inductance, SI_UNITS["L"], l_note)
    r_mean = parameters["R"].value
    fit.rmse = float(np.sqrt(np.mean((r_rows[kept] - r_mean) ** 2)))
    fit.n_points += int(inductance.size)
    if int(np.count_nonzero(kept)) > 2 and np.ptp(r_rows[kept]) > 0 and np.ptp(inductance[kept]) > 0:
        c = float(np.corrcoef(r_rows[kept], inductance[kept])[0, 1])
        fit.correlation = np.array([[1.0, c], [c, 1.0]])
        fit.correlation_names = ["R", "L"]
    if np.any(r_out):
        warnings.append(
            f"{int(np.count_nonzero(r_out))} of {r_rows.size} L/Q readings give an outlying R "
            f"({', '.join(f'{v:.3g} Ω' for v in r_rows[r_out])}; median {np.median(r_rows):.3g} Ω): "
            "excluded from R (poor probe or brush contact?)"
        )
    details["frequency_Hz"] = float(f[0]) if np.ptp(f) == 0 else [float(v) for v in f]
    details["frequency_from"] = "+".join(sorted(freq_origin))
    details["circuit"] = circ
    details["L_min"] = float(np.min(inductance))
    details["L_max"] = float(np.max(inductance))
    details["L_relative_spread"] = float(np.std(inductance, ddof=1) / np.mean(inductance))
    details["lq_readings"] = common.listed_rows(
        inductance.size,
        lambda k: {"reading": k + 1, "L_H": float(inductance[k]), "Q": float(q[k]), "R_ohm": float(r_rows[k]),
                   "outlier": bool(r_out[k])},
    )
    x = np.arange(1, r_rows.size + 1, dtype=float)
    extra = []
    if np.any(r_out):
        extra.append(Series(x[r_out], r_rows[r_out], "outlier (excluded)", "data"))
    fit.panels.append(
        Panel(
            title="Series resistance 2πfL/Q per reading",
            x_label="reading (shaft position) [-]",
            y_label="R [Ω]",
            data=Series(x[kept], r_rows[kept], "2πfL/Q", "data"),
            model=Series(x[kept], np.full(x[kept].size, r_mean), f"mean R = {r_mean:.4g} Ω", "model"),
            extra=extra,
        )
    )
    mean_uh = 1e6 * parameters["L"].value
    fit.panels.append(
        Panel(
            title="Inductance per reading (varies with the commutator position)",
            x_label="reading (shaft position) [-]",
            y_label="L [µH]",
            data=Series(x, 1e6 * inductance, "L", "data"),
            model=Series(x, np.full(x.size, mean_uh), f"mean L = {mean_uh:.4g} µH", "model"),
        )
    )


def _fit_dcr(rows: _Rows, threshold: float, fit: _Fit, warnings: list[str]) -> None:
    """R_dc from the DC-resistance readings (outliers excluded), with its panel."""
    dcr_rows, dcr_recs, parameters, details = rows.dcr_rows, rows.dcr_recs, fit.parameters, fit.details
    dcr = np.concatenate(dcr_rows)
    if dcr.size < 2:
        raise _only_one("DC resistance", dcr_recs, dcr_rows)
    d_out = robust_outliers(dcr, threshold=threshold)
    d_kept = ~d_out
    parameters["R_dc"] = _mean_estimate(
        "R_dc", dcr[d_kept], SI_UNITS["R_dc"], "DC resistance (winding + brushes), outliers excluded"
    )
    fit.n_points += int(dcr.size)
    if np.any(d_out):
        warnings.append(
            f"{int(np.count_nonzero(d_out))} of {dcr.size} DC resistance readings are outliers "
            f"({', '.join(f'{v:.3g} Ω' for v in dcr[d_out])}; median {np.median(dcr):.3g} Ω): "
            "excluded from R_dc (poor brush contact at that shaft position?)"
        )
    details["dcr_readings"] = common.listed_rows(
        dcr.size, lambda k: {"reading": k + 1, "DCR_ohm": float(dcr[k]), "outlier": bool(d_out[k])}
    )
    x = np.arange(1, dcr.size + 1, dtype=float)
    rdc = parameters["R_dc"].value
    dc_panel = Panel(
        title="DC resistance per reading",
        x_label="reading (shaft position) [-]",
        y_label="R_dc [Ω]",
        data=Series(x[d_kept], dcr[d_kept], "DCR", "data"),
        model=Series(x[d_kept], np.full(x[d_kept].size, rdc), f"mean R_dc = {rdc:.4g} Ω", "model"),
        extra=[Series(x[d_out], dcr[d_out], "outlier (excluded)", "data")] if np.any(d_out) else [],
    )
    fit.panels.insert(1 if rows.l_rows else 0, dc_panel)
    if not rows.l_rows:
        fit.rmse = float(np.sqrt(np.mean((dcr[d_kept] - rdc) ** 2)))


def _compare_resistances(parameters: dict[str, Estimate], details: dict[str, object], warnings: list[str]) -> None:
    """Say how far the AC resistance 2πfL/Q is from the DC one, or that the DC one is missing."""
    f = details.get("frequency_Hz")
    at = f"at {_freq_text(np.array([f]))}" if isinstance(f, float) else "at the test frequency"
    if "R" in parameters and "R_dc" in parameters:
        ratio = parameters["R"].value / parameters["R_dc"].value
        details["R_over_R_dc"] = ratio
        warnings.append(
            f"R from 2πfL/Q ({parameters['R'].value:.3g} Ω) is {100 * (ratio - 1):+.0f} % from the DC "
            f"resistance R_dc ({parameters['R_dc'].value:.3g} Ω): the value {at} includes AC losses "
            "(eddy currents, commutation); use R_dc as the model's winding resistance R"
        )
    elif "R" in parameters:
        warnings.append(
            f"no DC resistance readings: R from 2πfL/Q {at} includes AC losses and overstates the DC "
            "winding resistance the motor model needs; add DCR readings"
        )


def lcr(
    recordings: Recording | Sequence[Recording],
    *,
    frequency: float | None = None,
    circuit: str | None = None,
    threshold: float = OUTLIER_Z,
) -> FitResult:
    """R, L and R_dc from LCR-meter readings at several shaft positions.

    Parameters
    ----------
    recordings
        One or more recordings with ``inductance`` [H] and ``quality_factor`` (columns ``L_uH`` /
        ``L_mH`` / ``L_H`` and ``Q``) and/or ``dc_resistance`` [Ω] (column ``DCR_ohm``). L/Q and
        DCR readings may come in the same rows or in separate files.
    frequency
        Test frequency of the L/Q readings [Hz]. Default: a ``frequency_Hz`` column, else the
        ``# frequency_Hz:`` metadata, else 1 kHz (the seed's setting).
    circuit
        ``"series"`` (default; the seed's R = 2πfL/Q) or ``"parallel"`` when the meter showed the
        parallel equivalent Lp: it is converted to the series Ls = Lp·Q²/(1 + Q²) first. Default:
        the ``# circuit:`` metadata, else series.
    threshold
        Modified z-score above which a reading is set aside as an outlier [-].

    Returns
    -------
    FitResult
        ``R`` [Ω] (mean of 2πfL/Q), ``L`` [H] (mean), ``R_dc`` [Ω] (mean DC resistance without
        outliers), each with the standard error of the mean; the per-reading table in
        ``details["readings"]``; panels of R and L per reading.

    Raises
    ------
    LogFormatError
        If no file holds L and Q nor DCR, or a reading is not finite or not positive.
    OptionError
        For an impossible circuit, or a frequency outside :data:`FREQUENCY_LIMITS` (1 Hz–100 MHz: no
        LCR meter measures there; a frequency outside 20 Hz–2 MHz is warned about).
    LogFormatError
        If only one L/Q (or DC resistance) reading is given (naming its file), or a frequency
        column or ``# frequency_Hz:`` line lies outside :data:`FREQUENCY_LIMITS`.

    Notes
    -----
    R = 2π·f·L/Q (seed 1, "Data Analysis" step 1) is the series resistance *at f*: besides the
    copper and brush resistance it includes eddy-current and iron losses and the commutator's
    contact behaviour at 1 kHz, so it exceeds the DC value (the seed's table: 2.5 Ω against
    1.7 Ω). The model's R (V = R·i + K·ω at DC) is the outlier-free ``R_dc``; both are reported.
    L changes with the commutator position (seed 1), so its mean over random positions is the
    average inductance and its spread is physical, not only noise.
    A reading with poor brush contact reads high (3.65 Ω among 1.4–1.8 Ω in the seed's table);
    readings with a modified z-score above 3.5 are excluded from R and R_dc and listed. The median
    and its absolute deviation withstand up to four poor contacts in ten readings; with five or
    more (about 3 % of units at the rig's 20 % chance per position) the estimate is off.

    References
    ----------
    Seed 1 (Characterizing FTC-Legal Motors), "LCR Meter Experiment".
    """
    recs = [recordings] if isinstance(recordings, Recording) else list(recordings)
    if not recs:
        raise OptionError("no recording given")
    check_frequency(frequency)
    if not (math.isfinite(threshold) and MIN_OUTLIER_Z <= threshold):
        raise OptionError(
            f"the outlier threshold (--outlier-z) must be a modified z-score of at least {MIN_OUTLIER_Z:g}, got "
            f"{threshold!r} (below it ordinary readings are set aside; {OUTLIER_Z} is the usual choice)"
        )
    warnings: list[str] = reader_warnings(recs)
    rows = _collect(recs, frequency, circuit)
    fit = _Fit()
    if rows.l_rows:
        _fit_lq(rows, threshold, fit, warnings)
    if rows.dcr_rows:
        _fit_dcr(rows, threshold, fit, warnings)
    parameters, details = fit.parameters, fit.details
    sources = sources_of(recs)
    _compare_resistances(parameters, details, warnings)
    return FitResult(
        experiment="lcr",
        parameters=parameters,
        correlation=fit.correlation,
        correlation_names=fit.correlation_names,
        rmse=fit.rmse,
        rmse_unit="ohm",
        r2=math.nan,
        n_points=fit.n_points,
        panels=fit.panels,
        warnings=warnings,
        details=details,
        sources=sources,
    )


def _positive(rec: Recording, name: str) -> None:
    values = rec[name]
    bad = np.flatnonzero(values <= 0)
    if bad.size:
        raise LogFormatError(
            f"{name} must be positive, got {values[bad[0]]:g}", path=rec.source or None,
            line=rec.line_of(int(bad[0])),
        )


def _circuit_of(rec: Recording, circuit: str | None) -> str:
    value = circuit if circuit is not None else str(rec.metadata.get("circuit", "series"))
    value = value.strip().lower()
    if value not in ("series", "parallel"):
        raise OptionError(f"the equivalent circuit must be 'series' or 'parallel', got {value!r}")
    return value


def _freq_text(f: np.ndarray) -> str:
    f0 = float(f[0])
    text = f"{f0 / 1000:g} kHz" if f0 >= 1000 else f"{f0:g} Hz"
    return text if np.ptp(f) == 0 else "the row frequencies"
