"""Write fitted gains into the robot's ``@Config`` fields through FTC Dashboard, check them, undo them.

The tree is FTC Dashboard's (``DashboardCore/.../config/variable/ConfigVariableSerializer.java``,
``CustomVariable.java``, ``VariableType.java``; ``FtcDashboard.java`` ``addConfigClasses``): one top-level
node per ``@Config`` class, named by its simple name (or ``@Config("name")``), holding its public static
non-final fields; an object field (Road Runner's ``PARAMS``) is a node of its public fields. A path
here is the dotted names from the root: ``MecanumDrive.PARAMS.kS``.

Where each target's gains go (the fields' names read from the projects' sources):

* ``roadrunner``: road-runner-quickstart ``MecanumDrive.java`` (``@Config``, ``public static Params
  PARAMS``, ``kS``, ``kV``, ``kA`` "in tick units"), else ``TankDrive.PARAMS`` (same fields);
* ``pedro``: Pedro-Pathing/PedroPathing ``MecanumConstants`` (``xVelocity``, ``yVelocity``,
  ``staticFrictionCoefficient``) and ``FollowerConstants`` (``forwardZeroPowerAcceleration``,
  ``lateralZeroPowerAcceleration``), found by name anywhere in the tree (the quickstart's ``Constants``
  class needs ``@Config`` for Dashboard to see them);
* ``ftc-pidf``: a ``PIDFCoefficients`` field (FTC SDK: public ``p``, ``i``, ``d``, ``f``), the one node
  of the tree that has all four, or the one ``--config`` names.

Values written this way change the running robot controller app's fields only: they are lost when the
app restarts, so the code to paste is printed as well.
"""

from __future__ import annotations

import json
import math
import os
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from motorlab.robot import RobotLinkError

#: Targets ``push`` knows, and the gains each writes (name in motorlab's target -> leaf name).
TARGET_FIELDS: dict[str, dict[str, str]] = {
    "roadrunner": {"kS": "kS", "kV": "kV", "kA": "kA"},
    "pedro": {"xVelocity": "xVelocity", "yVelocity": "yVelocity",
              "staticFrictionCoefficient": "staticFrictionCoefficient",
              "forwardZeroPowerAcceleration": "forwardZeroPowerAcceleration",
              "lateralZeroPowerAcceleration": "lateralZeroPowerAcceleration"},
    "ftc-pidf": {"kP": "p", "kI": "i", "kD": "d", "kF": "f"},
}
#: Leaf types a number can be written to, and the relative precision the read-back must match.
NUMERIC_TYPES = {"double": 1e-12, "float": 1e-6}


@dataclass(frozen=True)
class Change:
    """One leaf to write: the gain's name, its path, the leaf's type, the value there now and the new one."""

    name: str
    path: str
    type: str
    old: Any
    new: float

    def to_dict(self) -> dict[str, Any]:
        return {"name": self.name, "path": self.path, "type": self.type, "old": self.old, "new": self.new}


def leaves(tree: dict[str, Any], prefix: str = "") -> dict[str, tuple[str, Any]]:
    """Every leaf of a config tree: dotted path -> (type, value)."""
    out: dict[str, tuple[str, Any]] = {}
    if tree.get("__type") != "custom":
        out[prefix] = (str(tree.get("__type")), tree.get("__value"))
        return out
    children = tree.get("__value") or {}
    if isinstance(children, dict):
        for name, child in children.items():
            if isinstance(child, dict):
                out.update(leaves(child, f"{prefix}.{name}" if prefix else name))
    return out


def _nodes(tree: dict[str, Any], prefix: str = "") -> dict[str, dict[str, Any]]:
    out: dict[str, dict[str, Any]] = {}
    children = tree.get("__value") if tree.get("__type") == "custom" else None
    if isinstance(children, dict):
        out[prefix] = children
        for name, child in children.items():
            if isinstance(child, dict):
                out.update(_nodes(child, f"{prefix}.{name}" if prefix else name))
    return out


