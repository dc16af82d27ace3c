"""Scale (issues 14 and 25): time and peak memory of every analysis on logs of 10k to 2M rows and on
scope waveform exports of 12 and 24 Mpts.

Targets: any analysis on 2M rows within 10 s and 500 MB peak resident memory; a 24 Mpt waveform
export through free-spinup within 20 s and 500 MB. Each run is ``motorlab analyze EXPERIMENT FILE
--json`` in a fresh Python process (so the peak is the command's own, imports included); the files
are written first, into a temporary folder under /tmp (never kept), in the formats a real rig writes:

- spindown, spinup: FTC OpMode logs from the exact simulator (flywheel rig, 1 ms log period);
- identify: the virtual rig's transient CSV (1 kHz); pulse: its scope CSV (four periods of 2 s);
  pulse-24: the same with 24 periods (48 regions, 51 fitted parameters);
- free-spinup: scope cursor times of n rising edges of a constant-current spin-up (closed form);
- feedforward: a SysId JSON whose four tests follow the feedforward model (closed form, 10 ms rows);
- terminal, lcr, torque, amplifier, tachometer: tables of n readings around the model's line;
- stall: the virtual rig's 300 s locked-rotor run at 4 V with heating (VEX's 0.35 s rows), interpolated to
  n rows with the meters' noise;
- curve: a 12 V motor curve of n rows (the motor model's steady states, meter noise; VEX's have ~100);
- waveform: free-spinup on a Rigol DS1054Z export of n samples of one encoder channel.

    python benchmarks/bench_scale.py [SIZES...] [--only=spindown,identify] [--waveform=12e6,24e6]

prints one table row per analysis and size: wall seconds, CPU seconds (child processes included),
peak MiB and the exit code. The peak is the command's own VmHWM (imports included: about 85–115 MiB
of it is Python, numpy, scipy and pint) or, when larger, the largest sum of the proportional set
sizes (PSS: shared pages divided among their sharers) of the command and its children, sampled
every 0.1 s (a large SysId file is parsed half in a forked child). The figures of issue 25, before
and after, are in docs/formats.md ("Large files").
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from motorlab.rig import VirtualRig

SIZES = (10_000, 100_000, 1_000_000, 2_000_000)
#: Samples of the scope waveform exports (a DS1054Z holds up to 24 Mpts a channel).
WAVEFORM_SIZES = (12_000_000, 24_000_000)
CPR = 1120

_RUN = """
import resource, sys, time, io, contextlib
t0 = time.perf_counter()
from motorlab.cli import main
out = io.StringIO()
with contextlib.redirect_stdout(out):
    code = main(sys.argv[1:])
elapsed = time.perf_counter() - t0
# VmHWM: this process's own peak (ru_maxrss would carry the parent's peak across fork and exec).
try:
    status = open("/proc/self/status").read()
    peak = int(status.split("VmHWM:")[1].split()[0]) / 1024
