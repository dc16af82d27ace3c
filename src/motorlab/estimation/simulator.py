"""The fast simulator of the output-error fits (:mod:`motorlab.estimation.output_error`): a linear plant with
Coulomb friction and stiction.

The optimisers of :mod:`motorlab.analyses.identify` and :mod:`motorlab.analyses.feedforward` simulate the same log
hundreds of times with changing parameters, so the simulator must take a few milliseconds for 30 000
samples. :mod:`motorlab.model.simulate` is general (several drives, crossovers); this one handles only what
the fits need: a voltage held over each sample (zero-order hold) driving a linear plant

    x' = A·x + b_V·V + b_F·s,      θ' = ω = x[w],      s = sgn(ω)

where ``x`` is (i, ω) for the full motor model or (ω) for the feedforward model, and s is the
friction sign. At rest the shaft stays at rest while the drive acceleration |(A·x + b_V·V)[w]| does not
exceed the friction level F = −b_F[w] (stiction at the Coulomb level).

Method
------
Between events (speed reaching zero, break-away) the plant is linear time-invariant with a held input,
so a stretch of samples is propagated exactly (matrix exponential of the augmented system) as a first-
or second-order recursion (:func:`motorlab.model.propagate`, the one propagator of both simulators).
An event is detected on the grid, its time inside the step found by linear interpolation of the
speed (or of the drive margin for a break-away), and the step finished in the new regime with two
fractional-step propagations. The located event time varies continuously with the parameters, so the
simulated outputs do too, which finite-difference Jacobians need; no smoothing of sgn(ω) is required.
"""

from __future__ import annotations

import cmath
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import linalg

from motorlab.model import HeldStep, phi_functions, phi_of, propagate, recursion

#: Kinds of the pieces of a simulation's trace (:func:`simulate`, :func:`sensitivities`).
RUN, SWITCH, EVENT = 0, 1, 2

#: Steps propagated at once after an event (doubling while nothing happens): a propagation costs ~70 µs of calls
#: whatever its length, and its samples ~5 ns each, so a long first chunk wastes less than short ones cost
#: (identify 35 % faster than from 64 on 1,200- to 20,000-sample logs).
_MIN_CHUNK = 512


@dataclass(frozen=True)
class StatePlant:
    """Continuous-time plant ``x' = A·x + b_V·V + b_F·sgn(ω)``.

    Parameters
    ----------
    a
        State matrix (n × n), n = 1 (ω) or 2 (i, ω) [1/s and mixed SI].
    b_drive
        Input vector of the applied voltage (n,).
    b_friction
        Input vector of the friction sign (n,); ``-b_friction[w]`` is the friction level F [rad/s²].
    w
        Index of the speed ω in the state.
    """

    a: np.ndarray
    b_drive: np.ndarray
    b_friction: np.ndarray
    w: int

    @property
    def n(self) -> int:
        return int(self.a.shape[0])

    @property
    def friction(self) -> float:
        return float(-self.b_friction[self.w])

    def same_as(self, other: StatePlant) -> bool:
        """Whether ``other`` has the same matrices (a parameter of a drive, not of the plant, was moved)."""
        return (self.w == other.w and np.array_equal(self.a, other.a) and np.array_equal(self.b_drive, other.b_drive)
                and np.array_equal(self.b_friction, other.b_friction))


def motor_plant(K: float, R: float, L: float, J: float, b: float, Tf: float) -> StatePlant:
    """The full model ``L·di/dt = V − R·i − K·ω``, ``J·dω/dt = K·i − b·ω − Tf·sgn(ω)``; state (i, ω)."""
    a = np.array([[-R / L, -K / L], [K / J, -b / J]])
    return StatePlant(a, np.array([1.0 / L, 0.0]), np.array([0.0, -Tf / J]), 1)


def feedforward_plant(kS: float, kV: float, kA: float) -> StatePlant:
    """The feedforward model ``V = kS·sgn(ω) + kV·ω + kA·α``; state (ω)."""
    return StatePlant(np.array([[-kV / kA]]), np.array([1.0 / kA]), np.array([-kS / kA]), 0)


