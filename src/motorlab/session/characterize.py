"""Run a whole session: every analysis the session has files for, per unit, and combine the sources.

:func:`characterize` takes a validated :class:`~motorlab.session.spec.Session` and returns a
:class:`Characterization`: per unit the fit of each experiment (or why it failed), the combined
motor parameters (J, b, Tf, K, R, L) with the source each one comes from, the disagreements
between sources, and the fleet statistics. :func:`motorlab.report.document.write_outputs` writes ``results.json``,
``results.csv`` (seed 1's "Final Calculated Parameters" table, one row per unit) and
``report.html``.

Combination
-----------
- Order: experiments that measure K run first (spin-down, torque, identification); the analyses
  that need K (terminal velocity, then free spin-up, which also takes b and Tf) receive the
  combined K *with its standard error*, which they propagate.
- "The more precise source wins": of the determined estimates of one parameter, the one with the
  smallest standard error is kept (not a weighted mean: sources may differ systematically, as
  the seed's Kt through a lossy gearbox and its Ke do, and a mean would hide that).
- Two sources a and b disagree when |a − b| > 3·sqrt(σa² + σb²); every disagreement is reported.
- Experiments run with the flywheel attached (:data:`~motorlab.session.spec.LOADED_EXPERIMENTS`)
  contribute only K: their J, b and Tf describe motor + gearbox + flywheel and are reported with
  the experiment, not as the motor's.
- The LCR meter's R = 2πfL/Q is an AC resistance; the model's R is its ``R_dc``.
- K is the back-EMF constant Ke (at the output shaft, = N·K_motor). A lever at the output (torque)
  and a torque balance through the gearbox (spin-up) measure Kt = η·Ke instead: they give K only
  when no back-EMF source (spin-down, identification) was run. With both a back-EMF K and a torque
  test, each unit gets the gearbox ``efficiency`` η = Kt/Ke ± σ and its ``loss_torque`` τ0
  (:data:`GEARBOX_PARAMETERS`; :mod:`motorlab.gearbox`), tested across the fleet like the others.
- One failing experiment or unit does not stop the others: every
  :class:`~motorlab.errors.MotorlabError` is caught per unit and experiment and its message kept.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from motorlab.errors import MotorlabError, OptionError
from motorlab.experiments import all_experiments
from motorlab.experiments import stderr_or_none as _stderr
from motorlab.io.headers import column_mapping
from motorlab.io.output import atomic_path
from motorlab.results import Estimate, FitResult, json_float, jsonable
from motorlab.session.efficiency import (  # noqa: F401 - re-exported: the session's gearbox figures
    BACK_EMF_SOURCES,
    EFFICIENCY_HEALTHY_SPREAD,
    GEARBOX_PARAMETERS,
    TORQUE_SOURCES,
    gearbox_estimates,
    motoring_friction,
    sources_of,
    spinup_warning,
)
from motorlab.session.fleet import DEFAULT_THRESHOLD, FleetSummary, fleet_summary
from motorlab.session.spec import LOADED_EXPERIMENTS, ExperimentSpec, Session, UnitSpec, read_truth
from motorlab.units import SI_UNITS

#: The motor parameters of the final table, in seed 1's column order (plus Tf).
PARAMETERS = ("J", "b", "Tf", "K", "R", "L")

#: Experiments in the order they run: sources of K first, then the analyses that take K
#: (the descriptions' ``order``, :mod:`motorlab.experiments`).
ORDER = tuple(all_experiments())

#: Result parameter -> motor parameter, per experiment (what each may contribute to the table).
CONTRIBUTIONS: dict[str, dict[str, str]] = {name: dict(exp.contributes) for name, exp in all_experiments().items()}

#: Which shaft, load and torque units each experiment's figures refer to (short, for tables).
SHAFTS: dict[str, str] = {name: exp.shaft for name, exp in all_experiments().items() if exp.shaft}

#: Two estimates disagree when they differ by more than this many combined standard errors.
DISAGREEMENT_SIGMAS = 3.0

Progress = Callable[[str, str], None]


@dataclass(frozen=True)
class Combined:
    """One motor parameter of one unit: the chosen estimate and every candidate."""

    estimate: Estimate
    source: str
    candidates: dict[str, Estimate] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        """JSON: the estimate (value, stderr, unit), its source and the other candidates."""
        out = self.estimate.to_dict()
        out["source"] = self.source
        if len(self.candidates) > 1:
            out["candidates"] = {k: v.to_dict() for k, v in self.candidates.items()}
        return out


@dataclass(frozen=True)
class Disagreement:
    """Two sources of one parameter that differ by more than :data:`DISAGREEMENT_SIGMAS`."""

    parameter: str
    first: str
    second: str
    first_estimate: Estimate
    second_estimate: Estimate

    @property
    def sigmas(self) -> float:
        """|a − b| / sqrt(σa² + σb²)."""
        a, b = self.first_estimate, self.second_estimate
        denom = math.hypot(_finite_or_zero(a.stderr), _finite_or_zero(b.stderr))
        return abs(a.value - b.value) / denom if denom > 0 else math.inf

    def message(self) -> str:
        """One line for people."""
        a, b = self.first_estimate, self.second_estimate
        return (
            f"{self.parameter}: {self.first} gives {a.value:.4g} ± {a.stderr:.2g}, {self.second} gives "
            f"{b.value:.4g} ± {b.stderr:.2g} ({self.sigmas:.1f} σ apart)"
        )


#: Motor parameters physics wants positive: a negative one in a unit's table carries its warning.
POSITIVE_PARAMETERS = frozenset({"J", "b", "Tf", "K", "R", "R_dc", "L", "Ka", "gamma"})


@dataclass
class UnitResult:
    """Everything measured on one unit."""

    spec: UnitSpec
    fits: dict[str, FitResult] = field(default_factory=dict)
    failures: dict[str, str] = field(default_factory=dict)
    parameters: dict[str, Combined] = field(default_factory=dict)
    disagreements: list[Disagreement] = field(default_factory=list)
    truth: dict[str, float] = field(default_factory=dict)

    @property
    def name(self) -> str:
        """The unit's key in the session."""
        return self.spec.name

    @property
    def status(self) -> str:
        """``"ok"``, or what failed (the row of the final table says why)."""
        if not self.failures:
            return "ok"
        return "; ".join(f"{exp} failed: {why}" for exp, why in self.failures.items())

    def estimates(self) -> dict[str, Estimate]:
        """The chosen estimate of each motor parameter."""
        return {name: c.estimate for name, c in self.parameters.items()}

    @property
    def warnings(self) -> list[str]:
        """What the analyses said of each chosen parameter that breaks physics (a negative b, R …).

        The unit's table takes each parameter from one analysis; when that value is negative, the
        warning its analysis gave comes with it (``"terminal: b is fitted negative …"``).
        """
        out: list[str] = []
        for name, c in self.parameters.items():
            if name not in POSITIVE_PARAMETERS or not c.estimate.value < 0:
                continue
            fit = self.fits.get(c.source)
            said = [w for w in (fit.warnings if fit is not None else []) if w.startswith(f"{name} ")]
            out += [f"{c.source}: {w}" for w in said] or [
                f"{c.source}: {name} = {c.estimate.value:.4g} is negative, which no motor has"]
        return list(dict.fromkeys(out))

    def to_dict(self) -> dict[str, Any]:
        """JSON of one unit: parameters, experiments, disagreements, failures, truth."""
        out: dict[str, Any] = {
            "label": self.spec.display_name,
            "status": self.status,
            "parameters": {name: c.to_dict() for name, c in self.parameters.items()},
            "experiments": {name: fit.to_dict() for name, fit in self.fits.items()},
            "failures": dict(self.failures),
            "warnings": self.warnings,
            "disagreements": [
                {
                    "parameter": d.parameter,
                    "sources": [d.first, d.second],
                    "sigmas": json_float(d.sigmas),
                    "message": d.message(),
                }
                for d in self.disagreements
            ],
        }
        if self.truth:
            out["truth"] = dict(self.truth)
        return out


