"""Accuracy and coverage of the gearbox efficiency from stall-torque logs (``analyze torque --ratio --K``).

The virtual rig writes lever-and-scale logs (seed 2's sweep up and back down, dither, 1 g scale, DMM
currents) of several catalogue gearmotors with known η and loss torque; the motor's K is given with a
1 % standard error and drawn off by it, as a spin-down would give it. Printed per η: the largest
|η̂ − η|, the mean standard error, and how often the truth lies inside the 95 % interval (η and the
loss torque); and the time.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np

from motorlab.analyses.torque import torque
from motorlab.catalog import Motor
from motorlab.gearbox import Gearbox
from motorlab.io import read_csv
from motorlab.rig import VirtualRig

MOTORS = ("neverest40", "neverest60", "hdhex40", "gobilda5202_19", "corehex")
ETAS = (0.3, 0.5, 0.7, 0.85, 0.95)
SEEDS = range(10)


def main() -> None:
    started = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for eta in ETAS:
            errors, stderrs, inside, loss_inside = [], [], 0, 0
            for k_index, key in enumerate(MOTORS):
                motor = Motor.from_catalog(key)
                for seed in SEEDS:
                    box = Gearbox(ratio=motor.gear_ratio, efficiency=eta, loss_torque=motor.gearbox().loss_torque)
                    rig = VirtualRig(motor, unit_seed=seed, noise_seed=seed, gearbox=box)
                    run = rig.torque(folder / f"{key}-{eta}-{seed}.csv")
                    k = rig.params.K / motor.gear_ratio
                    rng = np.random.default_rng([seed, k_index, round(100 * eta)])
                    k_given = k * (1 + 0.01 * rng.standard_normal())
                    result = torque(read_csv(run.paths[0]), ratio=motor.gear_ratio, motor_constant=k_given,
                                    motor_constant_stderr=0.01 * k)
                    est, loss = result["efficiency"], result["loss_torque"]
                    loss_inside += abs(loss.value - box.loss_torque) <= 1.96 * loss.stderr
                    errors.append(abs(est.value - eta))
                    stderrs.append(est.stderr)
                    inside += abs(est.value - eta) <= 1.96 * est.stderr
            n = len(errors)
            print(f"η = {eta:.2f}: max |error| {max(errors):.4f}, mean stderr {np.mean(stderrs):.4f}, "
                  f"95 % interval holds the truth in {inside}/{n} ({100 * inside / n:.0f} %); "
                  f"loss torque's in {loss_inside}/{n}")
    print(f"{len(ETAS) * len(MOTORS) * len(SEEDS)} logs in {time.perf_counter() - started:.1f} s")


if __name__ == "__main__":
    main()
