"""Issue 25's failures, one regression test each: power towers, integer literals of thousands of digits,
cpr and scale factors outside any encoder, numpy warnings on successful runs, ``-o ""``, deep TOML,
and argparse's refusals in the same words as every other.

Each runs ``motorlab`` in process on small files the virtual rig writes, except the power towers:
before the fix they never returned, so they run in a child process with a time limit.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from motorlab import cli, units
from motorlab.errors import OptionError
from motorlab.rig import VirtualRig
from motorlab.units import parse_quantity

HUGE = "9" * 5000  # beyond Python's 4,300-digit limit of integer conversion


@pytest.fixture(scope="module")
def rig(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("rig25")
    r = VirtualRig("neverest40", unit_seed=1, noise_seed=7)
    runs = {
        "terminal": r.run("terminal", folder / "terminal.csv"),
        "lcr": r.run("lcr", folder / "lcr.csv"),
        "amplifier": r.run("amplifier", folder / "amplifier.csv"),
        "transient": r.run("transient", folder / "transient.csv", duration=1.0),
        "sysid": r.run("sysid", folder / "sysid.json", quasistatic_duration=6.0, dynamic_duration=2.0),
    }
    out = {name: Path(run.paths[0]) for name, run in runs.items()}
    from motorlab.rig.ftc import simulate_flight_log, simulate_ramp

    simulate_ramp(folder / "ramp.json", seed=3)
    simulate_flight_log(folder / "flight.log", duration=4.0, seed=3)
    out["ramp"], out["flight"] = folder / "ramp.json", folder / "flight.log"
    return out


def run(capsys: pytest.CaptureFixture[str], *argv: object) -> tuple[int, str, str]:
    try:
        code = cli.main([str(a) for a in argv])
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else 1
    out, err = capsys.readouterr()
    return code, out, err


def refused(capsys: pytest.CaptureFixture[str], *argv: object, mentions: str = "") -> str:
    code, _, err = run(capsys, *argv)
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("motorlab: error: "), err
    assert "computation failed" not in err, err  # not the last-resort handler
    assert mentions.lower() in err.lower(), err
    return err


# ---- power towers: bounded work wherever a quantity is parsed ------------------------------------------


_THREE_RUNS = """
import contextlib, io, json, os, sys
from motorlab import cli
out = []
for argv, env in json.loads(sys.argv[1]):
    os.environ.update(env)
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        try:
            code = cli.main(argv)
        except SystemExit as exc:
            code = exc.code
    for key in env:
        del os.environ[key]
    out.append([code, err.getvalue()])
