"""An emulated robot on 127.0.0.1 with real-format files: Road Runner ramps, a FlightRecorder log, motorlab logs."""

from __future__ import annotations

import os
from collections.abc import Iterator
from pathlib import Path

import pytest

from motorlab.io import write_ftc_log
from motorlab.rig.ftc import simulate_flight_log, simulate_ramp
from motorlab.robot.emulator import EmulatedRobot, RobotFiles


@pytest.fixture(scope="session")
def robot_files(tmp_path_factory: pytest.TempPathFactory) -> RobotFiles:
    """Files as the robot holds them: two forward ramps (the older one not reachable), a lateral ramp, a
    FlightRecorder log (simulate_flight_log writes Road Runner's binary format) and a motorlab log."""
    root = tmp_path_factory.mktemp("sdcard")
    tuning: dict[str, list[Path]] = {}
    for kind, names in (("forward", ["1732521000000.json", "1732521600000.json"]), ("lateral", ["1732522000000.json"])):
        folder = root / "RoadRunner" / "tuning" / f"{kind}-ramp"
        folder.mkdir(parents=True)
        for k, name in enumerate(names):
            simulate_ramp(folder / name, kind=kind, seed=k + 1)
            os.utime(folder / name, (1_700_000_000 + k, 1_700_000_000 + k))
            (folder / "truth.json").unlink(missing_ok=True)
        tuning[f"{kind}-ramp"] = sorted(folder.glob("*.json"))
    logs = root / "RoadRunner" / "logs"
    logs.mkdir(parents=True)
    flight = logs / "2026_11_25__10_31_07_123__AutoOpMode.log"
    simulate_flight_log(flight, seed=2)
    ours = root / "FIRST" / "motorlab"
    ours.mkdir(parents=True)
    mine = ours / "motorlab-spindown-20261125-103107.txt"
    import numpy as np

    t = np.arange(0, 2.0, 0.005)
    write_ftc_log(mine, t, np.floor(3000 * (1 - np.exp(-t))), 6 * np.exp(-t), 0.5 * np.exp(-t),
                  fields={"experiment": "spindown", "cpr": 1120})
    return RobotFiles(tuning, [flight], [mine])


@pytest.fixture
def robot(robot_files: RobotFiles) -> Iterator[EmulatedRobot]:
    """The emulated robot, on free ports of 127.0.0.1, stopping by itself after 60 s at most."""
    with EmulatedRobot(robot_files, lifetime=60.0, max_requests=5000) as emulated:
        yield emulated


#: The FTC Dashboard versions every versioned test runs against: the last 0.4 (what most teams pin), the
#: quickstart's 0.5.0, the first with OpMode groups, and the newest (the only one with a config baseline).
VERSIONS = ("0.4.16", "0.5.0", "0.5.1", "0.6.0")


@pytest.fixture(params=VERSIONS)
def dashboard_version(request: pytest.FixtureRequest) -> str:
    return str(request.param)
