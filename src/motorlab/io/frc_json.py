"""JSON logs of the FRC characterization tools: WPILib SysId (JSON era) and frc-characterization.

Both store four tests, ``slow-forward``, ``slow-backward`` (quasistatic voltage ramps) and
``fast-forward``, ``fast-backward`` (dynamic voltage steps), as lists of rows, with the mechanism's
``units`` and ``unitsPerRotation``. The readers return one :class:`~motorlab.recording.Recording`
holding the tests one after the other, with ``segments`` so that ``Recording.split()`` gives them
back separately. See ``docs/formats.md`` and ``shared/data/real/README.md``.
"""

from __future__ import annotations

import difflib
import math
import os
import re
import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np

from motorlab import progress
from motorlab.errors import LogFormatError, OptionError
from motorlab.io.text import PathArg, load_json, read_bytes
from motorlab.recording import Recording

#: The four tests, in the order the tools run them (segments keep this order).
TESTS = ("slow-forward", "slow-backward", "fast-forward", "fast-backward")

#: Mechanism units the tools write -> (pint unit, SI unit of the stored signals).
UNITS: dict[str, tuple[str, str]] = {
    "meters": ("m", "m"),
    "feet": ("ft", "m"),
    "inches": ("inch", "m"),
    "radians": ("rad", "rad"),
    "rotations": ("revolution", "rad"),
    "degrees": ("degree", "rad"),
}
#: One unit of each in SI: pint's factors for :data:`UNITS` (a test checks them against pint), written out
#: because building pint's unit registry takes longer than reading a large log.
SI_PER_UNIT = {"meters": 1.0, "feet": 12 * 0.0254, "inches": 0.0254, "radians": 1.0, "rotations": 2 * math.pi,
               "degrees": math.pi / 180}

#: The length unit of a file's gains in each unit (``motorlab tune --units``): a team's code counts in the
#: file's own unit, so a file in Feet gives kV per foot.
GAIN_UNITS = {"meters": "m", "feet": "ft", "inches": "in", "radians": "rad", "rotations": "rotations",
              "degrees": "degrees"}

_SIDES = ("left", "right")
#: ``side="both"``: every drivetrain test twice, as ``<test>#left`` and ``<test>#right``.
BOTH = "both"


#: A rotation in the file's units that a mechanism can have: from a micrometre lead screw (1e-6 m)
#: to a million (a gear ratio times degrees, with margin). Outside, positions scale into absurd angles.
UNITS_PER_ROTATION_RANGE = (1e-6, 1e6)


def test_kind(name: str) -> dict[str, Any]:
    """``{"kind": "quasistatic"|"dynamic"|None, "direction": +1|-1|0}`` of a test name.

    Accepts the JSON names (``slow-forward``, ``fast-backward``) and the data-log names
    (``quasistatic-forward``, ``dynamic-reverse``).
    """
    tokens = name.split("#")[0].split("-")
    kinds = {"slow": "quasistatic", "quasistatic": "quasistatic", "fast": "dynamic", "dynamic": "dynamic"}
    directions = {"forward": 1, "backward": -1, "reverse": -1}
    return {"kind": kinds.get(tokens[0]), "direction": directions.get(tokens[-1], 0)}


@dataclass
class _Test:
    name: str
    rows: np.ndarray
    lines: np.ndarray


@dataclass(frozen=True)
class _Parsed:
    """A test's rows parsed by numpy before ``json.loads`` saw them (see :func:`_extract_tests`)."""

    rows: np.ndarray
    lines: np.ndarray


_TEST_START = re.compile(rb'"(slow-forward|slow-backward|fast-forward|fast-backward)"\s*:\s*(\[)\s*\[')
_TEST_END = re.compile(rb"\]\s*\]")
#: The bytes of rows of plain numbers (deleted by ``bytes.translate``: what is left is something else).
_JSON_NUMERIC = b"0123456789+-.eE \t\r\n,[]"
_TO_SPACE = bytes.maketrans(b",[]", b"   ")