print(json.dumps(out))
"""


def test_a_power_tower_is_refused_at_once_everywhere(rig, tmp_path: Path) -> None:
    """Option, session file and MOTORLAB_MAX_INPUT_SIZE: each answered at once, one line, exit 2.

    In one child process with a time limit: before the fix, pint evaluated 9**9**9 and never returned.
    """
    session = tmp_path / "session.toml"
    session.write_text('[motor]\ncatalog = "neverest40"\n[rig]\nlever_arm = "9**9**9 m"\n'
                       f'[units.A.lcr]\nfiles = ["{rig["lcr"]}"]\n')
    runs = [
        (["analyze", "terminal", str(rig["terminal"]), "--K", "9**9**9 V*s/rad"], {}),
        (["characterize", str(session), "-o", str(tmp_path / "out")], {}),
        (["analyze", "lcr", str(rig["lcr"])], {"MOTORLAB_MAX_INPUT_SIZE": "9**9**9"}),
    ]
    done = subprocess.run([sys.executable, "-c", _THREE_RUNS, json.dumps(runs)], capture_output=True, text=True,
                          timeout=120, check=False, env={**os.environ, "MPLBACKEND": "Agg"})
    assert done.returncode == 0, done.stderr
    results = json.loads(done.stdout)
    for code, err in results:
        assert code == 2, err
        assert len(err.strip().splitlines()) == 1, err
    assert "--K" in results[0][1]
    assert "power of a power" in results[0][1]
    assert f"{session}:4: rig.lever_arm" in results[1][1]
    assert "MOTORLAB_MAX_INPUT_SIZE" in results[2][1]
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("text", ["9**9**9", "9^9^9 m", "2**(2**40) m", "(((((1))))) m", "m^1000", "1" * 300 + " m",
                                  "9 ** 9 ** 9", "2**-9**9 m", "m**99999999", "(10^12)^12^12"])
def test_expressions_beyond_a_unit_are_refused_without_evaluating(text: str) -> None:
    start = time.perf_counter()
    with pytest.raises(OptionError):
        parse_quantity(text, "m", name="--arm")
    assert time.perf_counter() - start < 1.0


@pytest.mark.parametrize(("text", "unit", "value"), [
    ("7.8 kg*m^2", "kg*m^2", 7.8), ("400 in*oz", "N*m", 400 * 0.0254 * 0.028349523125 * 9.80665),
    ("130 rpm", "rad/s", 130 * 2 * 3.141592653589793 / 60), ("1.5 (m/s)^2", "m^2/s^2", 1.5), ("3 s**-1", "1/s", 3),
    ("10^3 m", "m", 1000.0), ("-12 V", "V", -12.0), ("2 kg m^2", "kg*m^2", 2.0), ("12 mV", "V", 0.012),
])
def test_units_still_read(text: str, unit: str, value: float) -> None:
    assert parse_quantity(text, unit) == pytest.approx(value)
    units.check_expression(text)


@pytest.mark.parametrize(("experiment", "option"), [("amplifier", "--nominal"), ("identify", "--R"),
                                                    ("terminal", "--K-stderr")])
def test_an_overflowing_quantity_option_is_one_line(experiment: str, option: str, rig, capsys) -> None:
    """``--nominal '2**1024'`` raised OverflowError inside argparse: a traceback."""
    files = {"amplifier": (rig["amplifier"],), "identify": (rig["transient"], "--cpr", "1120"),
             "terminal": (rig["terminal"], "--K", "0.7")}[experiment]
    for value in ("2**1024", "1e200^2 V", HUGE):
        err = refused(capsys, "analyze", experiment, *files, option, value, mentions=option)
        assert len(err) < 400


# ---- integer literals of thousands of digits ----------------------------------------------------------


def _with_huge_integer(source: Path, target: Path, old: str) -> int:
    """``source`` with the first ``old`` replaced by a 5,000-digit integer; the 1-based line of it."""
    text = source.read_text()
    at = text.index(old)
    target.write_text(text[:at] + HUGE + text[at + len(old):])
    return text.count("\n", 0, at) + 1


def test_sysid_json_with_a_huge_integer(rig, tmp_path: Path, capsys) -> None:
    path = tmp_path / "sysid.json"
    text = rig["sysid"].read_text()
    doc = json.loads(text)
    doc["sysid"] = True
    doc["test"] = "Simple"
    path.write_text(json.dumps(doc, indent=1).replace('"Simple"', HUGE, 1))
    line = path.read_text()[: path.read_text().index(HUGE)].count("\n") + 1
    refused(capsys, "analyze", "feedforward", path, mentions=f"{path}:{line}: an integer of 5000 digits")


def test_roadrunner_ramp_with_a_huge_integer(rig, tmp_path: Path, capsys) -> None:
    path = tmp_path / "ramp.json"
    text = rig["ramp"].read_text()
    key = text.index('"voltages"')
    start = text.index("[", key) + 1
    end = min(text.index(",", start), text.index("]", start))
    line = _with_huge_integer(rig["ramp"], path, text[start:end])
    refused(capsys, "analyze", "feedforward", path, "--cpr", "8192", mentions=f"{path}:{line}:")


def test_tune_params_with_a_huge_integer(tmp_path: Path, capsys) -> None:
    path = tmp_path / "params.json"
    path.write_text('{"experiment": "feedforward",\n "parameters": {"kV": {"value": ' + HUGE + ', "unit": "V*s/rad"}}}')
    refused(capsys, "tune", "velocity", "--params", path, mentions=f"{path}:2: an integer of 5000 digits")


@pytest.mark.parametrize("digits", [5000, 400])
def test_session_with_a_huge_integer(digits: int, rig, tmp_path: Path, capsys) -> None:
    path = tmp_path / "session.toml"
    path.write_text(f'[motor]\ncatalog = "neverest40"\n[rig]\nlever_arm = {"9" * digits}\n'
                    f'[units.A.lcr]\nfiles = ["{rig["lcr"]}"]\n')
    refused(capsys, "characterize", path, "-o", tmp_path / "out", mentions=f"{path}:4")
    assert not (tmp_path / "out").exists()


def test_truth_file_with_a_huge_integer(tmp_path: Path) -> None:
    from motorlab.errors import SessionError
    from motorlab.session.spec import read_truth

    path = tmp_path / "truth.json"
    path.write_text('{"K":\n ' + HUGE + "}")
    with pytest.raises(SessionError, match=r"truth.json:2: .*integer of 5000 digits"):
        read_truth(path)


# ---- cpr outside any encoder, in every reader and experiment -------------------------------------------


@pytest.mark.parametrize(("name", "extra"), [("sysid", ()), ("ramp", ()), ("flight", ()), ("transient", ())])
@pytest.mark.parametrize("cpr", ["1e-12", "0.5", "1e12"])
def test_feedforward_refuses_an_impossible_cpr(name: str, extra: tuple[str, ...], cpr: str, rig, capsys) -> None:
    """``--cpr 1e-12`` gave kV = 1.5e-17 V·s/rad and "R² 1.000000" at exit 0 for all but spindown."""
    refused(capsys, "analyze", "feedforward", rig[name], "--cpr", cpr, *extra, mentions="--cpr")


@pytest.mark.parametrize("cpr", ["1e-12", "0.5"])
def test_every_counting_experiment_refuses_an_impossible_cpr(cpr: str, rig, capsys) -> None:
    refused(capsys, "analyze", "identify", rig["transient"], "--cpr", cpr, mentions="--cpr")
    refused(capsys, "analyze", "terminal", rig["terminal"], "--K", "0.7", "--cpr", cpr, mentions="--cpr")


def test_a_csv_metadata_cpr_outside_any_encoder_is_refused_naming_the_file(rig, tmp_path: Path, capsys) -> None:
    path = tmp_path / "transient.csv"
    path.write_text(rig["transient"].read_text().replace("# cpr: 1120.0", "# cpr: 1e-12"))
    refused(capsys, "analyze", "identify", path, mentions=str(path))


def test_a_fractional_cpr_above_one_is_still_read(rig, capsys) -> None:
    code, _, err = run(capsys, "analyze", "feedforward", rig["flight"], "--cpr", "537.7", "--json")
    assert code == 0, err


def test_units_per_rotation_outside_any_mechanism_is_refused(rig, tmp_path: Path, capsys) -> None:
    doc = json.loads(rig["sysid"].read_text())
    for value in (1e-300, 1e300):
        doc["unitsPerRotation"] = value
        path = tmp_path / "scaled.json"
        path.write_text(json.dumps(doc))
        refused(capsys, "analyze", "feedforward", path, mentions="unitsPerRotation")


# ---- smaller ------------------------------------------------------------------------------------------


def test_characterize_refuses_an_empty_output_name(rig, tmp_path: Path, capsys) -> None:
    session = tmp_path / "session.toml"
    session.write_text(f'[motor]\ncatalog = "neverest40"\n[units.A.lcr]\nfiles = ["{rig["lcr"]}"]\n')
    refused(capsys, "characterize", session, "-o", "", mentions="-o")
    assert not (tmp_path / "results").exists()


@pytest.mark.parametrize("deep", ["array", "inline-table"])
def test_a_toml_nested_a_thousand_deep_is_refused_with_its_line(deep: str, tmp_path: Path, capsys) -> None:
    path = tmp_path / "session.toml"
    body = {"array": "x = " + "[" * 1000 + "]" * 1000, "inline-table": "x = " + "{a = " * 1000 + "1" + "}" * 1000}[deep]
    path.write_text('[motor]\ncatalog = "neverest40"\n\n' + body + "\n")
    err = refused(capsys, "characterize", path, mentions=f"{path}:4")
    assert "internal error" not in err


def test_argparse_refusals_read_like_every_other(capsys) -> None:
    err = refused(capsys, "analyze", "spindown", "x.txt", "--cpr", "abc", mentions="argument --cpr")
    assert err.startswith("motorlab: error: analyze spindown: argument --cpr")
    err = refused(capsys, "analyze", "lcr", mentions="the following arguments are required")
    assert err.startswith("motorlab: error: analyze lcr: ")


def test_the_app_still_reads_the_argparse_line() -> None:
    from motorlab.ui.runner import Outcome

    line = "motorlab: error: analyze spindown: argument --cpr: cannot read 'abc'"
    assert Outcome(2, "", line + "\n").error_line() == "analyze spindown: argument --cpr: cannot read 'abc'"


# ---- numpy warnings on successful runs -------------------------------------------------------------------


def test_the_open_loop_score_of_huge_residuals_warns_nothing() -> None:
    """``sysid_score.py: overflow encountered in square`` on runs that succeeded (pytest: warnings are errors)."""
    import numpy as np

    from motorlab.analyses.sysid_score import ScoreTest, score

    t = np.linspace(0.0, 1.0, 50)
    test = ScoreTest("fast-forward", t, np.full(50, 6.0), np.zeros(50), np.full(50, 1e200))
    result = score((0.1, 1.0, 0.1), [test])
    assert 1e199 < result.speed < 1e201
    from motorlab.analyses.sysid_score import rms

    assert rms(np.array([3.0, -4.0])) == pytest.approx(np.sqrt(12.5))


def test_the_sysid_regression_on_a_repeated_time_warns_nothing() -> None:
    """``feedforward.py: divide by zero`` from a time step of zero in the SysId-style regression."""
    import numpy as np

    from motorlab.analyses.feedforward import sysid_ols
    from motorlab.recording import Recording

    t = np.linspace(0.0, 2.0, 400)
    t = np.insert(t, 200, t[200])  # one time twice: a step of zero
    v = np.where(t < 1.0, 3.0, 6.0) + 0.5 * np.sin(7.0 * t)
    position = np.cumsum(v + 0.1 * np.cos(3.0 * t)) * 5e-3
    rec = Recording(time=t, signals={"voltage": v, "position": position}, source="rep.json")
    gains = sysid_ols([rec])
    assert all(np.isfinite(list(gains.values())))


# ---- other scale factors ---------------------------------------------------------------------------------


@pytest.mark.parametrize("value", ["1e-300", "1e300"])
def test_scale_factors_outside_any_rig_are_refused(value: str, rig, tmp_path: Path, capsys) -> None:
    """A gear ratio or a tachometer gain of 1e-300 gave an answer at exit 0 (or would scale J absurdly)."""
    torque = VirtualRig("neverest40", unit_seed=1, noise_seed=7).run("torque", tmp_path / "torque.csv").paths[0]
    refused(capsys, "analyze", "torque", torque, "--K", "0.7", "--ratio", value, mentions="--ratio")
    pulse = VirtualRig("neverest40", unit_seed=1, noise_seed=7).run("pulse", tmp_path / "pulse.csv").paths[0]
    refused(capsys, "analyze", "pulse", pulse, "--Ka", "1.96", "--K", "0.7", "--tach-gain", value,
            mentions="--tach-gain")
    spindown = VirtualRig("neverest40", unit_seed=1, noise_seed=7).run(
        "spindown", tmp_path / "spindown.txt", on_time=5.0, coast_time=10.0).paths[0]
    refused(capsys, "analyze", "spindown", spindown, "--cpr", "1120", "--disc-radius", "75 mm",
            "--disc-thickness", "50 mm", "--ratio", value, mentions="--ratio")


def test_the_speed_lag_of_tests_shorter_than_the_shift(tmp_path: Path, capsys) -> None:
    """Found by the fuzz run: a truncated .wpilog left a 25-row test, and the lag search sliced past it
    (``ValueError: operands could not be broadcast``, an internal error)."""
    import numpy as np

    from motorlab.analyses.sysid_score import ScoreTest, speed_lag

    t = np.linspace(0.0, 0.5, 25)
    test = ScoreTest("dynamic-forward", t, np.full(25, 6.0), 0.5 * t**2, t.copy())
    lag, ratio = speed_lag((0.1, 1.0, 0.1), [test], max_rows=40)
    assert lag >= 0.0
    assert 0.0 < ratio <= 1.0
    failure = Path(__file__).parents[1] / "data" / "fuzz" / "truncated-sysid.wpilog"
    code, _out, err = run(capsys, "analyze", "feedforward", failure, "--json")
    assert code in (0, 2), err
    assert "internal error" not in err


def test_free_spinup_without_a_cpr_names_the_file(tmp_path: Path, capsys) -> None:
    """Found by the fuzz run: a cursor-time file that lost its '# cpr:' line got a refusal naming no file."""
    run_ = VirtualRig("neverest40", unit_seed=1, noise_seed=7).free_spinup(tmp_path / "edges.csv")
    path = Path(run_.paths[0])
    path.write_text("".join(line for line in path.read_text().splitlines(keepends=True) if "cpr" not in line))
    refused(capsys, "analyze", "free-spinup", path, "--K", "0.7", "--current", "0.5 A", mentions=f"{path}: the file")


def test_a_blank_output_name_is_refused(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys) -> None:
    """Found by the fuzz run: ``simulate -o ' '`` wrote a file named by one space."""
    monkeypatch.chdir(tmp_path)
    refused(capsys, "simulate", "torque", "--motor", "neverest40", "-o", " ", mentions="blank")
    assert list(tmp_path.iterdir()) == []


def test_a_log_no_regression_start_can_simulate_is_refused(capsys) -> None:
    """Found by the long fuzz run (case 1370): a .wpilog with a range of its records repeated; every
    regression start simulated beyond a float, and an ``assert`` ended the run (exit 1)."""
    failure = Path(__file__).parents[1] / "data" / "fuzz" / "duplicated-range-sysid.wpilog"
    refused(capsys, "analyze", "feedforward", failure, "--json", mentions="duplicated-range-sysid.wpilog: cannot find")


@pytest.mark.parametrize("argv", [("simulate", "torque", "--motor", "neverest40", "-o", "sim.csv", "--noise-seed=--"),
                                  ("motors", "neverest40", "--voltage=--")])
def test_a_double_dash_as_an_option_value_is_refused(argv, tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                      capsys) -> None:
    """Found by the long fuzz run (cases 3950, 3967): ``--noise-seed=--`` and ``--R=--`` reached the
    analysis as an empty list (argparse drops the "--" and never runs the option's type): exit 1."""
    monkeypatch.chdir(tmp_path)
    refused(capsys, *argv, mentions="expected a value, got '--'")
    assert not (tmp_path / "sim.csv").exists()


def test_a_unit_value_that_breaks_physics_keeps_its_warning(tmp_path: Path, capsys) -> None:
    """Found by the long fuzz run (case 6514): a terminal table with a range of rows repeated gave
    b < 0; the terminal analysis warned, but the unit's table (results.json, results.csv, the printed
    table) showed the negative b with status "ok" and no warning."""
    import shutil

    folder = tmp_path / "session"
    shutil.copytree(Path(__file__).parents[1] / "data" / "fuzz" / "negative-b-session", folder)
    code, _out, err = run(capsys, "characterize", folder / "session.toml", "--no-report", "-o", tmp_path / "out")
    assert code == 0, err
    unit = json.loads((tmp_path / "out" / "results.json").read_text())["units"]["A"]
    assert unit["parameters"]["b"]["value"] < 0
    assert any(w.startswith("terminal: b is fitted negative") for w in unit["warnings"]), unit["warnings"]
    assert "motorlab: warning: unit A: terminal: b is fitted negative" in err


def test_a_curve_voltage_beyond_any_motor_is_refused(tmp_path: Path, capsys) -> None:
    """Found by the long fuzz run (case 4993): ``analyze curve --voltage 1e299`` ran, with numpy's
    overflow warnings on stderr, to exit 0."""
    from motorlab.io import write_csv

    path = tmp_path / "curve.csv"
    write_csv(path, {"speed_rpm": [0.0, 3000, 6000], "torque_Nm": [1.4, 0.7, 0.0], "current_A": [89.0, 46, 3]})
    refused(capsys, "analyze", "curve", path, "--voltage", "1e299", "--json", mentions="above 1000 V")
    code, _out, err = run(capsys, "analyze", "curve", path, "--voltage", "12", "--json")
    assert code == 0, err


def test_a_frequency_table_without_a_cpr_names_the_file(tmp_path: Path, capsys) -> None:
    """Found by the long fuzz run (case 6226): a terminal table of channel frequencies that lost its
    '# cpr:' line was refused with "give the counts per revolution (--cpr)" and no file name."""
    path = tmp_path / "terminal.csv"
    path.write_text("# experiment: 18.0\ncurrent_A,frequency_Hz\n0.292,375.42\n0.337,533.27\n0.382,691.5\n"
                    "0.426,849.77\n0.471,1011.4\n")
    refused(capsys, "analyze", "terminal", path, "--K", "0.7", "--json", mentions=f"{path}: the rows hold")


def test_a_file_name_with_a_nul_byte_is_refused(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys) -> None:
    """Found by the long fuzz run (case 6410): ``tune --params $'\\0'`` (a script's argv can hold a NUL)
    reached os.stat, whose ValueError ended the run with exit 1."""
    from motorlab.errors import LogFormatError
    from motorlab.io import read_any

    monkeypatch.chdir(tmp_path)
    refused(capsys, "tune", "velocity", "--params", "\x00", "--json", mentions="contains a NUL byte")
    refused(capsys, "analyze", "lcr", "lcr\x00.csv", "--json", mentions="'lcr?.csv': contains a NUL byte")
    refused(capsys, "simulate", "torque", "--motor", "neverest40", "-o", "a\x00.csv", mentions="contains a NUL")
    with pytest.raises(LogFormatError, match=r"lcr\?\.csv: the file name contains a NUL byte"):
        read_any("lcr\x00.csv")


def test_the_heat_of_a_long_table_is_bounded_work(monkeypatch: pytest.MonkeyPatch) -> None:
    """Found by bench_scale.py: `analyze terminal` on 2 M rows (18 s operating points, 10 h) moved
    360 M bins of 0.1 s through the thermal network: 24 GB, killed. The bins widen past a bound."""
    import numpy as np

    from motorlab.thermal import network as thermal

    steps = []
    original = thermal.ThermalModel.step
    monkeypatch.setattr(thermal.ThermalModel, "step", lambda self, *a: steps.append(1) or original(self, *a))
    t = np.arange(200_000) * 18.0
    energy, rise = thermal.log_rise(t, np.full(t.size, 0.3), 2.0)
    assert len(steps) <= thermal.LOG_RISE_BINS + 2
    assert energy == pytest.approx(2.0 * 0.09 * t[-1])
    assert rise == pytest.approx(0.09 * 2.0 * 5.7, rel=0.05)  # the steady rise I²R·(R_wc + R_ca)
