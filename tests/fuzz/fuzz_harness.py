"""Run one fuzz case in a child process and judge how it ended.

A case is a command line over files in a fresh folder (the corpus's valid files, mutated) and a few
environment variables. It runs ``motorlab.cli.main`` in a forked child of the fuzzing process (the
modules are already imported: a case costs its analysis, not Python's start-up), in that folder,
with its own temporary folder, an address-space limit and a time limit; the child's stdout and
stderr go to files. The judgement (:func:`judge`) is the promise of the README:

- exit 0 with valid output: ``--json`` output parses, holds no NaN, and a parameter that physics
  wants positive (J, R, L, K …) is negative only with a warning; no Python warning printed;
- exit 2 with one line ``motorlab: error: …`` naming the mutated file (and nothing written);
- exit 3 only for a session with per-unit failures, its results written;
- never exit 1, a traceback, a hang (time limit), a memory blow-up (peak RSS), a modified input,
  or a stray or half-written output (files other than the outputs asked for; temporary files).
"""

from __future__ import annotations

import contextlib
import gc
import hashlib
import json
import math
import multiprocessing
import os
import resource
import shutil
import signal
import stat
import sys
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

#: Classes of outcome that keep the promise.
GOOD = ("ok", "refused", "partial")

#: Parameters physics wants positive (by their JSON name): negative only with a warning.
POSITIVE = {"J", "R", "R_dc", "L", "K", "Ka", "Kt_tach", "kV", "b", "Tf", "gamma"}


@dataclass
class Case:
    """One run: the files of its folder (bytes, or a special kind), argv, environment, what it may write."""

    seed: str
    mutation: str
    argv: list[str]
    files: dict[str, bytes] = field(default_factory=dict)
    special: dict[str, str] = field(default_factory=dict)
    outputs: list[str] = field(default_factory=list)
    env: dict[str, str] = field(default_factory=dict)
    blame: str | None = None
    json_output: bool = False
    session: bool = False
    any_outcome: bool = False
    valid: bool = False

    def to_json(self) -> dict[str, Any]:
        d = asdict(self)
        d["files"] = {k: v.hex() for k, v in self.files.items()}
        return d

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> Case:
        d = dict(d)
        d["files"] = {k: bytes.fromhex(v) for k, v in d["files"].items()}
        return cls(**d)


@dataclass
class Outcome:
    """How a case ended and the verdict."""

    verdict: str
    detail: str
    code: int | None
    stdout: str
    stderr: str
    seconds: float
    peak_rss_mb: float


def warm() -> None:
    """Import every motorlab module (and what they import) once, so that forked cases do not each import them."""
    import importlib
    import pkgutil

    os.environ.setdefault("MPLBACKEND", "Agg")
    import motorlab

    for info in pkgutil.walk_packages(motorlab.__path__, "motorlab."):
        if info.name.endswith("__main__"):
            continue
        with contextlib.suppress(Exception):
            importlib.import_module(info.name)
    with contextlib.suppress(Exception):
        import matplotlib.pyplot  # noqa: F401  (the figures of --plot)
    # What a command sets up on first use, once here rather than in every forked case (half a second
    # of CPU a case: the pint registry alone): the unit registry, the parser, the motor catalog.
    with contextlib.suppress(Exception):
        from motorlab import catalog, cli, units

        for text, unit in (("0.5 A", "A"), ("12.2 kg*m^2", "kg*m^2"), ("400 in*oz", "N*m"), ("130 rpm", "rad/s")):
            units.parse_quantity(text, unit)
        cli.build_parser()
        catalog.list_motors()
    # The objects made so far live as long as this process: out of the collector's sight, a forked
    # case's collections do not touch (and so copy) every page of them — a fifth of a case's CPU.
    gc.collect()
    gc.freeze()


# ---- setting up the folder ------------------------------------------------------------------------


