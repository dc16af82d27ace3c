"""The motor catalogue: nominal figures of FTC-legal gearmotors, with a source for every number.

The figures live in package data (``motorlab/data/motors.toml``), stored in the units of their
source (``"350 in*oz"``, ``"160 rpm"``, ``"24.3 kg*cm"``) and converted to SI here with
:func:`motorlab.units.parse_quantity`. :meth:`Motor.from_catalog` is the factory (as WPILib's
``DCMotor.NEO()``); :meth:`Motor.nominal_params` turns a data-sheet entry into the
:class:`~motorlab.model.MotorParams` of the model, to seed fits and to compare against.

All figures are at the OUTPUT shaft of the gearmotor (the shaft whose encoder counts ``cpr`` per
revolution), at the nominal voltage.
"""

from __future__ import annotations

import math
import re
import tomllib
from dataclasses import dataclass, field
from functools import lru_cache
from importlib import resources
from os import PathLike
from pathlib import Path
from typing import Any

from motorlab.errors import InputError, OptionError
from motorlab.gearbox import Gearbox
from motorlab.model import MotorParams
from motorlab.thermal.network import MAGNET_COEFFICIENTS, ThermalModel
from motorlab.units import parse_quantity

#: Default bare-motor mechanical time constant τm = J·R/(K² + R·b) [s] used to guess J (see
#: :meth:`Motor.nominal_params`). Seed 1's measured armature inertias (≈ 1e-5 kg·m² at the motor
#: shaft of the NeveRest units) give τm ≈ 20-40 ms with the data-sheet K and R.
DEFAULT_MECHANICAL_TIME_CONSTANT = 0.030

#: Default electrical time constant L/R [s] when no source gives the inductance.
DEFAULT_ELECTRICAL_TIME_CONSTANT = 0.3e-3

#: Share of the free-running Coulomb loss taken as the gearbox's load-independent drag τ0 (the rest is
#: the motor's brush and bearing friction). A data sheet cannot separate them: an ASSUMPTION.
DEFAULT_GEARBOX_DRAG_SHARE = 0.5

# TOML field -> SI unit. Required fields first.
_REQUIRED_QUANTITIES = {
    "nominal_voltage": "V",
    "free_speed": "rad/s",
    "stall_torque": "N*m",
    "stall_current": "A",
    "free_current": "A",
}
_OPTIONAL_QUANTITIES = {
    "motor_free_speed": "rad/s",
    "inductance": "H",
    "armature_inertia": "kg*m^2",
}
_NUMBERS = ("gear_ratio", "cpr", "motor_cpr")
_TEXT = ("name", "note")
_LISTS = ("aliases", "unconfirmed")
_KNOWN_FIELDS = (
    set(_REQUIRED_QUANTITIES) | set(_OPTIONAL_QUANTITIES) | set(_NUMBERS) | set(_TEXT) | set(_LISTS) | {"sources"}
)
_REQUIRED_FIELDS = ("name", "gear_ratio", "cpr", *_REQUIRED_QUANTITIES)