def _roadrunner_paths(tree: dict[str, Any]) -> dict[str, str]:
    flat = leaves(tree)
    for drive in ("MecanumDrive", "TankDrive"):
        paths = {g: f"{drive}.PARAMS.{g}" for g in TARGET_FIELDS["roadrunner"]}
        if all(p in flat for p in paths.values()):
            return paths
    raise RobotLinkError("the robot's @Config tree has no MecanumDrive.PARAMS.kS, kV, kA (nor TankDrive.PARAMS): "
                         "keep @Config on the quickstart's drive class, or name the fields with "
                         "--config kS=CLASS.FIELD.kS (and kV=, kA=)")


def _by_name(tree: dict[str, Any], wanted: dict[str, float]) -> dict[str, str]:
    flat = leaves(tree)
    paths: dict[str, str] = {}
    for gain in wanted:
        leaf = TARGET_FIELDS["pedro"][gain]
        found = [p for p in flat if p.rsplit(".", 1)[-1] == leaf]
        if len(found) > 1:
            raise RobotLinkError(f"the robot's @Config tree has {leaf} in {len(found)} places ({', '.join(found)}): "
                                 f"name the one to write with --config {gain}=PATH")
        if found:
            paths[gain] = found[0]
    if not paths:
        raise RobotLinkError("the robot's @Config tree has none of Pedro's constants (xVelocity, "
                             "staticFrictionCoefficient, forwardZeroPowerAcceleration …): add @Config to the "
                             "class holding MecanumConstants and FollowerConstants, or name them with --config")
    return paths


def _pidf_paths(tree: dict[str, Any], node: str | None) -> dict[str, str]:
    nodes = _nodes(tree)
    if node is not None:
        if node not in nodes:
            raise RobotLinkError(f"the robot's @Config tree has no {node}: check the --config path")
        candidates = [node]
    else:
        candidates = [p for p, children in nodes.items() if {"p", "i", "d", "f"} <= set(children)]
    if len(candidates) != 1:
        what = "no" if not candidates else f"{len(candidates)} ({', '.join(candidates)})"
        raise RobotLinkError(f"the robot's @Config tree has {what} PIDF coefficients (a node with p, i, d, f): "
                             "make the PIDFCoefficients a public static field of a @Config class, and name it "
                             "with --config CLASS.FIELD when there are several")
    return {g: f"{candidates[0]}.{leaf}" for g, leaf in TARGET_FIELDS["ftc-pidf"].items()}


def target_paths(tree: dict[str, Any], target: str, values: dict[str, float],
                 overrides: list[str] | None = None) -> dict[str, str]:
    """Gain name -> leaf path for ``target``, with ``--config NAME=PATH`` (or a node ``PATH``) overrides."""
    explicit: dict[str, str] = {}
    node: str | None = None
    for item in overrides or []:
        name, sep, path = item.partition("=")
        if sep:
            if name not in values:
                raise RobotLinkError(f"--config {item}: {name!r} is not a gain of target {target} "
                                     f"(gains: {', '.join(values)})")
            explicit[name] = path.strip()
        else:
            node = item.strip()
    if node is not None and target != "ftc-pidf":
        explicit.update({g: f"{node}.{TARGET_FIELDS[target][g]}" for g in values})
    if target == "roadrunner" and not explicit:
        paths = _roadrunner_paths(tree)
    elif target == "pedro" and not explicit:
        paths = _by_name(tree, values)
    elif target == "ftc-pidf" and not explicit:
        paths = _pidf_paths(tree, node)
    else:
        paths = dict(explicit)
    flat = leaves(tree)
    for gain, path in paths.items():
        if path not in flat:
            raise RobotLinkError(f"the robot's @Config tree has no {path} (for {gain}): check the name, and that "
                                 "its class has @Config and the field is public static")
    return paths


