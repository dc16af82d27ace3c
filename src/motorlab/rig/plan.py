"""Rig design calculation: the flywheel a spin-up test needs (seed 1, "First Experiment").

Seed 1 sizes a flywheel so that a gearmotor driven at a constant current takes a chosen time to
reach a chosen fraction of its free speed, slow enough to resolve the acceleration from encoder
counts logged every ~30-100 ms. This module does that calculation and the checks around it:

- the inertia needed, J_f = τ/α with α = Δω/t (eq. (5) of the seed, constant torque);
- the disc that gives it, J = ½·π·r⁴·ρ·h, and how a step-up gear ratio N multiplies a disc's
  inertia as seen by the motor (J·N², the seed's 25:1 gearbox to the flywheel);
- the spin-up time the chosen rig really gives: the seed's constant-torque estimate, the exact
  time with friction for an ideal current source, and the exact time for a bench supply (constant
  voltage with a current limit, where the back-EMF ends the constant-current phase);
- the coast-down time with the catalogue's nominal friction;
- encoder count rates against the log period, and sensor range checks (INA219 bus voltage ≤ 16 V,
  shunt current range, scale capacity).

All functions are plain and take SI values; :func:`plan_rig` gathers them into a :class:`RigPlan`.
Inductance is neglected in the times (L/R ≈ 1 ms against spin-ups of seconds).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

from threadpoolctl import threadpool_limits

from motorlab.catalog import Motor
from motorlab.errors import OptionError
from motorlab.model import MotorParams
from motorlab.model.load import MATERIALS, disc_inertia, require_positive
from motorlab.units import STANDARD_GRAVITY

#: A supply setting above this many times the motor's nominal voltage is refused (12 V motors run
#: to 24 V at most on a bench; 1e6 V is a typo).
MAX_VOLTAGE_FACTOR = 4.0

#: INA219 limits: bus voltage it survives in the seed's experience [V] (seed 1: "do NOT set the
#: voltage ... higher than 16 volts ... a high voltage will fry the sensor"), and full-scale shunt
#: voltage at gain /8 [V] (±320 mV, i.e. ±3.2 A with the 0.1 Ω shunt of the Adafruit board).
INA219_BUS_MAX = 16.0
INA219_SHUNT_MAX = 0.32

#: Fewer counts than this per log period at the target speed give a speed resolution worse than 10 %.
MIN_COUNTS_PER_PERIOD = 10.0
#: Fewer log samples than this during the spin-up leave the acceleration poorly resolved.
MIN_SAMPLES_IN_SPIN_UP = 20.0

RPM = 2.0 * math.pi / 60.0


# ---- plain physics ------------------------------------------------------------------------------
def disc_mass(radius: float, thickness: float, density: float) -> float:
    """Mass m = π·r²·h·ρ of a uniform disc [kg] (radius [m], thickness [m], density [kg/m³])."""
    require_positive(radius=radius, thickness=thickness, density=density)
    return math.pi * radius**2 * thickness * density


def disc_radius_for_inertia(inertia: float, thickness: float, density: float) -> float:
    """Radius of a uniform disc of given thickness [m] and density [kg/m³] with inertia J [kg·m²].

    Notes
    -----
    Inverts J = ½·π·r⁴·ρ·h: r = (2·J/(π·ρ·h))^¼ [m].
    """
    require_positive(inertia=inertia, thickness=thickness, density=density)
    return (2.0 * inertia / (math.pi * density * thickness)) ** 0.25


def required_inertia(torque: float, speed: float, time: float) -> float:
    """Inertia that a constant torque brings from rest to ``speed`` in ``time``.

    Parameters
    ----------
    torque
        Constant driving torque τ [N·m].
    speed
        Speed to reach, Δω [rad/s].
    time
        Time allowed t [s].

    Returns
    -------
    float
        J = τ/α with α = Δω/t [kg·m²] (eq. (5) of seed 1; friction and back-EMF ignored).
    """
    require_positive(torque=torque, speed=speed, time=time)
    return torque * time / speed


def reflected_inertia(inertia: float, ratio: float) -> float:
    """Inertia seen at the motor shaft of a load turning ``ratio`` times faster: J·N² [kg·m²]."""
    require_positive(ratio=ratio)
    if inertia < 0:
        raise OptionError(f"inertia must not be negative, got {inertia}")
    reflected = inertia * ratio * ratio  # not ratio**2: float ** raises OverflowError where * gives inf
    if not math.isfinite(reflected):
        raise OptionError(f"a ratio of {ratio:g} reflects an inertia too large to represent ({inertia:g} kg·m² × N²)")
    return reflected


def step_up_ratio(required: float, available: float) -> float:
    """Step-up ratio N with available·N² = required: N = √(required/available) [-]."""
    require_positive(required=required, available=available)
    return math.sqrt(required / available)


def spin_up_time_current(params: MotorParams, current: float, speed: float) -> float:
    """Time from rest to ``speed`` at a constant winding current (ideal current source).

    Parameters
    ----------
    params
        Motor (and load) parameters at the encoder shaft.
    current
        Winding current i [A].
    speed
        Target speed ω [rad/s].

    Returns
    -------
    float
        t [s]; ``inf`` if the current cannot reach that speed (or cannot break away).

    Notes
    -----
    J·dω/dt = K·i − b·ω − Tf gives ω(t) = ω_ss·(1 − e^(−b·t/J)) with ω_ss = (K·i − Tf)/b, so
    t = −(J/b)·ln(1 − ω/ω_ss); with b = 0, t = J·ω/(K·i − Tf). Back-EMF does not act on an
    ideal current source (it only sets the compliance voltage, see :func:`spin_up_time_supply`).
    """
    require_positive(current=current, speed=speed)
    drive = params.K * current - params.Tf
    if drive <= 0:
        return math.inf
    return _time_to_speed(params.J, drive, params.b, 0.0, speed)


def spin_up_time_supply(params: MotorParams, voltage: float, current_limit: float, speed: float) -> float:
    """Time from rest to ``speed`` on a bench supply: constant current up to the crossover, then CV.

    Parameters
    ----------
    params
        Motor (and load) parameters at the encoder shaft.
    voltage
        Supply voltage setting V [V].
    current_limit
        Supply current limit I_lim [A].
    speed
        Target speed ω [rad/s].

    Returns
    -------
    float
        t [s] (L neglected); ``inf`` if the speed is not reachable.

    Notes
    -----
    While (V − K·ω)/R > I_lim the supply holds i = I_lim (current phase, as
    :func:`spin_up_time_current`) up to the crossover speed ω_c = (V − R·I_lim)/K; above it the
    supply holds V and J·dω/dt = K·(V − K·ω)/R − b·ω − Tf, a first-order lag towards
    ω_ss = (K·V/R − Tf)/(K²/R + b) with time constant J/(K²/R + b).
    """
    require_positive(voltage=voltage, current_limit=current_limit, speed=speed)
    K, R, J, b, Tf = params.K, params.R, params.J, params.b, params.Tf
    crossover = max((voltage - R * current_limit) / K, 0.0)
    t = 0.0
    start = 0.0
    if crossover > 0:
        drive = K * current_limit - Tf
        if drive <= 0:
            return math.inf
        if speed <= crossover:
            return _time_to_speed(J, drive, b, 0.0, speed)
        t = _time_to_speed(J, drive, b, 0.0, crossover)
        start = crossover
    # Constant-voltage phase: J·dω/dt = (K·V/R − Tf) − (K²/R + b)·ω.
    return t + _time_to_speed(J, K * voltage / R - Tf, K**2 / R + b, start, speed)


def coast_time(params: MotorParams, speed: float, *, final_speed: float = 0.0) -> float:
    """Time for the free (open-circuit) shaft to slow from ``speed`` to ``final_speed``.

    Parameters
    ----------
    params
        Motor (and load) parameters; only J, b and Tf matter.
    speed
        Initial speed ω₀ [rad/s].
    final_speed
        Speed at which to stop the clock [rad/s] (0: to rest).

    Returns
    -------
    float
        t [s]; ``inf`` when the friction cannot stop the shaft (Tf = 0 and final speed 0).

    Notes
    -----
    J·dω/dt = −b·ω − Tf gives ω(t) = (ω₀ + Tf/b)·e^(−b·t/J) − Tf/b, hence
    t = (J/b)·ln((ω₀ + Tf/b)/(ω_f + Tf/b)); with b = 0 the decay is linear, t = J·(ω₀ − ω_f)/Tf.
    """
    require_positive(speed=speed)
    if not 0 <= final_speed < speed:
        raise OptionError(f"final speed must lie in [0, {speed}), got {final_speed}")
    J, b, Tf = params.J, params.b, params.Tf
    if b > 0:
        offset = Tf / b
        if offset == 0 and final_speed == 0:
            return math.inf
        return J / b * math.log((speed + offset) / (final_speed + offset))
    if Tf > 0:
        return J * (speed - final_speed) / Tf
    return math.inf


def _time_to_speed(J: float, drive: float, damping: float, start: float, target: float) -> float:
    """Time for J·dω/dt = drive − damping·ω to go from ``start`` to ``target`` (inf if never)."""
    if target <= start:
        return 0.0
    if damping <= 0:
        return J * (target - start) / drive if drive > 0 else math.inf
    final = drive / damping
    if final <= target:
        return math.inf
    return J / damping * math.log((final - start) / (final - target))


# ---- the plan -----------------------------------------------------------------------------------
@dataclass(frozen=True)
class Figure:
    """One figure of a plan: a label for people, the SI value and its unit."""

    label: str
    value: float
    unit: str
    note: str = ""

    def to_dict(self) -> dict[str, Any]:
        """``{"label", "value", "unit"}`` with non-finite values as None (JSON)."""
        out: dict[str, Any] = {
            "label": self.label,
            "value": self.value if math.isfinite(self.value) else None,
            "unit": self.unit,
        }
        if self.note:
            out["note"] = self.note
        return out


@dataclass(frozen=True)
class RigPlan:
    """The result of :func:`plan_rig`: every figure with its unit, in sections, plus warnings.

    ``plan["required_inertia"]`` gives a figure's SI value; ``plan.figures`` holds
    ``section -> {key -> Figure}``.
    """

    motor: str
    figures: dict[str, dict[str, Figure]]
    warnings: tuple[str, ...] = ()

    def __getitem__(self, key: str) -> float:
        for section in self.figures.values():
            if key in section:
                return section[key].value
        raise KeyError(key)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready nested dict."""
        return {
            "motor": self.motor,
            "sections": {
                name: {key: fig.to_dict() for key, fig in section.items()} for name, section in self.figures.items()
            },
            "warnings": list(self.warnings),
        }


