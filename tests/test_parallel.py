"""motorlab.parallel: where children may be forked."""

from __future__ import annotations

import os

import pytest

from motorlab import parallel


def _may_fork(_: int) -> bool:
    return parallel.can_fork()


def test_a_pools_child_forks_no_children_of_its_own(monkeypatch: pytest.MonkeyPatch) -> None:
    """A session's unit runs in a pool's (daemonic) child, which may have no children: a reader there
    parses in its own process instead of failing. The pool is forked whatever threads this test process
    runs (an app served by an earlier test in it): spawned children could not import this test module."""
    monkeypatch.setattr(parallel, "_fork_safe", lambda: True)
    assert parallel.map_in_processes(_may_fork, [0, 1], processes=2) == [False, False]


def _fails(kind: str) -> None:
    if kind == "raise":
        raise ValueError("bad row")
    os._exit(3)


def test_a_forked_childs_answer_and_failures_reach_the_parent():
    assert parallel.Forked(sum, [1, 2, 3]).result() == 6
    with pytest.raises(ValueError, match="bad row"):
        parallel.Forked(_fails, "raise").result()
    with pytest.raises(ChildProcessError, match="code 3"):
        parallel.Forked(_fails, "exit").result()


def test_with_a_thread_running_the_children_come_from_the_fork_server(monkeypatch: pytest.MonkeyPatch) -> None:
    """A process running a thread (a progress bar, a test runner) may not fork: its pools' children are forked by
    multiprocessing's fork server (its imports done once), not spawned (each importing everything again). Each
    child's parent is that server, and the answers are those of the work done here."""
    from pathlib import Path

    monkeypatch.setattr(parallel, "_fork_safe", lambda: False)
    assert parallel._context().get_start_method() == "forkserver"
    stats = parallel.map_in_processes(Path.read_text, [Path("/proc/self/stat")] * 2, processes=2)
    parents = {int(stat.rsplit(")", 1)[1].split()[1]) for stat in stats}
    assert os.getpid() not in parents
    assert len(parents) == 1  # one fork server forked both
    assert parallel.map_in_processes(abs, [-1, 2, -3], processes=2) == [1, 2, 3]
