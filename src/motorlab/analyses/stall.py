"""Locked-rotor (stall) runs: K, R at 25 °C and the thermal network of the winding, with standard errors.

A supply holds a voltage on the stalled motor for up to minutes while the winding heats (VEX's
dynamometer runs, seed 1's lever-arm readings at 1, 10, 20 and 29 s, MIT 2.010's torque-constant test).
The current falls as the copper warms (+0.393 %/K): i = V/R(T_w). One run or several (voltages) are
fitted together (:mod:`motorlab.analyses._stall_fit`), each from its own initial temperature; a run
that stops being a healthy stall is cut where it does (:mod:`motorlab.analyses._stall_cuts`), with a
warning naming the file, the time, the likely cause and the winding temperature then. Torque, when
measured, gives K = τ/i (the magnets' coefficient applied at the case temperature).
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from motorlab.analyses._stall_cuts import NO_CURRENT, Cut, find_cut, first_full_sample, set_point
from motorlab.analyses._stall_fit import (
    PRIOR_WINDING_LOG_SIGMA,
    PRIOR_WINDING_TIME_CONSTANT,
    REFERENCE_SAMPLES,
    SHARED,
    HeatFit,
    StallData,
    TorqueFit,
    current_dependence,
    fit_heating,
    fit_torque,
    simulate_runs,
)
from motorlab.analyses._stall_report import answers, make_panels, parameters_of, run_rows
from motorlab.analyses.common import reader_warnings, sources_of
from motorlab.errors import FitError, LogFormatError, MotorlabError, OptionError
from motorlab.estimation.decimate import consecutive
from motorlab.recording import Recording
from motorlab.results import FitResult
from motorlab.thermal.network import MAGNET_COEFFICIENTS, WINDING_LIMIT, ThermalModel

#: Fewest healthy samples a run needs to enter the fit.
MIN_SAMPLES = 5
#: Most samples a run is analysed at: a denser log is reduced to medians of consecutive samples (a
#: winding heats over seconds; VEX's 300 s runs hold ~850 samples).
MAX_SAMPLES = 5000
#: A run fits this much worse than the others (relative RMS, and at least :data:`UNEXPLAINED_RMS`):
#: heating does not explain it.
UNEXPLAINED_FACTOR = 4.0
UNEXPLAINED_RMS = 0.03
#: The winding's thermal time constant R_wc·C_w below which a fitted network is no armature's [s]: the
#: copper and iron of a real one reach the case in 6–60 s (VEX's BAG, mini-CIM and AndyMark 9015 runs),
#: a 550-size FTC motor's estimate is 18 s. A fit that needs less is chasing a rise heat cannot make.
MIN_WINDING_TIME_CONSTANT = 2.0


@dataclass
class Run:
    """One file: its samples, where its healthy part starts and ends, and why it ends."""

    source: str
    time: np.ndarray
    current: np.ndarray
    voltage: np.ndarray
    torque: np.ndarray | None
    start: int
    end: int
    set_point: float
    cut: Cut
    on: int = 0  # the row the supply switched on at (rows logged before it carry no current)
    group: int = 1  # consecutive samples of the file reduced to each of these (their median)

    @property
    def switch_on(self) -> float:
        """The file's time of the row the supply switched on at [s]."""
        return float(self.time[self.on])

    def data(self) -> StallData:
        """The healthy part, its time counted from the supply switching on (the run's first row with current)."""
        sl = slice(self.start, self.end)
        return StallData(self.source, self.time[sl] - self.switch_on, self.voltage[sl], self.current[sl],
                         None if self.torque is None else self.torque[sl], self.switch_on)


