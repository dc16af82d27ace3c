"""The brushed DC motor model and the figures derived from it.

Equations (all quantities at the shaft whose encoder is counted, SI units)::

    L·di/dt = V − R·i − K·ω                       (4) of seed 1
    J·dω/dt = K·i − b·ω − Tf·sgn(ω)               (3) of seed 1 plus Coulomb friction
    τ = K·i,  e = K·ω                              (1), (2): Kt = Ke = K in SI

with stiction: at rest the shaft stays at rest while |K·i| ≤ Tf (static = Coulomb level).
Simulation lives in :mod:`motorlab.model.simulate` (every drive, events located exactly) and
:mod:`motorlab.estimation.simulator` (the fits' fast one); this module holds the parameters, the closed forms and
the one exact step of the linear equation both simulators take between events: the φ functions of
the zero-order hold (:func:`phi_functions`), a held step (:class:`HeldStep`) and its propagation
over many steps (:func:`propagate`).
"""

from __future__ import annotations

import cmath
import math
from dataclasses import asdict, dataclass, field, replace
from typing import Any

import numpy as np
from scipy.linalg import lapack

from motorlab.errors import OptionError
from motorlab.thermal.network import ThermalModel
from motorlab.units import SI_UNITS

PARAMETER_NAMES = ("K", "R", "L", "J", "b", "Tf")
#: Largest supply voltage [V] the derived figures accept. Brushed DC gearmotors of the seeds run on
#: 12 V; even industrial ones stay below a few hundred volts. Far beyond it power (∝ V²) overflows a
#: float (``--voltage 1e300`` printed overflow warnings and infinite figures).
MAX_VOLTAGE = 1000.0


def check_voltage(voltage: float) -> float:
    """Return ``voltage`` [V] if it is finite and |V| ≤ :data:`MAX_VOLTAGE`, else raise :class:`OptionError`."""
    if not (isinstance(voltage, int | float) and math.isfinite(voltage) and abs(voltage) <= MAX_VOLTAGE):
        raise OptionError(
            f"the supply voltage (--voltage) must be a finite number of at most {MAX_VOLTAGE:g} V in magnitude, "
            f"got {voltage!r} V (no brushed DC gearmotor runs on more)"
        )
    return float(voltage)