def plan_rig(
    motor: Motor,
    *,
    current: float | None = None,
    fraction: float = 0.5,
    time: float = 5.0,
    material: str = "steel",
    radius: float = 0.075,
    thickness: float = 0.05,
    ratio: float = 1.0,
    voltage: float | None = None,
    log_period: float = 0.1,
    free_speed: float | None = None,
    stall_torque: float | None = None,
    lever_arm: float | None = None,
    scale_capacity: float | None = None,
    shunt_resistance: float = 0.1,
) -> RigPlan:
    """Seed 1's flywheel design calculation for ``motor``, with the checks around it.

    Parameters
    ----------
    motor
        The gearmotor (:meth:`Motor.from_catalog`).
    current
        Constant drive current [A]; default half the stall current (the seed's i_max/2).
    fraction
        Fraction of the free speed to reach [-] (seed: 0.5).
    time
        Time in which to reach it [s] (seed: 5 s).
    material
        Flywheel material, a key of :data:`MATERIALS`.
    radius, thickness
        The disc on hand [m] (seed: 0.075 m × 0.05 m).
    ratio
        Step-up ratio from the motor shaft to the flywheel [-] (seed's gearbox: 25).
    voltage
        Supply voltage setting [V]; default the motor's nominal voltage. The current limit of the
        supply is ``current``.
    log_period
        Period of the OpMode's log [s] (seed: ~30-100 ms).
    free_speed, stall_torque
        Replace the catalogue's figures [rad/s], [N·m] (the seed's worked example uses 9.1 rad/s
        and 4.2 N·m for the AndyMark 60, scaled from its AndyMark 40 figures).
    lever_arm, scale_capacity
        Torque-arm length [m] and scale capacity [kg] of the cradle, for the scale range check.
    shunt_resistance
        Current-sense shunt of the INA219 board [Ω] (Adafruit: 0.1 Ω).

    Returns
    -------
    RigPlan
        Sections ``motor``, ``target``, ``flywheel``, ``times``, ``encoder``, ``sensors``.

    Raises
    ------
    OptionError
        For impossible options (fraction outside (0, 1), current above stall, unknown material...).

    Notes
    -----
    The seed's design rule is constant torque τ = Kt·i with Kt = τ_stall/I_stall from the data
    sheet (the AndyMark 60 at i_max/2 = 5.75 A gives τ_max/2 = 2.1 N·m), ignoring friction and
    back-EMF: J_f = τ·t/(fraction·ω_free). The rig's actual inertia is the motor's own
    (nominal, reflected to its output) plus the disc's, J_disc·N². Its spin-up time is then given
    three ways: the seed's constant-torque rule, an ideal current source with the catalogue's
    nominal friction (model torque K·i − b·ω − Tf with K = Ke), and a bench supply at ``voltage``
    with current limit ``current`` (the back-EMF ends the constant-current phase). The disc's own
    bearing friction is unknown and ignored.

    References
    ----------
    Seed 1, "First Experiment", eq. (5), and "Flywheel and INA219 Experiment" (16 V warning).
    """
    motor, current, voltage = _checked_plan_options(
        motor, material=material, fraction=fraction, time=time, radius=radius, thickness=thickness, ratio=ratio,
        log_period=log_period, shunt_resistance=shunt_resistance, free_speed=free_speed,
        stall_torque=stall_torque, current=current, voltage=voltage,
    )
    density = MATERIALS[material]
    params = motor.nominal_params()
    warnings: list[str] = []
    target = _target_section(motor, current=current, fraction=fraction, time=time)
    target_speed, torque = target["target_speed"].value, target["torque"].value
    flywheel = _size_flywheel(params, target["required_inertia"].value, density=density, radius=radius,
                              thickness=thickness, ratio=ratio, warnings=warnings)
    times = _times_section(motor, flywheel.rig, target_speed=target_speed, torque=torque, current=current,
                           voltage=voltage, warnings=warnings)
    encoder = _encoder_section(motor, flywheel.rig, times, target_speed=target_speed, torque=torque,
                               log_period=log_period, voltage=voltage, warnings=warnings)
    sensors = _sensors_section(torque=torque, current=current, voltage=voltage, shunt_resistance=shunt_resistance,
                               lever_arm=lever_arm, scale_capacity=scale_capacity, warnings=warnings)
    # The flywheel's figures come last: the mass of the direct disc is checked after the sensors'
    # options, in the order the checks have always been made.
    figures = {"motor": _motor_section(motor, params), "target": target,
               "flywheel": _flywheel_section(flywheel, material), "times": times, "encoder": encoder,
               "sensors": sensors}
    return RigPlan(motor=motor.key, figures=figures, warnings=tuple(warnings))


