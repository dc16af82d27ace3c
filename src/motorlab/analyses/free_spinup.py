"""Free spin-up of the bare motor at constant current: the armature inertia J from encoder edge times.

Seed 1, "Free Motor Spin-Up Experiment": the motor, without flywheel, is given a turn by hand and
then accelerates on a small constant current I; an oscilloscope gives the times of the rising
edges of one encoder channel (one edge every fourth count). With K known, J = (K·I − Tf)/α.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from motorlab.analyses import common
from motorlab.errors import FitError, OptionError
from motorlab.estimation.decimate import block_mean
from motorlab.estimation.least_squares import LeastSquares, r_squared
from motorlab.recording import Recording
from motorlab.results import Estimate, FitResult, Panel, Series
from motorlab.units import SI_UNITS

_MIN_EDGES = 5
_NAMES = ["P0", "omega0", "J", "K", "I", "Tf", "b"]
_UNITS = {"P0": "rad", "omega0": "rad/s", "J": SI_UNITS["J"], "K": SI_UNITS["K"], "I": "A",
          "Tf": SI_UNITS["Tf"], "b": SI_UNITS["b"]}


def _checked_options(
    edges: Recording, *, torque_constant: float, current: float, cpr: float | None,
    edges_per_revolution: float | None, viscous_friction: float | None, coulomb_friction: float | None,
    stderrs: tuple[float | None, float | None, float | None, float | None],
) -> tuple[dict[str, float], float | None, float]:
    """Refuse impossible options; the standard errors of K, I, b, Tf, the cpr (an option or the file's
    ``# cpr:`` line) and the rising edges per revolution."""
    source = edges.source or "edge times"
    torque_constant_stderr, current_stderr, viscous_friction_stderr, coulomb_friction_stderr = stderrs
    common.check_positive(torque_constant, "K (torque constant)", allow_none=False)
    common.check_positive(current, "current", allow_none=False)
    common.check_positive(cpr, "cpr (encoder counts per revolution)")
    common.check_positive(edges_per_revolution, "edges per revolution")
    # Generous physical limits, checked before K·I or 2π/n_e can overflow into a non-finite fit.
    common.check_torque_constant(torque_constant)
    common.check_current(current)
    common.check_cpr(cpr)
    common.check_range(edges_per_revolution, "the edges per revolution (--edges-per-rev)", 0.25, 2.0**30, "",
                       why="one channel of an encoder has at least a quarter of a rising edge per turn")
    common.check_nonnegative(viscous_friction, "viscous friction b")
    common.check_nonnegative(coulomb_friction, "Coulomb friction Tf")
    common.check_limits(viscous_friction, "b", "the viscous friction b (--b)")
    common.check_limits(coulomb_friction, "Tf", "the Coulomb friction Tf (--Tf)")
    se = {
        "K": common.check_stderr_limit(torque_constant_stderr, "K", "the standard error of K (--K-stderr)"),
        "I": common.check_stderr_limit(current_stderr, "I", "the standard error of the current (--current-stderr)"),
        "b": common.check_stderr_limit(viscous_friction_stderr, "b", "the standard error of b (--b-stderr)"),
        "Tf": common.check_stderr_limit(coulomb_friction_stderr, "Tf", "the standard error of Tf (--Tf-stderr)"),
    }
    if cpr is None and edges.metadata.get("cpr") is not None:  # a "# cpr: 1120" line of the CSV
        try:
            cpr = float(edges.metadata["cpr"])
        except (TypeError, ValueError):
            raise OptionError(f"{source}: the file's cpr {edges.metadata['cpr']!r} is not a number") from None
        common.check_positive(cpr, "cpr (encoder counts per revolution)")
        try:
            common.check_cpr(cpr)
        except OptionError as exc:
            raise OptionError(f"the file's '# cpr:' line: {exc.message}", path=edges.source or None) from None
    if edges_per_revolution is None:
        if cpr is None:
            raise OptionError("the file has no '# cpr:' line: give the encoder's counts per revolution (--cpr) or "
                              "--edges-per-rev", path=edges.source or None)
        edges_per_revolution = cpr / 4.0
    return se, cpr, edges_per_revolution


def _fragility_warnings(n_edges: int, viscous_friction: float | None, coulomb_friction: float | None,
                        drive: float) -> list[str]:
    """Few edges; friction not given (folded into J), with how much J is then overestimated."""
    out: list[str] = []
    if n_edges < 10:
        out.append(f"only {n_edges} edges: the estimate is fragile")
    if viscous_friction is None:
        out.append("no viscous friction given (--b): the drag b·ω is folded into J (J is overestimated)")
    if coulomb_friction is None:
        # J = (K·I − Tf)/α: taking Tf = 0 overestimates J by the factor K·I/(K·I − Tf).
        out.append(
            f"no Coulomb friction given (--Tf): Tf was taken as 0, which overestimates J by Tf/(K·I − Tf); "
            f"with the drive torque K·I = {drive:.3g} N·m here, Tf = {0.1 * drive:.2g} N·m would make J "
            f"11 % too high and Tf = {0.5 * drive:.2g} N·m 100 % too high: give --Tf (from a spin-down)"
        )
    return out


def _panels(t_edges: np.ndarray, theta: np.ndarray, model_theta: np.ndarray, ramp_speed: Any, omega0: float,
            rates: tuple[float, float]) -> list[Panel]:
    """Position and (display-only) edge-to-edge speed against the fitted spin-up."""
    mid = 0.5 * (t_edges[1:] + t_edges[:-1])
    panels = [
        Panel("Free spin-up: position", "time [s]", "position since the first edge [rad]",
              data=Series(t_edges, theta, "edges"), model=Series(t_edges, model_theta, "model", kind="model")),
        Panel("Free spin-up: speed", "time [s]", "speed [rad/s]",
              data=Series(mid, np.diff(theta) / np.diff(t_edges), "edge-to-edge speed (display only)"),
              model=Series(mid, ramp_speed(mid - t_edges[0], omega0, *rates), "model",
                           kind="model")),
    ]
    return panels


def free_spinup(
    edges: Recording,
    *,
    torque_constant: float,
    current: float,
    cpr: float | None = None,
    edges_per_revolution: float | None = None,
    torque_constant_stderr: float | None = None,
    current_stderr: float | None = None,
    viscous_friction: float | None = None,
    viscous_friction_stderr: float | None = None,
    coulomb_friction: float | None = None,
    coulomb_friction_stderr: float | None = None,
) -> FitResult:
    """Fit the armature inertia J from the edge times of a free constant-current spin-up.

    Parameters
    ----------
    edges
        Edge times (``time`` [s], one rising edge of one channel per sample), as
        :func:`motorlab.io.scope.read_scope_times` or :func:`~motorlab.io.scope.read_scope_waveform`
        return them.
    torque_constant
        K [V·s/rad] = [N·m/A] at the counted shaft.
    current
        The constant current I [A].
    cpr
        Encoder counts per revolution [count/rev]; one channel's rising edges are cpr/4 per turn.
    edges_per_revolution
        Rising edges per revolution, overriding cpr/4 [1/rev].
    torque_constant_stderr, current_stderr
        Standard errors of K [V·s/rad] and I [A], propagated into J (default: exact).
    viscous_friction, coulomb_friction
        b [N·m·s/rad] and Tf [N·m] of the bare motor, if known (default 0).
    viscous_friction_stderr, coulomb_friction_stderr
        Their standard errors (default: exact).

    Returns
    -------
    FitResult
        ``J`` [kg·m²] and ``alpha`` (the acceleration at zero speed, (K·I − Tf)/J) [rad/s²];
        ``details`` holds ω0 and the speed range.

    Raises
    ------
    OptionError
        Missing or impossible K, I, cpr, friction; K, I, cpr or the edges per revolution outside
        generous physical limits (:data:`~motorlab.analyses.common.TORQUE_CONSTANT_RANGE` ...).
    FitError
        Too few edges, or a motor that does not accelerate.

    Notes
    -----
    Position at edge k is P_k = k·2π/n_e (n_e edges per revolution). The seed fits
    P = P0 + K·I·(t − t0)²/J, which drops the ½ of constant acceleration (P = P0 + ½·α·τ²) and so
    gives a J twice too large; it also makes t0 free to absorb the hand start. With the initial
    speed free as well, t0 and ω0 describe the same thing (any point of a parabola can be its
    origin), so t0 is fixed at the first edge and P0, ω0 and α = (K·I − Tf)/J are fitted:

        P = P0 + ω0·τ + ½·α·τ²,  τ = t − t0.

    With b given the exact solution with viscous drag is fitted instead,
    ω(τ) = ω∞ + (ω0 − ω∞)·e^(−τ·b/J), ω∞ = (K·I − Tf)/b, and its integral. The errors are in the
    times (cursor placement), so position residuals are weighted by 1/ω; K, I, b and Tf enter as
    priors so that their standard errors reach J.

    References
    ----------
    Seed 1, "Free Motor Spin-Up Experiment", "Data Analysis".
    """
    edges = block_mean(edges)  # two million edge times: block means
    source = edges.source or "edge times"
    se, cpr, edges_per_revolution = _checked_options(
        edges, torque_constant=torque_constant, current=current, cpr=cpr, edges_per_revolution=edges_per_revolution,
        viscous_friction=viscous_friction, coulomb_friction=coulomb_friction,
        stderrs=(torque_constant_stderr, current_stderr, viscous_friction_stderr, coulomb_friction_stderr))
    t_edges, tau, theta = _edge_angles(edges, edges_per_revolution, source)
    b_given = viscous_friction or 0.0
    warnings: list[str] = common.reader_warnings(edges)
    x0 = _initial_guess(tau, theta, torque_constant=torque_constant, current=current, b_given=b_given,
                        tf_given=coulomb_friction or 0.0, source=source)
    fit, x_full = _fit_spinup(tau, theta, x0, se, source)
    warnings.extend(_fragility_warnings(t_edges.size, viscous_friction, coulomb_friction,
                                        torque_constant * current))
    model_theta = _position(x_full, tau)
    return FitResult(
        experiment="free-spinup",
        parameters=_parameters(fit, x_full),
        correlation=fit.correlation,
        correlation_names=list(fit.names),
        rmse=float(np.sqrt(np.mean((theta - model_theta) ** 2))),
        rmse_unit="rad",
        r2=r_squared(theta, model_theta),
        n_points=int(theta.size),
        panels=_panels(t_edges, theta, model_theta, common.ramp_speed, x_full[1], _rates(x_full)),
        warnings=warnings,
        details=_details(t_edges, x_full, edges_per_revolution, b_given),
        sources=[edges.source] if edges.source else [],
    )


def _edge_angles(edges: Recording, edges_per_revolution: float,
                 source: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The edge times [s], the times since the first edge τ [s] and the shaft angle at each edge since
    the first [rad].

    Raises
    ------
    FitError
        Too few edges, or edge times that do not increase.
    """
    common.check_finite_signals(edges, [])
    t_edges = np.asarray(edges.time, dtype=float)
    if t_edges.size < _MIN_EDGES:
        raise FitError(f"{source}: {t_edges.size} edges are too few to fit a spin-up (need {_MIN_EDGES})")
    if np.any(np.diff(t_edges) <= 0):
        raise FitError(f"{source}: the edge times do not increase")
    index = edges.signals.get("counts", np.arange(t_edges.size, dtype=float))
    theta = (index - index[0]) * (2.0 * math.pi / edges_per_revolution)
    return t_edges, t_edges - t_edges[0], theta


def _initial_guess(tau: np.ndarray, theta: np.ndarray, *, torque_constant: float, current: float, b_given: float,
                   tf_given: float, source: str) -> np.ndarray:
    """Starting values of (P0, ω0, J, K, I, Tf, b) from a parabola through the angles.

    Raises
    ------
    FitError
        A motor that does not accelerate.
    OptionError
        K·I not above the given Tf.
    """
    quad = np.polyfit(tau, theta, 2)
    alpha0 = 2.0 * quad[0]
    if alpha0 <= 0:
        raise FitError(f"{source}: the motor is not accelerating (fitted α = {alpha0:.3g} rad/s²)")
    torque = torque_constant * current - tf_given
    if torque <= 0:
        raise OptionError(f"K·I = {torque_constant * current:.3g} N·m does not exceed Tf = {tf_given:.3g} N·m")
    mean_speed = float(theta[-1] / tau[-1])
    j0 = max(torque - b_given * mean_speed, 0.1 * torque) / alpha0
    return np.array([quad[2], quad[1], j0, torque_constant, current, tf_given, b_given])


def _rates(x: np.ndarray) -> tuple[float, float]:
    """γ = b/J [1/s] and A = (K·I − Tf)/J [rad/s²]."""
    j, k, i, tf, b = x[2], x[3], x[4], x[5], x[6]
    return b / j, (k * i - tf) / j


def _position(x: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """Model angle [rad] at the times τ since the first edge."""
    gamma, accel = _rates(x)
    return x[0] + common.ramp_position(tau, x[1], gamma, accel)


def _speed(x: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """Model speed [rad/s] at the times τ since the first edge."""
    return common.ramp_speed(tau, x[1], *_rates(x))


def _fit_spinup(tau: np.ndarray, theta: np.ndarray, x0: np.ndarray, se: dict[str, float],
                source: str) -> tuple[LeastSquares, np.ndarray]:
    """The weighted fit of the angles, K, I, Tf and b entering as priors; the fit and all its parameters.

    A first unweighted fit gives the residuals from which the weights 1/σ are estimated, then the fit
    is repeated with them.
    """
    priors = [
        common.Prior([name], np.array([x0[_NAMES.index(name)]]), np.array([[se[name] ** 2]]))
        for name in ("K", "I", "Tf", "b")
    ]
    sigma = np.ones_like(theta)
    try:
        fit, x_full = common.fit_with_priors(lambda x: (_position(x, tau) - theta) / sigma, x0, _NAMES, priors)
        # Cursor errors are errors in time: a position error ω·δt (plus a constant part).
        sigma = common.speed_noise_sigma(_position(x_full, tau) - theta, _speed(x_full, tau),
                                         dof=max(theta.size - 3, 1))
        fit, x_full = common.fit_with_priors(lambda x: (_position(x, tau) - theta) / sigma, x_full, _NAMES, priors)
    except FitError as exc:
        raise common.in_file(exc, source) from None
    return fit, x_full


def _parameters(fit: LeastSquares, x_full: np.ndarray) -> dict[str, Estimate]:
    """J and the acceleration at zero speed α = (K·I − Tf)/J, with their standard errors."""
    est = fit.estimates({n: _UNITS[n] for n in fit.names})
    alpha = _rates(x_full)[1]
    alpha_se = common.derived_stderr(fit, x_full, _NAMES, lambda x: _rates(x)[1])
    return {
        "J": est["J"],
        "alpha": Estimate("alpha", alpha, alpha_se, "rad/s^2", note="acceleration at zero speed, (K·I − Tf)/J"),
    }


def _details(t_edges: np.ndarray, x_full: np.ndarray, edges_per_revolution: float, b_given: float) -> dict[str, Any]:
    """The free spin-up's ``details``: the first edge, the edges per revolution, the speed range, the model."""
    model_speed = _speed(x_full, t_edges - t_edges[0])
    return {
        "t0_s": float(t_edges[0]), "edges_per_revolution": float(edges_per_revolution),
        "omega0_rad_per_s": float(x_full[1]), "omega_end_rad_per_s": float(model_speed[-1]),
        "model": "viscous drag (exact solution)" if b_given > 0 else "constant acceleration",
    }


# ---- reading the files -------------------------------------------------------------------------
def read_edges(path: str) -> Recording:
    """Edge times from a scope waveform export or a cursor-times CSV.

    :func:`motorlab.io.detect_format` recognises the waveform export; anything else is read as
    cursor times, whose reader names the file and line of whatever does not fit (a header in an
    unknown unit, an FTC log given by mistake).

    Raises
    ------
    LogFormatError
        A file that is not edge times.
    """
    from motorlab.io import detect_format
    from motorlab.io.scope import read_scope_times, read_scope_waveform

    if detect_format(path) == "scope-waveform":
        return read_scope_waveform(path)
    return read_scope_times(path)
