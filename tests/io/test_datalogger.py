"""FTC SDK Datalogger files (motorlab.io.datalogger): a team's real logs read in place, refused only for
what they lack; a complete file, written as the SDK's Datalogger writes it, analysed back to its truth."""

from __future__ import annotations

import csv
import math
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from motorlab.analyses.feedforward import feedforward
from motorlab.errors import LogFormatError, MotorlabError, OptionError
from motorlab.io import detect_format, read_any, read_datalogger
from motorlab.model import MotorParams, feedforward_from_params
from motorlab.model.simulate import VoltageDrive, simulate
from motorlab.proposal import propose

#: hawkbsilleee/FTC-Data-logging's logs (README there), read in place: ../shared/data/real/ftc-datalogger.
BATTERY = ("voltage_just_intake.txt", "voltage_just_drive.txt", "voltage_drive_and_intake.txt")
INTAKE = ("Velocity_Intake.txt", "Velocity_Drive.txt", "Just_Intake_Velocity.txt", "voltage_intake_velocity.txt")
#: goBILDA 5203 312 rpm (the team's README and analysis sheet): 537.6 counts per output revolution.
CPR = 537.6


@pytest.fixture
def logs(real_dir: Path) -> Path:
    return real_dir / "ftc-datalogger" / "logs"


def _rows(path: Path) -> list[list[str]]:
    with path.open(newline="") as handle:
        return list(csv.reader(handle))


def test_every_real_file_is_recognised(logs: Path) -> None:
    assert {detect_format(logs / name) for name in (*BATTERY, *INTAKE)} == {"datalogger"}


@pytest.mark.parametrize("name", BATTERY)
def test_real_battery_logs_read_as_they_are(logs: Path, name: str) -> None:
    """Timestamp [s], the INIT row kept aside, every RUNNING row's Battery [V]; nothing asked."""
    raw = _rows(logs / name)
    assert raw[0] == ["Timestamp", "OpModeStatus", "Loop Counter", "Battery"]
    running = [r for r in raw[1:] if r[1] == "RUNNING"]
    rec = read_datalogger(logs / name)
    assert rec.metadata["format"] == "datalogger"
    assert rec.metadata["status_rows"] == {"INIT": 1, "RUNNING": len(running)}
    assert rec.metadata["init"]["Battery"] == raw[1][3]  # the battery at rest, before START
    assert rec.metadata["loop_counter"]["missed"] == 0
    np.testing.assert_array_equal(rec.time, [float(r[0]) for r in running])
    np.testing.assert_array_equal(rec.signals["battery"], [float(r[3]) for r in running])
    assert set(rec.signals) == {"battery"}
    assert 9.0 < rec.signals["battery"].min() < rec.signals["battery"].max() < 13.0  # a 12 V battery under load
    assert float(rec.metadata["init"]["Battery"]) > np.median(rec.signals["battery"])  # it sags while driving
    assert rec.metadata["lacks"].keys() == {"voltage", "position", "current"}