def _run_of(rec: Recording, voltage: float | None, until: float | None) -> Run:
    """The run of one recording, refused in one line when it cannot be a stall run."""
    source = rec.source or "the recording"
    if "current" not in rec:
        raise LogFormatError("this file has no current column: a locked-rotor run needs the winding current "
                             "(an export that logs torque only cannot give R or the heating)", path=rec.source or None)
    t, i = np.asarray(rec.time, dtype=float), np.abs(np.asarray(rec["current"], dtype=float))
    if t.size < 3:
        raise LogFormatError(f"only {t.size} samples: a stall run needs a time series", path=rec.source or None)
    if not np.any(i > 0):
        torque_only = "torque" in rec and np.any(np.asarray(rec["torque"]) != 0) and (
            "voltage" not in rec or not np.any(np.asarray(rec["voltage"]) != 0))
        raise LogFormatError("the current is 0 A in every row" + (
            ", and the voltage too, while the torque is not: this export logs torque only, and a locked-rotor run "
            "needs the winding current" if torque_only else
            ": no current flowed in this run (supply off, or the wrong column?)"), path=rec.source or None)
    if "voltage" in rec:
        v = np.asarray(rec["voltage"], dtype=float)
    elif voltage is not None:
        v = np.full(t.size, float(voltage))
    else:
        raise OptionError(f"{source}: no voltage column: give the supply's voltage (--voltage)")
    q = np.abs(np.asarray(rec["torque"], dtype=float)) if "torque" in rec else None
    group = math.ceil(t.size / MAX_SAMPLES)
    if group > 1:
        # Medians, not means: a group that straddles a cut or a glitch takes one side, never a half-cut sample.
        t, i, v = (consecutive(x, group) for x in (t, i, v))
        q = None if q is None else consecutive(q, group)
    start = first_full_sample(i)
    v_set = set_point(v) if voltage is None else float(voltage)
    cut = find_cut(t, i, v, q, start, v_set)
    end = t.size if cut.index is None else cut.index
    if until is not None:
        end = min(end, int(np.searchsorted(t, until, side="right")))
    on = int(np.flatnonzero(i > NO_CURRENT * float(np.max(i)))[0])
    return Run(source, t, i, v, q, start, end, v_set, cut, on, group)



def _runs_of(recs: list[Recording], voltage: float | None, until: float | None,
             warnings: list[str]) -> tuple[list[Run], list[Recording]]:
    """The runs of the recordings; among several, a file without current (an export of torque only) is left
    out and named, and refused only when no file is left.

    Raises
    ------
    LogFormatError
        A lone file without current, or every file without.
    """
    runs, kept = [], []
    refused: list[LogFormatError | OptionError] = []
    for rec in recs:
        try:
            runs.append(_run_of(rec, voltage, until))
            kept.append(rec)
            if runs[-1].group > 1:
                warnings.append(f"{runs[-1].source}: {len(rec.time):,} samples analysed as {runs[-1].time.size:,} "
                                f"medians of {runs[-1].group} consecutive samples (a winding heats over seconds)")
        except LogFormatError as exc:
            if len(recs) == 1 or "current" not in exc.message:
                raise
            refused.append(exc)
        except OptionError as exc:  # no voltage column (a peak-power export among the runs): named, left out
            if len(recs) == 1:
                raise
            refused.append(exc)
    if not runs:
        raise refused[0]
    warnings.extend(f"{exc}: left out" for exc in refused)
    return runs, kept