except (OSError, IndexError, ValueError):
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
usage = resource.getrusage(resource.RUSAGE_SELF)
children = resource.getrusage(resource.RUSAGE_CHILDREN)  # a large SysId file is parsed in a forked child
cpu = usage.ru_utime + usage.ru_stime + children.ru_utime + children.ru_stime
print(f"{elapsed:.3f} {peak:.1f} {code} {cpu:.3f}", file=sys.stderr)
"""


def _ftc(path: Path, n: int, *, coast: bool, rng: np.random.Generator) -> None:
    from motorlab.io import write_ftc_log
    from motorlab.model import MotorParams
    from motorlab.model.simulate import BenchSupply, CurrentDrive, OpenCircuit, simulate

    motor = MotorParams(K=0.35, R=2.0, L=0.6e-3, J=2e-4, b=1e-4, Tf=0.02).with_load(1.5e-3, ratio=25)
    duration = n * 1e-3
    if coast:
        drive = [(0.0, BenchSupply(12.0, 4.0)), (min(30.0, duration / 4), OpenCircuit())]
    else:
        drive = [(0.0, CurrentDrive(0.5))]
    sim = simulate(motor, drive, duration=duration, dt=1e-3)
    t = sim.time[:n]
    counts = np.floor(sim.position[:n] * CPR / (2 * math.pi))
    volts = sim.voltage[:n] + 0.004 * rng.standard_normal(t.size)
    amps = sim.current[:n] + 0.001 * rng.standard_normal(t.size)
    write_ftc_log(path, t, counts, volts, amps)


def _table(path: Path, n: int, columns: dict[str, np.ndarray]) -> None:
    from motorlab.io import write_csv

    write_csv(path, {k: np.round(v, 6) for k, v in columns.items()}, metadata={"cpr": CPR})


def _sysid(path: Path, n: int, rng: np.random.Generator) -> None:
    ks, kv, ka = 0.4, 1.0, 0.2  # V, V·s/rot, V·s²/rot
    quasi, dyn = int(0.35 * n), n // 2 - int(0.35 * n)
    doc: dict[str, object] = {}
    for name, rows, sign, kind in (("slow-forward", quasi, 1, "q"), ("slow-backward", quasi, -1, "q"),
                                   ("fast-forward", dyn, 1, "d"), ("fast-backward", dyn, -1, "d")):
        t = np.arange(rows) * 0.01
        if kind == "q":
            rate = 7.0 / max(t[-1], 1.0)
            volts = rate * t
            speed = np.maximum((volts - ks) / kv - rate * ka / kv**2, 0.0)
        else:
            volts = np.full(rows, 7.0)
            speed = (7.0 - ks) / kv * (1 - np.exp(-kv * t / ka))
        position = np.concatenate([[0.0], np.cumsum(0.5 * (speed[1:] + speed[:-1]) * 0.01)])
        speed = speed + 0.002 * rng.standard_normal(rows)
        doc[name] = np.column_stack([t + 10.0, sign * volts, sign * position, sign * speed]).round(6).tolist()
    doc.update({"sysid": True, "test": "Simple", "units": "Rotations", "unitsPerRotation": 1.0})
    path.write_text(json.dumps(doc))


def _stall(path: Path, n: int, rig: VirtualRig, rng: np.random.Generator) -> None:
    from motorlab.io import read_csv

    run = rig.stall(path, voltage=4.0, duration=300.0)
    rec = read_csv(run.paths[0])
    t = np.linspace(float(rec.time[0]), float(rec.time[-1]), n)
    noise = {"voltage": 0.001, "current": 0.02, "torque": 0.001}
    _table(path, n, {"time_s": t, **{f"{k}_{u}": np.interp(t, rec.time, rec[k]) + rng.normal(0, noise[k], n)
                                     for k, u in (("voltage", "V"), ("current", "A"), ("torque", "Nm"))}})


def _curve(path: Path, n: int, rng: np.random.Generator) -> None:
    k, r, kt, friction = 0.0190, 0.134, 0.0165, 0.045  # V·s/rad, Ω, N·m/A, N·m
    speed = np.linspace(0.0, (kt * 12.0 / r - friction) / (kt * k / r), n)
    current = (12.0 - k * speed) / r
    _table(path, n, {"speed_rad_per_s": speed + rng.normal(0, 0.5, n), "current_A": current + rng.normal(0, 0.02, n),
                     "torque_Nm": kt * current - friction + rng.normal(0, 0.002, n)})


def _edges(path: Path, n: int) -> None:
    from motorlab.io import write_csv

    gamma, accel = 0.5, 40.0  # 1/s, rad/s² of the free motor at the chosen current
    edge = 2 * math.pi / (CPR / 4)
    theta = np.arange(1, n + 1) * edge
    # θ(t) = (A/γ)·t − (A/γ²)(1 − e^{−γt}): solve for t by Newton from the late-time asymptote.
    t = theta * gamma / accel + 1.0 / gamma
    t = np.sqrt(2 * theta / accel) * (theta < accel / gamma**2) + t * (theta >= accel / gamma**2)
    for _ in range(30):
        f = accel / gamma * t - accel / gamma**2 * (1 - np.exp(-gamma * t)) - theta
        t -= f / (accel / gamma * (1 - np.exp(-gamma * t)))
    write_csv(path, {"time_ms": np.round(t * 1e3, 6)})


def _rigol(path: Path, n: int) -> None:
    """A Rigol DS1054Z export of ``n`` samples: one encoder channel (5 V logic, 8-bit steps, 20 mV noise)
    of a bare motor spinning up at constant current from a hand start (2.4 s, 280 rising edges per turn)."""
    increment, start = 2.4 / n, -0.2
    gamma, accel, omega0, per_turn = 0.5, 40.0, 5.0, 280.0
    rng = np.random.default_rng(1)
    with open(path, "w", newline="\n") as handle:
        handle.write(f"X,CH1,Start,Increment,\nSequence,Volt,{start:.6e},{increment:.6e},\n")
        for a in range(0, n, 1 << 20):
            k = np.arange(a, min(n, a + (1 << 20)))
            t = (k * increment).clip(0.0)
            theta = omega0 * (1 - np.exp(-gamma * t)) / gamma + accel / gamma * (t - (1 - np.exp(-gamma * t)) / gamma)
            volts = np.where((theta * per_turn / (2 * math.pi)) % 1.0 < 0.5, 5.0, 0.0) + rng.normal(0, 0.02, k.size)
            volts = np.round(volts / (10 / 256)) * (10 / 256)
            rows = np.empty(2 * k.size, dtype=object)
            rows[0::2], rows[1::2] = k.tolist(), volts.tolist()
            handle.write(("%d,%.4e,\n" * k.size) % tuple(rows))


def write_waveform(folder: Path, n: int) -> dict[str, tuple[list[str], list[str]]]:
    """free-spinup on a scope waveform export of ``n`` samples."""
    _rigol(folder / "waveform.csv", n)
    return {"waveform": ([str(folder / "waveform.csv")], ["--K", "0.7", "--current", "0.5 A", "--cpr", str(CPR)])}


def write_inputs(folder: Path, n: int) -> dict[str, tuple[list[str], list[str]]]:
    """Every analysis's file of ``n`` rows: experiment -> (paths, extra options)."""
    from motorlab.rig import VirtualRig

    rng = np.random.default_rng(n)
    rig = VirtualRig("neverest40", unit_seed=1, noise_seed=2)
    out: dict[str, tuple[list[str], list[str]]] = {}
    _ftc(folder / "spindown.txt", n, coast=True, rng=rng)
    out["spindown"] = ([str(folder / "spindown.txt")], ["--cpr", str(CPR)])
    _ftc(folder / "spinup.txt", n, coast=False, rng=rng)
    out["spinup"] = ([str(folder / "spinup.txt")], ["--cpr", str(CPR), "--inertia", "0.95"])
    rig.run("transient", folder / "transient.csv", duration=n / 1000.0, rate=1000.0)
    out["identify"] = ([str(folder / "transient.csv")], ["--cpr", str(CPR)])
    # A scope capture: four periods, n samples (a longer trace is a finer one, as on a real scope).
    rig.run("pulse", folder / "pulse.csv", period=2.0, periods=4, sample_interval=8.0 / n)
    out["pulse"] = ([str(folder / "pulse.csv")], ["--Ka", "1.96", "--K", "0.7"])
    # The same time base with 24 periods (48 regions: the fit's parameters grow with the pulses).
    rig.run("pulse", folder / "pulse24.csv", period=2.0, periods=24, sample_interval=48.0 / n)
    out["pulse-24"] = ([str(folder / "pulse24.csv")], ["--Ka", "1.96", "--K", "0.7"])
    _edges(folder / "edges.csv", n)
    out["free-spinup"] = ([str(folder / "edges.csv")], ["--K", "0.7", "--current", "0.5 A", "--cpr", str(CPR)])
    _sysid(folder / "sysid.json", n, rng)
    out["feedforward"] = ([str(folder / "sysid.json")], [])
    _stall(folder / "stall.csv", n, rig, rng)
    out["stall"] = ([str(folder / "stall.csv")], [])
    _curve(folder / "curve.csv", n, rng)
    out["curve"] = ([str(folder / "curve.csv")], ["--voltage", "12"])
    x = np.linspace(0.25, 1.0, n)
    noise = rng.standard_normal(n)
    _table(folder / "terminal.csv", n, {"current_A": 0.2 + 0.3 * x + 0.002 * noise, "frequency_Hz": 900 * x})
    out["terminal"] = ([str(folder / "terminal.csv")], ["--K", "0.7"])
    _table(folder / "lcr.csv", n, {"L_uH": 700 + 40 * np.sin(7 * x) + 3 * noise, "Q": 3.2 + 0.01 * noise,
                                    "DCR_ohm": 1.1 + 0.01 * noise})
    out["lcr"] = ([str(folder / "lcr.csv")], [])
    _table(folder / "torque.csv", n, {"current_A": 4 * x, "mass_kg": 0.45 * 4 * x + 0.003 * noise})
    out["torque"] = ([str(folder / "torque.csv")], ["--arm", "0.15 m"])
    _table(folder / "amplifier.csv", n, {"command_V": 5 * x, "current_A": 1.96 * 5 * x + 0.005 * noise})
    out["amplifier"] = ([str(folder / "amplifier.csv")], [])
    _table(folder / "tachometer.csv", n, {"speed_rpm": 300 * x, "tach_voltage_V": 0.003 * 300 * x + 0.001 * noise})
    out["tachometer"] = ([str(folder / "tachometer.csv")], [])
    return out


