"""Road Runner forward ramps on the simulated mecanum drive: accuracy, coverage and timing over seeds.

Compares motorlab's output-error fit with the tuning page's regression (applied voltage against the
repaired dead-wheel velocity, with intercept: kV slope, kS intercept).

    .venv/bin/python benchmarks/bench_roadrunner.py [SEEDS]
"""

from __future__ import annotations

import math
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from motorlab.feedforward import feedforward
from motorlab.io import read_any
from motorlab.io.roadrunner import drive_voltage
from motorlab.rig.ftc import simulate_ramp


def main(seeds: int = 20) -> None:
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for seed in range(seeds):
            path = Path(tmp) / f"ramp{seed}.json"
            truth = simulate_ramp(path, seed=100 + seed)
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
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 20)
