"""Headers in words with units (dynamometer exports) and the ``--column`` mapping (issue 23)."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from motorlab import cli
from motorlab.errors import LogFormatError, OptionError, SessionError
from motorlab.io import detect_format, read_any, read_csv
from motorlab.io.headers import column_mapping, normalise_unit, parse_column_mapping, worded_column


@pytest.mark.parametrize(
    ("header", "expected"),
    [
        ("Time", ("time", None)),
        ("Time (s)", ("time", "s")),
        ("Amps", ("current", "A")),
        ("Current (A)", ("current", "A")),
        ("Volts", ("voltage", "V")),
        ("Voltage (V)", ("voltage", "V")),
        ("Torque 6V (N · m)", ("torque", "N*m")),
        ("Torque (N·m)", ("torque", "N*m")),
        ("Torque [Nm]", ("torque", "N*m")),
        ("Speed (RPM)", ("speed", "rpm")),
        ("Power Output (W)", ("output_power", "W")),
        ("Output Power (W)", ("output_power", "W")),
        ("Supplied Power (W)", ("input_power", "W")),
        ("Power Dissipation (W)", ("power_dissipation", "W")),
        ("Efficiency (%)", ("efficiency", "percent")),
        ("Temperature (°C)", ("temperature", "degC")),
        ("I (mA)", ("current", "mA")),
        ("temperature_C", ("temperature", "degC")),
        ("Torque (oz-in)", ("torque", "ozf*in")),  # a weight on an arm, as gearmotor sheets mean it
        ("Torque (kg·cm)", ("torque", "kgf*cm")),
        ("Torque (mNm)", ("torque", "mN*m")),
        ("Torque (lb-ft)", ("torque", "lbf*ft")),
        ("Speed (rev/min)", ("speed", "rpm")),
        ("Motor Speed [r/min]", ("speed", "rpm")),
        ("Zeit", None),
        ("Power (W)", ("output_power", "W")),  # a datasheet's "Power" is the shaft's
        ("Input Output Power (W)", None),  # which power? the person says, with --column
        ("Current (Amps)", ("current", "A")),
        ("Torque (in-lbs)", ("torque", "lbf*in")),
        ("Voltage Current", None),
        ("Lost Power", ("power_dissipation", None)),  # karagenit/frc-motors' curves (VEX's data, units dropped)
        ("Input Power", ("input_power", None)),
        ("RPM", ("speed", "rpm")),
    ],
)
def test_worded_headers(header: str, expected: tuple[str, str | None] | None) -> None:
    assert worded_column(header) == expected


def test_a_speed_without_a_unit_is_refused_not_guessed(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """karagenit/frc-motors' copy of VEX's curves: ``Speed,Torque,Current,Input Power,Output Power,…`` in rpm."""
    with pytest.raises(LogFormatError, match="without a unit"):
        worded_column("Speed")
    path = tmp_path / "bag.csv"
    path.write_text("Speed,Torque,Current,Input Power,Output Power,Efficiency,Lost Power\n"
                    "0,0.431,52.619,631.428,0,0,631.428\n6588.845,0.2155,27.21,326.52,148.691,45.538,177.829\n"
                    "13177.689,0,1.8,21.6,0,0,21.6\n", encoding="utf-8")
    assert cli.main(["analyze", "curve", str(path)]) == 2
    err = capsys.readouterr().err
    assert "'Speed'" in err
    assert "--column" in err
    assert "\n" not in err.strip()
    assert cli.main(["analyze", "curve", str(path), "--column", "Speed=speed [rpm]", "--json"]) == 0
    assert '"K"' in capsys.readouterr().out


def test_unit_of_the_wrong_dimension_is_refused() -> None:
    with pytest.raises(LogFormatError, match="not a unit of current"):
        worded_column("Current (N·m)")
    assert normalise_unit("N · m") == "N*m"


def test_real_exports_read_as_they_are(dyno_dir: Path) -> None:
    """Every VEX export in the shared folder reads, with its channels under the Recording's names."""
    files = sorted(dyno_dir.glob("*.csv"))
    assert len(files) >= 24  # six motors: 2–12 V locked-rotor runs, a curve and a peak-power export each
    for path in files:
        assert detect_format(path) == "csv"
        rec = read_any(path)
        kind = path.name.split("-data-")[0].rsplit("-", 2)[-2:]
        if "locked" in path.name:
            assert rec.has("current", "voltage", "torque"), path.name
            assert rec.time[-1] > rec.time[0] >= 0.0  # seconds, as the file says (a run that failed ends early)
        elif "curve" in path.name:
            assert len(rec) == 101, kind
            assert rec.has("speed", "torque", "current", "input_power", "output_power", "efficiency")
        else:
            assert rec.has("current", "output_power"), path.name


def test_locked_rotor_values_in_si(dyno_dir: Path) -> None:
    """Latin-1 ``N · m`` header, CRLF: values as written, in SI (first row 0.001 s, 92.27 A, 12 V, 0.383 N·m)."""
    path = dyno_dir / "am-9015-locked-rotor-data-12v-20151210.csv"
    assert b"\xb7" in path.read_bytes()[:60]
    rec = read_csv(path)
    assert rec.time[0] == pytest.approx(0.001)
    assert rec["current"][0] == pytest.approx(92.27)
    assert rec["voltage"][0] == pytest.approx(12.0)
    assert rec["torque"][0] == pytest.approx(0.383)
    assert rec.lines is not None
    assert rec.lines[0] == 2


def test_curve_units_converted(dyno_dir: Path) -> None:
    """RPM -> rad/s and % -> a fraction; the free-speed row of the BAG curve (13177.689 rpm, 1.8 A)."""
    rec = read_csv(dyno_dir / "bag-motor-curve-data-20151207.csv")
    assert rec["speed"][-1] == pytest.approx(13177.689 * 2 * np.pi / 60)
    assert rec["current"][-1] == pytest.approx(1.8)
    assert np.max(rec["efficiency"]) < 1.0 < 100 * np.max(rec["efficiency"])


