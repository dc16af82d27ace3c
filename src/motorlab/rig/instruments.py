"""The instruments of the dynamometer, each with the imperfections that shape real logs.

Every instrument is a small frozen dataclass holding its settings and error figures (SI units) and
plain methods that turn true values into readings with a caller-supplied ``np.random.Generator``.
Nothing here simulates the motor: :mod:`motorlab.rig.virtual` does that and hands true values in.

Figures and where they come from (see ``docs/rig.md`` for the full table):

- INA219 (TI datasheet SBOS448): bus-voltage LSB 4 mV, shunt-voltage LSB 10 µV, PGA /8 range ±320 mV
  (±3.2 A with the Adafruit breakout's 0.1 Ω shunt, 0.1 mA per LSB). Seed 1 ("Noisy Bus Voltage
  Data and Filter") found the raw bus voltage "extremely noisy" (commutation noise on unfiltered
  leads), so the default noise is 70 mV rms, far above the LSB; it also warns never to set the supply
  above 16 V with the INA219 in circuit.
- Encoder: quadrature, counts = ⌊θ·cpr/2π⌋; channel B rises once every 4 counts.
- Logging loop: the OpMode's ~100 ms loop, late by an exponential extra delay (mean 2 ms) and now
  and then by a garbage-collection stall (1 %, +30 ms); each value is stamped when it is read.
- Bench supply (TEKPower TP3005T class): CV/CC, 30 V / 5 A, display 0.01 V / 0.001 A.
- Oscilloscope (Rigol DS1054Z): manual cursors move by one of 600 screen columns across 12
  divisions; a person lines the cursor up within about half a column; frequency counter 0.02 %.
- LCR meter (DER EE DE-5000): 1 kHz, display 0.1 µH / 0.01 / 0.01 Ω; reading scatter 0.2 % (L), 1 % (Q).
- Scale: 1 g resolution, 0.5 g noise, 5 kg capacity.
- Servo amplifier (seed 2): current source I = Ka·V + offset, ±40 V compliance, 5 A sustained.
- Tachometer (seed 2): v = Kt·Ω plus 1 % commutator ripple (7 cycles per revolution) and 3 mV noise;
  optical tachometer 0.1 rpm resolution, ±0.05 %.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from motorlab.rig.ftc import LCFilter

import numpy as np

from motorlab.errors import OptionError, RigError
from motorlab.units import STANDARD_GRAVITY


def quantize(values: np.ndarray | float, step: float) -> np.ndarray:
    """Round ``values`` to the nearest multiple of ``step`` (an ADC's or a display's resolution)."""
    arr = np.asarray(values, dtype=float)
    if step <= 0:
        return arr.copy()
    # The second rounding removes binary residue (0.30000000000000004) so files print cleanly.
    decimals = max(0, math.ceil(-math.log10(step)) + 2)
    return np.round(np.round(arr / step) * step, decimals)


def _settings(obj: Any) -> dict[str, Any]:
    """A dataclass's settings as a JSON-ready dict (tuples become lists)."""
    out: dict[str, Any] = {}
    for key, value in asdict(obj).items():
        out[key] = list(value) if isinstance(value, tuple) else value
    return out


