"""Closed-loop simulation of a designed controller on the identified (nonlinear) motor model.

The controller runs every ``period`` seconds, as on a robot: it reads a (delayed, quantised)
encoder, computes feedforward + PID (WPILib ``PIDController`` semantics), clamps the output to the
supply voltage and holds it until the next period. The plant between two controller runs is either

* the motor model (:class:`~motorlab.model.MotorParams`, with L, Coulomb friction and stiction),
  propagated exactly by :func:`motorlab.model.simulate.simulate`; or
* the feedforward-equivalent plant kA·dv/dt = V − kS·sgn(v) − kV·v with stiction (at rest the shaft
  stays at rest while |V| ≤ kS), propagated exactly here. This is the motor model with L = 0
  (kS = R·Tf/K, kV = K + R·b/K, kA = R·J/K), used when only kS, kV, kA are known.

Response figures (rise time, overshoot, settling time, steady-state error) are measured on the
simulated output, never computed from the linear model.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from motorlab.control.loop import Feedforward, Gains
from motorlab.errors import OptionError
from motorlab.model import MotorParams, feedforward_from_params
from motorlab.units import format_percent

#: Settling band: fraction of the step size (plus one encoder count when the encoder is quantised).
SETTLING_BAND = 0.02

#: Most controller periods one closed-loop run simulates (20 s at 10 µs; a few seconds of computing).
MAX_PERIODS = 2_000_000

Reference = Callable[[float], tuple[float, float, float]]

#: Control laws :func:`simulate_closed_loop` runs: WPILib's PIDController with SimpleMotorFeedforward, and
#: Road Runner 1.0's HolonomicController with MotorFeedforward.
LAWS = ("pid", "roadrunner")


# ---- plants ------------------------------------------------------------------------------------
def _ff_advance(
    x: float, v: float, volts: float, dt: float, kS: float, kV: float, kA: float
) -> tuple[float, float]:
    """Exact motion of kA·dv/dt = V − kS·sgn(v) − kV·v over ``dt`` with V held, stiction included."""
    remaining = dt
    tau = kA / kV
    for _ in range(4):  # at most a stop and a restart inside one step
        if remaining <= 0:
            break
        if v == 0.0:
            if abs(volts) <= kS:
                return x, 0.0
            s = math.copysign(1.0, volts)
        else:
            s = math.copysign(1.0, v)
        v_inf = (volts - kS * s) / kV
        if v_inf * s < 0 or v_inf == 0.0:
            # Heading for zero speed: v(t) = v_inf + (v − v_inf)·e^(−t/τ) reaches 0 at t0.
            t0 = tau * math.log((v - v_inf) / (-v_inf)) if v_inf != 0.0 else math.inf
            if t0 < remaining:
                x += v_inf * t0 + (v - v_inf) * tau * (1 - math.exp(-t0 / tau))
                v = 0.0
                remaining -= t0
                continue
        e = math.exp(-remaining / tau)
        x += v_inf * remaining + (v - v_inf) * tau * (1 - e)
        v = v_inf + (v - v_inf) * e
        remaining = 0.0
    return x, v


class _FeedforwardPlant:
    def __init__(self, ff: Feedforward):
        self.ff = ff
        self._decay: tuple[float, float] = (math.nan, math.nan)

    def run(self, state: tuple[float, float, float], volts: float, period: float,
            substeps: int) -> list[tuple[float, float, float]]:
        """States (position, speed, current=nan) at the ``substeps`` points after ``state``.

        A substep that moves on without stopping is :func:`_ff_advance`'s last branch written out, with its
        e^(−h/τ) computed once per run (the same numbers); a stop, a start or a standstill goes through it.
        """
        x, v, _ = state
        kS, kV, kA = self.ff.kS, self.ff.kV, self.ff.kA
        h = period / substeps
        tau = kA / kV
        if self._decay[0] != h:
            self._decay = (h, math.exp(-h / tau))
        e = self._decay[1]
        out = []
        for _ in range(substeps):
            if v != 0.0:
                s = 1.0 if v > 0 else -1.0
                v_inf = (volts - kS * s) / kV
                if not (v_inf * s < 0 or v_inf == 0.0):
                    x += v_inf * h + (v - v_inf) * tau * (1 - e)
                    v = v_inf + (v - v_inf) * e
                    out.append((x, v, math.nan))
                    continue
            x, v = _ff_advance(x, v, volts, h, kS, kV, kA)
            out.append((x, v, math.nan))
        return out


class _MotorPlant:
    def __init__(self, params: MotorParams):
        self.params = params

    def run(self, state: tuple[float, float, float], volts: float, period: float,
            substeps: int) -> list[tuple[float, float, float]]:
        from motorlab.model.simulate import State, VoltageDrive, simulate

        x, v, i = state
        sim = simulate(
            self.params, VoltageDrive(volts), duration=period, dt=period / substeps, initial=State(i, v, x)
        )
        return list(zip(sim.position[1:].tolist(), sim.speed[1:].tolist(), sim.current[1:].tolist(), strict=True))


def _plant_for(plant: MotorParams | Feedforward) -> _FeedforwardPlant | _MotorPlant:
    if isinstance(plant, MotorParams):
        if plant.L > 0:
            return _MotorPlant(plant)
        ff = feedforward_from_params(plant)
        return _FeedforwardPlant(Feedforward(ff["kS"], ff["kV"], ff["kA"]))
    return _FeedforwardPlant(plant.check_plant())


# ---- references --------------------------------------------------------------------------------
def step_reference(loop: str, size: float) -> Reference:
    """A step of ``size`` [rad or rad/s] at t = 0: returns ``r(t) -> (position, velocity, acceleration)``.

    A velocity step's position is the distance the reference covers, size·t (what a path follower such
    as Road Runner's compares the measured position with).
    """
    if loop == "velocity":
        return lambda t: (size * max(t, 0.0), size, 0.0)
    return lambda t: (size, 0.0, 0.0)


def trapezoid(distance: float, max_velocity: float, max_acceleration: float) -> tuple[Reference, float]:
    """A trapezoidal (or triangular) motion profile from rest to rest.

    Parameters
    ----------
    distance
        Signed travel [rad].
    max_velocity
        Cruise speed limit [rad/s].
    max_acceleration
        Acceleration limit [rad/s²].

    Returns
    -------
    tuple
        (r(t) -> (position, velocity, acceleration), duration [s]).
    """
    if max_velocity <= 0 or max_acceleration <= 0:
        raise OptionError("profile limits must be positive")
    d = abs(distance)
    sign = math.copysign(1.0, distance)
    t_acc = max_velocity / max_acceleration
    if max_acceleration * t_acc**2 > d:  # triangular: never reaches cruise speed
        t_acc = math.sqrt(d / max_acceleration)
    v_peak = max_acceleration * t_acc
    t_cruise = (d - max_acceleration * t_acc**2) / v_peak if v_peak > 0 else 0.0
    total = 2 * t_acc + t_cruise

    def ref(t: float) -> tuple[float, float, float]:
        if t <= 0:
            return 0.0, 0.0, 0.0
        if t < t_acc:
            return sign * 0.5 * max_acceleration * t * t, sign * max_acceleration * t, sign * max_acceleration
        x1 = 0.5 * max_acceleration * t_acc**2
        if t < t_acc + t_cruise:
            return sign * (x1 + v_peak * (t - t_acc)), sign * v_peak, 0.0
        if t < total:
            td = total - t
            return sign * (d - 0.5 * max_acceleration * td * td), sign * max_acceleration * td, -sign * max_acceleration
        return sign * d, 0.0, 0.0

    return ref, total


def velocity_ramp(size: float, max_acceleration: float) -> tuple[Reference, float]:
    """A velocity reference ramping to ``size`` [rad/s] at ``max_acceleration`` [rad/s²]."""
    t_ramp = abs(size) / max_acceleration
    sign = math.copysign(1.0, size)

    def ref(t: float) -> tuple[float, float, float]:
        if t <= 0:
            return 0.0, 0.0, 0.0
        if t < t_ramp:
            return sign * 0.5 * max_acceleration * t * t, sign * max_acceleration * t, sign * max_acceleration
        return sign * 0.5 * max_acceleration * t_ramp * t_ramp + size * (t - t_ramp), size, 0.0

    return ref, t_ramp


# ---- profile limits ----------------------------------------------------------------------------
@dataclass(frozen=True)
class ProfileLimits:
    """How fast a motion profile the motor can follow at a supply voltage.

    Attributes
    ----------
    free_speed
        (V − kS)/kV: the speed the motor tends to at full voltage [rad/s].
    stall_acceleration
        (V − kS)/kA: the acceleration from rest at full voltage [rad/s²].
    max_velocity, max_acceleration
        A trapezoid the feedforward alone can drive with ``headroom`` of the voltage left for
        feedback [rad/s], [rad/s²].
    voltage, headroom, velocity_fraction
        The settings used.
    """

    free_speed: float
    stall_acceleration: float
    max_velocity: float
    max_acceleration: float
    voltage: float
    headroom: float
    velocity_fraction: float

    def to_dict(self, per_radian: float = 1.0) -> dict[str, float]:
        """The figures in a length unit of which there are ``per_radian`` per radian."""
        return {
            "free_speed": self.free_speed * per_radian,
            "stall_acceleration": self.stall_acceleration * per_radian,
            "max_velocity": self.max_velocity * per_radian,
            "max_acceleration": self.max_acceleration * per_radian,
            "voltage": self.voltage,
            "headroom": self.headroom,
        }


def max_profile(
    plant: MotorParams | Feedforward,
    voltage: float = 12.0,
    *,
    headroom: float = 0.1,
    velocity_fraction: float = 0.8,
) -> ProfileLimits:
    """The fastest trapezoidal profile the motor can follow at ``voltage``.

    Parameters
    ----------
    plant
        Motor parameters or feedforward constants [SI].
    voltage
        Supply (battery) voltage [V].
    headroom
        Fraction of the voltage kept for feedback at every point of the profile [-].
    velocity_fraction
        Cruise speed as a fraction of the free speed at the remaining voltage [-].

    Returns
    -------
    ProfileLimits

    Notes
    -----
    With V_ff = (1 − headroom)·V left for feedforward, the profile is followable when
    kS + kV·v + kA·a ≤ V_ff everywhere; it is tightest at the end of the acceleration phase. Taking
    v_max = f·(V_ff − kS)/kV leaves a_max = (V_ff − kS − kV·v_max)/kA = (1 − f)·(V_ff − kS)/kA
    (WPILib's ``SimpleMotorFeedforward.maxAchievableAcceleration``).
    """
    ff = _feedforward_of(plant)
    if not (voltage > 0 and 0 <= headroom < 1 and 0 < velocity_fraction < 1):
        raise OptionError("need voltage > 0, 0 ≤ headroom < 1 and 0 < velocity fraction < 1")
    v_ff = (1 - headroom) * voltage
    if v_ff <= ff.kS:
        raise OptionError(f"{voltage:g} V cannot overcome kS = {ff.kS:.3g} V with {headroom:.0%} headroom")
    v_max = velocity_fraction * (v_ff - ff.kS) / ff.kV
    a_max = (v_ff - ff.kS - ff.kV * v_max) / ff.kA
    return ProfileLimits(
        free_speed=ff.free_speed(voltage),
        stall_acceleration=(voltage - ff.kS) / ff.kA,
        max_velocity=v_max,
        max_acceleration=a_max,
        voltage=voltage,
        headroom=headroom,
        velocity_fraction=velocity_fraction,
    )


def _feedforward_of(plant: MotorParams | Feedforward) -> Feedforward:
    if isinstance(plant, MotorParams):
        ff = feedforward_from_params(plant)
        return Feedforward(ff["kS"], ff["kV"], ff["kA"])
    return plant.check_plant()


# ---- the closed loop ---------------------------------------------------------------------------
@dataclass
class ClosedLoopResponse:
    """A simulated closed-loop run (SI units: rad, rad/s, V, s).

    Attributes
    ----------
    loop
        ``"velocity"`` or ``"position"``.
    kind
        ``"step"`` or ``"profile"``.
    time
        Dense time grid (``substeps`` points per controller period) [s].
    position, speed
        Plant state [rad], [rad/s].
    voltage
        Applied (clamped, held) voltage [V].
    reference
        Reference of the controlled quantity (speed or position) [rad/s or rad].
    output
        The controlled quantity (``speed`` or ``position``).
    target
        Final value of the reference [rad/s or rad].
    metrics
        ``rise_time`` [s], ``overshoot`` [%], ``settling_time`` [s], ``steady_state_error``
        [rad/s or rad], ``max_tracking_error`` [rad/s or rad], ``saturated_fraction`` [-],
        ``sustained_oscillation`` (bool). NaN where not reached.
    settings
        Period, delay, voltage, cpr, plant kind.
    """

    loop: str
    kind: str
    time: np.ndarray
    position: np.ndarray
    speed: np.ndarray
    voltage: np.ndarray
    reference: np.ndarray
    target: float
    metrics: dict[str, Any] = field(default_factory=dict)
    settings: dict[str, Any] = field(default_factory=dict)

    @property
    def output(self) -> np.ndarray:
        """The controlled quantity: speed for a velocity loop, position for a position loop."""
        return self.speed if self.loop == "velocity" else self.position

    def response_dict(self, per_radian: float = 1.0) -> dict[str, Any]:
        """The four figures of ``tune --json`` with lengths in the user's unit."""
        m = self.metrics
        return {
            "rise_time": _finite_or_none(m["rise_time"]),
            "overshoot": _finite_or_none(m["overshoot"]),
            "settling_time": _finite_or_none(m["settling_time"]),
            "steady_state_error": _finite_or_none(m["steady_state_error"] * per_radian),
        }


def _finite_or_none(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


def simulate_closed_loop(
    gains: Gains,
    feedforward: Feedforward,
    plant: MotorParams | Feedforward,
    reference: Reference,
    *,
    duration: float,
    voltage: float = 12.0,
    cpr: float | None = None,
    period: float | None = None,
    delay: float | None = None,
    substeps: int = 10,
    kind: str = "step",
    target: float | None = None,
    law: str = "pid",
) -> ClosedLoopResponse:
    """Run feedforward + PID at a fixed period on the nonlinear motor model.

    Parameters
    ----------
    gains
        PID gains in volts per SI unit (:class:`Gains`; ``gains.loop`` selects the loop).
    feedforward
        The controller's feedforward: V_ff = kS·sgn(v_ref) + kV·v_ref + kA·a_ref [V].
    plant
        The motor simulated: :class:`MotorParams` (exact simulation with L, friction and stiction)
        or :class:`Feedforward` (the L = 0 model with Coulomb-like kS and stiction).
    reference
        ``r(t) -> (position [rad], velocity [rad/s], acceleration [rad/s²])``.
    duration, substeps
        Length of the run [s]; plant samples per controller period (for plots and metrics).
    voltage
        Supply voltage: the output is clamped to ±voltage [V]; ``inf`` for no saturation.
    cpr
        Encoder counts per revolution of this shaft; None for an ideal (unquantised) encoder.
    period, delay
        Controller period and measurement delay [s] (default: ``gains.period``, ``gains.delay``).
    kind
        ``"step"`` or ``"profile"`` (which figures are meaningful).
    target
        Final reference value (default: the reference at ``duration``).
    law
        ``"pid"`` (WPILib's ``PIDController`` plus ``SimpleMotorFeedforward``) or ``"roadrunner"``
        (Road Runner 1.0's ``HolonomicController`` feeding its ``MotorFeedforward``; see Notes).

    Returns
    -------
    ClosedLoopResponse

    Notes
    -----
    Controller at t_k = k·T: position measured at t_k − delay, rounded down to whole encoder counts;
    velocity measured as the count difference over the last period divided by T (what an OpMode
    computing velocity from ``getCurrentPosition`` sees; exact speed when ``cpr`` is None).
    e_k = r_k − y_k; integral += e_k·T (frozen while the output saturates in the direction of e,
    a simple anti-windup); derivative = (e_k − e_{k−1})/T (0 on the first run, no derivative kick);
    u_k = clamp(V_ff + kP·e + kI·∫e + kD·ė, ±voltage).

    Road Runner's law (``law="roadrunner"``, road-runner ``Control.kt`` and the quickstart's
    ``MecanumDrive.FollowTrajectoryAction``): the controller turns the errors of position and of velocity
    into a velocity command v_c = v_r + g_x·(x_r − x) + g_v·(v_r − v) and the feedforward turns the command
    into volts, V = kS·sign(v_c) + kV·v_c + kA·a_r (``MotorFeedforward.compute``: ``kS.withSign(vel)``, so
    +kS when v_c is exactly 0). With kV·g_x and kV·g_v the position loop's kP and kD (a velocity loop's kI
    and kP: the integral of the velocity error is the position error) this is
    V = kS·sign(kV·v_r + fb) + kV·v_r + kA·a_r + fb, fb = kV·g_x·(x_r − x) + kV·g_v·(v_r − v): the static
    friction feedforward follows the correction, not only the reference, so friction cannot hold the
    robot short of its target. x_r − x uses the measured position, v the measured velocity.
    """
    if law not in LAWS:
        raise OptionError(f"unknown control law {law!r} (expected {' or '.join(LAWS)})")
    period = gains.period if period is None else period
    delay = gains.delay if delay is None else delay
    n_periods = _periods_to_run(duration, period=period, delay=delay, substeps=substeps, cpr=cpr)
    sim = _plant_for(plant)
    time, states, volts = _run_controller(
        gains, feedforward, sim, reference, n_periods=n_periods, period=period, delay=delay, substeps=substeps,
        voltage=voltage, cpr=cpr, law=law,
    )
    refs = np.array([reference(t) for t in time])
    ref_col = refs[:, 1] if gains.loop == "velocity" else refs[:, 0]
    resp = ClosedLoopResponse(
        loop=gains.loop,
        kind=kind,
        time=time,
        position=states[:, 0],
        speed=states[:, 1],
        voltage=volts,
        reference=ref_col,
        target=float(ref_col[-1] if target is None else target),
        settings={
            "period": period,
            "delay": delay,
            "voltage": voltage,
            "cpr": cpr,
            "plant": "motor" if isinstance(sim, _MotorPlant) else "feedforward",
            "law": law,
        },
    )
    resp.metrics = response_metrics(resp, resolution=0.0 if cpr is None else 2 * math.pi / cpr)
    return resp


def _periods_to_run(duration: float, *, period: float, delay: float, substeps: int, cpr: float | None) -> int:
    """Check the run's settings of :func:`simulate_closed_loop`; return how many controller periods it takes."""
    if not (period > 0 and delay >= 0 and duration > 0 and substeps >= 1):
        raise OptionError("need period > 0, delay ≥ 0, duration > 0 and substeps ≥ 1")
    if cpr is not None and not cpr > 0:
        raise OptionError(f"encoder counts per revolution must be positive, got {cpr}")
    n_periods = max(math.ceil(duration / period - 1e-9), 1)
    if n_periods > MAX_PERIODS:
        # Each period is a step of the controller loop: a nanosecond period over seconds would take
        # hours and gigabytes before failing, so refuse it up front.
        raise OptionError(
            f"too long to simulate: a {duration:.3g} s run at a controller period of {period:.3g} s is "
            f"{n_periods:.3g} periods (at most {MAX_PERIODS:.0e})"
        )
    return n_periods


def _run_controller(
    gains: Gains,
    feedforward: Feedforward,
    sim: _FeedforwardPlant | _MotorPlant,
    reference: Reference,
    *,
    n_periods: int,
    period: float,
    delay: float,
    substeps: int,
    voltage: float,
    cpr: float | None,
    law: str = "pid",
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The controller loop of :func:`simulate_closed_loop` (see its Notes), from rest.

    Returns
    -------
    tuple
        (time [s], states (position [rad], speed [rad/s], current [A]) [n, 3], voltage [V]) on the
        dense grid of ``substeps`` points per period.
    """
    n = n_periods * substeps
    h = period / substeps
    time = np.arange(n + 1) * h
    # the dense grid in Python lists (the loop reads and writes one point at a time; numpy's scalars cost more)
    states: list[tuple[float, float, float]] = [(0.0, 0.0, 0.0)]
    volts: list[float] = []
    counts_per_rad = None if cpr is None else cpr / (2 * math.pi)

    def measured(t: float) -> tuple[float, float]:
        """(position, speed) seen by the controller for the instant t (already delayed)."""
        if t <= 0:
            x, v = states[0][0], states[0][1]
        else:
            # Linear interpolation on the dense grid; t never lies beyond the last filled point.
            filled = len(states) - 1
            u = min(t / h, float(filled))
            j = min(int(u), max(filled - 1, 0))
            w = u - j
            (x0, v0, _), (x1, v1, _) = states[j], states[j + 1]
            x = (1 - w) * x0 + w * x1
            v = (1 - w) * v0 + w * v1
        if counts_per_rad is not None:
            x = math.floor(x * counts_per_rad + 1e-9) / counts_per_rad
        return x, v

    loop = gains.loop
    integral = 0.0
    prev_error: float | None = None
    prev_pos = measured(-delay)[0]
    k_s, k_v, k_a = feedforward.kS, feedforward.kV, feedforward.kA
    for k in range(n_periods):
        t_k = k * period
        pos_m, vel_m = measured(t_k - delay)
        if counts_per_rad is not None:
            vel_m = (pos_m - prev_pos) / period if k > 0 else 0.0
        prev_pos = pos_m
        r_pos, r_vel, r_acc = reference(t_k)
        if law == "roadrunner":
            u = min(max(_roadrunner_volts(gains, feedforward, (r_pos, r_vel, r_acc), pos_m, vel_m), -voltage),
                    voltage)
        else:
            error = (r_vel - vel_m) if loop == "velocity" else (r_pos - pos_m)
            derivative = 0.0 if prev_error is None else (error - prev_error) / period
            prev_error = error
            sign = (r_vel > 0) - (r_vel < 0) if r_vel == r_vel else math.nan  # np.sign's, NaN kept
            ff = k_s * sign + k_v * r_vel + k_a * r_acc
            unclamped = ff + gains.kP * error + gains.kI * (integral + error * period) + gains.kD * derivative
            u = min(max(unclamped, -voltage), voltage)
            if u == unclamped or (unclamped > voltage) != (error > 0):
                integral += error * period
        states += sim.run(states[-1], u, period, substeps)
        volts += [u] * substeps
    volts.append(volts[-1] if n > 0 else 0.0)
    return time, np.array(states, dtype=float).reshape(n + 1, 3), np.array(volts, dtype=float)


def _roadrunner_volts(gains: Gains, ff: Feedforward, ref: tuple[float, float, float], position: float,
                      velocity: float) -> float:
    """Road Runner's command in volts (:func:`simulate_closed_loop`'s Notes): HolonomicController, then
    MotorFeedforward with kS·sign of the velocity command."""
    r_pos, r_vel, r_acc = ref
    # Position and velocity gains in volts: a position loop's (kP, kD), a velocity loop's (kI, kP).
    k_x, k_v = (gains.kP, gains.kD) if gains.loop == "position" else (gains.kI, gains.kP)
    feedback = k_x * (r_pos - position) + k_v * (r_vel - velocity)
    command = ff.kV * r_vel + feedback  # kV·v_c
    return math.copysign(ff.kS, command) + command + ff.kA * r_acc


def response_metrics(resp: ClosedLoopResponse, *, resolution: float = 0.0) -> dict[str, Any]:
    """Rise time, overshoot, settling time, steady-state error of a simulated response.

    Parameters
    ----------
    resp
        The response.
    resolution
        Encoder resolution [rad]; widens the settling band of a position loop by one count.

    Returns
    -------
    dict
        ``rise_time`` (10 → 90 % of the target) [s], ``overshoot`` [%] of the target,
        ``settling_time`` (last exit from the ±2 % band) [s], ``steady_state_error`` (target minus the
        mean output over the last 10 % of the run), ``max_tracking_error`` (largest |r − y|),
        ``saturated_fraction`` (fraction of time at the voltage limit), ``sustained_oscillation``
        (peak-to-peak over the last 30 % wider than twice the band).
    """
    y = resp.output
    t = resp.time
    s = resp.target
    out: dict[str, Any] = {}
    if s == 0 or not np.isfinite(s):
        raise OptionError("the reference must end at a non-zero value to measure a response")
    yn = y / s
    out["rise_time"] = _crossing(t, yn, 0.9) - _crossing(t, yn, 0.1)
    out["overshoot"] = max(float(np.max(yn)) - 1.0, 0.0) * 100.0
    band = SETTLING_BAND * abs(s) + (resolution if resp.loop == "position" else 0.0)
    if resp.loop == "velocity" and resolution > 0:
        band += resolution / resp.settings["period"]
    outside = np.nonzero(np.abs(y - s) > band)[0]
    if outside.size == 0:
        out["settling_time"] = 0.0
    elif outside[-1] >= len(y) - 1:
        out["settling_time"] = math.nan
    else:
        out["settling_time"] = float(t[outside[-1] + 1])
    tail = t >= 0.9 * t[-1]
    out["steady_state_error"] = float(s - np.mean(y[tail]))
    out["max_tracking_error"] = float(np.max(np.abs(resp.reference - y)))
    v_lim = resp.settings.get("voltage", math.inf)
    out["saturated_fraction"] = float(np.mean(np.abs(resp.voltage) >= v_lim * (1 - 1e-12)))
    out["sustained_oscillation"] = _oscillates(y[t >= 0.7 * t[-1]], band)
    return out


def _oscillates(y: np.ndarray, band: float) -> bool:
    """True when the tail swings back and forth: at least two reversals wider than the settling band.

    A slow, monotone creep towards the target (a P-only loop against Coulomb friction) is not an
    oscillation, however wide its range.
    """
    if y.size < 3 or np.ptp(y) <= 2 * band:
        return False
    # Extrema that differ from the last kept one by more than 2·band (hysteresis against quantisation).
    turns = 0
    direction = 0
    anchor = float(y[0])
    for value in y[1:]:
        step = float(value) - anchor
        if direction >= 0 and step < -2 * band:
            turns += direction > 0
            direction, anchor = -1, float(value)
        elif direction <= 0 and step > 2 * band:
            turns += direction < 0
            direction, anchor = 1, float(value)
        elif (direction > 0 and value > anchor) or (direction < 0 and value < anchor):
            anchor = float(value)
    return turns >= 2


def _crossing(t: np.ndarray, y: np.ndarray, level: float) -> float:
    """First time ``y`` reaches ``level`` (linear interpolation), NaN if never."""
    idx = np.nonzero(y >= level)[0]
    if idx.size == 0:
        return math.nan
    i = int(idx[0])
    if i == 0:
        return float(t[0])
    y0, y1 = y[i - 1], y[i]
    return float(t[i - 1] + (level - y0) / (y1 - y0) * (t[i] - t[i - 1]))


def linear_step_metrics(gains: Gains, plant: Feedforward, *, horizon: float) -> tuple[float, float]:
    """(rise time [s], overshoot [%]) of a unit step on the sampled, delayed *linear* loop.

    No saturation, no friction (kS = 0), ideal encoder; used to refine pole-placement designs.
    """
    linear = Feedforward(0.0, plant.kV, plant.kA)
    resp = simulate_closed_loop(
        gains, linear, linear, step_reference(gains.loop, 1.0), duration=horizon, voltage=math.inf, substeps=4
    )
    tr = resp.metrics["rise_time"]
    return (tr if math.isfinite(tr) else 10 * horizon), resp.metrics["overshoot"]


# ---- plots -------------------------------------------------------------------------------------
def plot_response(
    resp: ClosedLoopResponse,
    *,
    ax: Any = None,
    per_radian: float = 1.0,
    unit: str = "rad",
    voltage_axis: bool = True,
) -> Any:
    """Draw a closed-loop response: reference and output, and the applied voltage on a twin axis.

    Parameters
    ----------
    resp
        The response to draw.
    ax
        Matplotlib axes (a new figure if None).
    per_radian
        Display length units per radian (1 for rad, 1/2π for rotations, cpr/2π for ticks) [-].
    unit
        Name of the display length unit.
    voltage_axis
        Also draw the voltage on a right-hand axis.

    Returns
    -------
    matplotlib.axes.Axes
    """
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(figsize=(7, 4))
    qty = f"{unit}/s" if resp.loop == "velocity" else unit
    ax.plot(resp.time, resp.reference * per_radian, "--", color="0.4", label="reference")
    ax.plot(resp.time, resp.output * per_radian, color="C0", label=resp.loop)
    ax.set_xlabel("time [s]")
    ax.set_ylabel(f"{resp.loop} [{qty}]")
    m = resp.metrics
    title = f"{resp.loop} {resp.kind}"
    if resp.kind == "step" and math.isfinite(m.get("rise_time", math.nan)):
        title += f": rise {m['rise_time'] * 1e3:.0f} ms, overshoot {format_percent(m['overshoot'] / 100, '.1f')}"
    ax.set_title(title, fontsize=10, y=1.0)  # placed, not measured (motorlab.plot.plot_panel)
    if voltage_axis:
        ax2 = ax.twinx()
        ax2.step(resp.time, resp.voltage, where="post", color="C3", alpha=0.5, lw=0.8, label="voltage")
        ax2.set_ylabel("voltage [V]", color="C3")
    ax.legend(loc="lower right", fontsize=8)
    return ax
