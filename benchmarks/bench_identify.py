"""Speed of whole-model identification: a 3 s log at 10 kHz (30 000 samples), target < 2 s.

Random voltage steps in ±12 V drive a simulated motor (:func:`motorlab.simulate.simulate`); the
encoder is counted at 2240 counts/rev and the current carries 20 mA of noise.
"""

from __future__ import annotations

import math
import time

import numpy as np

from motorlab.identify import identify
from motorlab.model import MotorParams
from motorlab.recording import Recording
from motorlab.simulate import VoltageDrive, simulate

MOTOR = MotorParams(K=0.35, R=2.5, L=7e-4, J=8e-4, b=2e-3, Tf=0.03)


def make_log(seed: int, *, duration: float = 3.0, dt: float = 1e-4, cpr: int = 2240) -> Recording:
    rng = np.random.default_rng(seed)
    n = int(duration / 0.1) + 1
    levels = rng.uniform(-12.0, 12.0, n)
    sim = simulate(MOTOR, VoltageDrive(lambda t: levels[np.minimum((t / 0.1 + 1e-9).astype(int), n - 1)]),
                   duration=duration, dt=dt)
    q = 2 * math.pi / cpr
    counts = np.floor((sim.position + rng.uniform(0.0, q)) / q)
    return Recording(sim.time, {"voltage": sim.voltage, "position": counts * q,
                                "current": sim.current + 0.02 * rng.standard_normal(sim.time.size)},
                     metadata={"cpr": cpr}, source=f"bench-{seed}")


def main() -> None:
    print("identify: 3 s at 10 kHz (30 001 samples), voltage + encoder + current")
    for seed in range(3):
        rec = make_log(seed)
        start = time.perf_counter()
        result = identify(rec)
        elapsed = time.perf_counter() - start
        errors = "  ".join(
            f"{n} {100 * (result.value(n) / getattr(MOTOR, n) - 1):+.3f}%" for n in ("K", "R", "L", "J", "b", "Tf")
        )
        print(f"  seed {seed}: {elapsed:.2f} s (target < 2 s)  {errors}")


if __name__ == "__main__":
    main()
