"""Session descriptions: one TOML file naming the motor, the rig and, per unit, the files of each experiment.

A person writes a session in minutes (see ``examples/session.toml`` and ``docs/session.md``)::

    [session]
    title = "NeveRest 40 fleet, March 2018"

    [motor]
    catalog = "neverest40"            # or name + counts_per_revolution + gear_ratio

    [rig]
    lever_arm = "0.20 m"
    [rig.flywheel]
    inertia = "0.0124 kg*m^2"         # or disc = { radius = ..., thickness = ..., material = ... }
    ratio = 25                        # flywheel turns per motor-shaft turn
    [rig.supply]
    voltage_limit = "18 V"
    current_limit = "4 A"

    [units.A.spindown]
    files = ["A/spindown.txt"]
    [units.A.free-spinup]
    files = ["A/free_spinup.csv"]
    current = "0.5 A"

:func:`load_session` parses and validates the whole description before any analysis runs: every
file must exist, every key must be known, every quantity must have the right dimension, and
contradictory settings (a flywheel given both as an inertia and as a disc, a current above the
supply's limit) are refused. Errors are :class:`~motorlab.errors.SessionError` naming the file,
the line and the key.

Line numbers
------------
``tomllib`` reports line numbers for syntax errors only. For semantic errors the key's line is
found by a small scan of the text (:func:`key_lines`): it follows ``[table]`` / ``[[array]]``
headers, records every ``key = value`` (dotted and quoted keys included, and the keys of inline
tables on the same line), and skips multi-line strings. A key that cannot be found falls back to
the line of its nearest enclosing table.
"""

from __future__ import annotations

import difflib
import json
import math
import re
import tomllib
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from motorlab.errors import InputError, MotorlabError, OptionError, SessionError
from motorlab.experiments import all_experiments, exclude_hint
from motorlab.io.text import (
    MAX_INTEGER_DIGITS,
    MAX_NESTING,
    deep_nesting_line,
    line_of_offset,
    load_json,
    read_bytes,
)
from motorlab.model.load import MATERIALS, disc_inertia
from motorlab.timespans import setting_spans
from motorlab.units import format_unit, parse_quantity

#: Densities of flywheel materials [kg/m³]: the one table of :mod:`motorlab.model.load`.
MATERIAL_DENSITY = MATERIALS

#: Plausible ranges (SI) of the rig's quantities: a value outside is a unit mistake, refused at load.
PLAUSIBLE: dict[str, tuple[float, float]] = {
    "lever_arm": (1e-4, 100.0), "voltage_limit": (1e-3, 1e3), "current_limit": (1e-6, 1e4),
    "inertia": (1e-12, 1e6), "radius": (1e-4, 10.0), "diameter": (2e-4, 20.0), "thickness": (1e-5, 10.0),
    "density": (1.0, 3e4),
}

#: Settings each experiment accepts besides ``files``: name -> (SI unit or type name, description).
#: A unit string means a quantity parsed with pint; "int" / "str" / "bool" are plain TOML values.
#: Generated from the experiments' descriptions (:mod:`motorlab.experiments`).
EXPERIMENT_SETTINGS: dict[str, dict[str, tuple[str, str]]] = {
    name: {s.name: (s.kind, s.help) for s in exp.settings} for name, exp in all_experiments().items()
}

#: Settings an experiment cannot do without.
REQUIRED_SETTINGS: dict[str, tuple[str, ...]] = {
    name: tuple(s.name for s in exp.settings if s.required)
    for name, exp in all_experiments().items()
    if any(s.required for s in exp.settings)
}

#: Experiments run with the flywheel attached (their J, b, Tf include the flywheel and gearbox).
LOADED_EXPERIMENTS = frozenset(name for name, exp in all_experiments().items() if exp.loaded)


