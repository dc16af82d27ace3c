"""Regenerate the figures of docs/roadrunner-pedro.md from the simulated mecanum drive.

    .venv/bin/python scripts/roadrunner_figures.py [OUTDIR]
"""

from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from motorlab.analyses.roadrunner import from_runs
from motorlab.io import read_any
from motorlab.io.roadrunner import read_ramp_data
from motorlab.plot import plot_fit, save_figure
from motorlab.rig.ftc import simulate_ramp


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        paths = {k: Path(tmp) / f"{k}-ramp.json" for k in ("forward", "lateral", "angular")}
        truth = {k: simulate_ramp(p, kind=k, seed=5) for k, p in paths.items()}["forward"]
        cpr = truth["cpr"]
        raw = json.loads(paths["forward"].read_text())
        data = read_ramp_data(paths["forward"])
        fig, axes = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
        rec = read_any(paths["forward"], cpr=cpr)
        axes[0].plot(rec.time, rec["voltage"], label="applied = power × battery")
        axes[0].plot(rec.time, rec["battery"] / 10, label="battery / 10 (sags under load)")
        axes[0].set_ylabel("V")
        axes[0].legend(fontsize=8)
        t = np.asarray(raw["forwardEncVels"][0]["times"])
        axes[1].plot(t, raw["forwardEncVels"][0]["values"], ".", ms=2, label="hub velocity as logged (16-bit)")
        axes[1].plot(data.time, data.velocities["forward0"], label="repaired from the positions")
        axes[1].set_ylabel("dead wheel [ticks/s]")
        axes[1].set_xlabel("time [s]")
        axes[1].legend(fontsize=8)
        fig.suptitle("Road Runner forward ramp (simulated mecanum, 8192-count dead wheels)", fontsize=10)
        fig.tight_layout()
        save_figure(fig, out / "rr-forward-ramp.png")
        runs = [read_any(p, cpr=cpr) for p in paths.values()]
        result = from_runs(runs, cpr=cpr)
        save_figure(plot_fit(result), out / "rr-fit.png")
        print(result.report())
        print({k: truth[k] for k in ("kS", "kV", "kA", "track_width_ticks", "lateral_ratio")})


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path("docs/img"))
