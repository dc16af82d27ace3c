"""Shared fixtures: paths to the small real-format files in tests/data."""

from __future__ import annotations

from pathlib import Path

import pytest

DATA = Path(__file__).parent / "data"


@pytest.fixture
def data_dir() -> Path:
    """``tests/data``: small files in the formats real rigs write (see tests/data/README.md)."""
    return DATA


@pytest.fixture
def real_dir() -> Path:
    """``tests/data/real``: public logs recorded on robots (SysId and frc-characterization JSON)."""
    return DATA / "real"


#: VEX Robotics' dynamometer exports (issue 23), read in place: ``../shared/data/real/dyno`` beside the
#: clone (as CI has it), or two levels up for a git worktree under ``wt/``.
_ROOT = Path(__file__).resolve().parent.parent
DYNO_CANDIDATES = [_ROOT.parent / "shared" / "data" / "real" / "dyno",
                   _ROOT.parent.parent / "shared" / "data" / "real" / "dyno"]


def find_dyno_dir() -> Path | None:
    """The shared folder of real dynamometer exports, or None when this checkout has none beside it."""
    return next((p for p in DYNO_CANDIDATES if (p / "README.md").is_file()), None)


@pytest.fixture
def dyno_dir() -> Path:
    """The shared real dynamometer exports (skips the test when they are not beside the clone)."""
    found = find_dyno_dir()
    if found is None:
        pytest.skip("the shared dynamometer exports (../shared/data/real/dyno) are not beside this clone")
    return found
