"""LCR analysis: the seed's table, simulated readings with known truth, outliers and bad input."""

from __future__ import annotations

import math

import numpy as np
import pytest

from motorlab.analyses.lcr import lcr, robust_outliers
from motorlab.errors import FitError, LogFormatError, OptionError
from motorlab.io import read_csv, write_csv
from motorlab.recording import Recording

# Seed 1, "LCR Meter Experiment", the table of ten readings (L in µH, Q, DCR in Ω).
SEED_L_UH = [697.2, 643, 645.2, 731.4, 732.8, 646.4, 695.9, 645.6, 656.4, 641.2]
SEED_Q = [1.03, 2, 1.38, 1.94, 2.17, 1.92, 1.77, 1.79, 1.7, 2.08]
SEED_DCR = [3.65, 1.46, 2.35, 1.75, 1.49, 1.57, 1.83, 1.69, 1.81, 1.38]


def lcr_readings(
    seed: int,
    *,
    resistance_ac: float = 2.3,
    resistance_dc: float = 1.7,
    inductance: float = 680e-6,
    frequency: float = 1000.0,
    n: int = 10,
    outlier: bool = False,
) -> Recording:
    """Readings a DE-5000 would display at n random shaft positions (series mode).

    L varies with the commutator position (±4 %); each reading's contact adds a few percent of
    resistance; the display rounds L to 0.1 µH, Q to 0.01 and DCR to 0.01 Ω. With ``outlier`` one
    DCR reading has a poor brush contact (+2 Ω).
    """
    rng = np.random.default_rng(seed)
    theta = rng.uniform(0, 2 * np.pi, n)
    ell = inductance * (1 + 0.04 * np.sin(2 * theta))  # the truth is the average over positions
    r_ac = resistance_ac * (1 + rng.normal(0, 0.04, n))
    q = 2 * np.pi * frequency * ell / r_ac
    dcr = resistance_dc * (1 + rng.normal(0, 0.04, n))
    if outlier:
        dcr[rng.integers(n)] += 2.0
    return Recording(
        time=np.arange(n, dtype=float),
        signals={
            "inductance": np.round(ell * 1e7) / 1e7,
            "quality_factor": np.round(q, 2),
            "dc_resistance": np.round(dcr, 2),
        },
        source=f"lcr-{seed}.csv",
    )


def test_seed_table_reproduces_the_seed_and_sets_aside_the_bad_contact():
    rec = Recording(
        np.arange(10.0),
        {
            "inductance": np.array(SEED_L_UH) * 1e-6,
            "quality_factor": np.array(SEED_Q),
            "dc_resistance": np.array(SEED_DCR),
        },
    )
    result = lcr(rec)
    r_rows = 2 * np.pi * 1000 * np.array(SEED_L_UH) * 1e-6 / np.array(SEED_Q)
    # The seed averages all ten R values (2.5 Ω); the 4.25 Ω reading (Q = 1.03) is set aside here.
    assert np.mean(r_rows) == pytest.approx(2.49, abs=0.01)
    assert result.value("R") == pytest.approx(np.mean(r_rows[1:]), rel=1e-12)
    assert result.value("L") == pytest.approx(np.mean(SEED_L_UH) * 1e-6, rel=1e-12)
    assert result.value("R_dc") == pytest.approx(np.mean(SEED_DCR[1:]), rel=1e-12)
    assert result["R_dc"].stderr == pytest.approx(np.std(SEED_DCR[1:], ddof=1) / 3.0, rel=1e-9)
    flagged = [row["DCR_ohm"] for row in result.details["dcr_readings"] if row["outlier"]]
    assert flagged == [3.65]
    assert any("use R_dc" in w for w in result.warnings)
    assert any("3.65" in w for w in result.warnings)