# ---------------------------------------------------------------------------------------------
# Data classes
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class MotorSpec:
    """The motor model under test.

    Attributes
    ----------
    name
        Human-readable model name.
    counts_per_revolution
        Encoder counts per revolution of the shaft the encoder is counted at (the output shaft of a
        gearmotor, as the FTC SDK reports) [count/rev].
    gear_ratio
        Gearbox reduction (motor turns per output turn) [-].
    catalog
        Catalogue key (``"neverest40"``) when the motor is in motorlab's catalogue, else None.
    nominal_voltage
        Voltage of the published figures [V] (None if unknown).
    """

    name: str
    counts_per_revolution: float
    gear_ratio: float = 1.0
    catalog: str | None = None
    nominal_voltage: float | None = None


@dataclass(frozen=True)
class FlywheelSpec:
    """The flywheel of the rig.

    Attributes
    ----------
    inertia
        Moment of inertia about its own axis [kg·m²].
    ratio
        Flywheel turns per turn of the motor's counted shaft (25 for the seed's 25:1 step-up) [-].
    description
        How it was given (``"0.0124 kg·m²"`` or ``"steel disc r = 75 mm, h = 50 mm"``).
    """

    inertia: float
    ratio: float = 1.0
    description: str = ""

    @property
    def reflected_inertia(self) -> float:
        """Inertia seen at the motor's counted shaft, J_f·N² [kg·m²]."""
        return self.inertia * self.ratio * self.ratio


@dataclass(frozen=True)
class RigSpec:
    """The dynamometer: flywheel, lever arm of the torque scale, supply limits (all optional)."""

    flywheel: FlywheelSpec | None = None
    lever_arm: float | None = None
    voltage_limit: float | None = None
    current_limit: float | None = None


@dataclass(frozen=True)
class ExperimentSpec:
    """One experiment of one unit: its files (absolute paths) and settings (SI)."""

    name: str
    files: tuple[Path, ...]
    settings: dict[str, Any] = field(default_factory=dict)
    line: int | None = None


@dataclass(frozen=True)
class UnitSpec:
    """One unit of the motor model (``A``, ``B`` ...) and its experiments, in the order written."""

    name: str
    experiments: dict[str, ExperimentSpec]
    label: str = ""
    truth: Path | None = None
    notes: str = ""
    line: int | None = None

    @property
    def display_name(self) -> str:
        """The label if given, else the unit's key."""
        return self.label or self.name


@dataclass(frozen=True)
class Session:
    """A validated session description."""

    path: Path
    title: str
    motor: MotorSpec
    rig: RigSpec
    units: dict[str, UnitSpec]
    date: str = ""
    notes: str = ""
    fleet_threshold: float | None = None
    healthy_spread: dict[str, float] = field(default_factory=dict)

    @property
    def folder(self) -> Path:
        """The folder relative paths are resolved against."""
        return self.path.parent

    def line_of(self, *keys: str) -> int | None:
        """Line of a key in the TOML text (see :func:`key_lines`)."""
        return _line_lookup(key_lines(self.path.read_text(encoding="utf-8")), keys)


# ---------------------------------------------------------------------------------------------
# Line numbers of keys
# ---------------------------------------------------------------------------------------------
_KEY_PART = r"""[A-Za-z0-9_-]+|"(?:[^"\\]|\\.)*"|'[^']*'"""
_DOTTED_KEY = rf"(?:{_KEY_PART})(?:\s*\.\s*(?:{_KEY_PART}))*"
_HEADER_RE = re.compile(rf"^\s*(\[\[|\[)\s*({_DOTTED_KEY})\s*\]\]?")
_ASSIGN_RE = re.compile(rf"^\s*({_DOTTED_KEY})\s*=(.*)$")
_INLINE_KEY_RE = re.compile(rf"(?:^|[{{,])\s*({_DOTTED_KEY})\s*=")


def _split_key(text: str) -> tuple[str, ...]:
    parts = re.findall(_KEY_PART, text)
    return tuple(p[1:-1] if p[:1] in "\"'" else p for p in parts)


