"""The emulated robot's drive under Road Runner's ``ManualFeedforwardTuner``: it follows the gains it is given.

The verification run of issue 32, item 7: the OpMode drives a motion profile open loop with the
feedforward built from the robot's ``@Config`` values, so wrong gains track worse, as on a real robot.
What the real OpMode does, read from acmerobotics/road-runner-ftc
``RoadRunner/src/main/java/com/acmerobotics/roadrunner/ftc/Tuning.kt`` (class ``ManualFeedforwardTuner``)
and road-runner-quickstart ``TuningOpModes.java`` / ``MecanumDrive.java``:

* the profile is ``constantProfile(DISTANCE = 64.0, 0.0, maxWheelVel, minProfileAccel, maxProfileAccel)``
  (a trapezoid in inches), driven forwards, then backwards, then forwards… until STOP;
* each loop the power is ``MotorFeedforward(kS, kV / inPerTick, kA / inPerTick).compute(v) / voltage``,
  ``compute`` being ``kS·sgn(v) + kV·v + kA·a``, clipped to ±1 by ``setDrivePowers``;
* its telemetry (``MultipleTelemetry``: the Dashboard gets it) is ``mode`` (``TUNING_MODE``, a word),
  ``v0``… ``v3`` (each forward encoder's velocity times ``inPerTick``; the encoder's velocity is a whole
  number of ticks per second, ``PositionVelocityPair``'s ``Int``) and ``vref`` (the profile's velocity).

The robot's true drive is the emulator's :class:`~motorlab.robot.emulator.Plant` (kS [V], kV [V·s/tick],
kA [V·s²/tick]): kA·dv/dt = V − kS·sgn(v) − kV·v in encoder ticks, held by stiction while |V| ≤ kS at
rest, the motor model of the seed (L neglected) that the ramp OpMode's telemetry is fitted to. The
gains are read from the ``@Config`` tree when START arrives (the real OpMode reads them each loop; a
value written during a run acts from the next run here).
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from typing import Any, Protocol

from motorlab.robot.config import leaves


class Plant(Protocol):
    """The emulated drive motor (:class:`motorlab.robot.emulator.Plant`, not imported: the emulator runs this
    module): its gains per tick and the OpMode's loop period."""

    kS: float
    kV: float
    kA: float
    period: float


class EmulatedRobot(Protocol):
    """What this drive reads of the emulated robot (:class:`motorlab.robot.emulator.EmulatedRobot`)."""

    config: dict[str, Any]
    battery: float
    lifetime: float

    @property
    def plant(self) -> Plant: ...

#: The OpMode's name as the quickstart registers it (``metaForClass``: the class's simple name).
NAME = "ManualFeedforwardTuner"
#: ``ManualFeedforwardTuner.DISTANCE`` [in] (Tuning.kt).
DISTANCE = 64.0
#: Forward encoders of a mecanum drive (leftFront, leftBack, rightBack, rightFront): telemetry v0…v3.
ENCODERS = 4
#: The longest run [s]: the real OpMode runs until STOP; this one ends by itself after it.
LONGEST = 600.0


def _legs(distance: float, max_vel: float, min_accel: float, max_accel: float) -> tuple[float, float, float, float]:
    """Acceleration up, deceleration (> 0), the peak velocity, and the cruise's duration of one leg."""
    up, down = max_accel, -min_accel
    peak = min(max_vel, math.sqrt(2 * distance * up * down / (up + down)))
    return up, down, peak, (distance - peak**2 / (2 * up) - peak**2 / (2 * down)) / peak


def trapezoid(t: float, distance: float, max_vel: float, min_accel: float, max_accel: float) -> tuple[float, float]:
    """Velocity and acceleration at ``t`` of a rest-to-rest profile over ``distance`` (0 outside it).

    As ``constantProfile``: accelerate at ``max_accel``, cruise at ``max_vel``, decelerate at ``min_accel``
    (< 0); a triangle when the distance is too short to reach ``max_vel``.
    """
    up, down, peak, cruise = _legs(distance, max_vel, min_accel, max_accel)
    if t < 0 or t > duration(distance, max_vel, min_accel, max_accel):
        return 0.0, 0.0
    if t < peak / up:
        return up * t, up
    if t < peak / up + cruise:
        return peak, 0.0
    return peak - down * (t - peak / up - cruise), -down