def _checked_plan_options(
    motor: Motor, *, material: str, fraction: float, time: float, radius: float, thickness: float, ratio: float,
    log_period: float, shunt_resistance: float, free_speed: float | None, stall_torque: float | None,
    current: float | None, voltage: float | None,
) -> tuple[Motor, float, float]:
    """Check :func:`plan_rig`'s options; return the motor with its replaced figures, the current and the voltage.

    The current defaults to half the stall current and the voltage to the motor's nominal one.
    """
    if material not in MATERIALS:
        raise OptionError(f"unknown material {material!r}; choose from {', '.join(sorted(MATERIALS))}")
    if not (math.isfinite(fraction) and 0 < fraction < 1):
        raise OptionError(f"fraction must lie strictly between 0 and 1, got {fraction}")
    require_positive(time=time, radius=radius, thickness=thickness, ratio=ratio, log_period=log_period)
    require_positive(shunt_resistance=shunt_resistance)
    for name, value, high, unit in (("free speed", free_speed, 1e5, "rad/s"),
                                    ("stall torque", stall_torque, 1e5, "N·m")):
        if value is not None and math.isfinite(value) and value > high:  # a unit mistake, not a gearmotor
            raise OptionError(f"the {name} {value:g} {unit} is beyond any gearmotor (at most {high:g} {unit})")
    if free_speed is not None:
        require_positive(free_speed=free_speed)
        motor = replace(motor, free_speed=free_speed)
    if stall_torque is not None:
        require_positive(stall_torque=stall_torque)
        motor = replace(motor, stall_torque=stall_torque)
    if current is None:
        current = motor.stall_current / 2
    require_positive(current=current)
    if current > motor.stall_current:
        raise OptionError(
            f"current {current:g} A exceeds the stall current {motor.stall_current:g} A of {motor.key}"
        )
    if voltage is None:
        voltage = motor.nominal_voltage
    require_positive(voltage=voltage)
    if voltage > MAX_VOLTAGE_FACTOR * motor.nominal_voltage:
        raise OptionError(
            f"voltage {voltage:g} V is more than {MAX_VOLTAGE_FACTOR:g} times the nominal "
            f"{motor.nominal_voltage:g} V of {motor.key}: no bench test drives a motor there"
        )
    return motor, current, voltage


