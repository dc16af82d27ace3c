"""Plots render to files without warnings and have the axes they should."""

from __future__ import annotations

import numpy as np
import pytest
from matplotlib.figure import Figure

from motorlab.analyses.gains import amplifier
from motorlab.errors import OptionError
from motorlab.model import MotorParams
from motorlab.plot import plot_fit, plot_motor_curves, save_figure
from motorlab.recording import Recording
from motorlab.results import FitResult, Panel, Series

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def line_result() -> FitResult:
    v = np.linspace(0.25, 2.0, 8)
    i = 2.0 * v + np.random.default_rng(0).normal(0, 0.01, v.size)
    return amplifier(Recording(np.arange(v.size, dtype=float), {"command": v, "current": i}, source="dir/amp.csv"))


def test_fit_with_residuals_renders_to_png(tmp_path):
    result = line_result()
    result.warnings.append("a warning long enough to need wrapping " * 8)
    fig = plot_fit(result)
    assert isinstance(fig, Figure)
    assert len(fig.axes) == 2  # data vs model, residuals beneath
    main, residual = fig.axes
    assert main.get_ylabel() == "output current [A]"
    assert residual.get_ylabel() == "residual [A]"
    assert "amp.csv" in fig.get_suptitle()
    path = tmp_path / "fit.png"
    save_figure(fig, path)
    assert path.read_bytes()[:8] == PNG_MAGIC


def test_panels_without_shared_x_have_no_residual_axis(tmp_path):
    x = np.linspace(0, 1, 20)
    result = FitResult(
        experiment="demo",
        parameters={},
        panels=[
            Panel("model on a finer grid", "t [s]", "ω [rad/s]", data=Series(x, x**2, "data"),
                  model=Series(np.linspace(0, 1, 200), np.linspace(0, 1, 200) ** 2, "model", "model")),
            Panel("data only", "t [s]", "V [V]", data=Series(x, np.sin(x), "volts")),
            Panel("with gaps", "t [s]", "ω [rad/s]", data=Series(np.r_[x, np.nan, x], np.r_[x, np.nan, x], "d"),
                  model=Series(np.r_[x, np.nan, x], np.r_[x, np.nan, x] * 1.01, "m", "model"),
                  extra=[Series(x, x, "other model", "model"), Series(x[:3], x[:3], "outliers", "data")]),
        ],
    )
    fig = plot_fit(result)
    assert len(fig.axes) == 4
    save_figure(fig, tmp_path / "panels.svg")
    assert (tmp_path / "panels.svg").stat().st_size > 0


def test_existing_figure_is_reused_and_empty_result_still_draws():
    fig = Figure()
    assert plot_fit(FitResult(experiment="empty", parameters={}), fig=fig) is fig
    assert len(fig.axes) == 1


def test_save_figure_rejects_bad_paths(tmp_path):
    fig = plot_fit(line_result())
    with pytest.raises(OptionError, match="type"):
        save_figure(fig, tmp_path / "fit.jpeg2000")
    with pytest.raises(OptionError, match="directory"):
        save_figure(fig, tmp_path / "missing" / "fit.png")


def test_motor_curves(tmp_path):
    measured = MotorParams(K=0.37, R=2.0, L=1e-3, J=1e-3, b=1e-4, Tf=0.05)
    catalogue = MotorParams(K=0.35, R=1.8, L=1e-3, J=1e-3)
    fig = plot_motor_curves(measured, 12.0, catalog=catalogue)
    assert len(fig.axes) == 4  # speed, current, power, efficiency
    assert len(fig.axes[0].get_lines()) == 2
    save_figure(fig, tmp_path / "curves.png")
    host = Figure()
    ax = host.add_subplot()
    assert plot_motor_curves(measured, 12.0, ax=ax) is host
    with pytest.raises(OptionError):
        plot_motor_curves(measured, 0.0)
