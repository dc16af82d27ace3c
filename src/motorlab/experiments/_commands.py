"""The options of ``motorlab tune`` and ``motorlab characterize``, described as the experiments' are.

One description feeds the CLI's parser (:mod:`motorlab.cli.tune`, :mod:`motorlab.cli.characterize`),
the browser app's forms (``GET /api/schema``) and the docs. Options that name output files or the
output format (``--json``, ``--plot``, ``--emit``, ``--output``, ``--quiet``, ``--no-report``) belong to
the CLI and are not described here.
"""

from __future__ import annotations

from motorlab.experiments import Option

#: ``--units`` of ``tune`` (as :data:`motorlab.control.plant.UNIT_NAMES`; tests/ui/test_api.py checks).
UNIT_NAMES = ("rad", "rotations", "degrees", "ticks", "m", "ft", "in")
#: ``--method`` of ``tune`` (as :data:`motorlab.control.tune.METHODS`).
METHODS = ("lqr", "poles")

_PLANT = "plant"
_DESIGN = "design"
_OUTPUT = "output"


def tune_options(targets: tuple[str, ...]) -> tuple[Option, ...]:
    """``motorlab tune``'s options; ``targets`` are :data:`motorlab.control.targets.TARGETS`."""
    return (
        Option("loop", kind="choice", choices=("velocity", "position"), positional=True, required=True,
               label="What the loop controls", help="the speed (velocity) or the angle or distance (position)"),
        Option("kv", "V*s/unit", kind="number", group=_PLANT, label="Velocity gain kV",
               help="volts per unit of speed, in the length unit chosen below"),
        Option("ka", "V*s^2/unit", kind="number", group=_PLANT, label="Acceleration gain kA",
               help="volts per unit of acceleration, in the length unit chosen below"),
        Option("ks", "V", kind="number", default=0.0, group=_PLANT, label="Static friction voltage kS",
               help="the voltage that just overcomes friction"),
        Option("params", kind="files", metavar="FILE.json", group=_PLANT, label="Results to take the motor from",
               help="motorlab's results (an analysis's JSON or a session's results.json) with K, R, J or kS, "
                    "kV, kA; several are merged"),
        Option("unit", kind="text", metavar="NAME", group=_PLANT, label="Which unit of the session",
               help="the unit's name in a session's results.json, when it has several"),
        Option("units", kind="choice", choices=UNIT_NAMES, group=_PLANT, label="Length unit",
               help="of kV, kA, the tolerances and the step: radians, rotations, degrees, encoder ticks, or "
                    "metres, feet or inches at the wheel; left empty: the unit of the file the results were "
                    "fitted from (a SysId file's), else radians"),
        Option("cpr", "count", kind="number", positive=True, group=_PLANT, label="Encoder counts per revolution",
               help="of the shaft the gains are for (the FTC, Road Runner and Phoenix 5 targets count ticks)"),
        Option("wheel-radius", "m", positive=True, group=_PLANT, label="Wheel radius",
               help='lengths in metres at the rim of this wheel, e.g. "2 in" or "48 mm"'),
        Option("method", kind="choice", choices=METHODS, default="lqr", group=_DESIGN, label="Design method",
               help="LQR as WPILib SysId (lqr), or a rise time and overshoot (poles)"),
        Option("qp", kind="text", metavar="TOLERANCE", group=_DESIGN, label="Position error tolerance",
               help="LQR: the position error the loop may keep: a number in the length unit, a quantity such as "
                    "\"2 deg\", \"0.5 in\" or \"100 ticks\", or a percentage of one revolution; left empty: the "
                    "distance the velocity tolerance covers in one time constant kA/kV, the same in every unit"),
        Option("qv", kind="text", metavar="TOLERANCE", group=_DESIGN, label="Velocity error tolerance",
               help="LQR: the velocity error the loop may keep: a number in the length unit per second, a quantity "
                    "such as \"30 rpm\" or \"0.2 m/s\", or a percentage of the free speed; left empty: 20 % of "
                    "the free speed"),
        Option("r", kind="text", metavar="VOLTS", group=_DESIGN, label="Control effort tolerance",
               help="LQR: the voltage the loop may spend on an error, in volts or a percentage of the supply "
                    "voltage; left empty: 7 V of 12 (58 %)"),
        Option("period", "s", positive=True, group=_DESIGN, label="Controller period",
               help="how often the controller runs; left empty: the target's (20 ms; 1 ms on a CTRE or REV "
                    "controller, as SysId's presets)"),
        Option("delay", "s", nonnegative=True, group=_DESIGN, label="Measurement delay",
               help="how late the measurement reaches the controller; left empty: the target's own (as "
                    "SysId's presets), 0 for volts"),
        Option("rise-time", "s", positive=True, group=_DESIGN, label="Rise time wanted",
               help="poles: the 10–90 % rise time of a step"),
        Option("overshoot", "%", kind="number", default=5.0, group=_DESIGN, label="Largest overshoot",
               help="poles: the overshoot allowed on a step"),
        Option("target", kind="choice", choices=targets, default="volts", group=_OUTPUT,
               label="Controller the gains are for",
               help="the library or device that runs the loop; the gains come in its units"),
        Option("drive", kind="choice", choices=("mecanum", "tank"), default="mecanum", group=_OUTPUT,
               label="Road Runner drive class",
               help="the quickstart's drive class whose Params the Road Runner code fills: MecanumDrive or TankDrive"),
        Option("voltage", "V", positive=True, default=12.0, group=_OUTPUT, label="Supply voltage",
               help="the battery's nominal voltage (power and duty conversions, the fastest profile)"),
        Option("step", "unit", kind="number", group=_OUTPUT, label="Step size simulated",
               help="a speed for a velocity loop, a distance for a position loop; left empty: half the free "
                    "speed, or one revolution"),
    )


CHARACTERIZE_OPTIONS = (
    Option("session", kind="files", positional=True, required=True, metavar="SESSION.toml",
           label="Session description", help="the session's TOML file (docs/session.md) with its logs"),
)


def command_options(command: str) -> tuple[Option, ...]:
    """The options of ``motorlab tune`` or ``motorlab characterize``.

    Raises
    ------
    KeyError
        Another command.
    """
    if command == "tune":
        from motorlab.control.targets import TARGETS

        return tune_options(TARGETS)
    return {"characterize": CHARACTERIZE_OPTIONS}[command]