@pytest.mark.parametrize("outlier", [False, True])
def test_simulated_readings_recover_the_truth(outlier):
    hits = {"R": 0, "L": 0, "R_dc": 0}
    seeds = range(12)
    for seed in seeds:
        result = lcr(lcr_readings(seed, outlier=outlier))
        truth = {"R": 2.3, "L": 680e-6, "R_dc": 1.7}
        assert result.value("R") == pytest.approx(truth["R"], rel=0.07)
        assert result.value("L") == pytest.approx(truth["L"], rel=0.03)
        assert result.value("R_dc") == pytest.approx(truth["R_dc"], rel=0.07)
        for name, value in truth.items():
            est = result[name]
            hits[name] += abs(est.value - value) <= 3 * est.stderr
        if outlier:
            assert sum(row["outlier"] for row in result.details["dcr_readings"]) >= 1
    for name, count in hits.items():
        assert count >= 0.9 * len(seeds), name


def test_parallel_readings_are_converted_to_the_series_circuit():
    ell_s, r_s, f = 700e-6, 2.0, 1000.0
    q = 2 * np.pi * f * ell_s / r_s
    ell_p = ell_s * (1 + q**2) / q**2
    rec = Recording(np.arange(3.0), {"inductance": np.full(3, ell_p), "quality_factor": np.full(3, q)})
    rec.metadata["circuit"] = "parallel"
    result = lcr(rec)
    assert result.value("L") == pytest.approx(ell_s, rel=1e-12)
    assert result.value("R") == pytest.approx(r_s, rel=1e-12)
    # Taken as series, the same numbers overstate both.
    assert lcr(rec, circuit="series").value("R") > 1.1 * r_s
    with pytest.raises(OptionError):
        lcr(rec, circuit="diagonal")


def test_frequency_from_option_metadata_and_column(tmp_path):
    path = tmp_path / "lcr.csv"
    write_csv(path, {"L_uH": [700.0, 710.0, 690.0], "Q": [22.0, 22.3, 21.7]}, metadata={"frequency_Hz": 10000})
    rec = read_csv(path)
    expected = np.mean(2 * np.pi * 1e4 * np.array([700e-6, 710e-6, 690e-6]) / np.array([22.0, 22.3, 21.7]))
    assert lcr(rec).value("R") == pytest.approx(expected, rel=1e-12)
    assert lcr(rec, frequency=1000.0).value("R") == pytest.approx(expected / 10, rel=1e-12)
    write_csv(path, {"L_uH": [700.0, 710.0], "Q": [2.2, 2.23], "frequency_Hz": [1000.0, 1000.0]})
    assert lcr(read_csv(path)).details["frequency_from"] == "column"
    with pytest.raises(OptionError):
        lcr(rec, frequency=-5.0)


@pytest.mark.parametrize("frequency", [1e300, 0.5, 2e8])
def test_frequency_no_lcr_meter_uses_is_refused(frequency, tmp_path):
    """1e300 Hz would overflow 2πfL/Q (and give R = 1e297 Ω): refused, option or file alike."""
    path = tmp_path / "lcr.csv"
    write_csv(path, {"L_uH": [700.0, 710.0, 690.0], "Q": [22.0, 22.3, 21.7]})
    with pytest.raises(OptionError, match="--frequency"):
        lcr(read_csv(path), frequency=frequency)
    write_csv(path, {"L_uH": [700.0, 710.0], "Q": [2.2, 2.23], "frequency_Hz": [1000.0, frequency]})
    with pytest.raises(LogFormatError, match="no LCR meter") as err:
        lcr(read_csv(path))
    assert err.value.path == str(path)
    assert err.value.line is not None
    write_csv(path, {"L_uH": [700.0, 710.0], "Q": [2.2, 2.23]}, metadata={"frequency_Hz": frequency})
    with pytest.raises(LogFormatError, match="frequency_Hz"):
        lcr(read_csv(path))


def test_readings_at_several_frequencies_are_not_averaged(tmp_path):
    """A meter switched from 1 kHz to 10 kHz: R = 2πfL/Q of both averaged (8.5 Ω of 1.55 and 15.5) is refused."""
    path = tmp_path / "lcr.csv"
    write_csv(path, {"L_uH": [700.0] * 4, "Q": [2.84] * 4, "frequency_Hz": [1000.0, 1000.0, 1e4, 1e4]})
    with pytest.raises(FitError, match="1 kHz, 10 kHz"):
        lcr(read_csv(path))
    write_csv(path, {"L_uH": [700.0, 705.0], "Q": [28.4, 28.1]}, metadata={"frequency_Hz": 10000})
    assert any("at 10 kHz includes AC losses" in w for w in lcr(read_csv(path)).warnings)


