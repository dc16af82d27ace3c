"""FTC OpMode logs: the quirks of seed 1's files, and the writer/reader round trip."""

from __future__ import annotations

import math
import shutil
from pathlib import Path

import numpy as np
import pytest

from motorlab.errors import LogFormatError, OptionError
from motorlab.io import detect_format
from motorlab.io.ftc import read_ftc_log, write_ftc_log

# The eight rows of tests/data/ftc/power_log.txt (time_ms, counts, V, A).
ROWS = np.array(
    [
        [0.0, 0, 12.004, 0.0],
        [30.512, 0, 11.968, 2.104],
        [61.027, 3, 11.952, 1.988],
        [91.540, 11, 11.960, 1.870],
        [122.049, 24, 11.964, 1.761],
        [152.561, 41, 11.968, 1.650],
        [183.070, 62, 11.972, 1.548],
        [213.583, 86, 11.976, 1.452],
    ]
)


def check_rows(rec, rows=ROWS):
    np.testing.assert_allclose(rec.time, rows[:, 0] * 1e-3)
    np.testing.assert_array_equal(rec["counts"], rows[:, 1])
    np.testing.assert_allclose(rec["voltage"], rows[:, 2])
    np.testing.assert_allclose(rec["current"], rows[:, 3])


def test_blank_lines_header_and_placeholders(data_dir):
    rec = read_ftc_log(data_dir / "ftc/power_log.txt")
    check_rows(rec)
    assert rec.metadata["placeholder_rows_dropped"] == 5
    assert rec.metadata["header"].startswith("time_ms")
    assert rec.metadata["variant"] == "power"
    assert rec.metadata["format"] == "ftc-log"
    # 3 blank lines and the header come first: the first sample is on line 5.
    assert rec.lines.tolist() == list(range(5, 13))
    assert "position" not in rec


def test_crlf_and_no_header_give_the_same_rows(data_dir):
    check_rows(read_ftc_log(data_dir / "ftc/power_log_crlf.txt"))
    rec = read_ftc_log(str(data_dir / "ftc/no_header.txt"))
    check_rows(rec)
    assert rec.metadata["header"] is None


def test_cpr_adds_position_in_radians(data_dir):
    rec = read_ftc_log(data_dir / "ftc/power_log.txt", cpr=1120)
    np.testing.assert_allclose(rec["position"], ROWS[:, 1] * 2 * math.pi / 1120)
    assert rec.metadata["cpr"] == 1120


def test_split_run_is_concatenated_in_order(data_dir):
    files = [data_dir / "ftc/split/testFile.txt", data_dir / "ftc/split/testFile2.txt"]
    rec = read_ftc_log(files)
    assert len(rec) == 8
    np.testing.assert_allclose(rec.time[:5], ROWS[:5, 0] * 1e-3)
    np.testing.assert_allclose(rec.time[5:], [0.244095, 0.274604, 0.305118])
    np.testing.assert_array_equal(rec["counts"][5:], [112, 135, 154])
    assert np.all(np.diff(rec.time) > 0)
    assert rec.source == " + ".join(str(f) for f in files)
    assert rec.metadata["file_starts"] == [0, 5]
    assert rec.metadata["placeholder_rows_dropped"] == 8
    # Lines refer to each file: the second file's first sample is on its line 3.
    assert rec.lines[5] == 3


def test_split_run_in_the_wrong_order_names_the_file_and_line(data_dir):
    files = [data_dir / "ftc/split/testFile2.txt", data_dir / "ftc/split/testFile.txt"]
    with pytest.raises(LogFormatError, match=r"testFile\.txt:4: time goes backwards across the join"):
        read_ftc_log(files)


def test_restarted_clock_is_an_error_unless_offset_is_asked(data_dir):
    files = [data_dir / "ftc/split/testFile.txt", data_dir / "ftc/split_restart/testFile2.txt"]
    with pytest.raises(LogFormatError, match="time_restart='offset'"):
        read_ftc_log(files)
    rec = read_ftc_log(files, time_restart="offset")
    step = np.median(np.diff(ROWS[:5, 0])) * 1e-3
    assert rec.time[5] == pytest.approx(ROWS[4, 0] * 1e-3 + step)
    np.testing.assert_allclose(np.diff(rec.time[5:]), [0.030509, 0.030514], atol=1e-9)
    with pytest.raises(OptionError):
        read_ftc_log(files, time_restart="guess")


