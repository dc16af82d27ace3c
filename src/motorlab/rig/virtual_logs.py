"""Identification logs from the virtual dynamometer: a transient CSV and a SysId JSON."""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from motorlab.errors import OptionError
from motorlab.io.csv_table import write_csv
from motorlab.io.output import write_text_atomic
from motorlab.model import MotorParams, feedforward_from_params
from motorlab.model.simulate import (
    VoltageDrive,
)
from motorlab.rig.base import PathArg, RigRun
from motorlab.rig.instruments import quantize
from motorlab.rig.profiles import voltage_profile
from motorlab.rig.virtual_core import (
    FLYWHEEL_DT,
    RigCore,
    check_positive,
)


class LogExperiments(RigCore):
    """Ordinary logs for whole-model identification and SysId on the simulated unit."""

    def transient(
        self,
        path: PathArg,
        *,
        profile: str = "steps",
        rate: float = 1000.0,
        duration: float = 4.0,
        max_voltage: float = 12.0,
        include_current: bool = True,
        flywheel: bool = False,
        voltage_noise: float = 0.02,
        current_noise: float = 5e-3,
    ) -> RigRun:
        """A voltage-driven identification log (steps, ramps or random steps) sampled at ``rate``.

        Parameters
        ----------
        path
            CSV to write: ``time_s,voltage_V,current_A,position_counts`` (no current column
            without ``include_current``).
        profile
            ``"steps"`` (0, ½, 1, ¼, −½, −1, 0 of ``max_voltage``), ``"ramps"`` (triangle ±max) or
            ``"random"`` (random levels held 0.1-0.5 s).
        rate
            Sample rate [Hz] (e.g. 1 kHz or 10 kHz).
        duration
            Length [s].
        max_voltage
            Largest |voltage| [V].
        include_current
            Log the current.
        flywheel
            Attach the flywheel.
        voltage_noise
            Rms noise of the voltage measurement [V] (1 mV resolution).
        current_noise
            Rms noise of the current measurement [A] (1 mA resolution).

        Returns
        -------
        RigRun
            ``truth["expected"]``: K, R, L, J, b, Tf of what is driven (totals with a flywheel).
        """
        for value, name, unit in ((rate, "rate", "Hz"), (duration, "duration", "s"),
                                  (max_voltage, "maximum voltage", "V")):
            check_positive(value, name, unit)
        if voltage_noise < 0 or current_noise < 0:
            raise OptionError("noise levels must not be negative")
        rng = self._rng("transient")
        voltage_of = voltage_profile(profile, duration, max_voltage, rng)
        loaded = self._loaded(flywheel)
        period = 1.0 / rate
        substeps = max(1, math.ceil(period / 1e-3))
        dt = period / substeps
        sim = self._simulate(self._drivetrain(flywheel), [(0.0, VoltageDrive(voltage_of))],
                             duration=duration + period, dt=dt)
        t = np.arange(round(duration * rate) + 1) * period
        state = sim.sample(t)
        applied = voltage_of(t)
        columns: dict[str, Any] = {
            "time_s": quantize(t, 1e-7),
            "voltage_V": quantize(applied + rng.normal(0.0, voltage_noise, t.shape), 1e-3),
        }
        if include_current:
            columns["current_A"] = quantize(state["current"] + rng.normal(0.0, current_noise, t.shape), 1e-3)
        # A real encoder is zeroed with the shaft anywhere within a count: the counting errors of a
        # run then differ from unit to unit (a shaft exactly on an edge would repeat one error pattern).
        # Drawn last so that the other noise streams stay as they were.
        phase = rng.uniform(0.0, 2.0 * math.pi / self.encoder.counts_per_revolution)
        columns["position_counts"] = self.encoder.counts(state["position"] + phase)
        path = Path(path)
        write_csv(path, columns, metadata={"experiment": "transient", "motor": self.motor.key,
                                           "cpr": self.motor.cpr, "profile": profile})
        expected = loaded.to_dict()
        settings = {"profile": profile, "rate": rate, "duration": duration, "max_voltage": max_voltage,
                    "include_current": include_current, "voltage_noise": voltage_noise,
                    "current_noise": current_noise, "dt": dt, "encoder_phase": phase}
        return self._finish("transient", [path], settings=settings, expected=expected,
                            instruments={"encoder": self.encoder.settings()}, flywheel=flywheel)

    def sysid(
        self,
        path: PathArg,
        *,
        ramp_rate: float = 0.25,
        step_voltage: float = 7.0,
        quasistatic_duration: float = 30.0,
        dynamic_duration: float = 10.0,
        flywheel: bool = True,
        start_time: float = 10.0,
        gap: float = 5.0,
    ) -> RigRun:
        """WPILib SysId tests (quasistatic ramps, dynamic steps, both directions) as SysId's JSON.

        Parameters
        ----------
        path
            JSON to write: keys ``slow-forward``, ``slow-backward``, ``fast-forward``,
            ``fast-backward``, rows ``[timestamp s, voltage V, position rot, velocity rot/s]``,
            ``"sysid": true``, ``"test": "Simple"``, ``"units": "Rotations"``, ``"unitsPerRotation": 1.0``.
        ramp_rate
            Quasistatic ramp rate [V/s] (SysId default 0.25 V/s).
        step_voltage
            Dynamic step [V] (SysId default 7 V).
        quasistatic_duration
            Length of each quasistatic test [s].
        dynamic_duration
            Length of each dynamic test [s].
        flywheel
            Attach the flywheel (default: the dynamometer with its flywheel, so kA is observable).
        start_time
            Timestamp of the first row [s] (robot clock).
        gap
            Time between tests [s]; the mechanism is at rest at the start of each test.

        Returns
        -------
        RigRun
            ``truth["expected"]``: kS [V], kV [V·s/rad], kA [V·s²/rad] (and per rotation) of
            what is driven, and the totals K, R, J, b, Tf.

        Notes
        -----
        Velocity is what a motor controller reports: the count difference over
        ``velocity_window``, refreshed with position every ``status_period`` (values repeat between
        refreshes, as in real SysId logs).
        """
        ins = self.instruments
        ctrl = ins.controller
        for value, name, unit in ((ramp_rate, "ramp rate", "V/s"), (step_voltage, "step voltage", "V"),
                                  (quasistatic_duration, "quasistatic duration", "s"),
                                  (dynamic_duration, "dynamic duration", "s")):
            check_positive(value, name, unit)
        if gap < 0:
            raise OptionError("gap must not be negative")
        rng = self._rng("sysid")
        loaded = self._loaded(flywheel)
        dt = FLYWHEEL_DT if flywheel else 2e-4
        tests: list[tuple[str, Callable[[np.ndarray], np.ndarray], float]] = [
            ("slow-forward", lambda t: ramp_rate * t, quasistatic_duration),
            ("slow-backward", lambda t: -ramp_rate * t, quasistatic_duration),
            ("fast-forward", lambda t: np.where(t > 0, step_voltage, 0.0), dynamic_duration),
            ("fast-backward", lambda t: np.where(t > 0, -step_voltage, 0.0), dynamic_duration),
        ]
        doc: dict[str, Any] = {}
        position0 = 0.0
        clock = start_time
        for name, command, length in tests:
            doc[name], position0, elapsed = self._sysid_test(command, length, rng, flywheel=flywheel, dt=dt,
                                                             position0=position0, clock=clock)
            clock += elapsed + gap
        doc.update({"sysid": True, "test": "Simple", "units": "Rotations", "unitsPerRotation": 1.0})
        path = Path(path)
        write_text_atomic(path, json.dumps(doc) + "\n")
        expected = _sysid_expected(loaded)
        settings = {"ramp_rate": ramp_rate, "step_voltage": step_voltage,
                    "quasistatic_duration": quasistatic_duration, "dynamic_duration": dynamic_duration,
                    "start_time": start_time, "gap": gap, "dt": dt}
        return self._finish("sysid", [path], settings=settings, expected=expected,
                            instruments={"controller": ctrl.settings(), "encoder": self.encoder.settings()},
                            flywheel=flywheel)

    def _sysid_test(
        self,
        command: Callable[[np.ndarray], np.ndarray],
        length: float,
        rng: np.random.Generator,
        *,
        flywheel: bool,
        dt: float,
        position0: float,
        clock: float,
    ) -> tuple[list[list[float]], float, float]:
        """Run one SysId test of ``length`` [s] from rest at ``position0`` [rad], logged from ``clock`` [s].

        Returns the SysId rows ``[timestamp s, voltage V, position rot, velocity rot/s]``, the final
        shaft position [rad] and the time from the first row to the last [s].
        """
        ctrl = self.instruments.controller
        cpr = self.motor.cpr
        # The command starts one log period after the test's first row (that row logs 0 V).
        lead = ctrl.log_period

        def applied(t: np.ndarray) -> np.ndarray:
            return np.where(t >= lead, command(np.asarray(t) - lead), 0.0)

        n = int(length / ctrl.log_period) + 1
        t_rows = np.arange(n) * ctrl.log_period + rng.normal(0.0, ctrl.log_jitter, n)
        t_rows[0] = 0.0
        t_rows = np.clip(np.maximum.accumulate(t_rows), 0.0, length + lead)
        # The robot loop computes the command, sends it and logs it in the same iteration: the
        # controller holds each row's voltage until the next row (a ramp is a staircase, a step
        # starts at a row), as in a real SysId run. The simulation holds its drive over grid steps,
        # so each change goes to the grid point nearest its row (no systematic delay).
        held = applied(t_rows)
        half = 0.5 * dt

        def staircase(t: np.ndarray) -> np.ndarray:
            k = np.searchsorted(t_rows, np.asarray(t) + half, side="right") - 1
            return held[np.clip(k, 0, held.size - 1)]

        sim = self._simulate(self._drivetrain(flywheel), [(0.0, VoltageDrive(staircase))],
                             duration=length + lead + dt, dt=dt,
                             initial_position=position0)
        volts = held + rng.normal(0.0, ctrl.voltage_noise, n)
        # Status frames: the value logged at t is the one refreshed at the last frame ≤ t. The
        # controller's clock runs apart from the robot loop's: the frames have a phase of their
        # own (frames locked to the rows would make the staleness hinge on the sign of the jitter).
        phase = rng.uniform(0.0, ctrl.status_period)
        frame = np.maximum(np.floor((t_rows + phase) / ctrl.status_period) * ctrl.status_period - phase, 0.0)
        counts_now = self.encoder.counts(sim.sample(frame)["position"])
        counts_then = self.encoder.counts(sim.sample(np.maximum(frame - ctrl.velocity_window, 0.0))["position"])
        window = np.maximum(np.minimum(frame, ctrl.velocity_window), ctrl.velocity_window)
        velocity = (counts_now - counts_then) / window / cpr
        rows = np.column_stack([clock + t_rows, np.round(volts, 6), counts_now / cpr, velocity])
        return [[round(float(x), 6) for x in row] for row in rows], float(sim.position[-1]), float(t_rows[-1])


def _sysid_expected(loaded: MotorParams) -> dict[str, Any]:
    """SysId's kS [V], kV [V·s/rad], kA [V·s²/rad] (and per rotation) of ``loaded``, with its parameters."""
    ff = feedforward_from_params(loaded)
    two_pi = 2 * math.pi
    return {
        **ff,
        "kS_per_rotation": ff["kS"], "kV_per_rotation": ff["kV"] * two_pi, "kA_per_rotation": ff["kA"] * two_pi,
        **dict(loaded.to_dict().items()),
    }
