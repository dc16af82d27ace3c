"""Voltage profiles of the virtual rig's identification logs (:meth:`motorlab.rig.VirtualRig.transient`)."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from motorlab.errors import OptionError


def voltage_profile(profile: str, duration: float, max_voltage: float,
             rng: np.random.Generator) -> Callable[[np.ndarray], np.ndarray]:
    """Voltage profile ``f(t) -> V`` of a transient test."""
    if profile == "steps":
        levels = np.array([0.0, 0.5, 1.0, 0.25, -0.5, -1.0, 0.0]) * max_voltage
        edges = np.linspace(0.0, duration, levels.size + 1)[1:-1]
        return lambda t: levels[np.searchsorted(edges, np.asarray(t), side="right")]
    if profile == "ramps":
        knots_t = np.linspace(0.0, duration, 5)
        knots_v = np.array([0.0, 1.0, 0.0, -1.0, 0.0]) * max_voltage
        return lambda t: np.interp(np.asarray(t), knots_t, knots_v)
    if profile == "random":
        holds = [0.0]
        while holds[-1] < duration:
            holds.append(holds[-1] + float(rng.uniform(0.1, 0.5)))
        starts = np.array(holds[1:-1])
        levels = rng.uniform(-max_voltage, max_voltage, starts.size + 1)
        levels[0] = 0.0
        return lambda t: levels[np.searchsorted(starts, np.asarray(t), side="right")]
    raise OptionError(f"unknown profile {profile!r}; choose steps, ramps or random")