def _parse_rows(raw: bytes, start: int, stop: int) -> tuple[np.ndarray, np.ndarray] | None:
    """``raw[start:stop]``, ``[[t, V, x, v], ...]``, as an (n, ncol) array and each row's ``[`` offset from
    ``start``, or None unless every row is plain numbers of one length.

    Held at once besides ``raw``: the text once more (for numpy's parser) and the numbers; the rest is
    looked at in place (a 700,000-row test: 30 MB of text, 22 MB of numbers).
    """
    if raw[start:stop].translate(None, _JSON_NUMERIC):
        return None  # NaN, Infinity, strings, objects: json.loads and the checks below name them
    codes = np.frombuffer(raw, dtype=np.uint8, count=stop - start, offset=start)
    opens = np.flatnonzero(codes == ord("["))[1:]
    closes = np.flatnonzero(codes == ord("]"))[:-1]
    if opens.size == 0 or opens.size != closes.size or np.any(closes <= opens) or np.any(opens[1:] <= closes[:-1]):
        return None
    commas = np.flatnonzero(codes == ord(","))
    per_row = np.searchsorted(commas, closes) - np.searchsorted(commas, opens)
    del commas, closes
    ncol = int(per_row[0]) + 1
    if ncol < 2 or np.any(per_row != ncol - 1):  # (numpy reads a blank "[]" row as -1.0)
        return None
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        try:
            values = np.fromstring(raw[start:stop].translate(_TO_SPACE), dtype=float, sep=" ")
        except (ValueError, DeprecationWarning):
            return None
    if values.size != opens.size * ncol or not np.all(np.isfinite(values)):
        return None
    return values.reshape(opens.size, ncol), opens


def _parse_test(part: tuple[bytes, int, int, int], report: Any = None) -> tuple[_Parsed, int] | None:
    """A test's rows ``raw[start:stop]`` whose ``[`` is on line ``line``: (rows and their lines, newlines
    inside), or None (:func:`_parse_rows`); ``report.advance()`` when given."""
    raw, start, stop, line = part
    found = _parse_rows(raw, start, stop)
    if report is not None:
        report.advance()
    if found is None:
        return None
    rows, opens = found
    breaks = raw.count(b"\n", start, stop)
    if breaks:
        newlines = np.flatnonzero(np.frombuffer(raw, dtype=np.uint8, count=stop - start, offset=start) == ord("\n"))
        lines = line + np.searchsorted(newlines, opens)
    else:  # (SysId writes its JSON on one line)
        lines = np.full(opens.size, line)
    return _Parsed(rows, lines.astype(int)), breaks


#: Tests of more bytes than this in all are parsed in two processes where this one may fork
#: (:func:`motorlab.parallel.can_fork`): numpy's parser holds the GIL, about 0.3 µs a number here.
PARALLEL_BYTES = 16_000_000


def _parse_tests(parts: list[tuple[bytes, int, int, int]], report: Any) -> list[tuple[_Parsed, int] | None]:
    """:func:`_parse_test` of each part (``report.advance()`` after each); a large file's half in a forked
    child while this process parses the other."""
    from motorlab import parallel

    sizes = [stop - start for _, start, stop, _ in parts]
    if len(parts) < 2 or sum(sizes) < PARALLEL_BYTES or not parallel.can_fork():
        return [_parse_test(part, report) for part in parts]
    groups: list[list[int]] = [[], []]
    for k in sorted(range(len(parts)), key=lambda k: -sizes[k]):  # largest first, to the lighter group
        min(groups, key=lambda g: sum(sizes[i] for i in g)).append(k)
    child = parallel.Forked(_parse_group, [parts[k] for k in groups[1]])
    done = [[_parse_test(parts[k], report) for k in groups[0]]]
    try:
        done.append(child.result())
    except ChildProcessError:  # killed (out of memory?): its half here, then
        done.append(_parse_group([parts[k] for k in groups[1]]))
    report.advance(len(groups[1]))
    found: dict[int, tuple[_Parsed, int] | None] = {}
    for group, results in zip(groups, done, strict=True):
        found.update(zip(group, results, strict=True))
    return [found[k] for k in range(len(parts))]


def _parse_group(parts: list[tuple[bytes, int, int, int]]) -> list[tuple[_Parsed, int] | None]:
    return [_parse_test(part) for part in parts]