def measure(experiment: str, paths: list[str], options: list[str]) -> tuple[float, float, int, float]:
    """Seconds, peak MiB, exit code and CPU seconds of ``motorlab analyze EXPERIMENT PATHS OPTIONS --json``."""
    env = {**os.environ, "MPLBACKEND": "Agg"}
    command = {"pulse-24": "pulse", "waveform": "free-spinup"}.get(experiment, experiment)
    argv = [sys.executable, "-c", _RUN, "analyze", command, *paths, *options, "--json"]
    with tempfile.TemporaryFile("w+") as err:
        proc = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=err, text=True, env=env)
        tree = 0.0
        while proc.poll() is None:
            tree = max(tree, _tree_pss(proc.pid))
            time.sleep(0.1)
        err.seek(0)
        last = (err.read().strip().splitlines() or ["nan nan -1 nan"])[-1].split()
    try:
        return float(last[0]), max(float(last[1]), tree), int(last[2]), float(last[3])
    except (ValueError, IndexError):
        return math.nan, math.nan, proc.returncode, math.nan


def _tree_pss(pid: int) -> float:
    """Proportional set size [MiB] of process ``pid`` and its descendants (0 where /proc cannot tell)."""
    total = 0.0
    pending = [pid]
    while pending:
        p = pending.pop()
        try:
            with open(f"/proc/{p}/smaps_rollup") as rollup:
                total += next((int(line.split()[1]) for line in rollup if line.startswith("Pss:")), 0) / 1024
            with open(f"/proc/{p}/task/{p}/children") as children:
                pending += [int(c) for c in children.read().split()]
        except (OSError, ValueError):
            continue
    return total


