"""Simulation speed (issue 2): targets

- 60 s of the flywheel rig at a 1 kHz internal step in under 0.5 s;
- 3 s of a free motor at a 10 µs step in under 1 s.
"""

from __future__ import annotations

import time

import numpy as np

from motorlab.model import MotorParams
from motorlab.model.simulate import BenchSupply, OpenCircuit, VoltageDrive, simulate

MOTOR = MotorParams(K=0.35, R=2.0, L=0.6e-3, J=2e-4, b=1e-4, Tf=0.02)


def best_of(n: int, fn) -> float:
    times = []
    for _ in range(n):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def main() -> None:
    flywheel = MOTOR.with_load(1.5e-3, ratio=25)  # steel disc through the seed's 25:1 step-up

    def rig() -> None:
        simulate(flywheel, [(0.0, BenchSupply(12.0, 4.0)), (30.0, OpenCircuit())], duration=60.0, dt=1e-3)

    def free() -> None:
        square = VoltageDrive(lambda t: 12.0 * np.sign(np.sin(2 * np.pi * 2 * t) + 1e-12))
        simulate(MOTOR, square, duration=3.0, dt=1e-5)

    t_rig = best_of(5, rig)
    t_free = best_of(5, free)
    print(f"flywheel rig, 60 s at 1 kHz (60 000 steps):     {t_rig * 1e3:8.1f} ms   (target < 500 ms)")
    print(f"free motor, 3 s at 10 µs (300 000 steps, ±12 V): {t_free * 1e3:8.1f} ms   (target < 1000 ms)")


if __name__ == "__main__":
    main()
