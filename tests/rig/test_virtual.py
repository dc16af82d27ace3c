"""The virtual rig's experiments: files parse with the readers and match closed forms of the model."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from scipy import optimize

from motorlab.errors import InputError, OptionError, RigError
from motorlab.io.csv_table import read_csv
from motorlab.io.ftc import read_ftc_log
from motorlab.io.scope import read_scope_times, read_scope_waveform
from motorlab.model import feedforward_from_params
from motorlab.rig import VirtualRig, read_truth, steady_state
from motorlab.units import STANDARD_GRAVITY

MOTOR = "neverest40"


def _coast(t: np.ndarray, w0: float, J: float, b: float, Tf: float) -> tuple[np.ndarray, np.ndarray]:
    """Speed and angle travelled during a coast J·ω' = −b·ω − Tf from ω0 (valid until the stop)."""
    g, c = b / J, Tf / b
    speed = (w0 + c) * np.exp(-g * t) - c
    angle = (w0 + c) * (1 - np.exp(-g * t)) / g - c * t
    return speed, angle


@pytest.mark.parametrize(("unit_seed", "noise_seed"), [(0, 0), (2, 5)])
def test_spindown_split_log_matches_the_coast_closed_form(tmp_path: Path, unit_seed: int, noise_seed: int) -> None:
    rig = VirtualRig(MOTOR, unit_seed=unit_seed, noise_seed=noise_seed)
    run = rig.spindown(tmp_path / "testFile.txt", split=True)
    assert [p.name for p in run.paths] == ["testFile.txt", "testFile2.txt"]
    first = (tmp_path / "testFile.txt").read_text().splitlines()
    assert first[:2] == ["", ""]
    assert first[-1] == "0.0 0 0.0 0.0"
    rec = read_ftc_log(run.paths, cpr=rig.motor.cpr)
    assert rec.metadata["placeholder_rows_dropped"] == 10
    gaps = np.diff(rec.time)
    assert 0.1 <= gaps.min()
    assert gaps.mean() < 0.11

    ex = run.truth["expected"]
    p = rig.params
    assert ex["K"] == p.K
    assert ex["J"] == pytest.approx(p.J + rig.flywheel.reflected_inertia)
    assert ex["gamma"] == pytest.approx(ex["b"] / ex["J"])
    d_enc, d_bus, _ = rig.instruments.logger.read_delays
    t0, w0 = ex["coast_start"], ex["speed_at_coast_start"]
    rows = np.flatnonzero(rec.time > t0 + 0.05)
    assert rows.size > 500
    speed, _ = _coast(rec.time[rows] + d_bus - t0, w0, ex["J"], ex["b"], ex["Tf"])
    moving = speed > 0.5
    residual = rec["voltage"][rows][moving] - p.K * speed[moving]  # coast: V = K·ω
    noise = rig.instruments.ina219.bus_noise
    assert abs(residual.mean()) < 4 * noise / math.sqrt(residual.size)
    assert residual.std() == pytest.approx(noise, rel=0.15)
    # Counts follow the coast's angle (floor quantisation: within 2 counts).
    _, angle = _coast(rec.time[rows] + d_enc - t0, w0, ex["J"], ex["b"], ex["Tf"])
    counts = rec["counts"][rows]
    predicted = angle * rig.motor.cpr / (2 * math.pi)
    offset = np.median(counts - predicted)
    assert np.max(np.abs(counts - predicted - offset)[moving]) <= 2.0
    # The relay is open during the coast: the INA219 reads its offset and noise only.
    assert abs(rec["current"][rows].mean() - rig.instruments.ina219.current_offset) < 1e-3


