"""Road Runner forward ramps on the simulated mecanum drive: accuracy, coverage and timing over seeds.

Compares motorlab's output-error fit with the tuning page's regression (applied voltage against the
repaired dead-wheel velocity, with intercept: kV slope, kS intercept). Variants of the simulated files
(other loops, encoders, ramp lengths, ideal sensors) check that the fit does not depend on how our
simulator happens to write them.

    .venv/bin/python benchmarks/bench_roadrunner.py [SEEDS] [VARIANT ...]   (variants: see VARIANTS, or "all")
"""

from __future__ import annotations

import math
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from motorlab.analyses.feedforward import feedforward
from motorlab.io import read_any
from motorlab.io.roadrunner import drive_voltage
from motorlab.model import MotorParams
from motorlab.rig.ftc import (
    Battery,
    BulkReadLoop,
    HubEncoder,
    HubVoltageSensor,
    MecanumDrive,
    RampSettings,
    simulate_ramp,
)

_EXACT = HubVoltageSensor(noise=0.0, resolution=1e-7)
#: Options of simulate_ramp for each variant.
VARIANTS: dict[str, dict[str, object]] = {
    "default": {},
    # Road Runner's own logger loop: no idle time, the period spent in long Lynx commands
    "logger-loop": {"loop": BulkReadLoop(min_period=0.0205, max_period=0.0205, mean_extra=0.0, command_time=3e-3,
                                         voltage_read_time=3.5e-3, bulk_read_time=5e-3)},
    "fixed-20ms": {"loop": BulkReadLoop(min_period=0.02, max_period=0.02, mean_extra=0.0)},
    "fast-loop": {"loop": BulkReadLoop(min_period=0.005, max_period=0.012, mean_extra=0.002, command_time=3e-4,
                                       voltage_read_time=5e-4, bulk_read_time=1e-3)},
    "short-3s": {"settings": RampSettings(duration=3.0)},
    "cpr2000": {"drive": MecanumDrive(dead_wheel=HubEncoder(2000))},
    "cpr537.7": {"drive": MecanumDrive(dead_wheel=HubEncoder(537.7), dead_wheel_radius=0.048)},
    "no-sag": {"battery": Battery(internal_resistance=0.0, drift=0.0)},
    "exact-battery": {"sensor": _EXACT},
    # no noise, no sag, a perfect loop, L = 0: what is left is the method
    "ideal": {"sensor": _EXACT, "battery": Battery(internal_resistance=0.0, drift=0.0),
              "loop": BulkReadLoop(min_period=0.02, max_period=0.02, mean_extra=0.0, command_time=1e-6,
                                   voltage_read_time=1e-6, bulk_read_time=1e-6),
              "drive": MecanumDrive(motor=MotorParams(K=0.34, R=1.3, L=1e-6, J=2e-3, b=1e-3, Tf=0.08))},
}


def main(seeds: int = 20, variant: str = "default") -> None:
    rows = []
    print(f"== {variant}")
    with tempfile.TemporaryDirectory() as tmp:
        for seed in range(seeds):
            path = Path(tmp) / f"ramp{seed}.json"
            truth = simulate_ramp(path, seed=100 + seed, **VARIANTS[variant])  # type: ignore[arg-type]
            t0 = time.perf_counter()
            rec = read_any(path, cpr=truth["cpr"])
            result = feedforward(rec, cpr=truth["cpr"])
            elapsed = time.perf_counter() - t0
            data = rec.metadata["roadrunner"]
            vel = np.mean(list(data.velocities.values()), axis=0) * 2 * math.pi / truth["cpr"]
            moving = vel > 0
            kv_page, ks_page = np.polyfit(vel[moving], drive_voltage(data)[moving], 1)
            row = {"time": elapsed}
            for name in ("kS", "kV", "kA"):
                est = result[name]
                row[name] = est.value / truth[name] - 1
                row[name + "_z"] = (est.value - truth[name]) / est.stderr
            row["kS_page"] = ks_page / truth["kS"] - 1
            row["kV_page"] = kv_page / truth["kV"] - 1
            rows.append(row)
    for name in ("kS", "kV", "kA"):
        err = np.array([r[name] for r in rows])
        z = np.array([r[name + "_z"] for r in rows])
        print(f"{name}: error mean {100 * err.mean():+.2f} %, max |error| {100 * np.abs(err).max():.2f} %, "
              f"|z| < 2 in {100 * np.mean(np.abs(z) < 2):.0f} %, |z| < 3 in {100 * np.mean(np.abs(z) < 3):.0f} %")
    for name in ("kS_page", "kV_page"):
        err = np.array([r[name] for r in rows])
        print(f"{name} (tuning-page regression): error mean {100 * err.mean():+.2f} %, "
              f"max |error| {100 * np.abs(err).max():.2f} %")
    print(f"read + fit: {np.median([r['time'] for r in rows]) * 1e3:.0f} ms per file (median of {seeds})")


if __name__ == "__main__":
    names = sys.argv[2:] or ["default"]
    for name in list(VARIANTS) if names == ["all"] else names:
        main(int(sys.argv[1]) if len(sys.argv) > 1 else 20, name)
