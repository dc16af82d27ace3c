"""Controller gains from motor parameters: the seed's "parameters will be used in PID algorithms".

* :mod:`~motorlab.control.design`: LQR gains exactly as WPILib SysId computes them
  (:func:`design_velocity_lqr`, :func:`design_position_lqr`, :func:`sysid_gains`) and a
  rise-time/overshoot pole-placement PID (:func:`design_pid_poles`).
* :mod:`~motorlab.control.plant`: the plant (:class:`Plant`, :func:`load_plant` from ``analyze --json``)
  and the user's length units (:class:`MechanismUnits`).
* :mod:`~motorlab.control.targets`: gains in a controller's units (:func:`to_target`: volts,
  WPILib, an FTC OpMode on power, the REV hub's velocity PIDF).
* :mod:`~motorlab.control.simulation`: closed-loop simulation on the nonlinear motor model
  (:func:`simulate_closed_loop`, :func:`max_profile`, :func:`plot_response`).
* :mod:`~motorlab.control.emit`: ready-to-paste Java/Kotlin/Python (:func:`emit_snippet`).
* :mod:`~motorlab.control.tolerances`: the LQR's default tolerances in physical terms (so that units never
  change a design) and the user's tolerances read with their units.
* :mod:`~motorlab.control.tune`: all of it in one call (:func:`tune` of a :class:`DesignRequest`,
  :func:`tune_summary`; :func:`design_for_target` without the simulations).
"""

from motorlab.control.design import (
    SYSID_PRESETS,
    Feedforward,
    Gains,
    SysIdPreset,
    design_pid_poles,
    design_position_lqr,
    design_velocity_lqr,
    sysid_gains,
)
from motorlab.control.emit import emit_snippet
from motorlab.control.plant import MechanismUnits, Plant, load_plant
from motorlab.control.simulation import (
    ClosedLoopResponse,
    ProfileLimits,
    max_profile,
    plot_response,
    simulate_closed_loop,
    step_reference,
    trapezoid,
)
from motorlab.control.targets import TARGETS, TargetGains, to_target
from motorlab.control.tune import DesignRequest, TuneResult, design_for_target, tune, tune_summary

__all__ = [
    "SYSID_PRESETS",
    "TARGETS",
    "ClosedLoopResponse",
    "DesignRequest",
    "Feedforward",
    "Gains",
    "MechanismUnits",
    "Plant",
    "ProfileLimits",
    "SysIdPreset",
    "TargetGains",
    "TuneResult",
    "design_for_target",
    "design_pid_poles",
    "design_position_lqr",
    "design_velocity_lqr",
    "emit_snippet",
    "load_plant",
    "max_profile",
    "plot_response",
    "simulate_closed_loop",
    "step_reference",
    "sysid_gains",
    "to_target",
    "trapezoid",
    "tune",
    "tune_summary",
]
