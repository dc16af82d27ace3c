"""Round trips, coverage and bad input for motorlab.analyses.identify (output-error whole-model fit)."""

from __future__ import annotations

import argparse
import math

import numpy as np
import pytest
from tests._coverage import assert_coverage

from motorlab.analyses.identify import identify
from motorlab.cli.analyze import add_arguments, from_cli
from motorlab.errors import LogFormatError, OptionError
from motorlab.estimation import output_error as _oe
from motorlab.estimation.runs import noise_warning
from motorlab.estimation.simulator import motor_plant
from motorlab.model import MotorParams, feedforward_from_params
from motorlab.model.simulate import VoltageDrive, simulate
from motorlab.recording import Recording

MOTOR = MotorParams(K=0.35, R=2.5, L=7e-4, J=8e-4, b=2e-3, Tf=0.03)
CPR = 2240  # 560 counts/rev × 4 (quadrature) at the shaft


def random_steps(seed: int, *, duration: float, dt: float, params: MotorParams = MOTOR, cpr: int = CPR,
                 current_noise: float = 0.02, hold: float = 0.1, ripple: float = 0.0) -> Recording:
    """Random voltage steps in ±12 V, encoder counted (floor, random phase), current with noise.

    ``ripple`` [V]: white supply ripple the motor really sees, logged exactly (not measurement noise).
    """
    rng = np.random.default_rng(seed)
    n_levels = math.ceil(duration / hold) + 1
    levels = rng.uniform(-12.0, 12.0, n_levels)
    n = round(duration / dt) + 1
    wobble = ripple * rng.standard_normal(n)

    def volts(t: np.ndarray) -> np.ndarray:
        level = levels[np.minimum((t / hold + 1e-9).astype(int), n_levels - 1)]
        return level + wobble[np.minimum(np.rint(t / dt).astype(int), n - 1)]

    sim = simulate(params, VoltageDrive(volts), duration=duration, dt=dt)
    q = 2 * math.pi / cpr
    counts = np.floor((sim.position + rng.uniform(0.0, q)) / q)
    return Recording(
        sim.time,
        {"voltage": sim.voltage, "position": counts * q, "counts": counts,
         "current": sim.current + current_noise * rng.standard_normal(sim.time.size)},
        metadata={"cpr": cpr},
        source=f"sim-{seed}",
    )


def test_fast_simulator_matches_reference_simulation():
    rec = random_steps(1, duration=1.0, dt=1e-3, current_noise=0.0)
    sim = simulate(MOTOR, VoltageDrive(lambda t: np.interp(t, rec.time, rec["voltage"])), duration=1.0, dt=1e-3)
    states, theta = _oe.simulate(motor_plant(*MOTOR.to_dict().values()), rec["voltage"][:-1], 1e-3)
    assert np.max(np.abs(theta - sim.position)) < 1e-8
    assert np.max(np.abs(states[:, 1] - sim.speed)) < 1e-7
    assert np.max(np.abs(states[:, 0] - sim.current)) < 1e-7


@pytest.mark.parametrize("seed", [3, 4])
def test_round_trip_with_current(seed):
    result = identify(random_steps(seed, duration=1.5, dt=1e-3))
    for name, truth in MOTOR.to_dict().items():
        est = result[name]
        assert est.determined, name
        assert abs(est.value - truth) < 4 * est.stderr, (name, est, truth)
        assert abs(est.value / truth - 1) < (0.1 if name in ("L", "b") else 0.02), (name, est)
    assert set(result.details["residual_rms"]) >= {"position", "current", "speed (differenced)"}
    assert result.correlation is not None
    assert result.correlation.shape == (6, 6)
    assert [p.y_label for p in result.panels] == ["θ [rad]", "ω [rad/s]", "i [A]"]
    assert result.details["feedforward"]["kV"] == pytest.approx(feedforward_from_params(MOTOR)["kV"], rel=0.01)