def _extract_tests(raw: bytes, name: str = "") -> tuple[bytes, dict[str, _Parsed]]:
    """The four tests' arrays parsed by numpy, and ``raw`` with each replaced by ``[]`` (lines kept).

    A 2M-row SysId file as Python lists would take about 1 GB; as arrays it takes 64 MB. A test
    whose rows are not plain numbers of one length is left in place for ``json.loads`` and the
    row-by-row checks, which name the line of the problem.
    """
    found: list[tuple[str, int, int]] = []
    at = 0
    for match in _TEST_START.finditer(raw):
        if match.start() < at:
            continue
        end = _TEST_END.search(raw, match.end())
        if end is None:
            break
        found.append((match.group(1).decode("ascii"), match.start(2), end.end()))
        at = end.end()
    parsed: dict[str, _Parsed] = {}
    pieces: list[bytes] = []
    at = 0
    parts, line, counted = [], 1, 0
    for _, start, stop in found:  # each test's first line: the newlines before it, each counted once
        line += raw.count(b"\n", counted, start)
        counted = start
        parts.append((raw, start, stop, line))
    with progress.task(f"Reading {os.path.basename(name)}", total=len(found), unit="tests") as report:
        done = _parse_tests(parts, report)
        for (test, start, stop), result in zip(found, done, strict=True):
            if result is None:
                continue
            parsed[test], breaks = result
            pieces += [raw[at:start], b"[" + b"\n" * breaks + b"]"]
            at = stop
    return b"".join([*pieces, raw[at:]]), parsed


def _load(path: PathArg) -> tuple[str, dict[str, Any], str]:
    name, raw = read_bytes(path)
    raw, parsed = _extract_tests(raw.removeprefix(b"\xef\xbb\xbf"), name)
    if not raw.strip():
        raise LogFormatError("the file is empty", path=name)
    if b"\0" in raw:
        raise LogFormatError("not a text file (it contains binary data)", path=name)
    try:
        text = raw.decode("utf-8-sig")  # JSON is UTF-8 by definition (RFC 8259)
    except UnicodeDecodeError:
        raise LogFormatError("not a text file (invalid UTF-8)", path=name) from None
    data = load_json(text, name)
    if not isinstance(data, dict):
        raise LogFormatError("expected a JSON object with test names as keys", path=name, line=1)
    data.update(parsed)
    return name, data, text


_TOKEN = re.compile(r'"(?:[^"\\]|\\.)*"|[\[\]{}]')


def _row_lines(text: str) -> dict[str, list[int]]:
    """1-based line of each row of each top-level list (``{"slow-forward": [12, 23, ...]}``)."""
    starts: dict[str, list[int]] = {}
    depth = 0
    last_string = ""
    current: list[int] | None = None
    positions: list[int] = []
    for match in _TOKEN.finditer(text):
        token = match.group()
        if token[0] == '"':
            if depth == 1:
                last_string = token[1:-1]
            continue
        if token in "[{":
            if depth == 1 and token == "[":
                current = starts.setdefault(last_string, [])
            elif depth == 2 and token == "[" and current is not None:
                current.append(len(positions))
                positions.append(match.start())
            depth += 1
        else:
            depth -= 1
            if depth == 1:
                current = None
    if text.isascii():  # fast path; character and byte offsets agree
        newlines = np.flatnonzero(np.frombuffer(text.encode("ascii"), dtype=np.uint8) == ord("\n"))
    else:
        newlines = np.fromiter((m.start() for m in re.finditer("\n", text)), dtype=int)
    lines = np.searchsorted(newlines, np.asarray(positions, dtype=int), side="left") + 1
    return {key: [int(lines[i]) for i in idx] for key, idx in starts.items()}


