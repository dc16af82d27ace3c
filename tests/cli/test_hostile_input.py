"""Issue 14's defects, one regression test each: special files, absurd magnitudes, impossible fits,
glitches, outputs that could overwrite inputs, and the smaller items.

Every case runs ``motorlab`` in process (as ``tests/cli/test_bad_input.py`` does) on small files
the virtual rig writes, corrupted in a temporary folder.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from motorlab import cli
from motorlab.rig import VirtualRig


@pytest.fixture(scope="module")
def rig(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """Valid files of the experiments these tests need (NeveRest 40, unit seed 1, noise seed 7)."""
    folder = tmp_path_factory.mktemp("rig")
    r = VirtualRig("neverest40", unit_seed=1, noise_seed=7)
    runs = {
        "spindown": r.run("spindown", folder / "spindown.txt", on_time=10.0, coast_time=20.0),
        "terminal": r.run("terminal", folder / "terminal.csv"),
        "lcr": r.run("lcr", folder / "lcr.csv"),
        "transient": r.run("transient", folder / "transient.csv", duration=2.0),
        "sysid": r.run("sysid", folder / "sysid.json", quasistatic_duration=10.0, dynamic_duration=3.0),
        "free-spinup": r.run("free-spinup", folder / "free_spinup.csv"),
    }
    return {name: Path(run.paths[0]) for name, run in runs.items()}


def run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    try:
        code = cli.main([str(a) for a in argv])
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else 1
    out, err = capsys.readouterr()
    return code, out, err


def refused(capsys: pytest.CaptureFixture[str], *argv: str, mentions: str = "") -> str:
    code, _, err = run(capsys, *argv)
    assert code == 2, err
    assert "Traceback" not in err
    assert len(err.strip().splitlines()) == 1, err
    assert mentions.lower() in err.lower(), err
    return err


def copy(path: Path, folder: Path) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    return Path(shutil.copy2(path, folder / path.name))


def data_rows(path: Path) -> list[int]:
    """0-based indices of the numeric rows of a text log."""
    lines = path.read_text().split("\n")
    return [k for k, line in enumerate(lines) if line.strip() and line.strip()[0] in "-0123456789"]


def set_field(path: Path, row: int, column: int, value: str) -> int:
    """Write ``value`` into one field of the 0-based line ``row``; the 1-based line number."""
    lines = path.read_text().split("\n")
    sep = "," if "," in lines[row] else " "
    fields = lines[row].split(sep)
    fields[column] = value
    lines[row] = sep.join(fields)
    path.write_text("\n".join(lines))
    return row + 1


# ---- special files and size -----------------------------------------------------------------------


@pytest.mark.parametrize("experiment", ["spindown", "terminal", "identify", "lcr"])
def test_dev_zero_is_refused_before_reading(experiment: str, capsys) -> None:
    if not os.path.exists("/dev/zero"):
        pytest.skip("no /dev/zero here")
    options = {"spindown": ("--cpr", "1120"), "terminal": ("--K", "0.7"), "identify": (), "lcr": ()}[experiment]
    refused(capsys, "analyze", experiment, "/dev/zero", *options, mentions="/dev/zero: is a device")


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs on this system")
def test_a_fifo_without_writer_is_refused_at_once(tmp_path: Path) -> None:
    """In a separate process with a timeout: a reader that opened the FIFO would wait for ever."""
    fifo = tmp_path / "log.csv"
    os.mkfifo(fifo)
    done = subprocess.run([sys.executable, "-m", "motorlab", "analyze", "lcr", str(fifo)],
                          capture_output=True, text=True, timeout=60, check=False)
    assert done.returncode == 2
    assert "FIFO" in done.stderr
    assert len(done.stderr.strip().splitlines()) == 1


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs on this system")
def test_outputs_never_replace_a_fifo_or_a_folder(tmp_path: Path, capsys) -> None:
    """The rename of an atomic write would put a regular file where the FIFO (or, as root, /dev/null) was."""
    import stat

    fifo = tmp_path / "out.csv"
    os.mkfifo(fifo)
    refused(capsys, "simulate", "torque", "--motor", "neverest40", "-o", fifo, mentions="not a regular file")
    refused(capsys, "simulate", "torque", "--motor", "neverest40", "-o", tmp_path, mentions="is a directory")
    os.mkfifo(tmp_path / "fifo.png")
    refused(capsys, "tune", "velocity", "--kv", "0.12", "--ka", "0.01", "--plot", tmp_path / "fifo.png",
            mentions="not a regular file")
    assert stat.S_ISFIFO(os.stat(fifo).st_mode)
    assert stat.S_ISFIFO(os.stat(tmp_path / "fifo.png").st_mode)


def test_size_limit_refuses_and_the_variable_lifts_it(rig, tmp_path: Path, monkeypatch, capsys) -> None:
    path = copy(rig["lcr"], tmp_path)
    monkeypatch.setenv("MOTORLAB_MAX_INPUT_SIZE", "100")
    err = refused(capsys, "analyze", "lcr", path, mentions="MOTORLAB_MAX_INPUT_SIZE")
    assert "limit" in err
    monkeypatch.setenv("MOTORLAB_MAX_INPUT_SIZE", "1 MB")
    code, _, err = run(capsys, "analyze", "lcr", path)
    assert code == 0, err
    monkeypatch.setenv("MOTORLAB_MAX_INPUT_SIZE", "lots")
    refused(capsys, "analyze", "lcr", path, mentions="MOTORLAB_MAX_INPUT_SIZE")


def test_deeply_nested_json_is_an_input_error(tmp_path: Path, capsys) -> None:
    deep = tmp_path / "deep.json"
    deep.write_text("[" * 100_000 + "]" * 100_000)
    refused(capsys, "analyze", "feedforward", deep, mentions="nested too deeply")
    refused(capsys, "tune", "velocity", "--params", deep, mentions="nested too deeply")


# ---- absurd magnitudes --------------------------------------------------------------------------


def test_one_absurd_value_is_excluded_as_a_glitch(rig, tmp_path: Path, capsys) -> None:
    path = copy(rig["terminal"], tmp_path)
    line = set_field(path, data_rows(path)[2], 1, "1e308")
    code, out, err = run(capsys, "analyze", "terminal", path, "--K", "0.7", "--json")
    assert code == 0, err
    warnings = " ".join(json.loads(out)["warnings"])
    assert f"{path.name}:{line}: single-sample glitch excluded" in warnings


def test_absurd_values_on_every_row_are_refused(rig, tmp_path: Path, capsys) -> None:
    path = copy(rig["lcr"], tmp_path)
    rows = data_rows(path)
    for row in rows:
        set_field(path, row, 2, "1e300")
    refused(capsys, "analyze", "lcr", path, mentions="beyond any measurement")


def test_identical_timestamps_are_refused(rig, tmp_path: Path, capsys) -> None:
    path = copy(rig["transient"], tmp_path)
    for row in data_rows(path):
        set_field(path, row, 0, "1.0")
    refused(capsys, "analyze", "identify", path, "--cpr", "1120", mentions="same time")


@pytest.mark.parametrize(("kv", "ka"), [("1", "1e308"), ("1e-300", "1"), ("1e300", "1e300")])
def test_tune_refuses_absurd_plants(kv: str, ka: str, capsys) -> None:
    refused(capsys, "tune", "velocity", "--kv", kv, "--ka", ka, mentions="k")


def test_numerical_failures_become_input_errors_naming_the_file(rig, monkeypatch, capsys) -> None:
    """A LinAlgError, an overflow or a RecursionError inside an analysis: exit 2 naming the input."""
    import motorlab.analyses.lcr as lcr

    for failure in (np.linalg.LinAlgError("Singular matrix"), OverflowError("math range error"),
                    RecursionError("maximum recursion depth exceeded")):
        def broken(*args, failure=failure, **kwargs):
            raise failure

        monkeypatch.setattr(lcr, "lcr", broken)  # the analysis motorlab.experiments.lcr runs
        err = refused(capsys, "analyze", "lcr", rig["lcr"], mentions=str(rig["lcr"]))
        assert "computation failed" in err


# ---- results outside physics ----------------------------------------------------------------------


def test_terminal_with_a_contradicting_tf_is_refused(rig, capsys) -> None:
    err = refused(capsys, "analyze", "terminal", rig["terminal"], "--K", "0.7", "--Tf", "100",
                  mentions="b comes out negative")
    assert "given Tf = 100" in err


def test_feedforward_with_a_contradicting_k_is_refused(rig, capsys) -> None:
    refused(capsys, "analyze", "feedforward", rig["sysid"], "--R", "2", "--K", "5", mentions="given K = 5")


def test_spinup_on_a_transient_log_warns_of_a_negative_k(tmp_path: Path, capsys) -> None:
    """The issue's case: K = −4376 at exit 0 without a word; now the warning names the likely cause."""
    path = VirtualRig("neverest40", unit_seed=1, noise_seed=7).run("transient", tmp_path / "t.csv").paths[0]
    code, out, err = run(capsys, "analyze", "spinup", path, "--cpr", "1120", "--inertia", "12.2", "--json")
    assert code == 0, err
    doc = json.loads(out)
    assert doc["parameters"]["K"]["value"] < 0
    assert any("K is fitted negative" in w and "not this experiment's" in w for w in doc["warnings"])


