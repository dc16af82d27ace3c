"""What Road Runner's tuning page gets from the lateral and angular ramps, with uncertainties.

``motorlab analyze feedforward forward.json lateral.json angular.json --cpr N`` fits kS, kV, kA to the
forward ramp (:func:`motorlab.analyses.feedforward.feedforward`, output error on the encoder angle) and then,
from the other ramps:

* lateral ramp: the ratio s = (perpendicular dead-wheel speed) / (forward speed the feedforward
  predicts at that voltage) [ticks per tick]. Road Runner's page regresses the same two quantities
  (in/s against ticks/s) and calls the slope ``lateralInPerTick`` = s·inPerTick; the kinematics' lateral
  multiplier is inPerTick / lateralInPerTick = 1/s.
* angular ramp: ``trackWidthTicks`` from the IMU's yaw rate ω and the wheels' speed, by the
  definitions of road-runner ``Kinematics.kt``: a mecanum wheel turns at ω·trackWidth, tank sides at
  ±ω·trackWidth/2. With drive encoders the wheels' travel is measured (½(x_right − x_left) = ψ·tw
  for mecanum, x_right − x_left = ψ·tw for tank, ψ the integrated yaw rate; the page regresses the hub
  velocities, which lag by half their 50 ms window: −0.7 % on the simulated ramp); with dead wheels
  the wheel speeds follow from the voltage and the forward ramp's feedforward. The dead wheels'
  positions (their travel per radian of yaw) are reported as the page reports them.

With dead wheels the lateral and angular motions are fitted as the forward one is, integrated:
∫(V − kS)dt = c₁·Δx + c₂·Δv (:func:`integral_fit`), c₂ taking the inertia of that motion, which differs
from the forward one. The page regresses the quasi-static (V − kS)/kV alone, so the part of the
voltage that accelerates the robot reads as speed: on the simulated ramps of
tests/analyses/test_roadrunner.py (true kS, kV given to both) the page's method is +1.3 % off on track
width and −2.8 % on the lateral ratio; the integrated fit is within 0.05 %. Regressions use
Newey–West standard errors (a ramp's residuals are serially correlated); the uncertainty of kS and
kV is propagated by finite differences (delta method) and added.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from motorlab.errors import FitError, OptionError
from motorlab.estimation.least_squares import fit_linear
from motorlab.io.roadrunner import RampData, held_voltage
from motorlab.recording import Recording
from motorlab.results import Estimate, FitResult, Panel, Series


def _slope(x: np.ndarray, y: np.ndarray) -> tuple[float, float]:
    """Slope through the origin and its Newey–West standard error."""
    fit = fit_linear(x[:, None], y, ["slope"], covariance="hac")
    return float(fit.values[0]), float(fit.stderr[0])


def _cumulative(time: np.ndarray, values: np.ndarray) -> np.ndarray:
    """∫ values dt from the first sample (trapezoids)."""
    return np.concatenate([[0.0], np.cumsum(0.5 * (values[1:] + values[:-1]) * np.diff(time))])


def _moving_from(position: np.ndarray, threshold: float) -> int:
    """First sample at which the position has left its starting value by more than ``threshold``."""
    moved = np.flatnonzero(np.abs(position - position[0]) > threshold)
    return int(moved[0]) if moved.size else position.size


def integral_fit(time: np.ndarray, voltage: np.ndarray, position: np.ndarray, velocity: np.ndarray,
                 ks: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """∫(V − kS)dt = c₁·Δx + c₂·Δv from break-away on (the model V = kS + c₁·v + c₂·v' integrated).

    Integrating instead of differentiating keeps the noisy acceleration out of the regressors, and
    the c₂ term absorbs the inertia of this motion (a turning or strafing robot is not the forward
    one: Road Runner's page, which regresses V on v alone, reads the lag of a ramp as a smaller slope).

    Returns
    -------
    (c, stderr, lhs, model)
        Coefficients (c₁, c₂), their Newey–West standard errors, and the two curves for a plot.
    """
    start = _moving_from(position, 2.0 * float(np.median(np.abs(np.diff(position)))) + 1e-12)
    if time.size - start < 10:
        raise FitError("the robot hardly moved during the ramp")
    t, v = time[start:], voltage[start:]
    # the voltage is held over each interval (held_voltage): rectangles, not trapezoids, which would
    # take each interval's voltage half an interval early (kA +10 % on the simulated ramps)
    drive = np.sign(v) * np.maximum(np.abs(v) - ks, 0.0)
    lhs = np.concatenate([[0.0], np.cumsum(drive[:-1] * np.diff(t))])
    design = np.column_stack([position[start:] - position[start], velocity[start:] - velocity[start]])
    # Fit the increments over windows of about 0.1 s: the cumulative sums carry random-walk errors
    # (input noise integrated) that no covariance estimator of a few hundred samples gets right.
    width = max(1, round(0.1 / float(np.median(np.diff(t)))))
    edges = np.arange(0, t.size, width)
    fit = fit_linear(np.diff(design[edges], axis=0), np.diff(lhs[edges]), ["c1", "c2"], covariance="hac")
    return fit.values, fit.stderr, lhs, design @ fit.values


def _with_gains(
    name: str, unit: str, fn: Callable[[np.ndarray], float], se_fit: float, gains: np.ndarray, cov: np.ndarray,
    note: str = "",
) -> Estimate:
    """fn(gains) with its regression error and the gains' error (delta method, finite differences)."""
    value = fn(gains)
    grad = np.zeros(gains.size)
    for j in range(gains.size):
        h = 1e-4 * max(abs(gains[j]), 1e-9)
        g2 = gains.copy()
        g2[j] += h
        grad[j] = (fn(g2) - value) / h
    total = math.sqrt(se_fit**2 + float(grad @ cov @ grad))
    determined = math.isfinite(total) and total < abs(value)
    return Estimate(name, value, total, unit, determined, note)


def _gains(forward: FitResult) -> tuple[np.ndarray, np.ndarray]:
    names = ["kS", "kV", "kA"]
    values = np.array([forward[n].value for n in names])
    se = np.array([forward[n].stderr for n in names])
    if not forward["kA"].determined:  # the page's (V − kS)/kV
        values[2], se[2] = 0.0, 0.0
    cov = np.diag(np.nan_to_num(se) ** 2)
    if forward.correlation is not None and list(forward.correlation_names[:3]) == names:
        corr = np.nan_to_num(np.asarray(forward.correlation)[:3, :3])
        cov = corr * np.outer(np.nan_to_num(se), np.nan_to_num(se))
    return values, cov


def lateral_ratio(data: RampData, gains: np.ndarray, cov: np.ndarray, *, cpr: float) -> list[Estimate]:
    """Lateral speed ratio s, lateral multiplier 1/s and the strafing kA from a lateral ramp.

    V = kS + (kV/s)·v_perp + kA_lat·v_perp' (perpendicular dead-wheel ticks): the perpendicular wheel
    turns s times as fast as a forward move at the same voltage would turn the forward wheels, so
    c₁ = kV/s (kV per tick of the same dead wheels); c₂ = kA_lat is the strafing robot's inertia
    (rollers and the 1/s gearing make it differ from kA), reported as ``lateral_kA`` [V·s²/rad at the
    perpendicular dead wheel] where the ramp's break-away shows it.
    """
    if not data.velocities:
        raise FitError(f"{data.source}: the lateral ramp has no perpendicular encoder (drive encoders: "
                       "use Road Runner's LateralPushTest)")
    volts = held_voltage(data)
    pos = np.mean(list(data.positions.values()), axis=0)
    vel = np.mean(list(data.velocities.values()), axis=0)
    per_tick = 2 * math.pi / cpr

    def ratio(g: np.ndarray) -> float:
        c, *_ = integral_fit(data.time, volts, pos, vel, g[0])
        return g[1] * per_tick / c[0]

    c, se, *_ = integral_fit(data.time, volts, pos, vel, gains[0])
    value = ratio(gains)
    s = _with_gains("lateral_ratio", "1", ratio, abs(value) * se[0] / abs(c[0]), gains, cov,
                    "lateralInPerTick / inPerTick: lateral speed per forward speed at equal voltage")
    mult = Estimate("lateral_multiplier", 1.0 / s.value if s.value else math.nan,
                    s.stderr / s.value**2 if s.value else math.nan, "1", s.determined,
                    "MecanumKinematics lateralMultiplier = inPerTick / lateralInPerTick")

    def inertia(g: np.ndarray) -> float:
        c, *_ = integral_fit(data.time, volts, pos, vel, g[0])
        return float(c[1]) / per_tick

    ka = _with_gains("lateral_kA", "V*s^2/rad", inertia, se[1] / per_tick, gains, cov,
                     "strafing kA at the perpendicular dead wheel (∫(V − kS)dt = c₁·Δx + c₂·Δv)")
    if not (ka.determined and ka.value > 0):
        ka = Estimate("lateral_kA", ka.value, ka.stderr, ka.unit, False,
                      "not determined: the lateral ramp's break-away does not show the strafing inertia")
    return [s, mult, ka]


def track_width(data: RampData, gains: np.ndarray | None, cov: np.ndarray | None, *,
                cpr: float) -> tuple[list[Estimate], Panel]:
    """trackWidthTicks (and dead-wheel positions) from an angular ramp."""
    if len(data.ang_vels) != 3:
        raise FitError(f"{data.source}: the angular ramp needs the IMU's three angular velocities")
    omega = data.ang_vels[2]
    if float(np.max(np.abs(omega))) == 0.0:
        raise FitError(f"{data.source}: the IMU's yaw rate is zero throughout (stuck IMU?)")
    mec = data.drive == "mecanum"
    psi = _cumulative(data.time, omega)
    left = [v - v[0] for k, v in data.positions.items() if k.startswith("left")]
    right = [v - v[0] for k, v in data.positions.items() if k.startswith("right")]
    out: list[Estimate] = []
    if left and right:  # drive encoders measure the wheels' travel: against the integrated yaw rate
        wheel = (np.mean(right, axis=0) - np.mean(left, axis=0)) * (0.5 if mec else 1.0)
        slope, slope_se = _slope(np.diff(psi), np.diff(wheel))  # increments: no random walk in the residuals
        tw = Estimate("track_width_ticks", slope, slope_se, "tick", slope_se < abs(slope),
                      "drive-encoder travel per radian of yaw")
        x, y = psi, wheel
    else:
        if gains is None or cov is None:
            raise OptionError(f"{data.source}: an angular ramp with dead wheels needs kS and kV: give the forward "
                              "ramp file too")
        volts = held_voltage(data)
        per_tick = 2 * math.pi / cpr
        factor = 1.0 if mec else 2.0  # mecanum wheel at ω·tw; tank side at ω·tw/2 (Kinematics.kt)

        def width(g: np.ndarray) -> float:
            c, *_ = integral_fit(data.time, volts, psi, omega, g[0])
            return factor * c[0] / (g[1] * per_tick)

        coef, se, _lhs, _model = integral_fit(data.time, volts, psi, omega, gains[0])
        value = width(gains)
        tw = _with_gains("track_width_ticks", "tick", width, abs(value) * se[0] / abs(coef[0]), gains, cov,
                         "∫(V − kS)dt = kV·tw·ψ + c₂·ω, kS and kV from the forward ramp")
        x, y = omega, factor * (volts - gains[0]) / (gains[1] * per_tick)
    out.append(tw)
    for k, x_ticks in data.positions.items():
        if k.startswith(("par", "perp")):  # positions against the integrated yaw: no 50 ms window lag
            pos, pos_se = _slope(np.diff(psi), np.diff(x_ticks))
            label = f"{k}_y_ticks" if k.startswith("par") else f"{k}_x_ticks"
            out.append(Estimate(label, pos, pos_se, "tick", pos_se < abs(pos),
                                "dead-wheel travel per radian of yaw (the page's "
                                + ("y-position)" if k.startswith("par") else "x-position)")))
    order = np.argsort(x)
    panel = Panel("track width", "yaw rate ω [rad/s]", "wheel speed [ticks/s]",
                  data=Series(x, y, "(V − kS)/kV: the page's quasi-static wheel speed" if gains is not None and
                              not (left and right) else "wheel speed", "data"),
                  model=Series(x[order], tw.value * x[order], f"ω·tw, tw = {tw.value:.4g} ticks", "model"))
    return out, panel


def from_runs(runs: Sequence[Recording], *, cpr: float | None, mechanism: str = "simple") -> FitResult:
    """Fit the forward ramp(s) and derive the lateral and angular quantities (see the module)."""
    from motorlab.analyses.feedforward import feedforward

    if cpr is None:
        raise OptionError("Road Runner ramps count ticks: give --cpr")
    forward = [r for r in runs if r.metadata.get("ramp") not in ("lateral", "angular")]
    others = [r for r in runs if r.metadata.get("ramp") in ("lateral", "angular")]
    angular_drive = [r for r in others if r.metadata.get("ramp") == "angular" and "position" in r]
    base: FitResult | None = None
    if forward:
        base = feedforward(forward, mechanism=mechanism, cpr=cpr)
    elif angular_drive:  # drive-encoder angular ramp: fit the feedforward to the wheels, as the page does
        base = feedforward(angular_drive, mechanism=mechanism, cpr=cpr)
    gains, cov = _gains(base) if base is not None else (None, None)
    params: dict[str, Estimate] = dict(base.parameters) if base is not None else {}
    panels: list[Panel] = list(base.panels) if base is not None else []
    warnings: list[str] = list(base.warnings) if base is not None else []
    details: dict[str, Any] = dict(base.details) if base is not None else {}
    for rec in others:
        data: RampData = rec.metadata["roadrunner"]
        warnings.extend(w for w in rec.metadata.get("warnings", []) if w not in warnings)
        if data.kind == "lateral":
            if gains is None or cov is None:
                raise OptionError(f"{rec.source}: the lateral ramp needs kS and kV: give the forward ramp file too")
            for est in lateral_ratio(data, gains, cov, cpr=cpr):
                params[est.name] = est
        else:
            ests, panel = track_width(data, gains, cov, cpr=cpr)
            params.update({e.name: e for e in ests})
            panels.append(panel)
    details["roadrunner"] = {"cpr": cpr, "files": [r.source for r in runs]}
    return FitResult(
        "feedforward", params,
        correlation=base.correlation if base is not None else None,
        correlation_names=list(base.correlation_names) if base is not None else [],
        rmse=base.rmse if base is not None else math.nan, rmse_unit=base.rmse_unit if base is not None else "",
        r2=base.r2 if base is not None else math.nan, n_points=base.n_points if base is not None else 0,
        panels=panels, warnings=warnings, details=details,
        sources=list(dict.fromkeys(r.source for r in runs)),
    )