def key_lines(text: str) -> dict[tuple[str, ...], int]:
    """Map every key path of a TOML text to its 1-based line number.

    Parameters
    ----------
    text
        The TOML document.

    Returns
    -------
    dict
        ``("units", "A", "spindown", "files") -> 17``; tables map to their header line. Arrays of
        tables get an index component (``("runs", "0", "file")``).

    Notes
    -----
    A deliberately small scanner, not a TOML parser: the text has already been parsed by
    ``tomllib``, so only the positions are wanted. Lines inside multi-line strings are skipped.
    """
    lines: dict[tuple[str, ...], int] = {}
    prefix: tuple[str, ...] = ()
    array_counts: dict[tuple[str, ...], int] = {}
    in_string: str | None = None
    for number, raw in enumerate(text.splitlines(), start=1):
        line = raw
        if in_string is not None:
            if line.count(in_string) % 2 == 1:
                in_string = None
            continue
        header = _HEADER_RE.match(line)
        if header:
            path = _split_key(header.group(2))
            if header.group(1) == "[[":
                index = array_counts.get(path, 0)
                array_counts[path] = index + 1
                path = (*path, str(index))
            prefix = path
            for k in range(1, len(path) + 1):
                lines.setdefault(path[:k], number)
            lines[path] = number
            continue
        assign = _ASSIGN_RE.match(line)
        if not assign:
            continue
        path = (*prefix, *_split_key(assign.group(1)))
        for k in range(len(prefix) + 1, len(path) + 1):
            lines.setdefault(path[:k], number)
        rest = assign.group(2)
        for quote in ('"""', "'''"):
            if rest.count(quote) % 2 == 1:
                in_string = quote
        stripped = rest.strip()
        if stripped.startswith("{"):
            for match in _INLINE_KEY_RE.finditer(stripped):
                lines.setdefault((*path, *_split_key(match.group(1))), number)
    return lines


def _line_lookup(lines: Mapping[tuple[str, ...], int], keys: Iterable[str]) -> int | None:
    path = tuple(keys)
    while path:
        if path in lines:
            return lines[path]
        path = path[:-1]
    return None


# ---------------------------------------------------------------------------------------------
# Validation helpers
# ---------------------------------------------------------------------------------------------
class _Context:
    """The file being validated: path, text, key lines."""

    def __init__(self, path: Path, text: str):
        self.path = path
        self.lines = key_lines(text)

    def error(self, keys: tuple[str, ...], message: str) -> SessionError:
        name = ".".join(keys)
        text = f"{name}: {message}" if name else message
        return SessionError(text, path=self.path, line=_line_lookup(self.lines, keys))


class _Table:
    """A TOML table being read: takes known keys, refuses the rest with a 'did you mean'."""

    def __init__(self, ctx: _Context, keys: tuple[str, ...], data: Any):
        self.ctx = ctx
        self.keys = keys
        if not isinstance(data, dict):
            raise ctx.error(keys, f"expected a table, got {_kind(data)}")
        self.data: dict[str, Any] = data
        self.known: list[str] = []

    def error(self, key: str | None, message: str) -> SessionError:
        return self.ctx.error(self.keys if key is None else (*self.keys, key), message)

    def has(self, key: str) -> bool:
        return key in self.data

    def raw(self, key: str, default: Any = None) -> Any:
        self.known.append(key)
        return self.data.get(key, default)

    def string(self, key: str, default: str | None = None, *, required: bool = False) -> str | None:
        value = self.raw(key)
        if value is None:
            if required:
                raise self.error(None, f"missing key {key!r}")
            return default
        if not isinstance(value, str):
            raise self.error(key, f"expected a string, got {_kind(value)}")
        return value

    def quantity(self, key: str, unit: str, *, positive: bool = True, required: bool = False) -> float | None:
        value = self.raw(key)
        if value is None:
            if required:
                raise self.error(None, f"missing key {key!r} (a quantity in {format_unit(unit)})")
            return None
        if isinstance(value, bool) or not isinstance(value, int | float | str):
            raise self.error(key, f"expected a quantity in {format_unit(unit)}, got {_kind(value)}")
        try:
            number = parse_quantity(value, unit, name=key)
        except OptionError as exc:
            raise self.error(key, exc.message.removeprefix(f"{key}: ")) from None
        if positive and number <= 0:
            raise self.error(key, f"must be positive, got {value!r}")
        low, high = PLAUSIBLE.get(key, (0.0, math.inf))
        if not low <= number <= high:  # a unit mistake ("15 furlongs"), refused now rather than failing later
            raise self.error(key, f"{value!r} is {number:.4g} {format_unit(unit)}, outside {low:g} … {high:g} "
                             f"{format_unit(unit)}: beyond any gearmotor rig")
        return number

    def number(self, key: str, *, required: bool = False, integer: bool = False) -> float | None:
        value = self.raw(key)
        if value is None:
            if required:
                raise self.error(None, f"missing key {key!r}")
            return None
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise self.error(key, f"expected a number, got {_kind(value)}")
        if integer and (not float(value).is_integer()):
            raise self.error(key, f"expected a whole number, got {value!r}")
        if not math.isfinite(value) or value <= 0:
            raise self.error(key, f"must be a positive number, got {value!r}")
        return float(value)

    def table(self, key: str) -> _Table | None:
        value = self.raw(key)
        if value is None:
            return None
        return _Table(self.ctx, (*self.keys, key), value)

    def finish(self) -> None:
        for key in self.data:
            if key not in self.known:
                hint = difflib.get_close_matches(key, self.known, n=1, cutoff=0.6)
                allowed = ", ".join(sorted(set(self.known)))
                suggestion = f"; did you mean {hint[0]!r}?" if hint else f" (known keys: {allowed})"
                raise self.error(key, f"unknown key {key!r}{suggestion}")


