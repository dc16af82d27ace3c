"""``make fuzz``: the long fuzz run over every reader, command, session file and the app's uploads.

Cases are numbered; case ``k`` of run seed ``s`` is always the same (tests/fuzz/fuzz_cases.py), so a
run is resumable: ``out/fuzz/state.json`` holds the next case and the tallies, and the next
``make fuzz`` carries on from there until ``--cases`` is reached. A failure is saved as a folder
under ``out/fuzz/failures/`` with its files, ``case.json`` and ``replay.sh`` (the command to run it
again); ``--replay FOLDER`` runs a saved case and prints its verdict. The run stops by itself
after ``--cases`` cases or ``--minutes`` minutes, whichever comes first, or on SIGTERM / Ctrl-C (the
cases under way finish and are counted). ``--jobs N`` runs N cases at once, each in a worker forked
from this process; results are tallied in case order, so the state file stays resumable.

Usage::

    python scripts/fuzz.py [--cases 10000] [--seed 1] [--minutes 60] [--jobs 1] [--out out/fuzz] [--time-limit 60]
    python scripts/fuzz.py --replay out/fuzz/failures/000123-traceback
    python scripts/fuzz.py --summary          # the tallies of the state file, as docs/fuzz.md shows them
"""

from __future__ import annotations

import argparse
import contextlib
import json
import multiprocessing
import os
import resource
import shlex
import shutil
import signal
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path
from typing import Any

# One BLAS thread a case: on a shared 2-core machine more threads only add CPU time (set before numpy).
for _name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "1")

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "fuzz"))
sys.path.insert(1, str(ROOT))  # tests.real_data: where the shared real data are (the corpus's real logs)

from fuzz_app import app_case, app_client  # noqa: E402
from fuzz_cases import case_for  # noqa: E402
from fuzz_corpus import build  # noqa: E402
from fuzz_harness import GOOD, Case, Outcome, run, warm  # noqa: E402


def _save_failure(out: Path, index: int, case: Case, outcome: Outcome) -> Path:
    folder = out / "failures" / f"{index:06d}-{outcome.verdict}"
    (folder / "files").mkdir(parents=True, exist_ok=True)
    for name, content in case.files.items():
        path = folder / "files" / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(content)
    (folder / "case.json").write_text(json.dumps(case.to_json(), indent=1))
    (folder / "outcome.txt").write_text(
        f"verdict: {outcome.verdict}\ndetail: {outcome.detail}\nexit: {outcome.code}\nseconds: {outcome.seconds:.1f}\n"
        f"mutation: {case.mutation}\nspecial files: {case.special}\nenv: {case.env}\n\n"
        f"--- stderr\n{outcome.stderr[-4000:]}\n--- stdout\n{outcome.stdout[-2000:]}\n"
    )
    env = " ".join(f"{k}={shlex.quote(v)}" for k, v in case.env.items())
    (folder / "replay.sh").write_text(
        "#!/bin/sh\n# Replays this case exactly (special files are re-created by the harness):\n"
        f"exec {shlex.quote(sys.executable)} {shlex.quote(str(ROOT / 'scripts' / 'fuzz.py'))} "
        '--replay "$(dirname "$0")"\n'
        f"# by hand, in a copy of files/: {env + ' ' if env else ''}motorlab {shlex.join(case.argv)}\n"
    )
    os.chmod(folder / "replay.sh", 0o755)
    return folder


def _load_state(path: Path, seed: int) -> dict:
    if path.exists():
        state = json.loads(path.read_text())
        if state.get("seed") == seed:
            return state
    return {"seed": seed, "next": 0, "verdicts": {}, "by_seed": {}, "failures": [], "seconds": 0.0,
            "max_case_seconds": 0.0, "max_peak_rss_mb": 0.0}


def _write_state(path: Path, state: dict) -> None:
    tmp = path.with_name(path.name + ".part")
    tmp.write_text(json.dumps(state, indent=1, sort_keys=True))
    os.replace(tmp, path)


