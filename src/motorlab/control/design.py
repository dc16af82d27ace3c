"""Feedback gains from the feedforward model: LQR as WPILib SysId computes it, and pole placement.

The plant is the feedforward model of a DC motor (L neglected, Coulomb friction cancelled by kS)::

    kA·dv/dt = V − kS·sgn(v) − kV·v          velocity loop: state v,        A = −kV/kA, B = 1/kA
    dx/dt = v                                 position loop: state [x, v],  A = [[0, 1], [0, −kV/kA]],
                                                                            B = [0, 1/kA]

Everything here is in one consistent length unit (SI: rad; or rotations, ticks, metres as long as kV,
kA and the tolerances use the same one) and volts. Gains are "time-normalised" (WPILib's
``PIDController`` convention: kI multiplies ∫e dt [V/(unit·s)], kD multiplies de/dt [V·s/unit]).

References
----------
WPILib SysId, ``sysid/src/main/native/cpp/analysis/FeedbackAnalysis.cpp`` (velocity and position
gains), ``FeedbackControllerPreset.h`` (presets) and wpimath's ``LinearQuadraticRegulator`` (ZOH
discretisation, Bryson cost matrices, ``LatencyCompensate``), allwpilib on GitHub. Seed 1, "What is
PID?", for what the gains are used for.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
import scipy.linalg

from motorlab.control.loop import KA_NEGLIGIBLE, LOOPS, Feedforward, Gains
from motorlab.errors import OptionError


@dataclass(frozen=True)
class SysIdPreset:
    """A SysId ``FeedbackControllerPreset``: how a controller wants its gains.

    Parameters
    ----------
    output_conversion
        Controller output units per volt (``outputConversionFactor``) [1/V].
    velocity_time_factor
        Divides velocity gains when the controller measures velocity per another time unit
        (``outputVelocityTimeFactor``: 0.1 for CTRE's per-100 ms, 60 for REV's per-minute) [-].
    period
        Controller period [s].
    normalized
        False when the controller's kD is per loop period rather than per second.
    delay
        Measurement delay (filtering, finite differences) [s].
    """

    output_conversion: float
    velocity_time_factor: float
    period: float
    normalized: bool
    delay: float


#: SysId's presets (FeedbackControllerPreset.h, with its sources for the delays).
SYSID_PRESETS: dict[str, SysIdPreset] = {
    "default": SysIdPreset(1.0, 1.0, 0.020, True, 0.0),
    "ctre-v5": SysIdPreset(1023.0 / 12.0, 0.1, 0.001, False, 0.0815),
    "ctre-v6": SysIdPreset(1.0, 1.0, 0.001, True, 0.001),
    "rev-neo-builtin": SysIdPreset(1.0 / 12.0, 60.0, 0.001, False, 0.112),
    "rev-non-neo": SysIdPreset(1.0 / 12.0, 60.0, 0.001, False, 0.0815),
    "venom": SysIdPreset(4096.0 / 12.0, 60.0, 0.001, False, 0.005),
}


# ---- LQR -----------------------------------------------------------------------------------------
def discretize(a: np.ndarray, b: np.ndarray, period: float) -> tuple[np.ndarray, np.ndarray]:
    """Zero-order-hold discretisation (wpimath ``DiscretizeAB``): exp([[A, B], [0, 0]]·T).

    Parameters
    ----------
    a, b
        Continuous state and input matrices.
    period
        Sample period T [s].

    Returns
    -------
    tuple
        (A_d, B_d).
    """
    n, m = a.shape[0], b.shape[1]
    block = np.zeros((n + m, n + m))
    block[:n, :n] = a
    block[:n, n:] = b
    phi = scipy.linalg.expm(block * period)
    return phi[:n, :n], phi[:n, n:]


def lqr_gain(
    a: np.ndarray,
    b: np.ndarray,
    tolerances: tuple[float, ...],
    effort: float,
    *,
    period: float,
    delay: float = 0.0,
) -> np.ndarray:
    """Discrete LQR gain of a continuous plant, the way wpimath's ``LinearQuadraticRegulator`` does it.

    Parameters
    ----------
    a, b
        Continuous state and input matrices (one input).
    tolerances
        Bryson's rule: the largest acceptable error of each state (Q = diag(1/q²)); ``inf`` for a
        state that is not penalised.
    effort
        Largest acceptable control effort [V] (R = 1/r²).
    period
        Controller period T [s] (ZOH discretisation).
    delay
        Measurement delay [s]; compensated as K·(A_d − B_d·K)^(delay/T) (``LatencyCompensate``).

    Returns
    -------
    numpy.ndarray
        K, shape (1, n): u = K·(r − x).

    Notes
    -----
    K = (B_dᵀ·S·B_d + R)⁻¹·B_dᵀ·S·A_d with S the solution of the discrete algebraic Riccati
    equation (scipy's ``solve_discrete_are``, the same equation WPILib solves with Drake's solver).
    """
    # t·t, not t**2: float ** raises OverflowError for a huge tolerance, where t·t gives inf and weight 0.
    q = np.array([0.0 if math.isinf(t) else 1.0 / (t * t) for t in tolerances])
    r = np.array([[1.0 / (effort * effort)]])
    ad, bd = discretize(a, b, period)
    s = scipy.linalg.solve_discrete_are(ad, bd, np.diag(q), r)
    k = np.linalg.solve(bd.T @ s @ bd + r, bd.T @ s @ ad)
    if delay > 0:
        # A fractional matrix power (Eigen's MatrixPower in wpimath): the closed loop A_d − B_d·K
        # is stable with positive real eigenvalues here, so the principal power is real.
        closed = ad - bd @ k
        k = k @ np.real(scipy.linalg.fractional_matrix_power(closed, delay / period))
    return np.asarray(k, dtype=float)


def _check_design(period: float, delay: float, **tolerances: float) -> None:
    if not (math.isfinite(period) and period > 0):
        raise OptionError(f"controller period must be positive, got {period}")
    if not (math.isfinite(delay) and delay >= 0):
        raise OptionError(f"measurement delay must not be negative, got {delay}")
    for name, value in tolerances.items():
        if not (value > 0):  # also rejects NaN
            raise OptionError(f"{name} must be positive (or inf), got {value}")
        if value * value == 0.0 or not math.isfinite(1.0 / (value * value)):  # the weight 1/tolerance² is inf
            raise OptionError(f"{name} = {value:g} is too small: its LQR weight 1/{name}² is not a finite number")


def design_velocity_lqr(
    kv: float,
    ka: float,
    *,
    qv: float = 1.5,
    r: float = 7.0,
    period: float = 0.02,
    delay: float = 0.0,
) -> Gains:
    """Velocity-loop P gain by LQR on the discretised kV/kA plant (WPILib SysId's convention).

    Parameters
    ----------
    kv
        Velocity constant [V·s/rad] (or per length unit in use).
    ka
        Acceleration constant [V·s²/rad] (same length unit).
    qv
        Velocity error tolerance [rad/s] (same length unit per second).
    r
        Control effort tolerance [V].
    period
        Controller period [s].
    delay
        Measurement delay to compensate [s].

    Returns
    -------
    Gains
        kP [V/(rad/s)], kI = kD = 0.

    Raises
    ------
    OptionError
        If kv ≤ 0, ka ≤ 0, or a tolerance/period is not positive.

    Notes
    -----
    A = −kV/kA, B = 1/kA, Q = 1/qv², R = 1/r², ZOH at ``period``, then latency compensation
    (``CalculateVelocityFeedbackGains`` of SysId). SysId returns 0 for kA < 1e-7; so does this.

    References
    ----------
    allwpilib ``sysid/.../FeedbackAnalysis.cpp``; test figures in ``FeedbackAnalysisTest.cpp``
    (kV = 3.060, kA = 0.327, qv = 1.5, r = 7, T = 20 ms give kP ≈ 2.11).
    """
    Feedforward(0.0, kv, ka).check_plant()
    _check_design(period, delay, qv=qv, r=r)
    settings = {"qv": qv, "r": r}
    if ka < KA_NEGLIGIBLE:
        return Gains("velocity", 0.0, method="lqr", period=period, delay=delay, settings=settings)
    k = lqr_gain(np.array([[-kv / ka]]), np.array([[1.0 / ka]]), (qv,), r, period=period, delay=delay)
    return Gains("velocity", float(k[0, 0]), method="lqr", period=period, delay=delay, settings=settings)


def design_position_lqr(
    kv: float,
    ka: float,
    *,
    qp: float = 1.0,
    qv: float = 1.5,
    r: float = 7.0,
    period: float = 0.02,
    delay: float = 0.0,
) -> Gains:
    """Position-loop PD gains by LQR on the discretised kV/kA plant (WPILib SysId's convention).

    Parameters
    ----------
    kv, ka
        Feedforward constants [V·s/rad], [V·s²/rad] (or per length unit in use).
    qp
        Position error tolerance [rad].
    qv
        Velocity error tolerance [rad/s].
    r
        Control effort tolerance [V].
    period
        Controller period [s].
    delay
        Measurement delay to compensate [s].

    Returns
    -------
    Gains
        kP [V/rad], kD [V·s/rad] (time-normalised), kI = 0.

    Notes
    -----
    States [x, v]: A = [[0, 1], [0, −kV/kA]], B = [0, 1/kA], Q = diag(1/qp², 1/qv²), R = 1/r².
    For kA ≤ 1e-7 SysId uses the first-order plant dx/dt = u (velocity as the input) and returns
    kP = kV·K; so does this.

    References
    ----------
    allwpilib ``sysid/.../FeedbackAnalysis.cpp``; ``FeedbackAnalysisTest.cpp`` (kV = 3.060,
    kA = 0.327: kP ≈ 6.41, kD ≈ 2.48; with a 10 ms delay kP ≈ 5.92, kD ≈ 2.12).
    """
    Feedforward(0.0, kv, ka)  # finite and not negative
    if not kv > 0:
        raise OptionError(f"kV must be positive, got {kv}")
    _check_design(period, delay, qp=qp, qv=qv, r=r)
    settings = {"qp": qp, "qv": qv, "r": r}
    if ka <= KA_NEGLIGIBLE:
        k = lqr_gain(np.array([[0.0]]), np.array([[1.0]]), (qp,), r, period=period, delay=delay)
        return Gains("position", kv * float(k[0, 0]), method="lqr", period=period, delay=delay, settings=settings)
    a = np.array([[0.0, 1.0], [0.0, -kv / ka]])
    b = np.array([[0.0], [1.0 / ka]])
    k = lqr_gain(a, b, (qp, qv), r, period=period, delay=delay)
    return Gains(
        "position", float(k[0, 0]), kD=float(k[0, 1]), method="lqr", period=period, delay=delay, settings=settings
    )


def sysid_gains(
    loop: str,
    kv: float,
    ka: float,
    preset: str | SysIdPreset = "default",
    *,
    qp: float = 1.0,
    qv: float = 1.5,
    r: float = 7.0,
    encoder_factor: float = 1.0,
) -> tuple[float, float]:
    """(kP, kD) exactly as SysId's Feedback pane shows them for a controller preset.

    Parameters
    ----------
    loop
        ``"velocity"`` or ``"position"``.
    kv, ka
        Feedforward constants in the analysis units [V·s/unit], [V·s²/unit].
    preset
        A key of :data:`SYSID_PRESETS` or a :class:`SysIdPreset`.
    qp, qv, r
        Bryson tolerances (position [unit], velocity [unit/s], effort [V]).
    encoder_factor
        Velocity gains are divided by this (SysId's ``encFactor``: encoder counts per unit, gearing).

    Returns
    -------
    tuple
        (kP, kD) in the controller's units.

    Notes
    -----
    Velocity: kP = K·c/(f_t·encFactor) with c = ``output_conversion`` and f_t the velocity time
    factor; position: kP = K₀·c, kD = K₁·c/(1 if normalised else T).
    """
    p = SYSID_PRESETS[preset] if isinstance(preset, str) else preset
    if loop == "velocity":
        g = design_velocity_lqr(kv, ka, qv=qv, r=r, period=p.period, delay=p.delay)
        return g.kP * p.output_conversion / (p.velocity_time_factor * encoder_factor), 0.0
    if loop == "position":
        g = design_position_lqr(kv, ka, qp=qp, qv=qv, r=r, period=p.period, delay=p.delay)
        return g.kP * p.output_conversion, g.kD * p.output_conversion / (1.0 if p.normalized else p.period)
    raise OptionError(f"unknown loop {loop!r} (expected velocity or position)")


# ---- pole placement ----------------------------------------------------------------------------
def damping_from_overshoot(overshoot: float) -> float:
    """ζ of a second-order system whose step overshoots by ``overshoot`` [%].

    Notes
    -----
    Mp = exp(−π·ζ/√(1 − ζ²))  ⇒  ζ = −ln(Mp)/√(π² + ln²(Mp)); 0 % overshoot gives ζ = 1.
    """
    if overshoot <= 0:
        return 1.0
    ln = math.log(overshoot / 100.0)
    return -ln / math.sqrt(math.pi**2 + ln**2)


def _pid_from_shape(loop: str, feedforward: Feedforward, speed: float, shape: float) -> tuple[float, float, float]:
    """(kP, kI, kD) placing the closed-loop poles; ``speed`` [rad/s] and ``shape`` [-] as below."""
    ka, kv = feedforward.kA, feedforward.kV
    if loop == "velocity":
        # Poles at −ωc and −ρ·ωc: kA·(s + ωc)(s + ρωc) = kA·s² + (kV + kP)·s + kI.
        wc, rho = speed, shape
        return max(ka * wc * (1 + rho) - kv, 0.0), ka * rho * wc * wc, 0.0
    # Position: ωn and ζ, kA·s² + (kV + kD)·s + kP = kA·(s² + 2ζωn·s + ωn²).
    wn, zeta = speed, shape
    return wn * wn * ka, 0.0, max(2 * zeta * wn * ka - kv, 0.0)


def design_pid_poles(
    loop: str,
    feedforward: Feedforward,
    *,
    rise_time: float | None = None,
    overshoot: float = 5.0,
    period: float = 0.02,
    delay: float = 0.0,
) -> Gains:
    """PI (velocity) or PD (position) gains from a rise time and an overshoot, by pole placement.

    Parameters
    ----------
    loop
        ``"velocity"`` (PI) or ``"position"`` (PD).
    feedforward
        The plant's feedforward model (kS is cancelled by feedforward and ignored here).
    rise_time
        Requested 10–90 % rise time of a step response [s]. Default: 1.1·τ for velocity (twice as
        fast as the motor with feedforward alone) and 2.2·τ for position, τ = kA/kV.
    overshoot
        Largest acceptable overshoot of the step response [%].
    period
        Controller period [s].
    delay
        Measurement delay [s].

    Returns
    -------
    Gains
        ``method="poles"``; ``settings`` holds the request, the pole parameters and the rise time and
        overshoot achieved on the sampled linear loop.

    Raises
    ------
    OptionError
        For a rise time below two periods, or (velocity) slower than the motor with feedforward alone.

    Notes
    -----
    Closed loops with feedforward and WPILib's ``PIDController`` acting on the error::

        velocity, PI:  kA·s² + (kV + kP)·s + kI = kA·(s + ωc)·(s + ρ·ωc)
        position, PD:  kA·s² + (kV + kD)·s + kP = kA·(s² + 2ζωn·s + ωn²)

    The velocity loop has a fast pole ωc (the rise time) and a slow integral pole ρ·ωc whose
    near-cancelling zero costs overshoot: ρ is the overshoot knob. The position loop's knob is ζ
    (initial guess from Mp = exp(−πζ/√(1 − ζ²))). Because the controller's zero, the sampling
    and the delay all change the response, both numbers are found numerically on the sampled,
    delayed linear loop (:func:`motorlab.control.simulation.linear_step_metrics`): for each shape the
    speed meeting the rise time (Brent's method), then the shape giving the largest overshoot not
    above the request. Friction and saturation are not part of this design; the closed-loop
    simulation on the nonlinear model reports their effect.
    """
    rise_time = _checked_pole_request(loop, feedforward, rise_time, overshoot, period, delay)
    search = _PoleSearch(loop, Feedforward(0.0, feedforward.kV, feedforward.kA), rise_time, period, delay)
    speed, shape = search.best(overshoot)
    result = search.gains(speed, shape)
    tr, os_ = search.metrics(speed, shape)
    names = ("wc", "rho") if loop == "velocity" else ("wn", "zeta")
    settings = {
        "rise_time": rise_time,
        "overshoot": overshoot,
        names[0]: speed,
        names[1]: shape,
        "linear_rise_time": tr,
        "linear_overshoot": os_,
    }
    return replace(result, settings=settings)


def _checked_pole_request(
    loop: str, feedforward: Feedforward, rise_time: float | None, overshoot: float, period: float, delay: float
) -> float:
    """Check :func:`design_pid_poles`'s request; return the rise time [s], its default filled in."""
    if loop not in LOOPS:
        raise OptionError(f"unknown loop {loop!r} (expected velocity or position)")
    feedforward.check_plant()
    _check_design(period, delay)
    tau = feedforward.time_constant
    if rise_time is None:
        rise_time = 1.1 * tau if loop == "velocity" else 2.2 * tau
    if not (rise_time > 0 and math.isfinite(rise_time)):
        raise OptionError(f"rise time must be positive, got {rise_time}")
    if not (0 <= overshoot < 100):
        raise OptionError(f"overshoot must be between 0 and 100 %, got {overshoot}")
    if rise_time < 2 * period:
        raise OptionError(
            f"rise time {rise_time:.4g} s is shorter than two controller periods ({period:.4g} s each)"
        )
    if loop == "velocity" and rise_time >= 2.2 * tau:
        raise OptionError(
            f"with feedforward the motor alone rises in {2.2 * tau:.3g} s (2.2·kA/kV); "
            f"ask for a shorter rise time than {rise_time:.3g} s"
        )
    return rise_time


@dataclass(frozen=True)
class _PoleSearch:
    """The numerical pole placement of :func:`design_pid_poles` on the sampled, delayed linear loop.

    A pole pair is a ``speed`` (ωc or ωn [rad/s]) and a ``shape`` (ρ or ζ [-]), turned into gains by
    :func:`_pid_from_shape`; ``plant`` is the feedforward model with kS = 0.
    """

    loop: str
    plant: Feedforward
    rise_time: float
    period: float
    delay: float

    def gains(self, speed: float, shape: float) -> Gains:
        """The PID gains placing the poles at (``speed``, ``shape``)."""
        kp, ki, kd = _pid_from_shape(self.loop, self.plant, speed, shape)
        return Gains(self.loop, kp, ki, kd, method="poles", period=self.period, delay=self.delay)

    def metrics(self, speed: float, shape: float) -> tuple[float, float]:
        """(rise time [s], overshoot [%]) of those gains on the sampled linear loop."""
        from motorlab.control.simulation import linear_step_metrics

        return linear_step_metrics(self.gains(speed, shape), self.plant, horizon=12 * self.rise_time)

    def speed_for(self, shape: float) -> float:
        """The speed meeting the requested rise time at this shape (Brent's method)."""
        import scipy.optimize

        # Rise time falls as the poles get faster; bracket in log(speed) around 2.2/t_r.
        def f(log_speed: float) -> float:
            return math.log(self.metrics(math.exp(log_speed), shape)[0] / self.rise_time)

        lo, hi = math.log(0.2 / self.rise_time), math.log(20.0 / self.rise_time)
        f_lo, f_hi = f(lo), f(hi)
        if f_lo * f_hi > 0:
            return math.exp(lo if abs(f_lo) < abs(f_hi) else hi)
        return math.exp(scipy.optimize.brentq(f, lo, hi, xtol=1e-4))

    def best(self, overshoot: float) -> tuple[float, float]:
        """(speed, shape) meeting the rise time with the largest overshoot not above ``overshoot`` [%].

        Scans nine shapes, then refines by Brent's method towards the request between the best shape
        and a neighbour above the limit. When no shape meets both, the least overshoot is kept (the
        closed-loop simulation reports it).
        """
        import scipy.optimize

        if self.loop == "velocity":
            shapes = list(np.geomspace(0.02, 1.0, 9))
        else:
            shapes = list(np.linspace(0.5, 2.5, 9))
        table = []
        for shape in shapes:
            speed = self.speed_for(shape)
            tr, os_ = self.metrics(speed, shape)
            table.append((shape, speed, tr, os_))
        ok = [row for row in table if row[3] <= overshoot and abs(math.log(row[2] / self.rise_time)) < 0.05]
        if not ok:
            # Nothing meets both: keep the least overshoot (reported by the simulation).
            shape, speed, _, _ = min(table, key=lambda row: row[3])
            return speed, shape
        shape, speed, _, _os_best = max(ok, key=lambda row: row[3])
        # Refine towards the request between this shape and a neighbour above the limit.
        k = shapes.index(shape)
        for nb in (k - 1, k + 1):
            if 0 <= nb < len(shapes) and table[nb][3] > overshoot:
                target = max(overshoot - 0.2, 0.0)

                def g(x: float, target: float = target) -> float:
                    return self.metrics(self.speed_for(x), x)[1] - target

                a, b = shape, shapes[nb]
                if g(a) * g(b) < 0:
                    shape = scipy.optimize.brentq(g, min(a, b), max(a, b), xtol=1e-3 * abs(b - a))
                    speed = self.speed_for(shape)
                break
        return speed, shape


def closed_loop_poles(gains: Gains, feedforward: Feedforward) -> np.ndarray:
    """Poles of the continuous linear closed loop (kS cancelled, no sampling) [1/s].

    Notes
    -----
    Velocity: kA·s² + (kV + kP)·s + kI (kA·s + kV + kP without kI); position:
    kA·s³ + (kV + kD)·s² + kP·s + kI. Used to size simulation runs, not to report performance.
    """
    ka, kv = feedforward.kA, feedforward.kV
    if gains.loop == "velocity":
        coeffs = [ka, kv + gains.kP, gains.kI] if gains.kI else [ka, kv + gains.kP]
    else:
        coeffs = [ka, kv + gains.kD, gains.kP, gains.kI] if gains.kI else [ka, kv + gains.kD, gains.kP]
    return np.roots(coeffs)