def test_unusual_frequency_is_warned(tmp_path):
    path = tmp_path / "lcr.csv"
    write_csv(path, {"L_uH": [700.0, 710.0, 690.0], "Q": [22.0, 22.3, 21.7]})
    assert any("check its unit" in w for w in lcr(read_csv(path), frequency=5e6).warnings)
    assert not any("check its unit" in w for w in lcr(read_csv(path), frequency=1e5).warnings)


def test_separate_files_for_lq_and_dcr(tmp_path):
    a, b = tmp_path / "lq.csv", tmp_path / "dcr.csv"
    write_csv(a, {"L_uH": [700.0, 705.0, 698.0], "Q": [1.9, 1.95, 1.92]})
    write_csv(b, {"DCR_ohm": [1.6, 1.65, 1.62, 1.7]})
    result = lcr([read_csv(a), read_csv(b)])
    assert set(result.parameters) == {"R", "L", "R_dc"}
    assert result.sources == [str(a), str(b)]
    only_lq = lcr(read_csv(a))
    assert "R_dc" not in only_lq
    assert any("no DC resistance" in w for w in only_lq.warnings)


def test_bad_input():
    with pytest.raises(LogFormatError, match="no LCR readings"):
        lcr(Recording(np.arange(3.0), {"current": np.ones(3)}, source="x.csv"))
    with pytest.raises(LogFormatError, match="only one DC resistance reading") as err:
        lcr(Recording(np.arange(1.0), {"dc_resistance": np.ones(1)}, source="one.csv", lines=np.array([4])))
    assert err.value.path == "one.csv"
    assert err.value.line == 4
    with pytest.raises(LogFormatError, match="positive"):
        lcr(Recording(np.arange(3.0), {"inductance": np.ones(3) * 1e-4, "quality_factor": np.array([1.0, -2, 3])}))
    with pytest.raises(LogFormatError, match="finite"):
        lcr(Recording(np.arange(3.0), {"dc_resistance": np.array([1.0, math.nan, 1.2])}))


def test_robust_outliers():
    # Clean normal readings are seldom flagged (ten at a time, as the seed takes them) ...
    flagged = [robust_outliers(np.random.default_rng(seed).normal(1.6, 0.05, 10)).sum() for seed in range(300)]
    assert np.sum(flagged) / (10 * 300) < 0.02
    # ... and a gross one always is.
    dirty = np.random.default_rng(3).normal(1.6, 0.05, 10)
    dirty[4] = 2.6
    assert np.flatnonzero(robust_outliers(dirty)).tolist() == [4]
    # More than half the readings equal (display resolution): MAD = 0, the mean deviation is used.
    flat = np.array([1.6, 1.6, 1.6, 1.6, 1.61, 1.59, 3.0])
    assert np.flatnonzero(robust_outliers(flat)).tolist() == [6]
    assert not robust_outliers(np.array([1.0, 5.0])).any()


def test_virtual_rig_files(tmp_path):
    """Files written by the virtual rig's LCR meter (position-dependent L, brush contacts, AC losses)."""
    from motorlab.rig import VirtualRig

    inside = inside_r = 0
    runs = [(motor, seed) for motor in ("neverest20", "neverest40", "neverest60", "corehex") for seed in range(3)]
    for motor, seed in runs:
        run = VirtualRig(motor, unit_seed=seed, noise_seed=seed).lcr(tmp_path / f"lcr-{motor}-{seed}.csv")
        result = lcr(read_csv(run.paths[0]))
        params = run.truth["params"]
        assert result.value("L") == pytest.approx(params["L"], rel=0.03)
        inside += abs(result.value("L") - params["L"]) <= 3 * result["L"].stderr
        # R_dc is the running resistance (winding plus a good brush contact), never the poor contacts.
        assert result.value("R_dc") == pytest.approx(params["R"], rel=0.07)
        inside_r += abs(result.value("R_dc") - params["R"]) <= 3 * result["R_dc"].stderr
        assert result.value("R") > result.value("R_dc")  # AC losses
    assert inside >= 0.9 * len(runs)
    assert inside_r >= 0.9 * len(runs)
