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

from motorlab.analyses.feedforward import feedforward, sysid_ols
from motorlab.model import MotorParams, feedforward_from_params
from motorlab.model.simulate import VoltageDrive, simulate
from motorlab.recording import Recording

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
    truth = feedforward_from_params(MOTOR)
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


def rig_files(n_seeds: int = 20) -> None:
    """FTC-like files of the virtual dynamometer: NeveRest 20 (560 counts/rev at the output) with the steel
    disc on its output shaft (τm ≈ 0.18 s), SysId tests logged every 10 ms with 0.02 V of voltage noise,
    20 ms status frames and 0.3 ms row jitter; 0.5 V/s ramps for 14 s, 7 V steps for 2 s."""
    import tempfile
    from pathlib import Path

    from motorlab.estimation.runs import read_runs
    from motorlab.rig import VirtualRig
    from motorlab.rig.flywheel import Flywheel

    worst = {"kS": 0.0, "kV": 0.0, "kA": 0.0}
    z: dict[str, list[float]] = {k: [] for k in worst}
    with tempfile.TemporaryDirectory() as folder:
        for seed in range(n_seeds):
            rig = VirtualRig("neverest20", unit_seed=seed % 5, noise_seed=seed, flywheel=Flywheel(ratio=1.0))
            run = rig.sysid(Path(folder) / "sysid.json", ramp_rate=0.5, quasistatic_duration=14.0,
                            dynamic_duration=2.0)
            result = feedforward(read_runs([str(run.paths[0])], cpr=None))
            for name in worst:
                truth = run.truth["expected"][name]
                worst[name] = max(worst[name], abs(result.value(name) / truth - 1))
                z[name].append((result.value(name) - truth) / result[name].stderr)
    print(f"rig SysId files (FTC-like, {n_seeds} seeds): worst error "
          + ", ".join(f"{k} {100 * v:.2f} %" for k, v in worst.items())
          + "; 95 % coverage " + ", ".join(f"{k} {np.mean(np.abs(z[k]) < 1.96):.2f}" for k in z))


if __name__ == "__main__":
    main()
    rig_files()
