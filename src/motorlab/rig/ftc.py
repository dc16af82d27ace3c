"""FTC sensors for the virtual rig: what a REV hub, its battery and the OpMode loop really report.

* :class:`HubEncoder`: counts (32-bit) and the hub's velocity, 20 × the count change over the hub's
  50 ms window, sent as a signed 16-bit integer that wraps at ±2¹⁵ ticks/s (the reason Road Runner
  repairs velocities: road-runner-ftc ``Encoders.kt``, ``inverseOverflow``).
* :class:`BulkReadLoop`: an OpMode loop of bulk reads and ``setPower`` commands whose period jitters
  between about 10 and 40 ms; each logged time is a ``MidpointTimer`` split (Tuning.kt).
* :class:`Battery`: a 12 V NiMH pack with internal resistance, sagging under the drive's current
  and drifting down as it discharges; :class:`HubVoltageSensor` reads it (1 mV, a little noise).
* :class:`LCFilter`: the seed's two-stage LC low-pass on the INA219's bus voltage (L1 = 33.5 mH,
  C1 = 8.3 µF, L2 = 23 mH, C2 = 2 µF; seed 1, "Noisy Bus Voltage Data and Filter"). The seed's
  diagram is not in its text: the ladder L1–C1–L2–C2 and the inductors' resistance are assumptions.
* INA219 conversion averaging lives on :class:`motorlab.rig.instruments.INA219`
  (``averaging=128``: 128 × 532 µs = 68.1 ms per result, TI SBOS448 Table 5).

:func:`simulate_ramp` drives a mecanum robot through Road Runner's ``ForwardRampLogger`` with these
sensors and writes the file in Road Runner's own JSON layout (:mod:`motorlab.io.roadrunner`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy import signal as sps

from motorlab.errors import OptionError
from motorlab.model import MotorParams, feedforward_from_params
from motorlab.model.simulate import VoltageDrive, simulate

#: The hub's velocity register: signed 16-bit.
INT16 = 2**16


def wrap_int16(values: np.ndarray) -> np.ndarray:
    """Signed 16-bit two's-complement wrap of integer values."""
    v = np.asarray(values, dtype=np.int64)
    return ((v + 2**15) % INT16) - 2**15


@dataclass(frozen=True)
class HubEncoder:
    """A quadrature encoder on a REV hub port.

    Parameters
    ----------
    counts_per_revolution
        Counts per turn of the encoder's shaft (8192 for a REV Through Bore, 2000 for a goBILDA pod).
    window
        The hub's velocity window [s]: velocity = count change over it / window (50 ms, so the
        velocity is a multiple of 20 ticks/s).
    update
        How often the hub recomputes the velocity [s] (not documented; 1 ms assumed).
    """

    counts_per_revolution: float
    window: float = 0.05
    update: float = 1e-3

    def counts(self, angle: np.ndarray) -> np.ndarray:
        """Counts at shaft angles [rad] (⌊θ·cpr/2π⌋)."""
        return np.floor(np.asarray(angle, dtype=float) * self.counts_per_revolution / (2 * math.pi) + 1e-9).astype(
            np.int64)

    def velocity(self, times: np.ndarray, angle_at: Any) -> np.ndarray:
        """The 16-bit velocity [ticks/s] the hub reports at ``times`` [s].

        ``angle_at(t)`` gives the shaft angle [rad] at any times. The count change over the last
        completed window, ×(1/window), wrapped to a signed 16-bit integer.
        """
        t = np.floor(np.asarray(times, dtype=float) / self.update) * self.update
        delta = self.counts(angle_at(t)) - self.counts(angle_at(t - self.window))
        return wrap_int16(np.round(delta / self.window).astype(np.int64))

    def true_velocity(self, times: np.ndarray, angle_at: Any) -> np.ndarray:
        """The same window velocity without the 16-bit wrap [ticks/s] (what a repair must give)."""
        t = np.floor(np.asarray(times, dtype=float) / self.update) * self.update
        return (self.counts(angle_at(t)) - self.counts(angle_at(t - self.window))) / self.window


