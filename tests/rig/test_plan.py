"""Rig design calculation (seed 1, "First Experiment"): worked example, closed forms, checks, CLI."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import motorlab.cli as cli
from motorlab.catalog import Motor
from motorlab.errors import OptionError
from motorlab.model import MotorParams
from motorlab.model.load import disc_inertia
from motorlab.rig.plan import (
    coast_time,
    disc_mass,
    disc_radius_for_inertia,
    plan_rig,
    reflected_inertia,
    required_inertia,
    spin_up_time_current,
    spin_up_time_supply,
    step_up_ratio,
)

STEEL = 7850.0


@pytest.fixture
def run_cli():
    """``motorlab.cli.main``, the console script's entry point."""
    return cli.main


@pytest.fixture
def seed_plan():
    """The seed's worked example: AndyMark 60 scaled from its AndyMark 40 figures (9.1 rad/s, 4.2 N·m)."""
    return plan_rig(Motor.from_catalog("neverest60"), free_speed=9.1, stall_torque=4.2)


# ---- the seed's worked example ---------------------------------------------------------------------
def test_seed_required_inertia_with_its_rounded_numbers():
    # "α = 4.5 rad/s ÷ 5 s = 0.90 rad/s², J_f = 2.1 N·m ÷ 0.90 rad/s² = 2.33 kg·m²"
    assert required_inertia(2.1, 4.5, 5.0) == pytest.approx(2.33, abs=0.005)


def test_seed_worked_example_through_plan(seed_plan):
    assert seed_plan["current"] == pytest.approx(5.75)  # i_max/2
    assert seed_plan["torque"] == pytest.approx(2.1)  # τ_max/2
    assert seed_plan["target_speed"] == pytest.approx(4.5, abs=0.06)  # ω_max/2 ≈ 4.5
    assert seed_plan["angular_acceleration"] == pytest.approx(0.90, abs=0.011)
    # Unrounded ω_max/2 = 4.55 rad/s gives 2.31; the seed's 2.33 uses 4.5: within rounding.
    assert seed_plan["required_inertia"] == pytest.approx(2.33, rel=0.015)


def test_seed_disc_figure_drops_the_half_pi_factor():
    r, h = 0.075, 0.05
    j = disc_inertia(r, h, STEEL)
    # ½·m·r² with m = π·r²·h·ρ, by hand.
    assert j == pytest.approx(0.5 * disc_mass(r, h, STEEL) * r**2)
    assert j == pytest.approx(0.01951, rel=1e-3)
    # The seed's "0.0124 kg·m²" is r⁴·ρ·h: its formula ½·π·r⁴·ρ·h evaluated without ½·π.
    assert r**4 * STEEL * h == pytest.approx(0.0124, rel=0.005)
    assert j == pytest.approx(0.0124 * math.pi / 2, rel=0.005)
    # Hence its "188 times less than desired" (2.33/0.0124); the correct shortfall is ≈ 120.
    assert 2.33 / (r**4 * STEEL * h) == pytest.approx(188, abs=1)
    assert 2.33 / j == pytest.approx(119.4, abs=0.5)


def test_seed_plan_flywheel_figures(seed_plan):
    assert seed_plan["disc_inertia"] == pytest.approx(0.01951, rel=1e-3)
    assert seed_plan["shortfall"] == pytest.approx(seed_plan["required_inertia"] / 0.019508, rel=1e-3)
    # The step-up ratio that makes this disc enough: √(J_f/J_disc) ≈ 10.9 (the seed built 25:1).
    assert seed_plan["step_up_needed"] == pytest.approx(10.88, abs=0.02)
    assert any("times less than" in w for w in seed_plan.warnings)


def test_step_up_and_reflection():
    assert reflected_inertia(0.0124, 25) == pytest.approx(7.75)
    assert step_up_ratio(2.33, 0.0124) == pytest.approx(math.sqrt(188), rel=0.01)
    j = disc_inertia(0.2, 0.03, 2700.0)
    assert disc_radius_for_inertia(j, 0.03, 2700.0) == pytest.approx(0.2)