def summary(state: dict) -> str:
    """The run's figures in a few lines (cases, outcomes by class, failures)."""
    verdicts = Counter(state["verdicts"])
    total = sum(verdicts.values())
    good = sum(verdicts[v] for v in GOOD)
    lines = [f"cases: {total} (seed {state['seed']}), kept the promise: {good} ({100 * good / max(total, 1):.2f} %)"]
    lines += [f"  {name}: {count}" for name, count in verdicts.most_common()]
    lines.append(f"time: {state['seconds'] / 60:.1f} min; slowest case {state['max_case_seconds']:.1f} s; "
                 f"largest peak RSS {state['max_peak_rss_mb']:.0f} MB")
    if state.get("wall_seconds"):
        lines.append(f"since the timing was kept ({state['timed_cases']} cases): {state['wall_seconds'] / 60:.1f} min "
                     f"of wall time, {60 * state['timed_cases'] / state['wall_seconds']:.1f} cases/min, "
                     f"{state['cpu_seconds'] / max(state['timed_cases'], 1):.2f} CPU s a case")
    slow = sorted(state.get("seconds_by_seed", {}).items(), key=lambda kv: -kv[1])[:8]
    if slow:
        lines.append("case time by seed (s): " + ", ".join(f"{name} {sec:.0f}" for name, sec in slow))
    for failure in state["failures"][-20:]:
        lines.append(f"  failure {failure}")
    return "\n".join(lines)


def replay(folder: Path, time_limit: float) -> int:
    case = Case.from_json(json.loads((folder / "case.json").read_text()))
    with tempfile.TemporaryDirectory(prefix="motorlab-fuzz-") as scratch:
        outcome = run(case, Path(scratch), time_limit=time_limit)
    print(f"{outcome.verdict}: {outcome.detail}\nexit {outcome.code}, {outcome.seconds:.1f} s")
    print(outcome.stderr[-2000:])
    return 0 if outcome.verdict in GOOD else 1


def _tally(state: dict, result: dict) -> None:
    seed, verdict, seconds, peak = result["seed"], result["verdict"], result["seconds"], result["peak"]
    state["verdicts"][verdict] = state["verdicts"].get(verdict, 0) + 1
    by_seed = state["by_seed"].setdefault(seed, {})
    by_seed[verdict] = by_seed.get(verdict, 0) + 1
    state["seconds"] += seconds
    timing = state.setdefault("seconds_by_seed", {})
    timing[seed] = timing.get(seed, 0.0) + seconds
    state["cpu_seconds"] = state.get("cpu_seconds", 0.0) + result.get("cpu", 0.0)
    state["max_case_seconds"] = max(state["max_case_seconds"], seconds)
    if peak == peak:  # not NaN
        state["max_peak_rss_mb"] = max(state["max_peak_rss_mb"], peak)
    if result.get("failure"):
        state["failures"].append(result["failure"])


def _children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def _cli_case(index: int, args: argparse.Namespace, seeds: list, scratch: Path) -> dict:
    case = case_for(index, args.seed, seeds, args.out / "corpus")
    cpu = _children_cpu()
    outcome = run(case, scratch, time_limit=args.time_limit)
    result = {"seed": case.seed, "verdict": outcome.verdict, "seconds": outcome.seconds,
              "peak": outcome.peak_rss_mb, "cpu": _children_cpu() - cpu}
    if outcome.verdict not in GOOD:
        folder = _save_failure(args.out, index, case, outcome)
        result["failure"] = f"{folder.name}: {case.seed}: {case.mutation[:80]}: {outcome.detail[:160]}"
        print(f"case {index}: {outcome.verdict}: {case.seed}: {case.mutation[:80]}: {outcome.detail[:200]}", flush=True)
    return result


