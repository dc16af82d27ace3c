"""Terminal-velocity analysis: b and Tf from steady speeds at constant currents."""

from __future__ import annotations

import argparse
import math

import numpy as np
import pytest

from motorlab.analyses.terminal import terminal
from motorlab.cli.analyze import add_arguments, from_cli
from motorlab.errors import FitError, LogFormatError, OptionError
from motorlab.recording import Recording

CPR = 28.0
K, B, TF = 0.0185, 1e-5, 2e-3


def rows(seed: int, currents=(0.2, 0.25, 0.3, 0.35, 0.4, 0.45)) -> Recording:
    """Steady rows: the supply's ammeter (1 mA, ±0.2 %) and the scope's frequency counter (5 digits)."""
    rng = np.random.default_rng(seed)
    i_true = np.asarray(currents, dtype=float)
    omega = (K * i_true - TF) / B
    f = omega * CPR / (8 * math.pi) * (1 + rng.normal(0, 2e-4, i_true.size))
    f = np.array([round(v, 4 - math.floor(math.log10(v))) for v in f])
    i_read = np.round(i_true * (1 + rng.uniform(-2e-3, 2e-3, i_true.size)) / 1e-3) * 1e-3
    return Recording(np.arange(i_true.size, dtype=float), {"current": i_read, "frequency": f}, source="rows.csv")


def test_round_trip_several_currents() -> None:
    covered = {"b": 0, "Tf": 0}
    for seed in range(10):
        result = terminal(rows(seed), torque_constant=K, cpr=CPR)
        for name, truth, rel in (("b", B, 0.06), ("Tf", TF, 0.12)):
            est = result[name]
            assert est.value == pytest.approx(truth, rel=rel), (seed, name)
            covered[name] += abs(est.value - truth) <= 3 * est.stderr
        assert result.correlation_names == ["b", "Tf"]
        assert result.panels[0].x_label == "speed [rad/s]"
    assert min(covered.values()) >= 9


def test_k_uncertainty_scales_both() -> None:
    data = rows(20)
    exact = terminal(data, torque_constant=K, cpr=CPR)
    loose = terminal(data, torque_constant=K, cpr=CPR, torque_constant_stderr=0.03 * K)
    assert loose["b"].relative_error == pytest.approx(math.hypot(exact["b"].relative_error, 0.03), rel=1e-6)


def test_single_row_folds_coulomb_into_b() -> None:
    one = rows(21, currents=(0.3,))
    result = terminal(one, torque_constant=K, cpr=CPR, current_stderr=1e-3)
    omega = (K * 0.3 - TF) / B
    assert result["b"].value == pytest.approx(K * 0.3 / omega, rel=0.01)  # > B: Tf folded in
    assert "Tf" not in result.parameters
    assert any("folded into b" in w for w in result.warnings)
    given = terminal(one, torque_constant=K, cpr=CPR, coulomb_friction=TF)
    assert given["b"].value == pytest.approx(B, rel=0.03)


def test_speed_conversion_uses_four_counts_per_cycle() -> None:
    # ω = 2π·4·f/cpr: f = 100 Hz on a 28-count encoder is 89.76 rad/s.
    data = Recording(np.arange(1.0), {"current": np.array([0.3]), "frequency": np.array([100.0])})
    result = terminal(data, torque_constant=K, cpr=CPR)
    assert result["b"].value == pytest.approx(K * 0.3 / (2 * math.pi * 4 * 100 / 28))


def test_bad_input() -> None:
    data = rows(22)
    with pytest.raises(OptionError, match="cpr"):
        terminal(data, torque_constant=K)
    with pytest.raises(OptionError):
        terminal(data, torque_constant=-1.0, cpr=CPR)
    # A row at zero speed (stiction held the shaft, K·I ≤ Tf) is left out with a warning ...
    data.signals["frequency"][2] = 0.0
    stuck = terminal(data, torque_constant=K, cpr=CPR)
    assert stuck.n_points == len(data) - 1
    assert any("zero speed" in w and "rows 3 " in w for w in stuck.warnings)
    # ... but with no row turning there is nothing to fit.
    still = Recording(np.arange(2.0), {"current": np.array([0.1, 0.2]), "frequency": np.zeros(2)}, source="rows.csv")
    with pytest.raises(FitError, match=r"rows\.csv: the motor did not turn"):
        terminal(still, torque_constant=K, cpr=CPR)
    data.signals["frequency"][2] = math.nan
    with pytest.raises(LogFormatError, match=r"rows\.csv"):
        terminal(data, torque_constant=K, cpr=CPR)


def test_cli_reads_csv(tmp_path) -> None:
    data = rows(23)
    path = tmp_path / "terminal.csv"
    path.write_text("current_A,frequency_Hz\n" + "".join(
        f"{i:.3f},{f}\n" for i, f in zip(data["current"], data["frequency"], strict=True)))
    parser = argparse.ArgumentParser()
    add_arguments(parser, "terminal")
    result = from_cli("terminal", [str(path)], parser.parse_args(["--cpr", "28", "--K", "0.0185 N*m/A"]))
    assert result["b"].value == pytest.approx(B, rel=0.06)
    assert result["Tf"].value == pytest.approx(TF, rel=0.12)


