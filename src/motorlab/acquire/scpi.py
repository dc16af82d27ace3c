"""Bench instruments through PyVISA: programmable supplies (Korad KA3005P, Rigol DP800) and a scope (Rigol DS1000Z).

Each driver wraps an open PyVISA resource and sends the instrument's own commands (short forms):

- Korad KAxxxxP (KA3005P, Tenma 72-2540 …): ``VSET1:12.00``, ``ISET1:1.000``, ``OUT1``/``OUT0``,
  ``VSET1?``/``ISET1?`` (5-character replies), ``VOUT1?``/``IOUT1?``, ``*IDN?``. The wire protocol
  has no terminator at all (sigrok wiki "Korad KAxxxxP series"; libsigrok ``korad-kaxxxxp`` reads
  fixed-length replies and waits ~50 ms between commands), so the driver writes raw bytes and reads
  five characters.
- Rigol DP800 (DP811/821/831/832): ``:INST:NSEL n``, ``:SOUR:VOLT v``, ``:SOUR:CURR i``,
  ``:OUTP ON|OFF``, ``:OUTP?``, ``:MEAS:VOLT?``, ``:MEAS:CURR?`` (libsigrok ``scpi-pps``,
  ``rigol_dp800_cmd``).
- Rigol DS1000Z (DS1054Z …): ``:MEAS:ITEM? FREQ,CHANn`` (9.9E37 when there is nothing to measure),
  edge trigger ``:TRIG:MODE EDGE``, ``:TRIG:EDG:SOUR``/``SLOP``/``LEV``, ``:TIM:MAIN:SCAL``,
  ``:SING``, ``:TRIG:STAT?`` (TD, WAIT, RUN, AUTO, STOP) and the screen waveform with
  ``:WAV:SOUR``/``MODE NORM``/``FORM ASC``/``XINC?``/``XOR?``/``DATA?`` (a ``#9nnnnnnnnn`` block of
  comma-separated volts) (MSO1000Z/DS1000Z Programming Guide).

:func:`open_instrument` opens a resource with PyVISA's pure-Python backend (``@py``) or, for
rehearsals and tests, with pyvisa-sim on the profiles shipped in ``motorlab/acquire/profiles``.
"""

from __future__ import annotations

import math
import time
from abc import ABC, abstractmethod
from importlib import resources
from typing import Any

import numpy as np

from motorlab.acquire.errors import InstrumentError

#: The pyvisa-sim profile shipped with motorlab (a Korad, a DP832 and a DS1054Z).
SIM_PROFILE = "bench.yaml"
#: Resource names of the simulated instruments in :data:`SIM_PROFILE`.
SIM_RESOURCES = {
    "korad": "ASRL1::INSTR",
    "dp800": "TCPIP0::192.168.1.20::INSTR",
    "ds1000z": "USB0::0x1AB1::0x04CE::DS1ZA000000000::INSTR",
}
#: Reply of a DS1000Z measurement with nothing to measure.
SCOPE_INVALID = 9.9e37


def sim_library() -> str:
    """The pyvisa ``visa_library`` string of the shipped simulation profile (``path@sim``)."""
    path = resources.files("motorlab.acquire").joinpath("profiles", SIM_PROFILE)
    return f"{path}@sim"


def open_instrument(resource: str, *, library: str = "@py", timeout: float = 2.0, terminated: bool = True) -> Any:
    """Open ``resource`` with PyVISA.

    Parameters
    ----------
    resource
        VISA resource name (``ASRL/dev/ttyACM0::INSTR``, ``TCPIP0::192.168.1.20::INSTR``,
        ``USB0::0x1AB1::0x04CE::DS1ZA...::INSTR``).
    library
        PyVISA backend: ``"@py"`` (pyvisa-py, pure Python), ``"@sim"`` for the shipped pyvisa-sim
        profile, or any ``visa_library`` string.
    timeout
        I/O timeout [s]: every query is bounded by it.
    terminated
        Commands and replies end with a newline (SCPI); False for the Korad protocol.

    Raises
    ------
    InstrumentError
        When the backend is missing or the resource cannot be opened.
    """
    import pyvisa

    if library == "@sim":
        library = sim_library()
    try:
        manager = pyvisa.ResourceManager(library)
        inst: Any = manager.open_resource(resource, timeout=int(timeout * 1000))
    except (pyvisa.Error, OSError, ValueError) as exc:
        hint = " (pip install 'motorlab[sim]' for @sim)" if library.endswith("@sim") else ""
        raise InstrumentError(f"{resource}: cannot open ({' '.join(str(exc).split())}){hint}") from None
    # pyvisa-sim cannot split unterminated commands: the simulated Korad takes a newline.
    inst.write_termination = "\n" if terminated or library.endswith("@sim") else ""
    inst.read_termination = "\n" if terminated else None
    return inst