def _long_integer_line(text: str) -> int | None:
    """The line of the first TOML integer literal (``_`` allowed) longer than :data:`MAX_INTEGER_DIGITS` digits."""
    match = re.search(rf"[0-9][0-9_]{{{MAX_INTEGER_DIGITS},}}", text)
    return line_of_offset(text, match.start()) if match else None


def _check_integers(ctx: _Context, keys: tuple[str, ...], data: Any, depth: int = 0) -> None:
    """Refuse an integer no float can hold (more than :data:`MAX_INTEGER_DIGITS` digits) before any use of it."""
    items = data.items() if isinstance(data, dict) else enumerate(data) if isinstance(data, list) else ()
    for key, value in items:
        where = (*keys, key) if isinstance(key, str) else keys
        if isinstance(value, int) and not isinstance(value, bool) and value.bit_length() > 1024:
            raise ctx.error(where, f"an integer of {len(str(abs(value)))} digits: beyond any number a quantity can be")
        if isinstance(value, dict | list) and depth < MAX_NESTING:
            _check_integers(ctx, where, value, depth + 1)


def _kind(value: Any) -> str:
    return {dict: "a table", list: "an array", str: "a string", bool: "a boolean"}.get(
        type(value), type(value).__name__
    )


# ---------------------------------------------------------------------------------------------
# Loading
# ---------------------------------------------------------------------------------------------
def _shorten(text: str, width: int = 60) -> str:
    return text if len(text) <= width else text[: width - 1] + "…"


