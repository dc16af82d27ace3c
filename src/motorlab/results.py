"""The one result type every analysis returns.

A :class:`FitResult` holds estimates (value, standard error, unit), the correlation of the fitted
parameters, residual statistics, the data and model curves needed to plot, and warnings. Its
:meth:`FitResult.report` is modelled on lmfit's ``fit_report``: value ± stderr (percent),
correlations above a threshold, and an explicit line for every parameter the data do not determine.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import PurePath
from typing import Any, ClassVar

import numpy as np

from motorlab.errors import OptionError
from motorlab.units import format_percent, format_unit


@dataclass(frozen=True)
class Estimate:
    """One estimated parameter.

    Parameters
    ----------
    name
        Symbol used in reports and JSON (``K``, ``R``, ``L``, ``J``, ``b``, ``Tf``, ``gamma`` ...).
    value
        Best estimate in SI units, or NaN when the data do not determine it.
    stderr
        One standard error in the same unit; NaN when it could not be estimated.
    unit
        SI unit string (``"V*s/rad"``).
    determined
        False when the data cannot determine this parameter (singular or near-singular
        information); ``value`` is then not to be used.
    note
        Short explanation (source, or why undetermined).
    """

    name: str
    value: float
    stderr: float
    unit: str
    determined: bool = True
    note: str = ""

    @property
    def relative_error(self) -> float:
        """``stderr / |value|`` (NaN if either is unavailable or value is 0)."""
        if not (math.isfinite(self.value) and math.isfinite(self.stderr)) or self.value == 0:
            return math.nan
        return abs(self.stderr / self.value)

    def interval(self, k: float = 1.96) -> tuple[float, float]:
        """``value ± k·stderr``."""
        return self.value - k * self.stderr, self.value + k * self.stderr

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict ``{"value", "stderr", "unit"}`` (plus ``determined``/``note`` when relevant)."""
        out: dict[str, Any] = {
            "value": json_float(self.value) if self.determined else None,
            "stderr": json_float(self.stderr),
            "unit": self.unit,
        }
        if not self.determined:
            out["determined"] = False
        if self.note:
            out["note"] = self.note
        return out

    def __str__(self) -> str:
        unit = format_unit(self.unit)
        if not self.determined:
            return f"{self.name} = not determined by these data [{unit}]" + (
                f" ({self.note})" if self.note else ""
            )
        if not math.isfinite(self.stderr):
            return f"{self.name} = {self.value:.6g} ± ? {unit} (uncertainty could not be estimated)"
        return f"{self.name} = {self.value:.6g} ± {self.stderr:.2g} {unit} ({format_percent(self.relative_error)})"


@dataclass
class Series:
    """One curve: x and y arrays with a label; ``kind`` is ``"data"`` or ``"model"``."""

    x: np.ndarray
    y: np.ndarray
    label: str
    kind: str = "data"


@dataclass
class Panel:
    """One plot: data against model, with axis labels carrying units.

    When ``data`` and ``model`` share the same x, :func:`motorlab.plot.plot_fit` draws their
    residuals beneath. ``time``, when the data points are samples of a log, is each point's time in
    the log's own time axis [s] (what ``--exclude`` takes), whatever the x axis shows.
    """

    title: str
    x_label: str
    y_label: str
    data: Series | None = None
    model: Series | None = None
    extra: list[Series] = field(default_factory=list)
    time: np.ndarray | None = None


