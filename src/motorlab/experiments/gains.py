"""Seed 2's two gain calibrations, each a straight line through its rows: the servo amplifier's Ka
("Amplifier Gain") and the tachometer's Kt_tach ("Tachometer Gain Constant")."""

from __future__ import annotations

from typing import Any

from motorlab.experiments import Experiment, FromSession, Option, RigRun, Setting
from motorlab.experiments._shared import COLUMN, read_tables


def _gain(name: str, *, title: str, summary: str, inputs: str, unit: str, example: str, reports: tuple[str, str],
          setting: str, order: int, rig_order: int) -> Experiment:
    def run(paths: list[str], v: dict[str, Any]) -> Any:
        from motorlab.analyses import gains

        return getattr(gains, name)(read_tables(paths), nominal=v["nominal"])

    def session(ctx: Any) -> FromSession:
        return FromSession({"nominal": ctx.setting("nominal")})

    return Experiment(
        name=name, title=title, summary=summary, analysis=f"motorlab.analyses.gains:{name}", inputs=inputs, run=run,
        options=(Option("nominal", unit, positive=True, metavar="GAIN", label="Nominal gain",
                        help=f"the gain it should have, to compare with, e.g. {example}"), COLUMN),
        reports=reports, shaft="electrical", order=order, settings=(Setting("nominal", unit, setting),),
        session=session, rig=RigRun(name, f"{name}.csv", order=rig_order),
    )


EXPERIMENTS = (
    _gain("amplifier", title="Servo-amplifier gain",
          summary='Servo-amplifier gain Ka from command voltage and output current (seed 2, "Amplifier Gain")',
          inputs="CSV of command_V and current_A (or current_mA)", unit="A/V", example="'2 A/V'",
          reports=("Ka", "I0"), setting="nominal amplifier gain to compare with", order=40, rig_order=70),
    _gain("tachometer", title="Tachometer gain",
          summary='Tachometer gain Kt_tach from speed and tachometer voltage (seed 2, "Tachometer Gain Constant")',
          inputs="CSV of speed (speed_rpm or speed_rad_per_s) and tach_voltage_V", unit="V*s/rad",
          example="'0.03 V*s/rad' or '3.1 V/(1000*rpm)'", reports=("Kt_tach", "V0"),
          setting="nominal tachometer gain to compare with", order=50, rig_order=80),
)