@dataclass(frozen=True)
class MotorParams:
    """Parameters of a brushed DC (gear)motor at the shaft whose encoder is counted.

    Parameters
    ----------
    K
        Back-EMF / torque constant [V·s/rad] = [N·m/A].
    R
        Winding (terminal) resistance [Ω].
    L
        Winding inductance [H].
    J
        Moment of inertia, everything rigidly coupled to the shaft [kg·m²].
    b
        Viscous friction [N·m·s/rad].
    Tf
        Coulomb (and static) friction torque [N·m].
    thermal
        Optional :class:`~motorlab.thermal.network.ThermalModel`: the winding heats, R and K drift with its
        temperatures, and K and R above are their values at 25 °C. Without it (the default) nothing
        changes with temperature.
    """

    K: float
    R: float
    L: float
    J: float
    b: float = 0.0
    Tf: float = 0.0
    thermal: ThermalModel | None = field(default=None, kw_only=True)

    def __post_init__(self) -> None:
        for name in PARAMETER_NAMES:
            value = getattr(self, name)
            if not math.isfinite(value):
                raise OptionError(f"motor parameter {name} = {value} is not finite")
        for name in ("K", "R", "J"):
            if getattr(self, name) <= 0:
                raise OptionError(f"motor parameter {name} must be positive, got {getattr(self, name)}")
        for name in ("L", "b", "Tf"):
            if getattr(self, name) < 0:
                raise OptionError(f"motor parameter {name} must not be negative, got {getattr(self, name)}")
        if self.thermal is not None and not isinstance(self.thermal, ThermalModel):
            raise OptionError(f"motor parameter thermal must be a ThermalModel, got {self.thermal!r}")

    # ---- construction -----------------------------------------------------------------------
    @classmethod
    def from_dict(cls, values: dict[str, Any]) -> MotorParams:
        """From ``{"K": 0.37, ...}`` or from an ``analyze --json`` style ``{"K": {"value": ...}}``."""
        kwargs = {}
        for name in PARAMETER_NAMES:
            if name in values:
                v = values[name]
                kwargs[name] = float(v["value"] if isinstance(v, dict) else v)
        missing = [n for n in ("K", "R", "J") if n not in kwargs]
        if missing:
            raise OptionError("motor parameters missing: " + ", ".join(missing))
        kwargs.setdefault("L", 0.0)
        thermal = values.get("thermal")
        return cls(**kwargs, thermal=ThermalModel.from_dict(thermal) if isinstance(thermal, dict) else None)

    def to_dict(self) -> dict[str, float]:
        """Plain dict of SI values of K, R, L, J, b, Tf (R and K at 25 °C with a thermal model; its
        figures are ``thermal.to_dict()``)."""
        out = asdict(self)
        out.pop("thermal", None)
        return out

    def at_temperature(self, winding: float, case: float | None = None) -> MotorParams:
        """The parameters at a winding (and case) temperature [°C], without a thermal model.

        R = R₂₅·(1 + α·(T_w − 25 °C)) and K = K₂₅·(1 + β·(T_c − 25 °C)) (``case`` defaults to ``winding``);
        a model without heat is returned unchanged.
        """
        if self.thermal is None:
            return self
        tc = winding if case is None else case
        return replace(self, R=self.R * self.thermal.resistance_factor(winding),
                       K=self.K * self.thermal.constant_factor(tc), thermal=None)

    def units(self) -> dict[str, str]:
        """SI unit of each parameter."""
        return {name: SI_UNITS[name] for name in PARAMETER_NAMES}

    def with_load(self, inertia: float, *, ratio: float = 1.0, friction: float = 0.0) -> MotorParams:
        """Add a load inertia turning ``ratio`` times faster than this shaft (reflected as J·N²).

        Parameters
        ----------
        inertia
            Load inertia on its own shaft [kg·m²].
        ratio
            Load speed / shaft speed (25 for the seed's 25:1 step-up to the flywheel) [-].
        friction
            Extra viscous friction at the load shaft [N·m·s/rad], reflected as b·N².
        """
        if inertia < 0 or ratio <= 0:
            raise OptionError("load inertia must be ≥ 0 and gear ratio > 0")
        return replace(self, J=self.J + inertia * ratio**2, b=self.b + friction * ratio**2)

    def scaled(self, **changes: Any) -> MotorParams:
        """A copy with some parameters replaced (e.g. ``b=2*p.b`` for a worn unit)."""
        return replace(self, **changes)

    # ---- time constants ---------------------------------------------------------------------
    @property
    def electrical_time_constant(self) -> float:
        """τe = L/R [s]."""
        return self.L / self.R

    @property
    def mechanical_time_constant(self) -> float:
        """τm = J·R/(K² + R·b) [s]: the speed time constant with the winding shorted through R."""
        return self.J * self.R / (self.K**2 + self.R * self.b)

    # ---- steady state at a supply voltage -----------------------------------------------------
    def free_speed(self, voltage: float) -> float:
        """Steady no-load speed ω = (K·V − R·Tf)/(K² + R·b) [rad/s] (0 if V cannot break away)."""
        w = (self.K * abs(voltage) - self.R * self.Tf) / (self.K**2 + self.R * self.b)
        return math.copysign(max(w, 0.0), voltage)

    def free_current(self, voltage: float) -> float:
        """Steady no-load current i = (b·ω + Tf)/K [A] (the stall current if the motor cannot turn)."""
        w = self.free_speed(voltage)
        if w == 0:
            return voltage / self.R
        return math.copysign((self.b * abs(w) + self.Tf) / self.K, voltage)

    def stall_current(self, voltage: float) -> float:
        """i = V/R [A]."""
        return voltage / self.R

    def stall_torque(self, voltage: float) -> float:
        """Shaft torque at stall, K·V/R − Tf [N·m] (electromagnetic torque minus Coulomb friction)."""
        return math.copysign(max(self.K * abs(voltage) / self.R - self.Tf, 0.0), voltage)

    def steady_current(self, voltage: float, speed: float) -> float:
        """Winding current at steady speed ω: i = (V − K·ω)/R [A]."""
        return (voltage - self.K * speed) / self.R

    def curves(self, voltage: float, *, points: int = 201) -> dict[str, np.ndarray]:
        """Torque–speed, current, power and efficiency curves at ``voltage`` (motoring quadrant).

        Returns
        -------
        dict
            ``speed`` [rad/s] from 0 to free speed, ``torque`` shaft output [N·m], ``current`` [A],
            ``power`` mechanical output [W], ``efficiency`` output/input [-].

        Raises
        ------
        OptionError
            A voltage that is not finite or exceeds :data:`MAX_VOLTAGE` in magnitude.
        """
        v = abs(check_voltage(voltage))
        w_free = self.free_speed(v)
        speed = np.linspace(0.0, w_free, points)
        current = (v - self.K * speed) / self.R
        torque = np.clip(self.K * current - self.b * speed - self.Tf, 0.0, None)
        power = torque * speed
        p_in = v * current
        with np.errstate(divide="ignore", invalid="ignore"):
            efficiency = np.where(p_in > 0, power / p_in, 0.0)
        return {"speed": speed, "torque": torque, "current": current, "power": power, "efficiency": efficiency}

    def peak_power(self, voltage: float) -> tuple[float, float]:
        """Maximum mechanical output power [W] and the speed at which it occurs [rad/s].

        Notes
        -----
        P(ω) = (K·(V − K·ω)/R − b·ω − Tf)·ω is a parabola: its peak is at ω = (K·V/R − Tf)/(2·(K²/R + b)).
        """
        v = abs(voltage)
        a = self.K**2 / self.R + self.b
        c = self.K * v / self.R - self.Tf
        if c <= 0:
            return 0.0, 0.0
        w = c / (2 * a)
        return c * w - a * w * w, w

    def peak_efficiency(self, voltage: float) -> tuple[float, float]:
        """Maximum efficiency [-] and the speed at which it occurs [rad/s] (numerically, on a fine grid)."""
        c = self.curves(voltage, points=4001)
        k = int(np.argmax(c["efficiency"]))
        return float(c["efficiency"][k]), float(c["speed"][k])

    def figures(self, voltage: float) -> dict[str, tuple[float, str]]:
        """The derived figures at ``voltage`` [V], each as (value, SI unit), for tables and reports.

        Raises
        ------
        OptionError
            A voltage that is not finite or exceeds :data:`MAX_VOLTAGE` in magnitude.
        """
        check_voltage(voltage)
        peak_p, w_p = self.peak_power(voltage)
        peak_e, w_e = self.peak_efficiency(voltage)
        return {
            "stall torque": (self.stall_torque(voltage), "N*m"),
            "stall current": (self.stall_current(voltage), "A"),
            "free speed": (self.free_speed(voltage), "rad/s"),
            "free current": (self.free_current(voltage), "A"),
            "electrical time constant": (self.electrical_time_constant, "s"),
            "mechanical time constant": (self.mechanical_time_constant, "s"),
            "peak power": (peak_p, "W"),
            "speed at peak power": (w_p, "rad/s"),
            "peak efficiency": (peak_e, "1"),
            "speed at peak efficiency": (w_e, "rad/s"),
        }


