"""Where ``make test``'s CPU goes: each test's CPU seconds, split by the processes that spent them (Linux).

    python benchmarks/suite_cpu.py                      # the workers' part of make test (-n 2, not realtime)
    python benchmarks/suite_cpu.py -m realtime -p no:xdist
    python benchmarks/suite_cpu.py tests/ui -n 2        # any pytest arguments

Runs pytest with this file as a plugin (``-p suite_cpu``). Around each test it reads /proc for the test process and
every process under it and charges the difference to the test, split into the test process itself, the Python
processes it started (the app's fork server and its commands, a pool's children, a CLI run as a program), the
browser (Chromium and chromedriver) and the rest; then it prints the totals, the costliest files and tests.

Each process is counted once: its own CPU while it runs, and when it has ended, the rest of its life as its
parent reaped it (a long-lived child, the app's fork server, is not charged again to the test that ends it). A
process whose parent did not wait for it takes its CPU out of the tree (a browser's renderers): that is printed as
left out. Session 15 found with it that the browser spends 119 s of the 571 s the workers spend.
"""

from __future__ import annotations

import collections
import json
import os
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
#: Where the plugin writes one line per test (a file per test process).
OUT = ROOT / "out" / "suite-cpu"
_TICK = os.sysconf("SC_CLK_TCK") if hasattr(os, "sysconf") else 100


def _kind(pid: int, root: int, name: str) -> str:
    if pid == root:
        return "test process"
    if "chrom" in name:
        return "browser"
    if "python" in name or name.startswith("motorlab"):
        return "python children"
    return "other"


@dataclass
class _Process:
    kind: str
    parent: int
    own: float  # its own CPU seconds (user + system)
    reaped: float  # its children's that it has waited for


def _tree(root: int) -> dict[int, _Process]:
    """``root`` and every process under it, from /proc."""
    found: dict[int, tuple[str, list[str]]] = {}
    children: dict[int, list[int]] = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            text = stat.read_text()
        except OSError:
            continue
        fields = text.rsplit(")", 1)[1].split()
        found[int(stat.parent.name)] = (text[text.find("(") + 1 : text.rfind(")")], fields)
        children.setdefault(int(fields[1]), []).append(int(stat.parent.name))
    tree: dict[int, _Process] = {}
    stack = [root] if root in found else []
    while stack:
        pid = stack.pop()
        name, f = found[pid]
        tree[pid] = _Process(_kind(pid, root, name), int(f[1]), (int(f[11]) + int(f[12])) / _TICK,
                             (int(f[13]) + int(f[14])) / _TICK)
        stack.extend(children.get(pid, []))
    return tree


def _spent(before: dict[int, _Process], after: dict[int, _Process]) -> tuple[dict[str, float], float]:
    """CPU seconds spent between two looks at the tree, by kind, each process counted once; and what could not be
    told (processes gone whose parent did not wait for them, or left the tree: a browser's renderers).

    A process's own CPU counts where it runs. A child that ended was counted up to the first look; what its parent
    reaped beyond that is the rest of its life (and that of children born and gone between the looks), given to
    the kind of the child."""
    spent: dict[str, float] = collections.defaultdict(float)
    for pid, now in after.items():
        then = before.get(pid)
        spent[now.kind] += now.own - (then.own if then else 0.0)
    lost = 0.0
    for pid, now in after.items():
        then = before.get(pid)
        gone = [child for cpid, child in before.items() if child.parent == pid and cpid not in after]
        reaped = now.reaped - (then.reaped if then else 0.0) - sum(c.own + c.reaped for c in gone)
        kind = gone[0].kind if gone else "python children" if now.kind == "test process" else now.kind
        spent[kind] += reaped
    for pid, then in before.items():
        if pid not in after and then.parent not in after:
            lost += then.own + then.reaped
    return dict(spent), lost


# ---- the plugin (in each test process) -----------------------------------------------------------------
_sink: Any = None
_before: dict[str, tuple[float, dict[int, _Process]]] = {}


def pytest_runtest_setup(item: Any) -> None:
    """Before the test's fixtures are set up: the tree's CPU so far."""
    global _sink
    if _sink is None:
        OUT.mkdir(parents=True, exist_ok=True)
        worker = os.environ.get("PYTEST_XDIST_WORKER", "main")
        _sink = (OUT / f"{worker}-{os.getpid()}.jsonl").open("w", encoding="utf-8")
    _before[item.nodeid] = (time.monotonic(), _tree(os.getpid()))


def pytest_runtest_makereport(item: Any, call: Any) -> None:
    """After its teardown: what the tree spent since, by kind."""
    if call.when != "teardown" or item.nodeid not in _before:
        return
    started, before = _before.pop(item.nodeid)
    spent, lost = _spent(before, _tree(os.getpid()))
    _sink.write(json.dumps({"test": item.nodeid, "wall": round(time.monotonic() - started, 2), "lost": round(lost, 2),
                            "cpu": {kind: round(seconds, 2) for kind, seconds in spent.items()}}) + "\n")
    _sink.flush()


# ---- the runner ------------------------------------------------------------------------------------------
def _report() -> None:
    rows = [json.loads(line) for path in sorted(OUT.glob("*.jsonl")) for line in path.read_text().splitlines()]
    kinds: collections.Counter[str] = collections.Counter()  # seconds by kind
    ended = 0.0
    by_file: collections.Counter[str] = collections.Counter()  # seconds by test file
    by_test: list[tuple[float, str, dict[str, float]]] = []
    for row in rows:
        positive = {k: v for k, v in row["cpu"].items() if v > 0}
        ended += row["lost"] - sum(v for v in row["cpu"].values() if v < 0)
        kinds.update(positive)
        total = sum(positive.values())
        by_file[row["test"].split("::")[0]] += total
        by_test.append((total, row["test"], positive))
    print(f"{len(rows)} tests, {sum(kinds.values()):.0f} s of CPU: "
          + ", ".join(f"{kind} {seconds:.0f} s" for kind, seconds in kinds.most_common())
          + f" (and {ended:.0f} s of processes gone unwaited for, left out)")
    print("\ncostliest files (CPU s):")
    for name, seconds in by_file.most_common(20):
        print(f"{seconds:8.1f}  {name}")
    print("\ncostliest tests (CPU s: by kind):")
    for total, name, parts in sorted(by_test, reverse=True)[:30]:
        split = ", ".join(f"{k} {v:.1f}" for k, v in sorted(parts.items(), key=lambda kv: -kv[1]))
        print(f"{total:8.1f}  {name}  ({split})")


def main() -> int:
    if not Path("/proc/self/stat").is_file():
        print("suite_cpu reads /proc: Linux only", file=sys.stderr)
        return 2
    args = sys.argv[1:] or ["-n", "2", "--dist", "worksteal", "-m", "not realtime"]
    for old in OUT.glob("*.jsonl"):
        old.unlink()
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(Path(__file__).parent),
                                                                      os.environ.get("PYTHONPATH")])),
           "MPLBACKEND": "Agg", "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "PYTHONDONTWRITEBYTECODE": "1"}
    started = time.monotonic()
    code = subprocess.call([sys.executable, "-m", "pytest", "-p", "suite_cpu", "-q", *args], cwd=ROOT, env=env)
    print(f"\npytest: exit {code}, {time.monotonic() - started:.0f} s on the wall clock")
    _report()
    return code


if __name__ == "__main__":
    sys.exit(main())