def _app_case(index: int, args: argparse.Namespace, seeds: list) -> dict:
    """An app request (fuzz_app.py); a failure is saved as what was sent and what came back.

    The app's client runs an event-loop thread: it lives only for this request, so that no thread
    exists when the next CLI case forks.
    """
    from fuzz_mutate import RandomChooser

    start = time.perf_counter()
    cpu = time.process_time() + _children_cpu()
    try:
        with app_client() as client:
            verdict, detail, what = app_case(client, args.out / "corpus", seeds,
                                             RandomChooser(f"app:{args.seed}:{index}"))
    except Exception as exc:  # the client itself failed: the app broke the connection
        verdict, detail, what = "app-exception", f"{type(exc).__name__}: {exc}"[:300], "?"
    result = {"seed": "app", "verdict": verdict, "seconds": time.perf_counter() - start, "peak": float("nan"),
              "cpu": time.process_time() + _children_cpu() - cpu}
    if verdict not in GOOD:
        folder = args.out / "failures" / f"{index:06d}-{verdict}"
        folder.mkdir(parents=True, exist_ok=True)
        (folder / "outcome.txt").write_text(
            f"verdict: {verdict}\ndetail: {detail}\nsent: {what}\nreplay: the app case of seed {args.seed}, "
            f"case {index}: fuzz_app.app_case(client, corpus, seeds, RandomChooser('app:{args.seed}:{index}'))\n")
        result["failure"] = f"{folder.name}: app: {what[:80]}: {detail[:160]}"
        print(f"case {index}: {verdict}: app: {what[:80]}: {detail[:200]}", flush=True)
    return result


