"""How well a drive followed its target velocity: the telemetry of a verification OpMode (issue 32, item 7).

Road Runner's ``ManualFeedforwardTuner`` (road-runner-ftc ``Tuning.kt``) publishes ``vref``, the profile's
velocity, and ``v0``, ``v1``… each forward encoder's velocity, both in Road Runner's distance unit per
second (``inPerTick`` converts ticks: inches when it is set, ticks while it is the quickstart's 1.0).
The tracking error is the measured velocity (the mean of the encoders) minus ``vref``; its RMS over the
run says in one number how well the feedforward gains fit the drive.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Any

from motorlab.robot import RobotLinkError
from motorlab.robot.record import Recording

_ENCODER = re.compile(r"v\d+")


@dataclass(frozen=True)
class Tracking:
    """A verification run: time [s], target and measured velocity [``unit``], RMS and largest error."""

    time: list[float]
    target: list[float]
    measured: list[float]
    rms: float
    worst: float
    unit: str
    encoders: list[str]

    def to_dict(self, *, points: int = 6000) -> dict[str, Any]:
        """JSON-ready; at most ``points`` samples of the curves (evenly strided), the figures from all."""
        step = max(1, math.ceil(len(self.time) / points))
        return {"time": self.time[::step], "target": self.target[::step], "measured": self.measured[::step],
                "rms": self.rms, "worst": self.worst, "unit": self.unit, "encoders": self.encoders,
                "samples": len(self.time)}


def _number(text: str | None) -> float | None:
    try:
        value = float(text) if text is not None else math.nan
    except ValueError:
        return None
    return value if math.isfinite(value) else None


def tracking(data: Recording, *, unit: str) -> Tracking:
    """The tracking error of a recorded ``ManualFeedforwardTuner`` run (``vref`` and ``v0``… keys).

    Raises
    ------
    RobotLinkError
        When the run holds no sample with both a target and a measured velocity.
    """
    encoders = sorted((k for k in data.numeric_keys() if _ENCODER.fullmatch(k)), key=lambda k: int(k[1:]))
    time, target, measured = [], [], []
    t0 = data.rows[0][0] if data.rows else 0
    for stamp, _, values in data.rows:
        ref = _number(values.get("vref"))
        seen = [v for v in (_number(values.get(k)) for k in encoders) if v is not None]
        if ref is None or not seen:
            continue
        time.append((stamp - t0) / 1000)
        target.append(ref)
        measured.append(sum(seen) / len(seen))
    if not time:
        raise RobotLinkError(f"{data.opmode or 'the OpMode'} sent no target and measured velocity ('vref' and "
                             "'v0' telemetry): run Road Runner's ManualFeedforwardTuner, which publishes them")
    errors = [m - r for m, r in zip(measured, target, strict=True)]
    rms = math.sqrt(sum(e * e for e in errors) / len(errors))
    return Tracking(time, target, measured, rms, max(abs(e) for e in errors), unit, encoders)