@dataclass
class FitResult:
    """What every analysis returns.

    Attributes
    ----------
    experiment
        Name of the experiment (``"spindown"``, ``"lcr"`` ...).
    parameters
        Estimates by symbol, in SI.
    correlation
        Correlation matrix of the fitted parameters named in ``correlation_names`` (or None).
    rmse, r2
        Residual root-mean-square (in ``rmse_unit``) and coefficient of determination of the main fit.
    n_points
        Number of samples the main fit used.
    panels
        Data-vs-model plots.
    warnings
        Things the user must know (e.g. "Coulomb friction folded into b").
    details
        Further numbers worth reporting (model-selection table, per-row values ...), JSON-ready.
    sources
        Paths of the files analysed.
    """

    experiment: str
    parameters: dict[str, Estimate]
    correlation: np.ndarray | None = None
    correlation_names: list[str] = field(default_factory=list)
    rmse: float = math.nan
    rmse_unit: str = ""
    r2: float = math.nan
    n_points: int = 0
    panels: list[Panel] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    details: dict[str, Any] = field(default_factory=dict)
    sources: list[str] = field(default_factory=list)

    #: What :func:`motorlab.plot.plot_fit` draws for a result without curves.
    EMPTY_PANEL: ClassVar[Panel] = Panel(title="(no curves to plot)", x_label="", y_label="")

    def __post_init__(self) -> None:
        self.check_physics()

    def check_physics(self) -> None:
        """Warn of parameters fitted negative that must be positive; refuse when given options force them.

        Runs when the result is made; run it again after adding parameters (see
        :func:`check_signs`).

        Raises
        ------
        OptionError
            When values the user gave (``note="given"``) clearly contradict the data.
        """
        for text in check_signs(self.parameters):
            if text not in self.warnings:
                self.warnings.append(text)

    def __getitem__(self, name: str) -> Estimate:
        return self.parameters[name]

    def __contains__(self, name: object) -> bool:
        return name in self.parameters

    def value(self, name: str) -> float:
        """The value of parameter ``name`` in SI."""
        return self.parameters[name].value

    def correlations(self, threshold: float = 0.1) -> list[tuple[str, str, float]]:
        """Pairs of parameters whose |correlation| exceeds ``threshold``, largest first."""
        if self.correlation is None:
            return []
        names = self.correlation_names
        pairs = [
            (names[i], names[j], float(self.correlation[i, j]))
            for i in range(len(names))
            for j in range(i + 1, len(names))
            if math.isfinite(self.correlation[i, j]) and abs(self.correlation[i, j]) > threshold
        ]
        return sorted(pairs, key=lambda p: -abs(p[2]))

    def report(self, *, min_correl: float = 0.1) -> str:
        """A plain-text report in the manner of lmfit's ``fit_report``."""
        lines = [f"[[{self.experiment}]]"]
        if self.sources:
            lines.append("    files:  " + ", ".join(self.sources))
        lines.append("[[Fit statistics]]")
        lines.append(f"    data points      = {self.n_points}")
        if math.isfinite(self.rmse):
            lines.append(f"    residual RMS     = {self.rmse:.4g} {format_unit(self.rmse_unit)}")
        if math.isfinite(self.r2):
            lines.append(f"    R²               = {self.r2:.6f}")
        lines.append("[[Parameters]]")
        lines.extend(f"    {est}" for est in self.parameters.values())
        if self.details.get("R_temperature"):
            lines.append(f"    (temperature of R: {self.details['R_temperature']})")
        pairs = self.correlations(min_correl)
        if pairs:
            lines.append(f"[[Correlations]] (unreported correlations are < {min_correl})")
            lines.extend(f"    C({a}, {b}) = {c:+.4f}" for a, b, c in pairs)
        if self.warnings:
            lines.append("[[Warnings]]")
            lines.extend(f"    - {w}" for w in self.warnings)
        return "\n".join(lines)

    def __repr__(self) -> str:
        """One line per parameter (the arrays behind the plots are not printed)."""
        head = f"FitResult({self.experiment!r}, n_points={self.n_points}"
        if math.isfinite(self.r2):
            head += f", r2={self.r2:.6f}"
        if self.warnings:
            head += f", {len(self.warnings)} warning(s)"
        return "\n".join([head + ")", *(f"    {est}" for est in self.parameters.values())])

    def _repr_html_(self) -> str:
        """A table of value ± stderr and unit (Jupyter), with the shaft, fit statistics and warnings."""
        from html import escape

        title = escape(self.experiment)
        if self.sources:
            title += ": " + escape(", ".join(self.sources))
        rows = "".join(
            "<tr>" + "".join(f"<td>{escape(str(cell))}</td>" for cell in _html_row(est)) + "</tr>"
            for est in self.parameters.values()
        )
        head = "".join(f"<th>{h}</th>" for h in ("parameter", "value", "± stderr", "unit", "rel. error", "note"))
        parts = [f"<b>{title}</b>", f"<table><thead><tr>{head}</tr></thead><tbody>{rows}</tbody></table>"]
        stats = [f"data points {self.n_points}"]
        if math.isfinite(self.rmse):
            stats.append(f"residual RMS {self.rmse:.4g} {escape(format_unit(self.rmse_unit))}")
        if math.isfinite(self.r2):
            stats.append(f"R² {self.r2:.6f}")
        parts.append("<p>fit: " + ", ".join(stats) + "</p>")
        if "shaft" in self.details:
            parts.append(f"<p>shaft: {escape(str(self.details['shaft']))}</p>")
        if self.warnings:
            parts.append("<ul>" + "".join(f"<li>{escape(w)}</li>" for w in self.warnings) + "</ul>")
        return "<div>" + "".join(parts) + "</div>"

    def plot(self, ax: Any = None) -> Any:
        """Draw the data against the model (:func:`motorlab.plot.plot_fit`).

        Parameters
        ----------
        ax
            A matplotlib ``Axes`` to draw the first panel into (without residuals), or None for a
            new ``Figure`` with every panel and its residuals.

        Returns
        -------
        The ``Figure`` (``ax=None``) or ``ax``.
        """
        from motorlab.plot import plot_fit, plot_panel

        if ax is None:
            return plot_fit(self)
        if not self.panels:
            raise ValueError(f"{self.experiment}: this result has no data to plot")
        plot_panel(self.panels[0], ax)
        return ax

    def to_rows(self) -> list[dict[str, Any]]:
        """The parameter table, one dict per parameter: name, value, stderr, unit, determined, note (SI)."""
        shaft = self.details.get("shaft", "")
        return [
            {"experiment": self.experiment, "parameter": est.name,
             "value": est.value if est.determined else math.nan, "stderr": est.stderr, "unit": est.unit,
             "determined": est.determined, "shaft": shaft, "note": est.note}
            for est in self.parameters.values()
        ]

    def to_csv(self, path: Any = None) -> str:
        """The rows of :meth:`to_rows` as CSV text (empty cells for NaN); written to ``path`` if given."""
        import csv
        import io

        buffer = io.StringIO()
        columns = ["experiment", "parameter", "value", "stderr", "unit", "determined", "shaft", "note"]
        writer = csv.DictWriter(buffer, fieldnames=columns, lineterminator="\n")
        writer.writeheader()
        for row in self.to_rows():
            writer.writerow({k: ("" if isinstance(v, float) and not math.isfinite(v) else v) for k, v in row.items()})
        text = buffer.getvalue()
        if path is not None:
            from motorlab.io.output import check_writable_target

            check_writable_target(path)
            with open(path, "w", encoding="utf-8", newline="") as handle:
                handle.write(text)
        return text

    def to_dict(self) -> dict[str, Any]:
        """The JSON object of ``motorlab analyze --json`` (SI units)."""
        fit: dict[str, Any] = {
            "rmse": json_float(self.rmse),
            "rmse_unit": self.rmse_unit,
            "r2": json_float(self.r2),
            "n_points": self.n_points,
        }
        if self.correlation is not None:
            fit["correlation"] = {
                "names": list(self.correlation_names),
                "matrix": [[json_float(v) for v in row] for row in np.asarray(self.correlation)],
            }
        out: dict[str, Any] = {
            "experiment": self.experiment,
            "parameters": {name: est.to_dict() for name, est in self.parameters.items()},
            "fit": fit,
            "warnings": list(self.warnings),
        }
        if self.details:
            out["details"] = jsonable(self.details)
        if self.sources:
            out["sources"] = list(self.sources)
        return out