def load_session(path: str | Path) -> Session:
    """Read and validate a session description.

    Parameters
    ----------
    path
        The TOML file. Relative file names inside it are resolved against its folder.

    Returns
    -------
    Session
        The validated description (quantities in SI, files as absolute paths).

    Raises
    ------
    SessionError
        On a TOML syntax error, an unknown key (with a "did you mean"), a missing or unreadable
        file, a quantity with the wrong dimension, or contradictory settings. The message names
        the file, the line and the key.
    """
    path = Path(path)
    try:
        _name, raw_bytes = read_bytes(path)  # a regular file of sane size only (not a FIFO, not /dev/zero)
    except InputError as exc:
        raise SessionError(exc.message, path=path) from None
    try:
        text = raw_bytes.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise SessionError("the session file is not UTF-8 text", path=path) from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        match = re.search(r"\(at line (\d+), column \d+\)", str(exc))
        message = re.sub(r"\s*\(at line \d+, column \d+\)", "", str(exc))
        line = int(match.group(1)) if match else None
        # tomllib names the line but not the key: quote the line, which shows the key to the user.
        lines = text.splitlines()
        if line is not None and 1 <= line <= len(lines) and lines[line - 1].strip():
            message += f" in {_shorten(lines[line - 1].strip())!r}"
        raise SessionError(f"invalid TOML: {message}", path=path, line=line) from None
    except ValueError:  # an integer of more than 4,300 digits, which Python refuses to convert
        raise SessionError("an integer of thousands of digits: not a quantity", path=path,
                           line=_long_integer_line(text)) from None
    except RecursionError:
        raise SessionError("not a session file: tables or arrays nested too deeply", path=path,
                           line=deep_nesting_line(text)) from None
    ctx = _Context(path, text)
    _check_integers(ctx, (), data)
    top = _Table(ctx, (), data)
    info = top.table("session")
    title = date = notes = ""
    if info is not None:
        title = info.string("title") or ""
        date = info.string("date") or ""
        notes = info.string("notes") or ""
        info.finish()
    motor_table = top.table("motor")
    if motor_table is None:
        raise ctx.error(("motor",), "missing table [motor] (a catalog name, or counts_per_revolution)")
    motor = _read_motor(motor_table)
    rig_table = top.table("rig")
    rig = _read_rig(rig_table) if rig_table is not None else RigSpec()
    units_table = top.table("units")
    if units_table is None or not units_table.data:
        raise ctx.error(("units",), "no units: add a [units.A.<experiment>] table with files = [...]")
    units = {name: _read_unit(units_table, name, path.parent, rig) for name in units_table.data}
    fleet_table = top.table("fleet")
    threshold, spread = (None, {}) if fleet_table is None else _read_fleet(fleet_table)
    top.finish()
    return Session(
        path=path.resolve(),
        title=title or f"{motor.name} session",
        motor=motor,
        rig=rig,
        units=units,
        date=date,
        notes=notes,
        fleet_threshold=threshold,
        healthy_spread=spread,
    )


def _read_fleet(table: _Table) -> tuple[float | None, dict[str, float]]:
    threshold = table.number("threshold")
    spread_table = table.table("spread")
    table.finish()
    spread: dict[str, float] = {}
    if spread_table is not None:
        for name in ("K", "R", "L", "J", "b", "Tf"):
            value = spread_table.raw(name)
            if value is None:
                continue
            if isinstance(value, str) and value.strip().endswith("%"):
                try:
                    number = float(value.strip()[:-1]) / 100
                except ValueError:
                    raise spread_table.error(name, f"cannot read {value!r} as a percentage") from None
            elif isinstance(value, int | float) and not isinstance(value, bool):
                number = float(value)
            else:
                raise spread_table.error(name, f'expected a fraction (0.1) or a percentage ("10 %"), got {value!r}')
            if not (math.isfinite(number) and 0 < number < 5):
                raise spread_table.error(name, f"a relative spread must lie in (0, 5), got {value!r}")
            spread[name] = number
        spread_table.finish()
    return threshold, spread


def _read_motor(table: _Table) -> MotorSpec:
    catalog_key = table.string("catalog")
    name = table.string("name")
    cpr = table.number("counts_per_revolution")
    ratio = table.number("gear_ratio")
    nominal = table.quantity("nominal_voltage", "V")
    table.finish()
    if catalog_key is not None:
        motor = _catalog_motor(table, catalog_key)
        cat_cpr = float(motor.cpr)
        cat_ratio = float(motor.gear_ratio)
        if cpr is not None and not math.isclose(cpr, cat_cpr, rel_tol=1e-9):
            raise table.error(
                "counts_per_revolution",
                f"{cpr:g} contradicts the catalogue's {cat_cpr:g} for {catalog_key!r} (remove one of them)",
            )
        if ratio is not None and not math.isclose(ratio, cat_ratio, rel_tol=1e-9):
            raise table.error("gear_ratio", f"{ratio:g} contradicts the catalogue's {cat_ratio:g} for {catalog_key!r}")
        return MotorSpec(
            name=name or motor.name,
            counts_per_revolution=cat_cpr,
            gear_ratio=cat_ratio,
            catalog=motor.key,
            nominal_voltage=nominal if nominal is not None else float(motor.nominal_voltage),
        )
    if cpr is None:
        raise table.error(None, 'give either catalog = "<name>" or counts_per_revolution (and gear_ratio)')
    return MotorSpec(
        name=name or "unnamed motor",
        counts_per_revolution=cpr,
        gear_ratio=ratio if ratio is not None else 1.0,
        catalog=None,
        nominal_voltage=nominal,
    )