@dataclass
class Characterization:
    """The outcome of :func:`characterize`."""

    session: Session
    units: dict[str, UnitResult]
    fleet: FleetSummary
    gains: dict[str, Any] | None = None
    notes: list[str] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        """The JSON document written as ``results.json`` (SI units)."""
        from motorlab import __version__

        s = self.session
        out: dict[str, Any] = {
            "motorlab_version": __version__,
            "session": {
                "path": str(s.path),
                "title": s.title,
                "date": s.date,
                "motor": {
                    "name": s.motor.name,
                    "catalog": s.motor.catalog,
                    "counts_per_revolution": s.motor.counts_per_revolution,
                    "gear_ratio": s.motor.gear_ratio,
                },
            },
            "units": {name: unit.to_dict() for name, unit in self.units.items()},
            "fleet": self.fleet.to_dict(),
            "notes": list(self.notes),
        }
        if self.gains is not None:
            out["gains"] = jsonable({k: v for k, v in self.gains.items() if k not in ("figure", "results")})
        return out


# ---------------------------------------------------------------------------------------------
# Combination
# ---------------------------------------------------------------------------------------------
def combine(name: str, candidates: Mapping[str, Estimate]) -> tuple[Combined | None, list[Disagreement]]:
    """Choose among several sources of one parameter and list their disagreements.

    Parameters
    ----------
    name
        Parameter symbol (``"K"``).
    candidates
        Source (experiment name) -> estimate, in SI.

    Returns
    -------
    combined, disagreements
        The estimate with the smallest standard error among the determined ones (None when there
        is no candidate at all; an undetermined estimate when no candidate is determined), and
        every pair of determined sources with |a − b| > 3·sqrt(σa² + σb²).
    """
    if not candidates:
        return None, []
    determined = {k: e for k, e in candidates.items() if e.determined and math.isfinite(e.value)}
    if not determined:
        source, est = next(iter(candidates.items()))
        return Combined(est, source, dict(candidates)), []

    def precision_key(item: tuple[str, Estimate]) -> float:
        se = item[1].stderr
        return se if math.isfinite(se) and se >= 0 else math.inf

    source, best = min(determined.items(), key=precision_key)
    chosen = Estimate(name, best.value, best.stderr, best.unit, True, f"from {source}")
    disagreements = []
    items = list(determined.items())
    for i in range(len(items)):
        for j in range(i + 1, len(items)):
            (sa, a), (sb, b) = items[i], items[j]
            denom = math.hypot(_finite_or_zero(a.stderr), _finite_or_zero(b.stderr))
            if abs(a.value - b.value) > DISAGREEMENT_SIGMAS * denom:
                disagreements.append(Disagreement(name, sa, sb, a, b))
    return Combined(chosen, source, dict(candidates)), disagreements


