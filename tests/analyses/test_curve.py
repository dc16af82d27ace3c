"""``motorlab analyze curve``: a steady-state motor curve → K, Kt, R, the free current, friction (issue 23)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from motorlab import cli
from motorlab.analyses.curve import curve
from motorlab.errors import LogFormatError, OptionError
from motorlab.io import read_csv, write_csv
from motorlab.recording import Recording

V = 12.0
RPM = 30.0 / math.pi


def _rows_implied(rec: Recording, voltage: float) -> dict[str, float]:
    """K, Kt and R from the curve's own free (largest speed) and stall (speed 0) rows."""
    speed, torque, current = rec["speed"], rec["torque"], rec["current"]
    free, stall = int(np.argmax(speed)), int(np.argmin(speed))
    r = voltage / current[stall]
    return {"R": r, "K": (voltage - r * current[free]) / speed[free],
            "Kt": (torque[stall] - torque[free]) / (current[stall] - current[free])}


@pytest.mark.parametrize("motor", ["am-9015", "bag", "mini-cim"])
def test_real_vex_curves_match_their_free_and_stall_rows(dyno_dir: Path, motor: str) -> None:
    """Judged: each curve's K, Kt and R within 2 % of what its own free and stall rows imply."""
    (path,) = dyno_dir.glob(f"{motor}-motor-curve-data-*.csv")
    rec = read_csv(path)
    result = curve(rec, voltage=V)
    implied = _rows_implied(rec, V)
    for name in ("K", "Kt", "R"):
        assert result[name].value == pytest.approx(implied[name], rel=0.02), name
    # the free current is the file's free-speed row; the ratio is what the two constants say
    assert result["I_free"].value == pytest.approx(rec["current"][np.argmax(rec["speed"])], rel=0.02)
    assert result["Kt_over_K"].value == pytest.approx(implied["Kt"] / implied["K"], rel=0.02)
    assert not result["b"].determined
    assert not result["Tf"].determined
    assert any("straight lines" in w for w in result.warnings)  # VEX drew the rows between two points


def test_vex_ratios_as_measured(dyno_dir: Path) -> None:
    """Kt/K of the three bare motors from their 12 V curves (AM 9015 0.70, BAG 1.01, mini-CIM 0.86)."""
    ratios = {}
    for motor in ("am-9015", "bag", "mini-cim"):
        (path,) = dyno_dir.glob(f"{motor}-motor-curve-data-*.csv")
        ratios[motor] = curve(read_csv(path), voltage=V)["Kt_over_K"].value
    assert ratios["am-9015"] == pytest.approx(0.697, abs=0.005)
    assert ratios["bag"] == pytest.approx(1.010, abs=0.005)
    assert ratios["mini-cim"] == pytest.approx(0.860, abs=0.005)


TRUTH = {"K": 0.0190, "R": 0.134, "Kt": 0.0165, "Tf": 0.045, "b": 2.0e-5}


def _synthetic(seed: int, voltages: tuple[float, ...] = (V,), rows: int = 40) -> list[Recording]:
    """Steady states of the motor model at each voltage, with meter noise on current, torque and speed."""
    rng = np.random.default_rng(seed)
    out = []
    k, r, kt, tf, b = (TRUTH[n] for n in ("K", "R", "Kt", "Tf", "b"))
    for volts in voltages:
        free = (kt * volts / r - tf) / (kt * k / r + b)  # speed where Kt·I = Tf + b·ω
        speed = np.linspace(0.0, free, rows)
        current = (volts - k * speed) / r
        torque = kt * current - tf - b * speed
        out.append(Recording(
            time=np.arange(rows, dtype=float),
            signals={"speed": speed + rng.normal(0, 0.5, rows), "current": current + rng.normal(0, 0.02, rows),
                     "torque": torque + rng.normal(0, 0.002, rows), "voltage": np.full(rows, volts)},
            source=f"synthetic-{volts:g}V.csv"))
    return out


@pytest.mark.parametrize("seed", range(5))
def test_round_trip_one_voltage(seed: int) -> None:
    """K and R within 3 standard errors; the slope is Kt + b·R/K (viscous friction folded in); I₀ as modelled."""
    result = curve(_synthetic(seed))
    k, r, kt, tf, b = (TRUTH[n] for n in ("K", "R", "Kt", "Tf", "b"))
    expected = {"K": k, "R": r, "Kt": kt + b * r / k}
    for name, truth in expected.items():
        est = result[name]
        assert abs(est.value - truth) < 3 * est.stderr, (name, est, truth)
    free_current = (tf + b * V / k) / (kt + b * r / k)
    assert abs(result["I_free"].value - free_current) < 3 * result["I_free"].stderr
    assert not result["b"].determined


