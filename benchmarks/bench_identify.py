"""Accuracy against the Cramér–Rao bound, and speed, of whole-model identification.

``bound_tables``: error/bound and stderr/bound on 3 s logs at 10 kHz from the independent Radau
simulator of the tests, for drives switching between samples (0.02 V voltage noise) and on sample
instants (exact voltage), four seeds each, with the time per log (issue 18: < 10 s).

Random voltage steps in ±12 V drive a simulated motor (:func:`motorlab.model.simulate.simulate`); the
encoder is counted at 2240 counts/rev and the current carries 20 mA of noise.
"""

from __future__ import annotations

import math
import time

import numpy as np

from motorlab.analyses.identify import identify
from motorlab.model import MotorParams
from motorlab.model.simulate import VoltageDrive, simulate
from motorlab.recording import Recording

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


def bound_tables(n_seeds: int = 4, *, duration: float = 3.0, dt: float = 1e-4) -> None:
    """Error/bound and stderr/bound on logs from the independent Radau simulator (tests/analyses/ivp_reference.py).

    Two drives, ``n_seeds`` seeds each: held levels switching between samples with 0.02 V noise on the
    logged voltage, and switching on sample instants with exact voltage; 0.02 A current noise, a
    560-count encoder, levels in ±12 V held 0.05–0.3 s. The bound is the Cramér–Rao bound the result
    reports for its own log (``details["cramer_rao_bound"]``).
    """
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
    from ivp_reference import logged

    names = ("K", "R", "L", "J", "b", "Tf")
    truth = MOTOR.to_dict()
    for on_samples, noise in ((False, 0.02), (True, 0.0), (True, 0.02)):
        kind = ("on sample instants" if on_samples else "between samples") + (
            f", {noise:g} V voltage noise" if noise else ", exact voltage")
        print(f"identify, {duration:g} s at {1 / dt:g} Hz, drive switching {kind}")
        err, se, z, times = [], [], [], []
        for seed in range(n_seeds):
            rec, _ = logged(truth, 100 + seed, duration=duration, dt=dt, on_samples=on_samples, voltage_noise=noise)
            start = time.perf_counter()
            result = identify(rec)
            times.append(time.perf_counter() - start)
            bound = result.details["cramer_rao_bound"]["bound"]
            err.append([(result.value(n) - truth[n]) / bound[n] for n in names])
            se.append([result[n].stderr / bound[n] for n in names])
            z.append([(result.value(n) - truth[n]) / result[n].stderr for n in names])
            print(f"  seed {seed}: {times[-1]:.2f} s, input model: {result.details['input_model']['text']}")
        e, s_, zz = (np.array(a) for a in (err, se, z))
        print("  " + " ".join(f"{n:>8}" for n in ("", *names)))
        print("  " + f"{'RMS err/bound':>8} " + " ".join(f"{v:8.2f}" for v in np.sqrt(np.mean(e**2, axis=0))))
        print("  " + f"{'stderr/bound':>8} " + " ".join(f"{v:8.2f}" for v in np.mean(s_, axis=0)))
        print("  " + f"{'|z|<3 seeds':>8} " + " ".join(f"{int(v):8d}" for v in np.sum(np.abs(zz) < 3, axis=0)))
        print("  " + f"{'max |z|':>8} " + " ".join(f"{v:8.2f}" for v in np.max(np.abs(zz), axis=0)))
        print(f"  time per log: mean {np.mean(times):.2f} s, max {np.max(times):.2f} s (target < 10 s)")


def main() -> None:
    bound_tables()
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