def _finite_or_zero(x: float) -> float:
    return x if math.isfinite(x) else 0.0


# ---------------------------------------------------------------------------------------------
# Running the analyses
# ---------------------------------------------------------------------------------------------
@dataclass
class _UnitContext:
    """What an adapter may use: the session, the unit's experiment, and what is known so far."""

    session: Session
    experiment: ExperimentSpec
    known: dict[str, Combined]
    fits: dict[str, FitResult]

    @property
    def cpr(self) -> float:
        return self.session.motor.counts_per_revolution

    @property
    def files(self) -> list[str]:
        return [str(p) for p in self.experiment.files]

    def setting(self, name: str) -> Any:
        return self.experiment.settings.get(name)

    def estimate(self, name: str) -> Estimate | None:
        combined = self.known.get(name)
        if combined is None or not combined.estimate.determined:
            return None
        return combined.estimate

    def require(self, name: str, why: str) -> Estimate:
        est = self.estimate(name)
        if est is None:
            raise OptionError(f"needs {name} ({why}); add an experiment that measures it")
        return est

    def loaded_inertia(self) -> tuple[float | None, float | None]:
        """Total inertia at the encoder shaft with the flywheel on, and its standard error [kg·m²].

        The flywheel reflected through its gear ratio (J·N², taken as exact: the session gives it) plus the
        gearmotor's own J: the unit's estimate when one is known already, otherwise the catalogue's nominal
        J with a 100 % standard error (a guess that only has to be small next to the flywheel's J·N²).
        """
        flywheel = self.session.rig.flywheel
        if flywheel is None:
            return None, None
        own = self.estimate("J")
        if own is not None:
            return flywheel.reflected_inertia + own.value, _stderr(own) or 0.0
        j_guess = 0.0
        if self.session.motor.catalog:
            from motorlab.catalog import Motor

            j_guess = Motor.from_catalog(self.session.motor.catalog).nominal_params().J
        return flywheel.reflected_inertia + j_guess, j_guess

    def motoring_friction(self) -> tuple[float, float, float, float, float] | None:
        """:func:`motorlab.session.efficiency.motoring_friction` with what the unit has measured so far."""
        return motoring_friction(self.fits.get("spindown"), gearbox_estimates(self.fits, self.known.get("K")),
                                 self.estimate("b"), self.estimate("Tf"))


