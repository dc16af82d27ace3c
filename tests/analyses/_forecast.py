"""The judged forecast of a locked-rotor run: fitted on its first 120 s, simulated over the rest."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from motorlab.analyses.stall import stall
from motorlab.experiments.stall import read_runs
from motorlab.stall_forecast import forecast, load_fit


def forecast_rms(path: str | Path, folder: Path, fitted_for: float = 120.0) -> float:
    """Relative RMS of `simulate stall`'s current against the run's measured current after ``fitted_for`` s,
    the forecast made from a fit of the run's first ``fitted_for`` s written to and read from ``folder``."""
    rec = read_runs([str(path)])[0]
    fit = stall(rec, until=fitted_for)
    row = fit.details["runs"][0]
    end = row["cut (s)"] or float(rec.time[-1])
    (folder / "fit.json").write_text(json.dumps(fit.to_dict()))
    out = forecast(load_fit(folder / "fit.json"), float(row["set point (V)"]), end - float(rec.time[0]))
    later = (rec.time > fitted_for) & (rec.time < end)
    pred = np.interp(rec.time[later] - rec.time[0], out.time, out.current)
    measured = rec["current"][later]
    return math.sqrt(float(np.mean(((pred - measured) / measured) ** 2)))
