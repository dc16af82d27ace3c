"""SysId and frc-characterization JSON: the two real logs, and crafted files for the quirks."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from motorlab.errors import LogFormatError, OptionError
from motorlab.io.frc_json import SI_PER_UNIT, TESTS, UNITS, read_frc_char_json, read_sysid_json
from motorlab.io.text import unit_factor

FRC_CHAR = "frc-characterization-drivetrain-linear.json"
SYSID = "sysid-flywheel.json"
UNITS_PER_ROTATION = 0.4787787204070844  # frc-characterization file: metres per rotation


def moving_sign_agreement(part):
    voltage, velocity = part["voltage"], part["velocity"]
    moving = (velocity != 0) & (voltage != 0)
    return np.mean(np.sign(voltage[moving]) == np.sign(velocity[moving])), moving.sum()


def test_frc_char_segments_signs_and_units(real_dir):
    path = real_dir / FRC_CHAR
    rec = read_frc_char_json(path)
    assert list(rec.segments) == list(TESTS)
    assert rec.metadata["units"] == "Meters"
    assert rec.metadata["position_unit"] == "m"
    assert rec.metadata["side"] == "left"
    assert rec.metadata["other_keys"] == ["track-width"]
    assert rec.metadata["warnings"] == []
    for signal in rec.signals.values():
        assert np.all(np.isfinite(signal))
    raw = json.loads(path.read_text())
    for part in rec.split():
        name = part.metadata["segment"]
        rows = np.asarray(raw[name])
        # The stale first row (autospeed 0, voltage from the previous test) is dropped.
        assert rows[0, 2] == 0
        assert rows[0, 3] != 0
        rows = rows[1:]
        assert len(part) == len(rows)
        # Metres = rotations × unitsPerRotation.
        np.testing.assert_allclose(part["position"], rows[:, 5] * UNITS_PER_ROTATION)
        np.testing.assert_allclose(part["velocity"], rows[:, 7] * UNITS_PER_ROTATION)
        np.testing.assert_allclose(part["battery"], rows[:, 1])
        np.testing.assert_allclose(np.abs(part["voltage"]), rows[:, 3])
        # Logged magnitudes are signed to match the motion: backward tests move and push backward.
        agreement, moving = moving_sign_agreement(part)
        assert moving > 100
        assert agreement == 1.0
        direction = rec.metadata["segment_kinds"][name]["direction"]
        assert direction == (-1 if "backward" in name else 1)
        assert np.all(part["voltage"] * direction >= 0)
        assert np.all(np.diff(part.time) >= 0)
    assert rec.metadata["stale_rows_dropped"] == dict.fromkeys(TESTS, 1)
    # Errors would point into the file: the first kept sample of slow-forward is on line 15.
    assert rec.lines[0] == 15


def test_frc_char_right_side(real_dir):
    rec = read_frc_char_json(real_dir / FRC_CHAR, side="right")
    raw = json.loads((real_dir / FRC_CHAR).read_text())
    fast = rec.split()[2]
    np.testing.assert_allclose(fast["velocity"], np.asarray(raw["fast-forward"])[1:, 8] * UNITS_PER_ROTATION)
    with pytest.raises(OptionError, match="side"):
        read_frc_char_json(real_dir / FRC_CHAR, side="middle")


def test_sysid_segments_units_and_repeats(real_dir):
    path = real_dir / SYSID
    rec = read_sysid_json(path)
    assert list(rec.segments) == list(TESTS)
    assert rec.metadata["test"] == "Simple"
    assert rec.metadata["units"] == "Radians"
    assert rec.metadata["unitsPerRotation"] == pytest.approx(2 * math.pi)
    assert rec.metadata["position_unit"] == "rad"
    raw = json.loads(path.read_text())
    for part in rec.split():
        rows = np.asarray(raw[part.metadata["segment"]])
        assert len(part) == len(rows)  # rows are kept as recorded, repeats included
        np.testing.assert_allclose(part["position"], rows[:, 2] * 2 * math.pi)
        np.testing.assert_allclose(part["velocity"], rows[:, 3] * 2 * math.pi)
        np.testing.assert_allclose(part["voltage"], rows[:, 1])
        agreement, moving = moving_sign_agreement(part)
        assert moving > 100
        assert agreement == 1.0
        assert np.all(np.isfinite(part["velocity"]))
    # Status frames refresh position/velocity every few 5 ms samples: most rows repeat.
    assert 0.7 < rec.metadata["repeated_fraction"] < 0.85
    fast = rec.split()[2]
    assert np.max(fast["voltage"]) == 7.0


def test_each_reader_refuses_the_other_format(real_dir):
    with pytest.raises(LogFormatError, match="read_frc_char_json"):
        read_sysid_json(real_dir / FRC_CHAR)
    with pytest.raises(LogFormatError, match="read_sysid_json"):
        read_frc_char_json(real_dir / SYSID)


def write(tmp_path, data, name="log.json"):
    path = tmp_path / name
    path.write_text(json.dumps(data, indent=2))
    return path


def sysid_data(**changes):
    rows = [[0.0 + 0.005 * k, 0.1 * k, 0.01 * k, 0.5] for k in range(5)]
    data = {"sysid": True, "test": "Simple", "units": "Rotations", "unitsPerRotation": 1.0}
    data.update({"slow-forward": rows, "fast-forward": [[1.0 + r[0], *r[1:]] for r in rows]})
    data.update(changes)
    return data


def test_unit_factors_are_pints():
    """The written-out factors are pint's, to the last bit (the readers skip building pint's registry)."""
    assert set(SI_PER_UNIT) == set(UNITS)
    for name, (unit, si_unit) in UNITS.items():
        assert SI_PER_UNIT[name] == unit_factor(unit, si_unit), name


def test_rotations_are_converted_to_radians(tmp_path):
    rec = read_sysid_json(write(tmp_path, sysid_data()))
    assert list(rec.segments) == ["slow-forward", "fast-forward"]
    np.testing.assert_allclose(rec["velocity"], 0.5 * 2 * math.pi)
    rec = read_sysid_json(write(tmp_path, sysid_data(units="Inches", unitsPerRotation=2.0)))
    np.testing.assert_allclose(rec["velocity"], 0.5 * 2.0 * 0.0254)
    assert rec.metadata["velocity_unit"] == "m/s"


def test_sysid_drivetrain_rows_take_a_side(tmp_path):
    rows = [[0.005 * k, 1.0, 2.0, 0.1, 0.2, 1.5, 2.5, 0.0, 0.0] for k in range(4)]
    data = {"sysid": True, "test": "Drivetrain", "units": "Meters", "unitsPerRotation": 0.5, "slow-forward": rows}
    path = write(tmp_path, data)
    np.testing.assert_allclose(read_sysid_json(path)["velocity"], 0.75)
    right = read_sysid_json(path, side="right")
    np.testing.assert_allclose(right["velocity"], 1.25)
    np.testing.assert_allclose(right["voltage"], 2.0)
    assert right.metadata["side"] == "right"


@pytest.mark.parametrize(
    ("changes", "pattern"),
    [
        ({"units": "Furlongs"}, "units 'Furlongs' unknown"),
        ({"unitsPerRotation": 0}, "unitsPerRotation 0 is not a positive number"),
        ({"slow-forward": [[0, 1, 2]]}, "rows should have 4 or 9 columns, found 3"),
        ({"slow-forward": [[0, 1, 2, 3], [1, 1, 2]]}, r":\d+: test 'slow-forward' row 1: expected 4 values"),
        ({"slow-forward": [[0, 1, 2, 3], [1, "x", 2, 3]]}, r"row 1: 'x' is not a number"),
        ({"slow-forward": [[0, 1, 2, 3], [1, None, 2, 3]]}, r"row 1: None is not a number"),
        ({"slow-forward": [[0, 1, 2, 3], [-1, 1, 2, 3]]}, "time goes backwards"),
        ({"slow-forward": [], "fast-forward": []}, "no test data"),
    ],
)
def test_bad_sysid_files(tmp_path, changes, pattern):
    with pytest.raises(LogFormatError, match=pattern):
        read_sysid_json(write(tmp_path, sysid_data(**changes)))


def test_nan_row_names_its_line(tmp_path):
    path = tmp_path / "nan.json"
    text = json.dumps(sysid_data(), indent=2).replace("0.01,\n", "NaN,\n", 1)
    path.write_text(text)
    line = next(n for n, s in enumerate(text.splitlines(), start=1) if "NaN" in s)
    # The error names the line where the row opens ("[", then time, voltage, position).
    with pytest.raises(LogFormatError, match=rf"nan\.json:{line - 3}: test 'slow-forward' row 1: nan is not a finite"):
        read_sysid_json(path)


def test_broken_json_empty_and_binary(tmp_path):
    path = tmp_path / "broken.json"
    path.write_text('{\n  "sysid": true,\n  "slow-forward": [[0, 1, 2, 3],\n')
    with pytest.raises(LogFormatError, match=r"broken\.json:4: not valid JSON"):
        read_sysid_json(path)
    path.write_text("")
    with pytest.raises(LogFormatError, match="empty"):
        read_frc_char_json(path)
    path.write_bytes(b"\x89PNG\r\n\x1a\n\xff\xff")
    with pytest.raises(LogFormatError, match="not a text file"):
        read_frc_char_json(path)
    path.write_text("[1, 2]")
    with pytest.raises(LogFormatError, match="JSON object"):
        read_frc_char_json(path)


def test_frc_char_mechanism_rows_and_stale_first_row(tmp_path):
    # time, battery, autospeed, volts, pos, vel: a stale 4 V first row, then a ramp backward.
    rows = [[0.0, 12.0, 0.0, 4.0, 1.0, 0.0]] + [[0.005 * k, 12.0, -0.01 * k, 0.12 * k, 1.0 - 0.001 * k, -0.1 * k]
                                                for k in range(1, 6)]
    data = {"test": "Simple", "units": "Rotations", "unitsPerRotation": 1.0, "slow-backward": rows}
    rec = read_frc_char_json(write(tmp_path, data))
    assert len(rec) == 5
    np.testing.assert_allclose(rec["voltage"], -0.12 * np.arange(1, 6))
    np.testing.assert_allclose(rec["velocity"], -0.1 * np.arange(1, 6) * 2 * math.pi)
    assert rec.metadata["stale_rows_dropped"] == {"slow-backward": 1}
    assert rec.metadata["side"] is None


def test_a_large_file_is_parsed_in_two_processes_as_in_one(tmp_path, monkeypatch):
    """Above PARALLEL_BYTES the tests are parsed in two forked processes: the same arrays, lines and errors."""
    from motorlab import parallel
    from motorlab.io import frc_json

    rows = [[0.005 * k, 0.1 * k, 0.01 * k, 0.5 + 0.001 * k] for k in range(50)]
    data = sysid_data(**{"slow-backward": [[r[0], -r[1], -r[2], -r[3]] for r in rows],
                         "fast-backward": [[2.0 + r[0], -r[1], -r[2], -r[3]] for r in rows[:7]]})
    path = write(tmp_path, data)  # indented: each row over several lines
    one = read_sysid_json(path)
    forked = []
    monkeypatch.setattr(frc_json, "PARALLEL_BYTES", 0)
    monkeypatch.setattr(parallel, "can_fork", lambda: True)

    class Counted(parallel.Forked):
        def __init__(self, fn, item):
            forked.append(len(item))
            super().__init__(fn, item)

    monkeypatch.setattr(parallel, "Forked", Counted)
    two = read_sysid_json(path)
    assert len(forked) == 1  # one child, with the tests of about half the bytes
    assert list(two.segments) == list(one.segments)
    assert two.segments == one.segments
    np.testing.assert_array_equal(two.time, one.time)
    np.testing.assert_array_equal(two.lines, one.lines)
    for name in one.signals:
        np.testing.assert_array_equal(two[name], one[name])
    text = json.dumps(data, indent=2).replace("0.01,\n", "NaN,\n", 1)
    path.write_text(text)
    line = next(n for n, s in enumerate(text.splitlines(), start=1) if "NaN" in s) - 3
    with pytest.raises(LogFormatError, match=rf"log\.json:{line}: test 'slow-forward' row 1: nan is not a finite"):
        read_sysid_json(path)
    assert len(forked) == 2

    class Killed(parallel.Forked):
        def result(self):
            super().result()
            raise ChildProcessError("a forked child ended with code -9")

    monkeypatch.setattr(parallel, "Forked", Killed)
    path.write_text(json.dumps(data, indent=2))
    again = read_sysid_json(path)  # a child that dies: its half parsed here
    np.testing.assert_array_equal(again["velocity"], one["velocity"])
