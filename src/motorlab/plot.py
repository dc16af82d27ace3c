"""Plots of fit results and motor curves, drawn with matplotlib's object API only.

Compute and plot apart (python-control's ``*_response`` / ``*_plot`` split): every analysis returns
a :class:`~motorlab.results.FitResult` whose :class:`~motorlab.results.Panel` objects hold the data
and model curves; :func:`plot_fit` only draws them. Figures are created as
:class:`matplotlib.figure.Figure` objects, never through ``pyplot``, so nothing opens a window and no
global state is touched; :func:`save_figure` writes them to a file.
"""

from __future__ import annotations

import math
import os
import textwrap
from typing import Any, TypeAlias

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from motorlab.errors import OptionError

# What is drawn: motorlab.results' FitResult, Panel and Series. Not imported, not even for type checking:
# FitResult.plot draws with this module, and an import back would close a circle.
FitResult: TypeAlias = Any
Panel: TypeAlias = Any
Series: TypeAlias = Any

#: File types :func:`save_figure` writes.
FIGURE_FORMATS = (".png", ".pdf", ".svg")


def _shares_x(panel: Panel) -> bool:
    """True when data and model are sampled at the same x (residuals can be drawn)."""
    if panel.data is None or panel.model is None:
        return False
    x1, x2 = np.asarray(panel.data.x, dtype=float), np.asarray(panel.model.x, dtype=float)
    return x1.shape == x2.shape and bool(np.allclose(x1, x2, equal_nan=True))


def _draw_series(ax: Axes, series: Series, *, main: bool) -> None:
    x, y = np.asarray(series.x, dtype=float), np.asarray(series.y, dtype=float)
    if not np.any(np.isfinite(y)):
        return
    if series.kind == "data":
        size = 3 if x.size > 200 else 6 if x.size > 30 else 8
        ax.plot(x, y, linestyle="none", marker="o", markersize=size if main else size + 2,
                alpha=0.6 if x.size > 200 else 0.9, label=series.label,
                markerfacecolor="none" if not main else None)
    else:
        ax.plot(x, y, linestyle="-" if main else "--", linewidth=2.0 if main else 1.4, label=series.label)


def plot_panel(panel: Panel, ax: Axes) -> Axes:
    """Draw one panel's data, model and extra curves into ``ax`` (no residual axis); returns ``ax``."""
    if panel.data is not None:
        _draw_series(ax, panel.data, main=True)
    if panel.model is not None:
        _draw_series(ax, panel.model, main=True)
    for series in panel.extra:
        _draw_series(ax, series, main=False)
    # at the axes' top, where matplotlib would put it after measuring every tick label for top ones (none here): a
    # fifth of the time a report took to draw
    ax.set_title(panel.title, fontsize=10, y=1.0)
    ax.set_xlabel(panel.x_label)
    ax.set_ylabel(panel.y_label)
    ax.grid(True, alpha=0.3)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=8, loc="best")
    return ax


def _draw_panel(fig: Figure, spec: Any, panel: Panel) -> list[Axes]:
    """Draw one panel (and its residuals) in the gridspec cell ``spec``; returns its axes."""
    residuals = _shares_x(panel)
    if residuals:
        inner = spec.subgridspec(2, 1, height_ratios=(3, 1), hspace=0.05)
        ax = fig.add_subplot(inner[0])
        ax_res = fig.add_subplot(inner[1], sharex=ax)
    else:
        ax = fig.add_subplot(spec)
        ax_res = None
    plot_panel(panel, ax)
    if ax_res is None:
        return [ax]
    ax.set_xlabel("")  # the residual axis beneath carries the x label
    assert panel.data is not None
    assert panel.model is not None
    x = np.asarray(panel.data.x, dtype=float)
    r = np.asarray(panel.data.y, dtype=float) - np.asarray(panel.model.y, dtype=float)
    ok = np.isfinite(x) & np.isfinite(r)
    ax_res.axhline(0.0, color="0.4", linewidth=1.0)
    if np.any(ok):
        ax_res.plot(x[ok], r[ok], linestyle="none", marker="o", markersize=3 if ok.sum() > 200 else 5, alpha=0.7)
    ax_res.set_xlabel(panel.x_label)
    unit = panel.y_label.rsplit("[", 1)[1].rstrip("]") if "[" in panel.y_label else ""
    ax_res.set_ylabel(f"residual [{unit}]" if unit else "residual", fontsize=8)
    ax_res.grid(True, alpha=0.3)
    ax.tick_params(labelbottom=False)
    return [ax, ax_res]


