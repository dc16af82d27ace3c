"""Headed CSV tables: the column table, unit conversion, metadata lines and bad input."""

from __future__ import annotations

import math

import numpy as np
import pytest

from motorlab.errors import LogFormatError, OptionError
from motorlab.io.csv_table import COLUMNS, read_csv, write_csv
from motorlab.recording import SIGNALS


def test_metadata_units_extras_and_cpr_from_comment(data_dir):
    rec = read_csv(data_dir / "csv/terminal.csv")
    assert rec.metadata["experiment"] == "terminal"
    assert rec.metadata["motor"] == "NeveRest 40"
    assert rec.metadata["frequency_Hz"] == 1000.0
    assert rec.metadata["cpr"] == 1120.0
    np.testing.assert_allclose(rec.time, [0, 0.001, 0.002, 0.003, 0.004])
    np.testing.assert_allclose(rec["current"], [0.0, 1.5205, 1.488, 1.4502, 1.4119])
    np.testing.assert_array_equal(rec["counts"], [0, 0, 1, 3, 6])
    np.testing.assert_allclose(rec["position"], np.array([0, 0, 1, 3, 6]) * 2 * math.pi / 1120)
    assert rec.metadata["units"]["current"] == "mA"
    assert "x_note" in rec.metadata["columns"]
    assert set(rec.signals) == {"voltage", "current", "counts", "position"}
    assert rec.lines.tolist() == [6, 7, 8, 9, 10]


def test_cpr_argument_overrides_metadata(data_dir):
    rec = read_csv(data_dir / "csv/terminal.csv", cpr=560)
    np.testing.assert_allclose(rec["position"][-1], 6 * 2 * math.pi / 560)


def test_table_without_time_uses_the_row_index(data_dir):
    rec = read_csv(data_dir / "csv/lcr.csv")
    np.testing.assert_array_equal(rec.time, [0, 1, 2])
    assert rec.metadata["time"] == "row index"
    np.testing.assert_allclose(rec["inductance"], [2.31e-3, 2.18e-3, 1.95e-3])
    np.testing.assert_allclose(rec["quality_factor"], [1.52, 8.9, 41.0])
    np.testing.assert_allclose(rec["frequency"], [100, 1000, 10000])


def test_semicolon_and_whitespace_delimiters(data_dir):
    rec = read_csv(data_dir / "csv/semicolon.csv")
    np.testing.assert_allclose(rec.time, [0, 0.01, 0.02])
    np.testing.assert_allclose(rec["current"], [0.10, 0.12, 0.11])
    rec = read_csv(data_dir / "csv/whitespace.csv")
    np.testing.assert_allclose(rec["speed"], np.array([0, 60, 120]) * 2 * math.pi / 60)


def test_every_unit_is_converted_to_si(data_dir):
    rec = read_csv(data_dir / "csv/units.csv")
    expected = {
        "position": 2 * math.pi,
        "velocity": 2 * math.pi,
        "mass": 0.5,
        "torque": 0.5,
        "inductance": 100e-6,
        "speed": 2.0,
        "tach_voltage": 1.5,
        "battery": 12.5,
        "command": 3.0,
    }
    for name, value in expected.items():
        assert rec[name][0] == pytest.approx(value), name


def test_column_table_targets_canonical_signals():
    for name, (signal, _) in COLUMNS.items():
        assert signal == "time" or signal in SIGNALS, name


@pytest.mark.parametrize(
    ("name", "pattern"),
    [
        ("unknown_column.csv", r"unknown_column\.csv:1: column 'humidity_pct' names no quantity motorlab knows: "
                                  r'map it with --column "humidity_pct=QUANTITY"'),
        ("nan.csv", r"nan\.csv:3: voltage_V: 'nan' is not a finite number"),
        ("missing_value.csv", r"missing_value\.csv:3: expected 3 columns"),
        ("no_header.csv", r"no_header\.csv:1: no header line"),
        ("duplicate_signal.csv", r"both give current"),
    ],
)
def test_bad_tables(data_dir, name, pattern):
    with pytest.raises(LogFormatError, match=pattern):
        read_csv(data_dir / "csv" / name)


def test_truncated_last_line_is_dropped(data_dir):
    rec = read_csv(data_dir / "csv/truncated.csv")
    assert len(rec) == 2
    assert rec.metadata["warnings"]


def test_empty_binary_and_comment_only_files(tmp_path):
    empty = tmp_path / "empty.csv"
    empty.write_text("")
    with pytest.raises(LogFormatError, match="empty"):
        read_csv(empty)
    binary = tmp_path / "scope.csv"
    binary.write_bytes(b"time_s,voltage_V\n\xff\xfe\x00\x01")
    with pytest.raises(LogFormatError, match="not a text file"):
        read_csv(binary)
    comments = tmp_path / "comments.csv"
    comments.write_text("# cpr: 10\n")
    with pytest.raises(LogFormatError, match="only comments"):
        read_csv(comments)
    header_only = tmp_path / "header.csv"
    header_only.write_text("time_s,voltage_V\n")
    with pytest.raises(LogFormatError, match=r"header\.csv:1: no data rows"):
        read_csv(header_only)


def test_time_going_backwards_and_bad_cpr(tmp_path):
    path = tmp_path / "t.csv"
    path.write_text("time_s,voltage_V\n0,1\n0.2,1\n0.1,1\n")
    with pytest.raises(LogFormatError, match=r"t\.csv:4: time goes backwards"):
        read_csv(path)
    path.write_text("# cpr: -3\ntime_s,position_counts\n0,1\n")
    with pytest.raises(LogFormatError, match="cpr"):
        read_csv(path)


@pytest.mark.parametrize("seed", [0, 1])
def test_write_read_round_trip(tmp_path, seed):
    rng = np.random.default_rng(seed)
    n = 50
    columns = {
        "time_ms": np.sort(rng.uniform(0, 1000, n)),
        "voltage_V": rng.normal(6, 1, n),
        "current_mA": rng.normal(500, 100, n),
        "position_counts": np.cumsum(rng.integers(0, 5, n)),
        "velocity_rpm": rng.normal(100, 10, n),
        "x_trial": np.arange(n),
    }
    path = tmp_path / "table.csv"
    write_csv(path, columns, metadata={"cpr": 288, "experiment": "spinup"})
    rec = read_csv(path)
    assert rec.metadata["cpr"] == 288
    assert rec.metadata["experiment"] == "spinup"
    np.testing.assert_allclose(rec.time, columns["time_ms"] * 1e-3, rtol=1e-12)
    np.testing.assert_allclose(rec["voltage"], columns["voltage_V"], rtol=1e-12)
    np.testing.assert_allclose(rec["current"], columns["current_mA"] * 1e-3, rtol=1e-12)
    np.testing.assert_allclose(rec["velocity"], columns["velocity_rpm"] * math.pi / 30, rtol=1e-12)
    np.testing.assert_allclose(rec["position"], columns["position_counts"] * 2 * math.pi / 288, rtol=1e-12)


def test_writer_refuses_what_would_not_read_back(tmp_path):
    path = tmp_path / "bad.csv"
    with pytest.raises(OptionError, match="unknown column"):
        write_csv(path, {"temperature_C": [1.0]})
    with pytest.raises(OptionError, match="NaN"):
        write_csv(path, {"time_s": [0.0, np.nan]})
    with pytest.raises(OptionError, match="values"):
        write_csv(path, {"time_s": [0.0, 1.0], "voltage_V": [1.0]})
    with pytest.raises(OptionError, match="metadata"):
        write_csv(path, {"time_s": [0.0]}, metadata={"a:b": 1})
    assert not path.exists()