def _visa_call(resource: Any, what: str, func: Any, *args: Any) -> Any:
    import pyvisa

    try:
        return func(*args)
    except (pyvisa.Error, OSError) as exc:
        name = getattr(resource, "resource_name", "instrument")
        raise InstrumentError(f"{name}: {what} failed ({' '.join(str(exc).split())})") from None


def _number(text: str, resource: Any, command: str) -> float:
    try:
        value = float(text.strip())
    except ValueError:
        name = getattr(resource, "resource_name", "instrument")
        raise InstrumentError(f"{name}: {command} answered {text.strip()!r}, not a number") from None
    return value


class Supply(ABC):
    """A programmable bench supply used as relay and current limit (one channel).

    Subclasses send their instrument's commands; :func:`motorlab.acquire.bench.powered` puts the
    safety sequence around them.
    """

    #: Highest voltage [V] and current [A] the model can be set to.
    max_voltage: float = 30.0
    max_current: float = 5.0

    def __init__(self, resource: Any):
        self.resource = resource

    @abstractmethod
    def identify(self) -> str:
        """The ``*IDN?`` reply."""

    @abstractmethod
    def set_voltage(self, volts: float) -> None:
        """Set the voltage [V]."""

    @abstractmethod
    def set_current_limit(self, amps: float) -> None:
        """Set the current limit [A]."""

    @abstractmethod
    def settings(self) -> tuple[float, float]:
        """Read back (voltage [V], current limit [A]) as set."""

    @abstractmethod
    def output(self, on: bool) -> None:
        """Switch the output on or off."""

    @abstractmethod
    def measure(self) -> tuple[float, float]:
        """Measured (voltage [V], current [A]) at the output."""

    def close(self) -> None:
        """Close the VISA session."""
        _visa_call(self.resource, "close", self.resource.close)


class KoradSupply(Supply):
    """Korad KAxxxxP (KA3005P: 30 V, 5 A). No terminators; replies are five characters."""

    max_voltage = 31.0
    max_current = 5.1

    def __init__(self, resource: Any, *, pause: float = 0.05, sleep: Any = time.sleep):
        super().__init__(resource)
        self.pause = pause  # the supply needs ~50 ms per command (libsigrok's processing time)
        self._sleep = sleep

    def _send(self, command: str) -> None:
        _visa_call(self.resource, command, self.resource.write, command)
        self._sleep(self.pause)

    def _ask(self, command: str, size: int = 5) -> str:
        self._send(command)
        raw = _visa_call(self.resource, command, self.resource.read_bytes, size)
        return bytes(raw).decode("ascii", errors="replace")

    def identify(self) -> str:
        """``*IDN?`` (variable length: read until the supply falls silent)."""
        import pyvisa

        self._send("*IDN?")
        out = bytearray()
        saved = self.resource.timeout
        self.resource.timeout = 300  # ms: the reply has no terminator, silence ends it
        try:
            while len(out) < 64:
                out += self.resource.read_bytes(1)
        except pyvisa.errors.VisaIOError:
            pass
        finally:
            self.resource.timeout = saved
        return out.decode("ascii", errors="replace").strip()

    def set_voltage(self, volts: float) -> None:
        self._send(f"VSET1:{volts:05.2f}")

    def set_current_limit(self, amps: float) -> None:
        self._send(f"ISET1:{amps:05.3f}")

    def settings(self) -> tuple[float, float]:
        volts = _number(self._ask("VSET1?"), self.resource, "VSET1?")
        amps = _number(self._ask("ISET1?"), self.resource, "ISET1?")
        self._drain()
        return volts, amps

    def _drain(self) -> None:
        """Drop a stray sixth byte some firmware sends after ``ISET1?`` (libsigrok's workaround)."""
        import pyvisa

        saved = self.resource.timeout
        self.resource.timeout = 10  # ms
        try:
            self.resource.read_bytes(1)
        except pyvisa.errors.VisaIOError:
            pass
        finally:
            self.resource.timeout = saved

    def output(self, on: bool) -> None:
        self._send("OUT1" if on else "OUT0")

    def measure(self) -> tuple[float, float]:
        return (_number(self._ask("VOUT1?"), self.resource, "VOUT1?"),
                _number(self._ask("IOUT1?"), self.resource, "IOUT1?"))