@dataclass(frozen=True)
class BulkReadLoop:
    """An OpMode loop: powers set, battery read, bulk read, each command taking a little time.

    Parameters
    ----------
    min_period, max_period
        Range of the loop period [s] (bulk reads of one or two hubs: 10–40 ms).
    mean_extra
        Mean of the exponential extra time above ``min_period`` [s].
    command_time
        Duration of one ``setPower`` (a Lynx command) [s].
    voltage_read_time, bulk_read_time
        Duration of the battery read and of the bulk read [s].
    """

    min_period: float = 0.010
    max_period: float = 0.040
    mean_extra: float = 0.006
    command_time: float = 0.6e-3
    voltage_read_time: float = 1.5e-3
    bulk_read_time: float = 2.5e-3

    def __post_init__(self) -> None:
        if not 0 < self.min_period <= self.max_period:
            raise OptionError("loop periods must satisfy 0 < min_period ≤ max_period")

    def starts(self, duration: float, rng: np.random.Generator) -> np.ndarray:
        """Start times [s] of the iterations within ``duration``."""
        n = int(duration / self.min_period) + 2
        steps = np.clip(self.min_period + rng.exponential(self.mean_extra, n), self.min_period, self.max_period)
        t = np.concatenate([[0.0], np.cumsum(steps)])
        return t[t < duration]

    def schedule(self, starts: np.ndarray, motors: int) -> dict[str, np.ndarray]:
        """End times of each command in every iteration: ``power`` (iterations × motors), ``voltage``, ``bulk``."""
        power = starts[:, None] + self.command_time * np.arange(1, motors + 1)[None, :]
        voltage = power[:, -1] + self.voltage_read_time
        bulk = voltage + self.bulk_read_time
        return {"power": power, "voltage": voltage, "bulk": bulk}


@dataclass(frozen=True)
class Battery:
    """A 12 V FTC battery pack: open-circuit voltage, internal resistance, discharge drift.

    Parameters
    ----------
    open_circuit
        Open-circuit voltage at the start [V].
    internal_resistance
        Pack + wiring + hub resistance [Ω].
    drift
        Fall of the open-circuit voltage [V/s] (discharge).
    other_current
        Current of everything else on the robot [A].
    """

    open_circuit: float = 13.2
    internal_resistance: float = 0.12
    drift: float = 0.01
    other_current: float = 0.4

    def bus_voltage(self, time: np.ndarray, drive_current: np.ndarray) -> np.ndarray:
        """Voltage at the hub [V] while the drive draws ``drive_current`` [A] from the battery."""
        t = np.asarray(time, dtype=float)
        return self.open_circuit - self.drift * t - self.internal_resistance * (self.other_current + drive_current)


