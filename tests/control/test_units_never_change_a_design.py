"""Units never change a design (issue 31, item 4): the same fit gives the same controller in radians,
rotations, degrees, ticks or metres of any wheel, up to the exact conversion, for every target; and Road
Runner's default design is the controller it runs (HolonomicController's position and velocity gains with
its kS·sign(command) feedforward), settling without a steady error."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from motorlab.cli import main
from motorlab.control import DesignRequest, Feedforward, MechanismUnits, Plant, design_for_target, tune
from motorlab.control.targets import INCH, TARGETS
from motorlab.control.tolerances import design_tolerances
from motorlab.errors import OptionError
from motorlab.model import MotorParams

CPR = 8192.0
#: A Road Runner forward ramp's fit at its dead wheel (the simulated drive of tests/analyses/test_roadrunner.py).
FIT = Feedforward(0.3097, 0.12536, 0.012028)
#: Every way a person can count lengths: (units, wheel radius [m]).
SYSTEMS = [("rad", None), ("rotations", None), ("degrees", None), ("ticks", None), ("rad", 0.0175), ("rad", 0.05)]
#: Targets whose numbers do not depend on the user's length unit (ticks, rotations, dimensionless gains).
OWN_UNITS = [t for t in TARGETS if t not in ("volts", "wpilib", "pedro")]


def _units(name: str, radius: float | None) -> MechanismUnits:
    return MechanismUnits.from_options(name, cpr=CPR, wheel_radius=radius)


def _design(target: str, loop: str, units: MechanismUnits, plant: Plant | None = None, **kw: object):
    return design_for_target(plant or Plant(FIT), DesignRequest(loop, target=target, units=units, **kw))  # type: ignore[arg-type]


@pytest.mark.parametrize("loop", ["velocity", "position"])
@pytest.mark.parametrize("target", TARGETS)
def test_every_target_gives_the_same_controller_in_every_unit(target: str, loop: str) -> None:
    systems = [s for s in SYSTEMS if s[1] is not None] if target == "pedro" else SYSTEMS
    if target == "ftc-pidf" and loop == "position":
        for system in systems:
            with pytest.raises(OptionError, match="velocity loop"):
                _design(target, loop, _units(*system))
        return
    designs = [(_units(*s), *_design(target, loop, _units(*s))) for s in systems]
    base_units, base_si, base_tg = designs[0]
    for units, si, tg in designs[1:]:
        # The SI design is bit for bit the same: the defaults are physical.
        assert si.to_dict() == base_si.to_dict(), (units, si, base_si)
        assert set(tg.gains) == set(base_tg.gains)
        assert set(tg.feedforward) >= set(base_tg.feedforward) - {"inPerTick"}
        if target in OWN_UNITS:
            # Per tick, per rotation, dimensionless: the same numbers whatever length unit is in use.
            shared = set(tg.feedforward) & set(base_tg.feedforward)
            assert {k: tg.feedforward[k] for k in shared} == {k: base_tg.feedforward[k] for k in shared}
            assert tg.gains == base_tg.gains
        elif target == "pedro":  # inches of the given wheel: the exact conversion
            ratio = (units.per_radian / INCH) / (base_units.per_radian / INCH)
            for key in ("driveP", "driveD"):
                assert tg.gains[key] * ratio == pytest.approx(base_tg.gains[key], rel=1e-12)
            assert tg.feedforward["xVelocity"] / ratio == pytest.approx(base_tg.feedforward["xVelocity"], rel=1e-12)
            assert tg.feedforward["staticFrictionCoefficient"] == base_tg.feedforward["staticFrictionCoefficient"]
        else:  # volts, wpilib: the user's unit, the exact conversion
            for key, value in tg.gains.items():
                assert value * units.per_radian == pytest.approx(base_tg.gains[key] * base_units.per_radian,
                                                                 rel=1e-12, abs=1e-300)
            assert tg.feedforward["kV"] * units.per_radian == pytest.approx(FIT.kV, rel=1e-12)
            assert tg.feedforward["kS"] == FIT.kS


def test_road_runner_gains_are_dimensionless_and_hold_position() -> None:
    """Both loops give the holonomic controller (a robot that corrects its position along a path), and
    the same one: axialGain [1/s] and axialVelGain [-] are kV-normalised position and velocity gains."""
    units = _units("rad", 0.0175)
    vel_si, vel = _design("roadrunner", "velocity", units)
    pos_si, pos = _design("roadrunner", "position", units)
    assert vel.gains == pos.gains
    assert pos.gains["axialGain"] > 0
    assert pos.gains["axialVelGain"] > 0
    assert pos.gains["axialGain"] == pytest.approx(pos_si.kP / FIT.kV, rel=1e-12)
    assert pos.gains["axialVelGain"] == pytest.approx(pos_si.kD / FIT.kV, rel=1e-12)
    assert (vel_si.kP, vel_si.kI) == (pos_si.kD, pos_si.kP)
    for name in ("lateral", "heading"):
        assert pos.gains[f"{name}Gain"] == pos.gains["axialGain"]
        assert pos.gains[f"{name}VelGain"] == pos.gains["axialVelGain"]


def _fit_file(tmp_path: Path) -> Path:
    path = tmp_path / "fit.json"
    path.write_text(json.dumps({"experiment": "feedforward", "parameters": {
        k: {"value": v, "stderr": 0.01 * v, "unit": u}
        for (k, v), u in zip(FIT.to_dict().items(), ("V", "V*s/rad", "V*s^2/rad"), strict=True)}}))
    return path


@pytest.mark.parametrize("loop", ["velocity", "position"])
def test_tune_command_road_runner_same_with_any_wheel_radius(tmp_path: Path, capsys, loop: str) -> None:
    """`motorlab tune … --target roadrunner --cpr 8192`: the same per-tick kS, kV, kA and path gains with no
    wheel radius, 17.5 mm and 50 mm (they were 4.53, 0.171 and 0.898 for axialVelGain)."""
    fit = _fit_file(tmp_path)
    docs = []
    for radius in ([], ["--wheel-radius", "17.5 mm"], ["--wheel-radius", "50mm"]):
        assert main(["tune", loop, "--params", str(fit), "--target", "roadrunner", "--cpr", "8192", *radius,
                     "--json"]) == 0
        docs.append(json.loads(capsys.readouterr().out))
    for doc in docs[1:]:
        assert doc["gains"] == docs[0]["gains"]
        assert {k: doc["feedforward"][k] for k in ("kS", "kV", "kA")} == {
            k: docs[0]["feedforward"][k] for k in ("kS", "kV", "kA")}
        assert doc["response"] == docs[0]["response"]
    assert docs[1]["feedforward"]["inPerTick"] == pytest.approx(2 * math.pi * 0.0175 / 8192 / INCH, rel=1e-12)


_SYSTEM = st.sampled_from(["rad", "rotations", "degrees", "ticks", "wheel"])


@settings(max_examples=25, deadline=None)
@given(kv=st.floats(0.005, 5.0), tau=st.floats(0.005, 2.0), ks=st.floats(0.0, 1.0), system=_SYSTEM,
       radius=st.floats(0.005, 0.2), cpr=st.floats(28.0, 8192.0), loop=st.sampled_from(["velocity", "position"]))
def test_a_plant_written_in_any_unit_gets_the_same_design(kv, tau, ks, system, radius, cpr, loop) -> None:
    """The plant as a person types it (kV, kA per their unit, as `tune --kv --ka --units` reads them) gives
    the SI design of the plant in radians, up to rounding."""
    si = Feedforward(ks, kv, kv * tau)
    user = MechanismUnits.from_options("rad" if system == "wheel" else system, cpr=cpr,
                                       wheel_radius=radius if system == "wheel" else None)
    n = user.per_radian
    typed = Feedforward(ks, kv / n, kv * tau / n)  # V·s per unit, as printed in that unit
    back = Plant(Feedforward(typed.kS, typed.kV * n, typed.kA * n))  # what the command line builds
    reference, _ = design_for_target(Plant(si), DesignRequest(loop, units=MechanismUnits("rad", 1.0)))
    design, tg = design_for_target(back, DesignRequest(loop, target="wpilib", units=user))
    for key, value in design.to_dict().items():
        assert value == pytest.approx(reference.to_dict()[key], rel=1e-9, abs=1e-12)
    assert tg.gains["kP"] * n == pytest.approx(reference.kP, rel=1e-9)


def test_user_tolerances_keep_their_units() -> None:
    """A tolerance typed with a unit means that quantity in every length unit; a plain number is in the unit
    in use; a percentage is of a revolution, of the free speed or of the supply voltage."""
    free = FIT.free_speed(12.0)
    wheel = _units("rad", 0.05)
    cases = [
        ({"qp": "2 deg"}, _units("rotations", None), math.radians(2), "qp"),
        ({"qp": "2 deg"}, wheel, math.radians(2), "qp"),
        ({"qp": "0.5 in"}, wheel, 0.5 * INCH / 0.05, "qp"),
        ({"qp": "100 ticks"}, _units("degrees", None), 100 * 2 * math.pi / CPR, "qp"),
        ({"qp": 0.25}, _units("rotations", None), 0.25 * 2 * math.pi, "qp"),
        ({"qp": "5 %"}, wheel, 0.05 * 2 * math.pi, "qp"),
        ({"qv": "30 rpm"}, wheel, math.pi, "qv"),
        ({"qv": "0.2 m/s"}, wheel, 0.2 / 0.05, "qv"),
        ({"qv": "1000 ticks/s"}, wheel, 1000 * 2 * math.pi / CPR, "qv"),
        ({"qv": "10%"}, _units("ticks", None), 0.1 * free, "qv"),
        ({"r": "3 V"}, wheel, 3.0, "r"),
        ({"r": "50 %"}, wheel, 6.0, "r"),
    ]
    for given_, units, expected, name in cases:
        tol = design_tolerances(FIT, 12.0, units, **given_)  # type: ignore[arg-type]
        assert getattr(tol, name) == pytest.approx(expected, rel=1e-12), (given_, units)
    assert design_tolerances(FIT, 12.0, wheel, qv="inf").qv == math.inf  # that error not penalised
    with pytest.raises(OptionError, match="wheel radius"):
        design_tolerances(FIT, 12.0, _units("rad", None), qp="1 cm")
    with pytest.raises(OptionError, match="counts per revolution"):
        design_tolerances(FIT, 12.0, MechanismUnits("rad", 1.0), qv="10 ticks/s")
    with pytest.raises(OptionError, match="--qv"):
        design_tolerances(FIT, 12.0, wheel, qv="3 V")
    with pytest.raises(OptionError, match="--r"):
        design_tolerances(FIT, 12.0, wheel, r="-2 V")


# ---- Road Runner's default design settles ------------------------------------------------------------------------
#: The drive of the ramp's fit, and a motor model with inductance, Coulomb friction and viscous friction at the dead
#: wheel (simulated exactly, not the feedforward plant the design used).
PLANTS = {
    "feedforward": Plant(FIT),
    "motor model": Plant.from_params(MotorParams(K=0.11, R=1.1, L=2e-3, J=1.15e-3, b=1.3e-4, Tf=0.031)),
}


@pytest.mark.parametrize("plant", list(PLANTS))
@pytest.mark.parametrize("loop", ["position", "velocity"])
def test_road_runner_default_design_settles_without_a_steady_error(plant: str, loop: str) -> None:
    units = _units("rad", 0.0175)
    result = tune(PLANTS[plant], DesignRequest(loop, target="roadrunner", units=units))
    m = result.step.metrics
    assert result.step.settings["law"] == "roadrunner"
    assert result.warnings == []
    assert m["settling_time"] < 2.0  # finite: reached
    assert not m["sustained_oscillation"]
    if loop == "position":  # within two encoder counts of the target (one revolution away)
        assert abs(m["steady_state_error"]) * CPR / (2 * math.pi) <= 2.0
        assert abs(result.profile.metrics["steady_state_error"]) * CPR / (2 * math.pi) <= 2.0
    else:
        assert abs(m["steady_state_error"]) < 0.01 * result.step.target


def test_without_road_runners_static_friction_feedforward_the_robot_stops_short() -> None:
    """The same gains run as a WPILib PIDController with kS·sgn(reference) feedforward (no kS at a held
    position): Coulomb friction holds the robot where the correction falls below kS. Road Runner's kS·sign of
    the velocity command is what takes the robot all the way."""
    from motorlab.control.simulation import simulate_closed_loop, step_reference

    gains, _ = _design("roadrunner", "position", _units("rad", None))
    run = {"duration": 2.0, "cpr": CPR, "voltage": 12.0}
    rr = simulate_closed_loop(gains, FIT, FIT, step_reference("position", 2 * math.pi), law="roadrunner", **run)
    pid = simulate_closed_loop(gains, FIT, FIT, step_reference("position", 2 * math.pi), law="pid", **run)
    ticks = CPR / (2 * math.pi)
    assert abs(rr.metrics["steady_state_error"]) * ticks <= 2.0
    assert pid.metrics["steady_state_error"] * ticks > 10 * max(abs(rr.metrics["steady_state_error"]) * ticks, 1.0)
    assert pid.metrics["steady_state_error"] <= FIT.kS / gains.kP * 1.001  # held where kP·e < kS


def test_road_runner_law_is_the_quickstarts_arithmetic_in_inches() -> None:
    """One controller period by hand as MecanumDrive.FollowTrajectoryAction computes it, in inches with the
    emitted PARAMS (HolonomicController.compute, then MotorFeedforward(kS, kV/inPerTick, kA/inPerTick)),
    against the simulation's law in radians."""
    from motorlab.control.simulation import _roadrunner_volts

    radius = 0.0175
    units = _units("rad", radius)
    gains, tg = _design("roadrunner", "position", units)
    p = {**tg.gains, **tg.feedforward}
    in_per_rad = radius / INCH
    cases = [((3.0, 40.0, 100.0), 2.9, 41.0), ((1.0, 0.0, 0.0), 1.0003, 0.0), ((0.0, -5.0, 0.0), 0.1, -4.0)]
    for ref, pos, vel in cases:
        x_t, v_t, a_t = (q * in_per_rad for q in ref)
        command = v_t + p["axialGain"] * (x_t - pos * in_per_rad) + p["axialVelGain"] * (v_t - vel * in_per_rad)
        ks, kv, ka = p["kS"], p["kV"] / p["inPerTick"], p["kA"] / p["inPerTick"]
        volts = math.copysign(ks, command) + kv * command + ka * a_t  # kS.withSign(vel) + kV·vel + kA·accel
        assert _roadrunner_volts(gains, FIT, ref, pos, vel) == pytest.approx(volts, rel=1e-9)
