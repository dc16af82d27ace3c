"""Feedforward gains on FTC-like SysId data: output error (motorlab) against SysId's OLS, side by side.

FTC-like: a gearmotor with a flywheel at the output (kS 0.214 V, kV 0.364 V·s/rad, kA 0.0357 V·s²/rad),
encoder 560 counts/rev at the output, logging every 10 ms, 0.02 V of noise on the logged voltage;
SysId's four tests (1 V/s ramps for 6 s, 6 V steps for 2 s, forward and backward).
Targets of the output-error fit: kS, kA within 2 %, kV within 0.5 %.
"""

from __future__ import annotations

import math
import time

import numpy as np

from motorlab.feedforward import feedforward, gains_from_params, sysid_ols
from motorlab.model import MotorParams
from motorlab.recording import Recording
from motorlab.simulate import VoltageDrive, simulate

MOTOR = MotorParams(K=0.35, R=2.5, L=7e-4, J=5e-3, b=2e-3, Tf=0.03)
CPR = 560


def sysid_tests(seed: int) -> list[Recording]:
    rng = np.random.default_rng(seed)
    q = 2 * math.pi / CPR
    recs = []
    for name in ("slow-forward", "slow-backward", "fast-forward", "fast-backward"):
        sign = 1.0 if name.endswith("forward") else -1.0
        slow = name.startswith("slow")
        sim = simulate(MOTOR, VoltageDrive((lambda t, s=sign: s * t) if slow else
                                           (lambda t, s=sign: s * 6.0 * np.ones_like(t))),
                       duration=6.0 if slow else 2.0, dt=0.01)
        counts = np.floor((sim.position + rng.uniform(0.0, q)) / q)
        recs.append(Recording(sim.time, {"voltage": sim.voltage + 0.02 * rng.standard_normal(sim.time.size),
                                         "position": counts * q}, metadata={"cpr": CPR}, source=name))
    return recs


def main() -> None:
    truth = gains_from_params(MOTOR)
    print("feedforward on FTC-like SysId data: error of each method [%] (output error ± its 1σ)")
    header = " | ".join(f"{n + ' OE':>14} {n + ' OLS':>8}" for n in truth)
    print(f"{'seed':>4} | {header} | time")
    worst = dict.fromkeys(truth, 0.0)
    for seed in range(8):
        recs = sysid_tests(seed)
        start = time.perf_counter()
        result = feedforward(recs)
        elapsed = time.perf_counter() - start
        ols = sysid_ols(recs)
        cells = []
        for name, value in truth.items():
            err = 100 * (result.value(name) / value - 1)
            sd = 100 * result[name].stderr / value
            worst[name] = max(worst[name], abs(err))
            cells.append(f"{err:+6.2f} ±{sd:5.2f} {100 * (ols[name] / value - 1):+8.2f}")
        print(f"{seed:>4} | " + " | ".join(cells) + f" | {elapsed:.2f} s")
    print("worst output-error errors: " + ", ".join(f"{k} {v:.2f} %" for k, v in worst.items())
          + "  (targets: kS 2 %, kV 0.5 %, kA 2 %)")


if __name__ == "__main__":
    main()