def _html_row(est: Estimate) -> tuple[str, ...]:
    unit = format_unit(est.unit)
    if not est.determined:
        return est.name, "not determined", "", unit, "", est.note
    rel = est.relative_error
    stderr = f"± {est.stderr:.2g}" if math.isfinite(est.stderr) else "± ?"
    return est.name, f"{est.value:.6g}", stderr, unit, f"{100 * rel:.2f} %" if math.isfinite(rel) else "?", est.note


def json_float(x: float) -> float | None:
    x = float(x)
    return x if math.isfinite(x) else None


def jsonable(obj: Any) -> Any:
    """``obj`` ready for ``json.dump``: numpy scalars and arrays, tuples and paths converted, NaN and
    infinities as None (the one converter: results, the characterisation, the rig's truth files)."""
    if isinstance(obj, dict):
        return {str(k): jsonable(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return [jsonable(v) for v in obj.tolist()]
    if isinstance(obj, np.generic):
        return jsonable(obj.item())
    if isinstance(obj, float):
        return json_float(obj)
    if isinstance(obj, PurePath):
        return str(obj)
    return obj


# ---------------------------------------------------------------------------------------------
# Fitted values that break physics are never printed silently: every FitResult passes through check_signs
# when it is made. A parameter that must be positive and comes out negative gets a warning naming the
# likely cause; when the user's own options (estimates marked note="given") push it below zero, clearly,
# the result is refused with an OptionError that names those options.
# ---------------------------------------------------------------------------------------------
#: Parameter -> (likely cause of a negative value, the given parameters that can force it below zero).
MUST_BE_POSITIVE: dict[str, tuple[str, tuple[str, ...]]] = {
    "K": ("the log is not this experiment's (the speed does not rise under a steady current), or the "
          "encoder or the current is reversed", ()),
    "R": ("the leads or the meter are reversed, or the current and voltage columns are swapped", ()),
    "R_dc": ("the meter's zero offset (null the leads first)", ()),
    "L": ("the meter's zero offset or open/short compensation", ()),
    "J": ("friction given too large, or a log that is not a spin-up or coast", ("b", "Tf", "K")),
    "b": ("Coulomb friction Tf given or fitted too large, K given too large, or too narrow a speed range",
          ("Tf", "K", "R", "J")),
    "Tf": ("viscous friction b given too large, or speeds that do not reach low enough", ("b", "K", "J")),
    "gamma": ("the shaft speeds up while it should coast (a drive left on?)", ()),
    "Tf_over_J": ("the coast does not slow down as friction would (a drive left on?)", ()),
    "kS": ("too narrow a voltage range (kS is the voltage at zero speed)", ()),
    "kV": ("the encoder or the voltage is reversed", ()),
    "kA": ("the encoder or the voltage is reversed, or the dynamic tests are missing", ()),
}

#: A negative value farther than this many standard errors below zero is "clearly" negative.
SIGNIFICANT = 2.0


def _given(parameters: Mapping[str, Estimate]) -> dict[str, Estimate]:
    return {name: est for name, est in parameters.items() if est.note.strip().lower().startswith("given")}


def _show(est: Estimate) -> str:
    se = f" ± {est.stderr:.2g}" if math.isfinite(est.stderr) and est.stderr > 0 else ""
    return f"{est.value:.4g}{se} {format_unit(est.unit)}"


def check_signs(parameters: Mapping[str, Estimate]) -> list[str]:
    """Warnings for parameters fitted negative that physics wants positive.

    Parameters
    ----------
    parameters
        The estimates of a fit, by symbol.

    Returns
    -------
    list of str
        One warning per negative parameter, with the likely cause.

    Raises
    ------
    OptionError
        A parameter clearly negative (more than :data:`SIGNIFICANT` standard errors below zero)
        because of values the user gave (``note="given"``) that can force it there: the options
        contradict the data.
    """
    given = _given(parameters)
    warnings = []
    for name, est in parameters.items():
        if name not in MUST_BE_POSITIVE or name in given or not est.determined:
            continue
        if not (math.isfinite(est.value) and est.value < 0):
            continue
        cause, forced_by = MUST_BE_POSITIVE[name]
        clear = not math.isfinite(est.stderr) or est.value < -SIGNIFICANT * est.stderr
        culprits = [g for g in forced_by if g in given]
        if clear and culprits:
            options = ", ".join(f"{g} = {_show(given[g])}" for g in culprits)
            raise OptionError(
                f"with the given {options}, {name} comes out negative ({_show(est)}), which no motor has: "
                f"the given value contradicts the data (likely cause: {cause})"
            )
        tail = "" if clear else ", though within its uncertainty of zero"
        warnings.append(f"{name} is fitted negative ({_show(est)}), which no motor has{tail}: likely cause: {cause}")
    return warnings