def duration(distance: float, max_vel: float, min_accel: float, max_accel: float) -> float:
    """How long one leg of :func:`trapezoid` lasts [s]."""
    up, down, peak, cruise = _legs(distance, max_vel, min_accel, max_accel)
    return peak / up + cruise + peak / down


def _motor_step(v: float, volts: float, plant: Plant, dt: float) -> float:
    """Velocity [ticks/s] after ``dt`` at ``volts`` from ``v``: kA·dv/dt = V − kS·sgn(v) − kV·v solved exactly.

    At rest the motor stays put while |V| ≤ kS (stiction); friction stops it, never reverses it: a solution
    that would cross zero within the step ends at rest.
    """
    if v == 0.0 and abs(volts) <= plant.kS:
        return 0.0
    direction = math.copysign(1.0, v if v != 0.0 else volts)
    final = (volts - plant.kS * direction) / plant.kV  # where the velocity heads, with this sign of friction
    new = final + (v - final) * math.exp(-plant.kV / plant.kA * dt)
    return 0.0 if new * direction < 0 else new


class Rows:
    """The OpMode's telemetry rows, computed as the emulator reaches them (a list that fills itself in order).

    The emulator sends what is due every 100 ms; computing a minute of loops at START instead would hold
    the interpreter long enough for the emulator to miss the client's heartbeats on a busy machine.
    """

    def __init__(self, rows: Iterator[tuple[float, dict[str, str]]], count: int) -> None:
        self._rows, self._count, self._done = rows, count, list[tuple[float, dict[str, str]]]()

    def __len__(self) -> int:
        return self._count

    def __getitem__(self, k: int) -> tuple[float, dict[str, str]]:
        if not 0 <= k < self._count:
            raise IndexError(k)
        while len(self._done) <= k:
            self._done.append(next(self._rows))
        return self._done[k]


def run(plant: Plant, params: dict[str, float], *, battery: float, seconds: float) -> Rows:
    """(t [s], telemetry data) every loop of ``ManualFeedforwardTuner`` with ``params`` (``MecanumDrive.PARAMS``'s
    leaves by name: kS, kV, kA, inPerTick, maxWheelVel, minProfileAccel, maxProfileAccel) on ``plant``."""
    per_tick = params["inPerTick"] or 1.0
    shape = (DISTANCE, params["maxWheelVel"], params["minProfileAccel"], params["maxProfileAccel"])
    leg = duration(*shape)
    count = int(seconds / plant.period) + 1

    def rows() -> Iterator[tuple[float, dict[str, str]]]:
        v = 0.0  # the drive's true velocity [ticks/s]
        for k in range(count):
            t = k * plant.period
            forwards = int(t // leg) % 2 == 0
            ref, acc = trapezoid(t % leg, *shape)
            ref, acc = (ref, acc) if forwards else (-ref, -acc)
            volts = (params["kS"] * (math.copysign(1.0, ref) if ref else 0.0)
                     + params["kV"] / per_tick * ref + params["kA"] / per_tick * acc)
            power = max(-1.0, min(1.0, volts / battery))  # setDrivePowers divides by max(1, |power|)
            measured = repr(per_tick * round(v))  # the encoder's velocity: whole ticks per second
            yield t, {"mode": "TUNING_MODE", **{f"v{i}": measured for i in range(ENCODERS)}, "vref": repr(ref)}
            v = _motor_step(v, power * battery, plant, plant.period)

    return Rows(rows(), count)


def packets(robot: EmulatedRobot, opmode: str) -> Rows | None:
    """The telemetry of ``opmode`` when it is this drive's OpMode (None for another: the emulator's ramp)."""
    if opmode != NAME:
        return None
    flat = {path.rsplit(".", 1)[-1]: value for path, (_, value) in leaves(robot.config).items()
            if path.startswith(("MecanumDrive.PARAMS.", "TankDrive.PARAMS."))}
    params: dict[str, Any] = {k: float(flat.get(k) or 0.0) for k in
                              ("kS", "kV", "kA", "inPerTick", "maxWheelVel", "minProfileAccel", "maxProfileAccel")}
    return run(robot.plant, params, battery=robot.battery, seconds=min(robot.lifetime, LONGEST))