RIG_TOLERANCE = {"K": 0.002, "R": 0.005, "L": 0.03, "J": 0.005, "b": 0.05, "Tf": 0.05}


def test_rig_transient_files_round_trip_with_honest_intervals(tmp_path):
    """Identify reads the virtual dynamometer's own transient files (1 kHz, V ± 20 mV, I ± 5 mA, 1120 counts).

    Five units, six noise seeds each, 1.2 s step logs: every parameter within a fraction of a
    percent (a few percent for L, b, Tf), and its 95 % interval holding the truth a number of times
    inside the binomial window of 30 trials (25–30, tests/_coverage.py). The logged voltage's noise
    enters the simulated current (errors in the input variable) and the quantised angle's errors
    repeat at rest or at a whole number of counts per sample: both are modelled (docs/identify.md).

    What it catches: intervals that hold the truth 60 % of the time, as the previous white-residual
    intervals did, pass this window less than one time in a hundred per parameter. The 100-seed
    version with the 90–98 % bar is benchmarks/bench_coverage.py (figures in docs/identify.md).
    """
    from motorlab.io import read_any
    from motorlab.rig import VirtualRig

    inside: dict[str, list[bool]] = {name: [] for name in RIG_TOLERANCE}
    for seed in range(30):
        rig = VirtualRig("neverest40", unit_seed=seed % 5, noise_seed=seed)
        run = rig.transient(tmp_path / "transient.csv", duration=1.2)
        result = identify(read_any(run.paths[0], cpr=rig.motor.cpr), cpr=rig.motor.cpr)
        truth = run.truth["expected"]
        for name, tolerance in RIG_TOLERANCE.items():
            est = result[name]
            assert est.determined, (seed, name)
            assert abs(est.value / truth[name] - 1) < tolerance, (seed, name, est, truth[name])
            lo, hi = est.interval(1.96)
            inside[name].append(lo <= truth[name] <= hi)
    assert_coverage(inside)


def _truth_started_cost(rec: Recording) -> float:
    """The cost the sample-held fit of ``identify`` reaches from the true parameters (its data and weights)."""
    from motorlab.analyses import identify as identify_module
    from motorlab.estimation.runs import MotorModel, prepare_runs

    recs = identify_module._checked_recordings(rec, resistance=None, torque_constant=None, cpr=None)
    logs, _ = prepare_runs(recs, cpr=None, with_current=True)
    p0, lower, upper, scale = identify_module._start_and_bounds(logs)
    sigma, current_noise, _ = identify_module._noise_weights(logs, np.clip(p0, lower, upper), logs[0].dt)
    truth = np.array(list(MOTOR.to_dict().values()))
    fit = _oe.fit_output_error(MotorModel(), logs, truth, lower=lower, upper=upper, scale=scale, sigma=sigma,
                               current_noise=current_noise)
    return fit.cost


@pytest.mark.parametrize("seed", [10, 11, 12])
def test_real_supply_ripple_is_input_not_noise(seed):
    """Ripple the motor sees and the log records is input: no bias 'correction', no absurd error bars.

    (A review found R = 2.4839 ± 1.8e-7 Ω against 2.5 Ω here: a near-singular information matrix
    inverted at pinv's default cut-off, and a first-order bias removed for noise that was not noise.
    Then seed 11 ended at cost 2,485 beside a cliff, R = 2.4841 ± 7.8e-9 Ω, where a start from the truth
    reaches 1,394: the simulator froze the current of a shaft that broke away and stopped again within
    one step. Every seed now reaches the minimum a start from the truth reaches, with finite, plausible
    standard errors. One case per seed, so that the workers share them.)
    """
    rec = random_steps(seed, duration=1.5, dt=1e-3, ripple=0.2)
    result = identify(rec)
    assert "bias removed" not in result.details["method"]
    assert result.details["cost"] <= _truth_started_cost(rec) * (1 + 1e-4), seed
    assert not any("no standard errors" in w for w in result.warnings), (seed, result.warnings)
    for name in ("K", "R", "J", "b", "Tf"):
        est = result[name]
        assert est.determined, (seed, name, est)
        assert math.isfinite(est.stderr), (seed, name, est)
        assert 1e-3 <= est.stderr / est.value <= 0.25, (seed, name, est)  # plausible (R: 0.7-1 %, b: 10 %)
        assert abs(est.value - getattr(MOTOR, name)) <= 3.5 * est.stderr, (seed, name, est)
    assert abs(result.value("R") - MOTOR.R) <= 3.0 * result["R"].stderr, seed


