"""The fuzz corpus: valid files of every format motorlab reads, and the command that reads each.

Written by the virtual dynamometer (``motorlab.rig``: the same code ``motorlab simulate`` runs) into a
folder once, plus, when present, the shared real data in ``../shared/data/real`` (where
``tests/real_data.py`` finds it; ``MOTORLAB_REAL_DATA`` names another folder). Each :class:`Seed` is one
valid run: its files, the command and the options that make it succeed. The fuzzer mutates the files, the
options or both (``tests/fuzz/mutate.py``).
"""

from __future__ import annotations

import json
import shutil
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from tests.real_data import find_real_dir as shared_real

#: Real logs also given as ``real-*`` seeds (identify on the flywheel, feed-forward on the others): the five scored
#: SysId logs of real robots and a SysId flywheel, in ``../shared/data/real``.
REAL_LOGS = ("sysid/mbb_drivetrain.json", "sysid/romi_drivetrain_small.json", "sysid/stma7028_shooter_0309.json",
             "sysid/t581_drivetrain_compbot.json", "sysid/t581_spu_roller.json", "sysid-flywheel.json")


@dataclass(frozen=True)
class Seed:
    """One valid run: ``motorlab *command *files *options`` succeeds (exit 0) on the corpus files.

    ``files`` are names inside the corpus folder, given as positional arguments; ``support`` are
    files the inputs refer to (a session's logs), copied beside them; ``kind`` says how to mutate
    the inputs (``text``, ``json``, ``toml``, ``binary``); ``outputs`` are the output options the
    command is given (relative names), the only files it may create.
    """

    name: str
    command: tuple[str, ...]
    files: tuple[str, ...] = ()
    options: tuple[str, ...] = ()
    kind: str = "text"
    support: tuple[str, ...] = ()
    outputs: tuple[str, ...] = ()
    json_output: bool = True
    real: bool = False
    slow: bool = False
    tags: frozenset[str] = field(default_factory=frozenset)


SESSION_TOML = """\
[session]
title = "fuzz session"

[motor]
catalog = "neverest40"

[rig]
lever_arm = "0.15 m"

[units.A.lcr]
files = ["lcr.csv"]
[units.A.terminal]
files = ["terminal.csv"]
[units.A.torque]
files = ["torque.csv"]
"""


def build(folder: Path) -> list[Seed]:
    """Write the corpus into ``folder`` (once: a stamp file marks it done) and return its seeds."""
    folder.mkdir(parents=True, exist_ok=True)
    stamp = folder / ".complete"
    if not stamp.exists():
        _write(folder)
        stamp.write_text("ok\n")
    return seeds(folder)


def _write(folder: Path) -> None:
    from motorlab.io import write_sysid_wpilog
    from motorlab.rig import VirtualRig
    from motorlab.rig.ftc import simulate_flight_log, simulate_ramp

    rig = VirtualRig("neverest40", unit_seed=1, noise_seed=7)
    rig.run("spindown", folder / "spindown.txt", on_time=5.0, coast_time=10.0)
    rig.run("spinup", folder / "spinup.txt", duration=5.0)
    rig.free_spinup(folder / "free_spinup.csv", waveform=folder / "waveform.csv")
    for name in ("terminal", "lcr", "torque", "amplifier", "tachometer", "pulse"):
        rig.run(name, folder / f"{name}.csv")
    rig.run("transient", folder / "transient.csv", duration=1.0)
    rig.run("sysid", folder / "sysid.json", quasistatic_duration=6.0, dynamic_duration=2.0)
    simulate_ramp(folder / "ramp.json", seed=3)
    simulate_flight_log(folder / "flight.log", duration=4.0, seed=3)
    t = np.arange(0.0, 3.0, 0.02)
    volts = np.where(t < 1.5, 0.5 + 2.0 * t, -0.5 - 2.0 * (t - 1.5))
    position = np.cumsum(volts) * 0.02 * 0.8
    velocity = np.gradient(position, t)
    states = ["quasistatic-forward" if v > 0 else "quasistatic-reverse" for v in volts]
    write_sysid_wpilog(folder / "sysid.wpilog", t, volts, position, velocity, states)
    for stray in folder.glob("truth*.json"):
        stray.rename(folder / f"_{stray.name}")  # the rig's truth files are not inputs
    (folder / "session.toml").write_text(SESSION_TOML)
    # An `analyze --json` result to give `tune --params`.
    (folder / "params.json").write_text(json.dumps({
        "experiment": "feedforward",
        "parameters": {"kS": {"value": 0.41, "stderr": 0.002, "unit": "V"},
                       "kV": {"value": 0.55, "stderr": 0.05, "unit": "V*s/rad"},
                       "kA": {"value": 0.045, "stderr": 0.003, "unit": "V*s^2/rad"}},
        "warnings": [],
    }, indent=2))
    shared = shared_real()
    if shared is not None:
        for name in REAL_LOGS:
            shutil.copy(shared / name, folder / f"real_{Path(name).name}")
        (folder / "shared").mkdir(exist_ok=True)
        for path in sorted(shared.rglob("*")):
            if path.is_file() and path.suffix in (".json", ".csv") and path.stat().st_size < 3_000_000:
                shutil.copy(path, folder / "shared" / f"{path.parent.name}_{path.name}")


