"""The virtual dynamometer's locked-rotor (stall) runs: the winding heats as on VEX's dynamometer.

The shaft is held (a brake or a lever on a load cell), a bench supply holds a voltage, and the rig logs
time, terminal voltage, current and the held torque every ~0.35 s (VEX's rate) while the winding heats
through the unit's thermal network (:class:`motorlab.thermal.network.ThermalModel`, the catalogue's figures
unless given). The simulation is :func:`motorlab.model.simulate.simulate` with the thermal model (inductance,
supply limit, stiction holding the rotor); ``truth.json`` records the temperatures at every sample.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from motorlab.errors import OptionError
from motorlab.io.csv_table import write_csv
from motorlab.model.simulate import BenchSupply, State, simulate
from motorlab.rig.base import PathArg, RigRun, check_size
from motorlab.rig.instruments import quantize
from motorlab.rig.virtual_core import RigCore, check_positive
from motorlab.thermal.network import ThermalModel

#: Simulator step of a stall run [s] (the winding's L/R ≈ 1 ms; the rotor does not move).
STALL_DT = 5e-3
#: How often R and K follow the temperatures in a stall run [s].
STALL_THERMAL_STEP = 0.5
#: Logging interval of VEX's dynamometer [s] and the jitter on it [s].
STALL_SAMPLE_INTERVAL = 0.35
STALL_SAMPLE_JITTER = 0.05
#: Reading noise: current [A] (fraction, floor), voltage [V], torque [N·m] (fraction, floor).
STALL_CURRENT_NOISE = (0.002, 0.02)
STALL_VOLTAGE_NOISE = 0.001
STALL_TORQUE_NOISE = (0.003, 0.001)


class ThermalExperiments(RigCore):
    """Locked-rotor runs on the simulated unit (its thermal model: the catalogue's, or the unit's own)."""

    def unit_thermal(self) -> ThermalModel:
        """The unit's thermal network: its parameters' own, else the catalogue's estimate."""
        return self.params.thermal if self.params.thermal is not None else self.motor.thermal_model()

    def stall(
        self,
        path: PathArg,
        *,
        voltage: float = 6.0,
        duration: float = 120.0,
        current_limit: float = 100.0,
        initial_temperature: float | None = None,
        sample_interval: float = STALL_SAMPLE_INTERVAL,
        torque: bool = True,
    ) -> RigRun:
        """A locked-rotor run: the shaft held, ``voltage`` held for ``duration`` while the winding heats.

        Parameters
        ----------
        path
            CSV to write: ``time_s,voltage_V,current_A,torque_Nm``.
        voltage
            Supply voltage [V].
        duration
            Length of the run [s].
        current_limit
            The supply's current limit [A] (VEX's supply: 100 A).
        initial_temperature
            The winding's (and case's) temperature at the start [°C] (default: the ambient, 25 °C).
        sample_interval
            Logging interval [s] (each interval jittered by up to 50 ms, as VEX's logs).
        torque
            Log the held torque (a load cell on a lever).

        Returns
        -------
        RigRun
            ``truth["expected"]``: R and K at 25 °C (K at the held shaft), the thermal network, the initial
            temperature and the true winding and case temperatures at every logged sample.
        """
        for value, name, unit in ((voltage, "voltage", "V"), (duration, "duration", "s"),
                                  (current_limit, "current limit", "A"), (sample_interval, "sample interval", "s")):
            check_positive(value, name, unit)
        check_size(duration / STALL_DT, f"simulator steps ({duration:.3g} s in steps of {STALL_DT:g} s)",
                   hint="a stall run lasts minutes at most")
        thermal = self.unit_thermal()
        t0 = thermal.ambient_temperature if initial_temperature is None else float(initial_temperature)
        if not -40 <= t0 <= 200:
            raise OptionError(f"the initial temperature must lie between −40 and 200 °C, got {t0:g} °C")
        rng = self._rng("stall")
        # The rotor is held: stiction far above any torque the winding makes keeps it still.
        held = replace(self.params, thermal=thermal, Tf=1e6, b=0.0)
        sim = simulate(held, BenchSupply(voltage, current_limit), duration=duration + 0.01, dt=STALL_DT,
                       initial=State(winding_temperature=t0, case_temperature=t0), thermal_step=STALL_THERMAL_STEP)
        steps = sample_interval + rng.uniform(0.0, STALL_SAMPLE_JITTER, int(duration / sample_interval) + 2)
        times = np.concatenate([[0.001], 0.001 + np.cumsum(steps)])
        times = times[times <= duration]
        state = sim.sample(times)
        assert sim.winding_temperature is not None
        assert sim.case_temperature is not None
        tw = np.interp(times, sim.time, sim.winding_temperature)
        tc = np.interp(times, sim.time, sim.case_temperature)
        eta, tau0 = self.gearbox.efficiency, self.gearbox.loss_torque
        true_torque = np.clip(eta * self.params.K * thermal.constant_factor(tc) * state["current"] - tau0, 0.0, None)
        columns: dict[str, Any] = {
            "time_s": quantize(times, 1e-3),
            "voltage_V": quantize(state["voltage"] + rng.normal(0, STALL_VOLTAGE_NOISE, times.size), 1e-3),
            "current_A": quantize(state["current"] + rng.normal(0, 1, times.size) * (
                STALL_CURRENT_NOISE[0] * state["current"] + STALL_CURRENT_NOISE[1]), 1e-2),
        }
        if torque:
            columns["torque_Nm"] = quantize(true_torque + rng.normal(0, 1, times.size) * (
                STALL_TORQUE_NOISE[0] * true_torque + STALL_TORQUE_NOISE[1]), 1e-3)
        path = Path(path)
        write_csv(path, columns, metadata={"experiment": "stall", "motor": self.motor.key, "voltage_V": voltage})
        expected = {
            "R": self.params.R, "K": eta * self.params.K, "Ke": self.params.K, "tau0": -tau0,
            "R_wc": thermal.winding_to_case, "R_ca": thermal.case_to_ambient, "C_w": thermal.winding_capacity,
            "C_c": thermal.case_capacity, "magnet_coefficient": thermal.magnet_coefficient,
            "initial_temperature": t0, "sample_times": times, "winding_temperature": tw, "case_temperature": tc,
            "current": state["current"], "supply_current_limited": bool(np.any(sim.mode == 1)),
        }
        settings = {"voltage": voltage, "duration": duration, "current_limit": current_limit,
                    "initial_temperature": t0, "sample_interval": sample_interval, "torque": torque, "dt": STALL_DT,
                    "thermal_step": STALL_THERMAL_STEP}
        return self._finish("stall", [path], settings=settings, expected=expected, flywheel=False,
                            instruments={"current_noise": STALL_CURRENT_NOISE, "voltage_noise": STALL_VOLTAGE_NOISE,
                                         "torque_noise": STALL_TORQUE_NOISE, "thermal": thermal.to_dict()})