def _regime(plant: StatePlant, s: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(A, b_V, const) of regime s: moving with sign s = ±1, or stuck (s = 0: ω frozen at 0)."""
    if s != 0:
        return plant.a, plant.b_drive, s * plant.b_friction
    a = plant.a.copy()
    a[plant.w, :] = 0.0
    a[:, plant.w] = 0.0
    bv = plant.b_drive.copy()
    bv[plant.w] = 0.0
    return a, bv, np.zeros(plant.n)


def _eig2(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Eigenvalues and eigenvectors (columns) of a real 2 × 2 matrix in closed form: what ``np.linalg.eig`` gives, up to
    each vector's scale and the order, in a tenth of its time (a fit decomposes each regime of every parameter vector
    it tries). The larger root without cancellation, the other from the determinant; each vector from the row of
    A − λI that determines it better."""
    (p, q), (r, t) = a.tolist()
    half = 0.5 * (p + t)
    root = cmath.sqrt(0.25 * (p - t) ** 2 + q * r)  # (λ₁ − λ₂)/2: no cancellation when p ≈ t
    if root.imag == 0.0:
        big = half + math.copysign(root.real, half)
        small = (p * t - q * r) / big if big != 0.0 else half - root.real
        lams: list[complex] = [complex(big), complex(small)]
    else:
        lams = [half + root, half - root]
    cols = []
    for lam in lams:
        one, two = (complex(q), lam - p), (lam - t, complex(r))
        cols.append(one if abs(one[0]) + abs(one[1]) >= abs(two[0]) + abs(two[1]) else two)
    vectors = np.array([[cols[0][0], cols[1][0]], [cols[0][1], cols[1][1]]])
    values = np.array(lams)
    if root.imag == 0.0:
        return values.real, vectors.real
    return values, vectors


class _Modal:
    """Eigen-decomposition of one regime's A for fast ZOH matrices at any step length.

    e^{Aτ} = P·e^{Λτ}·P⁻¹, ∫₀^τ e^{As} ds = P·τφ₁(Λτ)·P⁻¹ and ∫₀^τ∫₀^s e^{Ar} dr ds = P·τ²φ₂(Λτ)·P⁻¹ with
    φ₁, φ₂ of :func:`motorlab.model.phi_functions`: a few small numpy operations instead of a general
    matrix exponential (which dominated the run time at events). Near-repeated eigenvalues (critical
    damping, where P is ill-conditioned) fall back to :func:`scipy.linalg.expm`.
    """

    def __init__(self, plant: StatePlant, s: int):
        self.plant = plant
        self.s = s
        self._steps: dict[float, HeldStep] = {}
        a, self.bv, self.c = _regime(plant, s)
        self.a = a
        lam, vec = _eig2(a) if a.shape == (2, 2) else np.linalg.eig(a)
        spread = float(np.max(np.abs(lam))) if lam.size else 0.0
        self.ok = lam.size < 2 or bool(abs(lam[0] - lam[1]) > 1e-6 * spread)
        if self.ok:
            self.lam = lam
            self.vec = vec
            inv = np.linalg.inv(vec)
            self.pb = inv @ self.bv
            self.pc = inv @ self.c
            self.inv = inv
            self.row = vec[plant.w]
        # one state (the feedforward model): P = P⁻¹ = 1, so the products below reduce to products of floats
        self.scalar = self.ok and lam.size == 1 and bool(vec[0, 0] == 1.0 and self.inv[0, 0] == 1.0
                                                         and lam.imag[0] == 0)
        # two states (the motor model): the same sums of products written out in Python's complex numbers
        self.pair = self.ok and lam.size == 2
        if self.pair:
            self._lists = (lam.astype(complex).tolist(), vec.astype(complex).tolist(), inv.astype(complex).tolist(),
                           self.pb.astype(complex).tolist(), self.pc.astype(complex).tolist(),
                           self.row.astype(complex).tolist())

    def full_step(self, dt: float) -> HeldStep:
        """``discrete(dt)``, kept: every simulation of this plant on a dt grid takes the same full step."""
        step = self._steps.get(dt)
        if step is None:
            step = self._steps[dt] = self.discrete(dt)
        return step

    def discrete(self, tau: float) -> HeldStep:
        if not self.ok:
            return _discretise_expm(self.plant, self.s, tau)
        if self.scalar:
            return self._discrete_scalar(tau)
        if self.pair:
            return self._discrete_pair(tau)
        e, phi1, phi2 = phi_functions(self.lam * tau)
        vec, inv = self.vec, self.inv
        phi1 = tau * phi1
        phi2 = tau * tau * phi2
        ad = ((vec * e) @ inv).real
        bv = (vec @ (phi1 * self.pb)).real
        c = (vec @ (phi1 * self.pc)).real
        moving = 1.0 if self.s != 0 else 0.0
        hx = moving * ((self.row * phi1) @ inv).real
        hv = moving * float((self.row @ (phi2 * self.pb)).real)
        hc = moving * float((self.row @ (phi2 * self.pc)).real)
        return HeldStep(ad, bv, c, hx, hv, hc)

    def _discrete_pair(self, tau: float) -> HeldStep:
        """:meth:`discrete` of a two-state plant in Python's complex numbers: the same sums of products as the
        matrix form (to rounding, ``tests/estimation/test_simulator.py``), without the two dozen numpy calls on
        2 × 2 arrays that made it 80 µs (a fit locates hundreds of friction events and switches, each a few
        fractional steps)."""
        (l0, l1), ((v00, v01), (v10, v11)), ((i00, i01), (i10, i11)), (b0, b1), (c0, c1), (r0, r1) = self._lists
        e0, f0, g0 = phi_of(l0 * tau)
        e1, f1, g1 = phi_of(l1 * tau)
        f0, f1 = tau * f0, tau * f1
        g0, g1 = tau * tau * g0, tau * tau * g1
        ad = np.array([[(v00 * e0 * i00 + v01 * e1 * i10).real, (v00 * e0 * i01 + v01 * e1 * i11).real],
                       [(v10 * e0 * i00 + v11 * e1 * i10).real, (v10 * e0 * i01 + v11 * e1 * i11).real]])
        fb0, fb1, fc0, fc1 = f0 * b0, f1 * b1, f0 * c0, f1 * c1
        bv = np.array([(v00 * fb0 + v01 * fb1).real, (v10 * fb0 + v11 * fb1).real])
        c = np.array([(v00 * fc0 + v01 * fc1).real, (v10 * fc0 + v11 * fc1).real])
        if self.s == 0:
            return HeldStep(ad, bv, c, np.zeros(2), 0.0, 0.0)
        rf0, rf1 = r0 * f0, r1 * f1
        hx = np.array([(rf0 * i00 + rf1 * i10).real, (rf0 * i01 + rf1 * i11).real])
        hv = (r0 * g0 * b0 + r1 * g1 * b1).real
        hc = (r0 * g0 * c0 + r1 * g1 * c1).real
        return HeldStep(ad, bv, c, hx, hv, hc)

    def _coordinates(self, x: np.ndarray, v: float) -> tuple[complex, complex, complex, complex]:
        """(z₀, z₁, q₀, q₁): the state and the held input's effect in the modes, z = P⁻¹·x, q = P⁻¹·(b_V·v + c)."""
        _, _, ((i00, i01), (i10, i11)), (b0, b1), (c0, c1), _ = self._lists
        x0, x1 = float(x[0]), float(x[1])
        return i00 * x0 + i01 * x1, i10 * x0 + i11 * x1, b0 * v + c0, b1 * v + c1

    def flow(self, x: np.ndarray, v: float, tau: float) -> tuple[np.ndarray, float]:
        """``_flow(discrete(τ), x, v)``: the state and the angle's increment after τ [s] of the held input v. For a
        two-state plant from the modes directly, x(τ) = Σ_i p_i·(e^{λ_i τ}·z_i + τφ₁(λ_i τ)·q_i) and
        Δθ = Σ_i r_i·(τφ₁·z_i + τ²φ₂·q_i), z = P⁻¹·x, q = P⁻¹·(b_V·v + c), r = P's speed row (the same numbers
        to rounding, without the step's matrices: a drive switch inside a step and an event take a few)."""
        if not self.pair:
            return _flow(self.discrete(tau), x, v)
        (l0, l1), ((v00, v01), (v10, v11)), _, _, _, (r0, r1) = self._lists
        z0, z1, q0, q1 = self._coordinates(x, v)
        e0, f0, g0 = phi_of(l0 * tau)
        e1, f1, g1 = phi_of(l1 * tau)
        m0, m1 = e0 * z0 + tau * f0 * q0, e1 * z1 + tau * f1 * q1
        dth = (r0 * (tau * f0 * z0 + tau * tau * g0 * q0) + r1 * (tau * f1 * z1 + tau * tau * g1 * q1)).real \
            if self.s != 0 else 0.0
        return np.array([(v00 * m0 + v01 * m1).real, (v10 * m0 + v11 * m1).real]), dth

    def along(self, x: np.ndarray, v: float, weights: np.ndarray) -> Callable[[float], float] | None:
        """τ ↦ weights·x(τ), the state reached from ``x`` after τ [s] of the held input ``v``, for a two-state plant
        (None otherwise): the sum over the two modes of (weights·p_i)·(e^{λ_i τ}·z_i + τφ₁(λ_i τ)·(b_i·v + c_i)),
        z = P⁻¹·x, in Python's complex numbers. The same number as ``weights @ _flow(discrete(τ), x, v)[0]`` to
        rounding, without a step's matrices: an event's location asks for it up to ten times a step."""
        if not self.pair:
            return None
        (l0, l1), ((v00, v01), (v10, v11)), _, _, _, _ = self._lists
        w0, w1 = float(weights[0]), float(weights[1])
        a0, a1 = w0 * v00 + w1 * v10, w0 * v01 + w1 * v11  # weights·p_i
        z0, z1, q0, q1 = self._coordinates(x, v)

        def value(tau: float) -> float:
            e0, f0, _ = phi_of(l0 * tau)
            e1, f1, _ = phi_of(l1 * tau)
            return (a0 * (e0 * z0 + tau * f0 * q0) + a1 * (e1 * z1 + tau * f1 * q1)).real

        return value

    def _discrete_scalar(self, tau: float) -> HeldStep:
        """:meth:`discrete` of a one-state plant in floats: the same operations on the same numbers (numpy's exp,
        expm1 and power, then correctly rounded sums, products and quotients in the same order), so the same numbers
        bit for bit (``tests/estimation/test_simulator.py``), without two dozen numpy calls on arrays of one element
        (a fit locates hundreds of friction events, each a few fractional steps)."""
        z = float(self.lam.real[0]) * tau
        e = float(np.exp(z))
        if abs(z) < 1e-3:  # the series (a slow mode, a flywheel's; z = 0 when stuck), as phi_functions sums it
            cube = float(np.power(z, 3))
            phi1 = 1.0 + z / 2.0 + z * z / 6.0 + cube / 24.0
            phi2 = 0.5 + z / 6.0 + z * z / 24.0 + cube / 120.0
        else:
            em1 = float(np.expm1(z))
            phi1, phi2 = em1 / z, (em1 - z) / (z * z)
        phi1 = tau * phi1
        phi2 = tau * tau * phi2
        pb, pc = float(self.pb[0].real), float(self.pc[0].real)
        moving = 1.0 if self.s != 0 else 0.0
        return HeldStep(np.array([[e]]), np.array([phi1 * pb]), np.array([phi1 * pc]), np.array([moving * phi1]),
                        moving * (phi2 * pb), moving * (phi2 * pc))


#: Decompositions of the plants simulated lately, by regime and exact matrices: a fit simulates one
#: parameter vector many times (the residual, then the Jacobian's columns restarted in chunks, the
#: probes of smoothness), and the same matrices give the same eigenvectors, so each is computed once.
_MODALS: dict[tuple[int, int, bytes, bytes, bytes], _Modal] = {}
_MODALS_KEPT = 256


def modal_of(plant: StatePlant, s: int) -> _Modal:
    """The eigen-decomposition of regime s of ``plant`` (computed once for the same matrices)."""
    key = (s, plant.w, plant.a.tobytes(), plant.b_drive.tobytes(), plant.b_friction.tobytes())
    found = _MODALS.get(key)
    if found is None:
        own = StatePlant(plant.a.copy(), plant.b_drive.copy(), plant.b_friction.copy(), plant.w)
        found = _Modal(own, s)
        if len(_MODALS) >= _MODALS_KEPT:
            _MODALS.clear()
        _MODALS[key] = found
    return found


def moving_step(plant: StatePlant, tau: float) -> HeldStep:
    """ZOH matrices of the moving regime (s = +1) over a step τ [s] (the noise model's linearisation)."""
    return _Modal(plant, 1).discrete(tau)


def _discretise_expm(plant: StatePlant, s: int, tau: float) -> HeldStep:
    n = plant.n
    a, bv, c = _regime(plant, s)
    m = np.zeros((n + 3, n + 3))
    m[:n, :n] = a
    m[:n, n + 1] = bv
    m[:n, n + 2] = c
    if s != 0:  # θ' = ω (in the stuck regime ω = 0 and θ stays)
        m[n, plant.w] = 1.0
    phi = linalg.expm(m * tau)
    return HeldStep(
        phi[:n, :n], phi[:n, n + 1], phi[:n, n + 2], phi[n, :n], float(phi[n, n + 1]), float(phi[n, n + 2])
    )


def _flow(d: HeldStep, x: np.ndarray, v: float) -> tuple[np.ndarray, float]:
    """One (fractional) step."""
    return d.ad @ x + d.bv * v + d.c, float(d.hx @ x + d.hv * v + d.hc)


def _locate(fun: Callable[[float], float], f0: float, f1: float, *, iterations: int = 10) -> float:
    """Fraction of a step where ``fun`` (value f0 at 0, f1 at 1, opposite signs) crosses zero.

    Regula falsi with the Illinois modification: the first guess is the linear interpolation, and a
    few refinements on the continuous solution make the event time exact to far below a step, so the
    speed set to zero at a stop is not off by α·(interpolation error).
    """
    a, b, fa, fb = 0.0, 1.0, f0, f1
    if fa == 0.0:
        return 0.0
    if fb == fa or fa * fb > 0:
        return 1.0 if fa * fb > 0 else 0.0
    c = a
    side = 0
    tol = 1e-12 * (abs(f0) + abs(f1))
    for _ in range(iterations):
        c = (a * fb - b * fa) / (fb - fa)
        fc = fun(c)
        if fc == 0.0:
            return c
        if fc * fb < 0:
            a, fa = b, fb
            side_new = 1
        else:
            side_new = -1
            fa = 0.5 * fa if side == -1 else fa
        b, fb = c, fc
        side = side_new
        if abs(fc) < tol:
            break
    return min(max(c, 0.0), 1.0)


class _Regimes:
    """The plant's regimes for one simulation: cached ZOH matrices and the friction tests.

    ``modal(s)`` and ``discrete(s)`` build each regime's decomposition and its full-step matrices once
    per simulation (at most three regimes: moving either way, stuck).
    """

    def __init__(self, plant: StatePlant, dt: float):
        self.plant = plant
        self.dt = dt
        self.w = plant.w
        self.f_level = plant.friction
        self._modal: dict[int, _Modal] = {}
        self._discrete: dict[int, HeldStep] = {}

    def modal(self, s: int) -> _Modal:
        """Eigen-decomposition of regime s (built on first use)."""
        if s not in self._modal:
            self._modal[s] = modal_of(self.plant, s)
        return self._modal[s]

    def discrete(self, s: int) -> HeldStep:
        """ZOH matrices of regime s over one grid step (built on first use)."""
        if s not in self._discrete:
            self._discrete[s] = self.modal(s).full_step(self.dt)
        return self._discrete[s]

    def drive(self, xs: np.ndarray, v: np.ndarray | float) -> np.ndarray | float:
        """Acceleration the drive would give at rest (ω = 0): row w of A·x + b_V·V without the ω term."""
        plant, w = self.plant, self.w
        acc = xs @ plant.a[w] - (xs[..., w] * plant.a[w, w]) + plant.b_drive[w] * v
        return acc

    def event_function(self, mode: int, x: np.ndarray, v: float, tau: float) -> Callable[[float], float]:
        """frac ↦ the event function after frac·τ of the held input v from x in regime ``mode``: the speed when
        moving, the drive margin |drive| − F when stuck (what :func:`_locate` finds the zero of)."""
        w, f_level, modal = self.w, self.f_level, self.modal(mode)
        if mode != 0:
            weights, offset = np.eye(self.plant.n)[w], 0.0
        else:  # drive(x, v): row w of A·x without the ω term, plus b_V·v
            weights = self.plant.a[w].copy()
            weights[w] = 0.0
            offset = float(self.plant.b_drive[w]) * v
        fast = modal.along(x, v, weights)
        if fast is not None:
            if mode != 0:
                return lambda frac: fast(frac * tau)
            return lambda frac: abs(fast(frac * tau) + offset) - f_level

        def event_value(frac: float) -> float:
            xm, _ = _flow(modal.discrete(frac * tau), x, v)
            return float(xm[w]) if mode != 0 else abs(float(self.drive(xm, v))) - f_level

        return event_value

    def new_mode(self, xs: np.ndarray, v: float) -> int:
        """Regime a shaft at rest enters: stuck while the drive does not exceed the friction level."""
        acc = float(self.drive(xs, v))
        return 0 if abs(acc) <= self.f_level else (1 if acc > 0 else -1)


def simulate(
    plant: StatePlant,
    voltage: np.ndarray,
    dt: float,
    *,
    x0: np.ndarray | None = None,
    theta0: float = 0.0,
    switches: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
    trace: list[tuple[int, int, int, int]] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Simulate the plant on a uniform grid.

    Parameters
    ----------
    plant
        The linear plant with friction.
    voltage
        Applied voltage held over each step, N values [V].
    dt
        Grid step [s].
    x0
        Initial state (default: at rest).
    theta0
        Initial angle [rad].
    switches
        Drive switches inside steps: (step indices k, increasing; fractions f in [0, 1]; voltage
        before). Step k holds the voltage before for f·dt, then ``voltage[k]`` (a drive switching
        between the logger's samples); each such step is propagated exactly in two parts.
    trace
        A list that receives the run's structure, for :func:`sensitivities`: ``(k0, k1, mode, kind)`` for steps k0 to
        k1 propagated in regime ``mode``, ``kind`` :data:`RUN`, or one step k0 (k1 = k0 + 1) that starts in
        ``mode`` and is a drive switch (:data:`SWITCH`) or the step of a friction event (:data:`EVENT`).

    Returns
    -------
    states, theta
        States at the N + 1 grid points (shape (N + 1, n)) and the angle [rad] (N + 1,).
    """
    voltage = np.asarray(voltage, dtype=float)
    n_steps = voltage.size
    w = plant.w
    x = np.zeros(plant.n) if x0 is None else np.asarray(x0, dtype=float).copy()
    states = np.empty((n_steps + 1, plant.n))
    theta = np.empty(n_steps + 1)
    states[0] = x
    theta[0] = theta0
    reg = _Regimes(plant, dt)
    k = 0
    th = float(theta0)
    mode = int(np.sign(x[w])) if x[w] != 0 else (reg.new_mode(x, voltage[0]) if n_steps else 0)
    chunk = _MIN_CHUNK
    sw_steps, sw_frac, sw_before = switches if switches is not None else (np.zeros(0, int), (), ())
    sw = 0
    while k < n_steps:
        while sw < len(sw_steps) and sw_steps[sw] < k:
            sw += 1
        if sw < len(sw_steps) and sw_steps[sw] == k:
            _traced(trace, k, k + 1, mode, SWITCH)
            x, dth_step, mode = _switch_step(reg, x, mode, float(sw_before[sw]), float(voltage[k]), float(sw_frac[sw]))
        else:
            # Propagate a chunk in the current regime; stop at the first step where the regime ends
            # (the chunk doubles while nothing happens, up to 65 536 steps).
            stop = min(n_steps, k + chunk, int(sw_steps[sw]) if sw < len(sw_steps) else n_steps)
            v = voltage[k:stop]
            xs, dth = propagate(reg.discrete(mode), x, v)
            margins: tuple[np.ndarray, np.ndarray] | None = None
            if mode != 0:
                bad = np.flatnonzero(mode * xs[1:, w] <= 0.0)
            else:
                # break-away at the start of a step (input change) or inside it (current rising)
                margins = (np.abs(reg.drive(xs[:-1], v)) - reg.f_level, np.abs(reg.drive(xs[1:], v)) - reg.f_level)
                bad = np.flatnonzero((margins[0] > 0) | (margins[1] > 0))
            if bad.size == 0:
                _traced(trace, k, stop, mode, RUN)
                states[k + 1 : stop + 1] = xs[1:]
                theta[k + 1 : stop + 1] = th + np.cumsum(dth)
                th = float(theta[stop])
                x = xs[-1].copy()
                k = stop
                chunk = min(2 * chunk, 1 << 16)
                continue
            j = int(bad[0])  # the event happens inside step k + j
            if j:
                states[k + 1 : k + j + 1] = xs[1 : j + 1]
                theta[k + 1 : k + j + 1] = th + np.cumsum(dth[:j])
                th = float(theta[k + j])
                x = xs[j].copy()
            _traced(trace, k, k + j, mode, RUN)
            _traced(trace, k + j, k + j + 1, mode, EVENT)
            k += j
            ends = (float(x[w]), float(xs[j + 1, w])) if margins is None else (margins[0][j], margins[1][j])
            x, dth_step, mode = _event_step(reg, x, mode, float(voltage[k]), float(ends[0]), float(ends[1]))
        th += dth_step
        k += 1
        states[k] = x
        theta[k] = th
        chunk = _MIN_CHUNK
    return states, theta


def _traced(trace: list[tuple[int, int, int, int]] | None, k0: int, k1: int, mode: int, kind: int) -> None:
    """Add steps k0 to k1 of ``kind`` starting in ``mode`` to a trace (if any); a propagated stretch joins the one
    before when it continues it."""
    if trace is None or k1 == k0:
        return
    if kind == RUN and trace and trace[-1][3] == RUN and trace[-1][1] == k0 and trace[-1][2] == mode:
        k0 = trace.pop()[0]
    trace.append((k0, k1, mode, kind))


def _switch_step(reg: _Regimes, x: np.ndarray, mode: int, v_before: float, v_after: float,
                 frac: float) -> tuple[np.ndarray, float, int]:
    """One grid step with a drive switch at ``frac`` of it: v_before, then v_after, each part exact."""
    dt = reg.dt
    x, dth1, mode = _advance(reg, x, mode, v_before, frac * dt)
    x, dth2, mode = _advance(reg, x, mode, v_after, (1.0 - frac) * dt)
    return x, dth1 + dth2, mode


def _event_step(reg: _Regimes, x: np.ndarray, mode: int, vk: float, f0: float,
                f1: float) -> tuple[np.ndarray, float, int]:
    """The grid step (voltage vk held) in which the regime ends: locate the event, finish in the new regime.

    ``f0``, ``f1``: the event function at the start and end of the step in the old regime, the speed
    when moving, the drive margin |drive| − F when stuck. Returns the state at the step's end, the
    angle increment over the step and the new regime.
    """
    dt, w = reg.dt, reg.w
    event_value = reg.event_function(mode, x, vk, dt)
    if mode != 0:
        frac = _locate(event_value, f0, f1)
    else:
        frac = 0.0 if f0 > 0 else _locate(event_value, f0, f1)
    frac = min(max(frac, 0.0), 1.0)
    x_mid, dth_mid = reg.modal(mode).flow(x, vk, frac * dt) if frac > 0 else (x, 0.0)
    if mode != 0:
        x_mid = x_mid.copy()
        x_mid[w] = 0.0
    if mode == 0:  # break-away located: move in the direction of the drive (its margin is ~0 here)
        nxt = 1 if float(reg.drive(x_mid, vk)) > 0 else -1
    else:
        nxt = reg.new_mode(x_mid, vk)
    if nxt == mode:  # interpolation put the event at the very end: finish the step in the old regime
        nxt = 0 if mode != 0 else nxt
    x_end, dth_end = reg.modal(nxt).flow(x_mid, vk, (1.0 - frac) * dt) if frac < 1 else (x_mid, 0.0)
    if nxt != 0 and nxt * x_end[w] < 0:  # broke away and stopped again within the step
        x_end, dth_end, nxt = _stuck_rest(reg, x_mid, vk, (1.0 - frac) * dt)
    return np.asarray(x_end, dtype=float).copy(), dth_mid + dth_end, nxt


def _advance(reg: _Regimes, x: np.ndarray, mode: int, v: float, tau: float) -> tuple[np.ndarray, float, int]:
    """Propagate a part of a step (length τ, voltage v held) exactly, with at most one friction event."""
    w, f_level = reg.w, reg.f_level
    if tau <= 0.0:
        return x, 0.0, mode
    if mode == 0 and abs(float(reg.drive(x, v))) > f_level:  # break-away at once (the drive just changed)
        mode = 1 if float(reg.drive(x, v)) > 0 else -1
    x1, d1 = reg.modal(mode).flow(x, v, tau)
    if mode != 0:
        if mode * x1[w] > 0:
            return x1, d1, mode
        f0, f1 = float(x[w]), float(x1[w])
    else:
        f1 = abs(float(reg.drive(x1, v))) - f_level
        if f1 <= 0:
            return x1, d1, 0
        f0 = abs(float(reg.drive(x, v))) - f_level

    frac = _locate(reg.event_function(mode, x, v, tau), f0, f1)
    x_mid, d_mid = reg.modal(mode).flow(x, v, frac * tau) if frac > 0 else (x, 0.0)
    if mode != 0:
        x_mid = x_mid.copy()
        x_mid[w] = 0.0
        nxt = reg.new_mode(x_mid, v)
    else:
        nxt = 1 if float(reg.drive(x_mid, v)) > 0 else -1
    x_end, d_end = reg.modal(nxt).flow(x_mid, v, (1.0 - frac) * tau) if frac < 1 else (x_mid, 0.0)
    if nxt != 0 and nxt * x_end[w] < 0:  # broke away and stopped again within the part
        x_end, d_end, nxt = _stuck_rest(reg, x_mid, v, (1.0 - frac) * tau)
    return np.asarray(x_end, dtype=float), d_mid + d_end, nxt


def _stuck_rest(reg: _Regimes, x: np.ndarray, v: float, tau: float) -> tuple[np.ndarray, float, int]:
    """The rest (length τ) of a step in which the shaft broke away and stopped again: stuck, the current moving.

    At a break-away whose drive falls back below the friction level within the step (a ripple peak:
    the current, driven by the next held voltage, reverses in a fraction of the step) the moving
    regime ends the step with the speed's sign reversed. The excursion in between is a fraction of
    a step long and moves the angle by a second-order amount; the shaft is taken as at rest for the
    rest of the step, the winding's current still following the voltage. (Holding the whole state
    instead froze the current too, for as long as the drive stayed near the friction level: on a log
    with supply ripple a change of 1e-6 in R then moved the cost from 2,485 to 3e8.)
    """
    x = np.array(x, dtype=float)
    x[reg.w] = 0.0
    x_end, _ = reg.modal(0).flow(x, v, tau)
    return x_end, 0.0, 0


@dataclass(frozen=True)
class Perturbed:
    """A simulation's inputs with the parameters moved a little (one column of a Jacobian)."""

    plant: StatePlant
    voltage: np.ndarray
    x0: np.ndarray
    switches: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None


def _step_of(reg: _Regimes, x: np.ndarray, mode: int, kind: int, vk: float,
             switch: tuple[float, float] | None) -> tuple[np.ndarray, float, int]:
    """One step of a trace that is not a plain propagation (a drive switch, a friction event), from state x."""
    if kind == SWITCH:
        assert switch is not None
        return _switch_step(reg, x, mode, switch[1], vk, switch[0])
    x1, _ = _flow(reg.discrete(mode), x, vk)
    if mode != 0:
        f0, f1 = float(x[reg.w]), float(x1[reg.w])
    else:
        f0, f1 = (abs(float(reg.drive(x, vk))) - reg.f_level, abs(float(reg.drive(x1, vk))) - reg.f_level)
    return _event_step(reg, x, mode, vk, f0, f1)


def sensitivities(plant: StatePlant, voltage: np.ndarray, dt: float, states: np.ndarray, theta: np.ndarray,
                  trace: list[tuple[int, int, int, int]], switches: tuple[np.ndarray, np.ndarray, np.ndarray] | None,
                  columns: list[Perturbed], *, memo: dict[int, Any] | None = None,
                  ) -> tuple[np.ndarray, np.ndarray] | None:
    """How a simulation's states and angle change when its inputs change a little: C columns at once.

    ``states``, ``theta`` and ``trace`` are what :func:`simulate` gave for ``plant``, ``voltage`` and ``switches``
    (from ``states[0]``, angle 0); each column moves the plant, the voltage, the initial state or the switch
    instants a little. Along the stretches the trace propagated, the changes follow the nominal run's recursion
    δx⁺ = Ad·δx + ΔAd·x + Δb_V·v + b_V·Δv + Δc (the product of two changes dropped), all columns in one filter. A
    switch's or a friction event's step is linearised: its derivative in the state it starts from by differences of
    1e-7 (the event relocated each time), plus the step taken again with the column's plant, voltage or switch where
    the column moves them. A Jacobian then costs about one simulation, not one per parameter. ``memo`` (a dict kept
    for the same run) keeps the steps' own derivatives for the next batch of columns.

    Returns
    -------
    (dstates, dtheta) of shapes (N + 1, n, C) and (N + 1, C), or None when a column changes the run's sequence
    of regimes (it starts in another, moves a switch to another step, or leaves an event's step in another):
    then only simulating it says how.
    """
    n, count, w = plant.n, len(columns), plant.w
    dstates = np.empty((voltage.size + 1, n, count))
    dtheta = np.empty((voltage.size + 1, count))
    dstates[0] = np.stack([col.x0 for col in columns], axis=1) - states[0][:, None]
    dtheta[0] = 0.0
    reg = _Regimes(plant, dt)
    regs = [_Regimes(col.plant, dt) for col in columns]  # each regime built on first use
    for col, col_reg in zip(columns, regs, strict=True):
        start = int(np.sign(col.x0[w])) if col.x0[w] != 0 else col_reg.new_mode(col.x0, float(col.voltage[0]))
        if trace and start != trace[0][2]:
            return None
    if switches is not None and any(col.switches is None or not np.array_equal(col.switches[0], switches[0])
                                    for col in columns):
        return None
    dvolt = np.stack([col.voltage for col in columns], axis=1) - voltage[:, None]  # (N, C)
    plant_moved = np.array([not col.plant.same_as(plant) for col in columns])
    special = _SpecialSteps(reg, regs, voltage, columns, switches, np.maximum(np.abs(states).max(axis=0), 1e-300),
                            {} if memo is None else memo)
    for k0, k1, mode, kind in trace:
        if kind != RUN:
            again = plant_moved | (dvolt[k0] != 0.0)
            if not special.take(k0, mode, kind, states[k0], again, dstates, dtheta):
                return None
            continue
        step = reg.discrete(mode)
        # the changes of the step's matrices (none for a column that moves only the drive or the start)
        d_ad, d_bv, d_c = np.zeros((count, n, n)), np.zeros((n, count)), np.zeros((n, count))
        d_hx, d_hv, d_hc = np.zeros((n, count)), np.zeros(count), np.zeros(count)
        for c in np.flatnonzero(plant_moved):
            moved_step = regs[c].discrete(mode)
            d_ad[c] = moved_step.ad - step.ad
            d_bv[:, c] = moved_step.bv - step.bv
            d_c[:, c] = moved_step.c - step.c
            d_hx[:, c] = moved_step.hx - step.hx
            d_hv[c] = moved_step.hv - step.hv
            d_hc[c] = moved_step.hc - step.hc
        x = states[k0:k1]  # (m, n)
        v = voltage[k0:k1]
        dv = dvolt[k0:k1]  # (m, C)
        # e_k = ΔAd·x_k + Δb_V·v_k + b_V·Δv_k + Δc, laid out (n, C, m)
        e = (np.einsum("cij,kj->ick", d_ad, x) + d_bv[:, :, None] * v + step.bv[:, None, None] * dv.T[None]
             + d_c[:, :, None])
        xs = recursion(step.ad, dstates[k0], e)  # (n, C, m + 1)
        dstates[k0 + 1 : k1 + 1] = np.moveaxis(xs[:, :, 1:], 2, 0)
        increments = (np.einsum("i,ick->kc", step.hx, xs[:, :, :-1]) + x @ d_hx + np.outer(v, d_hv) + step.hv * dv
                      + d_hc)
        dtheta[k0 + 1 : k1 + 1] = dtheta[k0] + np.cumsum(increments, axis=0)
    return dstates, dtheta


class _SpecialSteps:
    """The linearised switch and event steps of :func:`sensitivities`."""

    def __init__(self, reg: _Regimes, regs: list[_Regimes], voltage: np.ndarray, columns: list[Perturbed],
                 switches: tuple[np.ndarray, np.ndarray, np.ndarray] | None, scale: np.ndarray, memo: dict[int, Any]):
        self.reg, self.regs, self.voltage, self.columns, self.scale = reg, regs, voltage, columns, scale
        self.memo = memo
        self.switches = switches
        self.index = {int(k): i for i, k in enumerate(switches[0])} if switches is not None else {}

    def _switch(self, k: int, inputs: tuple[np.ndarray, np.ndarray, np.ndarray] | None) -> tuple[float, float] | None:
        if k not in self.index:
            return None
        assert inputs is not None
        i = self.index[k]
        return float(inputs[1][i]), float(inputs[2][i])

    def _own(self, k: int, mode: int, kind: int, x: np.ndarray,
             nominal: tuple[float, float] | None) -> tuple[np.ndarray, float, int, np.ndarray, np.ndarray] | None:
        """The step from x (its end state, angle and regime) and its derivative in x (forward differences, else
        backward; None where both leave the step in another regime)."""
        vk = float(self.voltage[k])
        x_end, dth, after = _step_of(self.reg, x, mode, kind, vk, nominal)
        jac_x = np.empty((x.size, x.size))
        grad_x = np.empty(x.size)
        for j in range(x.size):
            for sign in (1.0, -1.0):
                eps = sign * 1e-7 * max(abs(float(x[j])), float(self.scale[j]))
                xj = x.copy()
                xj[j] += eps
                x1, dth1, mode1 = _step_of(self.reg, xj, mode, kind, vk, nominal)
                if mode1 == after:
                    break
            else:
                return None
            jac_x[:, j] = (x1 - x_end) / eps
            grad_x[j] = (dth1 - dth) / eps
        return x_end, dth, after, jac_x, grad_x

    def take(self, k: int, mode: int, kind: int, x: np.ndarray, again: np.ndarray, dstates: np.ndarray,
             dtheta: np.ndarray) -> bool:
        """Carry the changes over step k (starting in ``mode`` from the nominal state x); False where a change
        leaves the step in another regime. ``again``: the columns whose plant or voltage change the step."""
        nominal = self._switch(k, self.switches)
        if k not in self.memo:
            self.memo[k] = self._own(k, mode, kind, x, nominal)
        if self.memo[k] is None:
            return False
        x_end, dth, after, jac_x, grad_x = self.memo[k]
        dx = dstates[k]
        dstates[k + 1] = jac_x @ dx
        dtheta[k + 1] = dtheta[k] + grad_x @ dx
        # ... and the step taken again where a column moves its plant, its voltage or its switch
        for c, col in enumerate(self.columns):
            moved = self._switch(k, col.switches)
            if not again[c] and moved == nominal:
                continue
            xc, dthc, mode_c = _step_of(self.regs[c], x, mode, kind, float(col.voltage[k]), moved)
            if mode_c != after:
                return False
            dstates[k + 1, :, c] += xc - x_end
            dtheta[k + 1, c] += dthc - dth
        return True