def feedforward_from_params(p: MotorParams) -> dict[str, float]:
    """WPILib-style feedforward gains from motor parameters.

    Notes
    -----
    Steady state and acceleration of the model with L neglected:
    V = R·Tf/K·sgn(ω) + (K + R·b/K)·ω + R·J/K·α, so kS = R·Tf/K [V], kV = K + R·b/K [V·s/rad],
    kA = R·J/K [V·s²/rad].
    """
    return {"kS": p.R * p.Tf / p.K, "kV": p.K + p.R * p.b / p.K, "kA": p.R * p.J / p.K}


def params_from_feedforward(
    kS: float, kV: float, kA: float, *, R: float, K: float | None = None, L: float = 0.0
) -> MotorParams:
    """(K, R, J, b, Tf) from (kS, kV, kA) and the winding resistance R.

    Notes
    -----
    Inverting kS = R·Tf/K, kV = K + R·b/K, kA = R·J/K: with K known, Tf = kS·K/R,
    b = (kV − K)·K/R and J = kA·K/R. kV alone cannot separate K from b; without K the viscous
    friction is taken as zero (K = kV), which callers must say when they report b.
    """
    k = kV if K is None else K
    return MotorParams(K=k, R=R, L=L, J=kA * k / R, b=max((kV - k) * k / R, 0.0), Tf=max(kS * k / R, 0.0))