def plot_fit(result: FitResult, *, fig: Figure | None = None) -> Figure:
    """Draw every panel of a fit result: data, model, extra curves and residuals.

    Parameters
    ----------
    result
        What an analysis returned.
    fig
        A figure to draw into (cleared first); by default a new one, sized for the panels.

    Returns
    -------
    matplotlib.figure.Figure
        One block per panel, in a column: data as markers, the model as a line, extra series
        dashed (models) or hollow (data), and beneath it a residual axis when data and model share
        their x values. The title names the experiment and the files; warnings are a footnote.

    Notes
    -----
    The seed's "Actual Position vs. Fitted Position" chart (seed 1, "Data Analysis" step 4i) is
    this figure for a spin-down: the residual axis makes a misfit visible that the overlay hides.
    """
    panels = result.panels or [type(result).EMPTY_PANEL]
    n = len(panels)
    heights = [4.0 if _shares_x(p) else 3.0 for p in panels]
    notes = _footnote(result)
    note_lines = notes.count("\n") + 1 if notes else 0
    note_height = 0.18 * note_lines + (0.2 if notes else 0.0)
    if fig is None:
        fig = Figure(figsize=(9.0, sum(heights) + (n - 1) * PANEL_GAP + 1.4 + note_height))
    else:
        fig.clear()
    grid = fig.add_gridspec(n, 1, height_ratios=heights, **_margins(fig, n, top=0.8, bottom=0.55 + note_height))
    for k, panel in enumerate(panels):
        _draw_panel(fig, grid[k], panel)
    title = result.experiment
    if result.sources:
        names = [os.path.basename(s) for s in result.sources]
        title += " — " + (", ".join(names) if len(names) <= 3 else f"{names[0]} and {len(names) - 1} more files")
    fig.suptitle(title, fontsize=12)
    if notes:
        fig.text(0.01, 0.01, notes, fontsize=7, va="bottom", ha="left", color="0.25")
    return fig


#: Margins of a fit figure [in]: room for the y labels at the left, the panel titles and x labels between panels.
LEFT_MARGIN, RIGHT_MARGIN, PANEL_GAP = 1.0, 0.25, 0.8


def _margins(fig: Figure, n: int, *, top: float, bottom: float) -> dict[str, float]:
    """A fixed layout (margins in inches) for ``n`` panels in a column, as gridspec keywords.

    Constrained layout found the same margins by measuring every tick label of every axis, which
    took about half of the time a figure took to save (a session's report draws a hundred).
    """
    width, height = fig.get_figwidth(), fig.get_figheight()
    top_f = max(0.5, 1.0 - top / height)
    bottom_f = min(bottom / height, top_f - 0.1)
    cell = max((top_f - bottom_f) * height - (n - 1) * PANEL_GAP, 0.1 * n) / n
    return {"left": min(LEFT_MARGIN / width, 0.3), "right": 1.0 - min(RIGHT_MARGIN / width, 0.1),
            "top": top_f, "bottom": bottom_f, "hspace": PANEL_GAP / cell}


def _footnote(result: FitResult, width: int = 150) -> str:
    lines = []
    for w in result.warnings:
        lines += textwrap.wrap("• " + w, width=width, subsequent_indent="  ")
    return "\n".join(lines[:14])


def save_figure(fig: Figure, path: str | os.PathLike[str], *, dpi: int = 120) -> None:
    """Write ``fig`` to ``path`` (PNG, PDF or SVG, by the extension).

    Raises
    ------
    OptionError
        For an unsupported extension or a directory that does not exist.
    """
    target = os.fspath(path)
    ext = os.path.splitext(target)[1].lower()
    if ext not in FIGURE_FORMATS:
        raise OptionError(f"{target}: cannot write a figure of type {ext or '(none)'!r}; use .png, .pdf or .svg")
    folder = os.path.dirname(os.path.abspath(target))
    if not os.path.isdir(folder):
        raise OptionError(f"{target}: the directory {folder} does not exist")
    from motorlab.io.output import atomic_path

    with atomic_path(target) as temporary:
        fig.savefig(temporary, dpi=dpi)


