"""A whole characterisation session simulated on the virtual dynamometer, described in TOML.

:func:`write_simulated_session` draws units around a catalogue motor, runs every experiment of
:data:`SIMULATED_EXPERIMENTS` on each (the descriptions' :class:`~motorlab.experiments.RigRun`) and
writes the session file :func:`motorlab.session.spec.load_session` reads (docs/session.md).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

from motorlab.errors import OptionError
from motorlab.experiments import all_experiments
from motorlab.io.output import write_text_atomic
from motorlab.session.spec import toml_string

#: Experiments of a simulated session: session key -> (rig experiment, file name, rig settings), in
#: the order the rig runs them (from the descriptions' :class:`~motorlab.experiments.RigRun`).
SIMULATED_EXPERIMENTS: tuple[tuple[str, str, str, dict[str, Any]], ...] = tuple(
    (name, exp.rig.experiment, exp.rig.file, dict(exp.rig.settings))
    for name, exp in sorted(all_experiments().items(), key=lambda item: item[1].rig.order if item[1].rig else 0)
    if exp.rig is not None
)


def write_simulated_session(
    motor_key: str,
    *,
    out_dir: str | Path,
    units: int = 3,
    seed: int = 0,
    degrade: Mapping[str, Mapping[str, float]] | None = None,
    spread: Any = None,
    experiments: Iterable[str] | None = None,
    gearbox: str | float | None = None,
) -> Path:
    """Simulate a whole characterisation session on the virtual dynamometer and describe it in TOML.

    Parameters
    ----------
    motor_key
        Catalogue key or name of the motor (``"neverest40"``).
    out_dir
        Folder to write: ``session.toml`` and one folder per unit (``A/``, ``B/`` …) holding the
        data files and the rig's ``truth.json``.
    units
        Number of units (1 to 26).
    seed
        Fleet seed: unit k's parameters are drawn with unit seed ``1000·seed + k`` and the
        instrument noise uses ``seed``; the same seed gives the same session.
    degrade
        Factors applied to a unit's true parameters, e.g. ``{"B": {"b": 2.0}}`` for a unit with
        doubled viscous friction (a worn gearbox) [-].
    spread
        A :class:`motorlab.rig.units.UnitSpread` for the draw (default: the rig's); when given,
        the session's ``[fleet.spread]`` is set to it so the outlier test uses the same spreads.
    experiments
        Session keys of the experiments to run (default: every one of
        :data:`SIMULATED_EXPERIMENTS`).
    gearbox
        ``"catalog"``: each unit's gearbox drawn around the catalogue's figures
        (:meth:`motorlab.catalog.Motor.gearbox`, :func:`motorlab.rig.units.draw_gearbox`); a number:
        that efficiency η for every unit (the catalogue's drag); ``None``: an ideal gearbox. A
        ``degrade`` factor ``"efficiency"`` scales a unit's η (a worn gearbox).

    Returns
    -------
    Path
        The ``session.toml`` written.

    Raises
    ------
    OptionError
        Unknown motor, a number of units out of range, an unknown unit or parameter in
        ``degrade``, a non-positive factor, an unknown experiment.
    """
    from motorlab.catalog import Motor
    from motorlab.rig.flywheel import Flywheel

    motor = Motor.from_catalog(motor_key)
    names, degrade, plan = _checked_request(units, seed, degrade, experiments)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    flywheel = Flywheel()
    lines = _session_lines(motor, units, seed, degrade, flywheel, spread)
    for k, name in enumerate(names):
        lines += _unit_lines(motor, k, name, seed=seed, degrade=degrade, spread=spread, gearbox=gearbox,
                             flywheel=flywheel, plan=plan, out=out)
    path = out / "session.toml"
    write_text_atomic(path, "\n".join(lines) + "\n")
    return path


def _checked_request(
    units: int, seed: int, degrade: Mapping[str, Mapping[str, float]] | None, experiments: Iterable[str] | None
) -> tuple[list[str], dict[str, dict[str, float]], list[tuple[str, str, str, dict[str, Any]]]]:
    """The unit names, the degrade factors and the experiments to run, each checked."""
    from motorlab.rig.units import unit_name

    if not (isinstance(units, int) and 1 <= units <= 26):
        raise OptionError(f"units must be a whole number from 1 to 26, got {units!r}")
    if not (isinstance(seed, int) and seed >= 0):
        raise OptionError(f"seed must be a whole number ≥ 0, got {seed!r}")
    names = [unit_name(k) for k in range(units)]
    factors_by_unit = {k: dict(v) for k, v in (degrade or {}).items()}
    for unit, factors in factors_by_unit.items():
        if unit not in names:
            raise OptionError(f"degrade: no unit {unit!r} in a session of {units} unit(s)")
        for name, factor in factors.items():
            if name not in ("K", "R", "L", "J", "b", "Tf", "efficiency"):
                raise OptionError(f"degrade: unknown parameter {name!r} (K, R, L, J, b, Tf, efficiency)")
            if not (isinstance(factor, int | float) and math.isfinite(factor) and factor > 0):
                raise OptionError(f"degrade: factor of {unit}.{name} must be positive, got {factor!r}")
    known = [e[0] for e in SIMULATED_EXPERIMENTS]
    chosen = known if experiments is None else list(experiments)
    for name in chosen:
        if name not in known:
            raise OptionError(f"unknown simulated experiment {name!r}; known: {', '.join(known)}")
    return names, factors_by_unit, [e for e in SIMULATED_EXPERIMENTS if e[0] in chosen]


#: The simulated scale's lever arm [m].
LEVER_ARM = 0.15


def _session_lines(motor: Any, units: int, seed: int, degrade: Mapping[str, Mapping[str, float]], flywheel: Any,
                   spread: Any) -> list[str]:
    """The session file's tables before the units: session, motor, rig (flywheel, supply), fleet."""
    lines = [
        "# motorlab session: simulated on the virtual dynamometer (motorlab simulate session).",
        "# Relative file names are resolved against this file's folder; see docs/session.md.",
        "",
        "[session]",
        f"title = {toml_string(f'{motor.name}: {units} simulated unit(s), seed {seed}')}",
        f"notes = {toml_string(_degrade_note(degrade) or 'healthy units drawn around the catalogue figures')}",
        "",
        "[motor]",
        f"catalog = {toml_string(motor.key)}",
        "",
        "[rig]",
        f'lever_arm = "{LEVER_ARM:g} m"',
        "",
        "[rig.flywheel]",
        f"# steel disc r = {1e3 * flywheel.disc.radius:g} mm, h = {1e3 * flywheel.disc.thickness:g} mm "
        f"plus the gears at the flywheel shaft",
        f'inertia = "{flywheel.inertia:.8g} kg*m^2"',
        f"ratio = {flywheel.ratio:g}",
        "",
        "[rig.supply]",
        'voltage_limit = "18 V"',
        'current_limit = "4 A"',
    ]
    if spread is not None:
        lines += ["", "[fleet.spread]"] + [f"{k} = {v:g}" for k, v in spread.to_dict().items()]
    return lines


Plan = list[tuple[str, str, str, dict[str, Any]]]


def _unit_lines(motor: Any, k: int, name: str, *, seed: int, degrade: Mapping[str, Mapping[str, float]],
                spread: Any, gearbox: str | float | None, flywheel: Any, plan: Plan, out: Path) -> list[str]:
    """Draw unit ``k``, run the planned experiments on it into ``out/name`` and return its tables."""
    from motorlab.rig.units import draw_unit
    from motorlab.rig.virtual import VirtualRig

    params = draw_unit(motor, 1000 * seed + k, spread=spread)  # type: ignore[arg-type]  # rig protocol wants a settable key
    factors = dict(degrade.get(name, {}))
    box = _unit_gearbox(motor, gearbox, 1000 * seed + k, factors.pop("efficiency", 1.0))
    if factors:
        params = params.scaled(**{p: getattr(params, p) * f for p, f in factors.items()})
    if box.loss_torque > 0:  # the drawn unit runs free at the catalogue's current, gearbox drag included
        params = params.scaled(Tf=max(params.Tf - box.loss_torque / box.efficiency, 0.0))
    rig = VirtualRig(motor, unit_seed=k, noise_seed=seed, params=params, flywheel=flywheel, gearbox=box)
    folder = out / name
    folder.mkdir(exist_ok=True)
    truth = folder / "truth.json"
    if truth.exists():
        truth.unlink()  # a fresh session: the rig adds runs to an existing truth file
    lines = ["", f"[units.{name}]", f'truth = "{name}/truth.json"']
    if name in degrade:
        lines.append(f"notes = {toml_string(_degrade_note({name: degrade[name]}))}")
    for key, experiment, filename, settings in plan:
        run = rig.run(experiment, folder / filename, **settings)
        files = ", ".join(toml_string(f"{name}/{p.name}") for p in run.paths)
        lines += ["", f"[units.{name}.{key}]", f"files = [{files}]"]
        if key == "free-spinup":
            lines.append(f'current = "{settings["current"]:g} A"')
    return lines


def _unit_gearbox(motor: Any, gearbox: str | float | None, unit_seed: int, factor: float) -> Any:
    """The gearbox of one simulated unit (see :func:`write_simulated_session`)."""
    from dataclasses import replace

    from motorlab.gearbox import Gearbox
    from motorlab.rig.units import draw_gearbox

    if gearbox is None:
        box = Gearbox(ratio=motor.gear_ratio)
    elif gearbox == "catalog":
        box = draw_gearbox(motor.key, motor.gearbox(), unit_seed)
    elif isinstance(gearbox, int | float) and 0 < gearbox <= 1:
        box = replace(motor.gearbox(), efficiency=float(gearbox))
    else:
        raise OptionError(f"gearbox must be 'catalog', an efficiency in (0, 1] or None, got {gearbox!r}")
    return replace(box, efficiency=min(box.efficiency * factor, 1.0))


def _degrade_note(degrade: Mapping[str, Mapping[str, float]]) -> str:
    parts = [
        f"unit {unit}: " + ", ".join(f"{p} × {f:g}" for p, f in factors.items())
        for unit, factors in degrade.items()
        if factors
    ]
    return ("deliberately degraded: " + "; ".join(parts)) if parts else ""
