"""Torque constant from lever-arm scale readings: round trips, offsets, polarity, bad input."""

from __future__ import annotations

import numpy as np
import pytest

from motorlab.analyses.torque import torque
from motorlab.errors import FitError, LogFormatError, OptionError
from motorlab.io import read_csv, write_csv
from motorlab.recording import Recording
from motorlab.units import STANDARD_GRAVITY

K_TRUE = 0.105  # [N·m/A], about an Aerotech 1135 (seed 2)
ARM = 0.1  # [m]


def scale_readings(seed: int, *, tare: float = 0.0, stiction: float = 0.002, sign: float = 1.0) -> Recording:
    """Scale readings [kg] at 0…4 A: τ = K·i plus a random stiction torque (dither leaves a little),
    read on a postage scale with 1 g resolution; ``tare`` [kg] is a scale that was not zeroed."""
    rng = np.random.default_rng(seed)
    current = np.repeat(np.arange(0.5, 4.01, 0.5), 2)
    tau = K_TRUE * current + rng.uniform(-stiction, stiction, current.size)
    mass = np.round((tau / (STANDARD_GRAVITY * ARM) + tare) * 1000) / 1000
    return Recording(np.arange(current.size, dtype=float), {"current": sign * current, "mass": mass},
                     metadata={"arm_m": ARM}, source=f"torque-{seed}.csv")


def test_round_trip_over_seeds():
    seeds = range(12)
    inside = 0
    for seed in seeds:
        result = torque(scale_readings(seed))
        k = result["K"]
        assert k.value == pytest.approx(K_TRUE, rel=0.01)
        inside += abs(k.value - K_TRUE) <= 3 * k.stderr
        assert result.r2 > 0.999
        assert not result.warnings
        assert result["tau0"].unit == "N*m"
    assert inside >= 0.9 * len(seeds)


def test_tare_error_shows_as_an_offset_with_a_warning():
    result = torque(scale_readings(1, tare=0.02))
    assert result.value("tau0") == pytest.approx(0.02 * STANDARD_GRAVITY * ARM, rel=0.1)
    assert result.value("K") == pytest.approx(K_TRUE, rel=0.01)
    assert any("tau0" in w for w in result.warnings)


def test_reversed_polarity_reports_the_magnitude():
    result = torque(scale_readings(2, sign=-1.0))
    assert result.value("K") == pytest.approx(K_TRUE, rel=0.01)
    assert any("polarity" in w for w in result.warnings)


def test_arm_option_file_in_grams_and_arm_uncertainty(tmp_path):
    rec = scale_readings(4)
    path = tmp_path / "torque.csv"
    write_csv(path, {"current_A": rec["current"], "mass_g": 1000 * rec["mass"]})
    from_file = torque(read_csv(path), arm=ARM)
    assert from_file.value("K") == pytest.approx(torque(rec).value("K"), rel=1e-9)
    wider = torque(read_csv(path), arm=ARM, arm_stderr=0.001)
    assert wider["K"].stderr > from_file["K"].stderr
    assert wider["K"].stderr >= 0.01 * wider.value("K")
    # The same readings on twice the arm mean twice the torque.
    assert torque(read_csv(path), arm=2 * ARM).value("K") == pytest.approx(2 * from_file.value("K"), rel=1e-9)


def test_torque_column_needs_no_arm():
    current = np.array([1.0, 2.0, 3.0, 4.0])
    result = torque(Recording(np.arange(4.0), {"current": current, "torque": 0.3 * current + 0.01}))
    assert result.value("K") == pytest.approx(0.3, rel=1e-12)
    assert result.value("tau0") == pytest.approx(0.01, abs=1e-12)


def test_bad_input():
    rec = scale_readings(0)
    rec.metadata.clear()
    with pytest.raises(OptionError, match="--arm"):
        torque(rec)
    with pytest.raises(LogFormatError, match="mass"):
        torque(Recording(np.arange(3.0), {"current": np.ones(3)}, source="no-mass.csv"))
    with pytest.raises(FitError):
        torque(Recording(np.arange(1.0), {"current": np.ones(1), "mass": np.ones(1)}), arm=0.1)
    with pytest.raises(FitError, match="same current"):
        torque(Recording(np.arange(3.0), {"current": np.ones(3), "mass": np.ones(3)}), arm=0.1)
    with pytest.raises(LogFormatError, match="finite"):
        torque(Recording(np.arange(3.0), {"current": np.array([1.0, np.nan, 2]), "mass": np.ones(3)}), arm=0.1)


