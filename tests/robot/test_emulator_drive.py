"""The emulated drive under ManualFeedforwardTuner follows the gains it is given: the true motor's gains track
best, every wrong set worse (issue 32, item 7)."""

from __future__ import annotations

import numpy as np
import pytest

from motorlab.robot import emulator_drive
from motorlab.robot.emulator import Plant

PROFILE = {"inPerTick": 1.0, "maxWheelVel": 50.0, "minProfileAccel": -30.0, "maxProfileAccel": 50.0}


def rms(plant: Plant, **gains: float) -> float:
    rows = list(emulator_drive.run(plant, {**PROFILE, **gains}, battery=12.8, seconds=6.0))
    error = np.array([float(d["v0"]) - float(d["vref"]) for _, d in rows])
    return float(np.sqrt(np.mean(error**2)))


def test_the_profile_covers_the_distance_back_and_forth() -> None:
    shape = (emulator_drive.DISTANCE, 50.0, -30.0, 50.0)
    leg = emulator_drive.duration(*shape)
    t = np.linspace(0, leg, 20001)
    v = np.array([emulator_drive.trapezoid(x, *shape)[0] for x in t])
    assert float(np.sum(v) * (t[1] - t[0])) == pytest.approx(64.0, rel=1e-3)  # DISTANCE, Tuning.kt
    assert max(v) <= 50.0
    zeros = {**PROFILE, "kS": 0.0, "kV": 0.0, "kA": 0.0}
    rows = list(emulator_drive.run(Plant(), zeros, battery=12.8, seconds=2 * leg))
    refs = [float(d["vref"]) for _, d in rows]
    assert max(refs) > 40
    assert min(refs) < -40
    assert set(rows[0][1]) == {"mode", "v0", "v1", "v2", "v3", "vref"}  # the real OpMode's keys


@pytest.mark.parametrize("plant", [Plant(), Plant(kS=0.6, kV=0.012, kA=0.0015)])
def test_wrong_gains_track_worse(plant: Plant) -> None:
    true = {"kS": plant.kS, "kV": plant.kV, "kA": plant.kA}
    best = rms(plant, **true)
    assert best < 1.5  # ticks/s: whole-tick encoder velocity and one loop of lag
    for name, factor in (("kS", 0.0), ("kS", 1.5), ("kV", 0.8), ("kV", 1.2), ("kA", 0.0), ("kA", 3.0)):
        wrong = rms(plant, **{**true, name: true[name] * factor})
        assert wrong > 1.5 * best, (name, factor, wrong, best)
