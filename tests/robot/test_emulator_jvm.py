"""motorlab.robot.emulator_jvm: an OpMode process's packets forwarded as FTC Dashboard's DashboardCore sends
them (100 ms batches, a queue of at most 101), and STOP reaching the process (a Python stand-in process here;
tests/test_ftc_robot.py runs the real OpModes in the JVM)."""

from __future__ import annotations

import sys
import threading
import time
from typing import Any

from motorlab.robot.emulator_jvm import QUEUE_LIMIT, JvmOpMode

#: An "OpMode": ``count`` packets, ``pause`` s apart, until it reads "stop"; then its summary line.
PROCESS = """
import json, sys, threading, time
stop = threading.Event()
threading.Thread(target=lambda: (sys.stdin.readline(), stop.set()), daemon=True).start()
sent = 0
for i in range({count}):
    if stop.is_set():
        break
    print(json.dumps({{"timestamp": 1000 + i, "data": {{"x": str(i)}}, "log": []}}), flush=True)
    sent += 1
    time.sleep({pause})
print(json.dumps({{"stop_reason": "stopped" if stop.is_set() else "complete", "sent": sent}}), flush=True)
"""


def test_packets_arrive_in_batches_and_a_full_queue_drops_as_dashboard_does() -> None:
    messages: list[dict[str, Any]] = []
    opmode = JvmOpMode([sys.executable, "-c", PROCESS.format(count=2000, pause=0)])
    opmode(messages.append, lambda: True)  # 2000 packets at once: more than the queue holds in 100 ms
    assert opmode.summary == {"stop_reason": "complete", "sent": 2000}
    assert {m["type"] for m in messages} == {"RECEIVE_TELEMETRY"}
    batches = [m["telemetry"] for m in messages]
    assert max(len(b) for b in batches) <= QUEUE_LIMIT + 1
    assert opmode.packets == sum(len(b) for b in batches) == 2000 - opmode.dropped
    assert opmode.dropped > 0
    stamps = [p["timestamp"] for b in batches for p in b]
    assert stamps == sorted(stamps)


def test_stop_reaches_the_opmode_process() -> None:
    messages: list[dict[str, Any]] = []
    running = threading.Event()
    running.set()
    opmode = JvmOpMode([sys.executable, "-c", PROCESS.format(count=100000, pause=0.005)])
    threading.Timer(0.8, running.clear).start()  # the client's STOP_OP_MODE
    start = time.monotonic()
    opmode(messages.append, running.is_set)
    assert time.monotonic() - start < 3.0
    assert opmode.summary["stop_reason"] == "stopped"
    assert 0 < opmode.packets == opmode.summary["sent"] - opmode.dropped
    assert opmode.dropped == 0  # 200 packets a second fit the 100 ms batches


def test_a_missing_program_ends_the_opmode_with_a_reason() -> None:
    opmode = JvmOpMode(["/nonexistent/java", "-version"])
    opmode(lambda message: None, lambda: True)
    assert "cannot start /nonexistent/java" in opmode.stderr