def plot_motor_curves(
    params: Any,
    voltage: float,
    *,
    ax: Axes | None = None,
    catalog: Any | None = None,
    size: tuple[float, float] = (8.0, 5.0),
) -> Figure:
    """Speed, current, output power and efficiency against output torque at ``voltage``.

    Parameters
    ----------
    params
        A :class:`~motorlab.model.MotorParams` (anything with ``curves(voltage)``).
    voltage
        Supply voltage [V].
    ax
        Axes to draw on (speed on it, current, power and efficiency on twin axes at the right);
        by default a new figure.
    catalog
        Optional second motor (e.g. the catalogue's data-sheet parameters), drawn dashed for
        comparison; anything with ``curves(voltage)`` or a ``params`` attribute that has it.
    size
        Width and height [in] of a new figure (a fixed layout leaves room for the labels).

    Returns
    -------
    matplotlib.figure.Figure
        The figure holding ``ax``.

    Notes
    -----
    The curves are those of :meth:`~motorlab.model.MotorParams.curves`: with ω from 0 to the free
    speed, i = (V − K·ω)/R, τ = K·i − b·ω − Tf, P = τ·ω, η = P/(V·i); the data-sheet chart of
    AndyMark's motor tests (seed 1, "First Experiment") uses the same axes.
    """
    if not (isinstance(voltage, int | float) and math.isfinite(voltage) and voltage != 0):
        raise OptionError(f"the voltage for motor curves must be a non-zero number, got {voltage!r}")
    own = ax is None
    if ax is None:
        fig = Figure(figsize=size)
        width, height = size
        # Fixed margins [in]: three value axes stacked at the right, the legend below the axes.
        right = width - 0.7 - (width - 0.75 - 0.7) * 0.24 / 1.24
        fig.subplots_adjust(left=0.75 / width, right=right / width, top=1 - 0.4 / height, bottom=1.05 / height)
        ax = fig.add_subplot()
    else:
        parent = ax.get_figure()
        if not isinstance(parent, Figure):
            raise OptionError("the axes given to plot_motor_curves do not belong to a figure")
        fig = parent
    ax_i = ax.twinx()
    ax_p = ax.twinx()
    ax_e = ax.twinx()
    ax_p.spines["right"].set_position(("axes", 1.12))
    ax_e.spines["right"].set_position(("axes", 1.24))
    colours = {"speed": "C0", "current": "C3", "power": "C2", "efficiency": "C1"}
    motors = [(params, "-", "measured")]
    if catalog is not None:
        cat = catalog if hasattr(catalog, "curves") else getattr(catalog, "params", None)
        if cat is None or not hasattr(cat, "curves"):
            raise OptionError("catalog must be motor parameters (with curves()) or a catalogue motor")
        motors.append((cat, "--", "catalogue"))
    for motor, style, label in motors:
        c = motor.curves(voltage)
        tau = c["torque"]
        ax.plot(tau, c["speed"], style, color=colours["speed"], label=f"speed ({label})")
        ax_i.plot(tau, c["current"], style, color=colours["current"], label=f"current ({label})")
        ax_p.plot(tau, c["power"], style, color=colours["power"], label=f"power ({label})")
        ax_e.plot(tau, 100 * c["efficiency"], style, color=colours["efficiency"], label=f"efficiency ({label})")
    ax.set_xlabel("output torque τ [N·m]")
    ax.set_ylabel("speed ω [rad/s]", color=colours["speed"])
    ax_i.set_ylabel("current i [A]", color=colours["current"])
    ax_p.set_ylabel("output power P [W]", color=colours["power"])
    ax_e.set_ylabel("efficiency η [%]", color=colours["efficiency"])
    for a in (ax, ax_i, ax_p, ax_e):
        a.set_ylim(bottom=0)
    ax.set_xlim(left=0)
    ax.grid(True, alpha=0.3)
    ax.set_title(f"Motor curves at {abs(voltage):g} V", y=1.0)  # placed, not measured (plot_panel)
    handles, labels = [], []
    for a in (ax, ax_i, ax_p, ax_e):
        h, lab = a.get_legend_handles_labels()
        handles += h
        labels += lab
    # Below the axes, not on them: inside, the legend hid the current line's top and the stall point.
    if own:  # centred under the figure's width (the axes leave room at the right for the value axes)
        ax.legend(handles, labels, fontsize=7, loc="lower center", bbox_to_anchor=(0.5, 0.01),
                  bbox_transform=fig.transFigure, ncols=4, frameon=False)
    else:
        ax.legend(handles, labels, fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.14), ncols=4,
                  frameon=False)
    return fig
