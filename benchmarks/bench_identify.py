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


def rig_files(n_seeds: int = 30) -> None:
    """The virtual dynamometer's transient files as ``motorlab demo`` writes them (4 s steps at 1 kHz)."""
    import tempfile
    from pathlib import Path

    from motorlab.io import read_any
    from motorlab.rig import VirtualRig

    names = ("K", "R", "L", "J", "b", "Tf")
    print(f"identify on rig transient files (NeveRest 40, 5 units x {n_seeds // 5} noise seeds): |error| max, "
          "|z| rms, 95 % coverage")
    errors: dict[str, list[float]] = {n: [] for n in names}
    z: dict[str, list[float]] = {n: [] for n in names}
    elapsed = 0.0
    with tempfile.TemporaryDirectory() as folder:
        for seed in range(n_seeds):
            rig = VirtualRig("neverest40", unit_seed=seed % 5, noise_seed=seed)
            run = rig.transient(Path(folder) / "transient.csv")
            rec = read_any(run.paths[0], cpr=rig.motor.cpr)
            start = time.perf_counter()
            result = identify(rec, cpr=rig.motor.cpr)
            elapsed += time.perf_counter() - start
            for n in names:
                truth = run.truth["expected"][n]
                errors[n].append(abs(result.value(n) / truth - 1))
                z[n].append((result.value(n) - truth) / result[n].stderr)
    for n in names:
        zz = np.array(z[n])
        print(f"  {n:>2}: {100 * max(errors[n]):.3f} %  z rms {np.sqrt(np.mean(zz**2)):.2f}  "
              f"coverage {np.mean(np.abs(zz) < 1.96):.2f}")
    print(f"  {elapsed / n_seeds:.2f} s per 4 001-sample log")


def main() -> None:
    rig_files()
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