def test_negative_parameter_is_warned_and_given_values_refuse() -> None:
    from motorlab.errors import OptionError
    from motorlab.results import Estimate, FitResult

    b = Estimate("b", -0.5, 0.01, "N*m*s/rad")
    result = FitResult("x", {"b": b})
    assert any("b is fitted negative" in w and "likely cause" in w for w in result.warnings)
    near_zero = FitResult("x", {"b": Estimate("b", -0.001, 0.01, "N*m*s/rad")})
    assert any("within its uncertainty" in w for w in near_zero.warnings)
    with pytest.raises(OptionError, match="given Tf"):
        FitResult("x", {"b": b, "Tf": Estimate("Tf", 100.0, 0.0, "N*m", note="given")})


def test_free_spinup_says_what_assuming_no_coulomb_friction_costs(rig, capsys) -> None:
    code, out, err = run(capsys, "analyze", "free-spinup", rig["free-spinup"], "--K", "0.7", "--current", "0.5 A",
                         "--json")
    assert code == 0, err
    warnings = " ".join(json.loads(out)["warnings"])
    assert "Tf was taken as 0" in warnings
    assert "100 % too high" in warnings


# ---- single-sample glitches ---------------------------------------------------------------------


def test_failed_encoder_read_in_a_spindown_is_excluded_and_named(rig, tmp_path: Path, capsys) -> None:
    clean = run(capsys, "analyze", "spindown", rig["spindown"], "--cpr", "1120", "--json")
    assert clean[0] == 0, clean[2]
    path = copy(rig["spindown"], tmp_path)
    rows = data_rows(path)
    line = set_field(path, rows[len(rows) * 3 // 4], 1, str(2**31 - 1))
    code, out, err = run(capsys, "analyze", "spindown", path, "--cpr", "1120", "--json")
    assert code == 0, err
    doc = json.loads(out)
    assert any(f"{path.name}:{line}: single-sample glitch excluded" in w for w in doc["warnings"])
    k, k_clean = doc["parameters"]["K"], json.loads(clean[1])["parameters"]["K"]
    assert k["value"] is not None
    assert k["value"] == pytest.approx(k_clean["value"], rel=1e-3)


@pytest.mark.parametrize("glitch", ["two-failed-reads", "zero-mid-coast"])
def test_several_glitches_and_a_zero_in_a_coast_are_excluded(rig, tmp_path: Path, capsys, glitch: str) -> None:
    """Two failed reads once ended as "K not determined"; a 0 among 7491 and 7517 counts went unseen (the
    counts' spread over a coast set the threshold)."""
    clean = run(capsys, "analyze", "spindown", rig["spindown"], "--cpr", "1120", "--json")
    path = copy(rig["spindown"], tmp_path)
    rows = data_rows(path)
    coast = [r for r in rows if int(path.read_text().split("\n")[r].split()[1]) > 1000]  # the shaft has turned
    if glitch == "two-failed-reads":
        lines = [set_field(path, rows[len(rows) // 2], 1, str(2**31 - 1)),
                 set_field(path, rows[len(rows) * 3 // 4], 1, str(2**31 - 1))]
    else:
        lines = [set_field(path, coast[len(coast) * 2 // 3], 1, "0")]
    code, out, err = run(capsys, "analyze", "spindown", path, "--cpr", "1120", "--json")
    assert code == 0, err
    doc = json.loads(out)
    for line in lines:
        assert any(f"{path.name}:{line}: single-sample glitch excluded" in w for w in doc["warnings"]), line
    k, k_clean = doc["parameters"]["K"], json.loads(clean[1])["parameters"]["K"]
    assert k["value"] == pytest.approx(k_clean["value"], rel=2e-3)


def test_65535_in_a_terminal_table_is_flagged(rig, tmp_path: Path, capsys) -> None:
    path = copy(rig["terminal"], tmp_path)
    line = set_field(path, data_rows(path)[2], 0, "65535")
    code, out, err = run(capsys, "analyze", "terminal", path, "--K", "0.7", "--json")
    assert code == 0, err
    warnings = " ".join(json.loads(out)["warnings"])
    assert f"{path.name}:{line}" in warnings
    assert "65535" in warnings


# ---- outputs -------------------------------------------------------------------------------------


def test_characterize_refuses_to_overwrite_an_input_called_results_csv(tmp_path: Path, capsys) -> None:
    from motorlab.session.simulated import write_simulated_session

    write_simulated_session("neverest40", out_dir=tmp_path, units=1, seed=3, experiments=("lcr",))
    toml = tmp_path / "session.toml"
    lcr = next(tmp_path.glob("A/lcr*.csv"))
    target = tmp_path / "A" / "results.csv"
    lcr.rename(target)
    toml.write_text(toml.read_text().replace(lcr.name, "results.csv"))
    before = target.read_bytes()
    refused(capsys, "characterize", toml, "-o", tmp_path / "A", "--quiet", mentions="would overwrite the input")
    assert target.read_bytes() == before


def test_characterize_refuses_an_unknown_unit_in_a_header_before_any_analysis(tmp_path: Path, capsys) -> None:
    from motorlab.session.simulated import write_simulated_session

    write_simulated_session("neverest40", out_dir=tmp_path, units=1, seed=3, experiments=("lcr",))
    lcr = next(tmp_path.glob("A/lcr*.csv"))
    lcr.write_text(lcr.read_text().replace("DCR_ohm", "DCR_furlongs"))
    refused(capsys, "characterize", tmp_path / "session.toml", "-o", tmp_path / "out", "--quiet",
            mentions="DCR_furlongs")
    assert not (tmp_path / "out").exists()


def test_interrupted_simulate_leaves_no_partial_file(tmp_path: Path, monkeypatch, capsys) -> None:
    import motorlab.io.output as output

    def interrupted(src, dst):
        raise KeyboardInterrupt

    monkeypatch.setattr(output.os, "replace", interrupted)
    code, _, _ = run(capsys, "simulate", "lcr", "--motor", "neverest40", "-o", tmp_path / "lcr.csv")
    assert code == 130
    assert list(tmp_path.iterdir()) == []  # neither the file nor its temporary


# ---- the smaller items --------------------------------------------------------------------------


def test_digit_separators_are_not_numbers(rig, tmp_path: Path, capsys) -> None:
    path = copy(rig["terminal"], tmp_path)
    line = set_field(path, data_rows(path)[1], 0, "1_0")
    err = refused(capsys, "analyze", "terminal", path, "--K", "0.7", mentions="'1_0' is not a number")
    assert f"{path.name}:{line}" in err
    refused(capsys, "analyze", "terminal", rig["terminal"], "--K", "0_7", mentions="--K")
    refused(capsys, "demo", "--seed", "1_0", "-o", tmp_path / "demo",
            mentions="'1_0' is not a whole number")


def test_unknown_sysid_test_names_are_reported(rig, tmp_path: Path, capsys) -> None:
    path = tmp_path / "sysid.json"
    path.write_text(rig["sysid"].read_text().replace('"slow-backward"', '"slow-backwrd"'))
    code, out, err = run(capsys, "analyze", "feedforward", path, "--json")
    assert code == 0, err
    warnings = " ".join(json.loads(out)["warnings"])
    assert "'slow-backwrd' is not a test name" in warnings
    assert "did you mean 'slow-backward'" in warnings


def test_the_same_file_twice_is_refused(rig, capsys) -> None:
    refused(capsys, "analyze", "spindown", rig["spindown"], rig["spindown"], "--cpr", "1120", mentions="given twice")


def test_no_nan_percent_in_text() -> None:
    from motorlab.results import Estimate

    text = str(Estimate("Tf", 0.0, 0.001, "N*m"))
    assert "nan" not in text
    assert "? %" in text


def test_tune_says_when_ks_is_missing(tmp_path: Path, capsys) -> None:
    params = tmp_path / "p.json"
    params.write_text(json.dumps({"parameters": {"kS": {"value": None}, "kV": {"value": 1.0}, "kA": {"value": 0.1}}}))
    code, out, err = run(capsys, "tune", "velocity", "--params", params)
    assert code == 0, err
    assert "kS is not given (or not determined)" in out


def test_plan_refuses_a_megavolt(capsys) -> None:
    refused(capsys, "plan", "--motor", "neverest40", "--voltage", "1e6", mentions="nominal")


def test_identify_says_when_given_r_and_k_are_not_used(rig, capsys) -> None:
    code, out, err = run(capsys, "analyze", "identify", rig["transient"], "--cpr", "1120", "--R", "2", "--json")
    assert code == 0, err
    assert any("the given R = 2" in w and "was not used" in w for w in json.loads(out)["warnings"])


def test_the_same_file_twice_is_refused_in_every_analysis(rig, tmp_path: Path, capsys) -> None:
    """Its rows would count twice (torque: 22 points from 11); spindown and spinup refused it before."""
    for experiment, options in (("lcr", ()), ("terminal", ("--K", "0.7"))):
        path = copy(rig[experiment], tmp_path)
        refused(capsys, "analyze", experiment, path, path, *options, mentions="given twice")


def test_feedforward_k_without_r_is_refused(rig, capsys) -> None:
    refused(capsys, "analyze", "feedforward", rig["sysid"], "--K", "5", mentions="--R")


def test_absurd_plan_and_tune_options_get_messages_that_name_them(capsys) -> None:
    refused(capsys, "plan", "--motor", "neverest40", "--free-speed", "1e308", mentions="free speed")
    code, out, err = run(capsys, "tune", "position", "--kv", "1", "--ka", "0.1", "--step", "1e308")
    assert code == 0, err
    assert "still travelling" in out + err  # not "Coulomb friction holds it" with kS = 0
    assert "Coulomb" not in out + err
