"""read_any / detect_format: every format is recognised from its extension and content."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

from motorlab.errors import LogFormatError, OptionError
from motorlab.io import detect_format, read_any, write_sysid_wpilog


@pytest.mark.parametrize(
    ("name", "fmt"),
    [
        ("ftc/power_log.txt", "ftc-log"),
        ("ftc/power_log_crlf.txt", "ftc-log"),
        ("ftc/no_header.txt", "ftc-log"),
        ("ftc/ticks.txt", "ftc-log"),
        ("csv/terminal.csv", "csv"),
        ("csv/lcr.csv", "csv"),
        ("csv/semicolon.csv", "csv"),
        ("csv/unknown_column.csv", "csv"),
        ("scope/edges_ms.csv", "scope-times"),
        ("scope/edges_s.csv", "scope-times"),
        ("scope/edges_plain.txt", "scope-times"),
        ("scope/rigol_ds1054z.csv", "scope-waveform"),
        ("scope/waveform_table.csv", "scope-waveform"),
    ],
)
def test_detect_format(data_dir, name, fmt):
    assert detect_format(data_dir / name) == fmt


@pytest.mark.parametrize(
    ("name", "fmt"),
    [("sysid-flywheel.json", "sysid-json"), ("frc-characterization-drivetrain-linear.json", "frc-char-json")],
)
def test_detect_format_of_real_logs(real_dir, name, fmt):
    assert detect_format(real_dir / name) == fmt


def test_read_any_reads_with_the_right_reader(data_dir, real_dir, tmp_path):
    assert read_any(data_dir / "ftc/power_log.txt", cpr=1120).has("position")
    assert read_any(data_dir / "csv/terminal.csv").metadata["format"] == "csv"
    assert read_any(data_dir / "scope/rigol_ds1054z.csv", channel="CH1").metadata["kind"] == "edges"
    assert read_any(real_dir / "frc-characterization-drivetrain-linear.json", side="right").metadata["side"] == (
        "right"
    )
    split = read_any([data_dir / "ftc/split/testFile.txt", data_dir / "ftc/split/testFile2.txt"])
    assert len(split) == 8
    t = np.arange(0, 0.2, 0.01)
    path = tmp_path / "run.log"  # no .wpilog extension: the magic bytes decide
    write_sysid_wpilog(path, t, np.ones(t.size), t, np.ones(t.size), ["dynamic-forward"] * t.size)
    assert detect_format(path) == "wpilog"
    assert list(read_any(path).segments) == ["dynamic-forward"]


def test_read_any_refuses_options_that_do_not_apply(data_dir, real_dir):
    with pytest.raises(OptionError, match="'cpr' does not apply to sysid-json"):
        read_any(real_dir / "sysid-flywheel.json", cpr=1120)
    with pytest.raises(OptionError, match="'threshold' does not apply to ftc-log"):
        read_any(data_dir / "ftc/power_log.txt", threshold=1.0)
    with pytest.raises(OptionError, match="split FTC log"):
        read_any([data_dir / "ftc/power_log.txt", data_dir / "csv/terminal.csv"])


def test_read_any_bad_files(data_dir, tmp_path):
    with pytest.raises(LogFormatError, match="empty"):
        read_any(data_dir / "ftc/empty.txt")
    with pytest.raises(LogFormatError, match="not a text file"):
        read_any(data_dir / "ftc/binary.txt")
    with pytest.raises(LogFormatError, match="no such file"):
        read_any(tmp_path / "nothing.csv")
    path = tmp_path / "fake.wpilog"
    shutil.copy(data_dir / "csv/lcr.csv", path)
    with pytest.raises(LogFormatError, match="not a WPILib data log"):
        read_any(path)


@pytest.mark.parametrize(("where", "expected"), [("first", "sysid-json"), ("middle", "sysid-json"),
                                                 ("last", "sysid-json"), (None, "frc-char-json")])
def test_a_large_json_file_is_told_apart_wherever_its_key_sits(tmp_path, where, expected):
    """The head and the last 64 KiB are searched first (SysId writes its flag after the tests), the whole
    file when neither holds the key: the answer does not depend on where it sits."""
    rows = [[0.01 * k, 1.0, 0.5, 0.25] for k in range(6000)]  # ~170 KB a test
    doc = {"slow-forward": rows, "fast-forward": rows}
    items = list(doc.items())
    if where is not None:
        at = {"first": 0, "middle": 1, "last": 2}[where]
        items.insert(at, ("sysid", True))
    path = tmp_path / "big.json"
    path.write_text(json.dumps(dict(items)))
    assert path.stat().st_size > 3 * 65536
    assert detect_format(path) == expected
