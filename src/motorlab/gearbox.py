"""The gearbox between the motor and the output shaft: ratio, efficiency, loss torque, shafts.

Every FTC motor is a gearmotor: its figures (catalogue stall torque and free speed, the FTC SDK's
encoder counts) are at the OUTPUT shaft, while the motor's electromagnetic torque K·i acts at the
MOTOR shaft. This module is the one place where quantities cross the gearbox.

Loss model (load-dependent efficiency plus a constant drag)
-----------------------------------------------------------
With N = motor speed / output speed, τ_in the torque the motor shaft delivers into the gearbox and
τ_out the torque the output shaft delivers to the load::

    motor drives the load (forward):   τ_out = η·N·τ_in − τ0·sgn(ω)
    load drives the motor (back-driven): N·τ_in = η_b·(τ_out + τ0·sgn(ω))

η is the load-dependent (mesh and bearing friction, proportional to the transmitted torque)
efficiency, η_b the same when power flows backwards, τ0 the load-independent (churning, seals,
windage) drag at the output. This split is the usual one: ISO/TR 14179-1 separates a gear unit's
power loss into load-dependent and no-load parts; gearmotor makers quote an efficiency at rated load
and warn that it falls at light load (F. Faulhaber, "A second look at gearbox efficiencies",
Machine Design 2002: "a basic rule ... for spur gears is a 10 % loss per engagement"; Citizen Micro
"Gear efficiency": 90 % per spur mesh, 0.9³ = 0.73 for three stages, "when used at a lower torque
the efficiency will drop significantly") — the constant drag τ0 is what makes it fall.

Shafts and units
----------------
- ``MotorParams`` of a gearmotor in motorlab are at the output shaft "through an ideal gearbox":
  K = N·K_m, J = N²·J_m, b = N²·b_m, Tf = N·Tf_m (:func:`reflect_to_output`), so K is the back-EMF
  constant Ke an output-shaft encoder sees, and torques are in units of the electromagnetic torque
  K·i reflected by N (η not applied).
- A :class:`Drivetrain` (those parameters, a :class:`Gearbox` and what hangs on the output) has two
  single-K equivalents, one per direction of power flow (:meth:`Drivetrain.forward`,
  :meth:`Drivetrain.backward`): dividing the output's equation of motion by η (or multiplying by
  η_b) leaves the motor's K·i untouched, so the simulator and every single-K analysis keep working,
  and only the load side is scaled.
- Physical torques at the output shaft are those figures times η (forward) or ÷ η_b (back-driven):
  the torque constant a lever at the output measures is Kt = η·K (:meth:`Drivetrain.output_figures`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from motorlab.errors import OptionError
from motorlab.model import MotorParams, check_voltage
from motorlab.results import Estimate


@dataclass(frozen=True)
class Gearbox:
    """A gearbox with losses.

    Parameters
    ----------
    ratio
        N = motor-shaft speed / output-shaft speed [-] (40 for a NeveRest 40).
    efficiency
        η when the motor drives the load: the share of the motor's torque × N reaching the output
        under load [-], 0 < η ≤ 1.
    back_efficiency
        η_b when the load drives the motor (a flywheel coasting down through the gearbox) [-];
        ``None``: the same as ``efficiency``.
    loss_torque
        τ0, the load-independent drag at the OUTPUT shaft [N·m] (≥ 0).
    output_inertia
        Inertia of the output-side gears and shaft, at the OUTPUT shaft [kg·m²] (≥ 0).
    """

    ratio: float = 1.0
    efficiency: float = 1.0
    back_efficiency: float | None = None
    loss_torque: float = 0.0
    output_inertia: float = 0.0

    def __post_init__(self) -> None:
        if not (math.isfinite(self.ratio) and self.ratio > 0):
            raise OptionError(f"gear ratio must be positive, got {self.ratio}")
        for name in ("efficiency", "back_efficiency"):
            value = getattr(self, name)
            if value is not None and not (math.isfinite(value) and 0 < value <= 1):
                raise OptionError(f"gearbox {name.replace('_', ' ')} must lie in (0, 1], got {value}")
        for name in ("loss_torque", "output_inertia"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0):
                raise OptionError(f"gearbox {name.replace('_', ' ')} must not be negative, got {value}")

    @property
    def eta_back(self) -> float:
        """η_b [-] (``efficiency`` when no separate back-driving efficiency is given)."""
        return self.efficiency if self.back_efficiency is None else self.back_efficiency

    @property
    def ideal(self) -> bool:
        """True for a lossless gearbox (η = η_b = 1, τ0 = 0)."""
        return self.efficiency == 1.0 and self.eta_back == 1.0 and self.loss_torque == 0.0

    def output_torque(self, motor_torque: Any) -> Any:
        """Forward: torque at the output [N·m] for a torque ``motor_torque`` at the motor shaft [N·m].

        τ_out = η·N·τ_in − τ0 (the shaft turning or about to turn in the driving direction).
        """
        return self.efficiency * self.ratio * np.asarray(motor_torque) - self.loss_torque

    def motor_torque(self, output_torque: Any) -> Any:
        """Forward, inverted: motor-shaft torque [N·m] needed for ``output_torque`` at the output [N·m]."""
        return (np.asarray(output_torque) + self.loss_torque) / (self.efficiency * self.ratio)

    def to_dict(self) -> dict[str, float]:
        """SI figures for ``truth.json`` and results."""
        return {
            "ratio": self.ratio,
            "efficiency": self.efficiency,
            "back_efficiency": self.eta_back,
            "loss_torque": self.loss_torque,
            "output_inertia": self.output_inertia,
        }


# ---- conversions between the motor shaft and the output shaft --------------------------------------
def speed_at_output(motor_speed: Any, ratio: float) -> Any:
    """ω_out = ω_motor / N [rad/s]."""
    return np.asarray(motor_speed) / ratio


def speed_at_motor(output_speed: Any, ratio: float) -> Any:
    """ω_motor = N·ω_out [rad/s]."""
    return np.asarray(output_speed) * ratio


def reflect_to_output(motor: MotorParams, ratio: float) -> MotorParams:
    """Motor-shaft parameters seen from the output through an IDEAL gearbox of ratio N.

    K → N·K, J → N²·J, b → N²·b, Tf → N·Tf; R and L are electrical and do not change.
    """
    if not ratio > 0:
        raise OptionError(f"gear ratio must be positive, got {ratio}")
    return replace(motor, K=motor.K * ratio, J=motor.J * ratio**2, b=motor.b * ratio**2, Tf=motor.Tf * ratio)


def refer_to_motor(output: MotorParams, ratio: float) -> MotorParams:
    """The inverse of :func:`reflect_to_output`: output-shaft parameters referred to the motor shaft."""
    return reflect_to_output(output, 1.0 / ratio)


@dataclass(frozen=True)
class Drivetrain:
    """A gearmotor and its load: motor parameters (output shaft, ideal gearbox), gearbox, load.

    Parameters
    ----------
    motor
        The motor's K, R, L, J, b, Tf reflected to the output through an ideal gearbox
        (:func:`reflect_to_output`).
    gearbox
        The gearbox's losses (its ``ratio`` is informational here: ``motor`` is already reflected).
    load_inertia, load_viscous, load_coulomb
        What hangs on the output shaft, at the output shaft: inertia [kg·m²], viscous friction
        [N·m·s/rad], Coulomb friction [N·m] (a flywheel behind a step-up, reflected).
    """

    motor: MotorParams
    gearbox: Gearbox = field(default_factory=Gearbox)
    load_inertia: float = 0.0
    load_viscous: float = 0.0
    load_coulomb: float = 0.0

    @property
    def output_inertia(self) -> float:
        """Inertia on the output side [kg·m²] (gearbox output stage + load)."""
        return self.gearbox.output_inertia + self.load_inertia

    @property
    def drag_coulomb(self) -> float:
        """Constant drag on the output side [N·m] (gearbox τ0 + load Coulomb friction)."""
        return self.gearbox.loss_torque + self.load_coulomb

    @property
    def switches(self) -> bool:
        """True when the two directions of power flow have different dynamics."""
        g = self.gearbox
        return not (g.efficiency == 1.0 and g.eta_back == 1.0)

    def forward(self) -> MotorParams:
        """Single-K equivalent while the motor drives the load (output-side terms ÷ η)."""
        eta = self.gearbox.efficiency
        m = self.motor
        return replace(m, J=m.J + self.output_inertia / eta, b=m.b + self.load_viscous / eta,
                       Tf=m.Tf + self.drag_coulomb / eta)

    def backward(self) -> MotorParams:
        """Single-K equivalent while the load drives the motor (output-side terms × η_b)."""
        eta = self.gearbox.eta_back
        m = self.motor
        return replace(m, J=m.J + self.output_inertia * eta, b=m.b + self.load_viscous * eta,
                       Tf=m.Tf + self.drag_coulomb * eta)

    def flow(self, current: Any, speed: Any, sign: Any) -> Any:
        """D: positive while the motor drives the load, negative while the load drives the motor.

        Notes
        -----
        With the motor side's net torque F_m = K·i − b·ω − Tf·s and the load side's drag
        F_l = τ_drag·s + b_l·ω, the shared acceleration makes the torque through the gearbox
        proportional to J_l·F_m + J_m·F_l in either direction of flow (both equivalents give the
        same sign), so D = s·(J_l·F_m + J_m·F_l) decides it without an algebraic loop.
        """
        m = self.motor
        s = np.asarray(sign, dtype=float)
        w = np.asarray(speed, dtype=float)
        f_m = m.K * np.asarray(current, dtype=float) - m.b * w - m.Tf * s
        f_l = self.drag_coulomb * s + self.load_viscous * w
        return s * (self.output_inertia * f_m + m.J * f_l)

    def output_figures(self, *, back_driven: bool = False) -> dict[str, float]:
        """Physical figures at the output shaft: torque constant Kt, J, b, Tf (and Ke = K).

        Forward: the single-K equivalent's torques × η (Kt = η·K); back-driven: ÷ η_b (a coasting
        load sees the motor's drag magnified by 1/η_b).
        """
        p = self.backward() if back_driven else self.forward()
        scale = 1.0 / self.gearbox.eta_back if back_driven else self.gearbox.efficiency
        return {"Kt": p.K * scale, "Ke": p.K, "J": p.J * scale, "b": p.b * scale, "Tf": p.Tf * scale}


def output_stall_torque(params: MotorParams, efficiency: float, voltage: float) -> float:
    """Stall torque at the output [N·m]: η·(K·V/R − Tf), with ``params`` the forward single-K model."""
    return efficiency * params.stall_torque(voltage)


def output_curves(
    params: MotorParams, efficiency: float, voltage: float, *, points: int = 201
) -> dict[str, np.ndarray]:
    """Torque–speed, current, power and efficiency at the OUTPUT shaft, gearbox included.

    ``params`` is the forward single-K model (every load-side loss ÷ η, as :meth:`Drivetrain.forward`
    and the analyses give it); the output torque is η times its torque, and so are the power and the
    overall efficiency. Speeds and currents are unchanged.
    """
    check_voltage(voltage)
    if not (math.isfinite(efficiency) and 0 < efficiency <= 1):
        raise OptionError(f"efficiency must lie in (0, 1], got {efficiency}")
    c = params.curves(voltage, points=points)
    return {**c, "torque": efficiency * c["torque"], "power": efficiency * c["power"],
            "efficiency": efficiency * c["efficiency"]}


def efficiency_estimate(
    kt: float, kt_stderr: float, ke: float, ke_stderr: float, *, note: str = ""
) -> Estimate:
    """η = Kt/Ke with the two relative errors added in quadrature.

    Parameters
    ----------
    kt, kt_stderr
        Torque constant at the output shaft (lever test) and its standard error [N·m/A].
    ke, ke_stderr
        Back-EMF constant at the same shaft (N·K_motor) and its standard error [V·s/rad].
    """
    if not (math.isfinite(ke) and ke > 0 and math.isfinite(kt)):
        return Estimate("efficiency", math.nan, math.nan, "1", False, "not determined: no usable Kt or Ke")
    value = kt / ke
    rel = math.hypot(kt_stderr / kt if kt else math.inf, ke_stderr / ke)
    stderr = abs(value) * rel if math.isfinite(rel) else math.nan
    return Estimate("efficiency", value, stderr, "1", math.isfinite(stderr),
                    note or "gearbox efficiency η = Kt(output, lever) / (N·Ke(motor, back-EMF))")


@dataclass(frozen=True)
class OutputCurves:
    """A gearmotor's curves at the output shaft: the forward single-K model and the efficiency η.

    Anything that plots ``curves(voltage)`` (:func:`motorlab.plot.plot_motor_curves`) draws it.
    """

    params: MotorParams
    efficiency: float = 1.0

    def curves(self, voltage: float, *, points: int = 201) -> dict[str, np.ndarray]:
        """:func:`output_curves` of this gearmotor."""
        return output_curves(self.params, self.efficiency, voltage, points=points)

    def stall_torque(self, voltage: float) -> float:
        """Output stall torque η·(K·V/R − Tf) [N·m]."""
        return output_stall_torque(self.params, self.efficiency, voltage)

    def peak_power(self, voltage: float) -> tuple[float, float]:
        """Peak output power [W] (η times the model's) and the speed at which it occurs [rad/s]."""
        power, speed = self.params.peak_power(voltage)
        return self.efficiency * power, speed