def _tests(name: str, data: dict[str, Any], text: str, columns: tuple[int, ...]) -> tuple[list[_Test], list[str]]:
    """The standard tests present, as float arrays, checked (numbers, finite, column count, time order)."""
    line_map = _row_lines(text)
    tests: list[_Test] = []
    warnings: list[str] = []
    for key in TESTS:
        if key not in data:
            continue
        rows = data[key]
        lines = line_map.get(key, [])
        if isinstance(rows, _Parsed):  # parsed by numpy: plain numbers, one row length, finite
            if rows.rows.shape[1] not in columns:
                raise LogFormatError(
                    f"test {key!r}: rows should have {' or '.join(map(str, columns))} columns, "
                    f"found {rows.rows.shape[1]}",
                    path=name,
                    line=int(rows.lines[0]),
                )
            _check_time_order(key, rows.rows, rows.lines, name)
            tests.append(_Test(key, rows.rows, rows.lines))
            continue
        if not isinstance(rows, list):
            raise LogFormatError(f"{key!r} should be a list of rows", path=name)
        if not rows:
            warnings.append(f"test {key!r} is empty")
            continue
        ncol = len(rows[0]) if isinstance(rows[0], list) else -1
        if ncol not in columns:
            raise LogFormatError(
                f"test {key!r}: rows should have {' or '.join(map(str, columns))} columns, found {ncol}",
                path=name,
                line=lines[0] if lines else None,
            )
        for k, row in enumerate(rows):
            line = lines[k] if k < len(lines) else None
            if not isinstance(row, list) or len(row) != ncol:
                found = len(row) if isinstance(row, list) else type(row).__name__
                message = f"test {key!r} row {k}: expected {ncol} values, found {found}"
                raise LogFormatError(message, path=name, line=line)
            for value in row:
                if isinstance(value, bool) or not isinstance(value, int | float):
                    raise LogFormatError(f"test {key!r} row {k}: {value!r} is not a number", path=name, line=line)
                if not math.isfinite(value):
                    message = f"test {key!r} row {k}: {value!r} is not a finite number"
                    raise LogFormatError(message, path=name, line=line)
        array = np.asarray(rows, dtype=float)
        line_arr = np.asarray(lines if len(lines) == len(rows) else np.zeros(len(rows)), dtype=int)
        _check_time_order(key, array, line_arr, name)
        tests.append(_Test(key, array, line_arr))
    # frc-characterization's drivetrain files also hold a "track-width" test (not a feedforward test).
    unknown = [key for key, rows in data.items() if key not in (*TESTS, "track-width") and _looks_like_rows(rows)]
    for key in unknown:
        close = difflib.get_close_matches(key, TESTS, n=1)
        hint = f"did you mean {close[0]!r}? " if close else ""
        lines = line_map.get(key, [])
        where = f"{name}:{lines[0]}" if lines else name
        warnings.append(
            f"{where}: {key!r} is not a test name ({hint}known: {', '.join(TESTS)}): its rows were not used"
        )
    if not tests:
        also = f" (found {', '.join(map(repr, unknown))} instead)" if unknown else ""
        raise LogFormatError(f"no test data: none of {', '.join(TESTS)} is in the file{also}", path=name)
    return tests, warnings


def _check_time_order(key: str, rows: np.ndarray, lines: np.ndarray, name: str) -> None:
    back = np.flatnonzero(np.diff(rows[:, 0]) < 0)
    if back.size:
        i = int(back[0]) + 1
        raise LogFormatError(f"test {key!r}: time goes backwards at row {i}", path=name, line=int(lines[i]))


def _looks_like_rows(value: Any) -> bool:
    """True for a non-empty list of lists (a test's data under a name that is not a test's)."""
    return isinstance(value, list) and bool(value) and all(isinstance(row, list) for row in value[:3])


@dataclass
class _Units:
    units: str  # as written (or assumed)
    upr: float  # unitsPerRotation (1 when the file has none: rows are in ``units`` already)
    si_unit: str  # "m" or "rad"
    factor: float  # row value -> SI
    si_per_unit: float  # one ``units`` in SI
    rotation_si: float | None  # one logged rotation of the encoder shaft in SI (None: unknown)
    assumed: str | None  # what was assumed, for the warnings


#: Units of the pre-2020 frc-characterization robot templates, whose files carry no ``units`` key:
#: drivetrains and elevators logged feet ("getDistance and getRate should return ft and ft/s"), arms
#: degrees (``robot-java/src/main/java/dc/Robot.java``, ``arm-characterization/robot-python/robot.py``).
LEGACY_UNITS = {"arm": "Degrees", "other": "Feet"}