def _worker(conn: Any, args: argparse.Namespace, seeds: list) -> None:
    """A forked worker: runs the case numbers it is sent, answers each with its result, until None."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the main process decides when the run stops
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    scratch = Path(tempfile.mkdtemp(prefix="motorlab-fuzz-"))
    try:
        while True:
            try:
                index = conn.recv()
            except EOFError:  # the main process is gone
                break
            if index is None:
                break
            if args.app_every and index % args.app_every == args.app_every - 1:
                result = _app_case(index, args, seeds)
            else:
                result = _cli_case(index, args, seeds, scratch)
            conn.send((index, result))
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
        conn.close()


def run_cases(args: argparse.Namespace, seeds: list, state: dict, state_path: Path) -> None:
    """Cases ``state["next"]`` on, in ``args.jobs`` forked workers, tallied in case order (resumable).

    The run stops dispatching at ``--cases``, after ``--minutes``, or on SIGTERM / Ctrl-C; the cases
    under way finish and are counted, so ``state.json`` always means "every case before next is done".
    """
    from multiprocessing.connection import wait

    stop = {"now": False}

    def _stop(signum: int, frame: Any) -> None:
        stop["now"] = True
        print("stopping: the cases under way finish, then the state is saved", flush=True)

    previous = {sig: signal.signal(sig, _stop) for sig in (signal.SIGTERM, signal.SIGINT)}
    ctx = multiprocessing.get_context("fork")
    workers = []
    for _ in range(max(args.jobs, 1)):
        mine, theirs = ctx.Pipe()
        proc = ctx.Process(target=_worker, args=(theirs, args, seeds))
        proc.start()
        theirs.close()
        workers.append((proc, mine))
    deadline = time.monotonic() + 60.0 * args.minutes
    to_send, done, busy = state["next"], {}, {}
    wall, last = state.get("wall_seconds", 0.0), time.monotonic()
    try:
        while True:
            for _proc, conn in workers:
                if conn not in busy and to_send < args.cases and time.monotonic() < deadline and not stop["now"]:
                    conn.send(to_send)
                    busy[conn] = to_send
                    to_send += 1
            if not busy:
                break
            for conn in wait(list(busy), timeout=5.0):
                try:
                    index, result = conn.recv()
                except (EOFError, OSError):  # a worker died: its case is run again next time
                    to_send = min(to_send, busy.pop(conn))
                    continue
                del busy[conn]
                done[index] = result
            while state["next"] in done:
                result = done.pop(state["next"])
                _tally(state, result)
                with open(state_path.with_name("cases.jsonl"), "a") as log:  # each case's result, for --merge
                    log.write(json.dumps({"index": state["next"], **result}) + "\n")
                state["next"] += 1
                state["timed_cases"] = state.get("timed_cases", 0) + 1
                wall, last = wall + time.monotonic() - last, time.monotonic()
                state["wall_seconds"] = wall
                if state["next"] % 10 == 0:
                    _write_state(state_path, state)
            alive = [w for w in workers if w[0].is_alive()]
            if len(alive) < len(workers):
                workers = alive
                if not workers:
                    break
    finally:
        for _proc, conn in workers:
            with contextlib.suppress(OSError):
                conn.send(None)
        for proc, _conn in workers:
            proc.join(30)
        _write_state(state_path, state)
        for sig, handler in previous.items():
            signal.signal(sig, handler)


def merge(state: dict, state_path: Path, other: Path) -> int:
    """Add the cases of another run's folder (``--out`` of a run made with ``--start``) that follow ours.

    Two runs of the same seed may share the work: one from case 0, one ``--start K``. Its cases from
    our next one on are tallied in order (those we ran too are skipped); its failure folders are
    copied. A gap between our next case and its first leaves us where we are.
    """
    rows = [json.loads(line) for line in (other / "cases.jsonl").read_text().splitlines() if line.strip()]
    theirs = json.loads((other / "state.json").read_text())
    if theirs.get("seed") != state["seed"]:
        print(f"{other}: seed {theirs.get('seed')}, not {state['seed']}: not merged")
        return 1
    by_index = {row["index"]: row for row in rows}
    added = 0
    while state["next"] in by_index:
        _tally(state, by_index[state["next"]])
        state["next"] += 1
        added += 1
    state["timed_cases"] = state.get("timed_cases", 0) + added  # the runs overlapped in time: ours is the wall
    for folder in sorted((other / "failures").glob("*")) if (other / "failures").is_dir() else []:
        if folder.is_dir() and not (state_path.parent / "failures" / folder.name).exists():
            shutil.copytree(folder, state_path.parent / "failures" / folder.name)
    _write_state(state_path, state)
    print(f"merged {added} cases of {other}; next case {state['next']}")
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cases", type=int, default=10_000)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--minutes", type=float, default=90.0, help="stop after this long (default 90)")
    parser.add_argument("--out", type=Path, default=ROOT / "out" / "fuzz")
    parser.add_argument("--time-limit", type=float, default=60.0, help="CPU seconds per case (default 60)")
    parser.add_argument("--jobs", type=int, default=1, help="cases run at once, in forked workers (default 1)")
    parser.add_argument("--start", type=int, default=0, help="a new run's first case (to share a run; see --merge)")
    parser.add_argument("--merge", type=Path, help="add the cases of another run's --out folder that follow ours")
    parser.add_argument("--replay", type=Path)
    parser.add_argument("--summary", action="store_true")
    parser.add_argument("--only", help="only seeds whose name contains this")
    parser.add_argument("--app-every", type=int, default=40,
                        help="every N-th case is an app request (0: none; default 40: a request starts a Python "
                             "process for its command, the cost of some fifteen CLI cases)")
    args = parser.parse_args(argv)
    if args.replay:
        return replay(args.replay, args.time_limit)
    args.out.mkdir(parents=True, exist_ok=True)
    state_path = args.out / "state.json"
    state = _load_state(state_path, args.seed)
    if args.summary:
        print(summary(state))
        return 0
    if args.merge:
        return merge(state, state_path, args.merge)
    if state["next"] < args.start:
        if state["next"]:
            parser.error(f"--start {args.start}: {state_path} has run cases already")
        state["next"] = args.start
    seeds = build(args.out / "corpus")
    warm()
    if args.only:
        seeds = [s for s in seeds if args.only in s.name]
    run_cases(args, seeds, state, state_path)
    print(summary(state))
    return 0


if __name__ == "__main__":
    sys.exit(main())