#: Experiment name -> adapter running the experiment's own ``run`` (the command's and the notebook's) with
#: the option values its description draws from the session (:meth:`motorlab.experiments.Experiment.in_session`).
ADAPTERS: dict[str, Callable[[_UnitContext], FitResult]] = {
    name: exp.in_session for name, exp in all_experiments().items() if exp.session is not None
}


def characterize(
    session: Session, *, progress: Progress | None = None, control: bool = True, figures: bool = True,
    processes: int = 1,
) -> Characterization:
    """Run every analysis a session has files for and combine the results.

    Parameters
    ----------
    session
        A validated session (:func:`motorlab.session.spec.load_session`).
    progress
        Called as ``progress(unit, experiment)`` before each analysis and
        ``progress(unit, "")`` when a unit is done (drives the CLI's progress bar).
    control
        Also compute controller gains for the fleet's median parameters when
        :mod:`motorlab.control` is available.
    figures
        Draw the step-response figure of the gains now (otherwise the report draws it when it needs it).
    processes
        Analyse the units in up to this many processes (:func:`motorlab.parallel.map_in_processes`;
        the units are independent, the fleet is compared once all are done).

    Returns
    -------
    Characterization
        Per-unit fits, combined parameters, disagreements, failures, truth (simulated sessions)
        and the fleet summary.
    """
    from motorlab import parallel
    from motorlab import progress as reports

    specs = list(session.units.values())
    with reports.task("Characterising the units", total=len(specs), unit="unit") as task:
        done = [0]

        def told(message: tuple[str, str]) -> None:
            unit, experiment = message
            if experiment:
                task.update(done[0], detail=f"unit {unit}: {experiment}")
            if progress is not None:
                progress(unit, experiment)

        def finished(index: int, result: UnitResult) -> None:
            done[0] += 1
            task.update(done[0], detail=f"unit {result.spec.display_name} done")

        found = parallel.map_in_processes(_unit_job, [(session, spec) for spec in specs], processes=processes,
                                          on_message=told, on_result=finished)
    units = {spec.name: unit for spec, unit in zip(specs, found, strict=True)}
    threshold = DEFAULT_THRESHOLD if session.fleet_threshold is None else session.fleet_threshold
    fleet = fleet_summary(
        {n: u.estimates() for n, u in units.items()},
        model=session.motor.name,
        healthy_spread={"efficiency": EFFICIENCY_HEALTHY_SPREAD, **session.healthy_spread},
        threshold=threshold,
        parameters=(*PARAMETERS, "efficiency"),
    )
    result = Characterization(session=session, units=units, fleet=fleet)
    if control:
        result.gains = _controller_gains(result, plot=figures)
    return result


