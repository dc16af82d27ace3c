"""``motorlab demo`` end to end, and ``motorlab characterize`` on good and bad sessions."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from motorlab.cli import main


@pytest.fixture(scope="module")
def demo(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str, Any]:
    """One ``motorlab demo`` (two units, seed 1), run once for the tests that read it: its folder, what it printed
    and the characterisation whose table it printed (kept as the demo hands it to its table)."""
    import contextlib
    import io

    from motorlab.cli import demo as demo_module

    out = tmp_path_factory.mktemp("demo") / "demo"
    tabled: list[Any] = []
    table = demo_module.print_experiment_table
    printed = io.StringIO()
    with pytest.MonkeyPatch.context() as patch, contextlib.redirect_stdout(printed):
        patch.setattr(demo_module, "print_experiment_table", lambda result: (tabled.append(result), table(result)))
        assert main(["demo", "-o", str(out), "--units", "2", "--seed", "1"]) == 0
    assert len(tabled) == 1
    return out, printed.getvalue(), tabled[0]


def test_demo_writes_report_and_prints_table(demo: tuple[Path, str, Any]) -> None:
    out, printed, _ = demo
    assert "truth" in printed
    assert "σ" in printed
    assert "velocity loop" in printed  # the gains of the demo motor
    for name in ("report.html", "results.json", "results.csv", "step_response.png", "session/session.toml"):
        assert (out / name).is_file(), name
    doc = json.loads((out / "results.json").read_text())
    assert list(doc["units"]) == ["A", "B"]
    for unit in doc["units"].values():
        k = unit["parameters"]["K"]
        assert abs(k["value"] - unit["truth"]["K"]) < 4 * k["stderr"]
    html = (out / "report.html").read_text()
    assert html.count("data:image/png;base64,") >= 10


def test_demo_table_shows_every_analysis_against_the_truth(demo: tuple[Path, str, Any]) -> None:
    """The table the demo printed, from the characterisation it printed it of (the demo's own run)."""
    import re

    from motorlab.cli.demo import experiment_rows
    from motorlab.experiments import all_experiments

    rows = experiment_rows(demo[2])
    # every analysis the virtual rig can run is in the demo (a dynamometer's motor curve has no rig run)
    assert {exp for exp, *_ in rows} == {name for name, exp in all_experiments().items() if exp.rig is not None}
    distances = [float(m.group(1)) for *_, cells in rows for c in cells if (m := re.search(r"\(([+-][\d.]+)σ\)", c))]
    assert len(distances) >= 25
    # Honest error bars: the truth within 3 standard errors for (nearly) every compared estimate.
    assert sum(abs(z) <= 3 for z in distances) >= 0.9 * len(distances)


def test_characterize_cli(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from motorlab.session.simulated import write_simulated_session

    toml = write_simulated_session("neverest40", out_dir=tmp_path / "s", units=1, experiments=("lcr",))
    assert main(["characterize", str(toml), "-o", str(tmp_path / "r"), "--no-report"]) == 0
    assert (tmp_path / "r" / "results.csv").is_file()
    assert not (tmp_path / "r" / "report.html").exists()
    capsys.readouterr()
    # Bad input: one line naming the file, the line and the key; exit 2; nothing analysed.
    text = toml.read_text().replace('files = ["A/lcr.csv"]', 'files = ["A/lcr.csv"]\nfrequency = "1 kV"')
    bad = tmp_path / "s" / "bad.toml"
    bad.write_text(text)
    line = text.splitlines().index('frequency = "1 kV"') + 1
    assert main(["characterize", str(bad), "-o", str(tmp_path / "bad")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"motorlab: error: {bad}:{line}: units.A.lcr.frequency:")
    assert len(err.splitlines()) == 1
    assert not (tmp_path / "bad").exists()