def _units(name: str, data: dict[str, Any], *, units: str | None = None, legacy: bool = False) -> _Units:
    """The file's units; ``units`` (the user's) fills in or must agree with the file's ``units`` key.

    ``legacy``: a frc-characterization file may lack ``units`` and ``unitsPerRotation`` (older tool
    versions): the templates' units are assumed (:data:`LEGACY_UNITS`) and said so.
    """
    written = data.get("units")
    upr = data.get("unitsPerRotation")
    known = ", ".join(u.title() for u in UNITS)
    if units is not None and units.lower() not in UNITS:
        raise OptionError(f"units {units!r} unknown; expected one of {known}")
    assumed = None
    if written is None and units is not None:
        written = units.title()
        assumed = f"no 'units' key: rows read as {written} (as given)"
    elif written is None and legacy:
        written = LEGACY_UNITS["arm" if str(data.get("test", "")).lower() == "arm" else "other"]
        assumed = (f"no 'units' key (an older frc-characterization file): rows read as {written}, the unit of "
                   "that tool's robot templates; if the robot code logged another, give it (--units)")
    elif isinstance(written, str) and units is not None and written.lower() != units.lower():
        raise OptionError(f"{name}: the file logs {written}; the unit given ({units}) contradicts it")
    if not isinstance(written, str) or written.lower() not in UNITS:
        raise LogFormatError(f"units {written!r} unknown; expected one of {known}", path=name)
    if upr is None and assumed is not None:
        upr = 1.0
    if isinstance(upr, bool) or not isinstance(upr, int | float) or not math.isfinite(upr) or upr <= 0:
        raise LogFormatError(f"unitsPerRotation {upr!r} is not a positive number", path=name)
    low, high = UNITS_PER_ROTATION_RANGE
    if not low <= upr <= high:
        raise LogFormatError(f"unitsPerRotation {upr!r} is outside {low:g} … {high:g}: no mechanism turns a rotation "
                             "into that many units (a wheel's circumference, 360 degrees, a gear ratio)", path=name)
    si_unit = UNITS[written.lower()][1]
    si_per_unit = SI_PER_UNIT[written.lower()]
    if "unitsPerRotation" in data:
        rotation_si: float | None = float(upr) * si_per_unit
    else:  # rows in the unit itself: a rotation is known only for angles
        rotation_si = 2.0 * math.pi if si_unit == "rad" else None
    return _Units(written, float(upr), si_unit, float(upr) * si_per_unit, si_per_unit, rotation_si, assumed)


def _check_side(side: str) -> tuple[int, ...]:
    if side == BOTH:
        return (0, 1)
    if side not in _SIDES:
        raise OptionError(f"side must be 'left', 'right' or 'both', got {side!r}")
    return (_SIDES.index(side),)


def _side_names(drivetrain: bool, sides: tuple[int, ...], key: str) -> list[tuple[int, str]]:
    """(side index, segment name) of each part a test gives: one per side asked for a drivetrain."""
    if not drivetrain:
        return [(0, key)]
    if len(sides) == 1:
        return [(sides[0], key)]
    return [(i, f"{key}#{_SIDES[i]}") for i in sides]


def _assemble(
    name: str,
    parts: list[tuple[str, dict[str, np.ndarray], np.ndarray]],
    metadata: dict[str, Any],
) -> Recording:
    """Concatenate per-test signals (with ``time``) into one recording with segments."""
    segments: dict[str, tuple[int, int]] = {}
    start = 0
    for key, signals, _ in parts:
        stop = start + signals["time"].size
        segments[key] = (start, stop)
        start = stop
    names = [k for k in parts[0][1] if k != "time"]
    time = np.concatenate([s["time"] for _, s, _ in parts])
    signals = {k: np.concatenate([s[k] for _, s, _ in parts]) for k in names}
    metadata["segment_kinds"] = {key: test_kind(key) for key, _, _ in parts}
    return Recording(
        time=time,
        signals=signals,
        metadata=metadata,
        source=name,
        lines=np.concatenate([lines for _, _, lines in parts]),
        segments=segments,
    )


def _unit_metadata(unit: _Units) -> dict[str, Any]:
    return {
        "units": unit.units,
        "unitsPerRotation": unit.upr,
        "position_unit": unit.si_unit,
        "velocity_unit": f"{unit.si_unit}/s",
        "si_per_unit": unit.si_per_unit,
        "rotation_si": unit.rotation_si,
        "units_assumed": unit.assumed is not None,
    }


def _direction_warnings(key: str, voltage: np.ndarray, velocity: np.ndarray) -> list[str]:
    """A warning when the motion of a test mostly opposes its applied voltage (inverted sensor?)."""
    moving = (np.abs(velocity) > 0) & (voltage != 0)
    if moving.sum() < 10:
        return []
    agree = np.mean(np.sign(velocity[moving]) == np.sign(voltage[moving]))
    if agree < 0.5:
        return [f"test {key!r}: velocity opposes the voltage in {100 * (1 - agree):.0f} % of moving samples"]
    return []


