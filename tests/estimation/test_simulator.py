"""The output-error simulator's one-state path (the feedforward model) gives the general path's numbers bit for bit."""

import numpy as np
import pytest

from motorlab.estimation.simulator import _Modal, feedforward_plant


@pytest.mark.parametrize("gains", [(0.34, 0.9455, 18.12), (0.46, 0.0172, 0.0028), (0.1, 2.0, 1e-4), (0.0, 1e-6, 5.0)])
def test_one_state_steps_are_the_general_steps_bit_for_bit(gains):
    """Fractional steps of every regime (moving either way, stuck), fast and slow modes, both forms of φ."""
    plant = feedforward_plant(*gains)
    taus = np.concatenate([[0.0, 1e-12, 0.01], np.random.default_rng(7).uniform(0.0, 0.02, 300),
                           np.geomspace(1e-9, 10.0, 200)])
    for s in (1, -1, 0):
        modal = _Modal(plant, s)
        assert modal.scalar
        for tau in taus:
            fast = modal._discrete_scalar(float(tau))
            modal.scalar = False
            general = modal.discrete(float(tau))
            modal.scalar = True
            for name in ("ad", "bv", "c", "hx", "hv", "hc"):
                a, b = np.asarray(getattr(fast, name)), np.asarray(getattr(general, name))
                # the same numbers bit for bit (a zero's sign aside: the general path's matrix product sums −0 to +0)
                assert a.shape == b.shape, (s, tau, name)
                assert (a + 0.0).tobytes() == (b + 0.0).tobytes(), (s, tau, name, a, b)