class RigolDP800(Supply):
    """Rigol DP800 series, one channel (DP832: 30 V/3 A on channels 1 and 2)."""

    max_voltage = 32.0
    max_current = 3.2

    def __init__(self, resource: Any, *, channel: int = 1):
        super().__init__(resource)
        if channel not in (1, 2, 3):
            raise InstrumentError(f"DP800 channel must be 1, 2 or 3, got {channel}")
        self.channel = channel

    def _send(self, command: str) -> None:
        _visa_call(self.resource, command, self.resource.write, command)

    def _ask(self, command: str) -> str:
        return str(_visa_call(self.resource, command, self.resource.query, command))

    def _select(self) -> None:
        self._send(f":INST:NSEL {self.channel}")

    def identify(self) -> str:
        return self._ask("*IDN?").strip()

    def set_voltage(self, volts: float) -> None:
        self._select()
        self._send(f":SOUR:VOLT {volts:.4f}")

    def set_current_limit(self, amps: float) -> None:
        self._select()
        self._send(f":SOUR:CURR {amps:.4f}")

    def settings(self) -> tuple[float, float]:
        self._select()
        return (_number(self._ask(":SOUR:VOLT?"), self.resource, ":SOUR:VOLT?"),
                _number(self._ask(":SOUR:CURR?"), self.resource, ":SOUR:CURR?"))

    def output(self, on: bool) -> None:
        self._select()
        self._send(":OUTP ON" if on else ":OUTP OFF")

    def output_is_on(self) -> bool:
        """``:OUTP?`` of the selected channel."""
        self._select()
        return self._ask(":OUTP?").strip().upper() in ("ON", "1")

    def measure(self) -> tuple[float, float]:
        self._select()
        return (_number(self._ask(":MEAS:VOLT?"), self.resource, ":MEAS:VOLT?"),
                _number(self._ask(":MEAS:CURR?"), self.resource, ":MEAS:CURR?"))


#: Supply models by CLI name.
SUPPLIES: dict[str, type[Supply]] = {"korad": KoradSupply, "dp800": RigolDP800}


class RigolDS1000Z:
    """Rigol DS1000Z scope: frequency measurement, single edge trigger and the screen waveform."""

    def __init__(self, resource: Any, *, channel: int = 1):
        if channel not in (1, 2, 3, 4):
            raise InstrumentError(f"scope channel must be 1-4, got {channel}")
        self.resource = resource
        self.channel = channel

    def _send(self, command: str) -> None:
        _visa_call(self.resource, command, self.resource.write, command)

    def _ask(self, command: str) -> str:
        return str(_visa_call(self.resource, command, self.resource.query, command)).strip()

    def identify(self) -> str:
        """The ``*IDN?`` reply."""
        return self._ask("*IDN?")

    def frequency(self) -> float:
        """The scope's frequency measurement of the channel [Hz]; NaN when it shows nothing (9.9E37)."""
        command = f":MEAS:ITEM? FREQ,CHAN{self.channel}"
        value = _number(self._ask(command), self.resource, command)
        return math.nan if not math.isfinite(value) or value >= SCOPE_INVALID / 10 else value

    def arm_single(self, *, level: float, timebase: float) -> None:
        """Rising-edge trigger on the channel at ``level`` [V], ``timebase`` [s/div], single sweep."""
        self._send(":TRIG:MODE EDGE")
        self._send(f":TRIG:EDG:SOUR CHAN{self.channel}")
        self._send(":TRIG:EDG:SLOP POS")
        self._send(f":TRIG:EDG:LEV {level:.4f}")
        self._send(f":TIM:MAIN:SCAL {timebase:.6g}")
        self._send(":SING")

    def trigger_status(self) -> str:
        """``TD`` (triggered), ``WAIT``, ``RUN``, ``AUTO`` or ``STOP`` (a single sweep that completed)."""
        return self._ask(":TRIG:STAT?").upper()

    def stop(self) -> None:
        """Stop acquiring."""
        self._send(":STOP")

    def waveform(self) -> tuple[np.ndarray, np.ndarray]:
        """The screen waveform of the channel: times [s] (0 at the trigger) and volts [V].

        Raises
        ------
        InstrumentError
            When the data block is not a ``#N`` block of numbers.
        """
        self._send(f":WAV:SOUR CHAN{self.channel}")
        self._send(":WAV:MODE NORM")
        self._send(":WAV:FORM ASC")
        increment = _number(self._ask(":WAV:XINC?"), self.resource, ":WAV:XINC?")
        origin = _number(self._ask(":WAV:XOR?"), self.resource, ":WAV:XOR?")
        block = self._ask(":WAV:DATA?")
        name = getattr(self.resource, "resource_name", "scope")
        if not block.startswith("#") or len(block) < 2 or not block[1].isdigit():
            raise InstrumentError(f"{name}: :WAV:DATA? did not answer a #N data block")
        digits = int(block[1])
        body = block[2 + digits :]
        try:
            volts = np.array([float(v) for v in body.split(",") if v.strip()], dtype=float)
        except ValueError:
            raise InstrumentError(f"{name}: :WAV:DATA? holds something that is not a number") from None
        if volts.size < 2 or not (math.isfinite(increment) and increment > 0):
            raise InstrumentError(f"{name}: the waveform has {volts.size} points, increment {increment:g} s")
        return origin + increment * np.arange(volts.size), volts

    def close(self) -> None:
        """Close the VISA session."""
        _visa_call(self.resource, "close", self.resource.close)