def seeds(folder: Path) -> list[Seed]:
    """The valid runs over the files of ``folder``."""
    out = [
        Seed("spindown", ("analyze", "spindown"), ("spindown.txt",), ("--cpr", "1120"), outputs=("--plot",)),
        Seed("spinup", ("analyze", "spinup"), ("spinup.txt",), ("--cpr", "1120", "--inertia", "12.2")),
        Seed("free-spinup", ("analyze", "free-spinup"), ("free_spinup.csv",), ("--K", "0.7", "--current", "0.5 A")),
        Seed("free-spinup-waveform", ("analyze", "free-spinup"), ("waveform.csv",),
             ("--K", "0.7", "--current", "0.5 A", "--cpr", "1120")),
        Seed("terminal", ("analyze", "terminal"), ("terminal.csv",), ("--K", "0.7"), outputs=("--plot",)),
        Seed("lcr", ("analyze", "lcr"), ("lcr.csv",)),
        Seed("torque", ("analyze", "torque"), ("torque.csv",)),
        Seed("amplifier", ("analyze", "amplifier"), ("amplifier.csv",)),
        Seed("tachometer", ("analyze", "tachometer"), ("tachometer.csv",)),
        Seed("pulse", ("analyze", "pulse"), ("pulse.csv",), ("--Ka", "1.96", "--K", "0.7")),
        Seed("identify", ("analyze", "identify"), ("transient.csv",), ("--cpr", "1120"), slow=True),
        Seed("feedforward-csv", ("analyze", "feedforward"), ("transient.csv",), ("--cpr", "1120"), slow=True),
        Seed("feedforward-sysid", ("analyze", "feedforward"), ("sysid.json",), kind="json", slow=True),
        Seed("feedforward-ramp", ("analyze", "feedforward"), ("ramp.json",), ("--cpr", "8192"), kind="json",
             slow=True),
        Seed("feedforward-flight", ("analyze", "feedforward"), ("flight.log",), ("--cpr", "537.7"), kind="binary",
             slow=True),
        Seed("feedforward-wpilog", ("analyze", "feedforward"), ("sysid.wpilog",), kind="binary", slow=True),
        Seed("tune", ("tune", "velocity"), (), ("--params", "params.json"), kind="json", support=("params.json",),
             outputs=("--plot",)),
        Seed("characterize", ("characterize",), ("session.toml",), ("--no-report", "-o", "results"), kind="toml",
             support=("lcr.csv", "terminal.csv", "torque.csv"), json_output=False, tags=frozenset({"session"})),
        Seed("simulate", ("simulate", "torque"), (), ("--motor", "neverest40", "-o", "sim.csv"), json_output=False,
             tags=frozenset({"writes-truth"})),
        Seed("plan", ("plan",), (), ("--motor", "neverest60"), json_output=False),
        Seed("motors", ("motors",), (), ("neverest40",), json_output=False),
    ]
    for path in sorted(folder.glob("real_*.json")):
        reads = "identify" if "flywheel" in path.name else "feedforward"
        out.append(Seed(f"real-{path.stem[5:]}", ("analyze", reads), (path.name,), kind="json", real=True,
                        slow=True))
    for path in sorted((folder / "shared").glob("*")) if (folder / "shared").is_dir() else []:
        if path.suffix == ".json":
            out.append(Seed(f"shared-{path.stem}", ("analyze", "feedforward"), (f"shared/{path.name}",), kind="json",
                            real=True, slow=True))
        elif "motor-curve" in path.name:  # a VEX dynamometer curve (12 V, no voltage column): analyze curve
            out.append(Seed(f"shared-{path.stem}", ("analyze", "curve"), (f"shared/{path.name}",), ("--voltage", "12"),
                            real=True))
        elif "locked-rotor" in path.name or "peak" in path.name:
            # Tables that no analysis reads as they are: the reader must still answer in one line.
            out.append(Seed(f"shared-{path.stem}", ("analyze", "curve"), (f"shared/{path.name}",), ("--voltage", "12"),
                            real=True, tags=frozenset({"any-outcome"})))
    return out