def stall(
    recordings: Recording | Sequence[Recording],
    *,
    voltage: float | None = None,
    magnet: str = "ferrite",
    magnet_coefficient: float | None = None,
    ambient: float = 25.0,
    until: float | None = None,
    answer_voltage: float = 12.0,
    limit: float = 150.0,
    rise: float = 100.0,
    back_emf: float | None = None,
    back_emf_stderr: float | None = None,
    network: ThermalModel | None = None,
    network_source: str = "",
) -> FitResult:
    """K, R₂₅ and the two-node thermal network from locked-rotor runs.

    Parameters
    ----------
    recordings
        One recording per run: ``time`` [s], ``current`` [A], ``voltage`` [V] (or ``voltage`` given),
        ``torque`` [N·m] when measured.
    voltage
        The supply's voltage [V] for runs without a voltage column (also taken as the set point).
    magnet, magnet_coefficient
        The magnets' material (``"ferrite"`` −0.2 %/K, ``"ndfeb"`` −0.12 %/K) or their coefficient on K [1/K].
    ambient
        Ambient temperature [°C]; the coolest run starts at it.
    until
        Fit only the samples up to this time of each file [s] (to test forecasts on the rest).
    answer_voltage, limit, rise
        The answers: how long a stall at ``answer_voltage`` [V] takes to bring the winding to ``limit``
        [°C], and the stall current held indefinitely for a ``rise`` [K] of the winding.
    back_emf, back_emf_stderr
        The motor's back-EMF constant and its standard error [V·s/rad] (its curve's or a spin-down's): no shaft's
        torque per amp exceeds it, so a torque model putting K above it beyond their uncertainty is refused.
    network, network_source
        A thermal network to hold (the fit of the motor's other runs, :func:`motorlab.thermal.forecast.load_fit`) and
        where it comes from, in words: only R₂₅ and the initial temperatures are fitted (a run no single network
        fits, forecast from the motor's other runs).

    Returns
    -------
    FitResult
        ``R`` (at 25 °C), ``R_wc``, ``R_ca``, ``C_w``, ``C_c``, ``K`` and ``tau0`` (with torque), the
        answers ``t_limit``, ``I_continuous``, ``R_hot``; ``details["runs"]`` has one row per file
        (set point, cut time and cause, initial temperature and the temperature at the cut).

    Raises
    ------
    LogFormatError
        A file without current, or whose current is 0 everywhere.
    FitError
        No run with enough healthy samples.
    """
    recs = [recordings] if isinstance(recordings, Recording) else list(recordings)
    if not recs:
        raise OptionError("no recording given")
    beta = _magnet(magnet, magnet_coefficient)
    if not (math.isfinite(ambient) and -40 <= ambient <= 80):
        raise OptionError(f"the ambient temperature must lie between −40 and 80 °C, got {ambient!r}")
    warnings = reader_warnings(recs)
    recs, from_curve = _curves(recs, warnings)
    if back_emf is None and from_curve is not None:
        back_emf, back_emf_stderr = from_curve
    runs, recs = _runs_of(recs, voltage, until, warnings)
    used = [k for k, r in enumerate(runs) if r.end - r.start >= MIN_SAMPLES]
    for k, r in enumerate(runs):
        if k not in used:
            warnings.append(f"{r.source}: only {max(r.end - r.start, 0)} healthy samples before the cut: left out")
    if not used:
        raise FitError("no run has a healthy stretch of at least 5 samples to fit")
    used = _same_shaft(runs, used, warnings)
    if network is not None:
        heat = fit_heating([runs[k].data() for k in used], magnet=beta, ambient=ambient, network=(
            network.winding_to_case, network.case_to_ambient, network.winding_capacity, network.case_capacity))
        excluded: list[int] = []
        unexplained = ""
        warnings.append(f"the thermal network is held at that of {network_source or 'another fit'} (the motor's other "
                        f"runs: R_wc·C_w = {network.winding_to_case * network.winding_capacity:.3g} s, R_ca·C_c = "
                        f"{network.case_to_ambient * network.case_capacity:.3g} s); only R at 25 °C and the runs' "
                        "initial temperatures are fitted to these runs")
    else:
        heat, excluded, unexplained = _fit_with_exclusions([runs[k] for k in used], beta, ambient, warnings)
    if not unexplained and network is None:
        heat = _drop_implausible_starts([runs[k].data() for k in used], heat, excluded, beta, ambient, warnings)
    data = [runs[k].data() for k in used]
    fitted = [j for j in range(len(used)) if j not in excluded]
    # The torque against the heating model's current, not the measured one: the model's is free of the
    # ammeter's noise, which would bias the slope low (errors in the regressor).
    smooth = [replace(data[j], current=heat.model_current[pos]) for pos, j in enumerate(fitted)]
    torque = _torque(smooth, heat, beta, _back_emf(back_emf, back_emf_stderr), warnings)
    result = _result(runs, used, fitted, heat, torque, warnings, recs,
                     {"beta": beta, "ambient": ambient, "answer_voltage": answer_voltage, "limit": limit,
                      "rise": rise, "until": until, "magnet": magnet if magnet_coefficient is None else "given",
                      "network_source": network_source})
    if unexplained:
        _mark_unexplained(result, unexplained)
    return result


def _mark_unexplained(result: FitResult, why: str) -> None:
    """Every run fitted is one heating does not explain: the network and the answers are not determined, and a
    forecast (``simulate stall``) refuses this fit (``details["unexplained"]``)."""
    result.details["unexplained"] = why
    for name in ("R_wc", "R_ca", "C_w", "C_c", "t_limit", "I_continuous"):
        est = result.parameters.get(name)
        if est is not None:
            result.parameters[name] = replace(est, determined=False,
                                              note=f"{est.note}: heating does not explain the run (see the warnings)")
    for row in result.details["runs"]:
        row["heating explains it"] = False
        row["winding at the cut (°C)"] = None
    # the temperatures of a network heating does not explain are not the winding's: not stated
    result.warnings[:] = [re.sub(r"; the winding was at about -?\d+ °C", "", w) for w in result.warnings]


#: Runs whose torque per amp differs from the others' by more than this factor measure another shaft (a
#: gearbox's output) or another motor: no winding's torque per amp moves that much with current or heat.
SHAFT_FACTOR = 2.0


