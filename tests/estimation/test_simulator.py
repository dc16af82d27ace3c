"""The output-error simulator's fast paths: one state (the feedforward model) bit for bit, two states (the motor
model) to rounding, against the general matrix form."""

from collections.abc import Iterator

import numpy as np
import pytest

from motorlab.estimation.simulator import (
    EVENT,
    RUN,
    SWITCH,
    Perturbed,
    _Modal,
    feedforward_plant,
    motor_plant,
    sensitivities,
    simulate,
)

FIELDS = ("ad", "bv", "c", "hx", "hv", "hc")


def _both_paths(plant, taus: np.ndarray, fast_path: str) -> Iterator[tuple[_Modal, int, float, str, np.ndarray,
                                                                           np.ndarray]]:
    """(regime, s, τ, field, the fast path's value, the general path's) for every regime (moving either way, stuck)
    and step; ``fast_path`` names the flag that selects it (``scalar`` or ``pair``), switched off for the other."""
    for s in (1, -1, 0):
        modal = _Modal(plant, s)
        assert getattr(modal, fast_path)
        for tau in taus:
            fast = modal.discrete(float(tau))
            setattr(modal, fast_path, False)
            general = modal.discrete(float(tau))
            setattr(modal, fast_path, True)
            for name in FIELDS:
                yield modal, s, float(tau), name, np.asarray(getattr(fast, name)), np.asarray(getattr(general, name))


@pytest.mark.parametrize("gains", [(0.34, 0.9455, 18.12), (0.46, 0.0172, 0.0028), (0.1, 2.0, 1e-4), (0.0, 1e-6, 5.0)])
def test_one_state_steps_are_the_general_steps_bit_for_bit(gains):
    """Fractional steps of every regime, fast and slow modes, both forms of φ."""
    taus = np.concatenate([[0.0, 1e-12, 0.01], np.random.default_rng(7).uniform(0.0, 0.02, 300),
                           np.geomspace(1e-9, 10.0, 200)])
    for _modal, s, tau, name, a, b in _both_paths(feedforward_plant(*gains), taus, "scalar"):
        # the same numbers bit for bit (a zero's sign aside: the general path's matrix product sums −0 to +0)
        assert a.shape == b.shape, (s, tau, name)
        assert (a + 0.0).tobytes() == (b + 0.0).tobytes(), (s, tau, name, a, b)


@pytest.mark.parametrize("params", [(0.7, 1.18, 6.7e-4, 0.0149, 0.0082, 0.13),  # a NeveRest on a flywheel
                                    (0.02, 0.09, 5e-5, 1e-5, 1e-6, 1e-3),  # fast, light: complex poles
                                    (0.7, 1.18, 1e-9, 0.0149, 0.0, 0.0)])  # L → 0: a very fast electrical mode
def test_two_state_steps_are_the_matrix_steps_to_rounding(params):
    """The motor model's fractional steps in Python's complex numbers against the matrix form they write out."""
    taus = np.concatenate([[0.0, 1e-12], np.random.default_rng(3).uniform(0.0, 0.002, 100),
                           np.geomspace(1e-9, 1.0, 100)])
    for modal, s, tau, name, a, b in _both_paths(motor_plant(*params), taus, "pair"):
        # hv, hc are sums over the two modes of terms up to τ²/2·|row·pb| that cancel to O(τ³): rounding
        # is relative to the terms, not to their sum
        pulls = {"hv": modal.pb, "hc": modal.pc}
        terms = tau**2 / 2 * float(np.sum(np.abs(modal.row * pulls[name]))) if name in pulls else 0.0
        scale = max(float(np.max(np.abs(b))), terms, 1e-300)
        assert np.allclose(a, b, rtol=1e-12, atol=1e-12 * scale), (s, tau, name, a, b)


@pytest.mark.parametrize("params", [(0.7, 1.18, 6.7e-4, 0.0149, 0.0082, 0.13), (0.02, 0.09, 5e-5, 1e-5, 1e-6, 1e-3),
                                    (0.7, 1.18, 1e-9, 0.0149, 0.0, 0.0)])