def _motor_section(motor: Motor, params: MotorParams) -> dict[str, Figure]:
    """Section ``motor`` of the plan: the catalogue's figures and the nominal model's K and J."""
    return {
        "free_speed": Figure("free speed (nominal)", motor.free_speed, "rad/s"),
        "free_speed_rpm": Figure("free speed (nominal)", motor.free_speed / RPM, "rpm"),
        "stall_torque": Figure("stall torque", motor.stall_torque, "N*m"),
        "stall_current": Figure("stall current", motor.stall_current, "A"),
        "torque_constant": Figure("Kt = τ_stall/I_stall (data sheet)", motor.torque_constant, "N*m/A"),
        "K": Figure("K = Ke (model)", params.K, "V*s/rad"),
        "motor_inertia": Figure("gearmotor's own J (nominal, assumed)", params.J, "kg*m^2"),
    }


def _target_section(motor: Motor, *, current: float, fraction: float, time: float) -> dict[str, Figure]:
    """Section ``target``: the seed's constant-torque rule J_f = τ/α (half speed in 5 s at half stall torque)."""
    target_speed = fraction * motor.free_speed
    torque = motor.torque_constant * current
    acceleration = target_speed / time
    j_required = required_inertia(torque, target_speed, time)
    return {
        "target_speed": Figure(f"target speed ({fraction:g} × free speed)", target_speed, "rad/s"),
        "time": Figure("time to reach it", time, "s"),
        "current": Figure("drive current", current, "A"),
        "torque": Figure("drive torque Kt·i (constant)", torque, "N*m"),
        "angular_acceleration": Figure("angular acceleration α = Δω/t", acceleration, "rad/s^2"),
        "required_inertia": Figure("inertia needed J_f = τ/α", j_required, "kg*m^2"),
    }


