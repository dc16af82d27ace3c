"""motorlab.parallel: where children may be forked."""

from __future__ import annotations

from motorlab import parallel


def _may_fork(_: int) -> bool:
    return parallel.can_fork()


def test_a_pools_child_forks_no_children_of_its_own():
    """A session's unit runs in a pool's (daemonic) child, which may have no children: a reader there
    parses in its own process instead of failing."""
    assert parallel.map_in_processes(_may_fork, [0, 1], processes=2) == [False, False]