def test_an_events_function_is_the_stepped_state_to_rounding(params):
    """What an event's location asks at each fraction of a step (the speed moving, the drive's margin stuck), from
    the modes directly, against the same number from the step's matrices."""
    from motorlab.estimation.simulator import _flow, _Regimes

    plant = motor_plant(*params)
    reg = _Regimes(plant, 1e-3)
    rng = np.random.default_rng(11)
    for mode in (1, -1, 0):
        for _ in range(40):
            x = rng.normal(size=2) * [2.0, 30.0]
            if mode == 0:
                x[1] = 0.0
            v, tau = float(rng.uniform(-12, 12)), float(rng.choice([1e-3, 2.5e-4, 1e-7]))
            fast = reg.event_function(mode, x, v, tau)
            for frac in (0.0, 1e-9, 0.3, 0.77, 1.0):
                xm, _ = _flow(reg.modal(mode).discrete(frac * tau), x, v)
                exact = float(xm[1]) if mode else abs(float(reg.drive(xm, v))) - reg.f_level
                scale = float(np.max(np.abs(reg.modal(mode).vec))) * (np.sum(np.abs(x)) + abs(v) * tau * 1e4) + 1.0
                assert fast(frac) == pytest.approx(exact, rel=1e-10, abs=1e-11 * scale), (mode, frac, x, v, tau)


@pytest.mark.parametrize("params", [(0.7, 1.18, 6.7e-4, 0.0149, 0.0082, 0.13), (0.02, 0.09, 5e-5, 1e-5, 1e-6, 1e-3),
                                    (0.7, 1.18, 1e-9, 0.0149, 0.0, 0.0)])
def test_a_part_of_a_step_from_the_modes_is_the_matrix_step_to_rounding(params):
    """A drive switch's or an event's part of a step (state and angle) from the modes, against the step's matrices."""
    from motorlab.estimation.simulator import _flow

    rng = np.random.default_rng(5)
    for s in (1, -1, 0):
        modal = _Modal(motor_plant(*params), s)
        for tau in np.concatenate([[0.0, 1e-12], rng.uniform(0.0, 2e-3, 60), np.geomspace(1e-9, 1.0, 30)]):
            x, v = rng.normal(size=2) * [2.0, 30.0], float(rng.uniform(-12, 12))
            got, turned = modal.flow(x, v, float(tau))
            step = modal.discrete(float(tau))
            want, angle = _flow(step, x, v)
            size = np.abs(modal.vec) @ (np.abs(modal.inv) @ np.abs(x) + tau * np.abs(modal.pb * v + modal.pc))
            assert np.allclose(got, want, rtol=1e-11, atol=1e-11 * float(np.max(size))), (s, tau, got, want)
            terms = float(np.sum(np.abs(modal.row) * (tau * np.abs(modal.inv @ x) + tau**2 * np.abs(modal.pb * v))))
            assert turned == pytest.approx(angle, rel=1e-10, abs=1e-11 * terms + 1e-300), (s, tau, turned, angle)