@pytest.mark.parametrize("encoding", ["utf-8", "utf-8-sig", "latin-1"])
def test_encodings(tmp_path: Path, encoding: str) -> None:
    text = "Time (s),Current (A),Torque 6V (N · m),Temperature (°C)\r\n0,1.5,0.1,25\r\n0.5,1.4,0.09,26\r\n"
    path = tmp_path / "run.csv"
    path.write_bytes(text.encode(encoding))
    rec = read_any(path)
    assert rec["torque"][1] == pytest.approx(0.09)
    assert rec["temperature"][0] == pytest.approx(298.15)  # kelvin inside


def test_column_mapping(tmp_path: Path) -> None:
    path = tmp_path / "odd.csv"
    path.write_text("Zeit,Strom,Notes\n0,100,a\n1,200,b\n")
    with pytest.raises(LogFormatError, match=r'odd.csv:1: column .Zeit. .*--column "Zeit=QUANTITY"'):
        read_csv(path)
    rec = read_csv(path, columns={"Zeit": "time", "Strom": "current [mA]", "Notes": "skip"})
    assert rec["current"] == pytest.approx([0.1, 0.2])
    assert read_csv(path, columns=["Zeit=time", "Strom=amps", "Notes=skip"])["current"] == pytest.approx([100, 200])
    with column_mapping(["Zeit=time_s", "Strom=current_mA", "notes=skip"]):  # case-insensitive headers
        assert detect_format(path) == "csv"
        assert read_any(path)["current"] == pytest.approx([0.1, 0.2])
    with pytest.raises(LogFormatError, match="names no quantity"):
        read_csv(path)  # the mapping ended with the block


def test_mapping_overrides_words_and_unit_from_header(tmp_path: Path) -> None:
    path = tmp_path / "run.csv"
    path.write_text("t (ms),Load (mA),Volts\n0,100,12\n10,200,12\n")
    rec = read_csv(path, columns=["Load (mA)=current"])  # the unit from the header's brackets
    assert rec.time[1] == pytest.approx(0.01)
    assert rec["current"] == pytest.approx([0.1, 0.2])
    rec = read_csv(path, columns=["Load (mA)=current", "Volts=battery"])
    with pytest.raises(LogFormatError):
        rec.require("voltage")


@pytest.mark.parametrize(
    ("rule", "match"),
    [("Amps", "write HEADER=quantity"), ("=current", "empty"), ("Amps=furlongs", "unknown quantity"),
     ("Amps=current [N*m]", "not a unit of current"), (["A=current", "a=voltage"], "mapped twice")],
)
def test_bad_rules(rule: object, match: str) -> None:
    with pytest.raises(OptionError, match=match):
        parse_column_mapping(rule)


def test_no_current_is_refused_in_one_line(tmp_path: Path) -> None:
    path = tmp_path / "torque_only.csv"
    path.write_text("Time,Torque (N·m)\n0,0.1\n1,0.2\n", encoding="latin-1")
    with pytest.raises(LogFormatError, match=r"no current .*--column \"HEADER=current\""):
        read_csv(path).require("current")


def _run(args: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    try:
        code = cli.main(args)
    except SystemExit as exc:
        code = int(exc.code or 0)
    out = capsys.readouterr()
    return code, out.out, out.err


def test_cli_column_option(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "lever.csv"
    path.write_text("Strom,Moment\n0.5,0.011\n1.0,0.019\n1.5,0.031\n2.0,0.040\n")
    code, _out, err = _run(["analyze", "torque", str(path)], capsys)
    assert code == 2
    assert err.count("\n") == 1
    assert "--column \"Strom=QUANTITY\"" in err
    assert "Traceback" not in err
    code, out, _err = _run(["analyze", "torque", str(path), "--column", "Strom=current",
                            "--column", "Moment=torque", "--json"], capsys)
    assert code == 0
    assert '"K"' in out
    code, _out, err = _run(["analyze", "torque", str(path), "--column", "Strom"], capsys)
    assert code == 2
    assert err.count("\n") == 1
    assert "HEADER=quantity" in err


def test_session_columns(tmp_path: Path) -> None:
    from motorlab.session.spec import load_session

    shutil.copy(Path(__file__).parent.parent / "data" / "csv" / "lcr.csv", tmp_path / "lcr.csv")
    (tmp_path / "s.toml").write_text(
        '[motor]\nname = "m"\ncounts_per_revolution = 28\n[units.A.lcr]\nfiles = ["lcr.csv"]\n'
        'columns = { "Strom" = "current", "Notes" = "skip" }\n'
    )
    session = load_session(tmp_path / "s.toml")
    assert session.units["A"].experiments["lcr"].settings["columns"] == ["Strom=current", "Notes=skip"]
    (tmp_path / "s.toml").write_text(
        '[motor]\nname = "m"\ncounts_per_revolution = 28\n[units.A.lcr]\nfiles = ["lcr.csv"]\n'
        'columns = { "Strom" = "furlongs" }\n'
    )
    with pytest.raises(SessionError, match=r"s.toml:\d+: .*unknown quantity"):
        load_session(tmp_path / "s.toml")


def test_every_analysis_that_reads_a_csv_takes_column() -> None:
    """--column on every analysis whose input may be a CSV (the app's column picker is built on it)."""
    from motorlab.experiments import all_experiments

    for name, exp in all_experiments().items():
        if "csv" in exp.inputs.lower():
            assert any(opt.kind == "columns" and opt.name == "column" for opt in exp.options), name
