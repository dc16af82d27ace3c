"""motorlab simulate stall and analyze stall from the command line; the report's thermal section."""

from __future__ import annotations

import json
from pathlib import Path

from motorlab import cli
from motorlab.io.csv_table import read_csv


def test_virtual_run_fit_and_forecast(tmp_path: Path, capsys) -> None:
    run = tmp_path / "run.csv"
    assert cli.main(["simulate", "stall", "--motor", "neverest40", "--voltage", "6", "--duration", "90",
                     "-o", str(run)]) == 0
    capsys.readouterr()
    assert cli.main(["analyze", "stall", str(run), "--json"]) == 0
    fit = json.loads(capsys.readouterr().out)
    assert fit["parameters"]["R"]["unit"] == "ohm"
    assert "25 °C" in fit["details"]["R_temperature"]
    fit_path = tmp_path / "fit.json"
    fit_path.write_text(json.dumps(fit))
    out = tmp_path / "forecast.csv"
    assert cli.main(["simulate", "stall", "--params", str(fit_path), "--voltage", "12", "--duration", "30",
                     "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert "reaches 150 °C after" in text
    assert "R hot against cold" in text
    assert "warning: " in text
    assert "extrapolat" in text
    header = next(line for line in out.read_text().splitlines() if not line.startswith("#"))
    assert header == "time_s,current_A,torque_Nm,winding_temperature_C,case_temperature_C"
    assert "2 standard errors of the fit" in text
    rec = read_csv(out)
    assert rec["current"][0] > rec["current"][-1]
    assert cli.main(["simulate", "stall", "--params", str(fit_path), "--voltage", "12", "--duration", "30",
                     "-o", str(tmp_path / "again.csv"), "--json"]) == 0
    final = json.loads(capsys.readouterr().out)["final"]
    assert final["current_low_A"] < final["current_A"] < final["current_high_A"]  # a band, not a line


def test_refusals_are_one_line(tmp_path: Path, capsys) -> None:
    notfit = tmp_path / "other.json"
    notfit.write_text(json.dumps({"experiment": "lcr"}))
    code = cli.main(["simulate", "stall", "--params", str(notfit), "-o", str(tmp_path / "f.csv")])
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert "\n" not in err
    assert "not a stall fit" in err
    code = cli.main(["simulate", "stall", "-o", str(tmp_path / "f.csv")])
    assert code == 2
    assert "--params" in capsys.readouterr().err


def test_report_has_a_thermal_section(tmp_path: Path) -> None:
    from motorlab.report.document import render_report
    from motorlab.session.characterize import characterize
    from motorlab.session.simulated import write_simulated_session
    from motorlab.session.spec import load_session

    toml = write_simulated_session("neverest40", out_dir=tmp_path / "s", units=1, seed=1,
                                   experiments=("lcr", "stall"))
    html = render_report(characterize(load_session(toml), control=False, figures=False), figures=False)
    assert '<section id="thermal">' in html
    assert "stalled at 12 V until 150 °C" in html


def test_a_motors_exports_as_they_come_and_a_run_no_network_fits(tmp_path: Path, capsys, dyno_dir: Path) -> None:
    """`analyze stall cim-*.csv`: the runs fitted, the curve taken as the back-EMF bound, the peak-power export named
    and left out; each run's K beside the joint one. The CIM's 4 V run fitted on its first 120 s alone: no single
    network fits it, and `simulate stall` forecasts it (from the population's winding, says so) instead of refusing."""
    files = sorted(str(p) for p in dyno_dir.glob("cim-*.csv"))
    assert cli.main(["analyze", "stall", *files, "--json"]) == 0
    fit = json.loads(capsys.readouterr().out)
    text = " ".join(fit["warnings"])
    assert "cim-motor-curve-data-20151104.csv: a motor curve, not a locked-rotor run" in text
    assert "cim-peak-power-data-20151104.csv" in text
    assert "left out" in text
    assert "each run's K" in text
    assert fit["parameters"]["K"]["value"] <= 0.0211 + fit["parameters"]["K"]["stderr"]
    lone = tmp_path / "lone.json"
    assert cli.main(["analyze", "stall", str(dyno_dir / "cim-locked-rotor-data-4v-20151104.csv"), "--until", "120",
                     "--json"]) == 0
    lone.write_text(capsys.readouterr().out)
    assert cli.main(["simulate", "stall", "--params", str(lone), "--voltage", "4", "--duration", "300",
                     "-o", str(tmp_path / "f.csv")]) == 0
    assert "population's winding" in capsys.readouterr().out