def _make_special(path: Path, kind: str) -> None:
    if kind == "directory":
        path.mkdir()
    elif kind == "fifo":
        os.mkfifo(path)
    elif kind == "dev-zero":
        path.symlink_to("/dev/zero")
    elif kind == "symlink-loop":
        path.symlink_to(path.name)
    elif kind == "symlink-to-file":
        target = path.with_name(path.name + ".target")
        target.write_bytes(b"1 2 3\n")
        path.symlink_to(target.name)
    elif kind == "empty":
        path.write_bytes(b"")
    elif kind == "unreadable":
        path.write_bytes(b"time,current\n1,2\n")
        path.chmod(0)
    elif kind == "huge-sparse":
        with open(path, "wb") as handle:  # 3 GiB of nothing, on disk as a few blocks
            handle.truncate(3 * 2**30)
    # "missing": nothing at all


def prepare(case: Case, folder: Path) -> None:
    """Write the case's files and special files into the (new, empty) ``folder``."""
    folder.mkdir(parents=True)
    for name, content in case.files.items():
        path = folder / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(content)
    for name, kind in case.special.items():
        path = folder / name
        path.parent.mkdir(parents=True, exist_ok=True)
        _make_special(path, kind)


def snapshot(folder: Path) -> dict[str, str]:
    """Every entry under ``folder``: a hash for regular files, the kind for the others (links not followed)."""
    out: dict[str, str] = {}
    for root, dirs, files in os.walk(folder):
        for name in dirs + files:
            path = Path(root, name)
            rel = str(path.relative_to(folder))
            info = os.lstat(path)
            if stat.S_ISREG(info.st_mode):
                if info.st_size > 2**30 or not os.access(path, os.R_OK):
                    out[rel] = f"file:{info.st_size}:{info.st_mtime_ns}"
                    continue
                digest = hashlib.sha256()
                with open(path, "rb") as handle:
                    while chunk := handle.read(1 << 20):
                        digest.update(chunk)
                out[rel] = digest.hexdigest()
            else:
                out[rel] = stat.filemode(info.st_mode)[0]
    return out


# ---- running ----------------------------------------------------------------------------------------


def _child(argv: list[str], folder: str, env: dict[str, str], out: str, err: str, memory: int, conn: Any) -> None:
    """In the forked child: chdir, limits, stdout/stderr to files, ``motorlab.cli.main(argv)``."""
    try:
        os.chdir(folder)
        os.environ.update(env)
        import tempfile

        tempfile.tempdir = None
        if memory:
            _soft, hard = resource.getrlimit(resource.RLIMIT_AS)
            resource.setrlimit(resource.RLIMIT_AS, (memory, hard))
        fd_out = os.open(out, os.O_WRONLY | os.O_CREAT | os.O_TRUNC)
        fd_err = os.open(err, os.O_WRONLY | os.O_CREAT | os.O_TRUNC)
        sys.stdout.flush()
        sys.stderr.flush()
        os.dup2(fd_out, 1)
        os.dup2(fd_err, 2)
        sys.stdout = open(1, "w", encoding="utf-8", errors="replace", closefd=False)  # noqa: SIM115
        sys.stderr = open(2, "w", encoding="utf-8", errors="replace", closefd=False)  # noqa: SIM115
        import warnings

        warnings.resetwarnings()  # pytest's "error" filter does not apply to the user's run
        warnings.simplefilter("default")
        from motorlab import cli

        start = time.perf_counter()
        try:
            code = cli.main(argv)
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
        except BaseException:  # main lets nothing through; if it does, that is the finding
            import traceback

            traceback.print_exc()
            code = 99
        elapsed = time.perf_counter() - start
        sys.stdout.flush()
        sys.stderr.flush()
        peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
        conn.send((code, elapsed, peak))
    finally:
        conn.close()
        os._exit(0)


#: A case is also a hang after this many times its CPU-time limit in wall-clock time (a deadlock uses no CPU).
WALL_FACTOR = 6.0


def _cpu_seconds(pid: int) -> float:
    """User + system CPU time of process ``pid`` so far [s] (0 when it is gone)."""
    try:
        with open(f"/proc/{pid}/stat") as handle:
            fields = handle.read().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    except (OSError, IndexError, ValueError):
        return 0.0


def _address_space_limit(extra: int) -> int:
    """Current virtual size of this process plus ``extra`` bytes (numpy maps much it never touches)."""
    try:
        with open("/proc/self/statm") as handle:
            pages = int(handle.read().split()[0])
        return pages * os.sysconf("SC_PAGE_SIZE") + extra
    except (OSError, ValueError):
        return 0


