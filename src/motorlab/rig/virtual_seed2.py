"""Seed 2's bench experiments on the virtual dynamometer: amplifier, tachometer, pulse responses."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from motorlab.errors import OptionError
from motorlab.io.csv_table import write_csv
from motorlab.model.simulate import (
    BenchSupply,
    CurrentDrive,
    Drive,
)
from motorlab.rig.base import PathArg, RigRun, check_size
from motorlab.rig.instruments import quantize
from motorlab.rig.virtual_core import (
    RigCore,
    check_positive,
    steady_state,
)


class Seed2Experiments(RigCore):
    """Seed 2 ("Motor Mechanical Properties" and its gain calibrations) on the simulated unit."""

    def amplifier(self, path: PathArg, *, commands: Sequence[float] | None = None) -> RigRun:
        """Seed 2's "Amplifier Gain Constant": DC commands into the amplifier, output current on a DMM.

        Parameters
        ----------
        path
            CSV to write: ``command_V,current_A``.
        commands
            Command voltages [V] (default 0.25 V steps up to 90 % of the amplifier's 5 A).

        Returns
        -------
        RigRun
            ``truth["expected"]``: Ka [A/V] and the offset [A].

        Notes
        -----
        I_out = Ka·V_in (seed 2) plus a small offset; the output clips at the sustained maximum.
        """
        amp = self.instruments.amplifier
        if commands is None:
            top = 0.9 * amp.max_current / amp.gain
            cmd = np.arange(1, int(top / 0.25) + 1) * 0.25
        else:
            cmd = np.asarray(list(commands), dtype=float)
            if cmd.size == 0 or not np.all(np.isfinite(cmd)):
                raise OptionError("amplifier commands must be finite numbers")
        rng = self._rng("amplifier")
        true_i = amp.current(cmd)
        shown = self.instruments.multimeter.read_current(true_i, rng)
        path = Path(path)
        write_csv(path, {"command_V": cmd, "current_A": shown},
                  metadata={"experiment": "amplifier"})
        expected = {"Ka": amp.gain, "offset": amp.offset, "currents": true_i,
                    "saturated": bool(np.any(np.abs(amp.gain * cmd + amp.offset) > amp.max_current))}
        return self._finish("amplifier", [path], settings={"commands": cmd}, expected=expected,
                            instruments={"amplifier": amp.settings(),
                                         "multimeter": self.instruments.multimeter.settings()},
                            flywheel=False)

    def tachometer(self, path: PathArg, *, commands: Sequence[float] | None = None) -> RigRun:
        """Seed 2's "The Tachometer Gain Constant": steady speeds read by an optical tachometer and a DMM.

        Parameters
        ----------
        path
            CSV to write: ``speed_rpm,tach_voltage_V``.
        commands
            Amplifier commands [V] (default: five giving 30-90 % of the catalogue free speed).

        Returns
        -------
        RigRun
            ``truth["expected"]``: Kt_tach [V·s/rad] and the true speeds.

        Notes
        -----
        v_t = Kt·Ω (seed 2). Driven by the amplifier (a current source): K·I = b·ω + Tf, limited by
        the amplifier's compliance.
        """
        ins = self.instruments
        amp = ins.amplifier
        p = self._loaded(False)
        if commands is None:
            nominal = self.motor.nominal_params()
            targets = np.linspace(0.3, 0.9, 5) * self.motor.free_speed
            amps = (nominal.b * targets + nominal.Tf) / nominal.K
            cmd = np.round((amps - amp.offset) / 2.0, 3)  # the experimenter uses the nominal 2 A/V
        else:
            cmd = np.asarray(list(commands), dtype=float)
            if cmd.size == 0 or not np.all(np.isfinite(cmd)) or np.any(cmd < 0):
                raise OptionError("tachometer commands must be non-negative numbers")
        rng = self._rng("tachometer")
        true_i = amp.current(cmd)
        speeds = np.array([steady_state(p, float(i), voltage_limit=amp.compliance)[0] for i in true_i])
        rpm = ins.optical_tachometer.read_rpm(speeds, rng)
        volts = ins.multimeter.read_voltage(ins.tachometer.gain * speeds, rng)
        path = Path(path)
        write_csv(path, {"speed_rpm": rpm, "tach_voltage_V": volts}, metadata={"experiment": "tachometer"})
        expected = {"Kt_tach": ins.tachometer.gain, "speeds": speeds}
        instruments = {"tachometer": ins.tachometer.settings(), "optical_tachometer":
                       ins.optical_tachometer.settings(), "multimeter": ins.multimeter.settings(),
                       "amplifier": amp.settings()}
        return self._finish("tachometer", [path], settings={"commands": cmd}, expected=expected,
                            instruments=instruments, flywheel=False)

    def pulse(
        self,
        path: PathArg,
        *,
        amplitude: float = 1.0,
        period: float = 2.0,
        duty: float = 0.12,
        periods: int = 1,
        sample_interval: float = 1e-3,
        flywheel: bool = False,
        raw_tach: bool = False,
        dt: float = 2e-4,
    ) -> RigRun:
        """Seed 2's "Motor Mechanical Properties": a unipolar square wave through the amplifier.

        Parameters
        ----------
        path
            CSV to write: ``time_s,command_V,velocity_rad_per_s`` (``tach_voltage_V`` with
            ``raw_tach``), sampled like a scope trace; t = 0 at the first rising command edge.
        amplitude
            Square-wave high level [V] (seed 2: 0.5 V offset + 0.5 V amplitude = 1 V).
        period
            Period [s] (seed 2: 2 s).
        duty
            Duty cycle [-] (seed 2: 10-15 %).
        periods
            Number of periods on screen.
        sample_interval
            Scope sample interval [s].
        flywheel
            Attach the flywheel (default: bare motor, as seed 2 drives its own wheel).
        raw_tach
            Write the tachometer voltage instead of the speed converted with Kt_tach.
        dt
            Simulator step [s].

        Returns
        -------
        RigRun
            ``truth["expected"]``: J, Tf, b, K, Ka, Kt_tach, the accelerations
            α₁ = (Ka·K·V − Tf)/J and α₂ = −Tf/J at zero speed, whether the amplifier saturated.

        Notes
        -----
        J = Ka·Km·V/(Ω̇₁ − Ω̇₂) (seed 2, eq. (5)) holds when friction is Coulomb only.
        """
        ins = self.instruments
        amp = ins.amplifier
        for value, name, unit in ((amplitude, "amplitude", "V"), (period, "period", "s"),
                                  (sample_interval, "sample interval", "s"), (dt, "dt", "s")):
            check_positive(value, name, unit)
        if not 0 < duty < 1:
            raise OptionError(f"duty cycle must lie in (0, 1), got {duty:g}")
        if periods < 1:
            raise OptionError("need at least one period")
        check_size(period * periods / sample_interval,
                   "scope samples (--period × --periods / --sample-interval)", hint="a scope holds 12 Mpts at most")
        rng = self._rng("pulse")
        loaded = self._loaded(flywheel)
        i_on = float(amp.current(amplitude))
        i_off = float(amp.current(0.0))
        on_drive: Drive = BenchSupply(amp.compliance, i_on) if i_on > 0 else CurrentDrive(i_on)
        pre = 0.05 * period * periods
        schedule: list[tuple[float, Drive]] = [(0.0, CurrentDrive(i_off))]
        for k in range(periods):
            schedule += [(pre + k * period, on_drive), (pre + (k + duty) * period, CurrentDrive(i_off))]
        span = period * periods
        sim = self._simulate(self._drivetrain(flywheel), schedule, duration=span + dt, dt=dt)
        t = np.arange(-pre, span - pre, sample_interval)
        state = sim.sample(t + pre)
        phase = np.mod(t, period)
        command = np.where((t >= 0) & (phase < duty * period), amplitude, 0.0)
        command = quantize(command + rng.normal(0.0, ins.scope.vertical_noise, t.shape), 1e-4)
        tach = ins.tachometer.voltage(state["speed"], state["position"], rng)
        path = Path(path)
        columns: dict[str, Any] = {"time_s": quantize(t, 1e-7), "command_V": command}
        if raw_tach:
            columns["tach_voltage_V"] = quantize(tach, 1e-4)
        else:
            columns["velocity_rad_per_s"] = quantize(tach / ins.tachometer.gain, 1e-4)
        write_csv(path, columns, metadata={"experiment": "pulse", "motor": self.motor.key,
                                           "Ka_A_per_V": amp.gain, "Kt_tach_V_s_per_rad": ins.tachometer.gain})
        saturated = bool(np.any((sim.mode == 0) & (sim.time > pre)))
        end_on = pre + duty * period
        expected = {
            "J": loaded.J, "Tf": loaded.Tf, "b": loaded.b, "K": self.params.K,
            "Ka": amp.gain, "Kt_tach": ins.tachometer.gain, "current_on": i_on,
            "acceleration_on": (self.params.K * i_on - loaded.Tf) / loaded.J,
            "acceleration_off": -(loaded.Tf - self.params.K * i_off) / loaded.J,
            "peak_speed": float(np.interp(end_on, sim.time, sim.speed)),
            "amplifier_saturated": saturated,
            "rests_between_pulses": bool(sim.speed[np.searchsorted(sim.time, pre + period) - 1] == 0.0),
        }
        settings = {"amplitude": amplitude, "period": period, "duty": duty, "periods": periods,
                    "sample_interval": sample_interval, "raw_tach": raw_tach, "dt": dt}
        instruments = {"amplifier": amp.settings(), "tachometer": ins.tachometer.settings(),
                       "scope": ins.scope.settings()}
        return self._finish("pulse", [path], settings=settings, expected=expected, instruments=instruments,
                            flywheel=flywheel)

    # ---- identification logs --------------------------------------------------------------------