def _unit_job(item: tuple[Session, UnitSpec]) -> UnitResult:
    """One unit's analyses (run by :func:`motorlab.parallel.map_in_processes`), telling each step."""
    from motorlab import parallel

    session, spec = item
    return _characterize_unit(session, spec, lambda unit, experiment: parallel.tell((unit, experiment)))


def _characterize_unit(session: Session, spec: UnitSpec, progress: Progress | None) -> UnitResult:
    unit = UnitResult(spec=spec)
    if spec.truth is not None:
        try:
            unit.truth = read_truth(spec.truth)
        except MotorlabError as exc:
            unit.failures["truth"] = str(exc)
    candidates: dict[str, dict[str, Estimate]] = {name: {} for name in PARAMETERS}
    ordered = sorted(spec.experiments, key=lambda e: ORDER.index(e) if e in ORDER else len(ORDER))
    for exp_name in ordered:
        if progress is not None:
            progress(spec.name, exp_name)
        adapter = ADAPTERS.get(exp_name)
        if adapter is None:
            unit.failures[exp_name] = "this analysis is not available in this version of motorlab"
            continue
        ctx = _UnitContext(session, spec.experiments[exp_name], unit.parameters, unit.fits)
        try:
            with column_mapping(ctx.setting("columns")):  # the session's columns = {...} of this experiment
                fit = adapter(ctx)
        except MotorlabError as exc:
            unit.failures[exp_name] = str(exc)
            continue
        unit.fits[exp_name] = fit
        if exp_name in SHAFTS:
            fit.details.setdefault("shaft", SHAFTS[exp_name])
        for result_name, motor_name in CONTRIBUTIONS.get(exp_name, {}).items():
            if exp_name in LOADED_EXPERIMENTS and motor_name != "K":
                continue
            est = fit.parameters.get(result_name)
            if est is not None:
                candidates[motor_name][exp_name] = est
        # Re-combine after each experiment so that later analyses see the best K so far.
        for name in PARAMETERS:
            combined, _ = combine(name, sources_of(name, candidates[name]))
            if combined is not None:
                unit.parameters[name] = combined
    unit.parameters = {}
    for name in PARAMETERS:
        combined, disagreements = combine(name, sources_of(name, candidates[name]))
        if combined is not None:
            unit.parameters[name] = combined
        unit.disagreements.extend(disagreements)
    unit.parameters.update(gearbox_parameters(unit.fits, unit.parameters.get("K")))
    _warn_spinup_through_gearbox(unit)
    if progress is not None:
        progress(spec.name, "")
    return unit


def gearbox_parameters(fits: Mapping[str, FitResult], k: Combined | None) -> dict[str, Combined]:
    """The unit's gearbox ``efficiency`` and ``loss_torque`` (:func:`motorlab.session.efficiency.gearbox_estimates`)."""
    return {name: Combined(est, source, {source: est}) for name, (est, source) in gearbox_estimates(fits, k).items()}


def _warn_spinup_through_gearbox(unit: UnitResult) -> None:
    fit, eta = unit.fits.get("spinup"), unit.parameters.get("efficiency")
    if fit is not None and eta is not None and (warning := spinup_warning(fit, eta.estimate)):
        fit.warnings.append(warning)