@dataclass(frozen=True)
class _Flywheel:
    """The disc on hand against the inertia needed, and the rig it makes (SI; see :func:`_size_flywheel`)."""

    density: float
    radius: float
    thickness: float
    ratio: float
    disc_inertia: float
    reflected_inertia: float
    shortfall: float
    step_up_needed: float
    direct_radius: float
    rig: MotorParams


def _size_flywheel(
    params: MotorParams, j_required: float, *, density: float, radius: float, thickness: float, ratio: float,
    warnings: list[str],
) -> _Flywheel:
    """The disc's inertia seen by the motor, the rig it makes, and the disc that would give J_f.

    Appends a warning to ``warnings`` when the rig's inertia is more than a factor 2 from J_f.
    """
    j_disc = disc_inertia(radius, thickness, density)
    j_reflected = reflected_inertia(j_disc, ratio)
    if not (math.isfinite(j_reflected) and j_reflected > 0):
        raise OptionError(f"a disc of radius {radius:g} m and thickness {thickness:g} m has an inertia of "
                          f"{j_disc:g} kg·m² at the motor: no flywheel at all (check --radius, --thickness)")
    rig = params.with_load(j_disc, ratio=ratio)
    shortfall = j_required / j_reflected
    n_needed = step_up_ratio(j_required, j_disc)
    r_direct = disc_radius_for_inertia(j_required, thickness, density)
    if rig.J < 0.5 * j_required:
        warnings.append(
            f"the rig's inertia {rig.J:.3g} kg·m² is {j_required / rig.J:.3g} times less than the "
            f"{j_required:.3g} kg·m² needed: the spin-up will be about that much faster; "
            f"a step-up ratio of {n_needed:.3g} on this disc would give it"
        )
    elif rig.J > 2 * j_required:
        warnings.append(
            f"the rig's inertia {rig.J:.3g} kg·m² is {rig.J / j_required:.3g} times more than needed: "
            "the spin-up will be slower than asked"
        )
    return _Flywheel(density, radius, thickness, ratio, j_disc, j_reflected, shortfall, n_needed, r_direct, rig)


