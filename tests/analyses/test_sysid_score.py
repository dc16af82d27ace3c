"""The fair score of gains on SysId logs: an exact simulator, the fit to it, and five real robots' logs.

The real files (../shared/data/real/sysid/, read in place; provenance and the teams' gains in its README) are read
with both drivetrain sides, fitted by ``motorlab.analyses.feedforward.feedforward`` and scored against the gains
the teams published.
"""

from __future__ import annotations

import argparse
import json
import math

import numpy as np
import pytest
from tests.real_data import team_gains

from motorlab.analyses.feedforward import feedforward
from motorlab.analyses.sysid_score import (
    ScoreTest,
    file_tests,
    fit_gains,
    residuals,
    score,
    score_file,
    simulate_gains,
    simulate_sensitivity,
    speed_lag,
)
from motorlab.cli.analyze import add_arguments, from_cli
from motorlab.errors import LogFormatError, OptionError
from motorlab.io import read_frc_char_json, read_sysid_json

# --------------------------------------------------------------------------------------------------
# the simulator
# --------------------------------------------------------------------------------------------------


def jittered_time(n: int, seed: int, dt: float = 0.005) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.concatenate([[0.0], np.cumsum(dt * (1 + 0.3 * rng.uniform(-1, 1, n - 1)))])