def _controller_gains(result: Characterization, *, plot: bool = True) -> dict[str, Any] | None:
    """Gains for the fleet's median motor (SysId LQR defaults, :func:`motorlab.control.tune_summary`).

    Returns None when K, R or J were not measured; a failure of the design is kept in ``notes``.
    """
    from motorlab.model import MotorParams

    values: dict[str, Any] = {}
    for name in PARAMETERS:
        stats = result.fleet.parameters.get(name)
        if stats is not None and math.isfinite(stats.median):
            values[name] = max(stats.median, 0.0)
    if not all(name in values for name in ("K", "R", "J")):
        return None
    try:
        from motorlab.control import tune_summary

        params = MotorParams(**values)
        voltage = result.session.motor.nominal_voltage or 12.0
        summary = tune_summary(params, voltage=voltage, cpr=result.session.motor.counts_per_revolution, plot=plot)
    except (ImportError, MotorlabError) as exc:
        result.notes.append(f"controller gains not computed: {exc}")
        return None
    return {
        "motor": "median of the units",
        "voltage": voltage,
        "params": params.to_dict(),
        "velocity": summary.get("velocity"),
        "position": summary.get("position"),
        "text": summary.get("text", ""),
        "figure": summary.get("figure"),
        "results": summary.get("results"),  # the designs, for the report to draw their figure later
    }


# ---------------------------------------------------------------------------------------------
# Outputs
# ---------------------------------------------------------------------------------------------
def results_table(result: Characterization) -> list[dict[str, Any]]:
    """Seed 1's final table: one row per unit with value and standard error of each parameter (SI)."""
    rows = []
    for name, unit in result.units.items():
        row: dict[str, Any] = {"unit": name, "label": unit.spec.display_name}
        for p in table_parameters(result):
            combined = unit.parameters.get(p)
            est = combined.estimate if combined is not None else None
            ok = est is not None and est.determined
            row[p] = est.value if ok and est is not None else math.nan
            row[f"{p}_stderr"] = est.stderr if ok and est is not None else math.nan
            row[f"{p}_source"] = combined.source if combined is not None and ok else ""
        outliers = result.fleet.outliers_of(name)
        row["fleet"] = "; ".join(o.message() for o in outliers)
        row["status"] = unit.status
        rows.append(row)
    return rows


_GEARBOX_UNITS = {"efficiency": "1", "loss_torque": "N*m"}


def table_parameters(result: Characterization) -> tuple[str, ...]:
    """The final table's parameters: :data:`PARAMETERS`, plus the gearbox's when some unit has them."""
    extra = tuple(p for p in GEARBOX_PARAMETERS if any(p in u.parameters for u in result.units.values()))
    return (*PARAMETERS, *extra)


def write_csv(result: Characterization, path: str | Path) -> Path:
    """Write ``results.csv``: one row per unit, SI units named in the header."""
    path = Path(path)
    header = ["unit", "label"]
    for p in table_parameters(result):
        unit = _GEARBOX_UNITS.get(p) or SI_UNITS[p]
        header += [f"{p} ({unit})", f"{p} stderr ({unit})", f"{p} source"]
    header += ["fleet outliers", "status"]
    with atomic_path(path) as temporary, temporary.open("w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle)
        writer.writerow(header)
        for row in results_table(result):
            cells: list[Any] = [row["unit"], row["label"]]
            for p in table_parameters(result):
                cells += [_csv_float(row[p]), _csv_float(row[f"{p}_stderr"]), row[f"{p}_source"]]
            cells += [row["fleet"], row["status"]]
            writer.writerow(cells)
    return path


def output_paths(out_dir: str | Path, *, report: bool = True) -> list[Path]:
    """The files :func:`write_outputs` writes into ``out_dir``."""
    names = ["results.json", "results.csv"] + (["report.html"] if report else [])
    return [Path(out_dir) / name for name in names]


def session_inputs(session: Session) -> list[Path]:
    """Every file a session reads: the TOML, each experiment's data files, each unit's truth file."""
    found = [session.path]
    for unit in session.units.values():
        found.extend(f for spec in unit.experiments.values() for f in spec.files)
        if unit.truth is not None:
            found.append(unit.truth)
    return found


def _csv_float(x: float) -> str:
    return f"{x:.6g}" if math.isfinite(x) else ""


