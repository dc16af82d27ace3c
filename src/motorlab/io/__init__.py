"""Readers (and the writers the virtual rig uses): one module per file format, one shape for all.

Every reader is ``read_<format>(path, *, ...) -> Recording`` with SI arrays under the canonical
signal names of :data:`motorlab.recording.SIGNALS`; problems raise
:class:`~motorlab.errors.LogFormatError` naming the file and line. :func:`read_any` picks the reader
from the extension and the content. See ``docs/formats.md``.

========================  ======================================  ==================================
format                    reader                                  writer
========================  ======================================  ==================================
FTC OpMode log (.txt)     :func:`read_ftc_log`                    :func:`write_ftc_log`
CSV with unit header      :func:`read_csv`                        :func:`write_csv`
scope cursor times        :func:`read_scope_times`                :func:`write_csv` (``time_ms``)
scope waveform (Rigol)    :func:`read_scope_waveform`
SysId JSON                :func:`read_sysid_json`
frc-characterization      :func:`read_frc_char_json`
WPILib data log           :func:`read_wpilog`                     :func:`write_wpilog`,
                                                                  :func:`write_sysid_wpilog`
Road Runner ramp (.json)  :func:`read_roadrunner_ramp`            :func:`write_roadrunner_ramp`
Road Runner flight .log   :func:`read_flight_recorder`            :func:`write_flight_log`
FTC SDK Datalogger        :func:`read_datalogger`
========================  ======================================  ==================================
"""

from __future__ import annotations

import inspect
import os
import re
from collections.abc import Callable, Sequence
from typing import Any

from motorlab.errors import LogFormatError, OptionError
from motorlab.io.csv_table import COLUMNS, guess_delimiter, is_known_header, read_csv, split_fields, write_csv
from motorlab.io.datalogger import is_datalogger_header, read_datalogger
from motorlab.io.flightrecorder import read_flight_log_channels, read_flight_recorder, write_flight_log
from motorlab.io.frc_json import read_frc_char_json, read_sysid_json
from motorlab.io.ftc import read_ftc_log, write_ftc_log
from motorlab.io.roadrunner import read_roadrunner_ramp, write_roadrunner_ramp
from motorlab.io.scope import find_rising_edges, read_scope_times, read_scope_waveform
from motorlab.io.text import PathArg, check_distinct, check_input_file, decode_text, is_binary, is_number, read_bytes
from motorlab.io.wpilog import (
    WpilogEntry,
    read_wpilog,
    read_wpilog_entries,
    write_sysid_wpilog,
    write_wpilog,
)
from motorlab.recording import Recording

#: Format name (as in ``metadata["format"]``) -> reader.
READERS: dict[str, Callable[..., Recording]] = {
    "ftc-log": read_ftc_log,
    "csv": read_csv,
    "scope-times": read_scope_times,
    "scope-waveform": read_scope_waveform,
    "sysid-json": read_sysid_json,
    "frc-char-json": read_frc_char_json,
    "wpilog": read_wpilog,
    "roadrunner-ramp": read_roadrunner_ramp,
    "roadrunner-log": read_flight_recorder,
    "datalogger": read_datalogger,
}

_CHANNEL = re.compile(r"^ch\d+(_v)?$", re.IGNORECASE)
_SYSID_FLAG = re.compile(r'"sysid"\s*:\s*true')
_RR_RAMP = re.compile(r'"(forwardEncPositions|perpEncPositions|angVels)"\s*:')
_HEAD = 1 << 16


def _tail(name: str) -> str:
    """The last :data:`_HEAD` bytes of a file larger than twice that, decoded ("" for a smaller one)."""
    with open(name, "rb") as handle:
        size = handle.seek(0, os.SEEK_END)
        if size <= 2 * _HEAD:
            return ""
        handle.seek(size - _HEAD)
        return decode_text(handle.read())[0]