def plan(tree: dict[str, Any], paths: dict[str, str], values: dict[str, float]) -> list[Change]:
    """The leaves to write: old and new values side by side; refuses a leaf that is not a number."""
    flat = leaves(tree)
    changes = []
    for gain, path in paths.items():
        kind, old = flat[path]
        if kind not in NUMERIC_TYPES:
            raise RobotLinkError(f"{path} on the robot is a {kind}, not a double or float: motorlab writes numbers "
                                 "only; make the field a double")
        value = float(values[gain])
        if not math.isfinite(value):
            raise RobotLinkError(f"{gain} = {value} is not a finite number: nothing written")
        changes.append(Change(gain, path, kind, old, value))
    return changes


def diff_tree(changes: list[Change], *, old: bool = False) -> dict[str, Any]:
    """The ``SAVE_CONFIG`` diff: only these leaves and their parents (as the browser's ``validAndModified``)."""
    root: dict[str, Any] = {"__type": "custom", "__value": {}}
    for change in changes:
        node = root
        parts = change.path.split(".")
        for part in parts[:-1]:
            node = node["__value"].setdefault(part, {"__type": "custom", "__value": {}})
        node["__value"][parts[-1]] = {"__type": change.type, "__value": change.old if old else change.new}
    return root


def _close(a: Any, b: float, kind: str) -> bool:
    try:
        x = float(a)
    except (TypeError, ValueError):
        return False
    return x == b or abs(x - b) <= NUMERIC_TYPES.get(kind, 1e-12) * max(abs(x), abs(b))


def verify(before: dict[str, Any], after: dict[str, Any], changes: list[Change], *, old: bool = False) -> list[str]:
    """The read-back tree holds the new values (else :class:`RobotLinkError`); other leaves that moved, named."""
    flat_before, flat_after = leaves(before), leaves(after)
    for change in changes:
        want = change.old if old else change.new
        got = flat_after.get(change.path, (None, None))[1]
        if not _close(got, float(want), change.type):
            raise RobotLinkError(f"{change.path} reads back as {got!r}, not {want!r}: the robot did not take the "
                                 "value (an OpMode that sets it? a final field?); check it in FTC Dashboard")
    written = {c.path for c in changes}
    moved = [p for p in flat_before if p not in written and flat_after.get(p) != flat_before[p]]
    if moved:  # not motorlab's doing (it sent only its leaves): an OpMode or another client changes them
        return [f"other fields changed on the robot meanwhile ({', '.join(moved[:5])}): not motorlab's writing "
                "(an OpMode or another Dashboard client?); check them in FTC Dashboard"]
    return []


def save_state(path: Path, address: str, target: str, changes: list[Change]) -> None:
    """Keep the old values (before anything is written) for ``--restore``, through a temporary file."""
    path.parent.mkdir(parents=True, exist_ok=True)
    state = {"format": "motorlab-robot-push", "version": 1, "robot": address, "target": target,
             "changes": [c.to_dict() for c in changes]}
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".part", dir=path.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as out:
            json.dump(state, out, indent=2)
            out.write("\n")
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def load_state(path: Path) -> list[Change]:
    """The changes a previous push kept in ``path``."""
    try:
        state = json.loads(path.read_text(encoding="utf-8"))
        if state.get("format") != "motorlab-robot-push":
            raise ValueError("not a push state file")
        return [Change(c["name"], c["path"], c["type"], c["old"], float(c["new"])) for c in state["changes"]]
    except FileNotFoundError:
        raise RobotLinkError(f"{path}: no old values kept there (nothing pushed with this --params or --state?)"
                             ) from None
    except (ValueError, KeyError, TypeError) as exc:
        raise RobotLinkError(f"{path}: not a motorlab push state file ({exc})") from None


def default_state_path(params: str | os.PathLike[str]) -> Path:
    """Where ``push`` keeps the old values by default: next to the fit, ``FIT.robot-push.json``."""
    p = Path(params)
    return p.with_name(p.stem + ".robot-push.json")
