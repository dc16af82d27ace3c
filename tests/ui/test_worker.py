"""The worker's thinning of curves for the browser (issue 31, point 8): fast, and never losing a spike."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from motorlab.ui.worker import _listed, keep_extremes


def _by_buckets(y: np.ndarray, limit: int) -> np.ndarray:
    """What keep_extremes promises, written as a loop: each of limit // 4 equal runs keeps its first, smallest,
    largest and last sample (the first of equal values; the ends only where no sample is finite)."""
    edges = np.linspace(0, y.size, max(1, limit // 4) + 1).astype(int)
    keep = []
    for a, b in itertools.pairwise(edges):
        if b > a:
            part = y[a:b]
            keep += [a, b - 1]
            if np.isfinite(part).any():
                keep += [a + int(np.nanargmin(part)), a + int(np.nanargmax(part))]
    return np.unique(keep)


@pytest.mark.parametrize("seed", [1, 2, 3])
@pytest.mark.parametrize(("n", "limit"), [(20_004, 600), (20_004, 2000), (12_905, 600), (2001, 600), (5000, 7)])
def test_each_run_keeps_its_ends_and_extremes(seed: int, n: int, limit: int) -> None:
    rng = np.random.default_rng(seed)
    y = np.round(rng.normal(size=n), 1)  # ties: the first of equal values is kept
    y[rng.integers(0, n, 40)] = np.nan
    y[n // 3: n // 3 + n // 10] = np.nan  # runs with no finite sample
    kept = keep_extremes(y, limit)
    assert np.array_equal(kept, _by_buckets(y, limit))
    assert kept.size <= limit
    assert np.all(np.diff(kept) > 0)


def test_a_spike_is_never_thinned_away() -> None:
    y = np.sin(np.linspace(0, 20, 30_000))
    y[12_345] = 50.0
    y[23_456] = -50.0
    kept = keep_extremes(y, 600)
    assert {12_345, 23_456} <= set(kept.tolist())
    assert kept[0] == 0
    assert kept[-1] == y.size - 1


def test_short_curves_are_sent_whole_and_non_finite_values_as_null() -> None:
    assert np.array_equal(keep_extremes(np.arange(5.0), 600), np.arange(5))
    assert _listed(np.array([1.5, np.nan, -np.inf, 2e-9])) == [1.5, None, None, 2e-9]