class _CliffModel(_oe.OEModel):
    """The motor model whose friction triples for R above ``cliff``: a cost with a cliff at the minimum."""

    names = ("K", "R", "L", "J", "b", "Tf")
    uses_current = True

    def __init__(self, cliff: float):
        self.cliff = cliff

    def plant(self, p: np.ndarray) -> _oe.StatePlant:
        tf = float(p[5]) * (3.0 if p[1] > self.cliff else 1.0)
        return motor_plant(*(float(v) for v in p[:5]), tf)

    def initial(self, p: np.ndarray, log: _oe.Log, speed: float) -> np.ndarray:
        assert log.current is not None
        return np.array([float(log.current[0]), speed])


def test_a_fit_beside_a_cliff_says_so_instead_of_giving_standard_errors():
    rec = random_steps(3, duration=0.5, dt=1e-3)
    log = _oe.prepare_log(rec.time, rec["voltage"], rec["position"], rec["current"], resolution=2 * math.pi / CPR)
    truth = np.array(list(MOTOR.to_dict().values()))
    sigma = {"position": 2 * math.pi / CPR / math.sqrt(12), "current": 0.02}
    fits = {}
    for label in ("smooth", "cliff"):
        # the cliff a third of a standard error beyond the minimum (within the reach of a probe)
        cliff = 1e3 if label == "smooth" else fits["smooth"].values[1] + fits["smooth"].covariance[1, 1] ** 0.5 / 3
        fits[label] = _oe.fit_output_error(_CliffModel(cliff), [log], truth, lower=truth * 1e-3,
                                           upper=truth * 1e3, scale=truth, sigma=sigma, current_noise=0.02)
    assert fits["smooth"].not_minimum == ""
    assert np.all(np.isfinite(np.diag(fits["smooth"].covariance)))
    cliff = fits["cliff"]
    assert "not smooth" in cliff.not_minimum
    assert "R" in cliff.not_minimum
    assert np.all(np.isnan(np.diag(cliff.covariance)))
    assert not cliff.null.any()
    assert "no standard errors" in noise_warning(cliff, rms_text="")[0]
    assert cliff.cost <= fits["smooth"].cost * 1.5  # it still ends as low as it can on its side


def test_inductance_not_determined_when_the_current_rise_is_invisible():
    # τe = L/R = 0.4 µs against samples every 2 ms: neither the current nor the angle sees L (a claim about
    # the sampling, not the length: 1 s of log, where 2 s took three times as long to fit)
    fast = MOTOR.scaled(L=1e-6)
    result = identify(random_steps(7, duration=1.0, dt=2e-3, params=fast))
    assert not result["L"].determined
    assert "τe" in result["L"].note
    assert "L" not in result.to_dict()["parameters"] or result.to_dict()["parameters"]["L"]["value"] is None
    for name in ("K", "R", "J"):
        assert abs(result.value(name) / getattr(fast, name) - 1) < 0.03, name