def test_step_from_rest_is_exact_on_jittered_rows():
    ks, kv, ka, volts = 0.3, 2.0, 0.4, 6.0
    t = jittered_time(400, seed=1)
    test = ScoreTest("fast-forward", t, np.full(t.size, volts), np.full(t.size, 1.5), np.zeros(t.size))
    speed, position = simulate_gains(ks, kv, ka, test)
    tau, v_inf = ka / kv, (volts - ks) / kv
    np.testing.assert_allclose(speed, v_inf * (1 - np.exp(-t / tau)), rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(position, 1.5 + v_inf * (t - tau * (1 - np.exp(-t / tau))), rtol=1e-9, atol=1e-12)


def test_static_friction_holds_and_stops():
    ks, kv, ka = 0.5, 1.0, 0.2
    t = np.arange(200) * 0.01
    # below kS nothing moves; a coasting shaft whose push drops below kS stops and stays stopped
    test = ScoreTest("slow-forward", t, np.full(t.size, 0.4), np.zeros(t.size), np.zeros(t.size))
    speed, position = simulate_gains(ks, kv, ka, test)
    assert np.all(speed == 0)
    assert np.all(position == 0)
    coast = ScoreTest("x", t, np.full(t.size, 0.3), np.zeros(t.size), np.full(t.size, 2.0))
    speed, position = simulate_gains(ks, kv, ka, coast)
    # decelerating as τ·v' = (0.3 − 0.5) − v: zero at t0 = τ·ln((2 + 0.2)/0.2), then at rest
    t0 = 0.2 * math.log(2.2 / 0.2)
    assert np.all(speed[t > t0 + 1e-9] == 0)
    assert np.all(speed[t < t0 - 0.01] > 0)
    stop = -0.2 * t0 + (2.0 + 0.2) * 0.2 * (1 - math.exp(-t0 / 0.2))
    assert position[-1] == pytest.approx(stop, rel=1e-9)


def test_negative_ks_and_zero_ka():
    t = np.arange(50) * 0.01
    volts = np.where(t < 0.25, 3.0, -3.0)
    test = ScoreTest("x", t, volts, np.zeros(t.size), np.zeros(t.size))
    speed, _ = simulate_gains(-0.2, 2.0, 0.0, test)  # no inertia: the speed follows the voltage row by row
    np.testing.assert_allclose(speed[1:], (volts[:-1] + 0.2 * np.sign(volts[:-1])) / 2.0)
    speed, _ = simulate_gains(-0.2, 2.0, 1e-9, test)  # many time constants per row: no overflow
    assert np.all(np.isfinite(speed))
    with pytest.raises(OptionError, match="kV > 0"):
        score((0.1, 0.0, 0.1), [test])


@pytest.mark.parametrize("gains", [(0.4, 1.0, 0.2), (-0.1, 2.0, 0.5), (0.4, 1.0, 1e-7)])
def test_sensitivities_match_central_differences(gains):
    """The fit's Jacobian (sensitivity equations) against differences of the simulation itself, on jittered
    rows with a ramp from rest (static friction), a step, and a reversal (a stop inside a step, then off
    the other way); with kA = 1e-7 every row settles (the blocks of many time constants)."""
    rng = np.random.default_rng(3)
    t = np.concatenate([[0.0], np.cumsum(0.02 * (1 + 0.3 * rng.uniform(-1, 1, 799)))])
    volts = np.concatenate([np.linspace(0, 6, 400), np.full(200, 7.0), np.full(200, -3.0)])
    test = ScoreTest("x", t, volts, np.full(t.size, 1.0), np.zeros(t.size))
    speed, position, d_speed, d_position = simulate_sensitivity(*gains, test)
    plain = simulate_gains(*gains, test)
    np.testing.assert_array_equal(speed, plain[0])  # the same simulation
    np.testing.assert_array_equal(position, plain[1])
    p = np.array([gains[0], math.log(gains[1]), math.log(gains[2])])
    for i in range(3):
        h = np.zeros(3)
        h[i] = 1e-6
        up = simulate_gains(p[0] + h[0], math.exp(p[1] + h[1]), math.exp(p[2] + h[2]), test)
        down = simulate_gains(p[0] - h[0], math.exp(p[1] - h[1]), math.exp(p[2] - h[2]), test)
        for k, derivative in ((0, d_speed[i]), (1, d_position[i])):
            numeric = (up[k] - down[k]) / 2e-6
            scale = max(float(np.max(np.abs(numeric))), 1e-3)
            np.testing.assert_allclose(derivative, numeric, rtol=0, atol=2e-4 * scale)
    assert np.max(np.abs(d_position[0])) > 1  # kS moves the position: the test is not of zeros


def test_rows_of_many_time_constants_are_simulated_in_blocks(monkeypatch):
    """kA → 0 (a fit explores it): each row settles; the speed follows the voltage, not row by row in Python.

    A 150-row wpilog took 13 s of CPU in the fuzz run (case 1262): every row was a block of its own.
    """
    import motorlab.analyses.sysid_score as sysid_score

    calls = []
    for name in ("_linear_steps", "_stiff_block"):
        original = getattr(sysid_score, name)
        monkeypatch.setattr(sysid_score, name, lambda *a, _f=original: calls.append(1) or _f(*a))
    t = np.arange(5000) * 0.01
    volts = 2.0 + np.sin(t)
    test = ScoreTest("x", t, volts, np.zeros(t.size), np.zeros(t.size))
    speed, position = simulate_gains(0.3, 2.0, 1e-9, test)
    assert len(calls) <= 5
    np.testing.assert_allclose(speed[1:], (volts[:-1] - 0.3) / 2.0, rtol=1e-12)
    step = (volts[:-1] - 0.3) / 2.0 * np.diff(t)  # each row's distance at its settled speed (τ ≪ dt)
    np.testing.assert_allclose(position[1:], np.cumsum(step), rtol=1e-6)


def test_fit_round_trip_with_noise():
    """Tests simulated with known gains, noisy speed and position: the fit finds them within its errors."""
    truth = (0.25, 1.8, 0.3)
    rng = np.random.default_rng(7)
    tests = []
    for name, sign, volts in (("slow-forward", 1, None), ("slow-backward", -1, None),
                              ("fast-forward", 1, 6.0), ("fast-backward", -1, 6.0)):
        t = jittered_time(600 if volts is None else 300, seed=len(tests))
        v = sign * (0.5 * t if volts is None else np.full(t.size, volts))
        clean = ScoreTest(name, t, v, np.zeros(t.size), np.zeros(t.size))
        speed, position = simulate_gains(*truth, clean)
        # at rest a controller reports its reading exactly: the first row, where the score starts, is clean
        speed_noise, position_noise = 0.02 * rng.standard_normal(t.size), 0.002 * rng.standard_normal(t.size)
        speed_noise[0] = position_noise[0] = 0.0
        tests.append(ScoreTest(name, t, v, position + position_noise, speed + speed_noise))
    fit = fit_gains(tests, [(0.1, 1.5, 0.5)])
    stderr = np.sqrt(np.diag(fit.covariance))
    assert np.all(stderr > 0)
    for k in range(3):
        assert abs(fit.gains[k] - truth[k]) < 4 * stderr[k], (k, fit.gains[k], stderr[k])
        assert fit.gains[k] == pytest.approx(truth[k], rel=0.01)
    assert speed_lag(fit.gains, tests)[0] == 0.0  # nothing lags here


def _noisy_tests(truth, rows, seed):
    """The four SysId tests simulated with ``truth``, noisy speed and position (clean first rows)."""
    rng = np.random.default_rng(seed)
    tests = []
    for name, sign, volts in (("slow-forward", 1, None), ("slow-backward", -1, None),
                              ("fast-forward", 1, 6.0), ("fast-backward", -1, 6.0)):
        t = jittered_time(rows if volts is None else rows // 2, seed=seed + len(tests))
        v = sign * (6.0 * t / t[-1] if volts is None else np.full(t.size, volts))
        speed, position = simulate_gains(*truth, ScoreTest(name, t, v, np.zeros(t.size), np.zeros(t.size)))
        speed_noise, position_noise = 0.02 * rng.standard_normal(t.size), 0.002 * rng.standard_normal(t.size)
        speed_noise[0] = position_noise[0] = 0.0
        tests.append(ScoreTest(name, t, v, position + position_noise, speed + speed_noise))
    return tests


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_long_logs_rank_the_starts_on_every_kth_row(seed, monkeypatch):
    """Above COARSE_ROWS rows the starts are ranked on every k-th row and only the best is fitted to every
    row: the gains of fitting every start to every row, within a small part of a standard error."""
    from motorlab.analyses import sysid_score

    truth = (0.25, 1.8, 0.3)
    tests = _noisy_tests(truth, 8_000, seed)  # 24,000 rows
    assert sum(t.time.size for t in tests) > sysid_score.COARSE_ROWS
    starts = [(0.1, 1.5, 0.5), (0.6, 3.0, 0.02)]
    full_fits = []
    original = sysid_score._reweighted_fit

    def counted(sims, *args):
        full_fits.append(sum(t.time.size for t in sims.tests) == sum(t.time.size for t in tests))
        return original(sims, *args)

    monkeypatch.setattr(sysid_score, "_reweighted_fit", counted)
    ranked = fit_gains(tests, starts)
    assert full_fits.count(True) == 1
    assert full_fits.count(False) == 2
    monkeypatch.setattr(sysid_score, "COARSE_ROWS", 10**9)
    every = fit_gains(tests, starts)
    assert full_fits.count(True) == 3
    stderr = np.sqrt(np.diag(ranked.covariance))
    for k in range(3):
        assert abs(ranked.gains[k] - every.gains[k]) < 0.05 * stderr[k], (k, ranked.gains, every.gains, stderr)
        assert abs(ranked.gains[k] - truth[k]) < 4 * stderr[k], (k, ranked.gains[k], stderr[k])


# --------------------------------------------------------------------------------------------------
# the five real logs
# --------------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def real_scores(real_dir):
    """file -> (motorlab's gains in the file's units, its score, the team's score, the FitResult), for the five logs
    of the table of the teams' gains in ../shared/data/real/sysid/README.md."""
    out = {}
    for name, team in team_gains(real_dir / "sysid").items():
        path = real_dir / "sysid" / name
        rec = read_sysid_json(path, side="both")
        result = feedforward(rec.split())
        unit = rec.metadata["si_per_unit"]
        ours = (result.value("kS"), result.value("kV") * unit, result.value("kA") * unit)
        out[name] = (ours, score_file(path, ours), score_file(path, team), result)
    return out


def test_real_files_read_both_sides(real_dir):
    path = real_dir / "sysid" / "mbb_drivetrain.json"
    rec = read_sysid_json(path, side="both")
    assert list(rec.segments)[:2] == ["slow-forward#left", "slow-forward#right"]
    assert len(rec.split()) == 8
    raw = np.asarray(json.loads(path.read_text())["fast-backward"])
    right = rec.split()[-1]
    np.testing.assert_allclose(right["velocity"], raw[:, 6] * 0.4878)
    np.testing.assert_allclose(right["voltage"], raw[:, 2])
    assert rec.metadata["si_per_unit"] == 1.0
    assert rec.metadata["rotation_si"] == pytest.approx(0.4878)
    assert len(file_tests(real_dir / "sysid" / "t581_spu_roller.json")) == 4  # not a drivetrain: one side


def test_real_logs_beat_the_teams_gains(real_scores):
    ratios = []
    for name, (ours, mine, team, _) in real_scores.items():
        speed, position = mine.ratio(team)
        assert speed <= 1.03, (name, ours, speed)
        assert position <= 1.03, (name, ours, position)
        ratios.append((speed, position))
    geo = np.exp(np.mean(np.log(ratios), axis=0))
    assert geo[0] <= 0.85, geo
    assert geo[1] <= 0.85, geo


def test_real_logs_uncertainty_from_residuals(real_scores):
    for name, (_, _, _, result) in real_scores.items():
        for gain in ("kS", "kV", "kA"):
            est = result[gain]
            assert math.isfinite(est.stderr), (name, gain)
            assert est.stderr > 0, (name, gain)
        assert result.details["uncertainty"].startswith("Newey–West")
        assert any("the residuals look like" in w for w in result.warnings), name
        assert set(result.details["by_direction"]) == {"forward", "backward"}
    # the shooter's TalonFX speed is a ~100 ms moving average: the residuals show the lag
    shooter = real_scores["stma7028_shooter_0309.json"][3]
    assert shooter.details["residual_diagnostics"]["lag_s"] >= 0.03
    assert any("lag (the logged motion trails" in w for w in shooter.warnings)


def test_motor_model_alone_is_kept_when_it_explains_the_data():
    """No velocity column (or residuals the noise explains): the motor-model fit stands, no score fit."""
    t = np.arange(400) * 0.01
    test = ScoreTest("fast-forward", t, np.full(t.size, 6.0), np.zeros(t.size), np.zeros(t.size))
    _speed, position = simulate_gains(0.2, 0.4, 0.04, test)
    from motorlab.recording import Recording

    counts = np.floor(position / (2 * math.pi / 560)) * (2 * math.pi / 560)
    rec = Recording(t, {"voltage": np.full(t.size, 6.0), "position": counts}, metadata={"cpr": 560})
    result = feedforward([rec])
    assert "open_loop_score" not in result.details


# --------------------------------------------------------------------------------------------------
# units and cpr
# --------------------------------------------------------------------------------------------------


def legacy_file(tmp_path, **extra):
    rows = [[0.01 * k, 12.0, 0.5, 6.0 * (k > 0), 6.0 * (k > 0), 0.02 * k * k, 0.02 * k * k, 0.04 * k, 0.04 * k, 0.0]
            for k in range(40)]
    data = {"slow-forward": rows, "fast-forward": rows, **extra}
    path = tmp_path / "legacy.json"
    path.write_text(json.dumps(data))
    return path


def test_frc_characterization_without_units(tmp_path):
    path = legacy_file(tmp_path)
    rec = read_frc_char_json(path)
    assert rec.metadata["units"] == "Feet"
    assert rec.metadata["units_assumed"]
    assert "no 'units' key" in rec.metadata["warnings"][0]
    assert "Feet" in rec.metadata["warnings"][0]
    np.testing.assert_allclose(rec.split()[0]["position"][-1], 0.02 * 39**2 * 0.3048)
    metres = read_frc_char_json(path, units="Meters")
    np.testing.assert_allclose(metres.split()[0]["position"][-1], 0.02 * 39**2)
    arm = read_frc_char_json(legacy_file(tmp_path, test="Arm"), side="left")
    assert arm.metadata["units"] == "Degrees"


def test_given_units_must_agree_with_the_file(real_dir):
    path = real_dir / "frc-characterization-drivetrain-linear.json"
    with pytest.raises(OptionError, match="contradicts"):
        read_frc_char_json(path, units="Feet")
    assert read_frc_char_json(path, units="meters").metadata["units"] == "Meters"
    with pytest.raises(OptionError, match="unknown"):
        read_frc_char_json(path, units="furlongs")


def test_sysid_file_without_units_is_still_refused(tmp_path):
    path = tmp_path / "s.json"
    path.write_text(json.dumps({"sysid": True, "slow-forward": [[0, 1, 0, 0], [0.01, 1, 0.1, 1]]}))
    with pytest.raises(LogFormatError, match="units"):
        read_sysid_json(path)
    assert read_sysid_json(path, units="Rotations").metadata["units"] == "Rotations"


def _cli_args(*argv: str) -> argparse.Namespace:
    parser = argparse.ArgumentParser()
    add_arguments(parser, "feedforward")
    return parser.parse_args(list(argv))


def test_cpr_for_a_json_file_is_its_quantum_or_refused(real_dir, tmp_path):
    roller = str(real_dir / "sysid" / "t581_spu_roller.json")
    # the roller logs rotations of a 10:1 TalonFX shaft: 2048 × 10 counts per logged rotation
    result = from_cli("feedforward", [roller], _cli_args("--cpr", "20480"))
    assert result.details["cpr"]["given"] == 20480
    with pytest.raises(OptionError, match="finer than half a count"):
        from_cli("feedforward", [roller], _cli_args("--cpr", "2048"))
    with pytest.raises(OptionError, match="unitsPerRotation"):
        from_cli("feedforward", [str(legacy_file(tmp_path))], _cli_args("--cpr", "100"))


@pytest.mark.parametrize("command", ["identify", "feedforward"])
def test_cpr_takes_fractional_counts(command):
    from motorlab.cli import build_parser

    args = build_parser().parse_args(["analyze", command, "log.txt", "--cpr", "103.6"])
    assert args.cpr == pytest.approx(103.6)


def test_residuals_are_in_row_order():
    t = np.arange(20) * 0.01
    a = ScoreTest("a", t, np.ones(t.size), np.zeros(t.size), np.ones(t.size))
    rs, rp = residuals((0.0, 1.0, 0.1), [a, a])
    assert rs.size == rp.size == 40


def test_motor_model_warning_says_what_the_residuals_look_like(real_dir):
    """Without the open-loop fit (an elevator here), the noise warning still names the effect."""
    rec = read_sysid_json(real_dir / "sysid" / "mbb_drivetrain.json", side="both")
    result = feedforward(rec.split(), mechanism="elevator")
    warning = next(w for w in result.warnings if w.startswith("the measured noise does not explain"))
    assert "the residuals look like: drift" in warning
    assert result.details["uncertainty"].startswith("Newey")


def test_never_behind_sysid_regression_on_the_real_flywheel(real_dir):
    """No published gains for this log: motorlab's gains are at least as good as SysId's OLS on both scores."""
    from motorlab.analyses.feedforward import sysid_ols

    rec = read_sysid_json(real_dir / "sysid-flywheel.json")
    result = feedforward(rec.split())
    tests = file_tests(real_dir / "sysid-flywheel.json")
    ols = sysid_ols(rec.split())
    ratio = score([result.value(k) for k in ("kS", "kV", "kA")], tests).ratio(
        score([ols["kS"], ols["kV"], ols["kA"]], tests))
    assert ratio[0] <= 1.01, ratio
    assert ratio[1] <= 1.01, ratio
    assert result.details["position_weight"] != 0.25  # the weight moved to keep the position


def test_identify_applies_cpr_to_a_json_file_too(real_dir):
    from motorlab.cli import analyze as identify

    parser = argparse.ArgumentParser()
    identify.add_arguments(parser, "identify")
    roller = str(real_dir / "sysid" / "t581_spu_roller.json")
    with pytest.raises(OptionError, match="finer than half a count"):
        identify.from_cli("identify", [roller], parser.parse_args(["--cpr", "2048"]))


def test_a_speed_already_past_zero_stops_at_once():
    """A derivative's nudge can start a stopping step with the speed just past zero: the stop is at once (no
    logarithm of a negative number), the distance zero, and a drive under the static friction leaves it at rest."""
    from motorlab.analyses.sysid_score import _stop_within_step

    for v, u in ((1e-9, 0.5), (-1e-9, -0.5), (0.0, 0.5), (0.01, 1e-9)):  # the speed already on u's side of zero
        speed, dist = _stop_within_step(v, u, 0.01, 0.05, 0.1, 0.2, 1.0, 0.2)
        assert (speed, dist) == (0.0, 0.0)
    speed, dist = _stop_within_step(0.01, -0.5, 0.01, 0.05, -0.1, 0.2, 1.0, 0.2)  # a real stop inside the step
    assert speed == 0.0
    assert 0.0 < dist < 0.01 * 0.01
