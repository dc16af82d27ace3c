"""From a plant to checked gains: design, convert to a target, simulate, measure.

:func:`tune` is what ``motorlab tune`` runs; :func:`tune_summary` is the one-call version the report
and ``motorlab demo`` use.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from motorlab.control.design import (
    LOOPS,
    Feedforward,
    Gains,
    closed_loop_poles,
    design_pid_poles,
    design_position_lqr,
    design_velocity_lqr,
)
from motorlab.control.plant import MechanismUnits, Plant
from motorlab.control.simulation import (
    ClosedLoopResponse,
    ProfileLimits,
    max_profile,
    plot_response,
    simulate_closed_loop,
    step_reference,
    trapezoid,
    velocity_ramp,
)
from motorlab.control.targets import TargetGains, to_target
from motorlab.control.tolerances import Tolerances, describe_settings, design_tolerances
from motorlab.errors import OptionError
from motorlab.model import MotorParams
from motorlab.units import format_percent

METHODS = ("lqr", "poles")

#: Longest closed-loop run simulated [s] (a very slow loop is reported as not settled).
MAX_DURATION = 20.0


@dataclass
class TuneResult:
    """Everything ``motorlab tune`` reports.

    Attributes
    ----------
    gains
        Designed gains in SI (V per rad ...).
    target
        The gains in the target's units.
    step, profile
        Simulated closed-loop step and trapezoidal-profile responses (SI).
    limits
        The fastest profile the motor can follow at the supply voltage.
    plant
        The plant designed for.
    units
        The user's length unit.
    warnings
        Design targets not met, oscillation, saturation.
    """

    gains: Gains
    target: TargetGains
    step: ClosedLoopResponse
    profile: ClosedLoopResponse
    limits: ProfileLimits
    plant: Plant
    units: MechanismUnits
    warnings: list[str] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        """The JSON of ``motorlab tune --json`` (lengths in the target's units; see ``units``)."""
        per = self._display_per_radian()
        u = self.target.units
        m = self.profile.metrics
        return {
            "loop": self.gains.loop,
            "method": self.gains.method,
            "target": self.target.target,
            "gains": dict(self.target.gains),
            "feedforward": dict(self.target.feedforward),
            "units": {
                **u,
                "rise_time": "s",
                "overshoot": "%",
                "settling_time": "s",
                "steady_state_error": u["velocity"] if self.gains.loop == "velocity" else u["position"],
            },
            "response": self.step.response_dict(per),
            "step": {
                "size": self.step.target * per,
                "saturated_fraction": self.step.metrics["saturated_fraction"],
                "sustained_oscillation": self.step.metrics["sustained_oscillation"],
            },
            "profile": {
                "max_tracking_error": m["max_tracking_error"] * per,
                "final_error": m["steady_state_error"] * per,
                "sustained_oscillation": m["sustained_oscillation"],
            },
            "max_profile": {
                **self.limits.to_dict(per),
                "unit": f"{u['position']}/s, {u['position']}/s^2",
            },
            "design": {
                "period": self.gains.period,
                "delay": self.gains.delay,
                # An infinite tolerance (that error not penalised) is null in JSON.
                **{k: (v if math.isfinite(v) else None) for k, v in self.gains.settings.items()},
                "si_gains": self.gains.to_dict(),
                "plant": {**self.plant.feedforward.to_dict(), "unit": "V, V*s/rad, V*s^2/rad"},
                "simulated_on": self.step.settings["plant"],
            },
            "conversion": list(self.target.conversion),
            "notes": list(self.target.notes),
            "warnings": list(self.warnings),
        }

    def _display_per_radian(self) -> float:
        if self.target.target in ("phoenix6", "spark", "spark-data-port"):
            return 1 / (2 * math.pi)  # rotations
        if self.target.target.startswith("ftc") or self.target.target in ("roadrunner", "phoenix5"):
            return (self.units.cpr or 2 * math.pi) / (2 * math.pi)
        if self.target.target == "pedro":
            return (self.units.metres or 0.0) / 0.0254  # inches (pedro refuses a unit that is not a distance)
        return self.units.per_radian

    def plot(self, *, fig: Any = None) -> Any:
        """A figure with the step and profile responses (display units)."""
        import matplotlib.pyplot as plt

        if fig is None:
            fig = plt.figure(figsize=(8, 6.5))
        axes = fig.subplots(2, 1)
        per = self._display_per_radian()
        unit = self.target.units["position"]
        plot_response(self.step, ax=axes[0], per_radian=per, unit=unit)
        plot_response(self.profile, ax=axes[1], per_radian=per, unit=unit)
        g = self.target.gains
        import textwrap

        title = (f"{self.gains.loop} loop ({self.gains.method}, {self.target.target}): "
                 + ", ".join(f"{k} = {v:.4g}" for k, v in g.items()))
        fig.suptitle("\n".join(textwrap.wrap(title, 100)), fontsize=10)
        fig.tight_layout()
        return fig


def _duration(gains: Gains, ff: Feedforward, extra: float) -> float:
    poles = closed_loop_poles(gains, ff)
    sigma = min((abs(p.real) for p in poles if p.real < 0), default=0.0)
    settle = 8.0 / sigma if sigma > 0 else MAX_DURATION
    return min(max(settle + extra, 40 * gains.period, 0.5), MAX_DURATION)


@dataclass(frozen=True)
class DesignRequest:
    """What :func:`tune` and :func:`design_for_target` design: ``motorlab tune``'s options, written once.

    Parameters
    ----------
    loop
        ``"velocity"`` or ``"position"``.
    method
        ``"lqr"`` (SysId's) or ``"poles"`` (rise time / overshoot).
    target
        One of :data:`motorlab.control.targets.TARGETS`.
    units
        The user's length unit; plain numbers given as ``qp``, ``qv`` (and :func:`tune`'s ``step``) are in it.
        None: radians.
    qp, qv
        LQR tolerances on position [unit] and velocity [unit/s]: a number, a text with a unit or a
        percentage (:func:`motorlab.control.tolerances.design_tolerances`), or None for the physical
        default: 20 % of the free speed, and the distance it covers in one time
        constant kA/kV; the same in every unit.
    r
        LQR control effort tolerance [V] (or a text, ``"50 %"`` of ``voltage``); None: 7/12 of ``voltage``.
    period
        Controller period [s].
    delay
        Measurement delay [s].
    rise_time
        Pole placement: requested 10–90 % rise time [s].
    overshoot
        Pole placement: largest acceptable overshoot [%].
    voltage
        Supply voltage [V] (saturation, power and duty conversions, profile limits).
    """

    loop: str = "velocity"
    method: str = "lqr"
    target: str = "volts"
    units: MechanismUnits | None = None
    qp: float | str | None = None
    qv: float | str | None = None
    r: float | str | None = None
    period: float = 0.02
    delay: float = 0.0
    rise_time: float | None = None
    overshoot: float = 5.0
    voltage: float = 12.0

    @property
    def mechanism(self) -> MechanismUnits:
        """The length unit (radians when none was given)."""
        return self.units or MechanismUnits("rad", 1.0)


def tune(plant: Plant, request: DesignRequest | None = None, *, step: float | None = None) -> TuneResult:
    """Design gains, convert them to a target and check them in closed-loop simulation.

    Parameters
    ----------
    plant
        The plant (:class:`Plant`; SI).
    request
        What to design (:class:`DesignRequest`; default: LQR of a velocity loop in volts per radian).
    step
        Step size [unit/s for velocity, unit for position]; default half the free speed, or one
        revolution of the shaft.

    Returns
    -------
    TuneResult

    Raises
    ------
    OptionError
        For impossible settings.
    """
    request = request or DesignRequest()
    units = request.mechanism
    gains, tg = design_for_target(plant, request)
    ff = plant.feedforward
    limits = max_profile(ff, request.voltage)
    size = _step_size(ff, request.loop, step, units=units, voltage=request.voltage)
    step_resp, prof_resp = _simulate_step_and_profile(
        gains, ff, tg.equivalent_feedforward, plant.simulated, size, limits, voltage=request.voltage, cpr=units.cpr,
        law="roadrunner" if request.target == "roadrunner" else "pid",
    )
    overshoot = request.overshoot if request.method == "poles" else None
    warnings = [*plant.notes, *_check(gains, step_resp, prof_resp, overshoot, request.rise_time,
                                      static_friction=ff.kS)]
    return TuneResult(gains, tg, step_resp, prof_resp, limits, plant, units, warnings)


def design_for_target(plant: Plant, request: DesignRequest | None = None) -> tuple[Gains, TargetGains]:
    """The design of :func:`tune` without its simulations: (SI gains, the gains in the target's units).

    Parameters and errors as :func:`tune`'s. The SI gains depend on the plant, the target's kind of
    controller and the tolerances only, never on ``request.units`` (which reads user tolerances given as
    plain numbers, and prints the target's numbers).
    """
    q = request or DesignRequest()
    units = q.mechanism
    if q.loop not in LOOPS:
        raise OptionError(f"unknown loop {q.loop!r} (expected velocity or position)")
    if q.method not in METHODS:
        raise OptionError(f"unknown method {q.method!r} (expected lqr or poles)")
    if not (q.voltage > 0 and math.isfinite(q.voltage)):
        raise OptionError(f"supply voltage must be positive, got {q.voltage}")
    ff = plant.feedforward.check_plant()
    tolerances = design_tolerances(ff, q.voltage, units, qp=q.qp, qv=q.qv, r=q.r)
    gains = _design(ff, q, tolerances)
    return gains, to_target(gains, ff, q.target, units=units, voltage=q.voltage, geometry=plant.geometry)


#: Targets whose controller holds position and velocity together (Road Runner's HolonomicController):
#: their LQR design is the position loop's whatever the loop, and a velocity loop's kI is its position gain.
HOLONOMIC = ("roadrunner",)


def _design(ff: Feedforward, request: DesignRequest, tolerances: Tolerances) -> Gains:
    """Gains of :func:`tune` by ``request.method`` (SI: volts per rad)."""
    loop, target, period, delay = request.loop, request.target, request.period, request.delay
    if request.method == "poles":
        return design_pid_poles(loop, ff, rise_time=request.rise_time, overshoot=request.overshoot, period=period,
                                delay=delay)
    tol = tolerances
    if loop == "position" or target in HOLONOMIC:
        gains = design_position_lqr(ff.kV, ff.kA, qp=tol.qp, qv=tol.qv, r=tol.r, period=period, delay=delay)
        if loop == "velocity":
            # The same controller seen from the velocity: kP on the velocity error, kI on its integral,
            # the position error (Road Runner's axialVelGain and axialGain).
            gains = Gains("velocity", gains.kD, gains.kP, 0.0, method="lqr", period=period, delay=delay)
    else:
        gains = design_velocity_lqr(ff.kV, ff.kA, qv=tol.qv, r=tol.r, period=period, delay=delay)
    settings = tol.settings(request.mechanism)
    if loop == "velocity" and target not in HOLONOMIC:
        settings = {k: v for k, v in settings.items() if not k.startswith("qp")}
    return replace(gains, settings=settings)


def _step_size(ff: Feedforward, loop: str, step: float | None, *, units: MechanismUnits, voltage: float) -> float:
    """The step of :func:`tune` [rad/s or rad]: ``step`` [unit/s or unit], or half the free speed, or one turn.

    Raises
    ------
    OptionError
        When the motor cannot move at ``voltage``, for a zero step, or a velocity step beyond the free speed.
    """
    n = units.per_radian
    free = ff.free_speed(voltage)
    if step is None:
        size = 0.5 * free if loop == "velocity" else 2 * math.pi
    else:
        size = step / n
        if not (size != 0 and math.isfinite(size)):
            raise OptionError(f"step size must be non-zero, got {step}")
    if loop == "velocity" and abs(size) >= free:
        raise OptionError(
            f"velocity step {abs(size) * n:.4g} {units.short}/s is beyond the free speed "
            f"{free * n:.4g} {units.short}/s at {voltage:g} V"
        )
    return size


def _simulate_step_and_profile(
    gains: Gains,
    ff: Feedforward,
    ctrl_ff: Feedforward,
    sim_plant: MotorParams | Feedforward,
    size: float,
    limits: ProfileLimits,
    *,
    voltage: float,
    cpr: float | None,
    law: str = "pid",
) -> tuple[ClosedLoopResponse, ClosedLoopResponse]:
    """The closed-loop step of ``size`` and the fastest profile to it, each run long enough to settle.

    ``ff`` is the design plant (run lengths), ``ctrl_ff`` the feedforward the target applies and
    ``sim_plant`` the model simulated.
    """
    loop = gains.loop
    free = ff.free_speed(voltage)
    travel = abs(size) / free if loop == "position" else 0.0
    step_resp = simulate_closed_loop(
        gains,
        ctrl_ff,
        sim_plant,
        step_reference(loop, size),
        duration=_duration(gains, ff, 2 * travel + 5 * ff.time_constant),
        voltage=voltage,
        cpr=cpr,
        kind="step",
        law=law,
    )
    if loop == "velocity":
        ref, t_prof = velocity_ramp(size, limits.max_acceleration)
    else:
        ref, t_prof = trapezoid(size, limits.max_velocity, limits.max_acceleration)
    prof_resp = simulate_closed_loop(
        gains,
        ctrl_ff,
        sim_plant,
        ref,
        duration=_duration(gains, ff, t_prof + 2 * ff.time_constant),
        voltage=voltage,
        cpr=cpr,
        kind="profile",
        target=size,
        law=law,
    )
    return step_resp, prof_resp


def _check(
    gains: Gains,
    step: ClosedLoopResponse,
    profile: ClosedLoopResponse,
    overshoot: float | None,
    rise_time: float | None,
    *,
    static_friction: float = 0.0,
) -> list[str]:
    out = []
    m = step.metrics
    if m["sustained_oscillation"] or profile.metrics["sustained_oscillation"]:
        out.append("the simulated loop keeps oscillating (limit cycle or instability): lower the gains")
    if not math.isfinite(m["settling_time"]):
        stuck = (
            step.loop == "position"
            and not m["sustained_oscillation"]
            # Stopped, or creeping too slowly to close the gap within another run's length.
            and abs(float(step.speed[-1])) * float(step.time[-1]) < abs(m["steady_state_error"])
        )
        travelling = abs(float(step.speed[-1])) > 0.1 * float(np.max(np.abs(step.speed)))
        if stuck and travelling:  # not held: the step is longer than the motor can travel in the run
            out.append(
                f"the motor is still travelling at {abs(float(step.speed[-1])):.3g} rad/s when the simulated run ends, "
                f"{abs(m['steady_state_error']):.3g} rad short of the target: use a motion profile or a smaller step"
            )
        elif stuck and static_friction > 0:
            out.append(
                f"the motor stops (or creeps) {abs(m['steady_state_error']):.3g} rad short of the target: Coulomb "
                "friction holds it where kP·error < kS; add kS·sgn(error) feedforward, an integral term "
                "or a tighter qp"
            )
        elif stuck:
            out.append(
                f"the motor stops (or creeps) {abs(m['steady_state_error']):.3g} rad short of the target with no "
                "static friction in the model (kS = 0): the loop is too slow for the run; raise qp or lower r"
            )
        else:
            out.append("the simulated step response does not settle within the run")
    if overshoot is not None and m["overshoot"] > overshoot + 1.0:
        out.append(
            f"simulated overshoot {m['overshoot']:.1f} % exceeds the requested {overshoot:g} % "
            "(friction, saturation or quantisation the linear design ignores)"
        )
    wanted = gains.settings.get("rise_time") if rise_time is None else rise_time
    if gains.method == "poles" and wanted and math.isfinite(m["rise_time"]) and m["rise_time"] > 1.5 * wanted:
        out.append(
            f"simulated rise time {m['rise_time']:.3g} s is slower than the requested {wanted:.3g} s "
            "(the voltage saturates)"
        )
    if m["saturated_fraction"] > 0.2:
        out.append(
            f"the output saturates {100 * m['saturated_fraction']:.0f} % of the step: "
            "use a motion profile or a smaller step"
        )
    return out


def tune_summary(
    params: MotorParams | Plant,
    *,
    voltage: float = 12.0,
    cpr: float | None = None,
    target: str = "volts",
    units: str = "rad",
    period: float = 0.02,
    velocity_delay: float | None = None,
    plot: bool = True,
) -> dict[str, Any]:
    """Velocity and position gains (LQR with the physical default tolerances) for a motor, with a step-response figure.

    Parameters
    ----------
    params
        The motor (:class:`MotorParams`, at the encoder's shaft) or a :class:`Plant`.
    voltage
        Supply voltage [V].
    cpr
        Encoder counts per revolution (quantisation in the simulation; required by FTC targets).
    target
        Target for the gains (see :data:`motorlab.control.targets.TARGETS`); ``ftc-pidf`` applies to
        the velocity loop only, the position loop then uses ``ftc-power``.
    units
        Length unit of the reported gains (``rad``, ``rotations``, ``degrees``, ``ticks``).
    period
        Controller period [s].
    velocity_delay
        Measurement delay compensated in the velocity loop [s]; default ``period/2``, the lag of a
        velocity measured as the count difference over one period (as the simulation measures it).
    plot
        Also draw the figure.

    Returns
    -------
    dict
        ``{"velocity": TuneResult.to_dict(), "position": ..., "text": str (a few lines for a terminal
        or a report), "figure": matplotlib Figure or None, "results": {"velocity": TuneResult,
        "position": TuneResult}}``.
    """
    plant = params if isinstance(params, Plant) else Plant.from_params(params)
    mech = MechanismUnits.from_options(units, cpr=cpr)
    results = {}
    delays = {"velocity": period / 2 if velocity_delay is None else velocity_delay, "position": 0.0}
    for loop in LOOPS:
        tgt = "ftc-power" if (loop == "position" and target == "ftc-pidf") else target
        results[loop] = tune(plant, DesignRequest(loop, target=tgt, units=mech, period=period, voltage=voltage,
                                                  delay=delays[loop]))
    lines = []
    for loop, res in results.items():
        g = res.target.gains
        resp = res.step.metrics
        lines.append(
            f"{loop} loop ({res.target.target}, LQR tolerances: {describe_settings(res.gains.settings)}, "
            f"T={period:g} s, delay {delays[loop] * 1e3:g} ms): "
            + ", ".join(f"{k} = {v:.4g} {res.target.units.get(k, '')}" for k, v in g.items())
        )
        lines.append(
            f"    step: rise {resp['rise_time'] * 1e3:.0f} ms, "
            f"overshoot {format_percent(resp['overshoot'] / 100, '.1f')}, "
            f"settling {resp['settling_time'] * 1e3:.0f} ms"
            if math.isfinite(resp["rise_time"]) and math.isfinite(resp["settling_time"])
            else "    step: does not settle in the simulated run"
        )
        lines.extend(f"    warning: {w}" for w in res.warnings)
    lim = results["velocity"].limits
    per = mech.per_radian
    lines.append(
        f"fastest profile at {voltage:g} V: v_max = {lim.max_velocity * per:.4g} {mech.short}/s, "
        f"a_max = {lim.max_acceleration * per:.4g} {mech.short}/s² (free speed {lim.free_speed * per:.4g})"
    )
    return {
        "velocity": results["velocity"].to_dict(),
        "position": results["position"].to_dict(),
        "text": "\n".join(lines),
        "figure": summary_figure(results) if plot else None,
        "results": results,
    }


def summary_figure(results: dict[str, TuneResult]) -> Any:
    """The step responses of :func:`tune_summary`'s loops, one above the other (a matplotlib Figure)."""
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=(9, 6.5))
    axes = fig.subplots(2, 1)
    for ax, (loop, res) in zip(axes, results.items(), strict=True):
        disp = res._display_per_radian()
        plot_response(res.step, ax=ax, per_radian=disp, unit=res.target.units["position"])
        ax.set_title(ax.get_title().replace(f"{loop} step", f"{loop} step with LQR gains", 1), fontsize=10, y=1.0)
    fig.tight_layout()
    return fig