# ---- closed forms against the simulator -----------------------------------------------------------
def crossing_time(sim, speed):
    k = int(np.argmax(sim.speed >= speed))
    assert k > 0, "speed not reached in the simulation"
    t0, t1, w0, w1 = sim.time[k - 1], sim.time[k], sim.speed[k - 1], sim.speed[k]
    return t0 + (speed - w0) * (t1 - t0) / (w1 - w0)


@pytest.fixture
def rig():
    """NeveRest 40 nominal parameters with a steel disc on a 5:1 step-up (τm of a few seconds)."""
    return Motor.from_catalog("neverest40").nominal_params().with_load(disc_inertia(0.05, 0.02, STEEL), ratio=5)


def test_spin_up_current_matches_simulation(rig):
    from motorlab.model.simulate import CurrentDrive, simulate

    target = 10.0
    t = spin_up_time_current(rig, 2.0, target)
    sim = simulate(rig, CurrentDrive(2.0), duration=1.3 * t, dt=2e-3)
    assert crossing_time(sim, target) == pytest.approx(t, rel=2e-3)


@pytest.mark.parametrize(("voltage", "limit", "target"), [(12.0, 3.0, 14.0), (12.0, 3.0, 5.0), (6.0, 20.0, 6.0)])
def test_spin_up_bench_supply_matches_simulation(rig, voltage, limit, target):
    from motorlab.model.simulate import BenchSupply, simulate

    t = spin_up_time_supply(rig, voltage, limit, target)
    sim = simulate(rig, BenchSupply(voltage, limit), duration=1.2 * t, dt=2e-3)
    # L is neglected in the closed form (L/R ≈ 0.7 ms against seconds).
    assert crossing_time(sim, target) == pytest.approx(t, rel=3e-3)


def test_coast_matches_simulation(rig):
    from motorlab.model.simulate import OpenCircuit, State, simulate

    t = coast_time(rig, 15.0, final_speed=3.0)
    sim = simulate(rig, OpenCircuit(), duration=1.2 * t, dt=2e-3, initial=State(speed=15.0))
    k = int(np.argmax(sim.speed <= 3.0))
    assert sim.time[k] == pytest.approx(t, abs=3e-3)
    t_stop = coast_time(rig, 15.0)
    sim = simulate(rig, OpenCircuit(), duration=1.1 * t_stop, dt=2e-3, initial=State(speed=15.0))
    assert sim.time[int(np.argmax(sim.speed <= 0.0))] == pytest.approx(t_stop, abs=3e-3)


def test_coast_limits():
    viscous_only = MotorParams(K=0.5, R=1.0, L=0.0, J=0.1, b=0.01, Tf=0.0)
    assert math.isinf(coast_time(viscous_only, 10.0))
    assert coast_time(viscous_only, 10.0, final_speed=10 / math.e) == pytest.approx(10.0)
    coulomb_only = MotorParams(K=0.5, R=1.0, L=0.0, J=0.1, b=0.0, Tf=0.05)
    assert coast_time(coulomb_only, 10.0) == pytest.approx(20.0)
    with pytest.raises(OptionError):
        coast_time(coulomb_only, 10.0, final_speed=11.0)


def test_unreachable_speeds_are_infinite(rig):
    assert math.isinf(spin_up_time_current(rig, 0.9 * rig.Tf / rig.K, 1.0))  # cannot break away
    w_max = rig.free_speed(12.0)
    assert math.isinf(spin_up_time_supply(rig, 12.0, 5.0, 1.01 * w_max))
    assert math.isfinite(spin_up_time_supply(rig, 12.0, 5.0, 0.99 * w_max))


# ---- checks and errors ---------------------------------------------------------------------------
def test_sensor_and_resolution_warnings():
    motor = Motor.from_catalog("corehex")
    quiet = plan_rig(motor, current=1.0, ratio=25, voltage=12.0, fraction=0.5)
    assert not any("INA219" in w for w in quiet.warnings)
    loud = plan_rig(motor, current=4.0, voltage=18.0, log_period=2.0, lever_arm=0.05, scale_capacity=1.0)
    text = " ".join(loud.warnings)
    assert "16 V bus limit" in text
    assert "±3.2 A" in text
    assert "log samples" in text
    assert "capacity" in text
    assert loud["scale_reading"] == pytest.approx(loud["torque"] / (9.80665 * 0.05))
    sparse = plan_rig(Motor.from_catalog("neverest37"), fraction=0.01, log_period=0.01)
    assert any("encoder counts per" in w for w in sparse.warnings)


