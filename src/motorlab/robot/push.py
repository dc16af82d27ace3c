"""``motorlab robot push``: the gains of a fit, in a target's units, into the robot's ``@Config`` fields.

The gains come from :func:`motorlab.control.tune.tune` exactly as ``motorlab tune --target … --emit``
computes them (same plant from ``--params``, same units from ``--cpr`` and ``--wheel-radius``), so the
numbers written are the numbers the pasted code would hold. The sequence (:func:`apply`):

1. read the tree (``GET_CONFIG``) and the robot status (``GET_ROBOT_STATUS``);
2. refuse while an OpMode is initialised or running, unless the caller says the person confirmed it;
3. keep the old values in the state file, before anything is written;
4. ``SAVE_CONFIG`` with only those leaves; read the tree back; check the new values and that no other
   leaf moved.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from motorlab.robot import RobotLinkError
from motorlab.robot.config import (
    TARGET_FIELDS,
    Change,
    diff_tree,
    load_state,
    plan,
    save_state,
    target_paths,
    verify,
)
from motorlab.robot.dashboard import Dashboard, is_idle

#: What ``push`` says about the values' lifetime.
LIFETIME = ("values written through FTC Dashboard live until the robot controller app restarts: paste the code "
            "below into your robot code to keep them")


@dataclass
class TargetValues:
    """The gains a target takes from a fit (full precision: what is written), the code to paste, the tune
    notes, and for people each gain's unit and, where the fit gives it, its standard error (same unit)."""

    values: dict[str, float]
    snippet: str
    notes: list[str]
    units: dict[str, str] = field(default_factory=dict)
    stderr: dict[str, float] = field(default_factory=dict)


@dataclass
class PushPlan:
    """What would be written: the changes, the code to paste, the robot's state, the tune result."""

    target: str
    changes: list[Change]
    snippet: str
    running: str | None
    notes: list[str] = field(default_factory=list)
    units: dict[str, str] = field(default_factory=dict)
    stderr: dict[str, float] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        """The plan as JSON; each change with its gain's ``unit`` and ``stderr`` (null when the fit gives none)."""
        changes = [{**c.to_dict(), "unit": self.units.get(c.name, ""), "stderr": self.stderr.get(c.name)}
                   for c in self.changes]
        return {"target": self.target, "changes": changes, "snippet": self.snippet,
                "running": self.running, "notes": list(self.notes), "lifetime": LIFETIME}


def target_values(params: list[str], target: str, *, cpr: float | None = None, wheel_radius: float | None = None,
                  unit: str | None = None, voltage: float = 12.0, loop: str = "position",
                  language: str = "java") -> TargetValues:
    """The gains ``target`` takes from the fit in ``params``, the code to paste, and the tune notes.

    ``roadrunner``: ``kS`` [V], ``kV`` [V·s/tick], ``kA`` [V·s²/tick] (``cpr`` required, as for
    ``motorlab tune --target roadrunner``); ``pedro``: the constants the fit determines; ``ftc-pidf``:
    the hub's ``p, i, d, f`` for a velocity loop. kS, kV and kA carry the fit's standard errors, converted
    as the values are (a change of unit is a factor: kV per tick = kV per rad × 2π/cpr, and so its error).
    """
    from motorlab.control.emit import emit_snippet
    from motorlab.control.plant import MechanismUnits, load_plant
    from motorlab.control.tune import DesignRequest, tune

    if target not in TARGET_FIELDS:
        raise RobotLinkError(f"unknown target {target!r}: roadrunner, pedro or ftc-pidf")
    units = MechanismUnits.from_options("rad", cpr=cpr, wheel_radius=wheel_radius)
    plant = load_plant([Path(p) for p in params], unit=unit)
    result = tune(plant, DesignRequest("velocity" if target == "ftc-pidf" else loop, target=target, units=units,
                                       voltage=voltage))
    tg = result.target
    numbers = {**tg.feedforward, **tg.gains}
    values = {g: float(numbers[g]) for g in TARGET_FIELDS[target] if g in numbers}
    if not values:
        raise RobotLinkError(f"the fit in {', '.join(params)} gives none of {target}'s gains")
    si = plant.feedforward.to_dict()
    stderr = {g: abs(values[g] / si[g]) * plant.stderr[g] for g in values
              if g in plant.stderr and si.get(g)}
    return TargetValues(values, emit_snippet(tg, language), list(tg.notes),
                        {g: tg.units.get(g, "") for g in values}, stderr)


def prepare(dash: Dashboard, target: str, gains: TargetValues, overrides: list[str] | None = None) -> PushPlan:
    """Read the robot's tree and status and plan the write of ``gains`` (nothing is written)."""
    values = gains.values
    tree = dash.config()
    paths = target_paths(tree, target, values, overrides)
    changes = plan(tree, paths, values)
    status = dash.status()
    running = None if is_idle(status) else f"{status.get('activeOpMode')} ({status.get('activeOpModeStatus')})"
    notes = [f"{g}: not on the robot, not written" for g in values if g not in paths]
    return PushPlan(target, changes, gains.snippet, running, notes, gains.units, gains.stderr)


def apply(dash: Dashboard, push_plan: PushPlan, state: Path, *, while_running: bool = False,
          address: str = "") -> dict[str, Any]:
    """Write the planned leaves, verify them, keep the old values in ``state``; the tree read back."""
    status = dash.status()
    if not is_idle(status) and not while_running:
        raise RobotLinkError(f"an OpMode is active on the robot ({status.get('activeOpMode')}, "
                             f"{status.get('activeOpModeStatus')}): stop it first, or confirm writing while it runs "
                             "(--while-running)")
    before = dash.config()
    fresh = plan(before, {c.name: c.path for c in push_plan.changes}, {c.name: c.new for c in push_plan.changes})
    save_state(state, address or dash.address, push_plan.target, fresh)
    after = dash.save_config(diff_tree(fresh))
    push_plan.notes.extend(verify(before, after, fresh))
    return after


def restore(dash: Dashboard, state: Path, *, while_running: bool = False,
            confirm: Callable[[list[Change]], bool] | None = None) -> list[Change]:
    """Put back the old values a push kept in ``state``; the changes undone."""
    changes = load_state(state)
    status = dash.status()
    if not is_idle(status) and not while_running:
        raise RobotLinkError(f"an OpMode is active on the robot ({status.get('activeOpMode')}): stop it first, or "
                             "confirm with --while-running")
    before = dash.config()
    target_paths(before, "restore", {c.name: c.new for c in changes}, [f"{c.name}={c.path}" for c in changes])
    if confirm is not None and not confirm(changes):
        raise RobotLinkError("nothing restored (not confirmed)")
    after = dash.save_config(diff_tree(changes, old=True))
    verify(before, after, changes, old=True)
    return changes


def state_path(params: list[str] | None, state: str | os.PathLike[str] | None) -> Path:
    """``--state`` if given, else ``FIT.robot-push.json`` next to the first ``--params`` file."""
    from motorlab.robot.config import default_state_path

    if state is not None:
        return Path(state)
    if not params:
        raise RobotLinkError("give --params FIT.json (the old values are kept next to it) or --state FILE")
    return default_state_path(params[0])
