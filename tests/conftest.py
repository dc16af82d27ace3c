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


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """The longest tests first: the browser's (a Chromium, the app's commands, a minute each on a busy machine),
    then those marked ``slow``, then the rest, each group in its collection order. pytest-xdist's workers take
    the queue from its head and, once idle, steal from the tail of another's: the suite then ends on short tests
    on every core, not on one browser journey while the other core waits."""
    def cost(item: pytest.Item) -> int:
        if "page" in getattr(item, "fixturenames", ()):
            return 0
        return 1 if item.get_closest_marker("slow") is not None else 2

    items.sort(key=cost)  # stable: the collection order within each group
