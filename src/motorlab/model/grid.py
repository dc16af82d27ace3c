"""The simulator's drive schedules and output grid (:mod:`motorlab.model.simulate`'s plumbing)."""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from motorlab.errors import OptionError
from motorlab.model.drives import BenchSupply, CurrentDrive, Drive, OpenCircuit, VoltageDrive


def drive_schedule(drive: Drive | Sequence[tuple[float, Drive]]) -> list[tuple[float, Drive]]:
    if isinstance(drive, VoltageDrive | CurrentDrive | BenchSupply | OpenCircuit):
        return [(0.0, drive)]
    items = [(float(t), d) for t, d in drive]
    if not items:
        raise OptionError("the drive schedule is empty")
    for t, d in items:
        if not isinstance(d, VoltageDrive | CurrentDrive | BenchSupply | OpenCircuit):
            raise OptionError(f"not a drive: {d!r}")
        if not math.isfinite(t):
            raise OptionError(f"drive start time {t} is not finite")
    if any(b[0] < a[0] for a, b in itertools.pairwise(items)):
        raise OptionError("drive schedule times must be increasing")
    return items


def drive_values(drive: Drive, t: np.ndarray) -> np.ndarray:
    if isinstance(drive, VoltageDrive | CurrentDrive):
        value = drive.voltage if isinstance(drive, VoltageDrive) else drive.current
        if callable(value):
            out = np.broadcast_to(np.asarray(value(t), dtype=float), t.shape).astype(float)
        else:
            out = np.full(t.shape, float(value))
        if not np.all(np.isfinite(out)):
            raise OptionError("the drive produced a non-finite value")
        return out
    if isinstance(drive, BenchSupply):
        return np.full(t.shape, drive.voltage)
    return np.zeros(t.shape)


@dataclass
class OutputGrid:
    """Output arrays on the grid ``k·dt`` (``n + 1`` points), filled in as the run advances."""

    time: np.ndarray
    current: np.ndarray
    speed: np.ndarray
    position: np.ndarray
    voltage: np.ndarray
    mode: np.ndarray

    @classmethod
    def empty(cls, n: int, dt: float) -> OutputGrid:
        """``time`` = k·dt [s] for k = 0 … n; the other arrays allocated, not yet filled."""
        return cls(
            np.arange(n + 1) * dt,
            np.empty(n + 1),
            np.empty(n + 1),
            np.empty(n + 1),
            np.empty(n + 1),
            np.empty(n + 1, dtype=np.int8),
        )
