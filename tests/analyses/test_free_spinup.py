"""Free spin-up analysis: the armature inertia J from oscilloscope edge times."""

from __future__ import annotations

import argparse
import math

import numpy as np
import pytest

from motorlab.analyses.free_spinup import free_spinup
from motorlab.cli.analyze import add_arguments, from_cli
from motorlab.errors import FitError, OptionError
from motorlab.model import MotorParams
from motorlab.model.simulate import CurrentDrive, State, simulate
from motorlab.recording import Recording

CPR = 28.0  # at the motor shaft: one channel gives 7 rising edges per turn
BARE = MotorParams(K=0.0185, R=2.0, L=7e-4, J=9e-6, b=1e-5, Tf=2e-3)


def edge_times(seed: int, params: MotorParams = BARE, *, current: float = 0.5, n_edges: int = 20,
               step: float = 0.4e-3) -> Recording:
    """Cursor times of channel B's rising edges after a hand start (random initial speed)."""
    rng = np.random.default_rng(seed)
    omega0 = rng.uniform(30.0, 80.0)
    sim = simulate(params, CurrentDrive(current), duration=1.0, dt=1e-5, initial=State(speed=omega0))
    first = rng.uniform(0.0, 2 * math.pi / 7)
    angles = first + np.arange(n_edges) * 8 * math.pi / CPR
    t = np.interp(angles, sim.position, sim.time)
    t = np.round((t + rng.normal(0.0, 0.5 * step, t.size)) / step) * step
    return Recording(t, {"counts": np.arange(n_edges, dtype=float)}, {"kind": "edges"}, source="edges.csv")


def truth_ok(result, j: float, rel: float) -> tuple[bool, bool]:
    est = result["J"]
    return abs(est.value / j - 1) < rel, abs(est.value - j) <= 3 * est.stderr


def test_round_trip_with_viscous_drag() -> None:
    hits = 0
    for seed in range(10):
        result = free_spinup(edge_times(seed), torque_constant=BARE.K, current=0.5, cpr=CPR,
                             viscous_friction=BARE.b, coulomb_friction=BARE.Tf)
        close, covered = truth_ok(result, BARE.J, 0.03)
        assert close, (seed, result["J"])
        hits += covered
    assert hits >= 9


def test_k_and_current_uncertainty_propagate() -> None:
    edges = edge_times(11)

    def fit(k: float = BARE.K, i: float = 0.5, **stderr: float):
        return free_spinup(edges, torque_constant=k, current=i, cpr=CPR, viscous_friction=BARE.b,
                           coulomb_friction=BARE.Tf, **stderr)

    exact = fit()
    loose = fit(torque_constant_stderr=0.02 * BARE.K, current_stderr=0.005)
    # First-order propagation checked against refits with K and I moved by one standard error.
    dj_dk = fit(k=1.02 * BARE.K)["J"].value - exact["J"].value
    dj_di = fit(i=0.505)["J"].value - exact["J"].value
    expected = math.sqrt(exact["J"].stderr ** 2 + dj_dk**2 + dj_di**2)
    assert loose["J"].stderr == pytest.approx(expected, rel=0.05)
    assert abs(loose["J"].value - exact["J"].value) < 0.2 * loose["J"].stderr


def test_seed_formula_would_double_j() -> None:
    # No friction in the motor: the ½ matters. P = P0 + ω0·τ + ½·α·τ² gives J; the seed's K·I·τ²/J twice J.
    frictionless = BARE.scaled(b=0.0, Tf=0.0)
    result = free_spinup(edge_times(12, frictionless), torque_constant=BARE.K, current=0.5, cpr=CPR,
                         viscous_friction=0.0)
    assert result["J"].value == pytest.approx(BARE.J, rel=0.03)
    assert result["alpha"].value == pytest.approx(BARE.K * 0.5 / BARE.J, rel=0.03)


def test_edges_per_rev_override_and_warnings() -> None:
    edges = edge_times(13)
    a = free_spinup(edges, torque_constant=BARE.K, current=0.5, cpr=CPR)
    b = free_spinup(edges, torque_constant=BARE.K, current=0.5, edges_per_revolution=7)
    assert a["J"].value == pytest.approx(b["J"].value)
    assert any("viscous" in w for w in a.warnings)