def _flywheel_section(flywheel: _Flywheel, material: str) -> dict[str, Figure]:
    """Section ``flywheel``: the disc on hand, what the motor sees of it, and the disc that would do."""
    f = flywheel
    return {
        "density": Figure(f"density ({material})", f.density, "kg/m^3"),
        "disc_radius": Figure("disc radius", f.radius, "m"),
        "disc_thickness": Figure("disc thickness", f.thickness, "m"),
        "disc_mass": Figure("disc mass", disc_mass(f.radius, f.thickness, f.density), "kg"),
        "disc_inertia": Figure("disc inertia ½·π·r⁴·ρ·h", f.disc_inertia, "kg*m^2"),
        "ratio": Figure("step-up ratio to the disc", f.ratio, "1"),
        "reflected_inertia": Figure("disc inertia seen by the motor J·N²", f.reflected_inertia, "kg*m^2"),
        "shortfall": Figure("needed / seen by the motor", f.shortfall, "1"),
        "step_up_needed": Figure("step-up ratio that gives J_f with this disc", f.step_up_needed, "1"),
        "direct_disc_radius": Figure(f"radius of a {f.thickness:g} m disc with J_f", f.direct_radius, "m"),
        "direct_disc_mass": Figure("mass of that disc", disc_mass(f.direct_radius, f.thickness, f.density), "kg"),
        "rig_inertia": Figure("rig inertia (motor + disc·N²)", f.rig.J, "kg*m^2"),
    }


def _times_section(
    motor: Motor, rig: MotorParams, *, target_speed: float, torque: float, current: float, voltage: float,
    warnings: list[str],
) -> dict[str, Figure]:
    """Section ``times``: the rig's spin-up time three ways, the supply's crossover and the coast-down.

    Appends warnings for the gearbox loss at stall and for a target speed never reached.
    """
    t_constant = rig.J * target_speed / torque
    t_current = spin_up_time_current(rig, current, target_speed)
    t_supply = spin_up_time_supply(rig, voltage, current, target_speed)
    crossover = max((voltage - rig.R * current) / rig.K, 0.0)
    w_supply_final = rig.free_speed(voltage)
    t_coast = coast_time(rig, target_speed)
    efficiency = motor.gearbox_efficiency_at_stall
    if efficiency < 0.7:
        warnings.append(
            f"the data sheet's Kt is {efficiency:.2f} × Ke (gearbox loss at stall): the model's times (K = Ke) "
            "are optimistic, the constant-torque rule with Kt is the pessimistic bound"
        )
    for label, value in (("current source", t_current), ("bench supply", t_supply)):
        if math.isinf(value):
            warnings.append(f"with a {label} at {current:g} A / {voltage:g} V the target speed is never reached")
    return {
        "spin_up_constant_torque": Figure("spin-up, constant torque (seed's rule)", t_constant, "s"),
        "spin_up_current_source": Figure("spin-up, current source with friction", t_current, "s"),
        "spin_up_bench_supply": Figure(f"spin-up, bench supply {voltage:g} V / {current:g} A", t_supply, "s"),
        "crossover_speed": Figure("CC→CV crossover speed (V − R·i)/K", crossover, "rad/s"),
        "final_speed": Figure(f"final speed at {voltage:g} V", w_supply_final, "rad/s"),
        "mechanical_time_constant": Figure("rig τm = J·R/(K² + R·b)", rig.mechanical_time_constant, "s"),
        "coast_time": Figure("coast from target speed to rest", t_coast, "s"),
    }