def _same_shaft(runs: list[Run], used: list[int], warnings: list[str]) -> list[int]:
    """The runs fitted together: those whose torque per amp agrees (within :data:`SHAFT_FACTOR`) with the
    largest such group; the others are left out and named (fit them alone)."""
    ratio = {}
    for k in used:
        r = runs[k]
        if r.torque is not None:
            i = r.current[r.start:r.end]
            ok = i > 0
            if np.count_nonzero(ok) >= MIN_SAMPLES:
                ratio[k] = float(np.median(r.torque[r.start:r.end][ok] / i[ok]))
    if len(ratio) < 2 or all(v <= 0 for v in ratio.values()):
        return used
    groups = {k: [j for j in ratio if ratio[j] > 0 and 1 / SHAFT_FACTOR <= ratio[j] / ratio[k] <= SHAFT_FACTOR]
              for k in ratio if ratio[k] > 0}
    best = max(groups.values(), key=lambda g: (len(g), -min(g)))
    others = float(np.median([ratio[j] for j in best]))
    out = []
    for k in used:
        if k in ratio and k not in best:
            warnings.append(f"{runs[k].source}: left out: its torque per amp, {ratio[k]:.4g} N·m/A, is "
                            f"{ratio[k] / others:.3g} times the other runs' {others:.4g}: another shaft (a gearbox's "
                            "output?) or another motor; analyse it alone")
        else:
            out.append(k)
    return out


def _curves(recs: list[Recording], warnings: list[str]) -> tuple[list[Recording], tuple[float, float] | None]:
    """The recordings that are runs, and the back-EMF constant (value, standard error) [V·s/rad] of a motor curve
    among them (a file with a speed column, fitted by :func:`motorlab.analyses.curve.curve`), named in
    ``warnings``. A curve that cannot be fitted is named and left out.

    Raises
    ------
    FitError
        Every file is a curve: no locked-rotor run.
    """
    from motorlab.analyses.curve import curve

    runs, bound = [], None
    for rec in recs:
        if "speed" not in rec:
            runs.append(rec)
            continue
        name = str(rec.source or "a curve").replace("\\", "/").rsplit("/", 1)[-1]
        try:
            ke = curve(rec)["K"]
        except MotorlabError as exc:
            warnings.append(f"{name}: a motor curve (it has a speed column) that cannot be fitted ({exc}): left out")
            continue
        if not (ke.determined and math.isfinite(ke.value) and ke.value > 0):
            warnings.append(f"{name}: a motor curve whose back-EMF constant is not determined: left out")
            continue
        se = float(ke.stderr) if math.isfinite(ke.stderr) else 0.0
        if bound is None or ke.value < bound[0]:
            bound = (float(ke.value), se)
        warnings.append(f"{name}: a motor curve, not a locked-rotor run: its back-EMF constant K = {ke.value:.4g} ± "
                        f"{se:.1g} V·s/rad bounds the stall K (no shaft's torque per amp exceeds it)")
    if not runs:
        raise FitError("every file is a motor curve: give the locked-rotor runs (time, current, voltage, torque) too")
    return runs, bound


def _back_emf(value: float | None, stderr: float | None) -> tuple[float, float] | None:
    """The back-EMF bound (value, standard error) [V·s/rad], refused in one line when not a positive number."""
    if value is None:
        return None
    if not (math.isfinite(value) and value > 0):
        raise OptionError(f"the back-EMF constant must be a positive number of V·s/rad, got {value!r}")
    se = 0.0 if stderr is None else float(stderr)
    if not (math.isfinite(se) and se >= 0):
        raise OptionError(f"the back-EMF constant's standard error must be 0 or more, got {stderr!r}")
    return float(value), se


