"""Real SysId logs: motorlab's kS, kV, kA against the teams' own gains and SysId's OLS, on the fair score.

The score (``motorlab.analyses.sysid_score``, shared/data/real/sysid/README.md): every test, both drivetrain
sides, simulated open loop from the logged voltage; RMSE against the logged speed and position, in
the file's own units. Ratios are RMSE / the team's RMSE (below 1: better than the team).

    python benchmarks/bench_real_sysid.py [--dir DIR] [--plots DIR] [--limits]

``--dir`` a folder of JSON logs whose README.md tables the teams' gains (default ../shared/data/real/sysid, read
in place; a folder without that table is scored with the default folder's gains for the files it holds);
``--plots`` writes one PNG per file (logged against simulated speed and position, team and
motorlab, residuals beneath); ``--limits`` also fits the best three gains for each score alone
(the lower bounds any three gains can reach) and each drivetrain side alone.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

from motorlab.analyses.feedforward import feedforward, sysid_ols
from motorlab.analyses.sysid_score import Score, file_tests, fit_gains, score, simulate_gains
from motorlab.io import read_any

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
from tests.real_data import find_real_dir, not_found, team_gains  # noqa: E402

REAL = find_real_dir()
DEFAULT_DIR = REAL / "sysid" if REAL is not None else None


def team_table(folder: Path) -> dict[str, tuple[float, float, float]]:
    """The teams' gains of the files in ``folder`` (its README's table, else the shared one for the files present)."""
    try:
        return team_gains(folder)
    except (OSError, ValueError):
        if DEFAULT_DIR is None or folder.resolve() == DEFAULT_DIR.resolve():
            raise
        return {k: v for k, v in team_gains(DEFAULT_DIR).items() if (folder / k).exists()}


def evaluate(path: Path, team: tuple[float, float, float], *, limits: bool) -> dict:
    """Scores of the team's, OLS and motorlab's gains on one file (gains in the file's units)."""
    rec = read_any(path, side="both")
    unit = float(rec.metadata["si_per_unit"])
    tests = file_tests(path)
    parts = rec.split()
    start = time.perf_counter()
    result = feedforward(parts)
    elapsed = time.perf_counter() - start
    ours = (result.value("kS"), result.value("kV") * unit, result.value("kA") * unit)
    ols_si = sysid_ols(parts)
    ols = (ols_si["kS"], ols_si["kV"] * unit, ols_si["kA"] * unit)
    physics = result.details.get("physics_fit")
    out = {"team": (team, score(team, tests)), "motorlab": (ours, score(ours, tests)), "time": elapsed,
           "result": result, "tests": tests, "unit": unit}
    out["ols"] = (ols, score(ols, tests) if ols[1] > 0 and ols[2] >= 0 else Score(math.nan, math.nan))
    if physics:
        model = (physics["kS"]["value"], physics["kV"]["value"] * unit, physics["kA"]["value"] * unit)
        out["motor model"] = (model, score(model, tests) if model[2] >= 0 else Score(math.nan, math.nan))
    if limits:
        for label, weight in (("best speed", 0.0), ("best position", 1e6)):
            fit = fit_gains(tests, [ours], position_weight=weight)
            out[label] = (tuple(fit.gains), fit.score)
        sides = {t.name.split("#")[1] for t in tests if "#" in t.name}
        for side in sorted(sides):
            part = [t for t in tests if t.name.endswith("#" + side)]
            out[f"{side} side only"] = (tuple(fit_gains(part, [ours]).gains), Score(math.nan, math.nan))
    return out


def turning(path: Path) -> dict[str, float]:
    """Gyro angle change over each drivetrain test (column 8 of SysId drivetrain rows) [rad]; {} otherwise."""
    import json

    data = json.loads(path.read_text())
    out = {}
    for key in ("slow-forward", "slow-backward", "fast-forward", "fast-backward"):
        rows = np.asarray(data.get(key, []), dtype=float)
        if rows.ndim == 2 and rows.shape[1] == 9 and rows.shape[0] > 1:
            out[key] = float(rows[-1, 7] - rows[0, 7])
    return out


def plot_file(name: str, out: dict, folder: Path) -> Path:
    """Logged against open-loop simulated speed and position per test, team and motorlab, residuals beneath."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    tests = out["tests"]
    fig, axes = plt.subplots(4, len(tests), figsize=(2.2 * len(tests), 6.4), sharex="col",
                             gridspec_kw={"height_ratios": [3, 1, 3, 1]}, squeeze=False)
    for j, test in enumerate(tests):
        t = test.time
        axes[0, j].plot(t, test.velocity, color="0.3", lw=1.2, label="logged")
        axes[2, j].plot(t, test.position - test.position[0], color="0.3", lw=1.2, label="logged")
        for label, color in (("team", "tab:orange"), ("motorlab", "tab:blue")):
            g = out[label][0]
            speed, position = simulate_gains(g[0], g[1], g[2], test)
            axes[0, j].plot(t, speed, color=color, lw=0.8, label=label)
            axes[1, j].plot(t, speed - test.velocity, color=color, lw=0.6)
            axes[2, j].plot(t, position - test.position[0], color=color, lw=0.8, label=label)
            axes[3, j].plot(t, position - test.position, color=color, lw=0.6)
        axes[0, j].set_title(test.name.replace("#", "\n"), fontsize=7)
        axes[3, j].set_xlabel("t [s]", fontsize=7)
        for ax in axes[:, j]:
            ax.tick_params(labelsize=6)
    for i, label in enumerate(("speed", "speed resid.", "position", "pos. resid.")):
        axes[i, 0].set_ylabel(label, fontsize=7)
    axes[0, 0].legend(fontsize=6)
    fig.suptitle(f"{name}: logged vs open-loop simulated (units of the file)", fontsize=9)
    fig.tight_layout()
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"real-{Path(name).stem}.png"
    fig.savefig(path, dpi=72)
    plt.close(fig)
    return path


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dir", type=Path, default=DEFAULT_DIR)
    parser.add_argument("--plots", type=Path, default=None)
    parser.add_argument("--limits", action="store_true")
    args, _ = parser.parse_known_args(argv)  # benchmarks/run.py passes its own arguments through
    if args.dir is None:
        print(not_found("the shared real SysId logs (../shared/data/real/sysid)") + ": give --dir")
        return
    teams = team_table(args.dir)
    labels = ["motorlab", "ols", "motor model"] + (["best speed", "best position"] if args.limits else [])
    print("RMSE ratio to the team's gains (speed / position); team RMSE in the file's units")
    print(f"{'file':32s} {'team RMSE v / x':>17s} " + " ".join(f"{lab:>15s}" for lab in labels) + "  time")
    ratios: dict[str, list[tuple[float, float]]] = {lab: [] for lab in labels}
    evidence = []
    for name, team in teams.items():
        out = evaluate(args.dir / name, team, limits=args.limits)
        base = out["team"][1]
        cells = []
        for lab in labels:
            if lab in out:
                r = out[lab][1].ratio(base)
                ratios[lab].append(r)
                cells.append(f"{r[0]:6.3f} / {r[1]:6.3f}")
            else:
                cells.append(f"{'-':>15s}")
        print(f"{name:32s} {base.speed:8.4g} / {base.position:<6.4g} " + " ".join(cells) + f"  {out['time']:.1f} s")
        evidence.append((name, out))
        if args.plots:
            plot_file(name, out, args.plots)
    def geo(values: list[float]) -> float:
        return math.exp(float(np.nanmean(np.log(values))))

    print(f"{'pooled (geometric mean)':32s} {'':17s} " + " ".join(
        f"{geo([r[0] for r in v]):6.3f} / {geo([r[1] for r in v]):6.3f}" if v else f"{'-':>15s}"
        for v in ratios.values()))
    print("\ngains in the file's units (kS [V], kV [V/(u/s)], kA [V/(u/s²)]) and what the residuals show")
    for name, out in evidence:
        result = out["result"]
        diag = result.details.get("residual_diagnostics", {})
        print(f"{name}")
        for lab in ("team", *labels, "left side only", "right side only"):
            if lab in out:
                g = out[lab][0]
                print(f"    {lab:16s} kS {g[0]:9.5f}  kV {g[1]:9.5f}  kA {g[2]:9.6f}")
        for direction, g in result.details.get("by_direction", {}).items():
            u = out["unit"]
            print(f"    {direction + ' tests':16s} kS {g['kS']:9.5f}  kV {g['kV'] * u:9.5f}  kA {g['kA'] * u:9.6f}")
        turns = turning(args.dir / name)
        if turns:
            print("    gyro angle change per test [rad]: " + ", ".join(f"{k} {v:+.2f}" for k, v in turns.items()))
        if diag:
            print(f"    residuals: speed lag {1e3 * diag['lag_s']:.0f} ms (RMSE × {diag['lag_rmse_ratio']:.2f} when "
                  f"shifted), asymmetry {diag['asymmetry']:+.2f}, quasistatic drift {100 * diag['drift']:.0f} %")


if __name__ == "__main__":
    main()
