"""The gearbox efficiency of a characterised unit (which shaft each experiment's figures are at:
:mod:`motorlab.experiments`).

A session measures K twice in different ways: a back-EMF experiment (spin-down, identification) gives
Ke, which does not see the gearbox; a lever at the output (torque test) and a torque balance through
the gearbox (spin-up) give Kt = η·Ke. This module keeps them apart (:func:`sources_of`), turns a
unit's pair into its ``efficiency`` and ``loss_torque`` (:func:`gearbox_estimates`), corrects the
spin-up's friction for the direction of power flow (:func:`motoring_friction`) and answers seed 1's
question per unit (:func:`gearbox_answer`). The physics is in :mod:`motorlab.gearbox` and
docs/gearbox.md.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from motorlab.gearbox import efficiency_estimate
from motorlab.results import Estimate, FitResult
from motorlab.units import format_value

#: Gearbox figures per unit (output shaft), when a back-EMF K and a torque test are both there.
GEARBOX_PARAMETERS = ("efficiency", "loss_torque")
#: Experiments whose K is the back-EMF constant Ke (the model's K).
BACK_EMF_SOURCES = frozenset({"spindown", "identify"})
#: Experiments whose K is a torque constant measured through the gearbox (Kt = η·Ke at the output).
TORQUE_SOURCES = frozenset({"torque", "spinup"})
#: Healthy unit-to-unit spread of the gearbox efficiency (σ of ln η), for the fleet test.
EFFICIENCY_HEALTHY_SPREAD = 0.03

def sources_of(name: str, candidates: dict[str, Estimate]) -> dict[str, Estimate]:
    """K's candidates: the torque constants through the gearbox only when no back-EMF K is there."""
    if name != "K" or not BACK_EMF_SOURCES & set(candidates):
        return candidates
    return {k: v for k, v in candidates.items() if k not in TORQUE_SOURCES}


def gearbox_estimates(fits: Mapping[str, FitResult], k: Any) -> dict[str, tuple[Estimate, str]]:
    """η = Kt(torque test, output) / Ke(back-EMF, output) and the loss torque τ0, each with its source.

    ``k`` is the unit's combined K (with ``estimate`` and ``source``). Both constants are at the output
    shaft (the encoder's), so N cancels: Kt/Ke = η·N·K_m/(N·K_m). Empty without a torque fit or without
    a back-EMF K.
    """
    fit = fits.get("torque")
    if fit is None or k is None or k.source not in BACK_EMF_SOURCES or "K" not in fit:
        return {}
    kt, ke = fit["K"], k.estimate
    if not (kt.determined and ke.determined):
        return {}
    source = f"torque ÷ {k.source}"
    eta = efficiency_estimate(kt.value, kt.stderr, ke.value, ke.stderr,
                              note=f"gearbox efficiency η = Kt (lever, output) / Ke ({k.source}, output)")
    out = {"efficiency": (eta, source)}
    if "tau0" in fit:
        t = fit["tau0"]
        loss = Estimate("loss_torque", -t.value, t.stderr, "N*m", t.determined,
                        "gearbox loss torque τ0 at the output shaft (minus the torque test's intercept)")
        out["loss_torque"] = (loss, "torque")
    return out


def motoring_friction(
    spindown: FitResult | None, box: Mapping[str, tuple[Estimate, str]], b_bare: Estimate | None,
    tf_bare: Estimate | None,
) -> tuple[float, float, float, float, float] | None:
    """The flywheel rig's friction at the output while the motor drives it, when the gearbox loses torque.

    Returns
    -------
    tuple or None
        b [N·m·s/rad], its standard error, Tf [N·m], its standard error, and η; None when the gearbox's
        loss is not measured (the spin-down's friction is then used as it is).

    Notes
    -----
    The spin-down's b, Tf (physical, output, back-driven) hold the motor's friction F_m ÷ η_b plus the
    gearbox drag τ0 and the flywheel's; motoring, the output sees η·F_m instead. With η and τ0 from the
    torque test (``box``, :func:`gearbox_estimates`) and F_m from the bare gearmotor (identify, pulse:
    per unit of K·i, τ0/η included), and η_b = η: F_motoring = F_spindown − (1/η − η)·F_m.
    """
    if spindown is None or "efficiency" not in box or "loss_torque" not in box or b_bare is None or tf_bare is None:
        return None
    eta, tau0 = box["efficiency"][0], box["loss_torque"][0]
    if not (eta.determined and eta.value < 1 - 3 * eta.stderr and "b" in spindown and "Tf" in spindown):
        return None
    factor = 1.0 / eta.value - eta.value
    tf_motor = tf_bare.value - tau0.value / eta.value
    b = spindown["b"].value - factor * b_bare.value
    tf = spindown["Tf"].value - factor * tf_motor
    if b < 0 or tf < 0:
        return None
    b_se = math.hypot(spindown["b"].stderr, factor * _finite(b_bare.stderr))
    tf_se = math.hypot(spindown["Tf"].stderr, factor * _finite(tf_bare.stderr),
                       factor * _finite(tau0.stderr) / eta.value)
    return b, b_se, tf, tf_se, eta.value