def detect_format(path: PathArg) -> str:
    """The format of ``path`` (a key of :data:`READERS`), from its extension and content.

    Raises
    ------
    LogFormatError
        Missing, empty or binary file that is not a data log; text in no known layout.
    """
    name, _limit = check_input_file(path)
    try:
        with open(name, "rb") as handle:
            raw = handle.read(_HEAD)  # the layout shows in the first lines; a 2M-row log is not read twice
    except OSError as exc:
        raise LogFormatError(f"cannot read the file ({exc.strerror})", path=name) from None
    extension = os.path.splitext(name)[1].lower()
    if raw[:6] == b"WPILOG" or extension == ".wpilog":
        return "wpilog"
    if raw[:4] in (b"RR\x00\x00", b"RR\x00\x01"):  # Road Runner FlightRecorder (LogFile.kt)
        return "roadrunner-log"
    if not raw.strip():
        raise LogFormatError("the file is empty", path=name)
    if is_binary(raw[: raw.rfind(b"\n") + 1] if len(raw) == _HEAD else raw):
        raise LogFormatError("not a text file (it contains binary data) and not a WPILib data log", path=name)
    text, _encoding = decode_text(raw)
    if extension == ".json" or text.lstrip().startswith("{"):
        # The keys that tell these JSON files apart sit before or after their arrays (SysId writes
        # "sysid": true after its tests): the head and the last 64 KiB first, the whole file only if needed.
        for part in (text + _tail(name), None):
            part = decode_text(read_bytes(name)[1])[0] if part is None else part
            if _RR_RAMP.search(part):
                return "roadrunner-ramp"
            if _SYSID_FLAG.search(part):
                return "sysid-json"
        return "frc-char-json"
    if len(raw) == _HEAD:
        text = text[: max(text.rfind("\n"), 0)]  # drop the line the head cut
    lines = [line.strip() for line in text.splitlines()]
    lines = [line for line in lines if line and not line.startswith("#")]
    if not lines:
        raise LogFormatError("no data (only comments)", path=name)
    first = lines[0]
    comma = [f.lower() for f in split_fields(first, ",")]
    if comma and comma[0] == "x" and "increment" in comma:
        return "scope-waveform"
    fields = split_fields(first, guess_delimiter(first))
    lower = [f.lower() for f in fields]
    if len(lower) == 1 and lower[0] in ("time_ms", "time_s"):
        return "scope-times"
    if len(lower) > 1 and lower[0] in ("time_ms", "time_s") and all(_CHANNEL.match(f) for f in lower[1:]):
        return "scope-waveform"
    if is_datalogger_header(split_fields(first, ",")):  # FTC SDK Datalogger: Timestamp,OpModeStatus,…
        return "datalogger"
    if is_known_header(fields):
        return "csv"
    if all(is_number(f) for f in fields):
        if len(fields) == 1:
            return "scope-times"
        if guess_delimiter(first) is None:
            return "ftc-log"
    if extension == ".csv":
        return "csv"  # read_csv explains which columns it knows
    return "ftc-log"


def read_any(path: PathArg | Sequence[PathArg], *, cpr: float | None = None, **options: Any) -> Recording:
    """Read a log of any supported format, choosing the reader with :func:`detect_format`.

    Parameters
    ----------
    path
        One file, or the files of one FTC run in order (``[testFile.txt, testFile2.txt]``).
    cpr
        Encoder counts per revolution [count/rev], for the readers that use it (FTC log, CSV).
    **options
        Passed to the reader (``current_unit=``, ``side=``, ``threshold=`` …).

    Raises
    ------
    LogFormatError
        As the chosen reader; or an unknown layout.
    OptionError
        An option the chosen reader does not take (e.g. ``cpr`` for a SysId JSON file).
    """
    if isinstance(path, str | os.PathLike):
        fmt = detect_format(path)
        target: Any = path
    else:
        files = list(path)
        check_distinct(files)
        if len(files) == 1:
            return read_any(files[0], cpr=cpr, **options)
        formats = {detect_format(p) for p in files}
        if formats != {"ftc-log"}:
            raise OptionError("several files are read together only for a split FTC log (testFile.txt + testFile2.txt)")
        fmt, target = "ftc-log", files
    reader = READERS[fmt]
    accepted = inspect.signature(reader).parameters
    if cpr is not None:
        options["cpr"] = cpr
    for key in options:
        if key not in accepted:
            raise OptionError(f"option {key!r} does not apply to {fmt} files")
    return reader(target, **options)


__all__ = [
    "COLUMNS",
    "READERS",
    "WpilogEntry",
    "detect_format",
    "find_rising_edges",
    "read_any",
    "read_csv",
    "read_datalogger",
    "read_flight_log_channels",
    "read_flight_recorder",
    "read_frc_char_json",
    "read_ftc_log",
    "read_roadrunner_ramp",
    "read_scope_times",
    "read_scope_waveform",
    "read_sysid_json",
    "read_wpilog",
    "read_wpilog_entries",
    "write_csv",
    "write_flight_log",
    "write_ftc_log",
    "write_roadrunner_ramp",
    "write_sysid_wpilog",
    "write_wpilog",
]