def test_without_current_gives_gains_and_says_what_is_not_determined():
    rec = random_steps(5, duration=2.0, dt=1e-3)
    del rec.signals["current"]
    result = identify(rec, resistance=MOTOR.R)
    truth = feedforward_from_params(MOTOR)
    for name in ("kS", "kV", "kA"):
        assert result[name].determined
        assert abs(result.value(name) / truth[name] - 1) < 0.05, name
    for name in ("K", "b", "J", "Tf"):
        assert not result[name].determined, name
    assert result["R"].value == MOTOR.R
    with_k = identify(rec, resistance=MOTOR.R, torque_constant=MOTOR.K)
    assert abs(with_k.value("J") / MOTOR.J - 1) < 0.05
    assert abs(with_k.value("Tf") / MOTOR.Tf - 1) < 0.1


def test_reversed_encoder_is_flagged_and_fitted():
    rec = random_steps(8, duration=1.0, dt=1e-3)
    rec.signals["position"] = -rec.signals["position"]
    result = identify(rec)
    assert any("counts against" in w for w in result.warnings)
    assert abs(result.value("K") / MOTOR.K - 1) < 0.02


def test_saturated_current_is_flagged():
    rec = random_steps(9, duration=1.0, dt=1e-3)
    rec.signals["current"] = np.clip(rec.signals["current"], -3.0, 3.0)
    result = identify(rec)
    assert any("saturated" in w for w in result.warnings)


def test_encoder_overflow_is_flagged():
    rec = random_steps(10, duration=0.5, dt=1e-3)  # the check reads the data; the fit across the jump is slow
    q = 2 * math.pi / CPR
    rec.signals["position"][300:] -= 65536 * q
    result = identify(rec, use_current=True)
    assert any("overflow" in w for w in result.warnings)


@pytest.mark.parametrize(
    ("change", "error"),
    [
        ("nan", LogFormatError),
        ("short", LogFormatError),
        ("no_voltage", LogFormatError),
        ("time", LogFormatError),
    ],
)
def test_bad_logs_raise(change, error):
    rec = random_steps(11, duration=0.2, dt=1e-3)
    if change == "nan":
        rec.signals["position"][50] = np.nan
    elif change == "short":
        rec = rec.select(slice(0, 10))
    elif change == "no_voltage":
        del rec.signals["voltage"]
    elif change == "time":
        rec.time[30] = rec.time[29]
    with pytest.raises(error):
        identify(rec)


def test_impossible_options_raise():
    rec = random_steps(12, duration=0.3, dt=1e-3)
    with pytest.raises(OptionError):
        identify(rec, resistance=-1.0)
    with pytest.raises(OptionError):
        identify([])


def test_cli_on_csv(tmp_path):
    from motorlab.io import write_csv

    rec = random_steps(13, duration=1.0, dt=1e-3)
    path = tmp_path / "steps.csv"
    write_csv(path, {"time_s": rec.time, "voltage_V": rec["voltage"], "position_counts": rec["counts"],
                     "current_A": rec["current"]})
    parser = argparse.ArgumentParser()
    add_arguments(parser, "identify")
    args = parser.parse_args(["--cpr", str(CPR)])
    result = from_cli("identify", [str(path)], args)
    assert abs(result.value("R") / MOTOR.R - 1) < 0.02
    assert result.sources == [str(path)]
    assert result.to_dict()["parameters"]["K"]["unit"] == "V*s/rad"


def test_text_output_names_the_input_model(tmp_path, capsys):
    from motorlab import cli
    from motorlab.io import write_csv

    rec = random_steps(13, duration=1.0, dt=1e-3)
    path = tmp_path / "steps.csv"
    write_csv(path, {"time_s": rec.time, "voltage_V": rec["voltage"], "position_counts": rec["counts"],
                     "current_A": rec["current"]})
    assert cli.main(["analyze", "identify", str(path), "--cpr", str(CPR)]) == 0
    lines = [line for line in capsys.readouterr().out.splitlines() if line.startswith("input model: ")]
    assert len(lines) == 1


# --------------------------------------------------------------------------------------------------
# Drives that switch between samples, on an independent simulation path (tests/analyses/ivp_reference.py)
# --------------------------------------------------------------------------------------------------

TRUTH = MOTOR.to_dict()