def execute(case: Case, folder: Path, *, time_limit: float = 60.0, memory_mb: float = 1500.0) -> Outcome:
    """Run ``case`` in ``folder`` (made here; removed by the caller) and judge it."""
    prepare(case, folder / "work")
    work = folder / "work"
    tmp = folder / "tmp"
    tmp.mkdir()
    before = snapshot(work)
    out, err = folder / "stdout", folder / "stderr"
    env = {"TMPDIR": str(tmp), "MPLBACKEND": "Agg", "COLUMNS": "120", **case.env}
    env.pop("MOTORLAB_TRACEBACK", None)
    ctx = multiprocessing.get_context("fork")
    receive, send = ctx.Pipe(duplex=False)
    limit = _address_space_limit(int(3 * memory_mb * 2**20))
    proc = ctx.Process(target=_child, args=(case.argv, str(work), env, str(out), str(err), limit, send))
    start = time.perf_counter()
    proc.start()
    send.close()
    result = None
    cpu = 0.0
    while True:  # CPU seconds decide a hang (a loaded machine slows a case, it does not make it hang)
        if receive.poll(0.5):
            with contextlib.suppress(EOFError):
                result = receive.recv()
            break
        cpu = _cpu_seconds(proc.pid) if proc.pid is not None else 0.0
        if not proc.is_alive() or cpu > time_limit or time.perf_counter() - start > WALL_FACTOR * time_limit:
            break
    seconds = time.perf_counter() - start
    if proc.is_alive():
        with contextlib.suppress(ProcessLookupError):
            os.kill(proc.pid, signal.SIGKILL)
    proc.join(10)
    receive.close()
    stdout = out.read_text("utf-8", "replace") if out.exists() else ""
    stderr = err.read_text("utf-8", "replace") if err.exists() else ""
    if result is None:
        hung = proc.exitcode is None or proc.exitcode == -signal.SIGKILL
        verdict = "hang" if hung else "crash"
        detail = (f"no answer within {time_limit:g} s of CPU ({cpu:.0f} s used, {seconds:.0f} s wall)" if hung
                  else f"the child died (exit {proc.exitcode})")
        return Outcome(verdict, detail, None, stdout, stderr, seconds, math.nan)
    code, elapsed, peak = result
    verdict, detail = judge(case, code, stdout, stderr, before, snapshot(work), list(tmp.iterdir()), work)
    if verdict in GOOD and peak > memory_mb:
        verdict, detail = "memory", f"peak resident memory {peak:.0f} MB > {memory_mb:g} MB"
    return Outcome(verdict, detail, code, stdout, stderr, elapsed, peak)


# ---- judging ----------------------------------------------------------------------------------------


def _no_constant(name: str) -> Any:
    raise ValueError(f"{name} in the JSON output")


def _negative_unwarned(doc: Any) -> str | None:
    """A parameter physics wants positive printed negative with no warning, if any."""
    if not isinstance(doc, dict):
        return None
    params = doc.get("parameters")
    warnings = doc.get("warnings") or []
    if isinstance(params, dict) and not warnings:
        for name, entry in params.items():
            value = entry.get("value") if isinstance(entry, dict) else None
            if name in POSITIVE and isinstance(value, int | float) and value < 0:
                return f"{name} = {value:g} without a warning"
    for value in doc.values():  # nested results (characterize, both sides of a drivetrain)
        if isinstance(value, dict) and value is not params:
            found = _negative_unwarned(value)
            if found:
                return found
    return None