def test_virtual_rig_files(tmp_path):
    """Scale readings written by the virtual rig at its default procedure (a sweep up and back down
    with dither, 1 g scale, DMM currents): K within 1 % and the truth within 3 standard errors in at
    least 90 % of the units; the friction the stalled shaft holds is fitted as a hysteresis."""
    from motorlab.rig import VirtualRig

    inside = held = 0
    runs = [(motor, seed) for motor in ("neverest40", "corehex", "gobilda5202_19", "gobilda5202_188")
            for seed in range(3)]
    for motor, seed in runs:
        run = VirtualRig(motor, unit_seed=seed, noise_seed=seed).torque(tmp_path / f"t-{motor}-{seed}.csv")
        result = torque(read_csv(run.paths[0]))  # arm from '# arm_m:'
        k_true = run.truth["expected"]["K"]
        est = result["K"]
        assert est.value == pytest.approx(k_true, rel=0.01), (motor, seed)
        inside += abs(est.value - k_true) <= 3 * est.stderr
        # The rig's held friction is uniform in [0, 0.1·Tf]: the half-width of the loop is its mean.
        h_true = 0.05 * run.truth["params"]["Tf"]
        held += abs(result.value("tau_h") - h_true) <= 3 * result["tau_h"].stderr
        assert result.details["approach"] == [1] * 6 + [-1] * 5
    assert inside >= 0.9 * len(runs)
    assert held >= 0.9 * len(runs)


def test_hysteresis_is_fitted_only_with_both_directions():
    # One direction: the friction is a constant offset, folded into tau0; no tau_h.
    rec = scale_readings(5)
    order = np.argsort(rec["current"], kind="stable")
    up = Recording(np.arange(order.size, dtype=float), {"current": rec["current"][order], "mass": rec["mass"][order]},
                   metadata={"arm_m": ARM})
    assert "tau_h" not in torque(up)
    assert not torque(up).details["hysteresis_fitted"]
    # Up then down, the shaft holding 0.01 N·m against the creep: fitted, and K unbiased.
    current = np.concatenate([np.arange(0.5, 4.01, 0.5), np.arange(3.5, 0.49, -0.5)])
    approach = np.where(np.arange(current.size) < 8, 1.0, -1.0)
    mass = (K_TRUE * current - 0.01 * approach) / (STANDARD_GRAVITY * ARM)
    result = torque(Recording(np.arange(current.size, dtype=float), {"current": current, "mass": mass}), arm=ARM)
    assert result.value("tau_h") == pytest.approx(0.01, rel=1e-9)
    assert result.value("K") == pytest.approx(K_TRUE, rel=1e-9)
    assert result.correlation_names == ["K", "tau0", "tau_h"]
    assert result.correlation.shape == (3, 3)


def test_a_long_table_gives_counts_of_approach_directions_not_a_number_per_row():
    """Up to ROW_DETAILS rows the answer lists each row's approach; past it, only how many (a 2 M-row table's
    answer held 2 M numbers, most of its 10 s)."""
    from motorlab.analyses.torque import ROW_DETAILS

    for n in (11, ROW_DETAILS + 500):
        current = np.concatenate([np.linspace(0.5, 4.0, n // 2), np.linspace(4.0, 0.5, n - n // 2)])
        tau = 0.02 * current + 0.001 * np.sign(np.gradient(current))
        rec = Recording(np.arange(n, dtype=float), {"current": current, "torque": tau}, source="long.csv")
        details = torque(rec).details
        counts = details["approach_counts"]
        assert sum(counts.values()) == n
        assert counts["below"] > 0
        assert counts["above"] > 0
        assert ("approach" in details) == (n <= ROW_DETAILS)
