"""``motorlab robot pull``: bring the robot's logs home, byte for byte, and propose each one's analysis.

What the robot serves on port 8080 (read from the projects' sources, commits named in docs/robot.md):

* Road Runner 1.0 (road-runner-ftc ``RoadRunner/src/main/java/com/acmerobotics/roadrunner/ftc/FileServing.kt``,
  ``TuningFiles``): for each ``FileType`` (``forward-ramp``, ``lateral-ramp``, ``angular-ramp``, ``accel``)
  ``GET /tuning/<type>/latest.json`` answers the most recently modified file of
  ``/sdcard/RoadRunner/tuning/<type>/`` with its name in the ``X-Filename`` header (a chunked body, no
  length), or 404 with an empty body when there is none. Every file is also registered at
  ``/tuning/<type>/<millis>.json``, but nothing lists them: only the latest of each type can be
  reached without guessing names, so each pull adds the latest beside the earlier pulls in ``DIR``.
* Road Runner's ``LogFiles``: ``GET /logs`` is an HTML list, newest first, of
  ``<li><a href="/logs/download?file=NAME" download="NAME">NAME</a> (SIZE bytes)</li>``;
  ``GET /logs/download?file=NAME`` sends the file (chunked, ``application/json`` whatever it holds). The
  query string is split on ``&`` and ``=`` and not URL-decoded (FileServing.kt:172-182), so the name is
  sent as it is listed, its bytes in UTF-8 (NanoHTTPD reads the request line in the platform's charset,
  UTF-8 on Android: NanoHTTPD.java:917): ``$``, ``%``, ``#`` or ``é`` arrive as they are. A name holding
  white space, ``&``, ``=`` or a control character cannot be asked for at all (the request line or the
  query would be cut there): it is named as not pulled. On a robot without a log folder ``/logs`` throws
  (``LOG_ROOT.listFiles()!!``, FileServing.kt:153) and the robot answers nothing or 500.
* motorlab's own handler (``ftc/…/motorlab/MotorlabLogFiles.java``): ``GET /motorlab/logs`` answers JSON
  ``{"folder": …, "files": [{"name", "bytes", "modified_ms"}, …]}`` and
  ``GET /motorlab/logs/download?file=NAME`` the file with its ``Content-Length``.

Files are written under ``DIR/tuning/<type>/``, ``DIR/logs/`` and ``DIR/motorlab/`` (the robot's own
folders, so two types' ``<millis>.json`` never collide), through a temporary name and a rename: a file
is either complete or absent. A file whose size differs from the size the robot listed is refused.

One file or route that fails never costs the others: each failure is kept as one line
(:attr:`PullResult.failed`), the rest arrive byte for byte, and the CLI's exit code says "partial"
(3). Only a robot that cannot be reached at all stops the pull at once.
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import tempfile
import urllib.parse
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from motorlab import progress
from motorlab.robot import RobotLinkError
from motorlab.robot.http import Reply, RobotHttp, RobotUnreachable

#: Road Runner's ``TuningFiles.FileType`` base names (FileServing.kt).
TUNING_TYPES = ("forward-ramp", "lateral-ramp", "angular-ramp", "accel")
#: motorlab's handler routes (MotorlabLogFiles.java).
MOTORLAB_LIST = "/motorlab/logs"
MOTORLAB_DOWNLOAD = "/motorlab/logs/download"

#: One entry of Road Runner's ``/logs`` page (LogFiles.registerRoutes, FileServing.kt:155-164), the name
#: written three times as it is (not escaped): ``<li><a href="/logs/download?file=NAME" download="NAME">NAME</a>
#: (SIZE bytes)</li>``. :func:`log_entries` reads it exactly; this looser pattern is the fallback for a
#: page written a little differently.
_LOG_ENTRY = re.compile(r'href="/logs/download\?file=([^"]*)"[^>]*>[^<]*</a>(?:\s*\((\d+) bytes\))?')
_ENTRY_START = '<li><a href="/logs/download?file='
#: What Road Runner's query parsing cuts at, or the request line cannot carry (FileServing.kt:172-177;
#: NanoHTTPD's StringTokenizer splits the request line on white space, NanoHTTPD.java:667-679).
_UNASKABLE = re.compile(r"[\s&=\x00-\x1f\x7f]")
#: A name the robot may give: one path component, no separators, nothing hidden.
_SAFE_NAME = re.compile(r"^[^/\\\x00-\x1f]{1,255}$")


@dataclass
class PulledFile:
    """One file brought back: where it came from and where it is, and what to analyse it with."""

    source: str
    path: Path
    size: int
    status: str
    format: str | None = None
    experiment: str | None = None
    command: str | None = None
    note: str | None = None

    def to_dict(self) -> dict[str, Any]:
        return {"source": self.source, "path": str(self.path), "name": self.path.name, "bytes": self.size,
                "status": self.status, "format": self.format, "experiment": self.experiment,
                "command": self.command, "note": self.note}


@dataclass
class NotPulled:
    """A file (or a list of files) that did not come: which, why and what to do, each in words.

    ``line`` is the one line ``motorlab robot pull`` prints for it (the route and the robot's address in it).
    """

    file: str
    reason: str
    todo: str
    line: str

    def to_dict(self) -> dict[str, str]:
        return {"file": self.file, "reason": self.reason, "todo": self.todo, "line": self.line}


#: What to do about a failure whose message says nothing of it.
DEFAULT_TODO = "pull again; if it fails again, copy the file from the robot by USB"
#: Advice a failure's message may end with (its last clause): kept as the failure's "what to do".
_ADVICE = re.compile(r"[:;]\s*((?:[^:;]*\b(?:pull again|by USB|rename it|install|copy)\b[^:;]*))$")


def not_pulled(what: str, message: str, address: str) -> NotPulled:
    """The failure of the file or route ``what`` (a path the robot serves) from its one-line ``message``."""
    path, _, query = what.partition("?file=")
    if query:
        name = urllib.parse.unquote(query) if path == MOTORLAB_DOWNLOAD else query
    elif path.startswith("/tuning/"):
        name = f"the newest {path.split('/')[2]} file of Road Runner's tuning"
    else:
        name = {"/logs": "the list of FlightRecorder logs", MOTORLAB_LIST: "the list of motorlab's logs",
                "": "the rest of the robot's files"}.get(path, f"the robot's files ({path})")
    reason = message
    for prefix in (f"{what} from {address}: ", f"{what}: ", f"{path} from {address}: "):
        reason = reason.removeprefix(prefix)
    advice = _ADVICE.search(reason)
    todo = advice.group(1).strip() if advice else DEFAULT_TODO
    if advice:
        reason = reason[:advice.start()].strip()
    return NotPulled(name, reason, todo, message)


@dataclass
class PullResult:
    """What ``pull`` found: files, the services the robot does not have (with what to do), and the files that
    did not come (``failed``: one line each; ``not_pulled``: the same, in words for the app)."""

    address: str
    folder: Path
    files: list[PulledFile] = field(default_factory=list)
    missing: list[str] = field(default_factory=list)
    not_pulled: list[NotPulled] = field(default_factory=list)

    @property
    def failed(self) -> list[str]:
        """One line per file or route that failed, as ``motorlab robot pull`` prints them."""
        return [n.line for n in self.not_pulled]

    def fail(self, what: str, message: str) -> None:
        """Keep the failure of ``what`` (a route, or a file's download path)."""
        self.not_pulled.append(not_pulled(what, message, self.address))

    def to_dict(self) -> dict[str, Any]:
        return {"address": self.address, "folder": str(self.folder), "files": [f.to_dict() for f in self.files],
                "missing": list(self.missing), "failed": self.failed,
                "not_pulled": [n.to_dict() for n in self.not_pulled]}


def check_name(name: str, where: str) -> str:
    if not _SAFE_NAME.match(name) or name in (".", "..") or name.startswith("."):
        raise RobotLinkError(f"{where}: the robot named a file {name!r}, which is not a plain file name; not pulled")
    return name


def write_atomic(folder: Path, name: str, data: bytes) -> str:
    """Write ``data`` to ``folder/name`` through a temporary file and a rename; ``"new"``, ``"same"`` or ``"replaced"``.

    An existing file with the same bytes is left as it is. A different one is replaced (the robot's
    newer copy of the same file, e.g. a log that was still being written at the last pull).
    """
    folder.mkdir(parents=True, exist_ok=True)
    target = folder / name
    if target.is_symlink() or (target.exists() and not target.is_file()):
        raise RobotLinkError(f"{target}: exists and is not a regular file; not overwritten")
    status = "new"
    if target.exists():
        if target.stat().st_size == len(data) and target.read_bytes() == data:
            return "same"
        status = "replaced"
    fd, tmp = tempfile.mkstemp(prefix=f".{name}.", suffix=".part", dir=folder)
    try:
        with os.fdopen(fd, "wb") as out:
            out.write(data)
            out.flush()
            os.fsync(out.fileno())
        os.replace(tmp, target)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return status


def _tuning(robot: RobotHttp, result: PullResult, out: Path) -> None:
    found = -len(result.failed)  # a failed type is there (not a 404)
    for kind in TUNING_TYPES:
        path = f"/tuning/{kind}/latest.json"
        with _each(result, path):
            reply = robot.get(path)
            if reply.status == 404:
                continue
            found += 1
            if reply.status != 200:
                raise RobotLinkError(f"{path} from {robot.address}: HTTP {reply.status}")
            name = reply.headers.get("x-filename")
            if not name:
                raise RobotLinkError(f"{path} from {robot.address}: no X-Filename header (not Road Runner's "
                                     "FileServing.kt?)")
            check_name(name, path)
            _keep(result, out / "tuning" / kind, name, reply.body, path)
    if not found + len(result.failed):
        result.missing.append(f"no Road Runner tuning files ({', '.join(TUNING_TYPES)}: 404): run a ramp logger "
                              "(ForwardRampLogger …) first, or the robot has no Road Runner 1.0")


@contextlib.contextmanager
def _each(result: PullResult, what: str) -> Iterator[None]:
    """One file or route: its failure becomes one line of ``result.failed`` (a robot that cannot be reached
    at all stops the pull)."""
    try:
        yield
    except RobotUnreachable:
        raise
    except RobotLinkError as exc:
        result.fail(what, str(exc) if what in str(exc) else f"{what}: {exc}")


def _listed(robot: RobotHttp, path: str) -> Reply | None:
    reply = robot.get(path, max_bytes=8 << 20)
    if reply.status == 404:
        return None
    if reply.status != 200:
        raise RobotLinkError(f"{path} from {robot.address}: HTTP {reply.status} "
                             f"({reply.body[:120].decode('utf-8', 'replace').strip()}); the other files are pulled")
    return reply


def log_entries(page: str) -> list[tuple[str, int | None]]:
    """(name, size) of each file Road Runner's ``/logs`` page lists, any character in the name: the entry
    ``NAME" download="NAME">NAME</a> (SIZE`` is solved for the one NAME written three times."""
    entries: list[tuple[str, int | None]] = []
    chunks = page.split(_ENTRY_START)[1:]
    for chunk in chunks:
        m = re.match(r'(?s)(.*)</a> \((\d+) bytes\)</li>', chunk)
        if m:
            text, size = m.group(1), int(m.group(2))
            n = (len(text) - len('" download="') - len('">')) // 3
            name = text[:n]
            if n > 0 and text == f'{name}" download="{name}">{name}':
                entries.append((name, size))
                continue
        loose = _LOG_ENTRY.search('href="/logs/download?file=' + chunk)
        if loose:
            entries.append((loose.group(1), int(loose.group(2)) if loose.group(2) else None))
    return entries


def _flight_logs(robot: RobotHttp, result: PullResult, out: Path) -> None:
    with _each(result, "/logs"):
        reply = _listed(robot, "/logs")
        if reply is None:
            result.missing.append("no FlightRecorder log list (/logs: 404): the robot has no Road Runner 1.0 "
                                  "(its FileServing.kt serves the FlightRecorder logs)")
            return
        entries = log_entries(reply.body.decode("utf-8", "replace"))
        with progress.task("Pulling FlightRecorder logs", total=len(entries), unit="file") as step:
            for name, size in entries:
                path = f"/logs/download?file={name}"
                with _each(result, path):
                    check_name(name, "/logs")
                    if _UNASKABLE.search(name):  # the request line or the query would be cut there
                        raise RobotLinkError(f"{path}: its name holds a space, & or =, which Road Runner's file "
                                             "server cannot be asked for: not pulled; rename it on the robot or copy "
                                             "it by USB")
                    got = robot.get(path)
                    if got.status != 200:
                        raise RobotLinkError(f"{path} from {robot.address}: HTTP {got.status} "
                                             f"({got.body[:120].decode('utf-8', 'replace').strip()})")
                    note = _size_note(path, robot.address, size, len(got.body))
                    _keep(result, out / "logs", name, got.body, path, note)
                step.advance(detail=name)


def _size_note(path: str, address: str, listed: int | None, got: int) -> str | None:
    if listed is None:
        return None
    if got < listed:
        raise RobotLinkError(f"{path} from {address}: {got} of the {listed} bytes listed arrived (connection "
                             "dropped?); nothing of it was kept: pull again")
    if got > listed:  # FlightRecorder appends while an OpMode runs
        return f"grew from {listed} to {got} bytes while pulling: an OpMode is writing it; pull again after it stops"
    return None


def _motorlab_logs(robot: RobotHttp, result: PullResult, out: Path) -> None:
    with _each(result, MOTORLAB_LIST):
        reply = _listed(robot, MOTORLAB_LIST)
        if reply is None:
            result.missing.append(f"no motorlab log handler ({MOTORLAB_LIST}: 404): copy ftc/…/motorlab (with "
                                  "MotorlabLogFiles.java) into TeamCode to pull the OpModes' logs over Wi-Fi")
            return
        try:
            listing = json.loads(reply.body)
            entries = [(str(e["name"]), int(e["bytes"])) for e in listing["files"]]
        except (ValueError, KeyError, TypeError):
            raise RobotLinkError(f"{MOTORLAB_LIST} from {robot.address}: not motorlab's JSON file list") from None
        with progress.task("Pulling motorlab logs", total=len(entries), unit="file") as step:
            for name, size in entries:
                path = f"{MOTORLAB_DOWNLOAD}?file={urllib.parse.quote(name)}"  # getParameters() decodes it
                with _each(result, path):
                    check_name(name, MOTORLAB_LIST)
                    got = robot.get(path)
                    if got.status != 200:
                        raise RobotLinkError(f"{path} from {robot.address}: HTTP {got.status}")
                    _keep(result, out / "motorlab", name, got.body, path,
                          _size_note(path, robot.address, size, len(got.body)))
                step.advance(detail=name)


def _keep(result: PullResult, folder: Path, name: str, data: bytes, source: str, note: str | None = None) -> None:
    status = write_atomic(folder, name, data)
    result.files.append(PulledFile(source, folder / name, len(data), status, note=note))


def propose_analysis(pulled: PulledFile) -> None:
    """Fill in the file's format and the analysis proposed for it (as the app does for a dropped file)."""
    from motorlab.errors import MotorlabError, OptionError
    from motorlab.io import detect_format, read_any
    from motorlab.proposal import propose

    try:
        fmt = detect_format(pulled.path)
    except (MotorlabError, OSError, ValueError) as exc:
        pulled.note = " ".join(f"{pulled.note or ''} not a log motorlab reads: {exc}".split())
        return
    pulled.format = fmt
    signals: list[str] = []
    declared = None
    needs_cpr = False
    try:
        recording = read_any(pulled.path)
        signals = list(recording.signals)
        declared = str(recording.metadata.get("experiment") or "") or None
    except OptionError as exc:  # Road Runner's files count ticks: the analysis needs --cpr
        needs_cpr = "cpr" in str(exc)
        if not needs_cpr:
            pulled.note = " ".join(f"{pulled.note or ''} {exc}".split())
    except (MotorlabError, OSError, ValueError) as exc:
        pulled.note = " ".join(f"{pulled.note or ''} not readable as a log: {exc}".split())
        return
    pulled.experiment = propose(fmt, signals, declared)
    pulled.command = (f"motorlab analyze {pulled.experiment} {pulled.path}"
                      + (" --cpr <encoder counts per revolution>" if needs_cpr else ""))


def pull(host: str, out: str | os.PathLike[str], *, http_port: int = 8080, timeout: float = 5.0) -> PullResult:
    """Pull every file the robot serves into ``out`` and propose each one's analysis.

    Raises
    ------
    RobotLinkError
        No robot at the address, a robot with none of the three services, or nothing pulled because every
        file failed. A file or route that fails while others arrive is a line of ``failed`` instead
        (nothing half-written is left).
    """
    folder = Path(out)
    if folder.exists() and not folder.is_dir():
        raise RobotLinkError(f"{folder}: exists and is not a folder; give -o a folder")
    robot = RobotHttp(host, http_port, timeout=timeout)
    result = PullResult(robot.address, folder)
    for part in (_tuning, _flight_logs, _motorlab_logs):
        try:
            part(robot, result, folder)
        except RobotUnreachable as exc:
            if not result.files and not result.failed:
                raise
            result.fail("", f"{exc}: the robot went away during the pull; what came is kept, pull again for the "
                            "rest")
            break
    if not result.files and result.failed:
        more = f" (and {len(result.failed) - 1} more)" if len(result.failed) > 1 else ""
        raise RobotLinkError(f"nothing pulled: {result.failed[0]}{more}")
    if not result.files and len(result.missing) == 3:
        raise RobotLinkError(f"{robot.address} answers but serves neither Road Runner's files nor motorlab's logs: "
                             "install Road Runner 1.0 or copy ftc/…/motorlab into TeamCode, run an OpMode, pull again")
    for pulled in result.files:
        propose_analysis(pulled)
    return result
