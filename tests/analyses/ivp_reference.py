"""An independent reference simulator for identification tests: scipy's implicit Runge–Kutta (Radau).

Deliberately different from :mod:`motorlab.estimation.output_error` (exact zero-order-hold discretisation run as a
rational filter) and :mod:`motorlab.model.simulate`: the motor

    L·di/dt = V − R·i − K·ω,   J·dω/dt = K·i − b·ω − Tf·sgn(ω),   θ' = ω

is integrated by :func:`scipy.integrate.solve_ivp` (Radau, tight tolerances) piece by piece between
the drive's switch instants, which may fall anywhere between the logger's samples, with terminal
events where the shaft stops (ω = 0) and where it breaks away (|K·i| = Tf, stiction at the Coulomb
level). Samples are read from each piece's dense output. Nothing here imports motorlab's simulators.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

#: Radau's relative tolerance (its absolute ones: 1e-2 of it for the current and the angle, itself for the speed,
#: in A, rad/s and rad): the reference a simulator is compared with to 1e-8 rad.
RTOL = 1e-10
#: ... and for a log made to be identified (:func:`logged`): 4e-9 rad and 2e-7 A from the RTOL reference at most
#: (seed 20's 0.6 s), six orders below the counting quantum and five below the current's noise, in a quarter of
#: the time (the reference simulation was most of the identification tests' cost).
LOG_RTOL = 1e-7


@dataclass(frozen=True)
class Drive:
    """A held drive: ``levels[j]`` [V] from ``switches[j]`` [s] (``switches[0] == 0``) to the next switch."""

    levels: np.ndarray
    switches: np.ndarray

    def at(self, t: np.ndarray) -> np.ndarray:
        """The voltage at times t (a sample at a switch instant reads the new level) [V]."""
        return self.levels[np.searchsorted(self.switches, t, side="right") - 1]


def random_drive(rng: np.random.Generator, duration: float, dt: float, *, on_samples: bool,
                 hold: tuple[float, float] = (0.05, 0.3), amplitude: float = 12.0) -> Drive:
    """Levels uniform in ±amplitude held for uniform(hold) seconds; switches on sample instants or not."""
    times = [0.0]
    while times[-1] < duration:
        times.append(times[-1] + rng.uniform(*hold))
    switches = np.array(times[:-1])
    if on_samples:
        switches = np.round(switches / dt) * dt
    elif switches.size > 1:  # keep every switch strictly between two samples
        frac = switches[1:] / dt - np.floor(switches[1:] / dt)
        switches[1:] += np.where(frac < 0.01, 0.01 * dt, 0.0) - np.where(frac > 0.99, 0.01 * dt, 0.0)
    return Drive(rng.uniform(-amplitude, amplitude, switches.size), switches)


def _atol(rtol: float) -> list[float]:
    return [1e-2 * rtol, rtol, 1e-2 * rtol]


def _moving_piece(p: dict[str, float], v: float, t0: float, t1: float, y0: np.ndarray, sign: float, rtol: float):
    K, R, L, J, b, Tf = (p[k] for k in ("K", "R", "L", "J", "b", "Tf"))
    a = np.array([[-R / L, -K / L, 0.0], [K / J, -b / J, 0.0], [0.0, 1.0, 0.0]])
    c = np.array([v / L, -Tf * sign / J, 0.0])

    def stop(_t: float, y: np.ndarray) -> float:
        return y[1]

    stop.terminal = True  # type: ignore[attr-defined]
    stop.direction = -sign  # type: ignore[attr-defined]
    return solve_ivp(lambda _t, y: a @ y + c, (t0, t1), y0, method="Radau", jac=a, dense_output=True,
                     events=stop, rtol=rtol, atol=_atol(rtol))


def _stuck_piece(p: dict[str, float], v: float, t0: float, t1: float, y0: np.ndarray, rtol: float):
    K, R, L, Tf = p["K"], p["R"], p["L"], p["Tf"]
    a = np.array([[-R / L, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    c = np.array([v / L, 0.0, 0.0])

    def breakaway(_t: float, y: np.ndarray) -> float:
        return abs(K * y[0]) - Tf

    breakaway.terminal = True  # type: ignore[attr-defined]
    breakaway.direction = 1  # type: ignore[attr-defined]
    return solve_ivp(lambda _t, y: a @ y + c, (t0, t1), y0, method="Radau", jac=a, dense_output=True,
                     events=breakaway, rtol=rtol, atol=_atol(rtol))


def simulate_ivp(p: dict[str, float], drive: Drive, duration: float, dt: float, *,
                 rtol: float = RTOL) -> dict[str, np.ndarray]:
    """Current [A], speed [rad/s] and angle [rad] at the samples n·dt, n = 0..round(duration/dt), from rest."""
    n = round(duration / dt) + 1
    t_samples = dt * np.arange(n)
    out = np.zeros((n, 3))
    y = np.zeros(3)
    bounds = [*drive.switches.tolist(), t_samples[-1] + 0.5 * dt]
    for j, v in enumerate(drive.levels):
        t, t_end = float(bounds[j]), float(bounds[j + 1])
        force = 0.0  # direction forced by a break-away event (its located |K·i| may round below Tf)
        while t < t_end:
            sign = math.copysign(1.0, y[1]) if y[1] != 0.0 else force
            if sign == 0.0 and abs(p["K"] * y[0]) > p["Tf"]:
                sign = math.copysign(1.0, y[0])
            force = 0.0
            sol = (_moving_piece(p, v, t, t_end, y, sign, rtol) if sign else _stuck_piece(p, v, t, t_end, y, rtol))
            t_stop = float(sol.t[-1]) if sol.status == 1 else t_end
            inside = (t_samples >= t) & (t_samples < t_stop)
            if inside.any():
                out[inside] = sol.sol(t_samples[inside]).T
                if not sign:
                    out[inside, 1] = 0.0
            y = sol.y[:, -1].copy()
            if sol.status == 1:
                if sign:  # stopped: ω = 0, then stuck or reversing
                    y[1] = 0.0
                else:
                    force = math.copysign(1.0, y[0])
            t = t_stop
    return {"time": t_samples, "current": out[:, 0], "speed": out[:, 1], "position": out[:, 2]}


def logged(p: dict[str, float], seed: int, *, duration: float, dt: float, on_samples: bool,
           voltage_noise: float, current_noise: float = 0.02, cpr: int = 560):
    """A log as instruments give it: voltage (± noise), counted encoder angle (random phase), current (± noise).

    Returns ``(Recording, drive)``.
    """
    from motorlab.recording import Recording

    rng = np.random.default_rng(seed)
    drive = random_drive(rng, duration, dt, on_samples=on_samples)
    sim = simulate_ivp(p, drive, duration, dt, rtol=LOG_RTOL)
    q = 2.0 * math.pi / cpr
    counts = np.floor((sim["position"] + rng.uniform(0.0, q)) / q)
    volts = drive.at(sim["time"]) + voltage_noise * rng.standard_normal(sim["time"].size)
    rec = Recording(sim["time"], {"voltage": volts, "position": counts * q, "counts": counts,
                                  "current": sim["current"] + current_noise * rng.standard_normal(sim["time"].size)},
                    metadata={"cpr": cpr}, source=f"ivp-{seed}")
    return rec, drive
