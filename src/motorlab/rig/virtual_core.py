"""The virtual dynamometer's core: one simulated unit, its instruments and what every experiment shares.

:class:`RigCore` holds the unit, the flywheel and the instruments and writes each run's truth;
the experiments are methods of its subclasses (seed 1's in :mod:`motorlab.rig.virtual`, seed 2's
in :mod:`motorlab.rig.virtual_seed2`, the identification logs in :mod:`motorlab.rig.virtual_logs`),
put together as :class:`motorlab.rig.virtual.VirtualRig`.
"""

from __future__ import annotations

import json
import math
import zlib
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from motorlab.catalog import Motor
from motorlab.errors import OptionError
from motorlab.gearbox import Drivetrain, Gearbox
from motorlab.model import MotorParams
from motorlab.model.simulate import (
    Drive,
    Simulation,
    State,
    simulate,
)
from motorlab.results import jsonable
from motorlab.rig.base import MAX_READINGS, PathArg, RigRun, check_size, write_truth
from motorlab.rig.flywheel import Flywheel
from motorlab.rig.instruments import Encoder, Instruments
from motorlab.rig.units import Commutator, UnitSpread, draw_unit, unit_name

#: Experiment names (CLI spelling) -> method names.
EXPERIMENTS: dict[str, str] = {
    "spindown": "spindown",
    "spinup": "spinup",
    "free-spinup": "free_spinup",
    "terminal": "terminal",
    "lcr": "lcr",
    "torque": "torque",
    "amplifier": "amplifier",
    "tachometer": "tachometer",
    "pulse": "pulse",
    "transient": "transient",
    "sysid": "sysid",
    "stall": "stall",
}

#: Internal step of the simulator for flywheel runs [s] (mechanical time constant ≈ 10 s).
FLYWHEEL_DT = 1e-3
#: Screen divisions before the trigger with the horizontal position "to the left" (seed 1).
PRE_TRIGGER_DIVISIONS = 0.2


def check_positive(value: float, name: str, unit: str) -> float:
    if not (math.isfinite(value) and value > 0):
        raise OptionError(f"{name} must be positive, got {value:g} {unit}")
    return float(value)


def stepped_currents(values: Sequence[float] | None, name: str = "current") -> np.ndarray | None:
    if values is None:
        return None
    arr = np.asarray(list(values), dtype=float)
    if arr.size == 0:
        raise OptionError(f"no {name} values given")
    check_size(arr.size, f"{name} settings", limit=MAX_READINGS)
    if not np.all(np.isfinite(arr)):
        raise OptionError(f"{name} values must be finite")
    if np.any(arr < 0):
        raise OptionError(f"{name} {arr[arr < 0][0]:g} A is negative; give magnitudes (the rig sets the polarity)")
    return arr


def steady_state(params: MotorParams, current: float, *, voltage_limit: float) -> tuple[float, float, str]:
    """Steady speed [rad/s], current [A] and supply mode of a current source with a voltage limit.

    Notes
    -----
    In constant current, K·I = b·ω + Tf gives ω = (K·I − Tf)/b (0 if K·I ≤ Tf: stiction holds the
    shaft). If the terminal voltage R·I + K·ω would exceed the limit, the source runs in constant
    voltage at the limit: ω = (K·V − R·Tf)/(K² + R·b), I = (b·ω + Tf)/K (seed 1, "Terminal
    Velocity Experiment"; seed 2's amplifier compliance).
    """
    p = params
    if p.K * current <= p.Tf:
        return 0.0, current, "CC"
    if p.b <= 0:
        return p.free_speed(voltage_limit), p.free_current(voltage_limit), "CV"
    speed = (p.K * current - p.Tf) / p.b
    if p.R * current + p.K * speed > voltage_limit:
        return p.free_speed(voltage_limit), p.free_current(voltage_limit), "CV"
    return speed, current, "CC"