def _encoder_section(
    motor: Motor, rig: MotorParams, times: dict[str, Figure], *, target_speed: float, torque: float,
    log_period: float, voltage: float, warnings: list[str],
) -> dict[str, Figure]:
    """Section ``encoder``: count rates and samples against the log period (``times`` from :func:`_times_section`).

    Appends warnings for too few counts per log period or too few samples during the spin-up.
    """
    t_constant = times["spin_up_constant_torque"].value
    t_supply = times["spin_up_bench_supply"].value
    counts_per_rad = motor.cpr / (2 * math.pi)
    rate_target = target_speed * counts_per_rad
    rate_top = times["final_speed"].value * counts_per_rad
    counts_target = rate_target * log_period
    # Count samples on the slower (pessimistic) estimate: the model's times use K = Ke, optimistic
    # where the gearbox loses torque (the data sheet's Kt < Ke).
    t_spin = max(t for t in (t_supply, t_constant) if math.isfinite(t)) if math.isfinite(t_constant) else t_supply
    samples = t_spin / log_period
    # Counts in the first log period from rest (θ = ½·α·t² with the data sheet's torque, at most
    # the target speed's rate): how well the start is resolved.
    alpha_rig = (torque - rig.Tf) / rig.J
    counts_first = min(0.5 * max(alpha_rig, 0.0) * log_period**2, target_speed * log_period) * counts_per_rad
    if counts_target < MIN_COUNTS_PER_PERIOD:
        warnings.append(
            f"only {counts_target:.3g} encoder counts per {log_period * 1e3:g} ms log period at the target speed: "
            "log encoder tick times instead (seed 1 'First Motor Test') or log less often"
        )
    if samples < MIN_SAMPLES_IN_SPIN_UP:
        warnings.append(
            f"only {samples:.3g} log samples during the {t_spin:.3g} s spin-up: too few to resolve the acceleration"
        )
    return {
        "cpr": Figure("encoder counts per output revolution", motor.cpr, "counts"),
        "rate_target": Figure("count rate at target speed", rate_target, "counts/s"),
        "rate_top": Figure(f"count rate at {voltage:g} V free speed", rate_top, "counts/s"),
        "log_period": Figure("log period", log_period, "s"),
        "counts_per_period": Figure("counts per log period at target speed", counts_target, "counts"),
        "counts_first_period": Figure("counts in the first log period from rest", counts_first, "counts"),
        "samples_in_spin_up": Figure("log samples during the spin-up", samples, "1"),
    }


def _sensors_section(
    *, torque: float, current: float, voltage: float, shunt_resistance: float, lever_arm: float | None,
    scale_capacity: float | None, warnings: list[str],
) -> dict[str, Figure]:
    """Section ``sensors``: the INA219's bus and current ranges, and the scale's range when given.

    Appends warnings for a supply above the INA219's bus limit, a current beyond its shunt range and
    a scale reading above the scale's capacity.
    """
    shunt_range = INA219_SHUNT_MAX / shunt_resistance
    if voltage > INA219_BUS_MAX:
        warnings.append(
            f"supply {voltage:g} V exceeds the INA219's {INA219_BUS_MAX:g} V bus limit "
            "(seed 1: a higher voltage fried the sensor)"
        )
    if current > shunt_range:
        warnings.append(
            f"drive current {current:g} A exceeds the INA219 range ±{shunt_range:.3g} A "
            f"with a {shunt_resistance:g} Ω shunt: the current reading saturates"
        )
    sensors = {
        "bus_voltage": Figure("supply voltage (INA219 bus, max 16 V)", voltage, "V"),
        "shunt_range": Figure("INA219 current range (±0.32 V / shunt)", shunt_range, "A"),
        "drive_current": Figure("drive current", current, "A"),
    }
    if lever_arm is not None:
        require_positive(lever_arm=lever_arm)
        reading = torque / (STANDARD_GRAVITY * lever_arm)
        sensors["scale_reading"] = Figure("scale reading at the drive torque", reading, "kg")
        if scale_capacity is not None:
            require_positive(scale_capacity=scale_capacity)
            sensors["scale_capacity"] = Figure("scale capacity", scale_capacity, "kg")
            if reading > scale_capacity:
                warnings.append(
                    f"the drive torque reads {reading:.3g} kg on the scale at {lever_arm:g} m, "
                    f"above its {scale_capacity:g} kg capacity: lengthen the arm or lower the current"
                )
    return sensors


# ---- identification logs: what a log could tell (Cramér–Rao bound) -----------------------------
#: Candidate designs of an identification log: (sample rate [Hz], hold range of the levels [s]).
LOG_DESIGNS = ((1000.0, (0.05, 0.3)), (10000.0, (0.05, 0.3)), (10000.0, (0.3, 1.0)))