def read_sysid_json(path: PathArg, *, side: str = "left", units: str | None = None) -> Recording:
    """Read a WPILib SysId JSON log (``"sysid": true``; the format before data logs).

    Parameters
    ----------
    path
        The JSON file.
    side
        For drivetrain tests (rows of 9 values), which side to take: ``"left"``, ``"right"`` or
        ``"both"`` (each test twice, segments ``<test>#left`` and ``<test>#right``).
    units
        The file's unit (``"Meters"`` …) when it has no ``units`` key; it must agree with one it has.

    Returns
    -------
    Recording
        The four tests one after the other, ``segments`` per test. Signals: ``voltage`` [V] (signed,
        as SysId logs it), ``position`` and ``velocity`` = row value × ``unitsPerRotation`` converted to
        SI: [rad], [rad/s] for angular units, [m], [m/s] for linear ones. ``metadata``: ``format``
        ``"sysid-json"``, ``test`` (``Simple``, ``Arm``, ``Elevator``, ``Drivetrain`` …), ``units`` as
        written, ``unitsPerRotation``, ``position_unit``/``velocity_unit`` (SI), ``si_per_unit`` (one
        file unit in SI), ``rotation_si`` (one logged rotation in SI), ``units_assumed``, ``side``
        (drivetrain), ``segment_kinds``, ``repeated_fraction`` (share of rows whose position and velocity repeat
        the previous row's: the controller's status frame is slower than the logging loop) and
        ``repeated_fraction_by_test``.

    Raises
    ------
    LogFormatError
        Not JSON, no ``"sysid"`` key, unknown units, rows of the wrong length, non-numbers, NaN,
        time going backwards.
    OptionError
        Bad ``side``.

    Notes
    -----
    Rows are ``timestamp, voltage, position, velocity`` or, for drivetrains, ``timestamp, l voltage,
    r voltage, l position, r position, l velocity, r velocity, angle, angular rate``; positions and
    velocities are in rotations of the encoder shaft, and SysId's loader multiplies them by
    ``unitsPerRotation``. Repeated rows are kept as recorded: dropping them would bias the sampling.
    """
    sides = _check_side(side)
    name, data, text = _load(path)
    if not data.get("sysid"):
        raise LogFormatError(
            'not a SysId JSON file (no "sysid": true); frc-characterization files are read by read_frc_char_json',
            path=name,
        )
    unit = _units(name, data, units=units)
    tests, warnings = _tests(name, data, text, (4, 9))
    if unit.assumed:
        warnings.insert(0, unit.assumed)
    drivetrain = tests[0].rows.shape[1] == 9
    parts = []
    repeated: dict[str, float] = {}
    n_repeated = 0
    for test in tests:
        if test.rows.shape[1] != tests[0].rows.shape[1]:
            raise LogFormatError(f"test {test.name!r} has rows of another length than {tests[0].name!r}", path=name)
        rows = test.rows
        for index, key in _side_names(drivetrain, sides, test.name):
            cols = (1 + index, 3 + index, 5 + index) if drivetrain else (1, 2, 3)
            signals = {
                "time": rows[:, 0],
                "voltage": rows[:, cols[0]],
                "position": rows[:, cols[1]] * unit.factor,
                "velocity": rows[:, cols[2]] * unit.factor,
            }
            same = np.all(np.diff(rows[:, list(cols[1:])], axis=0) == 0, axis=1)
            repeated[key] = float(same.mean()) if same.size else 0.0
            n_repeated += int(same.sum())
            warnings += _direction_warnings(key, signals["voltage"], signals["velocity"])
            parts.append((key, signals, test.lines))
    total = sum(max(s["time"].size - 1, 0) for _, s, _ in parts)
    metadata = {
        "format": "sysid-json",
        "test": data.get("test"),
        **_unit_metadata(unit),
        "side": side if drivetrain else None,
        "repeated_fraction": n_repeated / total if total else 0.0,
        "repeated_fraction_by_test": repeated,
        "other_keys": [k for k in data if isinstance(data[k], list) and k not in TESTS],
        "warnings": warnings,
    }
    return _assemble(name, parts, metadata)


