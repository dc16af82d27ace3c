"""Shared fixtures: the small files the project made in tests/data, and the public real data read in place."""

from __future__ import annotations

from pathlib import Path

import pytest
from tests.real_data import find_dyno_dir, find_real_dir, not_found

DATA = Path(__file__).parent / "data"


@pytest.fixture
def data_dir() -> Path:
    """``tests/data``: small files in the formats real rigs write, crafted by the project (tests/data/README.md)."""
    return DATA


@pytest.fixture(scope="session")
def real_dir() -> Path:
    """``../shared/data/real``: public logs recorded by others (SysId and frc-characterization JSON in ``sysid/`` and
    at the top, VEX's exports in ``dyno/``, ``roadrunner-encoder/``, ``ftc-datalogger/``), read in place; skips the
    test, saying where it looked, when the folder is not beside the clone (tests/real_data.py)."""
    found = find_real_dir()
    if found is None:
        pytest.skip(not_found("the shared real data (../shared/data/real)"))
    return found


@pytest.fixture(scope="session")
def dyno_dir() -> Path:
    """VEX Robotics' dynamometer exports, ``../shared/data/real/dyno`` (skips the test, saying where it looked)."""
    found = find_dyno_dir()
    if found is None:
        pytest.skip(not_found("the shared dynamometer exports (dyno/ of ../shared/data/real)"))
    return found
