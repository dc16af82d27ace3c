"""The plant to tune for: feedforward constants and (when known) the full motor model, and the user's units.

SI inside (rad, V·s/rad; or m, V·s/m for a model fitted to distances, :attr:`Plant.length`);
:class:`MechanismUnits` converts lengths to what the user counts in: radians, rotations, degrees, encoder
ticks, or metres, feet or inches at a wheel of given radius (or of the distances the model was fitted to).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from os import PathLike
from typing import Any

from motorlab.control.design import Feedforward
from motorlab.errors import InputError, LogFormatError, OptionError
from motorlab.io.text import load_json, read_bytes
from motorlab.model import PARAMETER_NAMES, MotorParams, feedforward_from_params

UNIT_NAMES = ("rad", "rotations", "degrees", "ticks", "m", "ft", "in")

#: Metres per length unit of a distance (``m``, ``ft``, ``in``) [m].
METRES = {"m": 1.0, "ft": 0.3048, "in": 0.0254}


@dataclass(frozen=True)
class MechanismUnits:
    """A length unit of the mechanism and its size.

    Parameters
    ----------
    name
        ``"rad"``, ``"rotations"``, ``"degrees"``, ``"ticks"``, or a distance: ``"m"``, ``"ft"``, ``"in"``
        (at a wheel's rim, or the distances a model was fitted to).
    per_radian
        How many of these units the shaft covers per radian [unit/rad] (cpr/2π for ticks, the wheel
        radius for metres, the radius in feet for feet); of a model fitted to distances (its "radian" is
        a metre), how many per metre.
    cpr
        Encoder counts per revolution of the shaft, when known [-].
    base
        What the plant's lengths are: ``"rad"`` (a shaft's angle), or ``"m"`` for a model fitted to distances
        (:attr:`Plant.length`), whose "radian" is a metre.
    """

    name: str
    per_radian: float
    cpr: float | None = None
    base: str = "rad"

    @classmethod
    def from_options(
        cls, units: str = "rad", *, cpr: float | None = None, wheel_radius: float | None = None
    ) -> MechanismUnits:
        """Units from ``--units``, ``--cpr`` and ``--wheel-radius`` [m].

        Raises
        ------
        OptionError
            For an unknown unit, ticks without a cpr, or a non-positive radius or cpr.
        """
        if cpr is not None and not (cpr > 0 and math.isfinite(cpr)):
            raise OptionError(f"--cpr must be positive, got {cpr}")
        if wheel_radius is not None:
            if not (wheel_radius > 0 and math.isfinite(wheel_radius)):
                raise OptionError(f"--wheel-radius must be positive, got {wheel_radius}")
            if units == "rad":
                units = "m"
            if units not in METRES:
                raise OptionError("--wheel-radius gives lengths at the wheel (m, ft or in); do not combine it with "
                                  "--units " + units)
            return cls(units, wheel_radius / METRES[units], cpr)
        if units in METRES:
            raise OptionError(f"--units {units} needs --wheel-radius")
        if units == "rad":
            return cls("rad", 1.0, cpr)
        if units == "rotations":
            return cls("rotations", 1.0 / (2 * math.pi), cpr)
        if units == "degrees":
            return cls("degrees", 180.0 / math.pi, cpr)
        if units == "ticks":
            if cpr is None:
                raise OptionError("--units ticks needs --cpr (encoder counts per revolution)")
            return cls("ticks", cpr / (2 * math.pi), cpr)
        raise OptionError(f"unknown unit {units!r} (expected one of {', '.join(UNIT_NAMES)})")

    @classmethod
    def of_distances(cls, units: str = "m", *, cpr: float | None = None) -> MechanismUnits:
        """Units of a model fitted to distances (kV per metre, :attr:`Plant.length` ``"m"``): m, ft or in.

        Raises
        ------
        OptionError
            For an angle (radians, rotations, degrees, ticks): such a model has no shaft angle.
        """
        if units not in METRES:
            raise OptionError(f"--units {units}: the model gives kV, kA per metre travelled (its file logs "
                              "distances), so its gains are per metre, foot or inch: choose --units m, ft or in")
        return cls(units, 1.0 / METRES[units], cpr, base="m")

    @property
    def metres(self) -> float | None:
        """Metres per radian of the plant (a wheel's radius; 1 for a model of distances), or None for an angle."""
        return self.per_radian * METRES[self.name] if self.name in METRES else None

    @property
    def short(self) -> str:
        """Abbreviation for unit strings (``rad``, ``rot``, ``deg``, ``tick``, ``m``)."""
        return {"rotations": "rot", "degrees": "deg", "ticks": "tick"}.get(self.name, self.name)

    def to_si(self, value: float) -> float:
        """A length (or length per second ...) in this unit → radians."""
        return value / self.per_radian

    def from_si(self, value: float) -> float:
        """Radians → this unit."""
        return value * self.per_radian


#: Road Runner ramp results a plant may carry (motorlab.analyses.roadrunner).
GEOMETRY = ("lateral_ratio", "track_width_ticks", "lateral_kA")


@dataclass(frozen=True)
class Plant:
    """What the tuner knows about the motor.

    Parameters
    ----------
    feedforward
        kS [V], kV [V·s/rad], kA [V·s²/rad] used for the design.
    params
        The full motor model, when K, R, J are known (simulated instead of the feedforward plant).
    source
        Where the numbers came from (for reports).
    geometry
        Drive geometry from Road Runner ramps (``lateral_ratio`` [-], ``track_width_ticks`` [tick]), when
        the ``analyze --json`` file has it (for ``--target roadrunner`` / ``pedro``).
    notes
        What the tuner must say about the numbers (e.g. kS missing and taken as 0).
    length
        What the feedforward's lengths are: ``"rad"`` (a shaft's angle: kV [V·s/rad]) or ``"m"`` (the
        distance a file logged: kV [V·s/m]).
    own_units
        The length unit of the file the model was fitted from (:data:`motorlab.io.frc_json.GAIN_UNITS`:
        ``"ft"`` for a SysId file in Feet), when its results say: the gains' default unit.
    stderr
        The standard errors the results give of kS, kV, kA (SI, as ``feedforward``), where they give one.
    """

    feedforward: Feedforward
    params: MotorParams | None = None
    source: str = ""
    geometry: dict[str, float] = field(default_factory=dict)
    notes: tuple[str, ...] = ()
    length: str = "rad"
    own_units: str | None = None
    stderr: dict[str, float] = field(default_factory=dict)

    def units(self, units: str | None = None, *, cpr: float | None = None,
              wheel_radius: float | None = None) -> MechanismUnits:
        """The user's length unit for this plant: ``units`` (``--units``), else the file's own, else rad or m.

        A model fitted to distances takes m, ft or in and no wheel radius (its lengths are distances already).

        Raises
        ------
        OptionError
            As :meth:`MechanismUnits.from_options`; an angle, or a wheel radius, for a model of distances.
        """
        name = units or self.own_units or ("m" if self.length == "m" else "rad")
        if self.length != "m":
            return MechanismUnits.from_options(name, cpr=cpr, wheel_radius=wheel_radius)
        if wheel_radius is not None:
            raise OptionError(f"--wheel-radius: {self.source or 'the model'} gives kV, kA per metre travelled "
                              "already (its file logs distances): leave the wheel radius out")
        return MechanismUnits.of_distances(name, cpr=cpr)

    @property
    def simulated(self) -> MotorParams | Feedforward:
        """The model the closed loop is simulated on."""
        return self.params if self.params is not None else self.feedforward

    @classmethod
    def from_params(cls, params: MotorParams, *, source: str = "motor parameters") -> Plant:
        """Plant of a known motor: feedforward from :func:`motorlab.model.feedforward_from_params`."""
        ff = feedforward_from_params(params)
        return cls(Feedforward(ff["kS"], ff["kV"], ff["kA"]), params, source)


def _value(entry: Any) -> float | None:
    value = entry.get("value") if isinstance(entry, dict) else entry
    if value is None:
        return None  # "not determined" in analyze --json
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise TypeError(f"not a number: {value!r}")
    return float(value)


def _collect(obj: Any, found: list[dict[str, Any]]) -> None:
    """Every object whose ``parameters`` is an object, in document order."""
    if isinstance(obj, dict):
        params = obj.get("parameters")
        if isinstance(params, dict):
            found.append(params)
        for key, value in obj.items():
            if key != "parameters":
                _collect(value, found)
    elif isinstance(obj, list):
        for item in obj:
            _collect(item, found)


def _lengths(doc: Any, found: list[dict[str, Any]]) -> tuple[str, str | None] | None:
    """(the plant's length, the file's own unit) of a document that gives kV, or None when it gives none.

    The length is ``"m"`` when kV is per metre (``"unit": "V*s/m"``: a file that logs distances); the own
    unit is the analysis's ``details.file_units`` (a SysId file's ``units``), when it names one.
    """
    kv = [e["kV"] for e in found if isinstance(e.get("kV"), int | float)
          or (isinstance(e.get("kV"), dict) and e["kV"].get("value") is not None)]
    if not kv:
        return None
    unit = kv[-1].get("unit") if isinstance(kv[-1], dict) else None
    length = "m" if isinstance(unit, str) and unit.replace(" ", "").endswith("/m") else "rad"
    own = {u.get("length_unit") for u in _file_units(doc)}
    name = own.pop() if len(own) == 1 else None
    return length, name if isinstance(name, str) and name in UNIT_NAMES else None


def _file_units(obj: Any) -> list[dict[str, Any]]:
    """Every ``file_units`` object of an analysis's JSON (:func:`motorlab.analyses.feedforward.file_units`)."""
    if isinstance(obj, list):
        return [u for item in obj for u in _file_units(item)]
    if not isinstance(obj, dict):
        return []
    own = obj.get("file_units")
    return ([own] if isinstance(own, dict) else []) + [u for k, v in obj.items() if k != "file_units"
                                                      for u in _file_units(v)]


def _unit_parameters(doc: dict[str, Any], unit: str | None, path: str | PathLike[str]) -> dict[str, Any]:
    """The combined (bare-motor) parameters of one unit of a ``characterize`` results.json.

    Only ``units.<name>.parameters`` is read: the per-experiment results beside it include runs with
    the flywheel on (their kS, kV, kA and J describe motor + flywheel) and must not be mixed in.
    """
    units = doc["units"]
    names = list(units)
    if unit is None:
        if len(names) != 1:
            raise OptionError(f"{path} holds units {', '.join(names)}: choose one with --unit")
        unit = names[0]
    if unit not in units:
        raise OptionError(f"{path} has no unit {unit!r} (it has {', '.join(names)})")
    params = units[unit].get("parameters") if isinstance(units[unit], dict) else None
    if not isinstance(params, dict):
        raise LogFormatError(f"unit {unit} has no parameters", path=path)
    return params


def load_plant(paths: list[str | PathLike[str]], *, unit: str | None = None) -> Plant:
    """The plant from ``motorlab analyze --json`` / ``characterize`` JSON files.

    Parameters
    ----------
    paths
        JSON files: an ``analyze --json`` object (``{"parameters": {"K": {"value": ...}, ...}}``),
        a list of such objects, or the ``results.json`` of ``motorlab characterize`` (then only the
        chosen unit's combined motor parameters are used). Later values override earlier ones.
    unit
        Which unit of a ``results.json`` (required when it holds several).

    Returns
    -------
    Plant
        kS/kV/kA taken as given when present (a feedforward analysis), else derived from K, R, J,
        b, Tf; the motor model is kept for simulation whenever K, R, J are known.

    Raises
    ------
    LogFormatError
        For unreadable JSON, non-numeric values, or files without usable parameters.
    """
    merged: dict[str, float] = {}
    names = (*PARAMETER_NAMES, "kS", "kV", "kA", *GEOMETRY)
    lengths: tuple[str, str | None] = ("rad", None)  # of the file whose kV won the merge
    errors: dict[str, float] = {}  # standard errors of the values that won the merge
    for path in paths:
        _name, raw = read_bytes(path)  # missing, a directory, a FIFO, too large: named in one line
        if not raw.strip():
            raise LogFormatError("the file is empty (expected motorlab analyze --json output)", path=path)
        try:
            doc = load_json(raw.decode("utf-8-sig"), str(path))
        except UnicodeDecodeError:
            raise LogFormatError("not a text (JSON) file", path=path) from None
        found: list[dict[str, Any]] = []
        if isinstance(doc, dict) and isinstance(doc.get("units"), dict):  # characterize's results.json
            found.append(_unit_parameters(doc, unit, path))
        else:
            _collect(doc, found)
        before = len(merged)
        for entry in found:
            for name in names:
                if name in entry:
                    try:
                        value = _value(entry[name])
                    except TypeError as exc:
                        raise LogFormatError(f"parameter {name}: {exc}", path=path) from None
                    if value is not None:
                        if not math.isfinite(value):
                            raise LogFormatError(f"parameter {name} is not finite", path=path)
                        merged[name] = value
                        errors.pop(name, None)
                        error = entry[name].get("stderr") if isinstance(entry[name], dict) else None
                        if isinstance(error, int | float) and not isinstance(error, bool) and math.isfinite(error):
                            errors[name] = float(error)
        lengths = _lengths(doc, found) or lengths
        if not found or (len(merged) == before and not any(n in merged for n in names)):
            raise LogFormatError(
                'no "parameters" object with K, R, J or kS, kV, kA (expected motorlab analyze --json output)',
                path=path,
            )
    source = ", ".join(str(p) for p in paths)
    params: MotorParams | None = None
    # The values come from the files: an impossible one (R < 0, kA = 0) is a problem of the files,
    # so the error names them (the last one, whose values won the merge, when there are several).
    try:
        if all(n in merged for n in ("K", "R", "J")):
            params = MotorParams.from_dict(merged)
        if "kV" in merged and "kA" in merged:
            ff = Feedforward(max(merged.get("kS", 0.0), 0.0), merged["kV"], merged["kA"]).check_plant()
            notes: tuple[str, ...] = ()
            if "kS" not in merged:  # absent or null (not determined): say so, do not print a silent 0
                notes = (f"kS is not given (or not determined) in {source}: taken as 0 V, so there is no "
                         "static-friction feedforward",)
            return Plant(ff, params, source, {k: merged[k] for k in GEOMETRY if k in merged}, notes, *lengths,
                         stderr={k: errors[k] for k in ("kS", "kV", "kA") if k in errors})
    except InputError as exc:
        raise LogFormatError(exc.message, path=paths[-1] if len(paths) == 1 else source) from None
    if params is not None:
        return Plant.from_params(params, source=source)
    missing = "kV, kA" if ("kV" in merged or "kA" in merged) else "K, R, J (or kV, kA)"
    raise LogFormatError(f"the parameters lack {missing}", path=paths[-1] if paths else None)
