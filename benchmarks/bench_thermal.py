"""Heat (issue 23): targets

- a 300 s locked-rotor run fits (analyze stall) in under 2 s;
- a forecast (simulate stall --params) in under 0.2 s;
- the heated simulator: 300 s of a stalled motor on the virtual dynamometer (for reference).

Runs on a real 300 s export (VEX's BAG at 4 V) when ../shared/data/real/dyno is beside the clone, else on a
simulated one. Then, on VEX's exports (the shared ones, and those of ``--dyno DIR``): each motor's K against its
maker's figure, each healthy run's forecast from its first 120 s, and the population of cases behind the prior.

    python benchmarks/bench_thermal.py [--dyno DIR ...]

``--dyno`` a folder of VEX's dynamometer exports fetched by the person (e.g. ``motor_data/`` of the public
repository kForth/FrcMotorCompare, commit ed54731, which also holds the AndyMark 775 and BaneBots 550 and 775
that ../shared/data/real/dyno lacks); an export of the same name in the shared folder is read once.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

from motorlab.analyses.stall import stall
from motorlab.experiments.stall import read_runs
from motorlab.rig import VirtualRig
from motorlab.thermal.forecast import forecast, load_fit

HERE = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(HERE))
from tests.real_data import find_dyno_dir  # noqa: E402


def best_of(n: int, fn) -> float:
    times = []
    for _ in range(n):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dyno", type=Path, action="append", default=[],
                        help="a folder of VEX dynamometer exports besides ../shared/data/real/dyno (repeatable)")
    args, _ = parser.parse_known_args(argv)  # benchmarks/run.py passes its own arguments through
    shared = find_dyno_dir()
    dirs = [d for d in (shared, *args.dyno) if d is not None]
    with tempfile.TemporaryDirectory() as tmp:
        rig = VirtualRig("neverest40", noise_seed=1)
        t_rig = best_of(1, lambda: rig.stall(Path(tmp) / "s.csv", voltage=6.0, duration=300.0))
        real = shared / "bag-locked-rotor-data-4v-20151207.csv" if shared is not None else None
        path = str(real) if real is not None else str(Path(tmp) / "s.csv")
        rec = read_runs([path])[0]
        result = stall(rec)
        t_fit = best_of(3, lambda: stall(rec))
        fit = Path(tmp) / "fit.json"
        fit.write_text(json.dumps(result.to_dict()))
        model = load_fit(fit)
        t_fc = best_of(5, lambda: forecast(model, 12.0, 300.0))
    print(f"fit of a 300 s stall run ({Path(path).name}, {result.n_points} samples): {t_fit:8.3f} s   (target < 2 s)")
    print(f"forecast, 300 s at 0.1 s with the answers:          {t_fc * 1e3:8.1f} ms  (target < 200 ms)")
    print(f"virtual dynamometer, 300 s stalled and heating:     {t_rig:8.2f} s")
    if not dirs:
        print("no dynamometer exports: ../shared/data/real/dyno is not beside the clone and no --dyno was given")
        return
    makers(dirs)
    forecasts(dirs)
    population(dirs)


def exports(dirs: list[Path], pattern: str) -> list[Path]:
    """The exports matching ``pattern`` in ``dirs``, one per file name (the first folder's), sorted by name."""
    found: dict[str, Path] = {}
    for d in dirs:
        for p in d.glob(pattern):
            found.setdefault(p.name, p)
    return [found[name] for name in sorted(found)]


def makers(dirs: list[Path]) -> None:
    """Each motor's locked-rotor runs fitted together: K against the maker's 12 V stall torque / stall current (the
    speed-0 row of VEX's curve), R at 25 °C against V/I at the first full sample of the coolest run (the bars of
    tests/analyses/test_stall_motors.py and test_stall.py: 20 % and 10 %)."""
    import numpy as np

    from motorlab.io.csv_table import read_csv

    print("K of all of a motor's runs against the maker's stall torque / stall current, R against V/I:")
    for curve_path in exports(dirs, "*-motor-curve-data-*.csv"):
        motor = curve_path.name.split("-motor-curve-data-")[0]
        files = [str(p) for p in exports(dirs, f"{motor}-locked-rotor-data-*.csv")]
        if not files:
            continue
        curve_rec = read_csv(curve_path)
        row = int(np.argmin(curve_rec["speed"]))
        maker = float(curve_rec["torque"][row] / curve_rec["current"][row])
        result = stall(read_runs(files))
        fitted = [r for r in result.details["runs"] if r["heating explains it"] and r["healthy samples"] >= 30]
        text = f"  {motor:10s} K {result['K'].value:.5f} ± {result['K'].stderr:.5f} N·m/A, maker {maker:.5f} " \
               f"({100 * (result['K'].value / maker - 1):+.0f} %)"
        if fitted:
            coolest = min(fitted, key=lambda r: r["initial winding temperature (°C)"])
            rec = read_runs([next(f for f in files if Path(f).name == coolest["file"])])[0]
            k0 = int(np.searchsorted(rec.time, coolest["first full sample (s)"]))
            vi = float(rec["voltage"][k0] / rec["current"][k0])
            text += f"; R {result['R'].value:.4f} Ω, V/I {vi:.4f} Ω ({100 * (result['R'].value / vi - 1):+.0f} %)"
        print(text)


def forecasts(dirs: list[Path]) -> None:
    """Each run that heating explains, fitted on its first 120 s and forecast over the rest (relative RMS of the
    current; the judged aim: under 5 %)."""
    import math

    import numpy as np

    from motorlab.errors import InputError

    print("forecast of each healthy run from its first 120 s (relative RMS of the current over the rest):")
    with tempfile.TemporaryDirectory() as tmp:
        for path in exports(dirs, "*-locked-rotor-data-*.csv"):
            rec = read_runs([str(path)])[0]
            if not np.any(np.asarray(rec["current"]) > 0):
                continue  # torque only (Amps and Volts 0 in every row): no run to forecast
            fit = stall(rec, until=120.0)
            row = fit.details["runs"][0]
            end = row["cut (s)"] or float(rec.time[-1])
            if end < 150.0:
                continue
            (Path(tmp) / "fit.json").write_text(json.dumps(fit.to_dict()))
            try:
                out = forecast(load_fit(Path(tmp) / "fit.json"), float(row["set point (V)"]), end - float(rec.time[0]))
            except InputError:
                print(f"  {path.name:46s} not forecast: heating does not explain it (brush contact)")
                continue
            later = (rec.time > 120.0) & (rec.time < end)
            pred = np.interp(rec.time[later] - rec.time[0], out.time, out.current)
            rms = math.sqrt(float(np.mean(((pred - rec["current"][later]) / rec["current"][later]) ** 2)))
            print(f"  {path.name:46s} {100 * rms:5.2f} %")


def _motor(path: Path) -> str:
    return path.name.split("-locked-rotor-data-")[0]


def _forecast_rms(rec, tmp: Path) -> float | None:  # type: ignore[no-untyped-def]
    """Relative RMS of the forecast from the run's first 120 s over the rest (None: a run not forecast)."""
    import math

    import numpy as np

    from motorlab.errors import InputError

    fit = stall(rec, until=120.0)
    row = fit.details["runs"][0]
    end = row["cut (s)"] or float(rec.time[-1])
    (tmp / "fit.json").write_text(json.dumps(fit.to_dict()))
    try:
        out = forecast(load_fit(tmp / "fit.json"), float(row["set point (V)"]), end - float(rec.time[0]))
    except InputError:
        return None
    later = (rec.time > 120.0) & (rec.time < end)
    pred = np.interp(rec.time[later] - rec.time[0], out.time, out.current)
    return math.sqrt(float(np.mean(((pred - rec["current"][later]) / rec["current"][later]) ** 2)))


def population(dirs: list[Path]) -> None:
    """The empirical prior on the case's time constant R_ca·C_c (``_stall_fit.PRIOR_CASE_TIME_CONSTANT``): each
    healthy run of at least 150 s of every motor here fitted alone over its whole length; the runs whose R_ca is
    determined give the population. Then each run forecast from its first 120 s with the prior of the other
    motors only (leave one motor out)."""
    import math

    import numpy as np

    from motorlab.analyses import _stall_fit

    runs = []
    shipped = (_stall_fit.PRIOR_CASE_TIME_CONSTANT, _stall_fit.PRIOR_LOG_SIGMA)
    for path in exports(dirs, "*-locked-rotor-data-*.csv"):
        rec = read_runs([str(path)])[0]
        if not np.any(np.asarray(rec["current"]) > 0):
            continue
        full = stall(rec)
        row = full.details["runs"][0]
        if (row["cut (s)"] or float(rec.time[-1])) < 150.0 or "unexplained" in full.details:
            continue
        _stall_fit.PRIOR_LOG_SIGMA = math.inf  # the population from the runs alone: no prior (its weight is 0)
        try:
            alone = stall(rec)
        finally:
            _stall_fit.PRIOR_LOG_SIGMA = shipped[1]
        r_ca, c_c = alone["R_ca"], alone["C_c"]
        runs.append((path, rec, r_ca.value * c_c.value if r_ca.determined else None))
    known = [(_motor(p), math.log(tc)) for p, _, tc in runs if tc is not None]
    logs = np.array([v for _, v in known])
    print(f"case time constant R_ca·C_c over {len(known)} runs of {len({m for m, _ in known})} motors whose whole run "
          f"determines R_ca: {np.exp(logs.min()):.0f}–{np.exp(logs.max()):.0f} s, geometric mean "
          f"{np.exp(logs.mean()):.0f} s, a factor {np.exp(logs.std(ddof=1)):.2f} either way "
          f"(the prior used: {_stall_fit.PRIOR_CASE_TIME_CONSTANT:g} s, log sd {_stall_fit.PRIOR_LOG_SIGMA:g})")
    print("forecast from 120 s with the prior as shipped, and with the prior of the other motors only:")
    with tempfile.TemporaryDirectory() as tmp:
        try:
            for path, rec, _ in runs:
                others = np.array([v for m, v in known if m != _motor(path)])
                _stall_fit.PRIOR_CASE_TIME_CONSTANT, _stall_fit.PRIOR_LOG_SIGMA = shipped
                a = _forecast_rms(rec, Path(tmp))
                _stall_fit.PRIOR_CASE_TIME_CONSTANT = float(np.exp(others.mean()))
                _stall_fit.PRIOR_LOG_SIGMA = float(others.std(ddof=1))
                b = _forecast_rms(rec, Path(tmp))
                text = " ".join("not forecast" if v is None else f"{100 * v:5.2f} %" for v in (a, b))
                print(f"  {path.name:46s} {text}   (others' prior {_stall_fit.PRIOR_CASE_TIME_CONSTANT:.0f} s)")
        finally:
            _stall_fit.PRIOR_CASE_TIME_CONSTANT, _stall_fit.PRIOR_LOG_SIGMA = shipped


if __name__ == "__main__":
    main()