# ---- INA219 -------------------------------------------------------------------------------------
@dataclass(frozen=True)
class INA219:
    """INA219 high-side current and bus-voltage sensor (Adafruit breakout) read by the REV hub.

    Parameters
    ----------
    shunt_resistance
        Shunt resistor [Ω] (0.1 Ω on the Adafruit breakout).
    bus_lsb
        Bus-voltage register LSB [V] (4 mV, datasheet).
    shunt_lsb
        Shunt-voltage register LSB [V] (10 µV, datasheet), i.e. 0.1 mA with 0.1 Ω.
    shunt_range
        Full scale of the shunt voltage with PGA /8 [V] (±320 mV, i.e. ±3.2 A); larger currents clip.
    bus_range
        Bus-voltage full scale [V] (BRNG = 0: 16 V).
    bus_noise
        Rms noise of the raw bus-voltage reading [V]: commutation spikes picked up on the leads,
        "extremely noisy" in seed 1; the seed's 15-point average still looked noisy.
    current_noise
        Rms noise of the current reading [A].
    bus_offset
        Offset of the bus-voltage reading [V].
    current_offset
        Offset of the current reading [A] (seed 1's example log reads −0.001 A with the relay open).
    max_supply_voltage
        Highest supply setting allowed with the sensor in circuit [V] (seed 1: "do NOT set the
        voltage on the power supply to anything higher than 16 volts ... a high voltage will fry the
        sensor").
    averaging
        Samples averaged per result (1, 2, 4 … 128; the seed's sensor: 128).
    conversion_time
        Time of one 12-bit conversion [s] (532 µs, datasheet).
    bus_filter
        The seed's LC low-pass between the motor leads and the sensor's bus input
        (:class:`motorlab.rig.ftc.LCFilter`), or None (default: the sensor on the bare leads). The
        bus voltage it passes on is the filter's response to the terminal voltage, and the
        commutation noise is attenuated by its gain at ``noise_frequency`` (seed 1, "Noisy Bus
        Voltage Data and Filter").
    noise_frequency
        Frequency of the commutation noise in ``bus_noise`` [Hz] (brush and segment crossings of a
        small motor at speed: about 1 kHz; an assumption, the seed does not measure it).
    """

    shunt_resistance: float = 0.1
    bus_lsb: float = 4e-3
    shunt_lsb: float = 10e-6
    shunt_range: float = 0.32
    bus_range: float = 16.0
    bus_noise: float = 0.07
    current_noise: float = 3e-3
    bus_offset: float = 0.0
    current_offset: float = -1e-3
    max_supply_voltage: float = 16.0
    averaging: int = 1
    conversion_time: float = 532e-6
    bus_filter: LCFilter | None = None
    noise_frequency: float = 1e3

    @property
    def effective_bus_noise(self) -> float:
        """Rms bus-voltage noise at the sensor [V]: ``bus_noise`` × the filter's gain at ``noise_frequency``."""
        if self.bus_filter is None:
            return self.bus_noise
        return self.bus_noise * self.bus_filter.gain(self.noise_frequency)

    def bus_input(self, grid_time: np.ndarray, grid_voltage: np.ndarray) -> np.ndarray:
        """The voltage at the sensor's bus input [V] on a uniform grid [s]: filtered when there is a filter."""
        if self.bus_filter is None:
            return np.asarray(grid_voltage, dtype=float)
        return self.bus_filter.apply(grid_time, grid_voltage)

    @property
    def result_period(self) -> float:
        """Time of one (averaged) result [s]: ``averaging`` × 532 µs at 12 bits (128 samples: 68.1 ms)."""
        return self.averaging * self.conversion_time

    def conversion_average(self, times: np.ndarray, grid_time: np.ndarray, grid_value: np.ndarray) -> np.ndarray:
        """What the register holds at ``times`` [s]: the mean of the input over the last completed result.

        The INA219 converts continuously; with ``averaging`` = n (CONFIG BADC/SADC, datasheet SBOS448
        Table 5: 2 … 128 samples, 1.06 … 68.10 ms) the register is updated once per n·532 µs with the
        mean of those n conversions. A reading at t therefore shows the input averaged over
        [t_k − T, t_k], t_k the last completion before t: between T/2 and 3T/2 old (T = 68.1 ms with
        128 samples).
        """
        t = np.asarray(times, dtype=float)
        gt = np.asarray(grid_time, dtype=float)
        gv = np.asarray(grid_value, dtype=float)
        if self.averaging <= 1:
            return np.interp(t, gt, gv)
        period = self.result_period
        integral = np.concatenate([[0.0], np.cumsum(0.5 * (gv[1:] + gv[:-1]) * np.diff(gt))])
        done = np.floor((t - gt[0]) / period) * period + gt[0]
        start = done - period
        mean = (np.interp(done, gt, integral) - np.interp(start, gt, integral)) / period
        return np.where(start >= gt[0], mean, gv[0])

    @property
    def current_lsb(self) -> float:
        """Current resolution [A] = shunt LSB / shunt resistance."""
        return self.shunt_lsb / self.shunt_resistance

    @property
    def current_range(self) -> float:
        """Largest readable current magnitude [A]."""
        return self.shunt_range / self.shunt_resistance

    def check_supply(self, voltage: float) -> None:
        """Refuse a set-up whose supply voltage would damage the sensor.

        Raises
        ------
        RigError
            If ``voltage`` [V] exceeds ``max_supply_voltage``.
        """
        if abs(voltage) > self.max_supply_voltage:
            raise RigError(
                f"supply set to {voltage:g} V with the INA219 in circuit: it is rated "
                f"{self.max_supply_voltage:g} V (seed 1: 'a high voltage will fry the sensor')"
            )

    def read_bus_voltage(self, voltage: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Bus-voltage readings [V] of true terminal voltages ``voltage`` [V].

        The register is unsigned: negative voltages (motor turning backwards with the relay open)
        read 0; readings clip at ``bus_range``.
        """
        v = np.asarray(voltage, dtype=float)
        noisy = v + self.bus_offset + rng.normal(0.0, self.effective_bus_noise, v.shape)
        return np.clip(quantize(noisy, self.bus_lsb), 0.0, self.bus_range)

    def read_current(self, current: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Current readings [A] of true currents ``current`` [A] (signed, clipped at ±range)."""
        i = np.asarray(current, dtype=float)
        shunt = (i + self.current_offset + rng.normal(0.0, self.current_noise, i.shape)) * self.shunt_resistance
        shunt = np.clip(quantize(shunt, self.shunt_lsb), -self.shunt_range, self.shunt_range)
        # Divide and round to the 0.1 mA LSB again so that 1e-4 multiples print cleanly.
        return quantize(shunt / self.shunt_resistance, self.current_lsb)

    def settings(self) -> dict[str, Any]:
        """Settings for ``truth.json``."""
        return _settings(self)


# ---- encoder ------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Encoder:
    """Quadrature encoder counted by the hub, ``counts_per_revolution`` counts per shaft turn.

    Notes
    -----
    counts = ⌊θ·cpr/(2π)⌋ (θ [rad] from the count origin). Channel A leads channel B by a quarter
    cycle; one cycle of a channel spans 4 counts, and channel B rises when the count reaches
    4·m + 2 going forward, i.e. at θ = (4·m + 2)·2π/cpr (seed 1, Free Motor Spin-Up: "the times ...
    represent every fourth encoder count").
    """

    counts_per_revolution: float

    def __post_init__(self) -> None:
        if not self.counts_per_revolution > 0:
            raise OptionError(f"encoder counts per revolution must be positive, got {self.counts_per_revolution}")

    def counts(self, position: np.ndarray) -> np.ndarray:
        """Counts (integers) at shaft angles ``position`` [rad]."""
        x = np.asarray(position, dtype=float) * self.counts_per_revolution / (2 * math.pi)
        if not np.all(np.abs(x) < 2.0**62):  # NaN, inf or beyond a 64-bit counter: no cast warning
            raise RigError("the simulated shaft angle is not finite or overflows the encoder counter: "
                           "a setting far outside the rig's range (voltage, ramp rate, duration)?")
        # A tiny tolerance keeps exact multiples (e.g. position 0) from flooring to −1.
        return np.floor(x + 1e-9).astype(np.int64)

    def channel_b_rising_angles(self, start: float, stop: float) -> np.ndarray:
        """Angles [rad] in (start, stop] where channel B rises, for forward motion."""
        step = 2 * math.pi / self.counts_per_revolution
        m0 = math.floor((start / step - 2) / 4) + 1
        m1 = math.floor((stop / step - 2) / 4)
        m = np.arange(m0, m1 + 1)
        angles = (4 * m + 2) * step
        return angles[(angles > start) & (angles <= stop)]

    def channel_b_level(self, position: np.ndarray, *, high: float = 3.3) -> np.ndarray:
        """Logic level of channel B [V] at shaft angles ``position`` [rad]: high for counts ≡ 2, 3 (mod 4)."""
        return np.where(np.mod(self.counts(position), 4) >= 2, high, 0.0)

    def channel_frequency(self, speed: float) -> float:
        """Frequency [Hz] of one channel at shaft speed ``speed`` [rad/s]: |ω|·cpr/(4·2π)."""
        return abs(speed) * self.counts_per_revolution / (8 * math.pi)

    def settings(self) -> dict[str, Any]:
        """Settings for ``truth.json``."""
        return _settings(self)


# ---- logging loop -------------------------------------------------------------------------------
@dataclass(frozen=True)
class LoggingLoop:
    """The OpMode's logging loop: a sample every ``period`` plus a random extra delay.

    Parameters
    ----------
    period
        Nominal loop period [s] (seed 1: "take data every 100 milliseconds").
    extra_delay
        Mean of the exponential extra delay of each iteration [s] (the loop sleeps, then is late).
    stall_probability
        Probability that an iteration is delayed by ``stall_delay`` more (garbage collection, USB).
    stall_delay
        Extra delay of a stalled iteration [s].
    first_sample
        Range [s] of the first sample's time after the OpMode starts (seed 1's example: 12.6 ms).
    read_delays
        Delays [s] after the start of an iteration at which the encoder, the bus voltage and the
        shunt current are read (I²C reads take about a millisecond each); the row's time stamp is
        taken at the start of the iteration.
    """

    period: float = 0.1
    extra_delay: float = 2e-3
    stall_probability: float = 0.01
    stall_delay: float = 0.03
    first_sample: tuple[float, float] = (0.005, 0.02)
    read_delays: tuple[float, float, float] = (0.2e-3, 1.2e-3, 2.2e-3)

    def __post_init__(self) -> None:
        if not self.period > 0:
            raise OptionError(f"logging period must be positive, got {self.period}")

    def times(self, duration: float, rng: np.random.Generator) -> np.ndarray:
        """Time stamps [s] of the rows logged during ``duration`` [s] after the OpMode starts."""
        n_max = int(duration / self.period) + 2
        steps = self.period + rng.exponential(self.extra_delay, n_max)
        steps += np.where(rng.random(n_max) < self.stall_probability, self.stall_delay, 0.0)
        t0 = rng.uniform(*self.first_sample)
        times = t0 + np.concatenate(([0.0], np.cumsum(steps[:-1])))
        return times[times <= duration]

    def settings(self) -> dict[str, Any]:
        """Settings for ``truth.json``."""
        return _settings(self)


# ---- supply, relay ------------------------------------------------------------------------------
@dataclass(frozen=True)
class PowerSupply:
    """Bench supply in constant-voltage / constant-current mode (TEKPower TP3005T class).

    Parameters
    ----------
    max_voltage
        Highest voltage setting [V].
    max_current
        Highest current limit [A].
    voltage_resolution
        Display resolution of the voltage [V].
    current_resolution
        Display resolution of the current [A].
    current_accuracy
        Relative error of the current display (±0.2 % class) [-], drawn per reading.
    """

    max_voltage: float = 30.0
    max_current: float = 5.0
    voltage_resolution: float = 0.01
    current_resolution: float = 1e-3
    current_accuracy: float = 2e-3

    def check(self, voltage: float, current_limit: float) -> None:
        """Refuse settings outside the supply's range (``OptionError``)."""
        if not 0 < voltage <= self.max_voltage:
            raise OptionError(f"supply voltage must be in (0, {self.max_voltage:g}] V, got {voltage:g} V")
        if not 0 < current_limit <= self.max_current:
            raise OptionError(
                f"supply current limit must be in (0, {self.max_current:g}] A, got {current_limit:g} A"
            )

    def display_current(self, current: np.ndarray | float, rng: np.random.Generator) -> np.ndarray:
        """What the ammeter display shows [A] for true currents ``current`` [A]."""
        i = np.asarray(current, dtype=float)
        gain = 1 + rng.uniform(-self.current_accuracy, self.current_accuracy, i.shape)
        return quantize(i * gain, self.current_resolution)

    def settings(self) -> dict[str, Any]:
        """Settings for ``truth.json``."""
        return _settings(self)


@dataclass(frozen=True)
class Relay:
    """The relay between supply and motor, switched by the OpMode.

    Parameters
    ----------
    operate_time
        Delay from the command to contact closure [s].
    release_time
        Delay from the command to contact opening [s].
    """

    operate_time: float = 10e-3
    release_time: float = 5e-3

    def settings(self) -> dict[str, Any]:
        """Settings for ``truth.json``."""
        return _settings(self)


# ---- scale and lever ----------------------------------------------------------------------------
@dataclass(frozen=True)
class Scale:
    """Digital (postage) scale under a lever arm, tared with the arm resting on it.

    Parameters
    ----------
    resolution
        Display resolution [kg] (1 g).
    noise
        Rms reading noise [kg].
    capacity
        Largest readable mass [kg]; above it the display overloads.
    """

    resolution: float = 1e-3
    noise: float = 0.5e-3
    capacity: float = 5.0

    def read(self, torque: np.ndarray, arm: float, rng: np.random.Generator) -> np.ndarray:
        """Mass readings [kg] for torques ``torque`` [N·m] pressing through a lever of length ``arm`` [m].

        Notes
        -----
        m = τ/(g₀·arm) (seed 2, "The Motor Torque Constant"; g₀ = 9.80665 m/s²).

        Raises
        ------
        RigError
            If a reading would exceed the capacity.
        """
        force_mass = np.asarray(torque, dtype=float) / (STANDARD_GRAVITY * arm)
        if np.any(np.abs(force_mass) > self.capacity):
            raise RigError(
                f"scale overload: {np.max(np.abs(force_mass)):.2f} kg exceeds its {self.capacity:g} kg capacity "
                "(use a longer arm or smaller currents)"
            )
        return quantize(force_mass + rng.normal(0.0, self.noise, force_mass.shape), self.resolution)

    def settings(self) -> dict[str, Any]:
        """Settings for ``truth.json``."""
        return _settings(self)


# ---- LCR meter ----------------------------------------------------------------------------------
@dataclass(frozen=True)
class LCRMeter:
    """Handheld LCR meter (DER EE DE-5000) in series L/Q mode and DCR mode.

    Parameters
    ----------
    frequency
        Test frequency [Hz] (seed 1: 1 kHz).
    inductance_resolution
        Display resolution of L [H] (0.1 µH).
    quality_resolution
        Display resolution of Q [-].
    resistance_resolution
        Display resolution of DCR [Ω].
    inductance_scatter
        Relative rms scatter of L readings [-].
    quality_scatter
        Relative rms scatter of Q readings [-].
    resistance_noise
        Rms noise of DCR readings [Ω].
    """

    frequency: float = 1000.0
    inductance_resolution: float = 0.1e-6
    quality_resolution: float = 0.01
    resistance_resolution: float = 0.01
    inductance_scatter: float = 2e-3
    quality_scatter: float = 1e-2
    resistance_noise: float = 5e-3

    def read(
        self,
        inductance: np.ndarray,
        ac_resistance: np.ndarray,
        dc_resistance: np.ndarray,
        rng: np.random.Generator,
    ) -> dict[str, np.ndarray]:
        """Readings of L [H], Q [-] and DCR [Ω] for the true series L, AC and DC resistances.

        Notes
        -----
        Q = 2π·f·L/R_ac (seed 1, LCR Meter Experiment, "R = (2πFL)/Q").
        """
        L = np.asarray(inductance, dtype=float)
        q_true = 2 * math.pi * self.frequency * L / np.asarray(ac_resistance, dtype=float)
        return {
            "inductance": quantize(L * (1 + rng.normal(0.0, self.inductance_scatter, L.shape)),
                                   self.inductance_resolution),
            "quality_factor": quantize(q_true * (1 + rng.normal(0.0, self.quality_scatter, L.shape)),
                                       self.quality_resolution),
            "dc_resistance": quantize(np.asarray(dc_resistance, dtype=float)
                                      + rng.normal(0.0, self.resistance_noise, L.shape),
                                      self.resistance_resolution),
        }

    def settings(self) -> dict[str, Any]:
        """Settings for ``truth.json``."""
        return _settings(self)


# ---- oscilloscope -------------------------------------------------------------------------------
@dataclass(frozen=True)
class Oscilloscope:
    """Digital oscilloscope (Rigol DS1054Z): manual cursors, frequency counter, waveform export.

    Parameters
    ----------
    timebase
        Horizontal scale [s/div] (seed 1: 20 ms/div for fast motors, 200 ms/div otherwise).
    divisions
        Horizontal divisions on screen.
    columns
        Screen columns a manual cursor steps through.
    cursor_jitter
        Rms misalignment of a cursor placed by eye, in columns.
    frequency_scatter
        Relative rms error of the frequency counter [-].
    frequency_digits
        Significant digits the frequency counter shows.
    points
        Points per waveform export.
    vertical_noise
        Rms noise on exported waveforms [V].
    """

    timebase: float = 20e-3
    divisions: int = 12
    columns: int = 600
    cursor_jitter: float = 0.5
    frequency_scatter: float = 2e-4
    frequency_digits: int = 5
    points: int = 6000
    vertical_noise: float = 0.01

    #: Horizontal scales the DS1054Z offers [s/div].
    TIMEBASE_RANGE = (5e-9, 50.0)

    def __post_init__(self) -> None:
        low, high = self.TIMEBASE_RANGE
        if not low <= self.timebase <= high:  # NaN fails too
            raise OptionError(
                f"the scope's timebase (--timebase) must lie between {low:g} and {high:g} s/div, got {self.timebase!r}"
            )

    @property
    def cursor_step(self) -> float:
        """Time between adjacent cursor positions [s]."""
        return self.timebase * self.divisions / self.columns

    def cursor_times(self, times: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Cursor readings [s] of true edge times ``times`` [s] (relative to the trigger)."""
        t = np.asarray(times, dtype=float)
        placed = t + rng.normal(0.0, self.cursor_jitter * self.cursor_step, t.shape)
        return quantize(placed, self.cursor_step)

    def measure_frequency(self, frequency: np.ndarray | float, rng: np.random.Generator) -> np.ndarray:
        """Frequency-counter readings [Hz] of true frequencies [Hz]."""
        f = np.asarray(frequency, dtype=float)
        noisy = f * (1 + rng.normal(0.0, self.frequency_scatter, f.shape))
        out = np.zeros_like(noisy)
        nonzero = noisy > 0
        digits = self.frequency_digits - 1 - np.floor(np.log10(noisy[nonzero]))
        out[nonzero] = np.array([round(v, int(d)) for v, d in zip(noisy[nonzero], digits, strict=True)])
        return out

    def settings(self) -> dict[str, Any]:
        """Settings for ``truth.json``."""
        return _settings(self)


# ---- seed 2: amplifier, tachometers, multimeter -----------------------------------------------
@dataclass(frozen=True)
class Amplifier:
    """Servo amplifier used as a voltage-controlled current source (seed 2, "Amplifier Gain Constant").

    Parameters
    ----------
    gain
        Ka [A/V] of this amplifier (nominal 2 A/V in seed 2; this unit reads a little low).
    offset
        Output current at zero command [A].
    compliance
        Output voltage limit [V] (±40 V): beyond it the amplifier cannot keep the current.
    max_current
        Largest sustained output current [A] (5 A).
    """

    gain: float = 1.96
    offset: float = 6e-3
    compliance: float = 40.0
    max_current: float = 5.0

    def current(self, command: np.ndarray | float) -> np.ndarray:
        """Output current [A] for command voltages [V] into a short: clip(Ka·V + offset, ±max)."""
        i = self.gain * np.asarray(command, dtype=float) + self.offset
        return np.clip(i, -self.max_current, self.max_current)

    def settings(self) -> dict[str, Any]:
        """Settings for ``truth.json`` (``gain`` is the true Ka)."""
        return _settings(self)


@dataclass(frozen=True)
class Tachometer:
    """DC tachometer on the encoder shaft: v = Kt·Ω + ripple + noise (seed 2).

    Parameters
    ----------
    gain
        Kt_tach [V·s/rad] (3 V per 1000 rpm by default).
    ripple
        Relative commutator ripple amplitude [-].
    ripple_cycles
        Ripple cycles per shaft revolution.
    noise
        Rms voltage noise [V].
    """

    gain: float = 3.0 / (1000 * 2 * math.pi / 60)
    ripple: float = 0.01
    ripple_cycles: int = 7
    noise: float = 3e-3

    def voltage(self, speed: np.ndarray, position: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Tachometer voltage [V] at shaft speeds ``speed`` [rad/s] and angles ``position`` [rad]."""
        w = np.asarray(speed, dtype=float)
        ripple = 1 + self.ripple * np.sin(self.ripple_cycles * np.asarray(position, dtype=float))
        return self.gain * w * ripple + rng.normal(0.0, self.noise, w.shape)

    def settings(self) -> dict[str, Any]:
        """Settings for ``truth.json`` (``gain`` is the true Kt_tach)."""
        return _settings(self)


@dataclass(frozen=True)
class OpticalTachometer:
    """Non-contacting optical tachometer (seed 2, "The Tachometer Gain Constant").

    Parameters
    ----------
    resolution
        Display resolution [rpm].
    accuracy
        Relative rms error [-].
    """

    resolution: float = 0.1
    accuracy: float = 5e-4

    def read_rpm(self, speed: np.ndarray | float, rng: np.random.Generator) -> np.ndarray:
        """Readings [rpm] of shaft speeds ``speed`` [rad/s]."""
        rpm = np.abs(np.asarray(speed, dtype=float)) * 60 / (2 * math.pi)
        return quantize(rpm * (1 + rng.normal(0.0, self.accuracy, rpm.shape)), self.resolution)

    def settings(self) -> dict[str, Any]:
        """Settings for ``truth.json``."""
        return _settings(self)


@dataclass(frozen=True)
class Multimeter:
    """Bench multimeter (Wavetek class) reading a current or a voltage.

    Parameters
    ----------
    current_resolution
        Display resolution on the amp range [A].
    current_noise
        Rms reading noise on the amp range [A].
    voltage_resolution
        Display resolution on the volt range [V].
    voltage_noise
        Rms reading noise on the volt range [V] (after the meter's own averaging).
    """

    current_resolution: float = 1e-3
    current_noise: float = 2e-3
    voltage_resolution: float = 1e-3
    voltage_noise: float = 1e-3

    def read_current(self, current: np.ndarray | float, rng: np.random.Generator) -> np.ndarray:
        """Readings [A] of true currents [A]."""
        i = np.asarray(current, dtype=float)
        return quantize(i + rng.normal(0.0, self.current_noise, i.shape), self.current_resolution)

    def read_voltage(self, voltage: np.ndarray | float, rng: np.random.Generator) -> np.ndarray:
        """Readings [V] of true (averaged) voltages [V]."""
        v = np.asarray(voltage, dtype=float)
        return quantize(v + rng.normal(0.0, self.voltage_noise, v.shape), self.voltage_resolution)

    def settings(self) -> dict[str, Any]:
        """Settings for ``truth.json``."""
        return _settings(self)


# ---- FRC/FTC motor controller (SysId logs) ------------------------------------------------------
@dataclass(frozen=True)
class MotorController:
    """A smart motor controller's telemetry as WPILib SysId logs it.

    Parameters
    ----------
    log_period
        Logging period of the SysId routine [s].
    log_jitter
        Rms jitter of the log time stamps [s].
    status_period
        Refresh period of position and velocity in the controller's status frame [s]: between
        refreshes the logged values repeat (as in the real ``sysid-flywheel.json``).
    velocity_window
        Velocity is the count difference over this window [s] divided by it.
    voltage_noise
        Rms noise of the reported applied voltage [V].
    """

    log_period: float = 0.01
    log_jitter: float = 0.3e-3
    status_period: float = 0.02
    velocity_window: float = 0.05
    voltage_noise: float = 0.02

    def settings(self) -> dict[str, Any]:
        """Settings for ``truth.json``."""
        return _settings(self)


@dataclass(frozen=True)
class Instruments:
    """Every instrument on the bench; replace one with ``dataclasses.replace``."""

    ina219: INA219 = field(default_factory=INA219)
    logger: LoggingLoop = field(default_factory=LoggingLoop)
    supply: PowerSupply = field(default_factory=PowerSupply)
    relay: Relay = field(default_factory=Relay)
    scale: Scale = field(default_factory=Scale)
    lcr: LCRMeter = field(default_factory=LCRMeter)
    scope: Oscilloscope = field(default_factory=Oscilloscope)
    amplifier: Amplifier = field(default_factory=Amplifier)
    tachometer: Tachometer = field(default_factory=Tachometer)
    optical_tachometer: OpticalTachometer = field(default_factory=OpticalTachometer)
    multimeter: Multimeter = field(default_factory=Multimeter)
    controller: MotorController = field(default_factory=MotorController)