def _torque(smooth: list[StallData], heat: HeatFit, beta: float, bound: tuple[float, float] | None,
            warnings: list[str]) -> TorqueFit | None:
    """K (and τ₀ when the data select it) from the runs' torque against the heating model's current, with the
    standard errors of the heating model's case temperatures and the between-run scatter; the words that go
    with it appended to ``warnings``."""
    torque = fit_torque(smooth, heat.case, beta, back_emf=bound)
    if torque is None:
        return None
    if torque.form == "offset":
        torque = _offset_uncertainty(torque, smooth, heat)
        z = abs(torque.tau0) / torque.tau0_stderr
        if len(torque.per_run) == 2:
            if not z > 3:
                torque = fit_torque(smooth, heat.case, beta, offset=False, back_emf=bound) or torque
            torque.selection = (f"form chosen by the offset's z (two runs; the held-out test needs three): τ₀ = "
                                f"{torque.tau0 if torque.form == 'offset' else 0.0:.3g}, {z:.1f} standard errors of "
                                "the torque and the heating model" + ("" if z > 3 else ": under 3, no offset"))
    if torque.beta:
        torque = _with_case_uncertainty(torque, smooth, heat)
    if torque.warning:
        warnings.append(torque.warning)
    note = current_dependence(torque)
    if note:
        warnings.append(note)
    if bound is not None and torque.K > bound[0]:
        warnings.append(f"K = {torque.K:.4g} ± {torque.K_stderr:.2g} N·m/A is {100 * (torque.K / bound[0] - 1):.1f} % "
                        f"above the motor's back-EMF constant {bound[0]:.4g} V·s/rad, which no shaft's torque per amp "
                        "exceeds: the torque channel reads high (an offset or its scale)")
    return torque


def _offset_uncertainty(torque: TorqueFit, data: list[StallData], heat: HeatFit) -> TorqueFit:
    """τ₀'s standard error with the uncertainty of the heating model it is fitted against (the model's current
    and case temperature, from the heating fit's whole covariance by the delta method). Two runs determine τ₀
    through the contrast of their currents, which a relative error of 0.2 % between the runs' model currents,
    or 1 K in a case temperature, moves as much as the torque's own scatter does."""
    x = np.asarray(heat.fit.values, dtype=float)
    free = [j for j in range(len(heat.initial)) if j != heat.reference]
    ambient = heat.thermal.ambient_temperature
    grad = np.zeros(x.size)
    for k in range(x.size):
        step = 1e-3 if k < len(SHARED) else 0.1
        moved = x.copy()
        moved[k] += step
        initial = list(heat.initial)
        for pos, j in enumerate(free):
            initial[j] = float(moved[len(SHARED) + pos])
        sims = simulate_runs(np.exp(moved[: len(SHARED)]), initial, data, torque.beta, ambient)
        runs = [replace(d, current=s[0]) for d, s in zip(data, sims, strict=True)]
        refit = fit_torque(runs, [s[2] for s in sims], torque.magnet, offset=True, beta=torque.beta)
        grad[k] = ((refit.tau0 if refit is not None else torque.tau0) - torque.tau0) / step
    extra = float(grad @ np.nan_to_num(heat.fit.covariance) @ grad)
    torque.tau0_stderr = math.sqrt(torque.tau0_stderr**2 + max(extra, 0.0))
    return torque


def _with_case_uncertainty(torque: TorqueFit, data: list[StallData], heat: HeatFit) -> TorqueFit:
    """K's standard error with the uncertainty of the case temperatures it is corrected to (the network's
    covariance, by the delta method on the logarithms of the shared parameters)."""
    base = [heat.values[n] for n in SHARED]
    grad = np.zeros(len(SHARED))
    for k in range(len(SHARED)):
        shared = list(base)
        shared[k] *= math.exp(1e-3)
        sims = simulate_runs(shared, heat.initial, data, torque.beta, heat.thermal.ambient_temperature)
        moved = fit_torque(data, [s[2] for s in sims], torque.magnet, offset=torque.form == "offset",
                           beta=torque.beta)
        grad[k] = ((moved.K if moved is not None else torque.K) - torque.K) / 1e-3
    extra = float(grad @ np.nan_to_num(heat.log_covariance) @ grad)
    torque.K_stderr = math.sqrt(torque.K_stderr**2 + max(extra, 0.0))
    return torque


def _magnet(magnet: str, coefficient: float | None) -> float:
    if coefficient is not None:
        if not (math.isfinite(coefficient) and -0.01 < coefficient <= 0.001):
            raise OptionError(f"the magnets' coefficient must lie between −0.01 and 0.001 /K, got {coefficient!r}")
        return float(coefficient)
    if magnet not in MAGNET_COEFFICIENTS:
        raise OptionError(f"unknown magnet material {magnet!r}; known: {', '.join(MAGNET_COEFFICIENTS)}")
    return MAGNET_COEFFICIENTS[magnet]


