"""Road Runner ramps round-tripped on the simulated mecanum drive (known truth, several seeds)."""

from __future__ import annotations

import json

import pytest

from motorlab.analyses.feedforward import feedforward
from motorlab.cli import main
from motorlab.io import read_any
from motorlab.rig.ftc import BulkReadLoop, HubEncoder, MecanumDrive, RampSettings, simulate_ramp


@pytest.mark.parametrize("seed", [11, 12, 13])
def test_forward_ramp_gains_with_known_truth(tmp_path, seed):
    path = tmp_path / "forward.json"
    truth = simulate_ramp(path, seed=seed)
    assert truth["wrapped_samples"] > 0
    assert truth["min_bus_voltage"] < 13.0
    result = feedforward(read_any(path, cpr=truth["cpr"]), cpr=truth["cpr"])
    ks, kv, ka = result["kS"], result["kV"], result["kA"]
    assert ks.value == pytest.approx(truth["kS"], rel=0.05)
    assert kv.value == pytest.approx(truth["kV"], rel=0.02)
    for est in (ks, kv, ka):
        assert abs(est.value - truth[est.name]) < 3.5 * est.stderr, est
    assert ka.determined  # the break-away at the start of the ramp shows the inertia


def test_forward_ramp_other_loops_and_encoders(tmp_path):
    """Files unlike the default simulation: the logger's own loop (no idle time between iterations,
    so a fixed period and long Lynx commands), a fast loop, a fractional-cpr encoder, a short ramp."""
    cases = [
        ({"loop": BulkReadLoop(min_period=0.0205, max_period=0.0205, mean_extra=0.0, command_time=3e-3,
                               voltage_read_time=3.5e-3, bulk_read_time=5e-3)}, 21),
        ({"loop": BulkReadLoop(min_period=0.005, max_period=0.012, mean_extra=0.002, command_time=3e-4,
                               voltage_read_time=5e-4, bulk_read_time=1e-3),
          "settings": RampSettings(duration=3.0)}, 22),
        ({"drive": MecanumDrive(dead_wheel=HubEncoder(537.7), dead_wheel_radius=0.048)}, 23),
    ]
    for options, seed in cases:
        path = tmp_path / f"forward{seed}.json"
        truth = simulate_ramp(path, seed=seed, **options)
        result = feedforward(read_any(path, cpr=truth["cpr"]), cpr=truth["cpr"])
        ks, kv = result["kS"], result["kV"]
        assert ks.value == pytest.approx(truth["kS"], rel=0.05), options
        assert kv.value == pytest.approx(truth["kV"], rel=0.02), options
        assert abs(ks.value - truth["kS"]) < 3 * ks.stderr, options


def test_cli_all_three_ramps(tmp_path, capsys):
    paths = {k: tmp_path / f"{k}.json" for k in ("forward", "lateral", "angular")}
    truths = {k: simulate_ramp(p, kind=k, seed=5) for k, p in paths.items()}
    code = main(["analyze", "feedforward", *map(str, paths.values()), "--cpr", "8192", "--json"])
    out = capsys.readouterr().out
    assert code == 0
    doc = json.loads(out)
    params = doc["parameters"]
    assert "whole robot" in doc["details"]["shaft"]  # not a SysId mechanism's shaft
    truth = truths["forward"]
    for name in ("kS", "kV", "track_width_ticks", "lateral_ratio"):
        est = params[name]
        assert abs(est["value"] - truth[name]) < 4 * est["stderr"], name
    assert params["track_width_ticks"]["value"] == pytest.approx(truth["track_width_ticks"], rel=0.005)
    assert params["lateral_multiplier"]["value"] == pytest.approx(1 / truth["lateral_ratio"], rel=0.005)
    lateral_ka = params["lateral_kA"]  # the strafing inertia, for Pedro's lateralZeroPowerAcceleration
    assert abs(lateral_ka["value"] - truths["lateral"]["lateral_kA"]) < 3 * lateral_ka["stderr"]
    assert lateral_ka["value"] == pytest.approx(truths["lateral"]["lateral_kA"], rel=0.15)
    assert params["par0_y_ticks"]["unit"] == "tick"


def test_side_ramps_need_the_forward_one(tmp_path, capsys):
    path = tmp_path / "lateral.json"
    simulate_ramp(path, kind="lateral", seed=1)
    assert main(["analyze", "feedforward", str(path), "--cpr", "8192"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert "forward ramp" in err[0]


def test_angular_ramp_with_drive_encoders(tmp_path, capsys):
    path = tmp_path / "angular.json"
    truth = simulate_ramp(path, kind="angular", drive_encoder_cpr=538, seed=4)
    assert main(["analyze", "feedforward", str(path), "--cpr", "538", "--json"]) == 0
    params = json.loads(capsys.readouterr().out)["parameters"]
    tw = params["track_width_ticks"]
    assert abs(tw["value"] - truth["drive_track_width_ticks"]) < 4 * tw["stderr"]
    assert tw["value"] == pytest.approx(truth["drive_track_width_ticks"], rel=0.002)
    # the feedforward of the turning wheels, fitted from the same file as the page does
    assert params["kV"]["value"] == pytest.approx(0.3438, rel=0.01)


def test_simulate_roadrunner_ramp_command_round_trip(tmp_path, capsys):
    """``motorlab simulate roadrunner-ramp`` writes the OpMode's JSON and the truth; the fit recovers it."""
    path = tmp_path / "forward.json"
    assert main(["simulate", "roadrunner-ramp", "--seed", "11", "-o", str(path)]) == 0
    assert "--cpr 8192" in capsys.readouterr().out
    truth = json.loads((tmp_path / "truth.json").read_text())["runs"]["forward.json"]["expected"]
    assert main(["analyze", "feedforward", str(path), "--cpr", f"{truth['cpr']:g}", "--json"]) == 0
    params = json.loads(capsys.readouterr().out)["parameters"]
    assert params["kS"]["value"] == pytest.approx(truth["kS"], rel=0.05)
    assert params["kV"]["value"] == pytest.approx(truth["kV"], rel=0.02)
    assert main(["simulate", "roadrunner-ramp", "-o", str(tmp_path / "ramp.csv")]) == 2  # the OpMode writes JSON