def test_spinup_constant_current_closed_form(tmp_path: Path) -> None:
    rig = VirtualRig(MOTOR, unit_seed=1, noise_seed=3)
    run = rig.spinup(tmp_path / "spinup.txt", current=2.0, duration=20.0)
    rec = read_ftc_log(run.paths[0], cpr=rig.motor.cpr)
    ex = run.truth["expected"]
    assert ex["constant_current_throughout"]
    p = rig.params
    J, b, Tf = ex["J"], ex["b"], ex["Tf"]
    w_inf, g = (p.K * 2.0 - Tf) / b, b / J
    d_enc, d_bus, _d_cur = rig.instruments.logger.read_delays

    def angle(t: np.ndarray) -> np.ndarray:
        tau = np.clip(t - ex["relay_closed"], 0.0, None)
        return w_inf * (tau - (1 - np.exp(-g * tau)) / g)

    on = rec.time + d_enc < ex["relay_opened"]
    counts = rec["counts"][on]
    predicted = angle(rec.time[on] + d_enc) * rig.motor.cpr / (2 * math.pi)
    assert np.max(np.abs(counts - predicted)) <= 2.0
    powered = on & (rec.time > ex["relay_closed"] + 0.05)
    assert rec["current"][powered].mean() == pytest.approx(2.0 + rig.instruments.ina219.current_offset, abs=1e-3)
    tau = rec.time[powered] + d_bus - ex["relay_closed"]
    volts = p.R * 2.0 + p.K * w_inf * (1 - np.exp(-g * tau))
    assert abs((rec["voltage"][powered] - volts).mean()) < 0.02


def _free_angle(t: np.ndarray, theta0: float, w0: float, w_inf: float, tau: float) -> np.ndarray:
    return theta0 + w_inf * t + (w0 - w_inf) * tau * (1 - np.exp(-t / tau))


def test_free_spinup_edge_times_match_closed_form(tmp_path: Path) -> None:
    rig = VirtualRig(MOTOR, unit_seed=0, noise_seed=1)
    run = rig.free_spinup(tmp_path / "edges.csv", waveform=tmp_path / "wave.csv")
    rec = read_scope_times(run.paths[0])
    assert len(rec) == 20
    assert rec.metadata["channel"] == "B"
    p, st, ex = rig.params, run.truth["settings"], run.truth["expected"]
    w_inf, tau = (p.K * st["current"] - p.Tf) / p.b, p.J / p.b
    step = 2 * math.pi / rig.motor.cpr
    m0 = math.floor((st["initial_position"] / step - 2) / 4) + 1
    angles = (4 * (m0 + np.arange(21)) + 2) * step

    def time_of(a: float) -> float:
        return optimize.brentq(lambda t: _free_angle(np.array(t), st["initial_position"], st["hand_speed"],
                                                     w_inf, tau) - a, 0.0, 5.0)

    closed = np.array([time_of(a) for a in angles])
    assert np.allclose(ex["edge_times"], closed[1:] - closed[0], atol=2e-5)
    cursor = 12 * st["timebase"] / 600
    assert np.max(np.abs(rec.time - np.array(ex["edge_times"]))) <= 3 * cursor
    wave = read_scope_waveform(run.paths[1])
    n = min(len(wave), 20)
    assert np.allclose(wave.time[1:n] - wave.time[0], (closed[1:n] - closed[0]), atol=2 * cursor / 10)


@pytest.mark.parametrize("unit_seed", [0, 1])
def test_terminal_frequency_closed_form(tmp_path: Path, unit_seed: int) -> None:
    rig = VirtualRig("neverest20", unit_seed=unit_seed, noise_seed=2)
    run = rig.terminal(tmp_path / "terminal.csv", currents=[0.3, 0.35, 0.4])
    rec = read_csv(run.paths[0])
    p = rig.params
    for k, current in enumerate([0.3, 0.35, 0.4]):
        speed, i_true, mode = steady_state(p, current, voltage_limit=18.0)
        if mode == "CC":
            assert p.K * current == pytest.approx(p.b * speed + p.Tf)  # K·I = b·ω + Tf
        assert rec["frequency"][k] == pytest.approx(speed * rig.motor.cpr / (8 * math.pi), rel=1e-3)
        assert rec["current"][k] == pytest.approx(i_true, rel=3e-3, abs=1.5e-3)