class RigCore:
    """A simulated dynamometer with one unit of a catalogue motor on it (see :class:`VirtualRig`)."""

    experiments: tuple[str, ...] = tuple(EXPERIMENTS)

    def __init__(
        self,
        motor: Motor | str,
        *,
        unit_seed: int = 0,
        noise_seed: int = 0,
        params: MotorParams | None = None,
        spread: UnitSpread | None = None,
        flywheel: Flywheel | None = None,
        instruments: Instruments | None = None,
        commutator: Commutator | None = None,
        gearbox: Gearbox | None = None,
        heating: bool = False,
    ):
        self.motor = Motor.from_catalog(motor) if isinstance(motor, str) else motor
        if unit_seed < 0 or noise_seed < 0:
            raise OptionError("unit and noise seeds must not be negative")
        self.unit_seed = int(unit_seed)
        self.noise_seed = int(noise_seed)
        self.spread = spread or UnitSpread()
        self.gearbox = gearbox if gearbox is not None else Gearbox(ratio=self.motor.gear_ratio)
        if params is None:
            params = draw_unit(self.motor, self.unit_seed, spread=self.spread)
            drag = self.gearbox.loss_torque / self.gearbox.efficiency
            if drag > 0:
                params = params.scaled(Tf=max(params.Tf - drag, 0.0))
        if heating and params.thermal is None:
            params = params.scaled(thermal=self.motor.thermal_model())
        self.params = params
        self.heat_log: list[dict[str, float]] = []
        self.flywheel = flywheel or Flywheel()
        self.instruments = instruments or Instruments()
        self.commutator = commutator or Commutator()
        self.encoder = Encoder(self.motor.cpr)

    # ---- plumbing ---------------------------------------------------------------------------
    @property
    def unit(self) -> str:
        """The unit's letter name."""
        return unit_name(self.unit_seed)

    def __repr__(self) -> str:
        return f"VirtualRig({self.motor.key!r}, unit {self.unit}, noise_seed={self.noise_seed})"

    def run(self, experiment: str, path: PathArg, **settings: Any) -> RigRun:
        """Run ``experiment`` (a key of :data:`EXPERIMENTS`) writing ``path``; settings go to its method."""
        if experiment not in EXPERIMENTS:
            raise OptionError(f"unknown experiment {experiment!r}; known: {', '.join(EXPERIMENTS)}")
        method: Callable[..., RigRun] = getattr(self, EXPERIMENTS[experiment])
        return method(path, **settings)

    def _rng(self, experiment: str) -> np.random.Generator:
        # One independent stream per (noise seed, unit, motor, experiment): running one experiment
        # never changes the noise of another.
        return np.random.default_rng(
            [self.noise_seed, self.unit_seed, zlib.crc32(self.motor.key.encode()), zlib.crc32(experiment.encode())]
        )

    def _drivetrain(self, with_flywheel: bool) -> Drivetrain:
        fw = self.flywheel
        if not with_flywheel:
            return Drivetrain(self.params, self.gearbox)
        return Drivetrain(self.params, self.gearbox, fw.reflected_inertia, fw.reflected_viscous_friction,
                          fw.reflected_coulomb_friction)

    def _loaded(self, with_flywheel: bool) -> MotorParams:
        """The forward single-K equivalent (what a motoring analysis finds; = motor + load when ideal)."""
        return self._drivetrain(with_flywheel).forward()

    def _finish(
        self,
        experiment: str,
        paths: Sequence[Path],
        *,
        settings: dict[str, Any],
        expected: dict[str, Any],
        instruments: dict[str, Any],
        flywheel: bool,
    ) -> RigRun:
        loaded = self._loaded(flywheel)
        entry: dict[str, Any] = {
            "experiment": experiment,
            "files": [p.name for p in paths],
            "motor": self.motor.key,
            "cpr": self.motor.cpr,
            "unit": self.unit,
            "unit_seed": self.unit_seed,
            "noise_seed": self.noise_seed,
            # The model's parameters of the bare gearmotor at the output shaft (forward single-K
            # equivalent: the gearbox's drag and output inertia ÷ η included); "motor_params" are the
            # motor's own through an ideal gearbox. The two are equal with an ideal gearbox.
            "params": self._loaded(False).to_dict(),
            "motor_params": self.params.to_dict(),
            "params_units": self.params.units(),
            "nominal_params": self.motor.nominal_params().to_dict(),
            "unit_spread": self.spread.to_dict(),
            "flywheel": self.flywheel.settings() if flywheel else None,
            "totals": {"J": loaded.J, "b": loaded.b, "Tf": loaded.Tf},
            "gearbox": self.gearbox.to_dict(),
            "output_figures": self._drivetrain(flywheel).output_figures(),
            "expected": expected,
            "settings": settings,
            "instruments": instruments,
        }
        if self.params.thermal is not None:
            entry["thermal"] = self.params.thermal.to_dict()
            entry["temperatures"] = self.heat_log[-1] if self.heat_log else None
        truth_path = write_truth(paths[0], entry)
        return RigRun(experiment, tuple(paths), truth_path, json.loads(json.dumps(jsonable(entry))))

    def _simulate(
        self, params: MotorParams | Drivetrain, schedule: Sequence[tuple[float, Drive]], *, duration: float, dt: float,
        initial_speed: float = 0.0, initial_position: float = 0.0,
    ) -> Simulation:
        # Refused before the simulator allocates its arrays (on_time = 1e9 s asked for 7 TiB).
        check_size(duration / dt, f"simulator steps ({duration:.3g} s in steps of {dt:.3g} s)",
                   hint="shorten the run or sample it less finely")
        sim = simulate(
            params, list(schedule), duration=duration, dt=dt,
            initial=State(speed=initial_speed, position=initial_position),
        )
        if sim.winding_temperature is not None and sim.case_temperature is not None:
            self.heat_log.append({"winding_start_C": float(sim.winding_temperature[0]),
                                  "winding_end_C": float(sim.winding_temperature[-1]),
                                  "winding_max_C": float(np.max(sim.winding_temperature)),
                                  "case_end_C": float(sim.case_temperature[-1])})
        return sim

    # ---- seed 1: flywheel experiments -----------------------------------------------------------


def time_at_rest(sim: Simulation, after: float) -> float | None:
    """First time ≥ ``after`` at which the shaft is at rest (None if it still turns at the end)."""
    idx = np.flatnonzero((sim.time >= after) & (sim.speed == 0.0))
    return float(sim.time[idx[0]]) if idx.size else None


def timebase_at_least(limit: float) -> float:
    """The smallest 1-2-5 timebase [s/div] not below ``limit``."""
    exponent = math.floor(math.log10(limit))
    for mantissa in (1.0, 2.0, 5.0, 10.0):
        value = mantissa * 10.0**exponent
        if value >= limit * (1 - 1e-12):
            return value
    return 10.0 ** (exponent + 1)


def strictly_increasing(times: np.ndarray, step: float) -> np.ndarray:
    """Cursor readings never repeat: a person would move the cursor one step on."""
    out = np.array(times, dtype=float)
    for k in range(1, out.size):
        if out[k] <= out[k - 1]:
            out[k] = out[k - 1] + step
    return out
