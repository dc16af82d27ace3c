"""A self-contained HTML report of a characterised session: one file, plots embedded, printable.

:func:`render_report` turns a :class:`~motorlab.session.characterize.Characterization` into HTML with:

1. the final parameter table (seed 1's "Final Calculated Parameters": J, b, Ke, R, L per unit,
   plus Tf), every value with its standard error and unit, and the truth when the session was
   simulated;
2. disagreements between sources and failed experiments;
3. the fleet section: mean ± spread per parameter and the units that stand out;
4. the motor curves of each unit against the catalogue's published figures;
5. the controller gains (when :mod:`motorlab.control` gave them);
6. per unit and experiment, the fit summary and the data-vs-model plot with residuals;
7. the methods: the equations used and the seed's mistakes that motorlab corrects.

Figures are PNG (matplotlib's Agg canvas, ``Figure`` object API) embedded as base64 ``data:``
URIs, so the file reads offline and can be mailed. All text from files and fits is escaped with
:func:`html.escape`. A print stylesheet starts each unit on a new page and drops backgrounds.
"""

from __future__ import annotations

import base64
import functools
import html
import io
import json
import math
from collections.abc import Iterable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from matplotlib.figure import Figure

from motorlab.report.thermal import thermal_section
from motorlab.results import Estimate, FitResult
from motorlab.units import format_unit, format_value, power_of_ten

if TYPE_CHECKING:
    from motorlab.session.characterize import Characterization, UnitResult

#: Display unit and scale (display = SI·scale) of each motor parameter in the report's tables.
DISPLAY_UNITS: dict[str, tuple[str, float]] = {
    "J": ("kg·m²", 1.0),
    "b": ("N·m·s/rad", 1.0),
    "Tf": ("N·m", 1.0),
    "K": ("V·s/rad", 1.0),
    "R": ("Ω", 1.0),
    "L": ("µH", 1e6),
    "efficiency": ("1", 1.0),
    "loss_torque": ("N·m", 1.0),
}

#: Column titles of the final table (seed 1 calls K "Ke (spin down)").
COLUMN_TITLES = {"J": "J", "b": "b", "Tf": "Tf", "K": "K = Ke", "R": "R", "L": "L",
                 "efficiency": "η (gearbox)", "loss_torque": "τ0 (gearbox)"}

#: Resolution of embedded figures [dots per inch].
FIGURE_DPI = 80

_CSS = """
:root { --ink: #1d2330; --muted: #5b6475; --line: #d5d9e0; --accent: #1f5fa8; --flag: #b3261e; }
* { box-sizing: border-box; }
body { font: 15px/1.45 system-ui, -apple-system, "Segoe UI", Roboto, sans-serif; color: var(--ink);
       max-width: 1150px; margin: 0 auto; padding: 24px 28px 60px; background: #fff; }
h1 { font-size: 26px; margin: 0 0 4px; }
h2 { font-size: 20px; margin: 34px 0 10px; padding-bottom: 4px; border-bottom: 2px solid var(--accent); }
h3 { font-size: 16px; margin: 22px 0 8px; }
p.meta, .muted { color: var(--muted); }
table { border-collapse: collapse; margin: 8px 0 14px; font-size: 13.5px; }
th, td { border: 1px solid var(--line); padding: 4px 8px; text-align: right; vertical-align: top; }
th { background: #f1f4f8; font-weight: 600; }
td.name, th.name { text-align: left; }
td.flag { color: var(--flag); font-weight: 600; }
td.fail { color: var(--flag); text-align: left; max-width: 360px; }
tr.truth td { color: var(--muted); font-size: 12px; border-top: none; }
.ok { color: #2e7d32; }
.warn { color: var(--flag); }
ul.issues li { margin: 2px 0; }
figure { margin: 10px 0 18px; }
figure img { max-width: 100%; height: auto; border: 1px solid var(--line); }
figcaption { color: var(--muted); font-size: 13px; }
.grid { display: grid; grid-template-columns: repeat(auto-fit, minmax(520px, 1fr)); gap: 10px; }
pre { background: #f6f8fa; padding: 8px 10px; font-size: 12.5px; overflow-x: auto; }
code, .eq { font-family: ui-monospace, "DejaVu Sans Mono", monospace; font-size: 13px; }
.eq { display: block; margin: 4px 0 4px 18px; }
nav ol { columns: 2; }
@media print {
  body { max-width: none; padding: 0; font-size: 11pt; }
  h2 { break-after: avoid; }
  section.unit { break-before: page; }
  figure, table { break-inside: avoid; }
  th { background: none; }
  nav { display: none; }
  a { color: inherit; text-decoration: none; }
}
"""