def spinup_warning(fit: FitResult, eta: Estimate) -> str | None:
    """What to say on a spin-up's result when the gearbox measurably loses torque (None: nothing)."""
    if not eta.determined or any("corrected for the gearbox" in w for w in fit.warnings):
        return None
    if eta.value >= 1 - 3 * eta.stderr:
        return None
    return (
        f"the gearbox passes η = {eta.value:.3g} of the motor's torque: this K is a torque constant through it "
        "(Kt = η·Ke at the output), and the friction taken from the spin-down (the flywheel back-driving the "
        "gearbox) is larger than while the motor drives it, so it overestimates Kt; use the torque test's "
        "Kt and the efficiency (docs/gearbox.md)"
    )


def _finite(x: float) -> float:
    return x if math.isfinite(x) and x >= 0 else 0.0


def gearbox_answer(torque_fit: Any, k: Any, efficiency: Any, *, ratio: float | None) -> dict[str, str] | None:
    """Seed 1's question for one unit: Ke×N, Kt at the output, η, and whether the mismatch is explained.

    Parameters
    ----------
    torque_fit
        The unit's torque-test :class:`~motorlab.results.FitResult` (lever at the output), or None.
    k, efficiency
        The unit's combined K (back-EMF, output shaft) and efficiency (``characterize``'s ``Combined``).
    ratio
        Gear ratio N (None: the motor-shaft Ke is not given).

    Returns
    -------
    dict or None
        Display strings ``ke_motor``, ``ke_n``, ``kt``, ``eta``, ``loss``, ``mismatch``, ``verdict``;
        None when the unit lacks a torque test or a back-EMF K.

    Notes
    -----
    The mismatch Ke×N − Kt is measured in its combined standard error. It is "explained by the
    gearbox" when η = Kt/(Ke×N) is a physical efficiency (≤ 1 within two standard errors) and the loss
    torque is not negative beyond two standard errors; a Kt above Ke×N or a negative loss torque would
    point to a calibration error (arm length, scale, current) instead.
    """
    if torque_fit is None or k is None or efficiency is None or "K" not in torque_fit:
        return None
    kt, ke, eta = torque_fit["K"], k.estimate, efficiency.estimate
    if not (kt.determined and ke.determined and eta.determined):
        return None

    def pm(value: float, stderr: float) -> str:  # to its standard error's two digits, as every table of the report
        return format_value(value, stderr) if math.isfinite(stderr) else f"{value:.4g} ± ?"

    diff = ke.value - kt.value
    sigma = math.hypot(ke.stderr, kt.stderr)
    z = diff / sigma if sigma > 0 else math.inf
    loss = -torque_fit["tau0"].value if "tau0" in torque_fit else math.nan
    loss_se = torque_fit["tau0"].stderr if "tau0" in torque_fit else math.nan
    physical = eta.value - 2 * eta.stderr <= 1.0 and not (math.isfinite(loss) and loss + 2 * loss_se < 0)
    if abs(z) < 2:
        verdict = (f"Kt and Ke×N agree within {abs(z):.1f} combined standard errors: no measurable gearbox loss "
                   f"(η = {pm(eta.value, eta.stderr)}).")
    elif physical:
        verdict = (f"Kt is {z:.0f} σ below Ke×N: the mismatch is real, far beyond the measurement noise, and the "
                   f"gearbox explains it: η = {pm(eta.value, eta.stderr)} (a loss of {100 * (1 - eta.value):.0f} % of "
                   f"the motor's torque under load) with a loss torque τ0 = {pm(loss, loss_se)} N·m.")
    else:
        verdict = (f"Kt and Ke×N differ by {z:+.0f} σ but the implied η = {pm(eta.value, eta.stderr)} or loss torque "
                   f"is not physical: check the arm length, the scale's tare and the current reading.")
    return {
        "ke_motor": pm(ke.value / ratio, ke.stderr / ratio) if ratio else "—",
        "ke_n": pm(ke.value, ke.stderr),
        "kt": pm(kt.value, kt.stderr),
        "eta": pm(eta.value, eta.stderr),
        "loss": pm(loss, loss_se) if math.isfinite(loss) else "—",
        "mismatch": f"{z:+.0f}" if abs(z) >= 10 else f"{z:+.1f}",  # a z-score is itself uncertain by about 1
        "verdict": verdict,
    }