def test_milliamp_current_from_header_or_option(data_dir):
    rec = read_ftc_log(data_dir / "ftc/current_mA.txt")
    check_rows(rec)
    assert rec.metadata["current_unit"] == "mA"
    # An explicit unit wins over the header.
    rec = read_ftc_log(data_dir / "ftc/power_log.txt", current_unit="mA")
    np.testing.assert_allclose(rec["current"], ROWS[:, 3] * 1e-3)
    with pytest.raises(OptionError, match="current"):
        read_ftc_log(data_dir / "ftc/power_log.txt", current_unit="V")


def test_zero_rows_in_the_middle_are_data(data_dir):
    rec = read_ftc_log(data_dir / "ftc/zero_row_middle.txt")
    assert len(rec) == 4
    np.testing.assert_array_equal(rec["voltage"], [0.0, 11.968, 0.0, 11.960])
    assert rec.metadata["placeholder_rows_dropped"] == 2


def test_tick_log_two_columns(data_dir):
    rec = read_ftc_log(data_dir / "ftc/ticks.txt", cpr=288)
    assert rec.metadata["variant"] == "ticks"
    assert len(rec) == 12
    np.testing.assert_array_equal(rec["counts"], np.arange(12))
    np.testing.assert_allclose(rec["position"], np.arange(12) * 2 * math.pi / 288)
    assert not rec.has("voltage")
    assert not rec.has("current")
    assert rec.metadata["placeholder_rows_dropped"] == 4


def test_truncated_last_line_is_dropped_with_a_warning(data_dir):
    rec = read_ftc_log(data_dir / "ftc/truncated.txt")
    check_rows(rec)
    assert any("truncated" in w for w in rec.metadata["warnings"])


@pytest.mark.parametrize(
    ("name", "pattern"),
    [
        ("nan_row.txt", r"nan_row\.txt:5: bus_voltage_V: 'NaN' is not a finite number"),
        ("missing_column.txt", r"missing_column\.txt:4: expected 4 columns, found 3"),
        ("non_numeric.txt", r"non_numeric\.txt:7: bus_voltage_V: '11\.96B' is not a number"),
        ("time_backwards.txt", r"time_backwards\.txt:7: time goes backwards"),
        ("empty.txt", r"empty\.txt: the file is empty"),
        ("blank_only.txt", r"blank_only\.txt: the file is empty"),
        ("only_zeros.txt", r"only_zeros\.txt:2: only placeholder rows of zeros"),
        ("binary.txt", r"binary\.txt: not a text file"),
        ("missing.txt", r"missing\.txt: no such file"),
    ],
)
def test_bad_files_raise_one_line_naming_file_and_line(data_dir, name, pattern):
    with pytest.raises(LogFormatError, match=pattern) as info:
        read_ftc_log(data_dir / "ftc" / name)
    assert "\n" not in str(info.value)


def test_wrong_column_count_and_bad_cpr(tmp_path, data_dir):
    path = tmp_path / "three.txt"
    path.write_text("1 2 3\n4 5 6\n")
    with pytest.raises(LogFormatError, match=r"three\.txt:1: expected 4 columns .* or 2"):
        read_ftc_log(path)
    for cpr in (0, -5, float("nan"), "abc"):
        with pytest.raises(OptionError, match="cpr"):
            read_ftc_log(data_dir / "ftc/power_log.txt", cpr=cpr)
    with pytest.raises(OptionError):
        read_ftc_log([])


def test_input_is_never_modified(tmp_path, data_dir):
    path = tmp_path / "log.txt"
    shutil.copy(data_dir / "ftc/power_log_crlf.txt", path)
    before = path.read_bytes()
    read_ftc_log(path, cpr=560)
    assert path.read_bytes() == before