@pytest.mark.parametrize("name", INTAKE)
def test_real_velocity_logs_ask_what_the_field_is_then_the_cpr(logs: Path, name: str) -> None:
    """'Intake' names no quantity: the column question; answered (velocity, the SDK's ticks/s), the cpr."""
    with pytest.raises(LogFormatError, match=r"column 'Intake' .*--column \"Intake=QUANTITY\""):
        read_datalogger(logs / name)
    with pytest.raises(OptionError, match="counts per revolution"):
        read_datalogger(logs / name, columns=["Intake=velocity"])
    rec = read_any(logs / name, columns=["Intake=velocity"], cpr=CPR)
    running = [r for r in _rows(logs / name)[1:] if r[1] == "RUNNING"]
    np.testing.assert_allclose(rec.signals["velocity"], [float(r[3]) * 2 * math.pi / CPR for r in running])
    # The intake at constant power from rest settles at a steady speed below its 312 rpm free speed (132 to
    # 212 rpm in these runs: the README's 70 % power gives ≈ 218 rpm unloaded), never above it.
    rpm = np.abs(rec.signals["velocity"][len(running) // 2:]) * 60 / (2 * math.pi)
    settled = float(np.median(rpm))
    assert 100.0 < settled < 312.0
    assert float(np.percentile(np.abs(rpm - settled), 95)) < 0.05 * settled  # steady (the last row: at STOP)


@pytest.mark.parametrize("name", [BATTERY[0], INTAKE[0]])
def test_the_analysis_refuses_a_real_file_only_for_what_it_lacks(logs: Path, name: str,
                                                                 capsys: pytest.CaptureFixture[str]) -> None:
    """One line, exit 2: no voltage in the file, and how to log it; never the old ':2: a second text line'."""
    from motorlab.cli import main

    extra = ["--column", "Intake=velocity", "--cpr", str(CPR)] if name in INTAKE else []
    assert main(["analyze", "feedforward", str(logs / name), *extra]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    assert f"{name}: this log has no voltage" in err
    assert "field named 'Voltage'" in err
    assert "second text line" not in err


def test_the_upload_proposes_a_real_file_and_asks_in_words(logs: Path) -> None:
    """The app's detection (motorlab.ui.worker): a battery log is proposed; an Intake log asks what Intake is,
    then (the column given) for the counts per revolution."""
    from motorlab.ui.worker import detect

    battery, intake = detect([str(logs / BATTERY[0]), str(logs / INTAKE[0])])
    assert "error" not in battery
    assert battery["format"] == "datalogger"
    assert battery["experiment"] == propose("datalogger", ["battery"]) == "feedforward"
    assert intake["column"] == "Intake"
    assert "velocity" in intake["quantities"]


# ---- a complete Datalogger file, as the SDK writes it, against known truth -------------------------------

MOTOR = MotorParams(K=0.35, R=2.5, L=7e-4, J=5e-3, b=2e-3, Tf=0.03)


def write_datalogger(path: Path, seed: int, *, ramp: bool) -> None:
    """A run of an OpMode built on the SDK's Datalogger sample, fields OpModeStatus, Loop Counter, Voltage,
    Position, Battery: ``TimestampField`` ("000.000" seconds), ``set(double)`` ("%.3f"), ``set(int)``; one INIT
    row (Loop Counter and the motor fields not yet set), then a row per 10 ms loop."""
    rng = np.random.default_rng(seed)
    q = 2 * math.pi / CPR
    duration = 6.0 if ramp else 2.0
    sim = simulate(MOTOR, VoltageDrive(lambda t: 1.5 * t if ramp else 6.0 * np.ones_like(t)), duration=duration,
                   dt=0.01)
    counts = np.floor((sim.position + rng.uniform(0.0, q)) / q).astype(int)
    volts = sim.voltage + 0.02 * rng.standard_normal(sim.time.size)
    battery = 12.6 - 0.05 * np.abs(volts) + 0.01 * rng.standard_normal(sim.time.size)
    lines = ["Timestamp,OpModeStatus,Loop Counter,Voltage,Position,Battery", "000.004,INIT,,,,12.640"]
    start = 1.327  # START pressed 1.3 s after INIT
    for i, t in enumerate(sim.time):
        lines.append(f"{start + t:07.3f},RUNNING,{i},{volts[i]:.3f},{counts[i]},{battery[i]:.3f}")
    path.write_text("\n".join(lines) + "\n")


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_complete_datalogger_run_gives_the_motors_gains(tmp_path: Path, seed: int) -> None:
    """Quasistatic ramp + dynamic step logged by a Datalogger OpMode: kS, kV, kA within 4 standard errors."""
    files = [tmp_path / "ramp.txt", tmp_path / "step.txt"]
    write_datalogger(files[0], seed, ramp=True)
    write_datalogger(files[1], seed + 100, ramp=False)
    runs = [read_datalogger(f, cpr=CPR) for f in files]
    assert detect_format(files[0]) == "datalogger"
    assert set(runs[0].signals) == {"voltage", "counts", "position", "battery"}
    assert runs[0].metadata["lacks"].keys() == {"current"}
    assert runs[0].time[0] == pytest.approx(1.327)
    result = feedforward(runs)
    truth = feedforward_from_params(MOTOR)
    for name in ("kS", "kV", "kA"):
        p = result.parameters[name]
        assert abs(p.value - truth[name]) < 4 * p.stderr, (name, p, truth[name])
        assert p.value == pytest.approx(truth[name], rel=0.05)


def test_a_decimal_comma_is_named_with_its_line(tmp_path: Path) -> None:
    """A robot in a French or German locale: set(double) writes "12,332", one field too many."""
    path = tmp_path / "datalog.txt"
    path.write_text("Timestamp,OpModeStatus,Loop Counter,Battery\n000.006,INIT,,12,332\n")
    with pytest.raises(LogFormatError, match=r"datalog.txt:2: expected 4 fields .* decimal comma"):
        read_datalogger(path)


def test_fields_with_tick_units_and_unset_rows(tmp_path: Path) -> None:
    """'Lift (ticks/s)' is ticks per second; rows before the OpMode first sets a field are left out, said."""
    path = tmp_path / "lift.txt"
    path.write_text("Timestamp,OpModeStatus,Loop Counter,Lift (ticks/s),Voltage,Yaw\n"
                    "000.010,INIT,,,,0.000\n001.000,RUNNING,0,,3.000,0.100\n"
                    "001.020,RUNNING,1,537.600,3.000,0.200\n001.040,RUNNING,2,1075.200,3.000,0.300\n")
    rec = read_datalogger(path, cpr=CPR)
    np.testing.assert_allclose(rec.signals["velocity"], [2 * math.pi, 4 * math.pi])
    np.testing.assert_array_equal(rec.lines, [4, 5])
    assert rec.metadata["unread"] == ["Yaw"]
    assert any("--column \"Yaw=QUANTITY\"" in w for w in rec.metadata["warnings"])
    assert any("1 row(s) with a field not yet set" in w for w in rec.metadata["warnings"])


FIELD = st.one_of(st.sampled_from(["", "RUNNING", "INIT", "12.332", "-0.000", "1e308", "nan", "²", "1_0", "7"]),
                  st.text(max_size=6))


@settings(max_examples=60, deadline=None, derandomize=True)
@given(rows=st.lists(st.lists(FIELD, min_size=4, max_size=6), max_size=8), newline=st.booleans())
def test_any_rows_under_a_datalogger_header_give_a_recording_or_one_line(rows: list[list[str]],
                                                                        newline: bool) -> None:
    text = "Timestamp,OpModeStatus,Loop Counter,Battery,Intake Velocity\n" + "\n".join(
        ",".join(r) for r in rows) + ("\n" if newline else "")
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "datalog.txt"
        path.write_text(text, encoding="utf-8")
        message = ""
        try:
            rec = read_datalogger(path, cpr=CPR)
        except MotorlabError as exc:
            message = str(exc)
        else:
            assert all(np.isfinite(v).all() for v in rec.signals.values())
            assert np.all(np.diff(rec.time) >= 0)
        assert "\n" not in message
