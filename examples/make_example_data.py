"""Write the data files ``examples/session.toml`` names (units A, B, C), from the virtual dynamometer.

The files are shipped with the repository, so that ``motorlab characterize examples/session.toml``
works as written; this script regenerates them (``python examples/make_example_data.py``). Each unit
is a simulated NeveRest 40 drawn with its own seed, with its own gearbox drawn around the
catalogue's (η ≈ 0.31, as the sheet's stall torque implies: docs/gearbox.md), as the demo's units are;
the true parameters are in each file's ``truth.json``, which the session does not use.
"""

from __future__ import annotations

from pathlib import Path

from motorlab.catalog import Motor
from motorlab.rig import VirtualRig
from motorlab.rig.units import draw_gearbox

HERE = Path(__file__).resolve().parent

#: unit -> (unit seed, experiments as (rig experiment, file, settings)) — as examples/session.toml lists them.
UNITS = {
    "A": (1, [
        ("lcr", "lcr.csv", {}),
        ("spindown", "testFile.txt", {"split": True, "on_time": 20.0, "coast_time": 40.0}),
        ("spinup", "spinup.txt", {"current": 2.0, "duration": 10.0}),
        ("torque", "torque.csv", {}),
        ("terminal", "terminal.csv", {}),
        ("free-spinup", "free_spinup.csv", {"current": 0.5}),
        ("transient", "transient.csv", {"duration": 2.0}),
    ]),
    "B": (2, [
        ("lcr", "lcr.csv", {}),
        ("spindown", "spindown.txt", {"on_time": 20.0, "coast_time": 40.0}),
        ("terminal", "terminal.csv", {}),
        ("free-spinup", "free_spinup.csv", {"current": 0.5}),
    ]),
    "C": (3, [
        ("lcr", "lcr.csv", {}),
        ("spindown", "spindown.txt", {"on_time": 20.0, "coast_time": 40.0}),
        ("terminal", "terminal.csv", {}),
        ("free-spinup", "free_spinup.csv", {"current": 0.5}),
    ]),
}


def main() -> None:
    motor = Motor.from_catalog("neverest40")
    for unit, (seed, experiments) in UNITS.items():
        gearbox = draw_gearbox(motor.key, motor.gearbox(), seed)
        rig = VirtualRig(motor.key, unit_seed=seed, noise_seed=100 + seed, gearbox=gearbox)
        folder = HERE / unit
        folder.mkdir(exist_ok=True)
        (folder / "truth.json").unlink(missing_ok=True)  # the rig adds runs to an existing truth file
        for experiment, name, settings in experiments:
            run = rig.run(experiment, folder / name, **settings)
            print(" ".join(str(Path(p).relative_to(HERE)) for p in run.paths))


if __name__ == "__main__":
    main()
