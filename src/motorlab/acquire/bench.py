"""The real bench: seed 1's supply-and-scope experiments on hardware, behind the virtual rig's interface.

:class:`BenchRig` is the hardware counterpart of :class:`motorlab.rig.VirtualRig`: the same
experiment names, the same settings (``voltage``, ``current_limit``, ``currents``, ``edges`` …), the
same :class:`~motorlab.rig.base.RigRun` back and the same files written, so that whatever drives
one (``rig.run("terminal", path, currents=[...])``) drives the other. The programmable supply is
the relay and the current limit; the scope measures the encoder's channel B.

- ``terminal`` (seed 1 "Terminal Velocity"): for each current setting, constant current at
  ``voltage``, wait for the steady state, read the supply's current and the scope's frequency ->
  ``current_A,frequency_Hz``.
- ``free-spinup`` (seed 1 "Free Motor Spin-Up"): arm a single rising-edge sweep, switch the supply on
  at ``current``, read the screen waveform, keep the ``edges`` rising edges after the trigger edge ->
  ``time_ms`` CSV (and optionally the Rigol waveform CSV).
- ``spindown`` / ``spinup`` (seed 1 "Flywheel and INA219", "First Experiment"): the supply is the
  relay, on for ``on_time`` then off while the robot's OpMode logs encoder and INA219 (those logs
  come from the robot); the bench writes the supply's own readback, ``time_s,voltage_V,current_A``.

Safety, in :func:`powered`: the output is switched off first, the current limit is set and read
back before the voltage and before the output goes on, the voltage is refused above 16 V while an
INA219 is in circuit (and above the supply's range), and the output is switched off again on
leaving — normally, on any error and on Ctrl-C (``try/finally``).
"""

from __future__ import annotations

import contextlib
import math
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

import numpy as np

from motorlab.acquire.errors import InstrumentError
from motorlab.acquire.scpi import RigolDS1000Z, Supply
from motorlab.errors import OptionError, RigError
from motorlab.io.csv_table import write_csv
from motorlab.io.output import check_writable_target
from motorlab.io.scope import find_rising_edges
from motorlab.rig.base import MAX_READINGS, PathArg, RigRun, check_size
from motorlab.rig.instruments import INA219

#: Experiments the bench runs (names as :data:`motorlab.rig.virtual.EXPERIMENTS`).
BENCH_EXPERIMENTS: dict[str, str] = {
    "terminal": "terminal", "free-spinup": "free_spinup", "spindown": "spindown", "spinup": "spinup",
}
#: Read-back tolerance of the supply's settings: the larger of 1 % and this [V] / [A].
READBACK_VOLTS = 0.02
READBACK_AMPS = 0.005


@dataclass
class Clock:
    """Time source and sleep of the bench (replaced by a fake clock in tests)."""

    now: Callable[[], float] = time.monotonic
    sleep: Callable[[float], None] = time.sleep


def _close(setting: float, readback: float, floor: float) -> bool:
    return abs(setting - readback) <= max(floor, 0.01 * abs(setting))


def check_supply_settings(supply: Supply, *, voltage: float, current_limit: float, ina219: bool) -> None:
    """Refuse settings the supply cannot make or the INA219 cannot take (before anything is switched or written).

    Raises
    ------
    RigError
        Voltage above 16 V with the INA219 in circuit.
    OptionError
        Voltage or current limit outside the supply's range.
    """
    if ina219:
        INA219().check_supply(voltage)
    if not 0 < voltage <= supply.max_voltage:
        raise OptionError(f"supply voltage must be in (0, {supply.max_voltage:g}] V, got {voltage:g} V")
    if not 0 < current_limit <= supply.max_current:
        raise OptionError(f"supply current limit must be in (0, {supply.max_current:g}] A, got {current_limit:g} A")


