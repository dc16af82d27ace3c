"""``motorlab simulate ...`` through ``motorlab.cli.main``."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from motorlab.cli import main
from motorlab.io.csv_table import read_csv
from motorlab.io.ftc import read_ftc_log


def test_simulate_spindown_split(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "testFile.txt"
    code = main(["simulate", "spindown", "--motor", "NeveRest 40", "--unit-seed", "1", "--noise-seed", "3",
                 "--on-time", "5", "--coast-time", "5", "--split", "-o", str(out)])
    assert code == 0
    assert "unit B" in capsys.readouterr().out
    rec = read_ftc_log([out, tmp_path / "testFile2.txt"], cpr=1120)
    assert rec.time[-1] == pytest.approx(10.2, abs=0.15)
    truth = json.loads((tmp_path / "truth.json").read_text())["runs"]["testFile.txt"]
    assert truth["unit"] == "B"
    assert truth["noise_seed"] == 3
    assert truth["settings"]["on_time"] == 5.0


def test_simulate_lists_and_units(tmp_path: Path) -> None:
    out = tmp_path / "terminal.csv"
    assert main(["simulate", "terminal", "--motor", "neverest20", "--currents", "250 mA,0.3,0.35",
                 "-o", str(out)]) == 0
    assert len(read_csv(out)) == 3
    truth = json.loads((tmp_path / "truth.json").read_text())["runs"]["terminal.csv"]
    assert truth["settings"]["currents"] == pytest.approx([0.25, 0.3, 0.35])
    assert main(["simulate", "lcr", "--motor", "neverest20", "--positions", "4", "-o", str(tmp_path / "l.csv")]) == 0
    assert len(read_csv(tmp_path / "l.csv")) == 4


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["simulate", "lcr", "--motor", "nonsense"], "unknown motor"),
        (["simulate", "spinup", "--motor", "neverest40", "--current", "-0.5"], "negative"),
        (["simulate", "torque", "--motor", "neverest40", "--currents", "1,-2"], "negative"),
        (["simulate", "spindown", "--motor", "neverest40", "--voltage", "18"], "INA219"),
    ],
)
def test_simulate_errors_are_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str], argv: list[str],
                                      message: str) -> None:
    code = main([*argv, "-o", str(tmp_path / "x.txt")])
    err = capsys.readouterr().err
    assert code == 2
    assert err.count("\n") == 1
    assert message in err
    assert err.startswith("motorlab: error:")
    assert not (tmp_path / "x.txt").exists()


def test_simulate_bad_option_exits_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as info:
        main(["simulate", "lcr", "--motor", "neverest40", "--positions", "zero", "-o", str(tmp_path / "x.csv")])
    assert info.value.code == 2
    assert capsys.readouterr().err.count("\n") == 1


def test_simulate_session_is_wired(tmp_path: Path) -> None:
    out = tmp_path / "session"
    assert main(["simulate", "session", "--motor", "neverest20", "--units", "1", "-o", str(out)]) == 0
    assert (out / "session.toml").is_file()
    runs = json.loads((out / "A" / "truth.json").read_text())["runs"]
    assert all(run["unit"] == "A" for run in runs.values())


def test_simulate_session_with_a_worn_unit(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """``--worn B --wear 2``: unit B's true b is doubled; the session's notes say so; bad units refused."""
    out = tmp_path / "session"
    argv = ["simulate", "session", "--motor", "neverest40", "--units", "2", "-o", str(out), "--worn", "B"]
    assert main(argv) == 0
    healthy = tmp_path / "healthy"
    assert main(["simulate", "session", "--motor", "neverest40", "--units", "2", "-o", str(healthy)]) == 0

    def true_b(folder: Path, unit: str) -> float:
        runs = json.loads((folder / unit / "truth.json").read_text())["runs"]
        return float(next(iter(runs.values()))["params"]["b"])

    assert "b × 2" in (out / "session.toml").read_text()
    assert true_b(out, "B") == pytest.approx(2 * true_b(healthy, "B"))
    assert true_b(out, "A") == pytest.approx(true_b(healthy, "A"))
    capsys.readouterr()
    assert main(["simulate", "session", "--motor", "neverest40", "--units", "2", "-o", str(tmp_path / "x"),
                 "--worn", "Z"]) == 2
    assert "no unit 'Z'" in capsys.readouterr().err