#: Experiments run on the bare motor (no gearbox) that give its torque per amp over its back-EMF constant.
BARE_MOTOR_SOURCES = ("curve", "stall")


def bare_motor_ratio(fits_by_unit: Mapping[str, Mapping[str, FitResult]], unit: str, *,
                     k_output: Estimate | None = None, ratio: float | None = None) -> tuple[Estimate, str] | None:
    """Kt/K of the bare motor (no gearbox), and where it comes from, for ``unit``'s gearbox split.

    Looked for in ``unit``'s own fits first, then in any unit of the session (the same motor model):
    a motor curve's ``Kt_over_K`` (``analyze curve``), a stall run's ``Kt_over_K``, or a stall run's
    torque per amp ``K`` at the motor shaft divided by the unit's back-EMF constant ``k_output``/N. A
    stall run whose torque per amp exceeds the motor's back-EMF constant by more than three standard errors
    is no bare motor's (a motor's shaft gives at most Ke per amp): it was held at a gearbox's output, and is
    passed over.

    Returns
    -------
    (Estimate, str) or None
        ``Kt_over_K`` and a phrase naming its source ("curve of unit A"); None without such a run.
    """
    order = [unit, *(name for name in fits_by_unit if name != unit)]
    for name in order:
        for experiment in BARE_MOTOR_SOURCES:
            fit = fits_by_unit.get(name, {}).get(experiment)
            if fit is None:
                continue
            where = f"the {experiment} run of unit {name}"
            if "Kt_over_K" in fit and fit["Kt_over_K"].determined:
                return fit["Kt_over_K"], where
            if experiment == "stall" and "K" in fit and k_output is not None and ratio and fit["K"].determined:
                ke_motor = k_output.value / ratio
                value = fit["K"].value / ke_motor
                se = abs(value) * math.hypot(fit["K"].stderr / fit["K"].value, k_output.stderr / k_output.value)
                if value - 3 * se > 1.0:  # the torque per amp of a gearbox's output, not the motor's shaft
                    continue
                return Estimate("Kt_over_K", value, se, "1", True, "stall run's Kt ÷ the back-EMF K/N"), where
    return None


def gearbox_split(efficiency: Estimate, motor_ratio: Estimate) -> dict[str, float]:
    """Split the measured Kt/(Ke×N) = (Kt/K)_motor × η_gearbox into the bare motor's and the gearbox's parts.

    Returns
    -------
    dict
        ``motor`` (Kt/K of the bare motor) and ``gearbox`` (η of the gearbox alone = η / (Kt/K)), each
        with its standard error (``*_stderr``; relative errors combined in quadrature), and the shares of
        the total torque shortfall (``motor_share``, ``gearbox_share``: fractions of −ln(η) that sum to 1).
    """
    eta, r = efficiency, motor_ratio
    gear = eta.value / r.value
    gear_se = abs(gear) * math.hypot(eta.stderr / eta.value, r.stderr / r.value)
    total = -math.log(eta.value) if 0 < eta.value < 1 else math.nan
    motor_share = -math.log(r.value) / total if math.isfinite(total) and total > 0 and r.value > 0 else math.nan
    return {"motor": r.value, "motor_stderr": r.stderr, "gearbox": gear, "gearbox_stderr": gear_se,
            "motor_share": motor_share, "gearbox_share": 1.0 - motor_share}