@contextlib.contextmanager
def powered(supply: Supply, *, voltage: float, current_limit: float, ina219: bool) -> Iterator[Supply]:
    """Switch ``supply`` on at ``voltage`` with ``current_limit`` and off again, whatever happens.

    Parameters
    ----------
    supply
        The supply driver.
    voltage
        Voltage setting [V].
    current_limit
        Current limit [A], set (and read back) before the output goes on.
    ina219
        An INA219 is in circuit: refuse more than its 16 V.

    Raises
    ------
    RigError
        Voltage above 16 V with the INA219 in circuit.
    OptionError
        Settings outside the supply's range.
    InstrumentError
        The read-back settings differ from the ones sent (the output stays off), or the output could
        not be switched off (the message asks to switch it off by hand).
    """
    check_supply_settings(supply, voltage=voltage, current_limit=current_limit, ina219=ina219)
    supply.output(False)
    try:
        supply.set_current_limit(current_limit)  # the limit first: the voltage never meets an unlimited supply
        supply.set_voltage(voltage)
        volts, amps = supply.settings()
        if not (_close(current_limit, amps, READBACK_AMPS) and _close(voltage, volts, READBACK_VOLTS)):
            raise InstrumentError(
                f"the supply reads back {volts:g} V / {amps:g} A instead of {voltage:g} V / {current_limit:g} A; "
                "output left off")
        if ina219 and volts > INA219().max_supply_voltage:
            raise RigError(f"the supply reads back {volts:g} V with the INA219 in circuit; output left off")
        supply.output(True)
        yield supply
    finally:
        try:
            supply.output(False)
        except Exception as exc:
            raise InstrumentError(f"could not switch the supply off ({exc}): SWITCH ITS OUTPUT OFF BY HAND") from exc


@dataclass
class _RowLog:
    """A CSV written row by row, flushed after each row (a Ctrl-C keeps every row taken)."""

    path: Path
    columns: Sequence[str]
    metadata: dict[str, Any]
    handle: IO[str] | None = field(default=None, init=False)

    def __enter__(self) -> _RowLog:
        check_writable_target(self.path)  # a FIFO would hang the run, a device would swallow it
        self.handle = open(self.path, "w", encoding="utf-8", newline="")
        lines = [f"# {k}: {v}" for k, v in self.metadata.items()] + [",".join(self.columns)]
        self.handle.write("\n".join(lines) + "\n")
        self.handle.flush()
        return self

    def row(self, *values: float) -> None:
        assert self.handle is not None
        self.handle.write(",".join(f"{v:.10g}" for v in values) + "\n")
        self.handle.flush()

    def __exit__(self, *exc: object) -> None:
        if self.handle is not None:
            self.handle.close()