def test_terminal_default_currents_stay_in_constant_current(tmp_path: Path) -> None:
    run = VirtualRig("neverest20", unit_seed=0).terminal(tmp_path / "t.csv")
    assert "CC" in run.truth["expected"]["modes"]
    assert all(0.1 < i < 1.0 for i in run.truth["settings"]["currents"])  # the seed's 0.25-0.4 A region


def test_lcr_readings(tmp_path: Path) -> None:
    rig = VirtualRig("neverest20", unit_seed=1, noise_seed=4)
    run = rig.lcr(tmp_path / "lcr.csv")
    rec = read_csv(run.paths[0])
    assert rec.metadata["frequency_Hz"] == 1000.0
    assert len(rec) == 10
    ex = run.truth["expected"]
    assert rec["inductance"].mean() == pytest.approx(ex["L_mean_positions"], rel=0.01)
    r_ac = 2 * math.pi * 1000 * rec["inductance"] / rec["quality_factor"]  # seed: R = 2πfL/Q
    assert r_ac.mean() == pytest.approx(ex["R_ac_mean_positions"], rel=0.03)
    assert rec["dc_resistance"].mean() == pytest.approx(ex["DCR_mean_positions"], abs=0.01)
    assert rec["dc_resistance"].min() >= rig.params.R * 0.95 - 0.02  # brush contact only adds


def test_torque_readings_give_k(tmp_path: Path) -> None:
    rig = VirtualRig(MOTOR, unit_seed=2, noise_seed=1)
    run = rig.torque(tmp_path / "torque.csv", arm=0.15)
    rec = read_csv(run.paths[0])
    assert rec.metadata["arm_m"] == 0.15
    torque = rec["mass"] * STANDARD_GRAVITY * 0.15
    slope, intercept = np.polyfit(rec["current"], torque, 1)
    assert slope == pytest.approx(rig.params.K, rel=0.02)  # τ = K·I
    assert abs(intercept) < 0.1 * rig.params.Tf + 0.02
    with pytest.raises(OptionError, match="negative"):
        rig.torque(tmp_path / "bad.csv", currents=[1.0, -1.0])


def test_amplifier_and_tachometer_gains(tmp_path: Path) -> None:
    rig = VirtualRig(MOTOR, unit_seed=0, noise_seed=6)
    amp = read_csv(rig.amplifier(tmp_path / "amp.csv").paths[0])
    slope, intercept = np.polyfit(amp["command"], amp["current"], 1)
    assert slope == pytest.approx(rig.instruments.amplifier.gain, rel=3e-3)
    assert intercept == pytest.approx(rig.instruments.amplifier.offset, abs=4e-3)
    tach_run = rig.tachometer(tmp_path / "tach.csv")
    tach = read_csv(tach_run.paths[0])
    moving = tach["speed"] > 1.0
    assert moving.sum() >= 3
    gain = np.polyfit(tach["speed"][moving], tach["tach_voltage"][moving], 1)[0]
    assert gain == pytest.approx(tach_run.truth["expected"]["Kt_tach"], rel=0.02)


def test_pulse_follows_the_current_source_closed_form(tmp_path: Path) -> None:
    rig = VirtualRig(MOTOR, unit_seed=0, noise_seed=2)
    run = rig.pulse(tmp_path / "pulse.csv")
    rec = read_csv(run.paths[0])
    ex = run.truth["expected"]
    assert not ex["amplifier_saturated"]
    assert ex["rests_between_pulses"]
    p = rig.params
    w_inf, tau = (p.K * ex["current_on"] - p.Tf) / p.b, p.J / p.b
    on = (rec.time > 0.002) & (rec.time < 0.12 * 2.0)  # the pulse: duty × period
    closed = w_inf * (1 - np.exp(-rec.time[on] / tau))
    residual = rec["velocity"][on] - closed
    assert abs(residual.mean()) < 0.01 * closed.mean() + 0.02
    assert residual.std() < 0.02 * closed.max() + 0.15  # tachometer ripple and noise
    assert rec["command"][on].mean() == pytest.approx(1.0, abs=0.01)
    assert np.all(np.abs(rec["velocity"][rec.time > 1.5]) < 0.5)  # at rest before the next pulse


