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