class BenchRig:
    """A real dynamometer bench: a programmable supply and, for the scope experiments, a DS1000Z.

    Parameters
    ----------
    supply
        The supply driver (:class:`~motorlab.acquire.scpi.KoradSupply`, :class:`~motorlab.acquire.scpi.RigolDP800`).
    scope
        The scope driver (needed by ``terminal`` and ``free-spinup``).
    cpr
        Encoder counts per revolution at the motor shaft, written as ``# cpr:`` for the analyses.
    motor
        Catalogue key, written as ``# motor:``.
    clock
        Time source and sleep.
    progress
        Called with ``(description, done, total)`` as the run advances (a rich progress bar in the CLI).
    report
        Called with one line of text per step.
    """

    experiments: tuple[str, ...] = tuple(BENCH_EXPERIMENTS)

    def __init__(self, supply: Supply, scope: RigolDS1000Z | None = None, *, cpr: float | None = None,
                 motor: str | None = None, clock: Clock | None = None,
                 progress: Callable[[str, float, float], None] | None = None,
                 report: Callable[[str], None] | None = None):
        self.supply = supply
        self.scope = scope
        self.cpr = cpr
        self.motor = motor
        self.clock = clock or Clock()
        self._progress = progress or (lambda what, done, total: None)
        self._report = report or (lambda text: None)

    def run(self, experiment: str, path: PathArg, **settings: Any) -> RigRun:
        """Run ``experiment`` (a key of :data:`BENCH_EXPERIMENTS`) writing ``path``."""
        if experiment not in BENCH_EXPERIMENTS:
            raise OptionError(f"the bench does not run {experiment!r}; it runs: {', '.join(BENCH_EXPERIMENTS)}")
        method: Callable[..., RigRun] = getattr(self, BENCH_EXPERIMENTS[experiment])
        return method(path, **settings)

    # ---- helpers ---------------------------------------------------------------------------------
    def _meta(self, experiment: str, **extra: Any) -> dict[str, Any]:
        meta: dict[str, Any] = {"experiment": experiment}
        if self.motor:
            meta["motor"] = self.motor
        if self.cpr:
            meta["cpr"] = f"{self.cpr:g}"
        meta["supply"] = f"{type(self.supply).__name__} ({self.supply.identify().replace(':', ' ')})"
        if self.scope is not None and experiment in ("terminal", "free-spinup"):
            meta["scope"] = self.scope.identify().replace(":", " ")
        meta.update(extra)
        return meta

    def _need_scope(self, experiment: str) -> RigolDS1000Z:
        if self.scope is None:
            raise OptionError(f"{experiment} needs the scope (--scope RESOURCE)")
        return self.scope

    def _wait(self, seconds: float, what: str) -> None:
        """Sleep ``seconds`` in short steps, reporting progress (Ctrl-C is seen within 0.1 s)."""
        start = self.clock.now()
        while (elapsed := self.clock.now() - start) < seconds:
            self._progress(what, elapsed, seconds)
            self.clock.sleep(max(min(0.1, seconds - elapsed), 1e-3))  # never a sleep too short to pass time
        self._progress(what, seconds, seconds)

    # ---- seed 1: terminal velocity -----------------------------------------------------------------
    def terminal(self, path: PathArg, *, currents: Sequence[float] | None = None, voltage: float = 18.0,
                 settle: float = 3.0, samples: int = 5, ina219: bool = False) -> RigRun:
        """Steady current and encoder frequency at each current setting (seed 1 "Terminal Velocity").

        Parameters
        ----------
        path
            CSV to write: ``current_A,frequency_Hz`` (supply's measured current, scope frequency,
            each the mean of ``samples`` readings).
        currents
            Current settings [A] (required: the bench cannot guess the unit's break-away current).
        voltage
            Voltage setting [V] (seed 1: 18 V; no INA219 in this circuit).
        settle
            Wait after each change before reading [s] (several mechanical time constants).
        samples
            Readings averaged per setting.
        ina219
            An INA219 is in circuit (caps the voltage at 16 V).
        """
        scope = self._need_scope("terminal")
        amps = _settings_list(currents, "current")
        if samples < 1:
            raise OptionError(f"samples must be at least 1, got {samples}")
        path = Path(path)
        meta = self._meta("terminal", voltage_V=f"{voltage:g}", settle_s=f"{settle:g}", samples=samples)
        for amp in amps:
            check_supply_settings(self.supply, voltage=voltage, current_limit=float(amp), ina219=ina219)
        # One power-up for the whole run (a restart would meet stiction again); the limit changes while on.
        with _RowLog(path, ["current_A", "frequency_Hz"], meta) as log, \
                powered(self.supply, voltage=voltage, current_limit=float(amps[0]), ina219=ina219):
            for k, amp in enumerate(amps):
                if k:
                    self.supply.set_current_limit(float(amp))
                    set_amps = self.supply.settings()[1]
                    if not _close(float(amp), set_amps, READBACK_AMPS):
                        raise InstrumentError(f"the supply reads back a {set_amps:g} A limit instead of {amp:g} A")
                self._wait(settle, f"{amp:g} A: settling")
                current, freq = self._steady(scope, samples)
                log.row(current, freq)
                self._report(f"setting {k + 1}/{amps.size}: {current:.4g} A, {freq:.5g} Hz")
        return RigRun("terminal", (path,))

    def _steady(self, scope: RigolDS1000Z, samples: int) -> tuple[float, float]:
        currents, freqs = [], []
        for _ in range(samples):
            currents.append(self.supply.measure()[1])
            freqs.append(scope.frequency())
            self.clock.sleep(0.2)
        f = np.asarray(freqs)
        if np.any(~np.isfinite(f)):
            raise InstrumentError("the scope measures no frequency on the encoder channel: is the motor turning, "
                                  "the probe on channel B and the trigger level right?")
        return float(np.mean(currents)), float(np.mean(f))

    # ---- seed 1: free spin-up on the scope ---------------------------------------------------------
    def free_spinup(self, path: PathArg, *, current: float = 0.5, voltage: float = 18.0, edges: int = 20,
                    timebase: float = 0.2, level: float = 1.5, wait: float = 30.0,
                    waveform: PathArg | None = None, ina219: bool = False) -> RigRun:
        """Times of ``edges`` rising edges of channel B after the trigger edge (seed 1 "Free Motor Spin-Up").

        Parameters
        ----------
        path
            CSV to write: one ``time_ms`` column, times after the trigger edge.
        current, voltage
            Supply current limit [A] and voltage [V] (seed 1: 0.5 A at 18 V).
        edges
            Rising edges recorded after the trigger edge (seed 1: 20).
        timebase
            Scope horizontal scale [s/div] (seed 1: 200 ms/div).
        level
            Trigger level [V] (half the encoder's 3.3 V).
        wait
            Longest wait for the trigger after the output goes on [s] (give the shaft its hand start).
        waveform
            Also write the screen waveform as the scope's CSV export (``X,CH1,Start,Increment,``).
        ina219
            An INA219 is in circuit (caps the voltage at 16 V).
        """
        scope = self._need_scope("free-spinup")
        if edges < 2:
            raise OptionError(f"need at least 2 edges, got {edges}")
        check_size(edges, "rising edges (--edges)", limit=MAX_READINGS, hint="the seed records 20")
        check_supply_settings(self.supply, voltage=voltage, current_limit=current, ina219=ina219)
        scope.arm_single(level=level, timebase=timebase)
        with powered(self.supply, voltage=voltage, current_limit=current, ina219=ina219):
            self._report("output on: give the shaft its hand start")
            start = self.clock.now()
            while scope.trigger_status() not in ("TD", "STOP"):
                if self.clock.now() - start > wait:
                    raise InstrumentError(f"the scope did not trigger within {wait:g} s (trigger level {level:g} V)")
                self._progress("waiting for the trigger", self.clock.now() - start, wait)
                self.clock.sleep(0.1)
            self._wait(timebase * 12, "sweep")  # a single sweep fills 12 divisions
            t, volts = scope.waveform()
        found, _ = find_rising_edges(t, volts, threshold=level)
        after = found[found > -0.5 * (t[1] - t[0])]  # the trigger edge sits at t = 0
        if after.size < edges + 1:
            raise InstrumentError(f"the screen holds {after.size} rising edges from the trigger on, need {edges + 1}: "
                                  "use a slower timebase (--timebase)")
        relative = after[1 : edges + 1] - after[0]
        path = Path(path)
        meta = self._meta("free-spinup", channel="B", counts_per_edge=4, current_A=f"{current:g}")
        write_csv(path, {"time_ms": np.round(relative * 1e3, 6)}, metadata=meta)
        paths = [path]
        if waveform is not None:
            wpath = Path(waveform)
            lines = ["X,CH1,Start,Increment,", f"Sequence,Volt,{t[0]:.6e},{t[1] - t[0]:.6e},"]
            lines += [f"{k},{v:.4e}," for k, v in enumerate(volts)]
            wpath.write_text("\n".join(lines) + "\n", encoding="utf-8")
            paths.append(wpath)
        return RigRun("free-spinup", tuple(paths))

    # ---- seed 1: the supply as the relay of the flywheel experiments -------------------------------
    def spindown(self, path: PathArg, *, voltage: float = 12.0, current_limit: float = 4.0, on_time: float = 30.0,
                 coast_time: float = 60.0, relay_delay: float = 0.2, poll: float = 0.1, ina219: bool = True) -> RigRun:
        """Power the flywheel for ``on_time`` then let it coast, logging the supply (seed 1 "Flywheel and INA219").

        The encoder and INA219 log is the robot's (``motorlab analyze spindown`` reads it); this file
        is the supply's readback, ``time_s,voltage_V,current_A``, which shows when the "relay"
        closed and opened and whether the supply went into current limit.
        """
        return self._relay_run("spindown", path, voltage=voltage, current_limit=current_limit, on_time=on_time,
                               coast_time=coast_time, relay_delay=relay_delay, poll=poll, ina219=ina219)

    def spinup(self, path: PathArg, *, current: float = 2.0, voltage: float = 12.0, duration: float = 30.0,
               coast_time: float = 0.0, relay_delay: float = 0.2, poll: float = 0.1, ina219: bool = True) -> RigRun:
        """Constant current into the flywheel for ``duration`` (seed 1 "First Experiment"), logging the supply."""
        return self._relay_run("spinup", path, voltage=voltage, current_limit=current, on_time=duration,
                               coast_time=coast_time, relay_delay=relay_delay, poll=poll, ina219=ina219)

    def _relay_run(self, experiment: str, path: PathArg, *, voltage: float, current_limit: float, on_time: float,
                   coast_time: float, relay_delay: float, poll: float, ina219: bool) -> RigRun:
        for value, name in ((on_time, "on time"), (poll, "poll interval")):
            if not (math.isfinite(value) and value > 0):
                raise OptionError(f"{name} must be positive, got {value:g} s")
        if not (coast_time >= 0 and relay_delay >= 0):
            raise OptionError("coast time and relay delay must not be negative")
        check_size((relay_delay + on_time + coast_time) / poll, "supply readings (time / --poll)")
        check_supply_settings(self.supply, voltage=voltage, current_limit=current_limit, ina219=ina219)
        path = Path(path)
        meta = self._meta(f"{experiment}-supply", voltage_V=f"{voltage:g}", current_limit_A=f"{current_limit:g}",
                          on_time_s=f"{on_time:g}", coast_time_s=f"{coast_time:g}")
        start = self.clock.now()
        with _RowLog(path, ["time_s", "voltage_V", "current_A"], meta) as log:
            self._poll(log, start, relay_delay, poll, "before the relay closes")
            with powered(self.supply, voltage=voltage, current_limit=current_limit, ina219=ina219):
                self._poll(log, start, relay_delay + on_time, poll, "relay closed")
            self._poll(log, start, relay_delay + on_time + coast_time, poll, "coasting")
        return RigRun(experiment, (path,))

    def _poll(self, log: _RowLog, start: float, until: float, poll: float, what: str) -> None:
        while (elapsed := self.clock.now() - start) < until:
            volts, amps = self.supply.measure()
            log.row(elapsed, volts, amps)
            self._progress(what, elapsed, until)
            self.clock.sleep(max(min(poll, until - elapsed), 1e-3))


def _settings_list(values: Sequence[float] | None, name: str) -> np.ndarray:
    if values is None:
        raise OptionError(f"give the {name} settings (--{name}s), e.g. 0.25,0.3,0.35")
    arr = np.asarray(list(values), dtype=float)
    if arr.size == 0 or not np.all(np.isfinite(arr)) or np.any(arr <= 0):
        raise OptionError(f"{name} settings must be positive numbers, got {list(values)}")
    check_size(arr.size, f"{name} settings", limit=MAX_READINGS)
    return arr