def test_transient_steady_current_and_speed(tmp_path: Path) -> None:
    rig = VirtualRig(MOTOR, unit_seed=1, noise_seed=0)
    run = rig.transient(tmp_path / "transient.csv", profile="steps", rate=1000.0, duration=3.5)
    rec = read_csv(run.paths[0], cpr=rig.motor.cpr)
    assert len(rec) == 3501
    p = rig.params
    # Third segment (1.0-1.5 s) holds +12 V: after 20 time constants the motor runs at free speed.
    window = (rec.time > 1.35) & (rec.time < 1.49)
    assert rec["voltage"][window].mean() == pytest.approx(12.0, abs=0.01)
    assert rec["current"][window].mean() == pytest.approx(p.free_current(12.0), abs=3e-3)
    slope = np.polyfit(rec.time[window], rec["counts"][window], 1)[0]
    assert slope == pytest.approx(p.free_speed(12.0) * rig.motor.cpr / (2 * math.pi), rel=5e-3)
    no_current = rig.transient(tmp_path / "nc.csv", profile="ramps", include_current=False, rate=500.0, duration=1.0)
    assert "current" not in read_csv(no_current.paths[0])


def test_sysid_json_layout_and_dynamic_step(tmp_path: Path) -> None:
    rig = VirtualRig("neverest20", unit_seed=0, noise_seed=0)
    run = rig.sysid(tmp_path / "sysid.json", quasistatic_duration=8.0, dynamic_duration=6.0)
    doc = json.loads(run.paths[0].read_text())
    assert doc["sysid"] is True
    assert doc["test"] == "Simple"
    assert doc["units"] == "Rotations"
    assert doc["unitsPerRotation"] == 1.0
    for key in ("slow-forward", "slow-backward", "fast-forward", "fast-backward"):
        rows = np.array(doc[key])
        assert rows.shape[1] == 4
        assert np.all(np.diff(rows[:, 0]) > 0)
    slow = np.array(doc["slow-forward"])
    ramp = 0.25 * np.clip(slow[:, 0] - slow[0, 0] - 0.01, 0, None)
    assert np.std(slow[1:, 1] - ramp[1:]) == pytest.approx(0.02, rel=0.2)  # voltage noise
    backward = np.array(doc["slow-backward"])
    assert backward[-1, 2] < backward[0, 2]
    assert np.all(backward[:, 3] <= 0)
    loaded = rig.flywheel.attach(rig.params)
    ex = run.truth["expected"]
    assert ex["kA"] == pytest.approx(feedforward_from_params(loaded)["kA"])
    # Dynamic step: L ≪ τm, so ω(t) = ω∞·(1 − e^{−t/τm}); velocity is a 50 ms window average.
    fast = np.array(doc["fast-forward"])
    t = fast[-1, 0] - fast[0, 0] - 0.01
    frame = math.floor((t + 0.01) / 0.02) * 0.02 - 0.01
    tm, w_inf = loaded.mechanical_time_constant, loaded.free_speed(7.0)
    mean_w = w_inf * (1 - tm / 0.05 * (np.exp(-(frame - 0.05) / tm) - np.exp(-frame / tm)))
    assert fast[-1, 3] * 2 * math.pi == pytest.approx(mean_w, abs=2 * 2 * math.pi / (rig.motor.cpr * 0.05))


