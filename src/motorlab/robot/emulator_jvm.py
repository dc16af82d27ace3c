"""A real OpMode, run as a process, behind the emulated robot's FTC Dashboard (:mod:`motorlab.robot.emulator`).

The process is motorlab's own OpModes in the JVM (``ftc/TeamCode/src/test/.../sim/RunSim.java`` with
``dashboard=yes realtime=yes stdin_stop=yes``): its stand-in for ``FtcDashboard`` prints every
``TelemetryPacket`` it is sent as one JSON line, as Dashboard's Gson writes a packet. :class:`JvmOpMode`
starts the process when the client sends ``START_OP_MODE``, and forwards its packets to the clients as
``RECEIVE_TELEMETRY`` batches the way FTC Dashboard's ``DashboardCore`` does (acmerobotics/ftc-dashboard,
``DashboardCore/src/main/java/com/acmerobotics/dashboard/DashboardCore.java`` at v0.5.0: packets queue in
``sendTelemetryPacket``, a queue already holding more than 100 drops the new one (line 169), and the
``TelemetryUpdateRunnable`` sends the whole queue, then sleeps the 100 ms transmission interval (lines 30,
55-95); the same at v0.4.16). ``STOP_OP_MODE`` (or INIT of another OpMode) writes ``stop`` to the process's
stdin, which stops the OpMode as the Driver Station's STOP does (``requestOpModeStop``).

Use::

    robot = EmulatedRobot(opmodes=[OpModeSpec("motorlab: quasistatic ramp", "motorlab", "quasistatic_ramp")])
    robot.external_opmode = JvmOpMode(["java", "-cp", classes, "...RunSim", "experiment=quasistatic", ...])
"""

from __future__ import annotations

import contextlib
import json
import subprocess
import threading
import time
from collections.abc import Callable, Sequence
from typing import Any

#: DashboardCore's DEFAULT_TELEMETRY_TRANSMISSION_INTERVAL [s] (100 ms at every version 0.4.10–0.6.0).
TRANSMISSION_INTERVAL = 0.1
#: A packet sent while the queue holds more than this many is dropped (DashboardCore.sendTelemetryPacket).
QUEUE_LIMIT = 100
#: Seconds the process has to end after ``stop`` before it is killed.
STOP_GRACE = 5.0


class JvmOpMode:
    """Runs ``command`` as the OpMode each time the emulated robot starts one (see the module's notes).

    After a run: :attr:`summary` is the process's last JSON line that is not a packet (RunSim's summary:
    stop reason, log file, truth), :attr:`stderr` its error output, :attr:`packets` the packets forwarded
    and :attr:`dropped` those the queue limit dropped.
    """

    def __init__(self, command: Sequence[str], *, cwd: str | None = None) -> None:
        self.command = [str(c) for c in command]
        self.cwd = cwd
        self.summary: dict[str, Any] = {}
        self.stderr = ""
        self.packets = 0
        self.dropped = 0
        self._pending: list[dict[str, Any]] = []
        self._lock = threading.Lock()

    def _read(self, stream: Any) -> None:
        """Queue each packet line; keep the other JSON objects (the summary)."""
        for line in stream:
            try:
                item = json.loads(line)
            except ValueError:
                continue  # Driver Station text printed by the harness
            if not isinstance(item, dict):
                continue
            if isinstance(item.get("data"), dict) and "timestamp" in item:
                with self._lock:
                    if len(self._pending) > QUEUE_LIMIT:
                        self.dropped += 1
                    else:
                        self._pending.append(item)
            else:
                self.summary = item

    def _send_pending(self, broadcast: Callable[[dict[str, Any]], None]) -> None:
        with self._lock:
            batch, self._pending = self._pending, []
        if batch:
            self.packets += len(batch)
            broadcast({"type": "RECEIVE_TELEMETRY", "telemetry": batch})

    def __call__(self, broadcast: Callable[[dict[str, Any]], None], running: Callable[[], bool]) -> None:
        """Run the OpMode until it ends or ``running()`` turns false (STOP); forward its packets meanwhile."""
        try:
            proc = subprocess.Popen(self.command, cwd=self.cwd, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                    stderr=subprocess.PIPE, text=True, encoding="utf-8")
        except OSError as exc:  # no java: the OpMode ends at once, as one that throws in init
            self.stderr = f"cannot start {self.command[0]}: {exc.strerror}"
            return
        stdin, stdout, stderr = proc.stdin, proc.stdout, proc.stderr
        if stdin is None or stdout is None or stderr is None:  # pipes were asked for: never
            raise RuntimeError("the OpMode process has no pipes")
        errors: list[str] = []
        reader = threading.Thread(target=self._read, args=(stdout,), daemon=True)
        drain = threading.Thread(target=lambda: errors.append(stderr.read()), daemon=True)
        reader.start()
        drain.start()
        stop_sent = False
        try:
            while reader.is_alive() or proc.poll() is None:
                time.sleep(TRANSMISSION_INTERVAL)
                self._send_pending(broadcast)
                if not stop_sent and not running():
                    stop_sent = True
                    with contextlib.suppress(OSError):
                        stdin.write("stop\n")
                        stdin.close()
                    deadline = time.monotonic() + STOP_GRACE
                    while proc.poll() is None and time.monotonic() < deadline:
                        time.sleep(0.02)
                    if proc.poll() is None:
                        proc.kill()
            reader.join(1.0)
            self._send_pending(broadcast)
        finally:
            if proc.poll() is None:
                proc.kill()
            proc.wait(STOP_GRACE)
            drain.join(1.0)
            self.stderr = "".join(errors)
            for stream in (stdin, stdout, stderr):
                with contextlib.suppress(OSError):
                    stream.close()