def judge(case: Case, code: int, stdout: str, stderr: str, before: dict[str, str], after: dict[str, str],
          temp: list[Path], work: Path) -> tuple[str, str]:
    """The verdict on one run (a class of :data:`GOOD`, or the failure's class) and why."""
    lines = [line for line in stderr.splitlines() if line.strip()]
    if "Traceback (most recent call last)" in stderr:
        return "traceback", lines[-1] if lines else ""
    changed = [name for name, digest in before.items() if after.get(name) != digest]
    if changed:
        return "modified-input", ", ".join(changed[:3])
    created = sorted(set(after) - set(before))
    if any(o.strip() in (".", "./") for o in case.outputs):
        allowed = [""]  # the folder itself is the output folder asked for: anything new is an output
    else:
        allowed = [o.rstrip("/") for o in case.outputs if o.strip(" ./")]
    stray = [n for n in created if not any(o == "" or n == o or n.startswith(o + "/") or o.startswith(n + "/")
                                           for o in allowed)]
    hidden = [n for n in created if Path(n).name.startswith(".") or ".tmp" in Path(n).name]
    if temp:
        return "stray-output", f"left in the temporary folder: {', '.join(p.name for p in temp[:3])}"
    if hidden:
        return "stray-output", f"temporary file left: {hidden[0]}"
    if code == 1 or code not in (0, 2, 3):
        return "internal-error", lines[-1] if lines else f"exit {code}"
    if code == 2:
        return _judge_refusal(case, lines, created)
    if stray:
        return "stray-output", f"wrote {stray[0]} (asked for {allowed or 'nothing'})"
    python_warnings = [line for line in lines if "Warning:" in line and "motorlab: warning:" in line]
    if python_warnings:
        return "python-warning", python_warnings[0]
    if code == 3:
        if not case.session:
            return "bad-exit", "exit 3 from a command that is not a session"
        return _judge_outputs(case, stdout, "partial", work)
    return _judge_outputs(case, stdout, "ok", work)


def _judge_refusal(case: Case, lines: list[str], created: list[str]) -> tuple[str, str]:
    if case.valid:
        return "unexpected-refusal", lines[-1] if lines else "exit 2"
    if len(lines) != 1:
        return "not-one-line", f"{len(lines)} lines: " + " | ".join(line[:100] for line in lines[:3])
    if not lines[0].startswith("motorlab: error: "):
        return "not-one-line", lines[0][:200]
    if created:
        return "stray-output", f"refused, yet wrote {created[0]}"
    if case.blame and not case.any_outcome:
        name = Path(case.blame).name
        if name not in lines[0] and case.blame not in lines[0]:
            return "unnamed-file", lines[0][:300]
    return "refused", lines[0]


def _judge_outputs(case: Case, stdout: str, verdict: str, work: Path) -> tuple[str, str]:
    if case.json_output and "--json" in case.argv:
        try:
            doc = json.loads(stdout, parse_constant=_no_constant)
        except ValueError as exc:
            return "bad-json", str(exc)[:200]
        problem = _negative_unwarned(doc)
        if problem:
            return "unwarned-physics", problem
    if case.session:
        return _judge_session(case, verdict, work)
    return verdict, ""


def _judge_session(case: Case, verdict: str, work: Path) -> tuple[str, str]:
    given = [case.argv[k + 1] if a in ("-o", "--output") else a.split("=", 1)[1]
             for k, a in enumerate(case.argv) if (a in ("-o", "--output") and k + 1 < len(case.argv))
             or a.startswith(("--output=", "-o="))]
    out = given[-1] if given else None  # argparse keeps the last
    if out is None:
        return verdict, ""
    path = work / out / "results.json"
    try:
        doc = json.loads(path.read_text("utf-8"), parse_constant=_no_constant)
    except (OSError, ValueError) as exc:
        return "bad-json", f"results.json: {exc}"[:200]
    problem = _negative_unwarned(doc)
    return ("unwarned-physics", problem) if problem else (verdict, "")


def run(case: Case, scratch: Path, **limits: Any) -> Outcome:
    """:func:`execute` in a fresh sub-folder of ``scratch``, removed afterwards (even a 0-mode file)."""
    folder = Path(scratch) / f"case-{os.getpid()}-{time.monotonic_ns()}"
    folder.mkdir(parents=True)
    cwd = os.getcwd()
    try:
        return execute(case, folder, **limits)
    finally:
        os.chdir(cwd)
        for root, dirs, _files in os.walk(folder):
            for name in dirs:
                with contextlib.suppress(OSError):
                    os.chmod(Path(root, name), 0o700)
        for path in folder.rglob("*"):
            with contextlib.suppress(OSError):
                if not path.is_symlink():
                    path.chmod(0o700)
        shutil.rmtree(folder, ignore_errors=True)