def main() -> None:
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    only = next((a.split("=", 1)[1].split(",") for a in sys.argv[1:] if a.startswith("--only=")), None)
    waves = next((a.split("=", 1)[1].split(",") for a in sys.argv[1:] if a.startswith("--waveform=")), None)
    sizes = [int(float(a)) for a in args] or list(SIZES)
    wave_sizes = [int(float(a)) for a in waves if a] if waves is not None else list(WAVEFORM_SIZES)
    print("analysis      rows        seconds   cpu s   peak MiB  exit   (targets at 2M rows: <= 10 s, <= 500 MB)")
    jobs = [(n, write_inputs) for n in sizes if only != ["waveform"]] + [(n, write_waveform) for n in wave_sizes]
    for n, writer in jobs:
        with tempfile.TemporaryDirectory() as tmp:  # in /tmp: the inputs are never kept
            t0 = time.perf_counter()
            inputs = writer(Path(tmp), n)
            print(f"# {n} rows: inputs written in {time.perf_counter() - t0:.1f} s")
            for experiment, (paths, options) in inputs.items():
                if only and experiment not in only:
                    continue
                seconds, peak, code, cpu = measure(experiment, paths, options)
                print(f"{experiment:12s} {n:>10,d}   {seconds:9.2f}  {cpu:6.2f}  {peak:9.1f}  {code:4d}", flush=True)


if __name__ == "__main__":
    main()