def _fit_with_exclusions(runs: list[Run], beta: float, ambient: float,
                         warnings: list[str]) -> tuple[HeatFit, list[int], str]:
    """The heating fit, leaving out (and naming) a run that heating does not explain: with ≥ 3 runs the one
    that fits far worse than the others; with one or two, a run the fit misses by more than
    :data:`UNEXPLAINED_RMS`, or a network whose winding time constant is no armature's. The third value is
    the warning when no run is left that heating explains (a lone run), else ""."""
    data = [r.data() for r in runs]
    heat = fit_heating(data, magnet=beta, ambient=ambient)
    excluded: list[int] = []
    if len(data) < 3:
        tau_w = heat.values["R_wc"] * heat.values["C_w"]
        failing = [j for j, rms in enumerate(heat.run_rms)
                   if rms > UNEXPLAINED_RMS or (tau_w < MIN_WINDING_TIME_CONSTANT and data[j].time.size >= 30)]
        if (len(data) == 1 and data[0].time.size >= 30 and tau_w > heat.values["R_ca"] * heat.values["C_c"]
                and heat.run_rms[0] <= UNEXPLAINED_RMS):
            # a winding slower than its case: no motor's network. The run is forecast from the population's winding
            # (or, given, the motor's other runs' network) instead; said, with the run's figures.
            slow = _slow_start(data[0], heat)
            if slow:
                heat = fit_heating(data, magnet=beta, ambient=ambient, winding_prior=True)
                heat.winding_from_prior = True
                warnings.append(f"{data[0].source}: no single thermal network fits this run: {slow}")
                return heat, excluded, ""
        if len(failing) == len(data):  # nothing to compare with: say so, and what the run's own heat allows
            text = " ".join(_lone_unexplained(data[j], heat, j) for j in failing)
            warnings.append(text)
            return heat, excluded, text
        if failing:
            keep = [j for j in range(len(data)) if j not in failing]
            excluded.extend(failing)
            heat = fit_heating([data[j] for j in keep], magnet=beta, ambient=ambient)
            warnings.extend(_unexplained(data[j], heat) for j in failing)
        return heat, excluded, ""
    if len(data) >= 3:
        rms = np.array(heat.run_rms)
        bad = int(np.argmax(rms))
        others = np.delete(rms, bad)
        if rms[bad] > max(UNEXPLAINED_FACTOR * float(np.median(others)), UNEXPLAINED_RMS):
            excluded.append(bad)
            keep = [j for j in range(len(data)) if j != bad]
            heat = fit_heating([data[j] for j in keep], magnet=beta, ambient=ambient)
            warnings.append(_unexplained(data[bad], heat))
    return heat, excluded, ""


def _drop_implausible_starts(data: list[StallData], heat: HeatFit, excluded: list[int], beta: float, ambient: float,
                             warnings: list[str]) -> HeatFit:
    """Leave out (adding to ``excluded``, and naming) a run of at least 30 samples that heating explains only
    by a start at or above the winding's limit, 150 °C: a test does not start a motor that hot; its higher
    resistance is another winding or brush contact. The hottest such run first, refitting after each."""
    while True:
        keep = [j for j in range(len(data)) if j not in excluded]
        hot = [(heat.initial[pos], j) for pos, j in enumerate(keep)
               if heat.initial[pos] >= WINDING_LIMIT and data[j].time.size >= REFERENCE_SAMPLES]
        if not hot or len(keep) < 3:
            return heat
        start, j = max(hot)
        ref = data[keep[heat.reference]]
        r0, r_ref = float(data[j].voltage[0] / data[j].current[0]), float(ref.voltage[0] / ref.current[0])
        excluded.append(j)
        heat = fit_heating([data[k] for k in keep if k != j], magnet=beta, ambient=ambient)
        warnings.append(f"{data[j].source}: left out: heating explains this run only if its winding started at "
                        f"{start:.0f} °C (its resistance at the start, {r0:.3g} Ω, is {100 * (r0 / r_ref - 1):.0f} % "
                        f"above the coolest run's {r_ref:.3g} Ω); a test does not start a motor that hot: another "
                        "winding, or brush contact, not heat")