@pytest.mark.parametrize("seed", [0, 1])
def test_writer_round_trip_with_all_quirks(tmp_path: Path, seed):
    rng = np.random.default_rng(seed)
    n = 200
    time = np.cumsum(rng.uniform(0.025, 0.035, n))
    counts = np.cumsum(rng.integers(0, 30, n))
    voltage = 12 + rng.normal(0, 0.05, n)
    current = rng.uniform(-0.5, 3.0, n)
    first, second = tmp_path / "testFile.txt", tmp_path / "testFile2.txt"
    write_ftc_log(first, time[:120], counts[:120], voltage[:120], current[:120],
                  placeholder_rows=40, crlf=True, blank_lines=3)
    write_ftc_log(second, time[120:], counts[120:], voltage[120:], current[120:], current_unit="mA",
                  placeholder_rows=10, blank_lines=2)
    assert first.read_bytes().startswith(b"\r\n\r\n\r\ntime_ms")
    rec = read_ftc_log([first, second], cpr=1120)
    assert len(rec) == n
    np.testing.assert_allclose(rec.time, time, atol=1e-9)
    np.testing.assert_array_equal(rec["counts"], counts)
    np.testing.assert_allclose(rec["voltage"], voltage, rtol=1e-5)
    np.testing.assert_allclose(rec["current"], current, rtol=1e-5, atol=1e-9)
    np.testing.assert_allclose(rec["position"], counts * 2 * np.pi / 1120)
    assert rec.metadata["placeholder_rows_dropped"] == 50


def test_writer_tick_variant_and_bad_arguments(tmp_path):
    path = tmp_path / "ticks.txt"
    write_ftc_log(path, [0.0, 0.01, 0.015], [0, 1, 2], header=False, placeholder_rows=2)
    assert path.read_text().splitlines() == ["0.000000 0", "10.000000 1", "15.000000 2", "0.0 0", "0.0 0"]
    rec = read_ftc_log(path)
    assert rec.metadata["variant"] == "ticks"
    assert len(rec) == 3
    with pytest.raises(OptionError, match="both"):
        write_ftc_log(path, [0.0], [0], voltage=[1.0])
    with pytest.raises(OptionError, match="NaN"):
        write_ftc_log(path, [0.0, np.nan], [0, 1])
    with pytest.raises(OptionError, match="values"):
        write_ftc_log(path, [0.0, 1.0], [0])


def test_a_time_column_in_seconds_is_refused(tmp_path):
    """An OpMode logging getRuntime() (seconds) would make every rate 1000× wrong: refused, not guessed."""
    from motorlab.errors import LogFormatError
    from motorlab.io import read_ftc_log

    path = tmp_path / "seconds.txt"
    path.write_text("".join(f"{0.1 * k:.3f} {10 * k} 12.0 0.5\n" for k in range(50)))
    with pytest.raises(LogFormatError, match="looks like seconds"):
        read_ftc_log(path)
    assert path.read_text().startswith("0.000 0 12.0 0.5")


def test_header_fields_name_motor_cpr_and_ratio(tmp_path):
    """motorlab's OpModes write '# key: value' lines; '# cpr:' gives position when no cpr is passed."""
    path = tmp_path / "motorlab-spindown.txt"
    fields = {"experiment": "spindown", "motor": "neverest40", "cpr": 1120, "gear_ratio": 40}
    write_ftc_log(path, np.array([0.0, 0.005, 0.01]), np.array([0, 1120, 2240]), np.array([12.0, 11.9, 11.8]),
                  np.array([1.0, 1.0, 0.9]), fields=fields)
    assert path.read_text().splitlines()[:2] == ["# experiment: spindown", "# motor: neverest40"]
    rec = read_ftc_log(path)
    assert rec.metadata["motor"] == "neverest40"
    assert rec.metadata["gear_ratio"] == 40.0
    assert rec.metadata["cpr"] == 1120.0
    assert rec.metadata["format"] == "ftc-log"
    np.testing.assert_allclose(rec.signals["position"], [0.0, 2 * np.pi, 4 * np.pi])
    # An explicit cpr wins over the file's.
    assert read_ftc_log(path, cpr=560).metadata["cpr"] == 560.0
    assert detect_format(path) == "ftc-log"


def test_header_with_an_impossible_cpr_names_the_file(tmp_path):
    path = tmp_path / "bad.txt"
    path.write_text("# cpr: -4\ntime_ms encoder_counts\n0 0\n5 3\n")
    with pytest.raises(LogFormatError, match=r"bad\.txt.*# cpr"):
        read_ftc_log(path)
    with pytest.raises(OptionError):
        write_ftc_log(tmp_path / "x.txt", np.zeros(2), np.zeros(2), fields={"bad key": 1})
