"""The full-size coverage checks of identification, whose cheaper versions run in the test suite.

The tests check each 95 % interval's coverage on a few seeds against a binomial acceptance window
(tests/_coverage.py, docs/ARCHITECTURE.md "The test suite"); here the same checks run at their
original size, with the original bars, and print the figures docs/identify.md records:

- ``rig_transient``: the virtual dynamometer's 1.2 s transient files, five units x twenty noise
  seeds (100 fits): every parameter's 95 % interval holds the truth 90-98 % of the time.
- ``independent``: 0.6 s at 10 kHz from the Radau reference of the tests (tests/analyses/ivp_reference.py),
  twelve seeds per drive: within 3 standard errors in at least ten, within 2 in 90 % of all.
- ``feedforward``: SysId quasistatic and dynamic tests, fifty seeds: 90-98 % coverage of kS, kV, kA.

``python benchmarks/run.py coverage`` (about 4 minutes of one core; far longer on a loaded machine).
"""

from __future__ import annotations

import importlib.util
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from motorlab.analyses.identify import identify

HERE = Path(__file__).resolve().parent
TESTS = HERE.parent / "tests"
NAMES = ("K", "R", "L", "J", "b", "Tf")


def _load(path: Path, name: str):
    """A helper module of the tests, loaded by path (the tests are not a package; they import ``tests._coverage``)."""
    if str(HERE.parent) not in sys.path:
        sys.path.insert(0, str(HERE.parent))
    if name not in sys.modules:
        spec = importlib.util.spec_from_file_location(name, path)
        assert spec is not None
        assert spec.loader is not None
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
    return sys.modules[name]


def rig_transient(n_seeds: int = 100) -> dict[str, list[bool]]:
    """Coverage of the 95 % intervals on the rig's transient files (the bar: 90-98 % for every parameter)."""
    from motorlab.io import read_any
    from motorlab.rig import VirtualRig

    inside: dict[str, list[bool]] = {name: [] for name in NAMES}
    start = time.perf_counter()
    with tempfile.TemporaryDirectory() as folder:
        for seed in range(n_seeds):
            rig = VirtualRig("neverest40", unit_seed=seed % 5, noise_seed=seed)
            run = rig.transient(Path(folder) / "transient.csv", duration=1.2)
            result = identify(read_any(run.paths[0], cpr=rig.motor.cpr), cpr=rig.motor.cpr)
            truth = run.truth["expected"]
            for name in NAMES:
                lo, hi = result[name].interval(1.96)
                inside[name].append(bool(lo <= truth[name] <= hi))
    rates = {name: float(np.mean(hits)) for name, hits in inside.items()}
    held = all(0.90 <= rate <= 0.98 for rate in rates.values())
    print(f"rig transient files, {n_seeds} seeds ({time.perf_counter() - start:.0f} s): 95 % coverage "
          + ", ".join(f"{name} {rate:.0%}" for name, rate in rates.items())
          + f"; bar 90-98 % {'holds' if held else 'FAILS'}")
    for name, hits in inside.items():
        print(f"  {name} misses at seeds {[k for k, hit in enumerate(hits) if not hit]}")
    return inside


def independent(seeds: range = range(20, 32)) -> None:
    """|z| against the Radau reference for both drives (the bar: < 3 in at least 10 of 12, < 2 in 90 %)."""
    logged = _load(TESTS / "analyses" / "ivp_reference.py", "ivp_reference").logged
    from motorlab.model import MotorParams

    truth = MotorParams(K=0.35, R=2.5, L=7e-4, J=8e-4, b=2e-3, Tf=0.03).to_dict()
    for on_samples in (False, True):
        start = time.perf_counter()
        within = dict.fromkeys(truth, 0)
        within_2: list[bool] = []
        worst = 0.0
        for seed in seeds:
            rec, _ = logged(truth, seed, duration=0.6, dt=1e-4, on_samples=on_samples,
                            voltage_noise=0.0 if on_samples else 0.02)
            result = identify(rec)
            for name, value in truth.items():
                z = abs(result[name].value - value) / result[name].stderr
                worst = max(worst, z)
                within[name] += int(z < 3.0)
                within_2.append(bool(z < 2.0))
        held = all(n >= len(seeds) - 2 for n in within.values()) and np.mean(within_2) >= 0.9 and worst < 4
        print(f"independent simulator, {'on sample instants' if on_samples else 'between samples'}, "
              f"{len(seeds)} seeds ({time.perf_counter() - start:.0f} s): within 3σ {within}, "
              f"within 2σ {np.mean(within_2):.0%}, max |z| {worst:.2f}; bar {'holds' if held else 'FAILS'}")


def feedforward(n_seeds: int = 50) -> None:
    """Coverage of kS, kV, kA's 95 % intervals on SysId tests (the bar: 90-98 %)."""
    from motorlab.analyses.feedforward import feedforward as fit

    module = _load(TESTS / "analyses" / "test_feedforward.py", "bench_feedforward_tests")
    inside: dict[str, list[bool]] = {}
    start = time.perf_counter()
    for seed in range(n_seeds):
        result = fit(module.sysid_tests(500 + seed))
        for name, truth in module.GAINS.items():
            lo, hi = result[name].interval(1.96)
            inside.setdefault(name, []).append(bool(lo <= truth <= hi))
    rates = {name: float(np.mean(hits)) for name, hits in inside.items()}
    held = all(0.90 <= rate <= 0.98 for rate in rates.values())
    print(f"feedforward, {n_seeds} seeds ({time.perf_counter() - start:.0f} s): 95 % coverage "
          + ", ".join(f"{name} {rate:.0%}" for name, rate in rates.items())
          + f"; bar 90-98 % {'holds' if held else 'FAILS'}")


def main() -> None:
    rig_transient()
    independent()
    feedforward()


if __name__ == "__main__":
    main()