def test_bad_input() -> None:
    edges = edge_times(14)
    with pytest.raises(OptionError):
        free_spinup(edges, torque_constant=BARE.K, current=0.5)
    with pytest.raises(OptionError):
        free_spinup(edges, torque_constant=BARE.K, current=0.5, cpr=0.0)
    with pytest.raises(FitError, match=r"edges\.csv"):
        free_spinup(edges.select(slice(0, 3)), torque_constant=BARE.K, current=0.5, cpr=CPR)
    reversed_times = np.sort(edges.time[-1] - edges.time)  # the same edges played backwards: slowing down
    slowing = Recording(reversed_times, {"counts": edges["counts"]}, source="slow.csv")
    with pytest.raises(FitError, match="not accelerating"):
        free_spinup(slowing, torque_constant=BARE.K, current=0.5, cpr=CPR)


def test_cli_reads_scope_times(tmp_path) -> None:
    edges = edge_times(15)
    path = tmp_path / "edges.csv"
    path.write_text("time_ms\n" + "\n".join(f"{1e3 * t:.2f}" for t in edges.time) + "\n")
    parser = argparse.ArgumentParser()
    add_arguments(parser, "free-spinup")
    args = parser.parse_args(["--cpr", "28", "--K", "0.0185", "--current", "500 mA", "--b", "1e-5",
                              "--Tf", "2e-3 N*m"])
    result = from_cli("free-spinup", [str(path)], args)
    assert result["J"].value == pytest.approx(BARE.J, rel=0.03)


def test_virtual_rig_round_trip(tmp_path) -> None:
    """The rig's default procedure (0.5 A, hand start, 20 cursor-read edges on the finest timebase
    that shows them): J within 3 % given K, I, b and Tf, the truth within 3 standard errors in at
    least 90 % of the units; the waveform export gives the same J."""
    from motorlab.rig import VirtualRig

    runs = [(motor, seed) for motor in ("neverest40", "corehex", "matrix12v", "gobilda5202_188") for seed in range(3)]
    inside = 0
    for k, (motor, seed) in enumerate(runs):
        rig = VirtualRig(motor, unit_seed=seed, noise_seed=seed)
        waveform = tmp_path / f"wave{k}.csv" if k < 2 else None
        run = rig.free_spinup(tmp_path / f"edges{k}.csv", waveform=waveform)
        expected = run.truth["expected"]
        parser = argparse.ArgumentParser()
        add_arguments(parser, "free-spinup")
        args = parser.parse_args(["--cpr", str(rig.motor.cpr), "--K", str(expected["K"]),
                                  "--current", str(expected["current"]), "--b", str(expected["b"]),
                                  "--Tf", str(expected["Tf"])])
        for path in run.paths:  # cursor times, then the waveform export
            result = from_cli("free-spinup", [str(path)], args)
            assert result["J"].value == pytest.approx(expected["J"], rel=0.03), (motor, seed, path.name)
        inside += abs(result["J"].value - expected["J"]) <= 3 * result["J"].stderr
    assert inside >= 0.9 * len(runs)


def test_read_edges_tells_the_formats_apart(tmp_path) -> None:
    from motorlab.analyses.free_spinup import read_edges
    from motorlab.errors import LogFormatError

    times = tmp_path / "edges.csv"
    times.write_text("time_ms\n1.0\n2.5\n3.7\n")
    assert read_edges(str(times)).time.tolist() == pytest.approx([1e-3, 2.5e-3, 3.7e-3])
    log = tmp_path / "testFile.txt"
    log.write_text("12.5 0 0.96 -0.001\n112.7 3 0.97 -0.001\n")
    with pytest.raises(LogFormatError, match=r"testFile\.txt"):
        read_edges(str(log))


@pytest.mark.parametrize(
    ("options", "mention"),
    [({"torque_constant": 1e300, "current": 1e300}, "--K"), ({"current": 1e300}, "--current"),
     ({"edges_per_revolution": 1e-300}, "--edges-per-rev")],
)
def test_values_that_would_overflow_are_refused_up_front(options, mention) -> None:
    """K·I = 1e600 overflowed into RuntimeWarnings and a fit error that named neither file nor option."""
    import warnings

    kwargs = {"torque_constant": BARE.K, "current": 0.5, "cpr": CPR, **options}
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(OptionError, match=mention):
            free_spinup(edge_times(3), **kwargs)