def read_frc_char_json(path: PathArg, *, side: str = "left", units: str | None = None) -> Recording:
    """Read a frc-characterization JSON log (WPILib's Python-era tool, before SysId).

    Parameters
    ----------
    path
        The JSON file.
    side
        For drivetrain data (rows of 10 values, or 9 without the gyro in older files), which side to
        take: ``"left"``, ``"right"`` or ``"both"`` (segments ``<test>#left``, ``<test>#right``).
    units
        The unit of a file without a ``units`` key (older tool versions); by default the tool's
        template unit is assumed (:data:`LEGACY_UNITS`) and a warning says so.

    Returns
    -------
    Recording
        The four tests one after the other, ``segments`` per test. Signals: ``voltage`` [V] signed to
        match the motion (negative in the backward tests), ``battery`` [V], ``position``,
        ``velocity`` (row × ``unitsPerRotation`` in SI: [m], [m/s] or [rad], [rad/s]).
        ``metadata``: ``format`` ``"frc-char-json"``, ``test``, ``units`` as written (or assumed),
        ``unitsPerRotation``, ``position_unit``/``velocity_unit``, ``si_per_unit``, ``rotation_si``,
        ``units_assumed``, ``side`` (drivetrain),
        ``segment_kinds``, ``stale_rows_dropped`` ({test: rows}), ``other_keys`` (e.g.
        ``track-width``, not read) and ``warnings``.

    Raises
    ------
    LogFormatError
        Not JSON, a SysId file, unknown units, rows of the wrong length, non-numbers, NaN, time going
        backwards.
    OptionError
        Bad ``side``.

    Notes
    -----
    Drivetrain rows are ``time, battery, autospeed, l_volts, r_volts, l_pos, r_pos, l_vel, r_vel,
    gyro_angle``; other mechanisms ``time, battery, autospeed, volts, pos, vel``. Quirks handled:

    * the applied voltage is logged as a magnitude; the sign is the test's direction (backward
      tests negative), so that voltage and velocity agree as in the model V = kS·sgn(v) + kV·v + kA·a;
    * the first row of a test can carry a stale voltage from the previous test (``autospeed`` is 0
      but the voltage is not): such a row is dropped and counted in ``stale_rows_dropped``.
    """
    sides = _check_side(side)
    name, data, text = _load(path)
    if data.get("sysid"):
        raise LogFormatError('this is a SysId JSON file ("sysid": true): use read_sysid_json', path=name)
    unit = _units(name, data, units=units, legacy=True)
    tests, warnings = _tests(name, data, text, (6, 9, 10))
    if unit.assumed:
        warnings.insert(0, unit.assumed)
    drivetrain = tests[0].rows.shape[1] in (9, 10)
    parts = []
    stale: dict[str, int] = {}
    for test in tests:
        if test.rows.shape[1] != tests[0].rows.shape[1]:
            raise LogFormatError(f"test {test.name!r} has rows of another length than {tests[0].name!r}", path=name)
        direction = test_kind(test.name)["direction"]
        for index, key in _side_names(drivetrain, sides, test.name):
            cols = (3 + index, 5 + index, 7 + index) if drivetrain else (3, 4, 5)
            rows, lines = test.rows, test.lines
            if rows.shape[0] > 1 and rows[0, 2] == 0 and rows[0, cols[0]] != 0:
                rows, lines = rows[1:], lines[1:]
                stale[key] = 1
            signals = {
                "time": rows[:, 0],
                "voltage": direction * np.abs(rows[:, cols[0]]) + 0.0,  # + 0.0: no -0.0
                "battery": rows[:, 1],
                "position": rows[:, cols[1]] * unit.factor,
                "velocity": rows[:, cols[2]] * unit.factor,
            }
            warnings += _direction_warnings(key, signals["voltage"], signals["velocity"])
            parts.append((key, signals, lines))
    metadata = {
        "format": "frc-char-json",
        "test": data.get("test"),
        **_unit_metadata(unit),
        "side": side if drivetrain else None,
        "stale_rows_dropped": stale,
        "other_keys": [k for k in data if isinstance(data[k], list) and k not in TESTS],
        "warnings": warnings,
    }
    return _assemble(name, parts, metadata)
