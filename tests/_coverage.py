"""The one rule of the suite's coverage checks: how many of n intervals must hold the truth.

A 95 % interval holds the truth in a number of n independent trials that is Binomial(n, 0.95). A
check accepts the counts that calibrated intervals give with probability at least 1 − ``false_alarm``
(equal tails), so a few seeds give a wide window and many seeds a narrow one, at one stated
false-alarm rate instead of a bar chosen by eye. Every check also states what it can catch: the
white-residual intervals identification once reported hold the truth about 60 % of the time (their
standard errors 2.3 times too small), and a window that such intervals would pass more than one
time in a hundred is refused as too small to prove anything (:func:`assert_coverage`).

The full-size checks with the original bars (90–98 % of 100 seeds) are benchmarks
(benchmarks/bench_coverage.py, figures in docs/identify.md).
"""

from __future__ import annotations

from functools import cache

import numpy as np
from scipy.stats import binom

#: Chance that one check fails although its intervals are exactly calibrated.
FALSE_ALARM = 0.01
#: Coverage of a nominal 95 % interval under the old white-residual rule (the failure each check must catch).
BROKEN = 0.60
#: Largest chance a check may have of passing the broken rule.
MISSED = 0.01


@cache
def coverage_window(n: int, *, nominal: float = 0.95, false_alarm: float = FALSE_ALARM) -> tuple[int, int]:
    """(lo, hi): the counts of n calibrated intervals that hold the truth, but for ``false_alarm``.

    lo is the largest count with P(X < lo) ≤ false_alarm/2 and hi the smallest with
    P(X > hi) ≤ false_alarm/2, for X ~ Binomial(n, nominal).
    """
    k = np.arange(n + 1)
    lo = int(np.count_nonzero(binom.cdf(k, n, nominal) <= false_alarm / 2))  # P(X <= k) small for k < lo
    hi = int(k[np.argmax(binom.sf(k, n, nominal) <= false_alarm / 2)])
    return lo, hi


@cache
def pass_chance(n: int, coverage: float, *, nominal: float = 0.95, false_alarm: float = FALSE_ALARM) -> float:
    """Chance that intervals of true ``coverage`` pass the window of n trials at ``nominal``."""
    lo, hi = coverage_window(n, nominal=nominal, false_alarm=false_alarm)
    return float(binom.cdf(hi, n, coverage) - binom.cdf(lo - 1, n, coverage))


def assert_coverage(inside: dict[str, list[bool]], *, nominal: float = 0.95,
                    false_alarm: float = FALSE_ALARM) -> None:
    """Each name's intervals hold the truth a number of times inside its window (see the module's rule).

    Raises AssertionError naming the count, the window and the seeds missed, or when the number of
    trials is too small for the window to refuse the old white-residual intervals.
    """
    for name, hits in inside.items():
        n = len(hits)
        chance = pass_chance(n, BROKEN, nominal=nominal, false_alarm=false_alarm)
        assert chance <= MISSED, f"{n} trials cannot refuse intervals holding the truth 60 % of the time ({chance:.1%})"
        lo, hi = coverage_window(n, nominal=nominal, false_alarm=false_alarm)
        held = int(np.sum(hits))
        missed = [k for k, hit in enumerate(hits) if not hit]
        assert lo <= held <= hi, (f"{name}: {held} of {n} intervals hold the truth, outside {lo}–{hi} "
                                  f"(nominal {nominal:.0%}, false alarm {false_alarm:.0%}); missed at trials {missed}")