def _catalog_motor(table: _Table, key: str) -> Any:
    from motorlab import catalog

    try:
        return catalog.Motor.from_catalog(key)
    except MotorlabError as exc:
        known = [m if isinstance(m, str) else getattr(m, "key", str(m)) for m in catalog.list_motors()]
        hint = difflib.get_close_matches(key.lower(), known, n=1, cutoff=0.5)
        suffix = f"; did you mean {hint[0]!r}?" if hint else f" (known: {', '.join(known)})"
        raise table.error("catalog", f"unknown motor {key!r}{suffix}") from exc


def _read_rig(table: _Table) -> RigSpec:
    lever = table.quantity("lever_arm", "m")
    fly_table = table.table("flywheel")
    flywheel = _read_flywheel(fly_table) if fly_table is not None else None
    supply = table.table("supply")
    voltage_limit = current_limit = None
    if supply is not None:
        voltage_limit = supply.quantity("voltage_limit", "V")
        current_limit = supply.quantity("current_limit", "A")
        supply.finish()
    table.finish()
    return RigSpec(flywheel=flywheel, lever_arm=lever, voltage_limit=voltage_limit, current_limit=current_limit)


def _read_flywheel(table: _Table) -> FlywheelSpec:
    has_inertia, has_disc = table.has("inertia"), table.has("disc")
    if has_inertia and has_disc:
        raise table.error("disc", "the flywheel is given both as an inertia and as a disc: keep one")
    ratio = table.number("ratio") or 1.0
    if has_inertia:
        inertia = table.quantity("inertia", "kg*m^2", required=True)
        assert inertia is not None
        table.raw("disc")
        table.finish()
        return _checked_flywheel(table, FlywheelSpec(inertia, ratio, f"{inertia:.4g} kg·m²"))
    disc = table.table("disc")
    table.finish()
    if disc is None:
        raise table.error(
            None, 'give the flywheel as inertia = "... kg*m^2" or as disc = { radius, thickness, material }'
        )
    if disc.has("radius") and disc.has("diameter"):
        raise disc.error("diameter", "give the radius or the diameter, not both")
    if disc.has("material") and disc.has("density"):
        raise disc.error("density", "give the material or the density, not both")
    radius = disc.quantity("radius", "m")
    diameter = disc.quantity("diameter", "m")
    if radius is None:
        if diameter is None:
            raise disc.error(None, "missing key 'radius' (or 'diameter')")
        radius = diameter / 2
    thickness = disc.quantity("thickness", "m", required=True)
    assert thickness is not None
    material = disc.string("material")
    density = disc.quantity("density", "kg/m^3")
    disc.finish()
    if material is not None:
        if material.lower() not in MATERIAL_DENSITY:
            hint = difflib.get_close_matches(material.lower(), list(MATERIAL_DENSITY), n=1)
            suffix = f"; did you mean {hint[0]!r}?" if hint else ""
            raise disc.error("material", f"unknown material {material!r}{suffix} (or give density = ...)")
        density = MATERIAL_DENSITY[material.lower()]
    if density is None:
        raise disc.error(None, "missing key 'material' (or 'density')")
    inertia = disc_inertia(radius, thickness, density)  # ½·π·r⁴·ρ·h; inf (checked below) for absurd sizes
    if not math.isfinite(inertia):
        raise table.error("disc", f"a disc of radius {radius:g} m has an inertia too large to represent")
    what = material or f"ρ = {density:g} kg/m³"
    spec = FlywheelSpec(inertia, ratio, f"{what} disc r = {1e3 * radius:g} mm, h = {1e3 * thickness:g} mm")
    return _checked_flywheel(table, spec)