def test_each_regimes_decomposition_gives_the_matrix_exponentials_steps():
    """The closed-form 2 × 2 decomposition (stiff, complex, slow and stuck regimes) against scipy's expm of the same
    regime's augmented matrix: every matrix of a step, to rounding."""
    from motorlab.estimation.simulator import _discretise_expm, _eig2

    rng = np.random.default_rng(17)
    plants = [motor_plant(0.7, 1.18, 6.7e-4, 0.0149, 0.0082, 0.13), motor_plant(0.02, 0.09, 5e-5, 1e-5, 1e-6, 1e-3),
              motor_plant(0.7, 1.18, 1e-6, 0.0149, 0.0, 0.0), motor_plant(0.37, 1.16, 6.6e-4, 1.2e-4, 2.5e-5, 0.011)]
    ranges = np.log([(0.005, 2), (0.05, 20), (1e-6, 1e-2), (1e-6, 0.1), (1e-7, 1e-2), (1e-4, 0.5)])
    plants += [motor_plant(*np.exp(rng.uniform(ranges[:, 0], ranges[:, 1]))) for _ in range(30)]
    for plant in plants:
        for s in (1, -1, 0):
            modal = _Modal(plant, s)
            lam, vec = _eig2(modal.a)
            for j in range(2):  # A·v = λ·v to rounding of A·v's terms
                size = float(np.abs(modal.a).max() * np.abs(vec[:, j]).max())
                assert np.abs(modal.a @ vec[:, j] - lam[j] * vec[:, j]).max() <= 1e-13 * size, (plant, s, lam, vec)
            if not modal.ok:
                continue
            for tau in (1e-3, 2.7e-4, 1e-6):
                fast, exact = modal.discrete(tau), _discretise_expm(plant, s, tau)
                for name in FIELDS:
                    a, b = np.asarray(getattr(fast, name)), np.asarray(getattr(exact, name))
                    assert np.allclose(a, b, rtol=1e-8, atol=1e-9 * max(float(np.max(np.abs(b))), 1e-300)), \
                        (plant, s, tau, name, a, b)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_sensitivities_are_the_forward_differences_of_whole_simulations(seed):
    """:func:`sensitivities` of a motor-model run with drive switches inside steps, stops, stiction and break-aways
    gives, for a change of each plant parameter, of one held level, of one switch instant and of the initial
    state, what simulating the changed run gives (within 1e-4 of the change's size; the forward difference's own
    truncation is ~1e-6; or to rounding where the change is lost at a stop): the Jacobian of a fit costs one pass,
    not one simulation per parameter."""
    rng = np.random.default_rng(seed)
    params = np.array([0.0123, 1.3, 0.0021, 2.4e-5, 3e-6, 2.2e-3])  # K, R, L, J, b, Tf (SI)
    dt, n = 1e-3, 3000
    voltage = np.repeat(rng.choice([-6.0, -0.4, 0.0, 0.3, 5.0], 30), n // 30)  # levels below breaking away too
    steps = np.sort(rng.choice(np.arange(1, n, 100), 12, replace=False))
    switches = (steps, rng.uniform(0.1, 0.9, steps.size), voltage[steps - 1])
    x0 = np.array([0.1, 50.0])  # spinning at the start
    trace: list = []
    states, theta = simulate(motor_plant(*params), voltage, dt, x0=x0, switches=switches, trace=trace)
    assert {op[3] for op in trace} == {RUN, SWITCH, EVENT}  # every kind of step is there
    columns = []
    for j in range(params.size):
        moved = params.copy()
        moved[j] *= 1.0 + 1e-6
        columns.append(Perturbed(motor_plant(*moved), voltage, x0, switches))
    level = voltage.copy()
    level[1500:1600] += 1e-6  # one held level
    columns.append(Perturbed(motor_plant(*params), level, x0, switches))
    instant = (steps, switches[1] + np.where(np.arange(steps.size) == 5, 1e-6, 0.0), switches[2])
    columns.append(Perturbed(motor_plant(*params), voltage, x0, instant))  # one switch instant
    columns.append(Perturbed(motor_plant(*params), voltage, x0 + np.array([0.0, 5e-5]), switches))  # the initial speed
    found = sensitivities(motor_plant(*params), voltage, dt, states, theta, trace, switches, columns)
    assert found is not None
    for c, col in enumerate(columns):
        s1, t1 = simulate(col.plant, col.voltage, dt, x0=col.x0, switches=col.switches)
        pairs = [(found[0][:, :, c], s1 - states, states), (found[1][:, c], t1 - theta, theta)]
        for estimate, difference, run in pairs:
            floor = 1e-12 * np.linalg.norm(run)  # the rounding of two simulations (a change lost at a stop)
            assert np.linalg.norm(estimate - difference) <= 1e-4 * np.linalg.norm(difference) + floor, c