def test_encoder_figures(seed_plan):
    cpr = 1680
    assert seed_plan["rate_target"] == pytest.approx(seed_plan["target_speed"] * cpr / (2 * math.pi))
    assert seed_plan["counts_per_period"] == pytest.approx(seed_plan["rate_target"] * 0.1)


@pytest.mark.parametrize(
    "options",
    [{"fraction": 1.0}, {"fraction": 0.0}, {"current": 12.0}, {"current": -1.0}, {"material": "wood"},
     {"radius": -0.1}, {"ratio": 0.0}, {"time": math.nan}, {"log_period": 0.0}],
)
def test_impossible_options_raise(options):
    with pytest.raises(OptionError):
        plan_rig(Motor.from_catalog("neverest60"), **options)


def test_plan_json_is_complete(seed_plan):
    data = seed_plan.to_dict()
    json.dumps(data, allow_nan=False)
    assert data["sections"]["target"]["required_inertia"]["unit"] == "kg*m^2"
    with pytest.raises(KeyError):
        seed_plan["nonsense"]


# ---- CLI -----------------------------------------------------------------------------------------
def test_cli_plan_table(run_cli, capsys):
    argv = ["plan", "--motor", "NeveRest 60", "--free-speed", "9.1 rad/s", "--stall-torque", "4.2 N*m"]
    assert run_cli([*argv, "--ratio", "25", "--voltage", "12 V", "--log-period", "100 ms"]) == 0
    out = capsys.readouterr().out
    assert "2.308" in out
    assert "0.01951" in out
    assert "kg·m²" in out


def test_cli_plan_json(run_cli, capsys):
    assert run_cli(["plan", "--motor", "neverest60", "--current", "5.75 A", "--time", "5 s", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    target = data["sections"]["target"]
    assert target["torque"]["value"] == pytest.approx(5.75 * 593 * 0.0070615518 / 11.5, rel=1e-6)
    assert data["motor"] == "neverest60"


@pytest.mark.parametrize(
    "argv",
    [["--ratio", "-1"], ["--radius", "five"], ["--time", "5 V"], ["--material", "wood"]],
)
def test_cli_plan_bad_options_exit_2(run_cli, capsys, argv):
    with pytest.raises(SystemExit) as info:
        run_cli(["plan", "--motor", "neverest60", *argv])
    assert info.value.code == 2
    assert capsys.readouterr().err.count("\n") == 1


@pytest.mark.parametrize("argv", [["--motor", "neverest99"], ["--motor", "neverest60", "--fraction", "1.5"],
                                  ["--motor", "neverest60", "--current", "20 A"]])
def test_cli_plan_library_errors_exit_2(run_cli, capsys, argv):
    assert run_cli(["plan", *argv]) == 2
    err = capsys.readouterr().err
    assert err.startswith("motorlab: error: ")


def test_identification_log_plan_from_the_cramer_rao_bound():
    from motorlab.rig.plan import plan_identification_log

    motor = MotorParams(K=0.35, R=2.5, L=7e-4, J=8e-4, b=2e-3, Tf=0.03)
    plan = plan_identification_log(motor, target=0.01)
    slow, fast, long_holds = plan["designs"]
    # τe = L/R = 0.28 ms: a 1 kHz log barely sees the current rise, 10 kHz does
    assert slow["relative_bound_1s"]["L"] > 5 * fast["relative_bound_1s"]["L"]
    # long holds leave few switches and speeds: friction is told far less well
    assert long_holds["relative_bound_1s"]["Tf"] > 3 * fast["relative_bound_1s"]["Tf"]
    assert "10000 Hz" in plan["recommendation"]
    with pytest.raises(OptionError):
        plan_identification_log(motor, target=2.0)


def test_cli_plan_identification_log(run_cli, capsys):
    assert run_cli(["plan", "--motor", "neverest40", "--identification-log", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert "Hz" in data["identification_log"]["recommendation"]
    assert len(data["identification_log"]["designs"]) == 3