def _checked_flywheel(table: _Table, spec: FlywheelSpec) -> FlywheelSpec:
    """``spec`` once its reflected inertia J·N² is a finite number (else the ratio is absurd)."""
    if not math.isfinite(spec.reflected_inertia):
        raise table.error("ratio", f"a ratio of {spec.ratio:g} reflects an inertia too large to represent")
    return spec


def _read_unit(units: _Table, name: str, folder: Path, rig: RigSpec) -> UnitSpec:
    table = units.table(name)
    assert table is not None
    label = table.string("label") or ""
    notes = table.string("notes") or ""
    truth_name = table.string("truth")
    truth = None
    if truth_name is not None:
        truth = _existing_file(table, "truth", truth_name, folder)
    experiments: dict[str, ExperimentSpec] = {}
    for key in list(table.data):
        if key in ("label", "notes", "truth"):
            continue
        if key not in EXPERIMENT_SETTINGS:
            continue  # reported by finish() with a "did you mean"
        experiments[key] = _read_experiment(table, key, folder, rig)
    for key in EXPERIMENT_SETTINGS:
        table.known.append(key)
    table.finish()
    if not experiments:
        raise table.error(None, f"unit {name!r} has no experiment (add e.g. [units.{name}.spindown])")
    return UnitSpec(
        name=name,
        experiments=experiments,
        label=label,
        truth=truth,
        notes=notes,
        line=_line_lookup(table.ctx.lines, table.keys),
    )


def _read_experiment(unit: _Table, name: str, folder: Path, rig: RigSpec) -> ExperimentSpec:
    table = unit.table(name)
    assert table is not None
    files_value = table.raw("files")
    if files_value is None:
        raise table.error(None, "missing key 'files' (a file name or a list of file names)")
    names = [files_value] if isinstance(files_value, str) else files_value
    if not isinstance(names, list) or not names or not all(isinstance(n, str) for n in names):
        raise table.error("files", "expected a file name or a non-empty list of file names")
    files = tuple(_existing_file(table, "files", n, folder) for n in names)
    if len({f.resolve() for f in files}) < len(files):
        twice = next(n for k, n in enumerate(names) if files[k].resolve() in {f.resolve() for f in files[:k]})
        raise table.error("files", f"{twice!r} is listed twice: each file of a run is read once")
    settings: dict[str, Any] = {}
    columns = _read_columns(table)
    if columns:
        settings["columns"] = columns
    if table.has("exclude"):  # time spans to leave out of the log (motorlab.timespans)
        try:
            exp = all_experiments().get(name)
            takes = exp is not None and any(o.kind == "spans" for o in exp.options)
            settings["exclude"] = setting_spans(table.raw("exclude"), takes_spans=takes, hint=exclude_hint())
        except OptionError as exc:
            raise table.error("exclude", exc.message) from None
    for key, (kind, _description) in EXPERIMENT_SETTINGS[name].items():
        if not table.has(key):
            table.known.append(key)
            continue
        if kind == "int":
            value = table.number(key, integer=True)
            settings[key] = int(value) if value is not None else None
        elif kind == "float":
            settings[key] = table.number(key)
        elif kind == "str":
            settings[key] = table.string(key)
        else:
            settings[key] = table.quantity(key, kind, positive=kind != "s")
    table.finish()
    for key in REQUIRED_SETTINGS.get(name, ()):
        if settings.get(key) is None:
            si_unit = format_unit(EXPERIMENT_SETTINGS[name][key][0])
            raise table.error(None, f"missing key {key!r} ({EXPERIMENT_SETTINGS[name][key][1]}, in {si_unit})")
    current = settings.get("current")
    if current is not None and rig.current_limit is not None and current > rig.current_limit * (1 + 1e-9):
        raise table.error("current", f"{current:g} A is above the supply's current limit of {rig.current_limit:g} A")
    voltage = settings.get("voltage")
    if voltage is not None and rig.voltage_limit is not None and voltage > rig.voltage_limit * (1 + 1e-9):
        raise table.error("voltage", f"{voltage:g} V is above the supply's voltage limit of {rig.voltage_limit:g} V")
    if name == "torque" and rig.lever_arm is None:
        raise table.error(None, "the torque experiment needs the scale's lever arm: add rig.lever_arm")
    if name in LOADED_EXPERIMENTS - {"torque"} and rig.flywheel is None:
        raise table.error(None, f"the {name} experiment needs the flywheel: add a [rig.flywheel] table")
    return ExperimentSpec(name=name, files=files, settings=settings, line=_line_lookup(table.ctx.lines, table.keys))