@pytest.mark.parametrize("seed", range(3))
def test_a_curve_of_every_sample_is_fitted_as_means_of_neighbouring_rows(seed: int) -> None:
    """A dynamometer that logs every sample (50,000 rows) is reduced to MAX_ROWS means, says so, and keeps
    K, R and the slope within 3 standard errors of the truth."""
    from motorlab.analyses.curve import MAX_ROWS

    result = curve(_synthetic(seed, rows=50_000))
    assert any(f"50,000 rows fitted as {math.ceil(50_000 / 3):,} means of 3 neighbouring rows" in w
               for w in result.warnings)
    assert result.n_points <= MAX_ROWS
    k, r, kt, b = (TRUTH[n] for n in ("K", "R", "Kt", "b"))
    for name, truth in {"K": k, "R": r, "Kt": kt + b * r / k}.items():
        assert abs(result[name].value - truth) < 3 * result[name].stderr, (name, result[name], truth)


def test_round_trip_several_voltages_separates_friction() -> None:
    """Curves at 6, 9 and 12 V: Kt, Tf and b each determined, truth within 3 standard errors, over seeds."""
    inside = 0
    for seed in range(10):
        result = curve(_synthetic(seed, voltages=(6.0, 9.0, 12.0)))
        for name in ("K", "R", "Kt", "Tf", "b"):
            est = result[name]
            assert est.determined, name
            assert abs(est.value - TRUTH[name]) < 4 * est.stderr, (seed, name, est)
            inside += abs(est.value - TRUTH[name]) < 2 * est.stderr
    assert inside >= 0.85 * 50  # ~95 % of 2-standard-error intervals hold the truth


def test_refusals(tmp_path: Path) -> None:
    path = tmp_path / "torque_only.csv"
    path.write_text("Speed (RPM),Torque (N·m)\n0,1.4\n5000,0\n", encoding="latin-1")
    with pytest.raises(LogFormatError, match=r"torque_only.csv: this curve has no current \(it has: speed, torque\)"):
        curve(read_csv(path), voltage=V)
    ok = tmp_path / "ok.csv"
    write_csv(ok, {"speed_rpm": [0.0, 3000, 6000], "torque_Nm": [1.4, 0.7, 0.0], "current_A": [89.0, 46, 3],
                   "voltage_V": [12.0, 12, 12]})
    with pytest.raises(OptionError, match="leave out --voltage"):
        curve(read_csv(ok), voltage=V)
    with pytest.raises(OptionError, match="positive"):
        curve(read_csv(ok), voltage=-1.0)
    nov = tmp_path / "nov.csv"
    write_csv(nov, {"speed_rpm": [0.0, 3000, 6000], "torque_Nm": [1.4, 0.7, 0.0], "current_A": [89.0, 46, 3]})
    with pytest.raises(LogFormatError, match="--voltage"):
        curve(read_csv(nov))


def _run(args: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    try:
        code = cli.main(args)
    except SystemExit as exc:
        code = int(exc.code or 0)
    out = capsys.readouterr()
    return code, out.out, out.err


def test_cli(dyno_dir: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = dyno_dir / "bag-motor-curve-data-20151207.csv"
    figure = tmp_path / "curve.png"
    code, out, _err = _run(["analyze", "curve", str(path), "--voltage", "12 V", "--json", "--plot", str(figure)],
                           capsys)
    assert code == 0
    assert '"Kt_over_K"' in out
    assert figure.stat().st_size > 10_000
    code, out, _err = _run(["analyze", "curve", str(path), "--json"], capsys)  # 12 V = supplied power / current
    assert code == 0
    assert "supplied power / current, 12 V" in out
    no_power = tmp_path / "no_power.csv"
    no_power.write_bytes(b"Speed (RPM),Torque (N\xb7m),Current (A)\r\n0,0.43,52.6\r\n6000,0.2,25\r\n13000,0,1.8\r\n")
    code, _out, err = _run(["analyze", "curve", str(no_power)], capsys)
    assert code == 2
    assert err.count("\n") == 1
    assert "--voltage" in err
    torque_only = tmp_path / "t.csv"
    torque_only.write_text("Time,Torque 6V (N · m)\n0,0.3\n1,0.29\n2,0.28\n", encoding="latin-1")
    code, _out, err = _run(["analyze", "curve", str(torque_only), "--voltage", "6"], capsys)
    assert code == 2
    assert err.count("\n") == 1
    assert "no current" in err
    assert "Traceback" not in err