def test_truth_json_holds_every_run_of_the_folder(tmp_path: Path) -> None:
    a = VirtualRig(MOTOR, unit_seed=0)
    b = VirtualRig(MOTOR, unit_seed=1)
    run_a = a.lcr(tmp_path / "lcr_A.csv")
    b.lcr(tmp_path / "lcr_B.csv")
    b.spindown(tmp_path / "spindown_B.txt", on_time=5.0, coast_time=5.0)
    doc = json.loads((tmp_path / "truth.json").read_text())
    assert set(doc["runs"]) == {"lcr_A.csv", "lcr_B.csv", "spindown_B.txt"}
    assert run_a.truth_path == tmp_path / "truth.json"
    truth_a = read_truth(tmp_path / "lcr_A.csv")
    assert truth_a["unit"] == "A"
    assert truth_a["params"] == a.params.to_dict()
    truth_b = read_truth(tmp_path / "spindown_B.txt")
    assert truth_b["unit"] == "B"
    assert truth_b["unit_seed"] == 1
    assert truth_b["totals"]["J"] == pytest.approx(b.params.J + b.flywheel.reflected_inertia)
    assert truth_b["instruments"]["ina219"]["bus_lsb"] == 4e-3
    assert truth_b["settings"]["voltage"] == 12.0
    assert truth_b["noise_seed"] == 0
    with pytest.raises(InputError):
        read_truth(tmp_path / "missing.csv")
    (tmp_path / "other").mkdir()
    (tmp_path / "other" / "truth.json").write_text("{}")
    with pytest.raises(RigError):
        a.lcr(tmp_path / "other" / "lcr.csv")


def test_runs_are_deterministic_in_the_seeds(tmp_path: Path) -> None:
    def files(unit: int, noise: int, folder: str) -> tuple[bytes, bytes]:
        out = tmp_path / folder
        out.mkdir()
        rig = VirtualRig(MOTOR, unit_seed=unit, noise_seed=noise)
        s = rig.spindown(out / "s.txt", on_time=5.0, coast_time=5.0).paths[0].read_bytes()
        return s, rig.lcr(out / "l.csv").paths[0].read_bytes()

    first, again = files(0, 0, "a"), files(0, 0, "b")
    assert first == again
    other_noise = files(0, 1, "c")
    assert other_noise[0] != first[0]
    assert other_noise[1] != first[1]
    assert VirtualRig(MOTOR, unit_seed=0, noise_seed=1).params == VirtualRig(MOTOR, unit_seed=0).params


def test_refusals(tmp_path: Path) -> None:
    rig = VirtualRig(MOTOR)
    with pytest.raises(RigError, match="INA219"):
        rig.spindown(tmp_path / "s.txt", voltage=18.0)
    with pytest.raises(RigError, match="INA219"):
        rig.spinup(tmp_path / "s.txt", voltage=16.5)
    assert not (tmp_path / "s.txt").exists()
    with pytest.raises(OptionError, match="negative"):
        rig.spinup(tmp_path / "s.txt", current=-1.0)
    with pytest.raises(OptionError):
        rig.run("nonsense", tmp_path / "x.csv")
    with pytest.raises(OptionError):
        VirtualRig("not-a-motor")
    with pytest.raises(RigError, match="stopped"):
        rig.free_spinup(tmp_path / "f.csv", current=0.05, hand_speed=0.0)


@pytest.mark.parametrize(
    ("experiment", "settings", "mention"),
    [
        ("spindown", {"on_time": 1e9}, "simulator steps"),
        ("pulse", {"sample_interval": 1e-12}, "--sample-interval"),
        ("transient", {"rate": 1e12}, "simulator steps"),
        ("free-spinup", {"edges": 10**8}, "--edges"),
        ("lcr", {"positions": 10**8}, "--positions"),
        ("terminal", {"currents": [0.3] * 200_000}, "current settings"),
    ],
)
def test_absurdly_large_runs_are_refused_before_allocating(tmp_path: Path, experiment, settings, mention) -> None:
    """Settings that asked for terabytes (or hung) fail at once with an OptionError; nothing is written."""
    with pytest.raises(OptionError, match=mention):
        VirtualRig(MOTOR).run(experiment, tmp_path / "out.csv", **settings)
    assert list(tmp_path.iterdir()) == []