def _read_columns(table: _Table) -> list[str]:
    """The ``columns`` key of an experiment's table: ``{"Amps" = "current"}`` or ``["Amps=current"]``
    (the rules of ``--column``, :mod:`motorlab.io.headers`), as rule texts."""
    from motorlab.io.headers import parse_column_mapping

    value = table.raw("columns")
    if value is None:
        return []
    if not isinstance(value, dict | list | str):
        raise table.error("columns", f"expected a table such as {{ Amps = \"current\" }}, got {_kind(value)}")
    try:
        return [rule.text() for rule in parse_column_mapping(value, name="columns")]
    except OptionError as exc:
        raise table.error("columns", exc.message.removeprefix("columns").lstrip(": ")) from None


def _existing_file(table: _Table, key: str, name: str, folder: Path) -> Path:
    path = Path(name)
    if not path.is_absolute():
        path = folder / path
    if not path.exists():
        raise table.error(key, f"file not found: {name}")
    if not path.is_file():
        raise table.error(key, f"not a file: {name}")
    return path.resolve()


# ---------------------------------------------------------------------------------------------
# Writing
# ---------------------------------------------------------------------------------------------
def toml_string(value: str) -> str:
    """A TOML basic string (JSON string escapes are valid TOML)."""
    return json.dumps(value, ensure_ascii=False)


def read_truth(path: str | Path) -> dict[str, float]:
    """True parameters of a simulated unit from a ``truth.json`` (``{"K": 0.37, ...}`` in SI).

    Accepts the virtual rig's file (``{"format": "motorlab-truth", "runs": {file: {"params": ...}}}``;
    every run of one unit has the same parameters, the first is taken), ``{"params": {...}}``, a
    flat ``{"K": ...}`` mapping, or ``{"K": {"value": ...}}``.
    """
    path = Path(path)
    try:
        _name, raw = read_bytes(path)  # a regular file of sane size (not a FIFO, not /dev/zero)
        data = load_json(raw.decode("utf-8-sig"), str(path))
    except InputError as exc:
        raise SessionError(f"the truth file: {exc.message}", path=path, line=exc.line) from None
    except UnicodeDecodeError:
        raise SessionError("the truth file is not UTF-8 text", path=path) from None
    if isinstance(data, dict) and isinstance(data.get("runs"), dict) and data["runs"]:
        data = next(iter(data["runs"].values()))
    box = data.get("gearbox") if isinstance(data, dict) else None
    if isinstance(data, dict) and isinstance(data.get("params"), dict):
        data = data["params"]
    out: dict[str, float] = {}
    if isinstance(box, dict):  # the virtual rig's gearbox (motorlab.gearbox): η and τ0 at the output
        for name in ("efficiency", "loss_torque"):
            if isinstance(box.get(name), int | float):
                out[name] = float(box[name])
    if isinstance(data, dict):
        for name in ("K", "R", "L", "J", "b", "Tf"):
            value = data.get(name)
            if isinstance(value, dict):
                value = value.get("value")
            if isinstance(value, int | float) and not isinstance(value, bool):
                out[name] = float(value)
    if not set(out) - {"efficiency", "loss_torque"}:
        raise SessionError("no motor parameters (K, R, L, J, b, Tf) in the truth file", path=path)
    return out
