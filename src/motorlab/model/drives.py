"""The drives of the simulator: ideal voltage and current sources, a bench supply, an open circuit.

Re-exported by :mod:`motorlab.model.simulate` (import them from there).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from motorlab.errors import OptionError

MODE_VOLTAGE = 0
MODE_CURRENT = 1
MODE_OPEN = 2

Signal = float | Callable[[np.ndarray], Any]


@dataclass(frozen=True)
class VoltageDrive:
    """Ideal voltage source.

    Parameters
    ----------
    voltage
        Terminal voltage [V]: a constant or ``f(t) -> volts`` evaluated at the start of each step
        (held over the step, as a PWM average or a DAC output is).
    """

    voltage: Signal


@dataclass(frozen=True)
class CurrentDrive:
    """Ideal current source (a servo amplifier in current mode).

    Parameters
    ----------
    current
        Winding current [A]: a constant or ``f(t) -> amps`` held over each step.
    """

    current: Signal


@dataclass(frozen=True)
class BenchSupply:
    """Bench supply with constant-voltage / constant-current crossover.

    Parameters
    ----------
    voltage
        Voltage setpoint [V] (≥ 0).
    current_limit
        Current limit [A] (> 0).

    Notes
    -----
    In constant voltage (CV) the terminal voltage is the setpoint; when the current would exceed the
    limit the supply becomes a current source (CC) until R·I + K·ω reaches the setpoint again. A bench
    supply cannot sink current: when the back-EMF exceeds the setpoint the current stops at zero and
    the motor coasts as if disconnected.
    """

    voltage: float
    current_limit: float

    def __post_init__(self) -> None:
        if not (self.voltage >= 0 and math.isfinite(self.voltage)):
            raise OptionError(f"bench supply voltage must be ≥ 0 V, got {self.voltage}")
        if not (self.current_limit > 0 and math.isfinite(self.current_limit)):
            raise OptionError(f"bench supply current limit must be > 0 A, got {self.current_limit}")


@dataclass(frozen=True)
class OpenCircuit:
    """Relay open: no current; the terminals show the back-EMF K·ω."""


Drive = VoltageDrive | CurrentDrive | BenchSupply | OpenCircuit
