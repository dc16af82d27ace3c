"""The virtual dynamometer: the seeds' experiments on a simulated unit, writing real-rig files.

:class:`VirtualRig` holds one unit of a catalogue motor (true parameters drawn by
:func:`~motorlab.rig.units.draw_unit`), the flywheel and the instruments. Each experiment method
simulates the procedure of the seed with :func:`motorlab.model.simulate.simulate` (or, where the seed
waits for a steady state, the closed forms of :mod:`motorlab.model`), reads the result through the
instruments, writes exactly the files a real rig gives, records the truth in ``truth.json`` beside
them and returns a :class:`~motorlab.rig.base.RigRun`.

Experiments (seed section -> method -> file):

- seed 1 "Flywheel and INA219 Experiment" -> :meth:`VirtualRig.spindown` -> FTC log (optionally split)
- seed 1 "First Experiment" (constant current, flywheel) -> :meth:`VirtualRig.spinup` -> FTC log
- seed 1 "Free Motor Spin-Up Experiment" -> :meth:`VirtualRig.free_spinup` -> ``time_ms`` CSV
- seed 1 "Terminal Velocity Experiment" -> :meth:`VirtualRig.terminal` -> ``current_A,frequency_Hz``
- seed 1 "LCR Meter Experiment" -> :meth:`VirtualRig.lcr` -> ``L_uH,Q,DCR_ohm``
- seed 2 "The Motor Torque Constant" -> :meth:`VirtualRig.torque` -> ``current_A,mass_kg``
- seed 2 "Amplifier Gain Constant" -> :meth:`VirtualRig.amplifier` -> ``command_V,current_A``
- seed 2 "The Tachometer Gain Constant" -> :meth:`VirtualRig.tachometer` -> ``speed_rpm,tach_voltage_V``
- seed 2 "Motor Mechanical Properties" -> :meth:`VirtualRig.pulse` -> ``time_s,command_V,velocity_rad_per_s``
- identification logs -> :meth:`VirtualRig.transient` (CSV) and :meth:`VirtualRig.sysid` (SysId JSON)
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from motorlab.analyses.torque import approach_direction
from motorlab.errors import OptionError, RigError
from motorlab.gearbox import Drivetrain
from motorlab.io.csv_table import write_csv
from motorlab.io.ftc import write_ftc_log
from motorlab.io.output import write_text_atomic
from motorlab.model import MotorParams
from motorlab.model.simulate import (
    BenchSupply,
    Drive,
    OpenCircuit,
    Simulation,
)
from motorlab.rig.base import MAX_READINGS, PathArg, RigRun, check_size
from motorlab.rig.instruments import quantize
from motorlab.rig.virtual_core import (  # noqa: F401 - re-exported: the rig's names before the split
    EXPERIMENTS,
    FLYWHEEL_DT,
    PRE_TRIGGER_DIVISIONS,
    check_positive,
    steady_state,
    stepped_currents,
    strictly_increasing,
    time_at_rest,
    timebase_at_least,
)
from motorlab.rig.virtual_logs import LogExperiments
from motorlab.rig.virtual_seed2 import Seed2Experiments
from motorlab.rig.virtual_thermal import ThermalExperiments


class VirtualRig(Seed2Experiments, LogExperiments, ThermalExperiments):
    """A simulated dynamometer with one unit of a catalogue motor on it.

    Parameters
    ----------
    motor
        Catalogue :class:`~motorlab.catalog.Motor` or its key (``"neverest40"``).
    unit_seed
        Which unit (0 -> "A", 1 -> "B" …); its true parameters are drawn from this seed.
    noise_seed
        Seed of every random reading error and timing jitter.
    params
        True parameters to use instead of a drawn unit (at the encoder shaft).
    spread
        Unit-to-unit spreads for the draw.
    flywheel
        The flywheel and step-up gearbox (default: seed 1's steel disc, 25:1).
    instruments
        The instruments (default figures: :mod:`motorlab.rig.instruments`).
    commutator
        Position dependence of the LCR readings.
    gearbox
        The gearmotor's gearbox losses (:class:`~motorlab.gearbox.Gearbox`; ``motor.gearbox()`` gives
        the catalogue's). Default: an ideal gearbox (η = 1, no drag). With a lossy gearbox and a drawn
        unit, the gearbox's drag τ0/η is taken out of the unit's Coulomb friction, so the unit still
        runs free at the catalogue's free current; ``params`` are the motor's own, reflected to the
        output through an ideal gearbox (:func:`motorlab.gearbox.reflect_to_output`).
    heating
        Heat the winding in every experiment (the catalogue's thermal figures, unless ``params`` carry
        their own): R and K drift as the winding and the magnets warm, as on a real rig, and
        ``truth.json`` records the temperatures. Off by default (the seeds' analyses assume a cool
        motor); the stall experiment always heats.

    Raises
    ------
    OptionError
        Unknown motor, negative seeds.
    """

    def spindown(
        self,
        path: PathArg,
        *,
        voltage: float = 12.0,
        current_limit: float = 4.0,
        on_time: float = 30.0,
        coast_time: float = 60.0,
        relay_delay: float = 0.2,
        split: bool = False,
        placeholder_rows: int | None = None,
        blank_lines: int | None = None,
        header: bool = True,
        crlf: bool = False,
    ) -> RigRun:
        """Seed 1's "Flywheel and INA219 Experiment": spin the flywheel up from the bench supply, then coast.

        Parameters
        ----------
        path
            The FTC log to write (with ``split``, the first file; the second is ``<stem>2<suffix>``,
            as ``testFile.txt`` + ``testFile2.txt``).
        voltage
            Supply voltage setting [V] (refused above 16 V: the INA219 is in circuit).
        current_limit
            Supply current limit [A] (seed 1: 4 A for the AndyMark 20 and 40).
        on_time
            Time the OpMode keeps the relay closed [s] (seed 1: 30 s).
        coast_time
            Time logged after the relay opens [s].
        relay_delay
            Time after the OpMode starts at which it closes the relay [s].
        split
            Write the run as the real OpMode does: the powered part in ``path`` followed by
            placeholder zero rows, the coast in the second file, both starting with blank lines.
        placeholder_rows
            Zero rows after the powered part (default: 10 when split, else 0).
        blank_lines
            Blank lines at the top of each file (default: 2 when split, else 0).
        header
            Write the column header line.
        crlf
            Windows line endings.

        Returns
        -------
        RigRun
            Paths written; ``truth["expected"]`` holds K, the totals J, b, Tf with the flywheel,
            γ = b/J, Tf/J and the time the coast starts.

        Raises
        ------
        RigError
            Supply voltage above the INA219's 16 V.
        OptionError
            Settings out of range.

        Notes
        -----
        With the relay open the INA219 reads the back-EMF, V = K·ω; the coast obeys
        J·dω/dt = −b·ω − Tf (seed 1, "Data Analysis" steps 4-7).
        """
        ins = self.instruments
        ins.ina219.check_supply(voltage)
        ins.supply.check(voltage, current_limit)
        for value, name in ((on_time, "on time"), (coast_time, "coast time")):
            check_positive(value, name, "s")
        if relay_delay < 0:
            raise OptionError("relay delay must not be negative")
        rng = self._rng("spindown")
        t_close = relay_delay + ins.relay.operate_time
        t_command_off = relay_delay + on_time
        t_open = t_command_off + ins.relay.release_time
        duration = relay_delay + on_time + coast_time
        schedule: list[tuple[float, Drive]] = [
            (0.0, OpenCircuit()), (t_close, BenchSupply(voltage, current_limit)), (t_open, OpenCircuit())]
        train = self._drivetrain(True)
        sim = self._simulate(train, schedule, duration=duration + 0.01, dt=FLYWHEEL_DT)
        times, counts, bus, current = self._log_ftc(sim, duration, rng)
        log = (times, counts, bus, current)
        paths = _write_spindown_logs(Path(path), log, t_command_off, split=split, header=header, crlf=crlf,
                                     placeholder_rows=placeholder_rows, blank_lines=blank_lines)
        expected = self._spindown_expected(sim, train, t_close, t_open)
        settings = {
            "voltage": voltage, "current_limit": current_limit, "on_time": on_time, "coast_time": coast_time,
            "relay_delay": relay_delay, "relay_closed": t_close, "relay_opened": t_open, "split": split,
            "dt": FLYWHEEL_DT,
        }
        instruments = {
            "ina219": ins.ina219.settings(), "logger": ins.logger.settings(), "supply": ins.supply.settings(),
            "relay": ins.relay.settings(), "encoder": self.encoder.settings(),
        }
        return self._finish("spindown", paths, settings=settings, expected=expected, instruments=instruments,
                            flywheel=True)

    def _spindown_expected(self, sim: Simulation, train: Drivetrain, t_close: float, t_open: float) -> dict[str, Any]:
        """The truth of a spin-down run: the coast's J, b, Tf through the gearbox and the run's flags."""
        on = (sim.time >= t_close) & (sim.time < t_open)
        speed_off = float(np.interp(t_open, sim.time, sim.speed))
        # The coast is seen through the gearbox in the direction the power flows at its start: a
        # flywheel drives the motor's friction (back-driven), so J, b, Tf are physical figures at the
        # output shaft for that direction (= the totals with an ideal gearbox).
        back = train.switches and float(train.flow(0.0, speed_off, 1.0)) < 0
        coast = train.output_figures(back_driven=back)
        return {
            "K": self.params.K,
            "J": coast["J"],
            "b": coast["b"],
            "Tf": coast["Tf"],
            "gamma": coast["b"] / coast["J"],
            "Tf_over_J": coast["Tf"] / coast["J"],
            "gearbox_flow": "back-driven" if back else "forward",
            "coast_start": t_open,
            "speed_at_coast_start": speed_off,
            "supply_current_limited": bool(np.any(sim.mode[on] == 1)),
            "current_clipped": bool(np.max(np.abs(sim.current)) > self.instruments.ina219.current_range),
            "stop_time": time_at_rest(sim, t_open),
        }

    def _log_ftc(
        self, sim: Simulation, duration: float, rng: np.random.Generator
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Rows of the OpMode's log: time stamps, counts, INA219 bus voltage and current."""
        ins = self.instruments
        times = ins.logger.times(duration, rng)
        d_enc, d_bus, d_cur = ins.logger.read_delays
        counts = self.encoder.counts(sim.sample(times + d_enc)["position"])
        bus_in = ins.ina219.bus_input(sim.time, sim.voltage)  # through the LC filter, when fitted
        if ins.ina219.averaging > 1:  # the register holds the mean of the last completed conversion window
            true_v = ins.ina219.conversion_average(times + d_bus, sim.time, bus_in)
            true_i = ins.ina219.conversion_average(times + d_cur, sim.time, sim.current)
        else:
            true_v, true_i = np.interp(times + d_bus, sim.time, bus_in), sim.sample(times + d_cur)["current"]
        bus = ins.ina219.read_bus_voltage(true_v, rng)
        current = ins.ina219.read_current(true_i, rng)
        return times, counts, bus, current

    def spinup(
        self,
        path: PathArg,
        *,
        current: float = 2.0,
        voltage: float = 12.0,
        duration: float = 30.0,
        coast_time: float = 0.0,
        relay_delay: float = 0.2,
        header: bool = True,
        crlf: bool = False,
    ) -> RigRun:
        """Seed 1's "First Experiment": a constant current into the flywheel, τ = J·α, K = τ/I.

        Parameters
        ----------
        path
            The FTC log to write.
        current
            Supply current limit [A]: the supply runs in constant current while R·I + K·ω < V.
        voltage
            Supply voltage setting [V] (≤ 16 V with the INA219).
        duration
            Time the relay stays closed [s].
        coast_time
            Time logged after the relay opens [s] (0: none).
        relay_delay
            Time after the OpMode starts at which the relay closes [s].
        header, crlf
            Log layout.

        Returns
        -------
        RigRun
            ``truth["expected"]``: K, totals J, b, Tf, the initial acceleration (K·I − Tf)/J and
            whether the supply stayed in constant current.

        Raises
        ------
        RigError
            Supply voltage above 16 V with the INA219.
        OptionError
            Settings out of range (negative current …).
        """
        ins = self.instruments
        stepped_currents([current])
        ins.ina219.check_supply(voltage)
        ins.supply.check(voltage, current)
        check_positive(duration, "duration", "s")
        if coast_time < 0 or relay_delay < 0:
            raise OptionError("coast time and relay delay must not be negative")
        rng = self._rng("spinup")
        loaded = self._loaded(True)
        t_close = relay_delay + ins.relay.operate_time
        t_open = relay_delay + duration + ins.relay.release_time
        total = relay_delay + duration + coast_time
        schedule: list[tuple[float, Drive]] = [
            (0.0, OpenCircuit()), (t_close, BenchSupply(voltage, current)), (t_open, OpenCircuit())]
        train = self._drivetrain(True)
        sim = self._simulate(train, schedule, duration=total + 0.01, dt=FLYWHEEL_DT)
        times, counts, bus, amps = self._log_ftc(sim, total, rng)
        path = Path(path)
        write_ftc_log(path, times, counts, bus, amps, header=header, crlf=crlf)
        on = (sim.time >= t_close + 0.05) & (sim.time < t_open)
        # The motor drives the flywheel through the gearbox: a torque balance at the output finds the
        # output's Kt = η·K with the physical J, b, Tf there (K, J, b, Tf themselves when ideal).
        phys = train.output_figures()
        expected = {
            "K": phys["Kt"],
            "Ke": self.params.K,
            "J": phys["J"],
            "b": phys["b"],
            "Tf": phys["Tf"],
            "current": current,
            "acceleration_initial": max(self.params.K * current - loaded.Tf, 0.0) / loaded.J,
            "constant_current_throughout": bool(np.all(sim.mode[on] == 1)),
            "relay_closed": t_close,
            "relay_opened": t_open,
        }
        settings = {"current": current, "voltage": voltage, "duration": duration, "coast_time": coast_time,
                    "relay_delay": relay_delay, "dt": FLYWHEEL_DT}
        instruments = {"ina219": ins.ina219.settings(), "logger": ins.logger.settings(),
                       "supply": ins.supply.settings(), "relay": ins.relay.settings(),
                       "encoder": self.encoder.settings()}
        return self._finish("spinup", [path], settings=settings, expected=expected, instruments=instruments,
                            flywheel=True)

    # ---- seed 1: bare motor on the scope --------------------------------------------------------
    def free_spinup(
        self,
        path: PathArg,
        *,
        current: float = 0.5,
        voltage: float = 18.0,
        hand_speed: float | None = None,
        edges: int = 20,
        timebase: float | None = None,
        waveform: PathArg | None = None,
        dt: float = 1e-4,
    ) -> RigRun:
        """Seed 1's "Free Motor Spin-Up Experiment": cursor times of 20 rising edges of channel B.

        Parameters
        ----------
        path
            CSV to write, one ``time_ms`` column (times after the trigger edge).
        current
            Supply current limit [A] (seed 1: 0.5 A at 18 V; the INA219 is not in this circuit).
        voltage
            Supply voltage setting [V].
        hand_speed
            Speed the hand start gives the shaft [rad/s] (default 5 % of the catalogue free speed).
        edges
            Rising edges recorded after the trigger edge (seed 1: 20).
        timebase
            Scope horizontal scale [s/div]; default: the finest 1-2-5 setting that still shows the
            trigger and every recorded edge (the trigger near the left edge of the screen), as a person
            zooms in until the edges fill the screen (seed 1: 200 ms/div, 20 ms/div for the fast
            AM3.7).
        waveform
            Also write the scope's waveform export of channel B (Rigol CSV) to this path.
        dt
            Simulator step [s] (0.1 ms resolves edges of a ~30 ms mechanical time constant).

        Returns
        -------
        RigRun
            ``truth["expected"]``: J, K, Tf, b, the current, the true edge times and the
            acceleration at the trigger (K·I − Tf − b·ω)/J.

        Raises
        ------
        RigError
            If the motor stops before the edges are recorded (current too low for the friction).
        OptionError
            Settings out of range.

        Notes
        -----
        Channel B rises every 4 counts; the scope triggers on one rising edge and, as the seed says
        ("if the first transition goes up, start counting cycles at the second up transition"), the
        recorded edges are the next ``edges`` ones.
        """
        ins = self.instruments
        stepped_currents([current])
        ins.supply.check(voltage, current)
        if edges < 2:
            raise OptionError(f"need at least 2 edges, got {edges}")
        check_size(edges, "rising edges (--edges)", limit=MAX_READINGS, hint="the seed records 20")
        check_positive(dt, "dt", "s")
        rng = self._rng("free-spinup")
        p = self._loaded(False)
        w0 = self._hand_start_speed(hand_speed)
        step = 2 * math.pi / self.motor.cpr
        theta0 = float(rng.uniform(0.0, 4 * step))
        needed = theta0 + (edges + 2) * 4 * step
        sim = self._spin_free(BenchSupply(voltage, current), w0, theta0, needed, dt)
        true_times = self._rising_edge_times(sim, theta0, edges, current)
        t_trigger = true_times[0]
        relative = true_times[1:] - t_trigger
        scope = ins.scope
        if timebase is None:
            # The finest setting whose screen holds the last edge; the seed sets "the horizontal
            # position to the left", leaving a fifth of a division before the trigger.
            timebase = timebase_at_least(1.01 * float(relative[-1]) / (scope.divisions - PRE_TRIGGER_DIVISIONS))
        check_positive(timebase, "timebase", "s/div")
        scope = replace(scope, timebase=timebase)
        readings = strictly_increasing(scope.cursor_times(relative, rng), scope.cursor_step)
        path = Path(path)
        metadata = {"experiment": "free-spinup", "motor": self.motor.key, "cpr": self.motor.cpr,
                    "channel": "B", "counts_per_edge": 4, "current_A": current}
        write_csv(path, {"time_ms": quantize(readings * 1e3, 1e-6)}, metadata=metadata)
        paths = [path]
        if waveform is not None:
            wpath = Path(waveform)
            self._write_waveform(wpath, sim, t_trigger, scope, rng)
            paths.append(wpath)
        expected = _free_spinup_expected(sim, p, current, true_times, w0)
        settings = {"current": current, "voltage": voltage, "hand_speed": w0, "edges": edges,
                    "timebase": timebase, "dt": dt, "initial_position": theta0}
        instruments = {"scope": scope.settings(), "supply": ins.supply.settings(),
                       "encoder": self.encoder.settings()}
        return self._finish("free-spinup", paths, settings=settings, expected=expected, instruments=instruments,
                            flywheel=False)

    def _hand_start_speed(self, hand_speed: float | None) -> float:
        """The speed the hand start gives the shaft [rad/s] (default 5 % of the free speed), checked."""
        w0 = 0.05 * self.motor.free_speed if hand_speed is None else float(hand_speed)
        if not 0 <= w0 <= 2 * self.motor.free_speed:  # a hand does not spin it past its own free speed
            raise OptionError(f"the hand-start speed (--hand-speed) must lie between 0 and twice the free speed "
                              f"({2 * self.motor.free_speed:.3g} rad/s), got {w0:g} rad/s")
        return w0

    def _spin_free(self, supply: BenchSupply, w0: float, theta0: float, needed: float, dt: float) -> Simulation:
        """Simulate the bare motor from the hand start until it has turned to ``needed`` [rad] (or stopped).

        The run starts at twice the time the shaft would take at half the free speed and is doubled
        (at most 12 times) until the shaft reaches ``needed`` or comes to rest.
        """
        drive = [(0.0, supply)]
        guess = max(self.motor.free_speed * 0.5, 1e-3)
        duration = max(4 * needed / guess, 0.05)
        for _ in range(12):
            sim = self._simulate(self._drivetrain(False), drive, duration=duration, dt=dt, initial_speed=w0,
                                 initial_position=theta0)
            if sim.position[-1] >= needed or sim.speed[-1] <= 0:
                break
            duration *= 2
        return sim

    def _rising_edge_times(self, sim: Simulation, theta0: float, edges: int, current: float) -> np.ndarray:
        """True times [s] of the trigger edge and the ``edges`` rising edges of channel B after it.

        Raises
        ------
        RigError
            If the motor stopped before the last edge.
        """
        angles = self.encoder.channel_b_rising_angles(theta0, float(sim.position[-1]))
        if angles.size < edges + 1:
            raise RigError(
                f"the motor stopped after {angles.size} rising edges at {current:g} A; "
                "raise the current or the hand-start speed"
            )
        angles = angles[: edges + 1]
        return np.interp(angles, sim.position, sim.time)

    def _write_waveform(self, path: Path, sim: Simulation, t_trigger: float, scope: Any,
                        rng: np.random.Generator) -> None:
        """Rigol DS1000Z CSV export of channel B: a fifth of a division before the trigger, the rest after."""
        span = scope.timebase * scope.divisions
        increment = span / scope.points
        start = -PRE_TRIGGER_DIVISIONS * scope.timebase
        t = t_trigger + start + increment * np.arange(scope.points)
        t = t[t <= sim.time[-1]]
        volts = self.encoder.channel_b_level(sim.sample(t)["position"])
        volts = volts + rng.normal(0.0, scope.vertical_noise, volts.shape)
        lines = ["X,CH1,Start,Increment,", f"Sequence,Volt,{start:.6e},{increment:.6e},"]
        lines += [f"{k},{v:.4e}," for k, v in enumerate(volts)]
        write_text_atomic(path, "\n".join(lines) + "\n")

    def terminal(
        self,
        path: PathArg,
        *,
        currents: Sequence[float] | None = None,
        voltage: float = 18.0,
    ) -> RigRun:
        """Seed 1's "Terminal Velocity Experiment": steady current and channel frequency, no flywheel.

        Parameters
        ----------
        path
            CSV to write: ``current_A,frequency_Hz`` (supply display, scope frequency counter).
        currents
            Supply current settings [A] (default: five settings between the break-away current and
            the one where the supply would reach ``voltage``, from the catalogue figures, as the seed
            picks 0.25-0.4 A for the NeveRest 20; a default setting that does not turn this unit is
            raised in 0.01 A steps until it does, as the seed says: "If this current doesn't work,
            change it to a higher value and record this new value").
        voltage
            Supply voltage setting [V] (seed 1: 18 V).

        Returns
        -------
        RigRun
            ``truth["expected"]``: b, Tf, K, the true steady speeds, currents and the supply mode.

        Notes
        -----
        At steady state K·I = b·ω + Tf and f = ω·cpr/(4·2π) (seed 1: "Multiply the recorded frequency
        ... by 4 ... dividing this number by counts per revolution ... multiply by 2π").
        """
        ins = self.instruments
        amps = stepped_currents(currents)
        if amps is None:
            amps = self._default_terminal_currents(voltage)
            # The experimenter raises a setting that leaves the shaft at rest (K·I ≤ Tf).
            need = self._loaded(False).Tf / self.params.K
            amps = np.array([a if a > need * 1.02 else math.ceil(need * 1.02 / 0.01 + 1) * 0.01 for a in amps])
            amps = np.unique(np.round(amps, 3))
        ins.supply.check(voltage, float(np.max(amps)) if amps.size else 1.0)
        if np.any(amps == 0):
            raise OptionError("a current setting of 0 A cannot spin the motor")
        rng = self._rng("terminal")
        p = self._loaded(False)
        states = [steady_state(p, float(i), voltage_limit=voltage) for i in amps]
        speeds = np.array([s[0] for s in states])
        true_i = np.array([s[1] for s in states])
        freq = ins.scope.measure_frequency(np.array([self.encoder.channel_frequency(w) for w in speeds]), rng)
        shown = ins.supply.display_current(true_i, rng)
        path = Path(path)
        write_csv(path, {"current_A": shown, "frequency_Hz": freq},
                  metadata={"experiment": "terminal", "motor": self.motor.key, "cpr": self.motor.cpr,
                            "voltage_V": voltage})
        expected = {"K": p.K, "b": p.b, "Tf": p.Tf, "speeds": speeds, "currents": true_i,
                    "frequencies": speeds * self.motor.cpr / (8 * math.pi), "modes": [s[2] for s in states]}
        settings = {"currents": amps, "voltage": voltage}
        instruments = {"scope": ins.scope.settings(), "supply": ins.supply.settings(),
                       "encoder": self.encoder.settings()}
        return self._finish("terminal", [path], settings=settings, expected=expected, instruments=instruments,
                            flywheel=False)

    def _default_terminal_currents(self, voltage: float) -> np.ndarray:
        nominal = self.motor.nominal_params()
        i_min = nominal.Tf / nominal.K
        if nominal.b > 0:
            # R·i + K·(K·i − Tf)/b = V  ->  i where the supply would leave constant current.
            i_cv = (voltage + nominal.K * nominal.Tf / nominal.b) / (nominal.R + nominal.K**2 / nominal.b)
        else:
            i_cv = 2 * i_min
        grid = i_min + np.linspace(0.3, 0.9, 5) * (i_cv - i_min)
        return np.unique(np.round(grid, 3))

    def lcr(self, path: PathArg, *, positions: int = 10) -> RigRun:
        """Seed 1's "LCR Meter Experiment": L, Q and DCR at ``positions`` random shaft positions, 1 kHz.

        Parameters
        ----------
        path
            CSV to write: ``L_uH,Q,DCR_ohm`` with ``# frequency_Hz: 1000``.
        positions
            Number of shaft positions (seed 1: 10).

        Returns
        -------
        RigRun
            ``truth["expected"]``: L; R, the mean AC resistance 2πfL/Q measures at good contacts; R_dc, the model's
            R (the running motor's terminal resistance: winding plus a good brush contact on
            average); the mean true L and DCR over the positions and the contact resistance at each.

        Notes
        -----
        Q = 2π·f·L/R_ac; the DCR includes the brush contact resistance, sometimes much higher than
        usual (seed 1's table: DCR 1.38-3.65 Ω for a 1.9 Ω winding).
        """
        if positions < 1:
            raise OptionError(f"need at least one position, got {positions}")
        check_size(positions, "shaft positions (--positions)", limit=MAX_READINGS, hint="the seed takes ten")
        rng = self._rng("lcr")
        p = self.params
        true = self.commutator.positions(p, positions, rng)
        meter = self.instruments.lcr
        readings = meter.read(true["inductance"], true["ac_resistance"], true["dc_resistance"], rng)
        path = Path(path)
        write_csv(path, {"L_uH": quantize(readings["inductance"] * 1e6, 0.1),
                         "Q": readings["quality_factor"], "DCR_ohm": readings["dc_resistance"]},
                  metadata={"experiment": "lcr", "motor": self.motor.key, "frequency_Hz": meter.frequency})
        # What each of the analysis's outputs should find: R = 2πfL/Q is the meter's AC resistance
        # (winding plus eddy-current and brush losses at f); R_dc, with poor contacts set aside, is the
        # model's R (winding plus a good brush contact).
        expected = {
            "L": p.L, "R": self.commutator.expected_ac_resistance(p), "R_dc": p.R,
            "L_mean_positions": float(np.mean(true["inductance"])),
            "DCR_mean_positions": float(np.mean(true["dc_resistance"])),
            "R_ac_mean_positions": float(np.mean(true["ac_resistance"])),
            "contact_resistance": true["contact_resistance"],
        }
        return self._finish("lcr", [path], settings={"positions": positions}, expected=expected,
                            instruments={"lcr": meter.settings(), "commutator": self.commutator.settings()},
                            flywheel=False)

    # ---- seed 2 ---------------------------------------------------------------------------------
    def torque(
        self,
        path: PathArg,
        *,
        currents: Sequence[float] | None = None,
        arm: float = 0.15,
        dither: bool = True,
    ) -> RigRun:
        """Seed 2's "The Motor Torque Constant": a lever arm on the shaft pressing on a scale.

        Parameters
        ----------
        path
            CSV to write: ``current_A,mass_kg`` with ``# arm_m: ...``, one row per reading in the
            order taken.
        currents
            Winding currents [A] (≥ 0), in the order they are set. Default: seed 2's sweep of
            equal steps up to the least of 4 A, half the stall current and 80 % of the scale's
            capacity (six steps instead of the seed's four), then back down the same steps, so that
            friction is seen from both sides (eleven readings).
        arm
            Lever arm length [m].
        dither
            Seed 2's 0.25 V, 30 Hz dither that frees stiction: without it the friction held by the
            stalled gearbox biases each reading by up to Tf.

        Returns
        -------
        RigRun
            ``truth["expected"]``: K (slope τ/I), the true torques, the friction held at each
            reading and the direction (+1 up, −1 down) from which each current was approached.

        Notes
        -----
        τ = K·I (seed 2, T(t) = Km·I(t)); the scale shows m = τ_arm/(g₀·arm). Through a lossy
        gearbox the arm at the output feels τ = η·K·I − τ0 (:mod:`motorlab.gearbox`). The stalled shaft
        creeps towards the new balance after each change of current, so the friction it holds
        opposes that creep: τ_arm = K·I − d·f with d = ±1 the sign of the change (from rest for the
        first reading) and f uniform in [0, r·Tf], r = 0.1 with the dither and 1 without. A sweep
        up and back down therefore reads a hysteresis loop of half-width ≈ r·Tf/2 about K·I.
        """
        ins = self.instruments
        check_positive(arm, "lever arm", "m")
        amps = stepped_currents(currents)
        p = self.params
        if amps is None:
            nominal = self.motor.nominal_params()
            i_max = min(4.0, 0.5 * self.motor.stall_current,
                        0.8 * ins.scale.capacity * 9.80665 * arm / nominal.K)
            up = np.round(np.linspace(i_max / 6, i_max, 6), 2)
            amps = np.concatenate([up, up[-2::-1]])
        if float(np.max(amps)) > ins.supply.max_current:
            raise OptionError(f"currents above the supply's {ins.supply.max_current:g} A")
        rng = self._rng("torque")
        approach = approach_direction(amps)
        # Through the gearbox (forward, the motor pushing the arm): τ_out = η·K·I − τ0, the motor's own
        # Coulomb friction held either way by the stalled shaft (× η at the output).
        eta, tau0 = self.gearbox.efficiency, self.gearbox.loss_torque
        held = eta * p.Tf * (0.1 if dither else 1.0) * rng.uniform(0.0, 1.0, amps.shape)
        torque = np.where(amps > 0, eta * p.K * amps - tau0 - approach * held, 0.0)
        mass = ins.scale.read(np.clip(torque, 0.0, None), arm, rng)
        shown = ins.multimeter.read_current(amps, rng)
        path = Path(path)
        write_csv(path, {"current_A": shown, "mass_kg": mass},
                  metadata={"experiment": "torque", "motor": self.motor.key, "arm_m": arm})
        expected = {"K": eta * p.K, "Ke": p.K, "efficiency": eta, "loss_torque": tau0,
                    "ratio": self.gearbox.ratio, "K_motor": p.K / self.gearbox.ratio,
                    "torques": torque, "currents": amps, "friction_held": -approach * held,
                    "approach": approach}
        instruments = {"scale": ins.scale.settings(), "multimeter": ins.multimeter.settings()}
        return self._finish("torque", [path], settings={"currents": amps, "arm": arm, "dither": dither},
                            expected=expected, instruments=instruments, flywheel=False)


def _write_spindown_logs(
    path: Path,
    log: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    t_command_off: float,
    *,
    split: bool,
    header: bool,
    crlf: bool,
    placeholder_rows: int | None,
    blank_lines: int | None,
) -> list[Path]:
    """Write a spin-down's FTC log rows (times, counts, bus, current), split in two as the OpMode does if asked.

    With ``split`` the powered part (before the relay is commanded open) goes to ``path`` followed by
    placeholder zero rows and the coast to ``<stem>2<suffix>``, both after blank lines. Returns the
    paths written.
    """
    times, counts, bus, current = log
    paths = [path]
    if split:
        first = times < t_command_off
        second_path = path.with_name(f"{path.stem}2{path.suffix}")
        paths.append(second_path)
        blanks = 2 if blank_lines is None else blank_lines
        placeholders = 10 if placeholder_rows is None else placeholder_rows
        write_ftc_log(path, times[first], counts[first], bus[first], current[first], header=header,
                      placeholder_rows=placeholders, crlf=crlf, blank_lines=blanks)
        write_ftc_log(second_path, times[~first], counts[~first], bus[~first], current[~first], header=header,
                      crlf=crlf, blank_lines=blanks)
    else:
        write_ftc_log(path, times, counts, bus, current, header=header,
                      placeholder_rows=placeholder_rows or 0, crlf=crlf, blank_lines=blank_lines or 0)
    return paths


def _free_spinup_expected(
    sim: Simulation, p: MotorParams, current: float, true_times: np.ndarray, w0: float
) -> dict[str, Any]:
    """The truth of a free spin-up: parameters, edge times after the trigger, speed and acceleration there."""
    t_trigger = true_times[0]
    state = sim.sample(np.array([t_trigger]))
    w_trig = float(state["speed"][0])
    return {
        "J": p.J, "K": p.K, "Tf": p.Tf, "b": p.b, "current": current,
        "edge_times": true_times[1:] - t_trigger,
        "speed_at_trigger": w_trig,
        "acceleration_at_trigger": (p.K * current - p.Tf - p.b * w_trig) / p.J,
        "hand_speed": w0,
        # After the winding current has risen (5·L/R), the supply must hold constant current.
        "constant_current_throughout": bool(np.all(
            sim.mode[(sim.time >= 5 * p.L / p.R) & (sim.time <= true_times[-1])] == 1)),
    }