@dataclass(frozen=True)
class HubVoltageSensor:
    """The hub's battery ``VoltageSensor``: millivolt resolution and a little noise [V]."""

    resolution: float = 1e-3
    noise: float = 0.01

    def read(self, voltage: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Readings [V] of true bus voltages [V]."""
        v = np.asarray(voltage, dtype=float)
        return np.round((v + rng.normal(0.0, self.noise, v.shape)) / self.resolution) * self.resolution


@dataclass(frozen=True)
class LCFilter:
    """The seed's two-stage LC low-pass on the bus voltage (ladder L1, C1, L2, C2; unloaded output).

    Parameters
    ----------
    L1, L2
        Inductances [H] (seed: 33.5 mH, 23 mH).
    C1, C2
        Capacitances [F] (seed: 8.3 µF, 2 µF).
    resistance
        Series resistance of each inductor [Ω] (not in the seed; assumed).
    """

    L1: float = 33.5e-3
    L2: float = 23e-3
    C1: float = 8.3e-6
    C2: float = 2e-6
    resistance: float = 5.0

    def state_space(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(A, B, C, D) with state (i1, v1, i2, v2), input the source voltage, output v2."""
        r, l1, l2, c1, c2 = self.resistance, self.L1, self.L2, self.C1, self.C2
        a = np.array([
            [-r / l1, -1 / l1, 0, 0],
            [1 / c1, 0, -1 / c1, 0],
            [0, 1 / l2, -r / l2, -1 / l2],
            [0, 0, 1 / c2, 0],
        ])
        return a, np.array([[1 / l1], [0], [0], [0]]), np.array([[0, 0, 0, 1.0]]), np.zeros((1, 1))

    def apply(self, time: np.ndarray, voltage: np.ndarray) -> np.ndarray:
        """The filtered voltage [V] on a uniform time grid [s] (starting in steady state)."""
        t = np.asarray(time, dtype=float)
        v = np.asarray(voltage, dtype=float)
        a, b, c, d = self.state_space()
        x0 = np.linalg.solve(a, -b[:, 0] * v[0])
        _, y, _ = sps.lsim((a, b, c, d), v, t - t[0], X0=x0)
        return np.asarray(y, dtype=float)

    def gain(self, frequency: float) -> float:
        """|H(j2πf)|: the amplitude ratio of output to source at ``frequency`` [Hz]."""
        a, b, c, _ = self.state_space()
        h = c @ np.linalg.solve(2j * math.pi * frequency * np.eye(4) - a, b)
        return float(abs(h[0, 0]))

    def resonances(self) -> list[float]:
        """Resonant frequencies [Hz] of the ladder (lossless)."""
        a, *_ = self.state_space()
        lossless = LCFilter(self.L1, self.L2, self.C1, self.C2, 0.0).state_space()[0] if self.resistance else a
        w = np.abs(np.linalg.eigvals(lossless).imag)
        return sorted({round(float(x) / (2 * math.pi), 3) for x in w if x > 0})


# ---- Road Runner ramp on a simulated mecanum drive -----------------------------------------------


@dataclass(frozen=True)
class MecanumDrive:
    """A mecanum robot: four identical gearmotors, three dead wheels on hub encoder ports.

    Parameters
    ----------
    motor
        One drive motor at its output shaft (goBILDA 5203 312 rpm class by default) [SI].
    mass
        Robot mass [kg].
    yaw_inertia
        Robot moment of inertia about its vertical axis [kg·m²].
    wheel_radius
        Drive wheel radius [m].
    track_width
        Road Runner's mecanum ``trackWidth``: a wheel's rolling speed per yaw rate [m] (Kinematics.kt:
        wheel velocity = … ± ω·trackWidth).
    strafe_ratio
        Lateral robot speed per forward speed at equal wheel speed (roller slip; 1 = ideal).
    dead_wheel_radius
        Dead-wheel radius [m].
    dead_wheel
        The dead wheels' encoder (8192 counts per revolution: REV Through Bore).
    par_y
        Lateral offsets of the two parallel dead wheels [m].
    perp_x
        Longitudinal offset of the perpendicular dead wheel [m].
    """

    motor: MotorParams = field(default_factory=lambda: MotorParams(K=0.34, R=1.3, L=1e-3, J=2e-3, b=1e-3, Tf=0.08))
    mass: float = 12.0
    yaw_inertia: float = 0.35
    wheel_radius: float = 0.048
    track_width: float = 0.32
    strafe_ratio: float = 0.85
    dead_wheel_radius: float = 0.0175
    dead_wheel: HubEncoder = field(default_factory=lambda: HubEncoder(8192))
    par_y: tuple[float, float] = (0.15, -0.15)
    perp_x: float = -0.1

    def wheel_params(self, kind: str = "forward") -> MotorParams:
        """One motor with its share of the robot at the wheel (forward, lateral or angular motion)."""
        r = self.wheel_radius
        if kind == "lateral":
            load = 0.25 * self.mass * (self.strafe_ratio * r) ** 2
        elif kind == "angular":
            load = 0.25 * self.yaw_inertia * (r / self.track_width) ** 2
        else:
            load = 0.25 * self.mass * r**2
        return self.motor.with_load(load)

    def encoder_params(self, kind: str = "forward") -> MotorParams:
        """The motor seen at the dead wheel's shaft: G = r_dead/r_wheel motor radians per encoder radian.

        K' = G·K, J' = G²·J, b' = G²·b, Tf' = G·Tf, so kS is unchanged and kV, kA scale by G. For the
        lateral ramp the encoder is the perpendicular wheel, G = r_dead / (strafe_ratio·r_wheel).
        """
        m = self.wheel_params(kind)
        g = self.dead_wheel_radius / self.wheel_radius
        if kind == "lateral":
            g /= self.strafe_ratio
        return MotorParams(K=g * m.K, R=m.R, L=m.L, J=g * g * m.J, b=g * g * m.b, Tf=g * m.Tf)

    def truth(self) -> dict[str, float]:
        """kS [V], kV [V·s/rad], kA [V·s²/rad] at the dead-wheel encoder, and the geometry in ticks."""
        ticks_per_m = self.dead_wheel.counts_per_revolution / (2 * math.pi * self.dead_wheel_radius)
        return {
            **feedforward_from_params(self.encoder_params()),
            "track_width_ticks": self.track_width * ticks_per_m,
            "lateral_ratio": self.strafe_ratio,
            "in_per_tick": 39.37007874 / ticks_per_m,
        }


@dataclass(frozen=True)
class RampSettings:
    """Road Runner's ramp logger settings (``POWER_PER_SEC``, ``POWER_MAX``) and the run's length."""

    power_per_sec: float = 0.1
    power_max: float = 0.9
    duration: float = 6.0


#: Power sign of each motor (leftFront, leftBack, rightFront, rightBack) in each ramp (Tuning.kt).
SIGNS = {"forward": (1, 1, 1, 1), "lateral": (-1, 1, 1, -1), "angular": (-1, -1, 1, 1)}


def _motion(drive: MecanumDrive, kind: str, wheel_angle: Any) -> dict[str, Any]:
    """Dead-wheel angles [rad] (par0, par1, perp) and yaw rate as functions of time, from one wheel's angle."""
    r, rd = drive.wheel_radius, drive.dead_wheel_radius

    def along(t: np.ndarray) -> np.ndarray:  # wheel rolling distance [m]
        return np.asarray(wheel_angle(t)) * r

    par: list[Callable[[np.ndarray], np.ndarray]]
    perp: list[Callable[[np.ndarray], np.ndarray]]
    if kind == "forward":
        par = [lambda t: along(t) / rd] * 2
        perp = [lambda t: 0.0 * along(t)]
    elif kind == "lateral":
        par = [lambda t: 0.0 * along(t)] * 2
        perp = [lambda t: drive.strafe_ratio * along(t) / rd]
    else:  # yaw angle = distance / trackWidth; a dead wheel at (x, y) moves by (−y·ψ, x·ψ)
        def par_wheel(y: float) -> Callable[[np.ndarray], np.ndarray]:
            return lambda t: -y * along(t) / drive.track_width / rd

        par = [par_wheel(y) for y in drive.par_y]
        perp = [lambda t: drive.perp_x * along(t) / drive.track_width / rd]
    return {"par": par, "perp": perp}
def held_mean(edges: np.ndarray, switch: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Mean over each step [edges_j, edges_j+1) of a staircase set to ``values[k]`` at ``switch[k]`` (0 before).

    The integral of a staircase is piecewise linear, so interpolating it at the edges is exact: a
    power applied between two simulation steps acts for its share of the step, not from the next one
    (on the ramp that would delay every power by half a step on average).
    """
    knots = np.concatenate([[min(edges[0], switch[0]) - 1.0], switch, [max(edges[-1], switch[-1]) + 1.0]])
    levels = np.concatenate([[0.0], values])
    integral = np.concatenate([[0.0], np.cumsum(levels * np.diff(knots))])
    return np.diff(np.interp(edges, knots, integral)) / np.diff(edges)


def _simulate_motion(params: MotorParams, applied: np.ndarray, powers: np.ndarray, battery: Battery,
                     duration: float) -> tuple[Any, np.ndarray]:
    """One wheel driven by power × bus voltage, the bus sagging with the four motors' current.

    ``applied`` and ``powers`` are (iterations,) or (iterations × motors): when each motor's power
    took effect [s] and its value; the wheel sees the motors' mean power, averaged exactly over
    each simulation step.
    """
    dt = 1e-3
    bus_t = np.arange(0.0, duration + 0.2, dt)
    bus_v = battery.bus_voltage(bus_t, np.zeros_like(bus_t))
    applied2, powers2 = np.atleast_2d(np.asarray(applied).T).T, np.atleast_2d(np.asarray(powers).T).T
    edges = np.append(bus_t, bus_t[-1] + dt)
    step_power = np.mean([held_mean(edges, applied2[:, m], powers2[:, m]) for m in range(powers2.shape[1])], axis=0)

    def power_at(t: np.ndarray) -> np.ndarray:
        return step_power[np.clip(np.round(np.asarray(t) / dt).astype(np.int64), 0, step_power.size - 1)]

    # Fixed point: the bus voltage depends on the current it drives (a contraction by about
    # R_batt·4·p²/R per pass). Iterate to 1 µV and return the bus the last simulation was driven
    # with: after a fixed four passes the logged bus differed from the one driving the motors by
    # a few mV, which reads as kV −0.015 %.
    for _ in range(30):
        bv = bus_v.copy()

        def volts(t: np.ndarray, bv: np.ndarray = bv) -> np.ndarray:
            return power_at(t) * np.interp(t, bus_t, bv)

        sim = simulate(params, VoltageDrive(volts), duration=float(bus_t[-1]), dt=dt)
        bus_v = battery.bus_voltage(sim.time, 4.0 * power_at(sim.time) * np.abs(sim.current))
        if float(np.max(np.abs(bus_v - bv))) < 1e-6:
            break
    return sim, bv


def _ramp_content(kind: str, mids: np.ndarray, powers: np.ndarray, readings: np.ndarray,
                  signals: dict[str, list[tuple[np.ndarray, np.ndarray]]]) -> dict[str, Any]:
    """The fields of a ramp file (Tuning.kt's ``data`` objects) from the simulated signals."""
    signs = SIGNS[kind]
    content: dict[str, Any] = {"type": "MECANUM"}
    if kind == "forward":
        content["powers"] = [(mids[:, i], signs[i] * powers[:, i]) for i in range(4)]
        content["voltages"] = (mids[:, 4], readings)
        content.update(forwardEncPositions=signals["parPos"], forwardEncVels=signals["parVel"],
                       forwardEncFixVels=[True, True])
    elif kind == "lateral":
        order = (0, 2, 1, 3)  # Tuning.kt sets frontLeft, frontRight, backLeft, backRight in turn
        for i, key in enumerate(("frontLeftPower", "backLeftPower", "frontRightPower", "backRightPower")):
            content[key] = (mids[:, order[i]], signs[i] * powers[:, order[i]])
        content["voltages"] = (mids[:, 4], readings)
        content.update(perpEncPositions=signals["perpPos"], perpEncVels=signals["perpVel"], perpEncFixVels=[True])
    else:
        content["leftPowers"] = [(mids[:, i], -powers[:, i]) for i in (0, 1)]
        content["rightPowers"] = [(mids[:, i], powers[:, i]) for i in (2, 3)]
        content["voltages"] = (mids[:, 4], readings)
        for side in ("left", "right"):
            content.update({f"{side}EncPositions": [], f"{side}EncVels": [], f"{side}EncFixVels": []})
        content.update(parEncPositions=signals["parPos"], parEncVels=signals["parVel"], parEncFixVels=[True, True],
                       perpEncPositions=signals["perpPos"], perpEncVels=signals["perpVel"], perpEncFixVels=[True])
    return content


def _drive_encoder_signals(cpr: float, sim: Any, bulk_t: np.ndarray, rng: np.random.Generator) -> dict[str, Any]:
    """Angular ramp fields with two drive-motor encoders per side (left turning backwards), no dead wheels."""
    enc = HubEncoder(cpr)
    content: dict[str, Any] = {}
    for side, sign in (("left", -1.0), ("right", 1.0)):
        pos, vel = [], []
        for _ in range(2):
            off = rng.uniform(0, 2 * math.pi / cpr)

            def wheel(t: np.ndarray, sign: float = sign, off: float = off) -> np.ndarray:
                return sign * np.interp(t, sim.time, sim.position, left=0.0) + off

            pos.append((bulk_t, enc.counts(wheel(bulk_t)) - enc.counts(wheel(np.zeros(1)))))
            vel.append((bulk_t, enc.velocity(bulk_t, wheel)))
        content.update({f"{side}EncPositions": pos, f"{side}EncVels": vel, f"{side}EncFixVels": [True, True]})
    for group in ("par", "perp"):
        content.update({f"{group}EncPositions": [], f"{group}EncVels": [], f"{group}EncFixVels": []})
    return content


def simulate_ramp(
    path: Any,
    *,
    kind: str = "forward",
    drive: MecanumDrive | None = None,
    settings: RampSettings | None = None,
    loop: BulkReadLoop | None = None,
    battery: Battery | None = None,
    sensor: HubVoltageSensor | None = None,
    drive_encoder_cpr: float | None = None,
    seed: int = 0,
) -> dict[str, Any]:
    """Simulate one of Road Runner's ramp loggers on a mecanum drive and write its JSON file.

    The power ramps by ``power_per_sec`` (capped at ``power_max``) with each motor's sign of the
    logger (Tuning.kt); the motors see power × bus voltage, the bus sags with the drive's current
    through the battery's internal resistance (fixed-point iteration of the simulation); the dead
    wheels are counted by the hub and their 16-bit velocities wrap; the angular ramp adds the IMU's
    angular velocities.

    Parameters
    ----------
    path
        The ``.json`` file to write.
    kind
        ``"forward"``, ``"lateral"`` or ``"angular"``.
    drive_encoder_cpr
        Angular ramp only: log the drive motors' encoders (counts per revolution of the wheel shaft)
        instead of dead wheels; the truth's ``drive_track_width_ticks`` is then in those ticks.

    Returns
    -------
    dict
        The truth: ``kS``, ``kV``, ``kA`` at the dead-wheel encoder (forward motion), ``track_width_ticks``,
        ``lateral_ratio``, ``cpr``, the number of wrapped velocity samples, the lowest bus voltage.
    """
    from motorlab.io.roadrunner import write_roadrunner_ramp

    if kind not in SIGNS:
        raise OptionError(f"ramp kind must be forward, lateral or angular, got {kind!r}")
    drive = drive or MecanumDrive()
    settings = settings or RampSettings()
    loop = loop or BulkReadLoop()
    battery = battery or Battery()
    sensor = sensor or HubVoltageSensor()
    rng = np.random.default_rng(seed)
    starts = loop.starts(settings.duration, rng)
    sched = loop.schedule(starts, 4)
    # Tuning.kt evaluates power(t.seconds()) just before each motor's setPower; the hub applies it
    # during that Lynx command (taken at its middle)
    cmd_start = sched["power"] - loop.command_time
    powers = np.minimum(settings.power_per_sec * cmd_start, settings.power_max)
    sim, bus_v = _simulate_motion(drive.wheel_params(kind), cmd_start + 0.5 * loop.command_time, powers, battery,
                                  settings.duration)
    # MidpointTimer splits: each logged time is the midpoint of the previous split and this one
    ends = np.column_stack([sched["power"], sched["voltage"], sched["bulk"]]).ravel()
    mids = (0.5 * (np.concatenate([[0.0], ends[:-1]]) + ends)).reshape(-1, 6)
    bulk_t = mids[:, 5]
    readings = sensor.read(np.interp(sched["voltage"], sim.time, bus_v), rng)
    motion = _motion(drive, kind, lambda t: np.interp(t, sim.time, sim.position, left=0.0))
    enc = drive.dead_wheel
    signals: dict[str, list[tuple[np.ndarray, np.ndarray]]] = {}
    wrapped = 0
    for group, fns in motion.items():
        pos, vel = [], []
        for fn in fns:
            offset = rng.uniform(0, 2 * math.pi / enc.counts_per_revolution)
            def angle(t, fn=fn, offset=offset):
                return (fn(t) + offset)
            v = enc.velocity(bulk_t, angle)
            wrapped += int(np.count_nonzero(v != enc.true_velocity(bulk_t, angle)))
            pos.append((bulk_t, enc.counts(angle(bulk_t)) - enc.counts(angle(np.zeros(1)))))
            vel.append((bulk_t, v))
        signals[group + "Pos"], signals[group + "Vel"] = pos, vel
    content = _ramp_content(kind, mids, powers, readings, signals)
    extra: dict[str, float] = {}
    if kind == "angular" and drive_encoder_cpr:
        content.update(_drive_encoder_signals(drive_encoder_cpr, sim, bulk_t, rng))
        extra["drive_track_width_ticks"] = drive.track_width / drive.wheel_radius * drive_encoder_cpr / (2 * math.pi)
    if kind == "angular":
        yaw_rate = np.interp(bulk_t, sim.time, sim.speed) * drive.wheel_radius / drive.track_width
        imu_t, noise = bulk_t + 1e-3, 2e-3
        content["angVels"] = [(imu_t, rng.normal(0, noise, bulk_t.size)), (imu_t, rng.normal(0, noise, bulk_t.size)),
                              (imu_t, yaw_rate + rng.normal(0, noise, bulk_t.size))]
    write_roadrunner_ramp(path, content)
    if kind == "lateral":
        extra["lateral_kA"] = feedforward_from_params(drive.encoder_params("lateral"))["kA"]
    return {
        **drive.truth(),
        "kind": kind,
        "cpr": enc.counts_per_revolution,
        "wrapped_samples": wrapped,
        "samples": int(starts.size),
        "min_bus_voltage": float(bus_v.min()),
        **extra,
    }


def simulate_flight_log(
    path: Any,
    *,
    motor: MotorParams | None = None,
    cpr: float = 537.7,
    duration: float = 8.0,
    loop: BulkReadLoop | None = None,
    battery: Battery | None = None,
    dead_wheels: bool | int = False,
    seed: int = 0,
) -> dict[str, Any]:
    """A FlightRecorder log of a mecanum robot following back-and-forth moves.

    With ``dead_wheels`` (True or 3) the localizer is the quickstart's ThreeDeadWheelLocalizer
    (8192-count dead wheels; ``THREE_DEAD_WHEEL_INPUTS`` and the ``MECANUM_PARAMS`` /
    ``THREE_DEAD_WHEEL_PARAMS`` it needs); with 2, the TwoDeadWheelLocalizer (``TWO_DEAD_WHEEL_INPUTS``
    with the IMU's angles and rates, ``TWO_DEAD_WHEEL_PARAMS``). The truth is then at the dead wheel.

    Each wheel is the forward-motion wheel of :class:`MecanumDrive` (drive motor encoders, ``cpr`` at
    the motor's output). The drive sets its powers every loop iteration from a smooth profile
    (forward, back, with a pause); ``MECANUM_COMMAND`` is logged at most every 50 ms (Road Runner's
    ``DownsampledWriter``), ``MECANUM_LOCALIZER_INPUTS`` every iteration, time stamps in ns.

    Returns
    -------
    dict
        Truth: ``kS``, ``kV``, ``kA`` of one wheel at its motor encoder, ``cpr``.
    """
    from motorlab.io.flightrecorder import MECANUM_WHEELS, write_flight_log

    drive = MecanumDrive() if motor is None else MecanumDrive(motor=motor)
    params = drive.wheel_params("forward")
    loop = loop or BulkReadLoop()
    battery = battery or Battery()
    rng = np.random.default_rng(seed)
    starts = loop.starts(duration, rng)
    sched = loop.schedule(starts, 4)

    def profile(t: np.ndarray) -> np.ndarray:  # two moves: forward then back, 0.6 power peak
        move = lambda t0, t1: np.clip(np.sin(np.pi * (t - t0) / (t1 - t0)), 0, None) * ((t > t0) & (t < t1))  # noqa: E731
        return 0.6 * move(0.5, 3.5) ** 0.7 - 0.45 * move(4.5, 7.5) ** 0.7

    powers = profile(sched["power"][:, 0])
    sim, bus_v = _simulate_motion(params, sched["power"].mean(axis=1), powers, battery, duration)
    enc = drive.dead_wheel if dead_wheels else HubEncoder(cpr)
    scale = drive.wheel_radius / drive.dead_wheel_radius if dead_wheels else 1.0
    offsets = rng.uniform(0, 2 * math.pi / enc.counts_per_revolution, 4)
    bulk = sched["bulk"] - 0.5 * loop.bulk_read_time
    ns = lambda t: round(1e9 * (t + 100.0))  # noqa: E731  (nanoTime has an arbitrary origin)
    messages: list[tuple[str, Any]] = []
    truth = drive.truth()
    two = dead_wheels == 2 and dead_wheels is not True
    if dead_wheels:
        ticks = truth["track_width_ticks"] / drive.track_width  # dead-wheel ticks per metre
        messages.append(("MECANUM_PARAMS", {"inPerTick": truth["in_per_tick"], "lateralInPerTick": truth["in_per_tick"],
                                            "trackWidthTicks": truth["track_width_ticks"], "kS": 0.0, "kV": 0.0,
                                            "kA": 0.0}))
        if two:
            messages.append(("TWO_DEAD_WHEEL_PARAMS", {"parYTicks": drive.par_y[0] * ticks,
                                                       "perpXTicks": drive.perp_x * ticks}))
        else:
            messages.append(("THREE_DEAD_WHEEL_PARAMS", {"par0YTicks": drive.par_y[0] * ticks,
                                                         "par1YTicks": drive.par_y[1] * ticks,
                                                         "perpXTicks": drive.perp_x * ticks}))
    names = (("par", "perp", "unused0", "unused1") if two else ("par0", "par1", "perp", "unused0")) if dead_wheels \
        else MECANUM_WHEELS
    last = -math.inf
    for k in range(starts.size):
        pairs = {}
        for w, off in zip(names, offsets, strict=True):
            along = 0.0 if w == "perp" else scale

            def angle(t: np.ndarray, off: float = off, along: float = along) -> np.ndarray:
                return along * np.interp(t, sim.time, sim.position) + off

            c = int(enc.counts(angle(np.array([bulk[k]])))[0] - enc.counts(np.array([off]))[0])
            v = int(enc.velocity(np.array([bulk[k]]), angle)[0])
            pairs[w] = {"position": c, "rawPosition": c, "rawVelocity": v, "velocity": v}
        for unused in ("unused0", "unused1"):
            pairs.pop(unused, None)
        if two:  # a robot moving straight: the IMU reads no turn (yaw, pitch, roll; rates in rad/s)
            imu = dict.fromkeys(("yaw", "pitch", "roll", "xRotationRate", "yRotationRate", "zRotationRate"), 0.0)
            messages.append(("TWO_DEAD_WHEEL_INPUTS", {"timestamp": ns(bulk[k]), **pairs, **imu}))
        elif dead_wheels:
            messages.append(("THREE_DEAD_WHEEL_INPUTS", {"timestamp": ns(bulk[k]), **pairs}))
        else:
            messages.append(("MECANUM_LOCALIZER_INPUTS", {"timestamp": ns(bulk[k]), **pairs, "pitch": 0.0,
                                                          "roll": 0.0, "yaw": 0.0}))
        t_cmd = sched["power"][k, 0]
        if t_cmd - last >= 0.05:  # DownsampledWriter(…, 50_000_000)
            last = t_cmd
            volt = float(np.round(np.interp(sched["voltage"][k], sim.time, bus_v), 3))
            p = float(powers[k])
            messages.append(("MECANUM_COMMAND", {"timestamp": ns(t_cmd), "voltage": volt, "leftFrontPower": p,
                                                 "leftBackPower": p, "rightBackPower": p, "rightFrontPower": p}))
    write_flight_log(path, messages)
    if dead_wheels:
        return {k: truth[k] for k in ("kS", "kV", "kA")} | {"cpr": enc.counts_per_revolution}
    return {**feedforward_from_params(params), "cpr": cpr}