def test_virtual_rig_round_trip(tmp_path) -> None:
    """The rig's default currents (raised where they do not turn the unit, as the seed says): b within
    6 %, Tf within 12 %, the truth within 3 standard errors in at least 90 % of the units."""
    from motorlab.rig import VirtualRig

    runs = [(motor, seed) for motor in ("neverest40", "gobilda5202_19", "hdhex40") for seed in range(4)]
    inside = {"b": 0, "Tf": 0}
    for k, (motor, seed) in enumerate(runs):
        run = VirtualRig(motor, unit_seed=seed, noise_seed=seed).terminal(tmp_path / f"terminal{k}.csv")
        expected = run.truth["expected"]
        assert min(expected["speeds"]) > 0  # every default setting turns the unit
        parser = argparse.ArgumentParser()
        add_arguments(parser, "terminal")
        result = from_cli("terminal", [str(run.paths[0])], parser.parse_args(["--K", str(expected["K"])]))
        for name, rel in (("b", 0.06), ("Tf", 0.12)):
            assert result[name].value == pytest.approx(expected[name], rel=rel), (motor, seed, name)
            inside[name] += abs(result[name].value - expected[name]) <= 3 * result[name].stderr
    for name, count in inside.items():
        assert count >= 0.9 * len(runs), (name, count)


def test_single_row_uncertainty_is_unknown_without_the_readings_errors() -> None:
    """One row fits b = K·I/ω exactly: its stderr was reported as 0 ('± 0'); now NaN with a warning,
    or the given reading uncertainties propagated to first order."""
    one = Recording(np.arange(1.0), {"current": np.array([0.3]), "frequency": np.array([100.0])}, source="one.csv")
    bare = terminal(one, torque_constant=K, cpr=CPR)
    assert math.isnan(bare["b"].stderr)
    assert any("--current-stderr" in w for w in bare.warnings)
    assert any("folded into b" in w for w in bare.warnings)
    i_se, f_se, k_se = 1e-3, 0.05, 2e-4
    given = terminal(one, torque_constant=K, cpr=CPR, current_stderr=i_se, frequency_stderr=f_se,
                     torque_constant_stderr=k_se)
    b = given["b"].value
    expected = b * math.sqrt((i_se / 0.3) ** 2 + (f_se / 100.0) ** 2 + (k_se / K) ** 2)
    assert given["b"].stderr == pytest.approx(expected, rel=1e-9)
    speeds = Recording(np.arange(1.0), {"current": np.array([0.3]), "speed": np.array([90.0])})
    with pytest.raises(OptionError, match="frequency"):
        terminal(speeds, torque_constant=K, frequency_stderr=0.1)


def test_the_same_current_in_every_row_cannot_separate_b_and_tf() -> None:
    """Equal currents at different speeds gave b = −7e-19 ± 0 (a regression on a constant): now the
    rows are repeats of one operating point, said so, and b's scatter is its uncertainty."""
    rng = np.random.default_rng(3)
    f = 1000.0 * (1 + rng.normal(0, 0.01, 5))
    data = Recording(np.arange(5.0), {"current": np.full(5, 0.3), "frequency": f}, source="same.csv")
    result = terminal(data, torque_constant=K, cpr=CPR)
    assert "Tf" not in result.parameters
    b = result["b"]
    per_row = K * 0.3 / (2 * math.pi * 4 * f / CPR)
    assert b.value == pytest.approx(K * 0.3 / np.mean(2 * math.pi * 4 * f / CPR))
    assert b.stderr == pytest.approx(np.std(per_row, ddof=1) / math.sqrt(5), rel=1e-9)
    assert any("same current" in w and "cannot be separated" in w for w in result.warnings)
    # Exact repeats leave no scatter: the uncertainty is unknown without --current-stderr.
    twins = Recording(np.arange(3.0), {"current": np.full(3, 0.3), "frequency": np.full(3, 1000.0)})
    assert math.isnan(terminal(twins, torque_constant=K, cpr=CPR)["b"].stderr)


def test_rows_exactly_on_a_line_do_not_claim_zero_uncertainty() -> None:
    omega = np.array([100.0, 200.0, 300.0, 400.0])
    current = (B * omega + TF) / K
    data = Recording(np.arange(4.0), {"current": current, "speed": omega}, source="exact.csv")
    result = terminal(data, torque_constant=K)
    assert result["b"].value == pytest.approx(B)
    assert math.isnan(result["b"].stderr)
    assert any("exactly on a straight line" in w for w in result.warnings)


def test_absurd_torque_constant_or_cpr_is_refused() -> None:
    with pytest.raises(OptionError, match="--K"):
        terminal(rows(24), torque_constant=1e300, cpr=CPR)
    with pytest.raises(OptionError, match="--cpr"):
        terminal(rows(24), torque_constant=K, cpr=1e-300)
