"""The two values every controller design passes around: the plant's feedforward and the PID gains.

Kept apart from :mod:`motorlab.control.design` (which designs gains) and
:mod:`motorlab.control.simulation` (which runs them), so that neither imports the other's module for
its types.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from motorlab.errors import OptionError

LOOPS = ("velocity", "position")

#: SysId's thresholds: below this kA [V·s²/unit] acceleration "costs no effort" and the LQR is
#: numerically meaningless (FeedbackAnalysis.cpp special-cases it the same way).
KA_NEGLIGIBLE = 1e-7


@dataclass(frozen=True)
class Feedforward:
    """WPILib ``SimpleMotorFeedforward`` constants: V = kS·sgn(v) + kV·v + kA·a.

    Parameters
    ----------
    kS
        Static (Coulomb) friction voltage [V].
    kV
        Velocity constant [V·s/rad] (or V·s per length unit in use).
    kA
        Acceleration constant [V·s²/rad] (or V·s² per length unit in use).
    """

    kS: float
    kV: float
    kA: float

    def __post_init__(self) -> None:
        for name in ("kS", "kV", "kA"):
            if not math.isfinite(getattr(self, name)):
                raise OptionError(f"{name} = {getattr(self, name)} is not finite")
        for name in ("kS", "kV", "kA"):
            if getattr(self, name) < 0:
                raise OptionError(f"{name} must not be negative, got {getattr(self, name)}")

    def check_plant(self) -> Feedforward:
        """Return self if it can describe a motor (kV > 0, kA > 0), else raise :class:`OptionError`."""
        if not self.kV > 0:
            raise OptionError(f"kV must be positive, got {self.kV}")
        if not self.kA > 0:
            raise OptionError(f"kA must be positive, got {self.kA}")
        # Finite, with a time constant kA/kV that is a number: kV = 1e308 with kA = 1e-308 passes the
        # signs but gives τ = 0 and infinite matrix entries in the design.
        tau = self.kA / self.kV
        if not (math.isfinite(self.kV) and math.isfinite(self.kA) and math.isfinite(self.kS)):
            raise OptionError(f"kS, kV, kA must be finite, got {self.kS}, {self.kV}, {self.kA}")
        if not (tau > 0 and math.isfinite(1.0 / tau) and math.isfinite(1.0 / self.kA)):
            raise OptionError(f"kA/kV = {tau:g} s is not a motor's time constant (kV = {self.kV:g}, kA = {self.kA:g})")
        # Magnitudes no motor has (kA = 1e308 V·s²/rad, kV = 1e-300): refused here rather than
        # overflowing in the design and the simulation. τ up to a day (a negligible kA, τ → 0, is
        # SysId's special case and allowed); kV from 1e-12 and kS, kV, kA up to 1e12 in SI.
        if tau > 1e5:
            raise OptionError(f"kA/kV = {tau:.3g} s is not a motor's time constant (at most a day): "
                              f"kV = {self.kV:g}, kA = {self.kA:g}")
        if self.kV < 1e-12 or max(abs(self.kS), self.kV, self.kA) > 1e12:
            raise OptionError(f"kS = {self.kS:g}, kV = {self.kV:g}, kA = {self.kA:g} are beyond any motor's "
                              "(kV from 1e-12, each at most 1e12 in SI units)")
        return self

    def voltage(self, velocity: Any, acceleration: Any = 0.0) -> Any:
        """V = kS·sgn(v) + kV·v + kA·a [V]."""
        return self.kS * np.sign(velocity) + self.kV * np.asarray(velocity) + self.kA * np.asarray(acceleration)

    @property
    def time_constant(self) -> float:
        """τ = kA/kV [s], the open-loop velocity time constant."""
        return self.kA / self.kV

    def free_speed(self, voltage: float) -> float:
        """(V − kS)/kV, the steady speed at ``voltage`` [rad/s] (0 if V ≤ kS)."""
        return max(abs(voltage) - self.kS, 0.0) / self.kV

    def scaled(self, per_radian: float) -> Feedforward:
        """The same feedforward with lengths in a unit of which there are ``per_radian`` per radian."""
        return Feedforward(self.kS, self.kV / per_radian, self.kA / per_radian)

    def to_dict(self) -> dict[str, float]:
        """``{"kS", "kV", "kA"}``."""
        return {"kS": self.kS, "kV": self.kV, "kA": self.kA}


@dataclass(frozen=True)
class Gains:
    """PID gains in volts per unit of error, time-normalised.

    Parameters
    ----------
    loop
        ``"velocity"`` or ``"position"``.
    kP
        Proportional gain [V/(rad/s)] for velocity, [V/rad] for position.
    kI
        Integral gain [V/rad] for velocity, [V/(rad·s)] for position.
    kD
        Derivative gain [V·s²/rad] for velocity, [V·s/rad] for position.
    method
        ``"lqr"`` or ``"poles"``.
    period
        Controller period the gains were designed for [s].
    delay
        Measurement delay the gains compensate [s].
    settings
        Design settings (tolerances, rise time ...), for reports.
    """

    loop: str
    kP: float
    kI: float = 0.0
    kD: float = 0.0
    method: str = "lqr"
    period: float = 0.02
    delay: float = 0.0
    settings: dict[str, float] = field(default_factory=dict)

    def scaled(self, per_radian: float) -> Gains:
        """The same gains with lengths in a unit of which there are ``per_radian`` per radian."""
        return replace(self, kP=self.kP / per_radian, kI=self.kI / per_radian, kD=self.kD / per_radian)

    def to_dict(self) -> dict[str, float]:
        """``{"kP", "kI", "kD"}``."""
        return {"kP": self.kP, "kI": self.kI, "kD": self.kD}