@dataclass(frozen=True)
class Motor:
    """One catalogue entry: the nominal (data-sheet) figures of a gearmotor.

    Parameters
    ----------
    key
        Short identifier (``"neverest40"``).
    name
        Full product name.
    cpr
        Encoder counts per output-shaft revolution [counts/rev].
    gear_ratio
        Motor-shaft revolutions per output revolution [-].
    nominal_voltage
        Voltage at which the figures are given [V].
    free_speed
        No-load speed of the output shaft at the nominal voltage [rad/s].
    stall_torque
        Output-shaft stall torque at the nominal voltage [N·m].
    stall_current
        Stall current at the nominal voltage [A].
    free_current
        No-load current at the nominal voltage [A].
    sources
        Field name -> where the figure comes from.
    unconfirmed
        Fields that could not be confirmed against a vendor sheet or the FTC SDK.
    note
        Disagreements between sources and other remarks.
    aliases
        Other names accepted by :meth:`from_catalog`.
    motor_cpr
        Encoder counts per motor-shaft revolution [counts/rev], if known.
    motor_free_speed
        No-load speed of the motor shaft [rad/s], if known.
    inductance
        Typical winding inductance [H], if a source gives it.
    armature_inertia
        Armature inertia at the motor shaft [kg·m²], if a source gives it.
    """

    key: str
    name: str
    cpr: float
    gear_ratio: float
    nominal_voltage: float
    free_speed: float
    stall_torque: float
    stall_current: float
    free_current: float
    sources: dict[str, str] = field(default_factory=dict)
    unconfirmed: tuple[str, ...] = ()
    note: str = ""
    aliases: tuple[str, ...] = ()
    motor_cpr: float | None = None
    motor_free_speed: float | None = None
    inductance: float | None = None
    armature_inertia: float | None = None

    # ---- factory ----------------------------------------------------------------------------
    @classmethod
    def from_catalog(cls, key: str, *, path: str | PathLike[str] | None = None) -> Motor:
        """The catalogue entry ``key``.

        Parameters
        ----------
        key
            A key (``"neverest40"``), a product name or an alias; case, spaces, dashes, dots and
            underscores are ignored (``"NeveRest 40"``, ``"goBILDA 5202-19"``).
        path
            Another catalogue file of the same format (default: the package's ``motors.toml``).

        Raises
        ------
        OptionError
            If no entry matches; the message lists the valid keys.
        """
        motors = list_motors(path=path)
        wanted = _normalize(key)
        for motor in motors:
            names = (motor.key, motor.name, *motor.aliases)
            if wanted in {_normalize(n) for n in names}:
                return motor
        valid = ", ".join(m.key for m in motors)
        raise OptionError(f"unknown motor {key!r}; valid motors: {valid}")

    # ---- WPILib-style derivations ---------------------------------------------------------------
    @property
    def resistance(self) -> float:
        """Terminal resistance R = V/I_stall [Ω]."""
        return self.nominal_voltage / self.stall_current

    @property
    def torque_constant(self) -> float:
        """Kt = τ_stall/I_stall [N·m/A] at the output shaft (includes the gearbox loss at stall)."""
        return self.stall_torque / self.stall_current

    @property
    def back_emf_constant(self) -> float:
        """Ke = 1/Kv with Kv = ω_free/(V − R·I_free) [V·s/rad] at the output shaft.

        Notes
        -----
        At free speed the winding carries I_free, so the back-EMF is V − R·I_free (WPILib's
        ``DCMotor`` derives Kv the same way).
        """
        return (self.nominal_voltage - self.resistance * self.free_current) / self.free_speed

    @property
    def gearbox_efficiency_at_stall(self) -> float:
        """Kt/Ke [-]: the fraction of the electromagnetic stall torque that reaches the output."""
        return self.torque_constant / self.back_emf_constant

    def gearbox(self, *, drag_share: float = DEFAULT_GEARBOX_DRAG_SHARE) -> Gearbox:
        """Gearbox figures consistent with the sheet's stall torque, stall current and free running.

        Parameters
        ----------
        drag_share
            Share of the free-running Coulomb loss put in the gearbox's drag τ0 [-] (assumption).

        Returns
        -------
        Gearbox
            ``ratio`` N, ``efficiency`` η, ``loss_torque`` τ0 at the output [N·m].

        Notes
        -----
        The forward single-K model of the whole gearmotor is :meth:`nominal_params` (it reproduces
        the free speed, free current and stall current). Its output torque at stall is
        η·(K·I_stall − Tf), so the sheet's stall torque gives η = τ_stall/(K·I_stall − Tf): the
        stall-torque-to-(Ke·I_stall) ratio, corrected for the friction the stalled motor still
        fights. The free-running loss K·I_free = b·ω_free + Tf is split into the motor's friction
        and the gearbox's drag τ0/η = ``drag_share``·Tf (an assumption: the sheet cannot tell them
        apart, and η does not depend on it).
        """
        if not 0.0 <= drag_share <= 1.0:
            raise OptionError(f"gearbox drag share must lie in [0, 1], got {drag_share}")
        p = self.nominal_params()
        eta = min(self.stall_torque / (p.K * self.stall_current - p.Tf), 1.0)
        return Gearbox(ratio=self.gear_ratio, efficiency=eta, loss_torque=eta * drag_share * p.Tf)

    def motor_params(self, *, drag_share: float = DEFAULT_GEARBOX_DRAG_SHARE) -> MotorParams:
        """The motor alone, reflected to the output through an ideal gearbox (:meth:`gearbox` excluded).

        ``Drivetrain(motor_params(), gearbox()).forward()`` equals :meth:`nominal_params`.
        """
        p = self.nominal_params()
        box = self.gearbox(drag_share=drag_share)
        return p.scaled(Tf=p.Tf - box.loss_torque / box.efficiency)

    def nominal_params(
        self,
        *,
        mechanical_time_constant: float = DEFAULT_MECHANICAL_TIME_CONSTANT,
        viscous_fraction: float = 0.5,
    ) -> MotorParams:
        """Model parameters (K, R, L, J, b, Tf) at the output shaft from the data-sheet figures.

        Parameters
        ----------
        mechanical_time_constant
            Assumed τm = J·R/(K² + R·b) of the bare gearmotor [s], used to guess J.
        viscous_fraction
            Share of the free-running loss torque taken as viscous (the rest is Coulomb) [-].

        Returns
        -------
        MotorParams
            Nominal parameters: a starting point for fits and a reference to compare against,
            not a measurement.

        Raises
        ------
        OptionError
            If an option is out of range.

        Notes
        -----
        - R = V/I_stall and K = Ke = (V − R·I_free)/ω_free (WPILib's derivation). The model has one
          K; Ke is used because Kt = τ_stall/I_stall is measured through a lossy gearbox and is
          the less accurate figure (seed 1, "Experimental Notes"). :attr:`torque_constant`
          reports Kt separately.
        - Friction: at free speed the motor torque only overcomes friction, K·I_free =
          b·ω_free + Tf. The split of that loss into viscous and Coulomb parts is an ASSUMPTION
          (half and half by default): a data sheet cannot tell them apart.
        - L: the catalogue's inductance when a source gives one (seed 1's LCR measurements),
          else L = 0.3 ms·R (an electrical pole L/R ≈ 0.3 ms, an assumption).
        - J: no source gives the armature inertia reflected through the gearbox. It is an
          ASSUMPTION from a bare-motor mechanical time constant, J = τm·(K² + R·b)/R, with
          τm = 30 ms by default (seed 1's armature inertias give 20-40 ms); when the catalogue
          has ``armature_inertia`` at the motor shaft, J = J_m·N² instead.

        With these choices the model reproduces the data sheet's free speed, free current and
        stall current exactly at the nominal voltage; its stall torque K·V/R − Tf is larger than
        the sheet's by the gearbox loss.

        References
        ----------
        Seed 1, "Equations" (1)-(4) and "Experimental Notes"; WPILib ``DCMotor``.
        """
        if not (math.isfinite(mechanical_time_constant) and mechanical_time_constant > 0):
            raise OptionError(f"mechanical time constant must be positive, got {mechanical_time_constant}")
        if not 0.0 <= viscous_fraction <= 1.0:
            raise OptionError(f"viscous fraction must lie in [0, 1], got {viscous_fraction}")
        R = self.resistance
        K = self.back_emf_constant
        loss = K * self.free_current  # friction torque at free speed [N·m]
        b = viscous_fraction * loss / self.free_speed
        Tf = (1.0 - viscous_fraction) * loss
        L = self.inductance if self.inductance is not None else DEFAULT_ELECTRICAL_TIME_CONSTANT * R
        if self.armature_inertia is not None:
            J = self.armature_inertia * self.gear_ratio**2
        else:
            J = mechanical_time_constant * (K**2 + R * b) / R
        return MotorParams(K=K, R=R, L=L, J=J, b=b, Tf=Tf)

    def thermal_model(self) -> ThermalModel:
        """The motor's thermal network and magnets (``data/thermal.toml``; every figure an estimate with its reason).

        Raises
        ------
        InputError
            If the thermal table is malformed or has no family for this motor.
        """
        family, _ = thermal_family(self.key)
        try:
            values = {name: parse_quantity(family[name], unit, name=name) for name, unit in _THERMAL_FIELDS.items()}
        except (KeyError, OptionError) as exc:
            raise InputError(f"motor {self.key!r}: thermal figures: {exc}", path="motorlab/data/thermal.toml") from None
        magnet = str(family.get("magnet", "ferrite"))
        if magnet not in MAGNET_COEFFICIENTS:
            raise InputError(f"motor {self.key!r}: unknown magnet {magnet!r}", path="motorlab/data/thermal.toml")
        return ThermalModel(**values, magnet_coefficient=MAGNET_COEFFICIENTS[magnet])

    def counts_per_radian(self) -> float:
        """Encoder counts per radian of the output shaft [counts/rad]."""
        return self.cpr / (2 * math.pi)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict: SI figures with units, the derived constants, sources and flags."""
        return {
            "key": self.key,
            "name": self.name,
            "gear_ratio": self.gear_ratio,
            "cpr": self.cpr,
            "motor_cpr": self.motor_cpr,
            "nominal_voltage": {"value": self.nominal_voltage, "unit": "V"},
            "free_speed": {"value": self.free_speed, "unit": "rad/s"},
            "stall_torque": {"value": self.stall_torque, "unit": "N*m"},
            "stall_current": {"value": self.stall_current, "unit": "A"},
            "free_current": {"value": self.free_current, "unit": "A"},
            "motor_free_speed": None
            if self.motor_free_speed is None
            else {"value": self.motor_free_speed, "unit": "rad/s"},
            "inductance": None if self.inductance is None else {"value": self.inductance, "unit": "H"},
            "derived": {
                "R": {"value": self.resistance, "unit": "ohm"},
                "Kt": {"value": self.torque_constant, "unit": "N*m/A"},
                "Ke": {"value": self.back_emf_constant, "unit": "V*s/rad"},
                "efficiency": {"value": self.gearbox().efficiency, "unit": "1"},
                "loss_torque": {"value": self.gearbox().loss_torque, "unit": "N*m"},
            },
            "unconfirmed": list(self.unconfirmed),
            "sources": dict(self.sources),
            "note": self.note,
        }


_THERMAL_FIELDS = {"winding_to_case": "K/W", "case_to_ambient": "K/W", "winding_capacity": "J/K",
                   "case_capacity": "J/K"}


def thermal_family(key: str) -> tuple[dict[str, Any], str]:
    """The thermal family (figures and their ``sources``) of catalogue motor ``key``, and its name.

    Raises
    ------
    InputError
        No family lists the motor.
    """
    text = resources.files("motorlab").joinpath("data/thermal.toml").read_text(encoding="utf-8")
    families = tomllib.loads(text).get("families", {})
    for name, family in families.items():
        if key in family.get("motors", ()):
            return family, name
    raise InputError(f"no thermal figures for motor {key!r}", path="motorlab/data/thermal.toml")


def list_motors(*, path: str | PathLike[str] | None = None) -> list[Motor]:
    """Every catalogue entry, in file order.

    Parameters
    ----------
    path
        A catalogue file of the same format (default: the package's ``data/motors.toml``).

    Raises
    ------
    InputError
        If the file is not valid TOML, or an entry lacks a field, has an unknown field, a wrong
        unit or a physically impossible figure (the message names the entry).
    """
    if path is None:
        where = "motorlab/data/motors.toml"
        text = resources.files("motorlab").joinpath("data/motors.toml").read_text(encoding="utf-8")
    else:
        where = str(path)
        text = Path(path).read_text(encoding="utf-8")
    return list(_parsed_catalog(text, where))


@lru_cache(maxsize=8)
def _parsed_catalog(text: str, where: str) -> tuple[Motor, ...]:
    """The entries of a catalogue's text, parsed once per text (pint's parsing of every figure takes a
    third of a second: every virtual rig and every ``--motor`` looks the catalogue up; entries are frozen)."""
    try:
        table = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"not a valid catalogue: {exc}", path=where) from None
    except (ValueError, RecursionError):  # an integer of 4,300 digits, or tables nested too deeply
        raise InputError("not a valid catalogue: a number or a nesting beyond any motor's figures",
                         path=where) from None
    return tuple(_motor_from_entry(key, entry, where) for key, entry in table.items())


def _motor_from_entry(key: str, entry: Any, where: str) -> Motor:
    def fail(message: str) -> InputError:
        return InputError(f"motor {key!r}: {message}", path=where)

    if not isinstance(entry, dict):
        raise fail("expected a table")
    unknown = sorted(set(entry) - _KNOWN_FIELDS)
    if unknown:
        raise fail("unknown field(s) " + ", ".join(unknown))
    missing = [name for name in _REQUIRED_FIELDS if name not in entry]
    if missing:
        raise fail("missing field(s) " + ", ".join(missing))
    values: dict[str, Any] = {}
    try:
        for name, unit in (_REQUIRED_QUANTITIES | _OPTIONAL_QUANTITIES).items():
            if name in entry:
                values[name] = parse_quantity(entry[name], unit, name=name)
        for name in _NUMBERS:
            if name in entry:
                values[name] = parse_quantity(entry[name], "", name=name)
    except OptionError as exc:
        raise fail(exc.message) from None
    for name, value in values.items():
        if value <= 0:
            raise fail(f"{name} must be positive, got {entry[name]!r}")
    if values["free_current"] >= values["stall_current"]:
        raise fail("free current must be smaller than the stall current")
    sources = entry.get("sources", {})
    if not isinstance(sources, dict) or not all(isinstance(v, str) for v in sources.values()):
        raise fail("sources must be a table of strings")
    unconfirmed = tuple(entry.get("unconfirmed", ()))
    bad = [name for name in unconfirmed if name not in _KNOWN_FIELDS]
    if bad:
        raise fail("unconfirmed lists unknown field(s) " + ", ".join(bad))
    return Motor(
        key=key,
        name=str(entry["name"]),
        cpr=values["cpr"],
        gear_ratio=values["gear_ratio"],
        nominal_voltage=values["nominal_voltage"],
        free_speed=values["free_speed"],
        stall_torque=values["stall_torque"],
        stall_current=values["stall_current"],
        free_current=values["free_current"],
        sources=dict(sources),
        unconfirmed=unconfirmed,
        note=str(entry.get("note", "")),
        aliases=tuple(str(a) for a in entry.get("aliases", ())),
        motor_cpr=values.get("motor_cpr"),
        motor_free_speed=values.get("motor_free_speed"),
        inductance=values.get("inductance"),
        armature_inertia=values.get("armature_inertia"),
    )


def _normalize(name: str) -> str:
    """Lower case without spaces, dashes, underscores, dots, colons or slashes."""
    return re.sub(r"[\s\-_.:/]+", "", str(name).lower())
