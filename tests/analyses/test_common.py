"""Shared helpers of the analyses: reader warnings passed on, physical ranges, flat and exact fits."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from motorlab.analyses import common
from motorlab.analyses.gains import amplifier, tachometer
from motorlab.analyses.lcr import lcr
from motorlab.analyses.torque import torque
from motorlab.errors import FitError, OptionError
from motorlab.recording import Recording

TRUNCATED = "t.csv:12: truncated last line dropped ('0.3')"


def _with_warning(signals: dict[str, np.ndarray], *, metadata: dict | None = None, source: str = "t.csv"):
    n = len(next(iter(signals.values())))
    return Recording(np.arange(n, dtype=float), signals, {**(metadata or {}), "warnings": [TRUNCATED]},
                     source=source)


def test_reader_warnings_in_order_once_each() -> None:
    a = Recording(np.arange(2.0), {"x": np.ones(2)}, {"warnings": ["a", "b"]})
    b = Recording(np.arange(2.0), {"x": np.ones(2)}, {"warnings": ["b", "c"]})
    c = Recording(np.arange(2.0), {"x": np.ones(2)})
    assert common.reader_warnings([a, b, c]) == ["a", "b", "c"]
    assert common.reader_warnings(c) == []
    # concatenate keeps every file's warnings, not only the first one's.
    assert common.concatenate([c, b], ["x"]).metadata["warnings"] == ["b", "c"]


@pytest.mark.parametrize(
    "analysis",
    [
        lambda: torque(_with_warning({"current": np.array([1.0, 2.0, 3.0]), "torque": np.array([0.1, 0.21, 0.29])})),
        lambda: amplifier(_with_warning({"command": np.array([0.5, 1.0, 1.5]), "current": np.array([1.0, 2.01, 2.9])})),
        lambda: tachometer(_with_warning({"speed": np.array([10.0, 20, 30]),
                                          "tach_voltage": np.array([0.3, 0.61, 0.9])})),
        lambda: lcr(_with_warning({"dc_resistance": np.array([1.6, 1.62, 1.61])})),
    ],
    ids=["torque", "amplifier", "tachometer", "lcr"],
)
def test_bench_analyses_pass_the_readers_warnings_on(analysis) -> None:
    assert analysis().warnings[0] == TRUNCATED


@pytest.mark.parametrize(
    ("analysis", "what"),
    [
        (lambda: torque(Recording(np.arange(4.0), {"current": np.arange(1.0, 5.0), "mass": np.zeros(4)},
                                  {"arm_m": 0.1}, source="flat.csv")), "scale reading"),
        (lambda: amplifier(Recording(np.arange(4.0), {"command": np.arange(1.0, 5.0), "current": np.zeros(4)},
                                     source="flat.csv")), "output current"),
        (lambda: tachometer(Recording(np.arange(4.0), {"speed": np.arange(1.0, 5.0), "tach_voltage": np.zeros(4)},
                                      source="flat.csv")), "tachometer voltage"),
    ],
    ids=["torque", "amplifier", "tachometer"],
)
def test_a_flat_response_is_refused_naming_the_file(analysis, what: str) -> None:
    """A column of zeros fits a line exactly: it used to give 'K = 0 ± 0' with exit code 0."""
    with pytest.raises(FitError, match=rf"^flat\.csv: the {what} reads 0 in every row"):
        analysis()


def test_rows_exactly_on_a_line_have_an_unknown_uncertainty() -> None:
    """Zero residuals with more rows than parameters: stderr NaN ('± ?') with a warning, never '± 0'."""
    rec = Recording(np.arange(4.0), {"command": np.array([0.5, 1.0, 1.5, 2.0]),
                                     "current": np.array([1.0, 2.0, 3.0, 4.0])}, source="exact.csv")
    result = amplifier(rec)
    assert result["Ka"].value == pytest.approx(2.0)
    assert math.isnan(result["Ka"].stderr)
    assert common.EXACT_LINE_WARNING in result.warnings
    assert "± ?" in str(result["Ka"])


@pytest.mark.parametrize("value", [1e-300, 0.5, 1e300, math.inf, math.nan])
def test_check_cpr_refuses_values_no_encoder_has(value: float) -> None:
    with pytest.raises(OptionError, match="--cpr"):
        common.check_cpr(value)


def test_check_range_accepts_the_limits_and_none() -> None:
    for value in (None, 1.0, 2.0**30):
        common.check_cpr(value)
    with pytest.raises(OptionError, match=r"between 1 and 5 \[A\], got 7 \(why not\)"):
        common.check_range(7, "x", 1.0, 5.0, "A", why="why not")


def test_position_of_refuses_a_cpr_that_would_overflow() -> None:
    """cpr = 1e-300 made 2π/cpr = 6e300 rad per count: overflow warnings, then a fit error without the file."""
    rec = Recording(np.arange(5.0), {"counts": np.arange(5.0)}, {"cpr": 1e-300}, source="log.txt")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(OptionError, match="--cpr"):
            common.position_of(rec, cpr=1e-300)
        with pytest.raises(Exception, match=r"log\.txt") as err:
            common.position_of(rec)  # the file's own '# cpr:' line
    assert getattr(err.value, "path", None) == "log.txt"


def test_in_file_prefixes_the_source_once() -> None:
    assert str(common.in_file(FitError("bad"), "a.txt")) == "a.txt: bad"
    assert str(common.in_file(FitError("a.txt: bad"), "a.txt")) == "a.txt: bad"
