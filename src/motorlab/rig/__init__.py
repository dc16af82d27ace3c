"""Dynamometers: the virtual one (simulation) and the interface a real rig implements.

The virtual rig reproduces seed 1's dynamometer (motor, 25:1 step-up gearbox, steel disc flywheel,
relay, bench supply, INA219, encoder, logging OpMode, lever arm on a scale, LCR meter, oscilloscope)
and seed 2's servo amplifier and tachometer, writes exactly the files a real rig gives and records
the truth in ``truth.json``::

    from motorlab.rig import VirtualRig
    rig = VirtualRig("neverest40", unit_seed=1, noise_seed=7)   # unit "B"
    run = rig.spindown("testFile.txt", voltage=12.0, current_limit=4.0, split=True)
    run.paths, run.truth["expected"]["K"]
"""

from motorlab.rig.base import Dynamometer, RigRun, read_truth, write_truth
from motorlab.rig.flywheel import Disc, Flywheel
from motorlab.rig.instruments import (
    INA219,
    Amplifier,
    Encoder,
    Instruments,
    LCRMeter,
    LoggingLoop,
    MotorController,
    Multimeter,
    OpticalTachometer,
    Oscilloscope,
    PowerSupply,
    Relay,
    Scale,
    Tachometer,
)
from motorlab.rig.units import Commutator, UnitSpread, draw_gearbox, draw_unit, unit_name
from motorlab.rig.virtual import EXPERIMENTS, VirtualRig, steady_state

__all__ = [
    "EXPERIMENTS",
    "INA219",
    "Amplifier",
    "Commutator",
    "Disc",
    "Dynamometer",
    "Encoder",
    "Flywheel",
    "Instruments",
    "LCRMeter",
    "LoggingLoop",
    "MotorController",
    "Multimeter",
    "OpticalTachometer",
    "Oscilloscope",
    "PowerSupply",
    "Relay",
    "RigRun",
    "Scale",
    "Tachometer",
    "UnitSpread",
    "VirtualRig",
    "draw_gearbox",
    "draw_unit",
    "read_truth",
    "steady_state",
    "unit_name",
    "write_truth",
]