def _reference():
    """tests/analyses/ivp_reference.py (pytest runs with --import-mode=importlib: load it by path)."""
    import importlib.util
    import sys
    from pathlib import Path

    if "ivp_reference" not in sys.modules:
        spec = importlib.util.spec_from_file_location("ivp_reference", Path(__file__).with_name("ivp_reference.py"))
        assert spec is not None
        assert spec.loader is not None
        module = importlib.util.module_from_spec(spec)
        sys.modules["ivp_reference"] = module
        spec.loader.exec_module(module)
    return sys.modules["ivp_reference"]


def test_switch_inside_a_step_matches_the_radau_reference():
    ref_module = _reference()
    random_drive, simulate_ivp = ref_module.random_drive, ref_module.simulate_ivp
    dt = 1e-4
    drive = random_drive(np.random.default_rng(2), 0.3, dt, on_samples=False, hold=(0.03, 0.08))
    ref = simulate_ivp(TRUTH, drive, 0.3, dt)
    first = np.searchsorted(ref["time"], drive.switches[1:], side="left")  # first sample showing each level
    steps = first - 1
    fractions = (drive.switches[1:] - steps * dt) / dt
    grid = drive.at(ref["time"][:-1])
    grid[steps] = drive.levels[1:]  # a switch step holds the voltage before for f·dt, then the new level
    states, theta = _oe.simulate(motor_plant(*TRUTH.values()), grid, dt,
                                 switches=(steps, fractions, drive.levels[:-1]))
    assert np.max(np.abs(theta - ref["position"])) < 1e-8
    assert np.max(np.abs(states[:, 0] - ref["current"])) < 1e-7
    # without the switch inside the step (the sample-held model) the current is off by far more
    late, _ = _oe.simulate(motor_plant(*TRUTH.values()), drive.at(ref["time"][:-1]), dt)
    assert np.max(np.abs(late[:, 0] - ref["current"])) > 0.1


def test_held_levels_are_detected_and_ripple_or_ramps_are_not():
    from motorlab.estimation.held_input import detect_held

    rng = np.random.default_rng(3)
    levels = np.repeat([-10.0, 5.0, -3.0, 8.0, 0.0, 11.0, -6.0, 2.0], 500)
    held, why = detect_held(levels + 0.02 * rng.standard_normal(levels.size), None)
    assert held is not None, why
    assert held.n_segments == 8
    assert held.sigma == pytest.approx(0.02, rel=0.05)
    # a jump of 0.05 V (2.5σ between two samples) is found by binary segmentation
    small = np.repeat([-10.0, 5.0, 5.05, 8.0], 1000)
    held, why = detect_held(small + 0.02 * rng.standard_normal(small.size), None)
    assert held is not None, why
    assert held.first.tolist() == [0, 1000, 2000, 3000]
    exact, _ = detect_held(levels, None)
    assert exact is not None
    assert exact.sigma == 0.0
    assert detect_held(np.linspace(0, 12, 4000) + 0.02 * rng.standard_normal(4000), None)[0] is None
    # scatter the current follows is ripple the motor saw: used as logged
    ripple = 0.2 * rng.standard_normal(levels.size)
    current = np.concatenate([[0.0], np.cumsum(0.1 * ripple[:-1])]) + 0.01 * rng.standard_normal(levels.size)
    held, why = detect_held(levels + ripple, current)
    assert held is None
    assert "ripple" in why