def _slow_start(run: StallData, heat: HeatFit) -> str:
    """Why a network with a winding slower (R_wc·C_w) than its case (R_ca·C_c) is no motor's, in the run's figures:
    R's rise in its first seconds and later, against what heat from rest does. The winding is the inner node,
    the fast one: in every healthy run of VEX's nine motors its time constant is 3–114 s against the case's
    49–660 s, and the heat of a held stall warms it fastest at the start. A fit that needs a slower winding is
    chasing a resistance that rises slowly at first and faster later ("" when the run is too short to say)."""
    r_meas = run.voltage / run.current
    t = run.time - run.time[0]
    at = [int(np.searchsorted(t, x)) for x in (5.0, 60.0)]
    if at[1] >= t.size - 1:
        return ""
    r0, r5, r60 = (float(np.median(r_meas[max(k - 1, 0): k + 2])) for k in (0, *at))
    p0 = float(np.median((run.voltage * run.current)[:3]))
    tau_w = heat.values["R_wc"] * heat.values["C_w"]
    tau_c = heat.values["R_ca"] * heat.values["C_c"]
    return (f"its resistance moved {100 * (r5 / r0 - 1):+.1f} % in its first {t[at[0]]:.0f} s on {p0:.3g} W, "
            f"then rose {100 * (r60 / r5 - 1):.0f} % by {t[at[1]]:.0f} s: slow at first and faster later, which "
            "heat does not do (a held stall warms a winding fastest at its start); the best heating model needs a "
            f"winding slower to reach its case (R_wc·C_w = {tau_w:.0f} s) than the case is to reach the air "
            f"(R_ca·C_c = {tau_c:.0f} s), a network no motor has (VEX's healthy runs: 3–114 s against 49–660 s); "
            "likely cause: brush contact (the brushes' contact resistance falling as they warm and bed in hides "
            "the copper's rise at first), not heat. Its network is the population's winding instead (R_wc·C_w held "
            f"near {PRIOR_WINDING_TIME_CONSTANT:.0f} s, a factor {math.exp(PRIOR_WINDING_LOG_SIGMA):.1f} either way; "
            "its forecast says so); for a better forecast, fit the motor's other runs and give that fit as the "
            "network (--network FIT.json): their network with this run's R")