# ---------------------------------------------------------------------------------------------
# Formatting
# ---------------------------------------------------------------------------------------------
def _e(text: Any) -> str:
    return html.escape(str(text), quote=True)


def _estimate_cell(est: Estimate | None, name: str) -> str:
    if est is None:
        return "—"
    if not est.determined:
        return "not determined"
    _, scale = DISPLAY_UNITS.get(name, (format_unit(est.unit), 1.0))
    return format_value(est.value, est.stderr, scale=scale)


def _display_unit(name: str, unit: str) -> str:
    return DISPLAY_UNITS[name][0] if name in DISPLAY_UNITS else format_unit(unit)


def figure_to_data_uri(fig: Figure, *, dpi: int = FIGURE_DPI) -> str:
    """A matplotlib figure as a ``data:image/png;base64,...`` URI (Agg canvas, no pyplot)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    FigureCanvasAgg(fig)
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=dpi)
    return "data:image/png;base64," + base64.b64encode(buffer.getvalue()).decode("ascii")


def _figure_html(fig: Figure | None, caption: str, alt: str) -> str:
    if fig is None:
        return ""
    return (
        f'<figure><img src="{figure_to_data_uri(fig)}" alt="{_e(alt)}"><figcaption>{_e(caption)}</figcaption></figure>'
    )


# ---------------------------------------------------------------------------------------------
# Sections
# ---------------------------------------------------------------------------------------------
def render_report(result: Characterization, *, figures: bool = True, processes: int = 1) -> str:
    """The report as one HTML document.

    Parameters
    ----------
    result
        What :func:`motorlab.session.characterize.characterize` returned.
    figures
        Draw and embed the figures (False gives a quick text-only report).
    processes
        Draw the sections with figures (the motor curves, the gains, each unit's fits) in up to this
        many processes (:func:`motorlab.parallel.map_in_processes`); each figure is drawn once.

    Returns
    -------
    str
        A complete, self-contained HTML5 document.
    """
    from motorlab import __version__, parallel
    from motorlab import progress as reports

    s = result.session
    keys = ["curves", *(f"unit:{name}" for name in result.units), "gains"]  # the longest first
    with reports.task("Drawing the report", total=len(keys), unit="section") as task:
        drawn = parallel.map_in_processes(
            functools.partial(_render_section, result, figures), keys, processes=processes if figures else 1,
            on_result=lambda _index, _html: task.advance(),
        )
    sections = dict(zip(keys, drawn, strict=True))
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        f"<title>{_e(s.title)} — motorlab report</title>",
        f"<style>{_CSS}</style></head><body>",
        f"<h1>{_e(s.title)}</h1>",
        f'<p class="meta">{_e(_session_line(result))}<br>motorlab {_e(__version__)} · session file '
        f"<code>{_e(s.path.name)}</code></p>",
        _nav(result),
        _final_table(result),
        _issues(result),
        _fleet_section(result),
        _gearbox_section(result),
        sections["curves"],
        thermal_section(result),
        sections["gains"],
    ]
    parts += [sections[f"unit:{name}"] for name in result.units]
    parts.append(_methods_section())
    parts.append("</body></html>")
    return "\n".join(p for p in parts if p)


def _render_section(result: Characterization, figures: bool, key: str) -> str:
    """One section of the report that draws figures: ``"curves"``, ``"gains"`` or ``"unit:NAME"``."""
    if key == "curves":
        return _curves_section(result, figures=figures)
    if key == "gains":
        return _gains_section(result, figures=figures)
    return _unit_section(result.units[key.split(":", 1)[1]], figures=figures)


def write_report(result: Characterization, path: str | Path, *, figures: bool = True, processes: int = 1) -> Path:
    """Write :func:`render_report`'s HTML to ``path`` (UTF-8) and return the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    from motorlab.io.output import write_text_atomic

    write_text_atomic(path, render_report(result, figures=figures, processes=processes))
    return path


def write_outputs(result: Characterization, out_dir: str | Path, *, report: bool = True,
                  processes: int = 1) -> dict[str, Path]:
    """Write ``results.json`` and ``results.csv``, then (by default) ``report.html``, into ``out_dir``.

    The numbers come first: ``results.json`` is complete (written atomically) before the report's
    first figure is drawn, so a front end can show the table while the figures follow.

    Returns
    -------
    dict
        ``{"json": path, "csv": path, "html": path}``.
    """
    from motorlab.io.output import write_text_atomic
    from motorlab.session.characterize import write_csv

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = {"json": out / "results.json", "csv": out / "results.csv"}
    write_csv(result, paths["csv"])
    write_text_atomic(paths["json"], json.dumps(result.to_dict(), indent=2, allow_nan=False) + "\n")
    if report:
        paths["html"] = write_report(result, out / "report.html", processes=processes)
    return paths


def _session_line(result: Characterization) -> str:
    s = result.session
    bits = [f"Motor: {s.motor.name}"]
    if s.motor.catalog:
        bits.append(f"catalogue key {s.motor.catalog}")
    bits.append(f"{s.motor.counts_per_revolution:g} counts/rev, {s.motor.gear_ratio:g}:1")
    if s.rig.flywheel is not None:
        fw = s.rig.flywheel
        bits.append(f"flywheel {fw.description} × {fw.ratio:g}² = {fw.reflected_inertia:.4g} kg·m² at the output shaft")
    if s.date:
        bits.append(s.date)
    bits.append(f"{len(result.units)} unit(s)")
    return " · ".join(bits)


def _nav(result: Characterization) -> str:
    items = [
        ("parameters", "Final parameters"),
        ("issues", "Disagreements and failures"),
        ("fleet", "Fleet"),
        ("gearbox", "The gearbox: Kt against Ke"),
        ("curves", "Motor curves"),
    ]
    if any("stall" in unit.fits for unit in result.units.values()):
        items.append(("thermal", "Heat"))
    if result.gains:
        items.append(("gains", "Controller gains"))
    items += [(f"unit-{u}", f"Unit {r.spec.display_name}") for u, r in result.units.items()]
    items.append(("methods", "Methods"))
    links = "".join(f'<li><a href="#{_e(anchor)}">{_e(title)}</a></li>' for anchor, title in items)
    return f"<nav><ol>{links}</ol></nav>"


def _final_table(result: Characterization) -> str:
    from motorlab.session.characterize import table_parameters

    columns = table_parameters(result)
    flagged = {(o.unit, o.parameter) for o in result.fleet.outliers}
    head = "".join(
        f"<th>{_e(COLUMN_TITLES[p])}<br><span class='muted'>[{_e(DISPLAY_UNITS[p][0])}]</span></th>" for p in columns
    )
    rows = []
    any_truth = any(u.truth for u in result.units.values())
    for name, unit in result.units.items():
        cells = []
        for p in columns:
            combined = unit.parameters.get(p)
            est = combined.estimate if combined is not None else None
            cls = "flag" if (name, p) in flagged else ""
            title = f"from {combined.source}" if combined is not None else "no experiment measured it"
            cells.append(f'<td class="{cls}" title="{_e(title)}">{_e(_estimate_cell(est, p))}</td>')
        status = unit.status
        status_html = '<td class="name ok">ok</td>' if status == "ok" else f'<td class="fail">{_e(status)}</td>'
        rows.append(f'<tr><td class="name">{_e(unit.spec.display_name)}</td>{"".join(cells)}{status_html}</tr>')
        if unit.truth:
            truth_cells = []
            for p in columns:
                t = unit.truth.get(p)
                combined = unit.parameters.get(p)
                text = "—"
                if t is not None:
                    text = f"{t * DISPLAY_UNITS[p][1]:.4g}"
                    if combined is not None and combined.estimate.determined:
                        est = combined.estimate
                        if math.isfinite(est.stderr) and est.stderr > 0:
                            text += f" ({(est.value - t) / est.stderr:+.1f}\u00a0σ)"  # σ never alone on a line
                truth_cells.append(f"<td>{_e(text)}</td>")
            rows.append(f'<tr class="truth"><td class="name">truth</td>{"".join(truth_cells)}<td></td></tr>')
    sources = sorted({c.source for u in result.units.values() for c in u.parameters.values()})
    note = (
        "Each value is the estimate ± one standard error. Where several experiments measure a parameter, "
        "the most precise one is kept (hover a cell to see which); sources used: " + ", ".join(sources) + "."
    )
    if any_truth:
        note += " The grey rows give the simulated truth and the error in standard errors."
    if flagged:
        note += " Values in red stand out from the fleet (see Fleet)."
    return (
        '<section id="parameters"><h2>Final parameters</h2>'
        f'<table><thead><tr><th class="name">Unit</th>{head}<th class="name">Status</th></tr></thead>'
        f"<tbody>{''.join(rows)}</tbody></table>"
        f'<p class="muted">{_e(note)} All quantities at the output shaft whose encoder is counted. K is the '
        "back-EMF constant Ke; J, b and Tf are those of the bare gearmotor per unit of the motor's torque K·i "
        "(the gearbox's efficiency not applied: the physical torques at the output are η times them; the "
        "spin-down's and spin-up's figures, which include the flywheel, are in each unit's section). "
        "η and τ0 are the gearbox's efficiency and loss torque at the output (see The gearbox).</p></section>"
    )


def _issues(result: Characterization) -> str:
    items = []
    for unit in result.units.values():
        for d in unit.disagreements:
            items.append(f"<li><b>{_e(unit.spec.display_name)}</b>: sources disagree: {_e(d.message())}</li>")
        for exp, why in unit.failures.items():
            items.append(f'<li class="warn"><b>{_e(unit.spec.display_name)}</b>: {_e(exp)} failed: {_e(why)}</li>')
    body = (
        f'<ul class="issues">{"".join(items)}</ul>'
        if items
        else "<p>All sources agree within three combined standard errors, and every analysis ran.</p>"
    )
    return f'<section id="issues"><h2>Disagreements and failures</h2>{body}</section>'


def _fleet_section(result: Characterization) -> str:
    fleet = result.fleet
    if not fleet.parameters:
        return '<section id="fleet"><h2>Fleet</h2><p>No parameter was estimated.</p></section>'
    units = list(result.units)
    head = "".join(f"<th>z ({_e(result.units[u].spec.display_name)})</th>" for u in units)
    rows = []
    for name, stats in fleet.parameters.items():
        unit, scale = DISPLAY_UNITS.get(name, (format_unit(stats.unit), 1.0))
        mean = format_value(stats.mean, stats.std, scale=scale) if stats.n > 1 else f"{stats.mean * scale:.4g}"
        rel = 100 * stats.std / abs(stats.mean) if stats.n > 1 and stats.mean != 0 else math.nan
        zs = []
        for u in units:
            z = stats.z.get(u)
            flag = z is not None and abs(z) > fleet.threshold
            zs.append(f'<td class="{"flag" if flag else ""}">{"—" if z is None else f"{z:+.1f}"}</td>')
        rows.append(
            f'<tr><td class="name">{_e(name)} [{_e(unit)}]</td><td>{_e(mean)}</td>'
            f"<td>{'—' if not math.isfinite(rel) else f'{rel:.1f} %'}</td>"
            f"<td>{_e(f'{stats.median * scale:.4g}')}</td><td>{stats.n}</td>{''.join(zs)}</tr>"
        )
    if fleet.outliers:
        found = "".join(
            f"<li><b>{_e(result.units[o.unit].spec.display_name)}</b>: {_e(o.message())}</li>" for o in fleet.outliers
        )
        verdict = f'<p class="warn">Units that stand out (|z| &gt; {fleet.threshold:g}):</p><ul>{found}</ul>'
    elif not fleet.tested:
        verdict = f'<p class="muted">{_e(fleet.verdict().capitalize())}.</p>'
    else:
        verdict = f'<p class="ok">No unit stands out (every |z| ≤ {fleet.threshold:g}).</p>'
    notes = "".join(f"<li>{_e(n)}</li>" for n in fleet.notes)
    return (
        f'<section id="fleet"><h2>Fleet: {_e(fleet.model)}</h2>{verdict}'
        f'<table><thead><tr><th class="name">Parameter</th><th>mean ± std</th><th>std/mean</th><th>median</th>'
        f"<th>n</th>{head}</tr></thead><tbody>{''.join(rows)}</tbody></table>"
        f"{f'<ul class=muted>{notes}</ul>' if notes else ''}"
        '<p class="muted">Robust z-score on ln x: z = (ln x − median ln x)/√(s² + (σ/x)²) with '
        "s = the healthy spread (or the MAD from five units on); see Methods. "
        "“Which of our motors is worn?” — a unit whose friction stands out is the first suspect.</p></section>"
    )


def _gearbox_section(result: Characterization) -> str:
    """Seed 1's open question ("our Kt and Ke measurements don't quite match") answered per unit."""
    from motorlab.session.efficiency import gearbox_answer

    motor = _catalog_motor(result)
    ratio = result.session.motor.gear_ratio or (motor.gear_ratio if motor is not None else None)
    rows, verdicts = [], []
    for unit in result.units.values():
        a = gearbox_answer(unit.fits.get("torque"), unit.parameters.get("K"), unit.parameters.get("efficiency"),
                           ratio=ratio)
        if a is None:
            continue
        name = _e(unit.spec.display_name)
        rows.append(
            f'<tr><td class="name">{name}</td><td>{_e(a["ke_motor"])}</td><td>{_e(a["ke_n"])}</td>'
            f"<td>{_e(a['kt'])}</td><td>{_e(a['eta'])}</td><td>{_e(a['loss'])}</td><td>{_e(a['mismatch'])}</td></tr>"
        )
        verdicts.append(f"<li><b>{name}</b>: {_e(a['verdict'] + _bare_motor_part(result, unit.name, ratio))}</li>")
    if not rows:
        return (
            '<section id="gearbox"><h2>The gearbox: Kt against Ke</h2><p class="muted">Not determined: the gearbox '
            "efficiency needs a back-EMF K (spin-down or identification) and a torque test at the output shaft "
            "(lever on a scale) of the same unit.</p></section>"
        )
    sheet = ""
    if motor is not None:
        box = motor.gearbox()
        sheet = (
            f" The catalogue's figures for the {motor.name} imply Kt/Ke = {motor.gearbox_efficiency_at_stall:.2f} at "
            f"stall, i.e. η = {box.efficiency:.3f} once the stalled motor's own friction is allowed for."
        )
    return (
        '<section id="gearbox"><h2>The gearbox: Kt against Ke</h2>'
        "<p>Seed 1 ends with an open question: the torque constant Kt from a torque measurement does not match "
        "the back-EMF constant Ke, and the team suspected the gearbox. Ke comes from the back-EMF (spin-down: "
        "V = Ke·ω with no current, so the gearbox's losses do not enter); Kt from a lever at the output shaft, "
        "which feels τ = η·N·Ke_motor·i − τ0. Their ratio η holds two parts: the bare motor's own torque per amp "
        "over its back-EMF constant (Kt/K, below 1 on real motors: a motor curve or a stall run of the bare motor "
        "measures it) and the gearbox's efficiency." + _e(sheet) + "</p>"
        '<table><thead><tr><th class="name">Unit</th><th>Ke, motor shaft [V·s/rad]</th>'
        "<th>Ke×N (Kt if lossless) [N·m/A]</th><th>Kt at the output [N·m/A]</th><th>η = Kt/(Ke×N)</th>"
        "<th>loss torque τ0 [N·m]</th><th>(Ke×N − Kt)/σ</th></tr></thead>"
        f"<tbody>{''.join(rows)}</tbody></table><ul>{''.join(verdicts)}</ul>"
        '<p class="muted">Estimate ± one standard error; the error of η includes those of both constants and of '
        "the arm. N is the catalogue's gear ratio; Ke×N is what an encoder at the output measures directly. See "
        "docs/gearbox.md.</p></section>"
    )


def _bare_motor_part(result: Characterization, unit: str, ratio: float | None) -> str:
    """The split of a unit's Kt/(Ke×N) into the bare motor's Kt/K and the gearbox's η, when the session has
    a curve or stall run of the bare motor (:func:`motorlab.session.efficiency.bare_motor_ratio`); else ""."""
    from motorlab.session.efficiency import bare_motor_ratio, gearbox_split

    spec = result.units[unit]
    eta, k = spec.parameters.get("efficiency"), spec.parameters.get("K")
    if eta is None or not eta.estimate.determined:
        return ""
    found = bare_motor_ratio({name: u.fits for name, u in result.units.items()}, unit,
                             k_output=k.estimate if k is not None else None, ratio=ratio)
    if found is None:
        return (" All of it is given to the gearbox here: a motor curve or a stall run of the bare motor in the "
                "session would tell how much of it the motor's own torque per amp (Kt/K < 1) accounts for.")
    r, where = found
    part = gearbox_split(eta.estimate, r)
    motor_pc, gear_pc = 100 * part["motor_share"], 100 * part["gearbox_share"]
    share = (f" Of the shortfall, {motor_pc:.0f} % is the motor's and {gear_pc:.0f} % the gearbox's (shares of −ln η)."
             if math.isfinite(motor_pc) else "")
    return (f" Split with {where}: the bare motor gives Kt/K = {part['motor']:.3g} ± {part['motor_stderr']:.2g} of its "
            f"back-EMF constant per amp, so the gearbox's own efficiency is η/(Kt/K) = {part['gearbox']:.3g} ± "
            f"{part['gearbox_stderr']:.2g}.{share}"
            + (" An efficiency above 1 is not physical: the bare-motor run is not this motor's, or a calibration "
               "differs." if part["gearbox"] - 2 * part["gearbox_stderr"] > 1 else ""))


def unit_params(unit: UnitResult) -> Any:
    """MotorParams of a unit for its curves (None when K, R or J are missing)."""
    from motorlab.errors import MotorlabError
    from motorlab.model import MotorParams

    values: dict[str, Any] = {}
    for name in ("K", "R", "L", "J", "b", "Tf"):
        combined = unit.parameters.get(name)
        if combined is not None and combined.estimate.determined and math.isfinite(combined.estimate.value):
            values[name] = max(combined.estimate.value, 0.0)
    if not all(k in values for k in ("K", "R")):
        return None
    values.setdefault("J", 1e-6)
    try:
        return MotorParams(**values)
    except MotorlabError:
        return None


def _catalog_motor(result: Characterization) -> Any:
    if not result.session.motor.catalog:
        return None
    from motorlab.catalog import Motor
    from motorlab.errors import MotorlabError

    try:
        return Motor.from_catalog(result.session.motor.catalog)
    except MotorlabError:
        return None


def _curves_section(result: Characterization, *, figures: bool) -> str:
    from motorlab.gearbox import OutputCurves

    motor = _catalog_motor(result)
    voltage = result.session.motor.nominal_voltage or (motor.nominal_voltage if motor is not None else 12.0)
    blocks = []
    rows = []
    catalogue_eta = motor.gearbox().efficiency if motor is not None else 1.0
    eta_notes = []
    for unit in result.units.values():
        model = unit_params(unit)
        if model is None:
            blocks.append(f"<p>{_e(unit.spec.display_name)}: K or R not measured, no curves.</p>")
            continue
        eta_est = unit.parameters.get("efficiency")
        if eta_est is not None and eta_est.estimate.determined and 0 < eta_est.estimate.value <= 1:
            eta = eta_est.estimate.value
        else:
            eta = catalogue_eta
            eta_notes.append(f"{unit.spec.display_name}: gearbox efficiency not measured, the catalogue's "
                             f"η = {eta:.3g} used")
        params = OutputCurves(model, eta)
        peak_p, _ = params.peak_power(voltage)
        rows.append(
            f'<tr><td class="name">{_e(unit.spec.display_name)}</td>'
            f"<td>{params.stall_torque(voltage):.3g}</td><td>{model.free_speed(voltage) * 60 / (2 * math.pi):.4g}</td>"
            f"<td>{model.stall_current(voltage):.3g}</td><td>{model.free_current(voltage):.3g}</td>"
            f"<td>{peak_p:.3g}</td></tr>"
        )
        if figures:
            blocks.append(
                _figure_html(
                    _curves_figure(params, voltage, motor),
                    f"Unit {unit.spec.display_name}",
                    f"motor curves of unit {unit.spec.display_name}",
                )
            )
    if motor is not None:
        rows.append(
            f'<tr class="truth"><td class="name">catalogue</td><td>{motor.stall_torque:.3g}</td>'
            f"<td>{motor.free_speed * 60 / (2 * math.pi):.4g}</td><td>{motor.stall_current:.3g}</td>"
            f"<td>{motor.free_current:.3g}</td><td></td></tr>"
        )
    table = (
        '<table><thead><tr><th class="name">Unit</th><th>stall torque [N·m]</th><th>free speed [rpm]</th>'
        f"<th>stall current [A]</th><th>free current [A]</th><th>peak power [W]</th></tr></thead>"
        f"<tbody>{''.join(rows)}</tbody></table>"
    )
    caption = (
        f"At the nominal {voltage:g} V: torque–speed, current, output power and efficiency of each unit "
        "(solid) against the catalogue's nominal model (dashed); dots mark the published figures "
        "(stall torque, free speed, stall and free current). Torques and powers are at the output shaft, "
        "the gearbox included: η times the motor model's (each unit's measured η; the catalogue's derived "
        f"from its sheet, {catalogue_eta:.3g})." + "".join(f" {n}." for n in eta_notes)
    )
    return (
        f'<section id="curves"><h2>Motor curves at {voltage:g} V</h2>{table}<p class="muted">{_e(caption)}</p>'
        f'<div class="grid">{"".join(blocks)}</div></section>'
    )


def _curves_figure(params: Any, voltage: float, motor: Any) -> Figure | None:
    from motorlab.gearbox import OutputCurves
    from motorlab.plot import plot_motor_curves

    reference = OutputCurves(motor.nominal_params(), motor.gearbox().efficiency) if motor is not None else None
    fig = plot_motor_curves(params, voltage, catalog=reference, size=(6.4, 4.0))
    if motor is not None and fig.axes:
        ax_speed = fig.axes[0]
        ax_speed.plot(
            [0.0, motor.stall_torque], [motor.free_speed, 0.0], "o", color="C0", ms=6, label="published speed"
        )
        if len(fig.axes) > 1:
            fig.axes[1].plot(
                [0.0, motor.stall_torque],
                [motor.free_current, motor.stall_current],
                "s",
                color="C3",
                ms=6,
                label="published current",
            )
    return fig


def _gains_section(result: Characterization, *, figures: bool) -> str:
    gains = result.gains
    if not gains:
        return ""
    text = str(gains.get("text") or "")
    params = gains.get("params") or {}
    used = ", ".join(_with_unit(k, v) for k, v in params.items() if isinstance(v, int | float))
    body = (
        f"<p>For the {_e(gains.get('motor', 'motor'))} ({_e(used)}) at {_e(gains.get('voltage', ''))} V, "
        "WPILib SysId's LQR defaults (velocity and position loops, 20 ms period):</p>"
        f"<pre>{_e(text)}</pre>"
    )
    fig = gains_figure(result) if figures else None
    if fig is not None:
        body += _figure_html(
            fig, "Closed-loop step responses with these gains (nonlinear motor model)", "step response"
        )
    return f'<section id="gains"><h2>Controller gains</h2>{body}</section>'


def _with_unit(name: str, value: float) -> str:
    """``"L = 661.4 µH"``: a motor parameter in the report's display unit (SI, inductance in µH)."""
    from motorlab.units import SI_UNITS

    unit, scale = DISPLAY_UNITS.get(name, (format_unit(SI_UNITS.get(name, "")), 1.0))
    shown = value * scale
    text = f"{shown:.4g}"
    if shown != 0 and not 1e-3 <= abs(shown) < 1e6:  # 2.5 × 10⁻⁵, as the page writes it
        mantissa, exponent = f"{shown:.3e}".split("e")
        text = f"{float(mantissa):g} × {power_of_ten(int(exponent))}"
    return f"{name} = {text} {unit}".rstrip()


def gains_figure(result: Characterization) -> Figure | None:
    """The step responses of the session's gains, drawn once (when :func:`characterize` did not draw them)."""
    gains = result.gains or {}
    if gains.get("figure") is None and gains.get("results"):
        from motorlab.control.tune import summary_figure

        gains["figure"] = summary_figure(gains["results"])
    fig = gains.get("figure")
    return fig if isinstance(fig, Figure) else None


def _short(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:.4g}"
    return str(value)


def _unit_section(unit: UnitResult, *, figures: bool) -> str:
    parts = [f'<section class="unit" id="unit-{_e(unit.name)}"><h2>Unit {_e(unit.spec.display_name)}</h2>']
    if unit.spec.notes:
        parts.append(f"<p>{_e(unit.spec.notes)}</p>")
    for exp, why in unit.failures.items():
        parts.append(f'<p class="warn"><b>{_e(exp)}</b> failed: {_e(why)}</p>')
    for exp, fit in unit.fits.items():
        parts.append(_fit_block(exp, fit, figures=figures))
    parts.append("</section>")
    return "".join(parts)


def _fit_block(experiment: str, fit: FitResult, *, figures: bool) -> str:
    rows = []
    for name, est in fit.parameters.items():
        pct = est.relative_error
        rows.append(
            f'<tr><td class="name">{_e(name)}</td><td>{_e(_estimate_cell(est, name))}</td>'
            f"<td>{_e(_display_unit(name, est.unit))}</td>"
            f"<td>{'—' if not math.isfinite(pct) else f'{100 * pct:.2g} %'}</td>"
            f'<td class="name muted">{_e(est.note)}</td></tr>'
        )
    stats = [f"{fit.n_points} points"]
    if math.isfinite(fit.rmse):
        stats.append(f"residual RMS {fit.rmse:.3g} {format_unit(fit.rmse_unit)}")
    if math.isfinite(fit.r2):
        stats.append(f"R² = {fit.r2:.5f}")
    correlations = fit.correlations(0.5)
    if correlations:
        stats.append("correlations " + ", ".join(f"C({a}, {b}) = {c:+.2f}" for a, b, c in correlations[:4]))
    if isinstance(fit.details.get("shaft"), str):
        stats.append(f"shaft: {fit.details['shaft']}")
    warnings = "".join(f"<li>{_e(w)}</li>" for w in fit.warnings)
    files = ", ".join(Path(s).name for src in fit.sources for s in src.split(" + "))
    figure = ""
    if figures and fit.panels:
        figure = _figure_html(
            _fit_figure(fit), f"{experiment}: data against the fitted model, residuals beneath", f"{experiment} fit"
        )
    return (
        f"<h3>{_e(experiment)}</h3>"
        f'<p class="muted">{_e(" · ".join(stats))}{" · files: " + _e(files) if files else ""}</p>'
        '<table><thead><tr><th class="name">parameter</th><th>value ± stderr</th><th>unit</th><th>rel.</th>'
        f'<th class="name">note</th></tr></thead><tbody>{"".join(rows)}</tbody></table>'
        f"{f'<ul class=warn>{warnings}</ul>' if warnings else ''}{figure}"
    )


def _fit_figure(fit: FitResult) -> Figure | None:
    from motorlab.plot import plot_fit

    return plot_fit(fit)


def _methods_section() -> str:
    equations = [
        "L·di/dt = V − R·i − K·ω   (4) of seed 1",
        "J·dω/dt = K·i − b·ω − Tf·sgn(ω)   (3) plus Coulomb friction; at rest the shaft stays at rest while |K·i| ≤ Tf",
        "τ = K·i, e = K·ω   (1), (2): Kt = Ke = K in SI units",
        "spin-down (relay open, i = 0): J·dω/dt = −b·ω − Tf and V = K·ω, position fitted directly",
        "free spin-up at constant current: θ = θ0 + ω0·t + ½·α·t² with α = (K·I − Tf)/J (exact solution "
        "with b when it is known)",
        "terminal velocity: K·I = b·ω + Tf, so b = (K·I − Tf)/ω",
        "LCR: R_ac = 2π·f·L/Q (seed); the model's R is the DC resistance",
        "combination: the determined estimate with the smallest standard error wins; two sources disagree "
        "when |a − b| > 3·√(σa² + σb²); K's standard error is propagated into the analyses that use it",
        "fleet: z = (ln x − median ln x)/√(s² + (σ/x)²), s = the healthy spread below five units, "
        "max(1.4826·MAD(ln x), healthy spread) from five on; "
        "|z| > threshold stands out (Iglewicz & Hoaglin's modified z-score)",
    ]
    mistakes = [
        "Free spin-up: the seed fits P = P0 + K·I·(t − t0)²/J, which omits the ½ of "
        "P = P0 + ½·α·t²; its J comes out twice the true value. motorlab fits θ0 + ω0·t + ½·α·t².",
        "Terminal velocity: the seed's ω = Ke·J/b is dimensionally wrong (and step 3 then divides by ω). "
        "The steady state of (3) is K·I = b·ω + Tf, so b = (K·I − Tf)/ω.",
        "Spin-down: the pure exponential P(∞) − B·e^(−γ(t−30)) ignores Coulomb friction, which then "
        "inflates b; motorlab fits viscous and Coulomb friction together and compares the models.",
        "Velocity was differentiated from the fitted position and smoothed; motorlab fits position (and the "
        "bus voltage) directly, so quantisation and differentiation noise do not bias the estimates.",
        "The 15-point average of the bus voltage biases K where the speed changes within the window and is "
        "unnecessary: the raw samples are fitted with their noise estimated from the data.",
        "Flywheel: the seed's 0.0124 kg·m² for a steel disc r = 0.075 m, h = 0.05 m is r⁴·ρ·h without the "
        "factor π/2; J = ½·π·r⁴·ρ·h = 0.0195 kg·m². motorlab computes J from the session's disc.",
        "The seed's table gives single numbers; every estimate here carries a standard error, and a "
        "parameter the data cannot determine is reported as such.",
    ]
    eq_html = "".join(f'<span class="eq">{_e(eq)}</span>' for eq in equations)
    mistakes_html = "".join(f"<li>{_e(m)}</li>" for m in mistakes)
    return (
        '<section id="methods"><h2>Methods</h2>'
        "<p>Model (SI units, all quantities at the output shaft whose encoder is counted):</p>"
        f"{eq_html}"
        "<h3>The seed's mistakes that motorlab corrects</h3>"
        f"<ol>{mistakes_html}</ol>"
        '<p class="muted">Seed 1: “Characterizing FTC-Legal Motors” (Dynamometer Project 2017–2018); '
        "seed 2: MIT 2.010 Lab 2.</p></section>"
    )


def image_sources(document: str) -> Iterable[str]:
    """The ``src`` of every ``<img>`` of an HTML document (used by tests and the render script)."""
    from html.parser import HTMLParser

    found: list[str] = []

    class _Images(HTMLParser):
        def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
            if tag == "img":
                found.extend(v or "" for k, v in attrs if k == "src")

    parser = _Images()
    parser.feed(document)
    parser.close()
    return found
