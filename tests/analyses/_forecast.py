"""The judged forecast of a locked-rotor run: fitted on its first 120 s, simulated over the rest.

A run that no single thermal network fits (its fit says so in ``details["network"]``) is forecast as a person
would: the motor's other runs (the other locked-rotor exports of the same motor beside it) fitted whole, and that
fit given as the network of the run's first 120 s (``analyze stall RUN --until 120 --network OTHERS.json``)."""

from __future__ import annotations

import functools
import json
import math
import pickle
from collections.abc import Iterable
from pathlib import Path

import numpy as np

from motorlab.analyses.stall import stall
from motorlab.errors import MotorlabError
from motorlab.experiments.stall import read_runs
from motorlab.results import FitResult
from motorlab.thermal.forecast import forecast, load_fit


@functools.cache
def _fitted(paths: tuple[str, ...]) -> bytes:
    return pickle.dumps(stall(read_runs(list(paths))))


def stall_of_files(paths: Iterable[str | Path]) -> FitResult:
    """``stall(read_runs(paths))`` of published files that several tests fit alike: fitted once in this process,
    each caller given its own copy (the files are read in place and never change during a run)."""
    return pickle.loads(_fitted(tuple(str(p) for p in paths)))


def other_runs(path: str | Path) -> list[str]:
    """The other locked-rotor exports of the same motor in the same folder (VEX's ``<motor>-locked-rotor-data-*``)."""
    path = Path(path)
    motor = path.name.split("-locked-rotor-data-")[0]
    return sorted(str(p) for p in path.parent.glob(f"{motor}-locked-rotor-data-*.csv") if p.name != path.name)


def forecast_fit(path: str | Path, folder: Path, fitted_for: float = 120.0) -> tuple[Path, dict]:
    """The fit file a forecast of ``path`` is made from: its first ``fitted_for`` s alone, or held at the network of
    the motor's other runs when no single network fits them; and the run's row of that fit."""
    rec = read_runs([str(path)])[0]
    fit = stall(rec, until=fitted_for)
    if fit.details["network"] != "fitted to these runs" and other_runs(path):
        try:
            others = stall_of_files(other_runs(path))
            (folder / "others.json").write_text(json.dumps(others.to_dict()))
            fit = stall(rec, until=fitted_for, network=load_fit(folder / "others.json").thermal,
                        network_source="the fit of the motor's other runs")
        except MotorlabError:
            pass  # the population's winding, as the lone fit has it
    (folder / "fit.json").write_text(json.dumps(fit.to_dict()))
    return folder / "fit.json", fit.details["runs"][0]


def forecast_rms(path: str | Path, folder: Path, fitted_for: float = 120.0) -> float:
    """Relative RMS of `simulate stall`'s current against the run's measured current after ``fitted_for`` s,
    the forecast made from the fit of :func:`forecast_fit` written to and read from ``folder``."""
    rec = read_runs([str(path)])[0]
    fit, row = forecast_fit(path, folder, fitted_for)
    model = load_fit(fit)
    end = row["cut (s)"] or float(rec.time[-1])
    out = forecast(model, float(row["set point (V)"]), end - float(rec.time[0]))
    later = (rec.time > fitted_for) & (rec.time < end)
    pred = np.interp(rec.time[later] - rec.time[0], out.time, out.current)
    measured = rec["current"][later]
    return math.sqrt(float(np.mean(((pred - measured) / measured) ** 2)))