def identification_bound(params: MotorParams, *, rate: float, hold: tuple[float, float], duration: float = 1.0,
                         voltage: float = 12.0, cpr: float = 560.0, current_noise: float = 0.02,
                         voltage_noise: float = 0.02, seed: int = 0) -> dict[str, float]:
    """Cramér–Rao bound of (K, R, L, J, b, Tf) for a log of random held levels switching between samples.

    Levels uniform in ±``voltage`` held uniform(``hold``) seconds, switching mid-interval, sampled at
    ``rate`` for ``duration``; current noise [A], logged voltage noise [V], a ``cpr``-count encoder.
    The bound counts the held levels and switch instants as nuisance parameters
    (:func:`motorlab.estimation.held_input.cramer_rao`), at the model ``params``. Returns the relative bound
    σ/value per parameter.
    """
    import numpy as np

    from motorlab.estimation import held_input
    from motorlab.estimation import output_error as _oe

    rng = np.random.default_rng(seed)
    dt = 1.0 / rate
    n = round(duration / dt) + 1
    first = [0]
    while True:
        nxt = first[-1] + max(2, round(rng.uniform(*hold) / dt))
        if nxt >= n - 2:
            break
        first.append(nxt)
    first_arr = np.array(first)
    levels = rng.uniform(-voltage, voltage, first_arr.size)
    count = np.diff(np.concatenate([first_arr, [n]]))
    seg = np.repeat(np.arange(first_arr.size), count)
    p = np.array([params.K, params.R, params.L, params.J, params.b, params.Tf])
    held = held_input.HeldInput(first_arr, levels, count, voltage_noise)
    log = _oe.prepare_log(dt * np.arange(n), levels[seg], np.zeros(n), np.zeros(n), resolution=2 * math.pi / cpr)
    model = held_input.HeldMotorModel([log], [held], free_switch=True)
    fractions = [np.full(first_arr.size - 1, 0.5)]
    states, theta = _oe.simulate(model.plant(p), model.drive(np.concatenate([p, levels]), log), dt,
                                 switches=(first_arr[1:] - 1, fractions[0], levels[:-1]))
    q = 2 * math.pi / cpr
    log = _oe.prepare_log(log.time, levels[seg], np.floor(theta / q + 0.5) * q, states[:, 0], resolution=q)
    model = held_input.HeldMotorModel([log], [held], free_switch=True)
    scale = np.maximum(np.abs(p), 1e-12)
    z0, lo, hi, sc = model.start_and_bounds(p, 1e-3 * scale, 1e3 * scale, scale, fractions)
    fit = _oe.fit_output_error(model, [log], z0, lower=lo, upper=hi, scale=sc,
                               sigma={"position": q / math.sqrt(12.0), "current": current_noise},
                               current_noise=current_noise, max_nfev=0)
    bound = held_input.cramer_rao(fit, [log], 6)
    return {name: float(b / v) for name, b, v in zip(("K", "R", "L", "J", "b", "Tf"), bound, p, strict=True)}


@threadpool_limits.wrap(limits=1, user_api="blas")
def plan_identification_log(params: MotorParams, *, target: float = 0.01, **options: Any) -> dict[str, Any]:
    """Recommend sample rate, excitation and length of an identification log from its Cramér–Rao bound.

    Each design of :data:`LOG_DESIGNS` is scored by the bound of a 1 s log; the bound shrinks as
    1/√length, so the length that brings every parameter's relative bound to ``target`` is
    (worst relative bound / target)² seconds. The design needing the shortest log is recommended.
    ``options`` go to :func:`identification_bound` (voltage, cpr, noises).

    Returns
    -------
    dict
        ``designs`` (rate, hold, relative bound per parameter, length needed [s]) and
        ``recommendation`` (a sentence).
    """
    if not (math.isfinite(target) and 0 < target < 1):
        raise OptionError(f"target must lie strictly between 0 and 1, got {target}")
    designs: list[dict[str, Any]] = []
    for rate, hold in LOG_DESIGNS:
        rel = identification_bound(params, rate=rate, hold=hold, **options)
        worst = max(rel, key=lambda k: rel[k])
        designs.append({"rate_hz": rate, "hold_s": list(hold), "relative_bound_1s": rel,
                        "limiting": worst, "length_s": (rel[worst] / target) ** 2})
    best = min(designs, key=lambda d: d["length_s"])
    text = (f"log at {best['rate_hz']:g} Hz with levels held {best['hold_s'][0]:g}–{best['hold_s'][1]:g} s for "
            f"{max(best['length_s'], 1.0):.3g} s: every parameter to {100 * target:g} % (1σ, Cramér–Rao; "
            f"{best['limiting']} limits)")
    return {"designs": designs, "recommendation": text}