# --------------------------------------------------------------------------------------------------
# The exact zero-order-hold step of the linear equation x' = A·x + b·u (between friction events)
# --------------------------------------------------------------------------------------------------


def phi_functions(z: np.ndarray | complex | float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """e^z, φ₁(z) = (e^z − 1)/z and φ₂(z) = (e^z − 1 − z)/z², element by element (real or complex).

    With the eigenvalues λ of A and z = λ·τ: e^{Aτ} = P·e^{z}·P⁻¹, ∫₀^τ e^{As} ds = P·τφ₁(z)·P⁻¹ and
    ∫₀^τ∫₀^s e^{Ar} dr ds = P·τ²φ₂(z)·P⁻¹ (the held input's effect on the state and on the angle).
    Near z = 0 (a free integrator, a very slow mode) the series 1 + z/2 + z²/6 + z³/24 and
    1/2 + z/6 + z²/24 + z³/120 replace the forms that cancel (their error there is below 1e-15; the
    direct forms' just beyond |z| = 1e-3, below 1e-12).
    """
    z = np.asarray(z)
    small = np.abs(z) < PHI_SERIES
    if not small.any():  # the direct forms alone (the same numbers, without the series' work)
        em1 = np.expm1(z)
        return np.exp(z), em1 / z, (em1 - z) / (z * z)
    zs = np.where(small, 1.0, z)
    em1 = np.expm1(zs)
    phi1, phi2 = em1 / zs, (em1 - zs) / (zs * zs)
    if phi1.ndim == 0:
        series1, series2 = _phi_series(z)
        return np.exp(z), np.where(small, series1, phi1), np.where(small, series2, phi2)
    phi1[small], phi2[small] = _phi_series(z[small])  # the series where they are needed only (z³ costs)
    return np.exp(z), phi1, phi2


def phi_of(z: complex) -> tuple[complex, complex, complex]:
    """:func:`phi_functions` of one complex number in Python's arithmetic (the same forms and series, to rounding):
    the output-error simulator's fractional steps call it hundreds of times a fit, where numpy's calls on arrays of
    two elements cost more than the numbers."""
    e = cmath.exp(z)
    if abs(z) < PHI_SERIES:
        return (e, *_phi_series(z))
    x, y = z.real, z.imag
    # e^z − 1 without the cancellation near 0: (e^x − 1)·cos y − 2·sin²(y/2) + i·e^x·sin y
    em1 = complex(math.expm1(x) * math.cos(y) - 2.0 * math.sin(0.5 * y) ** 2, math.exp(x) * math.sin(y)) if y \
        else complex(math.expm1(x))
    return e, em1 / z, (em1 - z) / (z * z)


#: Below this |z| the series replace φ₁'s and φ₂'s direct forms.
PHI_SERIES = 1e-3


def _phi_series(z: Any) -> tuple[Any, Any]:
    """φ₁(z) ≈ 1 + z/2 + z²/6 + z³/24 and φ₂(z) ≈ 1/2 + z/6 + z²/24 + z³/120 (an array or a number)."""
    return 1.0 + z / 2.0 + z * z / 6.0 + z**3 / 24.0, 0.5 + z / 6.0 + z * z / 24.0 + z**3 / 120.0


@dataclass(frozen=True)
class HeldStep:
    """One step with a held input: x⁺ = Ad·x + bv·v + c, θ⁺ = θ + hx·x + hv·v + hc (one or two states)."""

    ad: np.ndarray
    bv: np.ndarray
    c: np.ndarray
    hx: np.ndarray
    hv: float
    hc: float


def first_order(a: float, u: np.ndarray) -> np.ndarray:
    """y with y_k = a·y_(k−1) + u_k along axis 0 (y_(−1) = 0): ``scipy.signal.lfilter([1], [1, −a], u, axis=0)``.

    Solved as the unit lower bidiagonal system it is (LAPACK ``dtbtrs``: the same forward
    substitution). The feedforward model has one state, so its fits never import ``scipy.signal``
    (which imports ``scipy.stats``: 0.7 s of every ``analyze feedforward``); the motor model's
    two-state recursion stays with lfilter.
    """
    y = np.array(u, dtype=float, order="F")  # a copy: the solve overwrites it
    if y.shape[0] == 0:
        return y
    rows = y.reshape(y.shape[0], -1, order="F")
    band = np.empty((2, rows.shape[0]))
    band[0], band[1] = 1.0, -a  # band[k, j] = A[j + k, j]
    x, info = lapack.dtbtrs(band, rows, uplo="L", diag="U", overwrite_b=1)
    if info != 0:
        raise ValueError(f"dtbtrs failed (info {info})")
    return x.reshape(y.shape, order="F")


def recursion(ad: np.ndarray, x0: np.ndarray, e: np.ndarray) -> np.ndarray:
    """x_0 = x0 and x_(k+1) = Ad·x_k + e_k for k < M, for several sequences at once (one or two states).

    ``x0`` is (n, C) and ``e`` (n, C, M), time last: C sequences of the same recursion (a simulation, or the
    sensitivities of one to C parameters). Returns x (n, C, M + 1). Run as a rational filter in z⁻¹ (one or two
    poles); the initial state enters as an input at step −1, so every sequence starts exactly at its x0. ``e`` is
    overwritten.
    """
    n, m = e.shape[0], e.shape[-1]
    if n == 1:
        u = np.empty((m + 1, e.shape[1]))
        u[0] = x0[0]
        u[1:] = e[0].T
        return first_order(float(ad[0, 0]), u).T[None]  # lfilter([0, 1], [1, −a], e)[1:]
    from scipy import signal

    (a11, a12), (a21, a22) = ad.tolist()
    den = [1.0, -(a11 + a22), a11 * a22 - a12 * a21]
    # X0 = z⁻¹[(1 − a22 z⁻¹)E0 + a12 z⁻¹ E1]/det,  X1 = z⁻¹[a21 z⁻¹ E0 + (1 − a11 z⁻¹)E1]/det with
    # E = (x0, e_0, …, e_(M−1), 0): both rows in one array, one lfilter call
    u = np.zeros((2, e.shape[1], m + 2))
    u[:, :, 1] = x0
    u[:, :, 2:] = e
    if m:
        e0, e1 = e  # the E's kept in front: E[k − 1] beside E[k]
        p0 = u[0, :, 1:-1]
        p1 = u[1, :, 1:-1]
        e0 += -a22 * p0 + a12 * p1
        e1 += -a11 * p1 + a21 * p0
        u[:, :, 2:] = e
    return signal.lfilter([1.0], den, u, axis=-1)[:, :, 1:]


def propagate(step: HeldStep, x0: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """States x_0..x_M and angle increments for held inputs v_0..v_{M-1}, starting from x0: the one
    propagator of the motor equation (both simulators).

    The recursion x⁺ = Ad·x + e with e = bv·v + c is :func:`recursion`.
    """
    e = np.empty((x0.size, 1, v.size))
    for row, (bv, c) in enumerate(zip(step.bv.tolist(), step.c.tolist(), strict=True)):
        np.multiply(v, bv, out=e[row, 0])
        e[row, 0] += c
    x = np.ascontiguousarray(recursion(step.ad, x0[:, None], e)[:, 0].T)
    dtheta = x[:-1] @ step.hx + step.hv * v + step.hc
    return x, dtheta