def _lone_unexplained(run: StallData, heat: HeatFit, pos: int) -> str:
    """The warning for a run that heating does not explain, from its own figures: the rise of R against the
    energy put in, the heating fit's miss and the winding its best network would need."""
    tau_w = heat.values["R_wc"] * heat.values["C_w"]
    slow = _slow_start(run, heat) if tau_w > heat.values["R_ca"] * heat.values["C_c"] else ""
    if slow:
        return f"{run.source}: heating does not explain this run: {slow}"
    r_meas = run.voltage / run.current
    n = max(3, run.time.size // 20)
    r0, r1 = float(np.median(r_meas[:n])), float(np.median(r_meas[-n:]))
    power = run.voltage * run.current
    p0, p1 = float(np.median(power[:n])), float(np.median(power[-n:]))
    energy = float(np.trapezoid(power, run.time))
    rise = (r1 / r0 - 1) / heat.thermal.resistance_coefficient
    i0 = float(np.median(run.current[:n]))
    return (f"{run.source}: heating does not explain this run: its resistance rose {100 * (r1 / r0 - 1):.0f} % "
            f"({r0:.3g} -> {r1:.3g} Ω, {rise:.0f} K if it were the copper warming) on {p0:.3g} W falling to "
            f"{p1:.3g} W ({energy / 1e3:.3g} kJ in {float(run.time[-1]):.0f} s); the best heating model misses the "
            f"current by {100 * heat.run_rms[pos]:.1f} % "
            f"RMS (a healthy run: under 2 %) and needs a winding of {heat.values['C_w']:.2g} J/K that reaches its case "
            f"in {tau_w:.2g} s (real armatures: 10–100 J/K, 6–60 s); likely cause: brush contact (at {i0:.3g} A, a low "
            "current for this winding, the contact resistance of brushes on the commutator grows), not heat. No "
            "thermal network from it, and no forecast")


def _unexplained(run: StallData, heat: HeatFit) -> str:
    """The warning for a run whose resistance rises far more (or less) than its heat allows."""
    r_meas = run.voltage / run.current
    n = max(3, run.time.size // 20)
    r0, r1 = float(np.median(r_meas[:n])), float(np.median(r_meas[-n:]))
    power = float(np.mean(run.voltage * run.current))
    shared = [heat.values[name] for name in SHARED]
    t0 = heat.thermal.ambient_temperature + (r0 / shared[0] - 1) / heat.thermal.resistance_coefficient
    sim = simulate_runs(shared, [t0], [run], heat.thermal.magnet_coefficient, heat.thermal.ambient_temperature)[0]
    r_model = run.voltage / sim[0]
    allowed = float(r_model[-1] / r_model[0] - 1)
    return (f"{run.source}: heating does not explain this run: its resistance rose {100 * (r1 / r0 - 1):.0f} % "
            f"({r0:.3g} -> {r1:.3g} Ω) on {power:.3g} W, where the thermal network of the other runs allows "
            f"{100 * allowed:.0f} %; likely cause: brush contact (the contact resistance of brushes on the "
            "commutator grows at low current), not heat. Left out of the fit; no forecast for it")


#: The last seconds of a fitted stretch whose resistance, against the heating model's, gives the brushes'
#: contact a forecast carries on from [s].
CONTACT_WINDOW = 5.0


def _contact_at_end(run: StallData, model_current: np.ndarray, set_point: float) -> dict[str, float]:
    """The resistance the heating model does not account for at the end of a lone run's fitted stretch: the mean
    of V/i − V/i_model over its last :data:`CONTACT_WINDOW` s [Ω]. The brushes' contact moves in steps heat does
    not make (VEX's CIM at 8 V: +7.6 % between two samples at 115.8 s, where all of its 390 W allows 1.2 %) and
    stays; a forecast that continues the run (``simulate stall`` at its set point, from its start) holds it on
    from there."""
    m = run.time >= run.time[-1] - CONTACT_WINDOW
    extra = run.voltage[m] / run.current[m] - run.voltage[m] / model_current[m]
    return {"resistance_ohm": float(np.mean(extra)), "from_s": float(run.time[-1]), "voltage_V": float(set_point),
            "relative": float(np.mean(extra / (run.voltage[m] / model_current[m])))}


def _result(runs: list[Run], used: list[int], fitted: list[int], heat: HeatFit, torque: TorqueFit | None,
            warnings: list[str], recs: list[Recording], opts: dict[str, Any]) -> FitResult:
    """The FitResult: parameters, answers, run table, cut warnings, panels."""
    rows, cut_warnings = run_rows(runs, used, fitted, heat)
    warnings[:0] = cut_warnings
    params, extra = answers(heat, opts)
    warnings.extend(extra)
    parameters = parameters_of(heat, torque, params)
    data = [runs[used[j]].data() for j in fitted]
    resid = np.concatenate([(m - d.current) for m, d in zip(heat.model_current, data, strict=True)])
    hottest = float(max(float(np.max(w)) for w in heat.winding))
    details: dict[str, Any] = {
        "runs": rows,
        "R_temperature": "R is the winding's resistance at 25 °C (R(T) = R·(1 + 0.00393·(T − 25 °C)))",
        "thermal": heat.thermal.to_dict(),
        "initial_temperature_C": rows[0]["initial winding temperature (°C)"],
        "max_winding_temperature_C": hottest,
        "answers": {k: v for k, v in opts.items() if k in ("answer_voltage", "limit", "rise")},
        "until_s": opts["until"],
        "magnet": opts["magnet"],
        "shaft": "the stalled shaft where torque is measured (a bare motor: the motor shaft)",
        "network": ("held at " + (opts.get("network_source") or "another fit's") if heat.held else
                    "the population's winding (the run alone needs a winding slower than its case)"
                    if heat.winding_from_prior else "fitted to these runs"),
    }
    if torque is not None:
        details["K_runs"] = [{"file": runs[used[fitted[pos]]].source.replace("\\", "/").rsplit("/", 1)[-1],
                              "mean current (A)": r[0], "K (N·m/A)": r[1], "stderr (N·m/A)": r[2]}
                             for pos, r in enumerate(torque.per_run)] if len(torque.per_run) == len(fitted) else []
        details["K_model"] = {"form": torque.form, "beta_per_K": torque.beta, "magnet_bound_per_K": torque.magnet,
                              "between_run_sd": torque.between, "pooled_K": torque.pooled[0],
                              "selection": torque.selection, "refused": list(torque.refused)}
    if len(data) == 1:
        details["brush_contact"] = _contact_at_end(data[0], heat.model_current[0], runs[used[fitted[0]]].set_point)
    current = np.concatenate([d.current for d in data])
    return FitResult(
        experiment="stall",
        parameters=parameters,
        correlation=heat.fit.correlation[: len(SHARED), : len(SHARED)],
        correlation_names=list(SHARED),
        rmse=float(np.sqrt(np.mean(resid**2))),
        rmse_unit="A",
        r2=float(1 - np.sum(resid**2) / np.sum((current - current.mean()) ** 2)) if current.size > 1 else math.nan,
        n_points=int(current.size),
        panels=make_panels(runs, used, fitted, heat, torque),
        warnings=warnings,
        details=details,
        sources=sources_of(recs),
    )