@pytest.mark.parametrize("seed", [20, 26, 28, 31])
@pytest.mark.parametrize("on_samples", [False, True])
def test_independent_simulator_truth_and_bound(on_samples, seed):
    """0.6 s at 10 kHz from the Radau reference (0.02 A, 560 counts, 0.02 V noise when switching between samples).

    Every parameter within 4 reported standard errors of the truth; the input model named; each
    standard error at (or not far above) the Cramér–Rao bound the result reports for its own log.
    Seeds 28 and 31 have one switch a little off its sample instant among few: taken for a
    synchronised drive, that switch once biased L by 6 standard errors; seed 26 reports K and J
    below their bound. One case per seed and drive (the reference simulation is most of the cost),
    so that the workers share them.

    What it catches: a sample-held model of a drive switching between samples (L biased by 6σ),
    standard errors far from the bound either way (the white-residual ones were ~2.3 times too
    small: an error of 2σ then reads above 4σ). The pooled figures over twelve seeds per drive
    (within 3σ in at least ten, within 2σ in 90 %) are benchmarks/bench_coverage.py and
    docs/identify.md; the 3 s tables benchmarks/bench_identify.py.
    """
    logged = _reference().logged
    rec, _ = logged(TRUTH, seed, duration=0.6, dt=1e-4, on_samples=on_samples,
                    voltage_noise=0.0 if on_samples else 0.02)
    result = identify(rec)
    model = result.details["input_model"]
    assert ("on sample instants" in model["text"]) == on_samples, model
    bound = result.details["cramer_rao_bound"]
    for name, truth in TRUTH.items():
        est = result[name]
        assert est.determined, name
        z = abs(est.value - truth) / est.stderr
        assert z < 4.0, (seed, name, est, truth)
        # below 1 is possible: the bound approximates counting errors as white (q²/12); seed 26 (both
        # drives) reports K and J at 0.46× their bound, with |z| < 1 (left open on issue 18)
        assert (0.4 if name in ("K", "R", "L", "J") else 0.2) < bound["stderr_over_bound"][name] < 3.0, (
            seed, name, bound)
        assert "the best any method could do on this log" in est.note


def test_long_log_with_switches_inside_blocks_is_windowed_not_blurred():
    """Block means of a voltage that switches inside a block are levels the motor never saw (identify was
    biased by 8 standard errors on a 60 000-sample log averaged in pairs): such a log is fitted on the
    window where its voltage changes most, and says so."""
    from motorlab.estimation.decimate import block_mean, driven_log

    rec = random_steps(21, duration=1.2, dt=1e-3, hold=0.0505)  # switches on odd samples: inside blocks of 2
    window = driven_log(rec, max_points=1000)
    assert len(window) == 1000
    assert window.metadata["decimation"]["window"][1] - window.metadata["decimation"]["window"][0] == 1000
    assert any("split the log" in w for w in window.metadata["warnings"])
    result = identify(window, cpr=CPR)
    for name in ("K", "R", "J"):
        assert abs(result.value(name) / getattr(MOTOR, name) - 1) < 0.03, name
    held = Recording(np.arange(1200) * 1e-3, {"voltage": np.repeat([1.0, 2.0, -1.0], 400), "counts": np.zeros(1200)})
    assert "window" not in driven_log(held, max_points=600).metadata["decimation"]  # held over every block
    assert len(block_mean(held, max_points=600)) == 600


def test_held_levels_by_their_stretches_or_in_the_one_pass_give_the_same_fit(monkeypatch):
    """A held-level fit with more columns than one pass of the sensitivities holds simulates each level's and switch
    instant's stretch (``_Problem.local_column``); with fewer, they join the pass. Either way the same fit: the
    parameters to 1e-6, their standard errors to 1e-3 (the Jacobians differ by a forward difference's truncation)."""
    from motorlab.estimation import output_error

    rec = random_steps(5, duration=1.0, dt=1e-3, hold=0.1)
    one_pass = identify(rec)
    assert one_pass.details["input_model"]["segments"] > 4  # held levels were fitted as nuisance parameters
    monkeypatch.setattr(output_error, "SENSITIVITY_BATCH", 4)
    stretches = identify(rec)
    for name in ("K", "R", "L", "J", "b", "Tf"):
        assert stretches[name].value == pytest.approx(one_pass[name].value, rel=1e-6), name
        assert stretches[name].stderr == pytest.approx(one_pass[name].stderr, rel=1e-3), name
