"""A client for FTC Dashboard's WebSocket: robot status, OpModes, telemetry and the ``@Config`` tree.

The protocol, as acmerobotics/ftc-dashboard defines it (``DashboardCore/src/main/java/com/acmerobotics/
dashboard/``: ``message/MessageType.java``, ``message/redux/*.java``, ``DashboardCore.java``; the server
``FtcDashboard/src/main/java/com/acmerobotics/dashboard/FtcDashboard.java``; the browser client
``client/src/store/middleware/socketMiddleware.ts`` and ``client/src/store/types/*.ts``):

* a plain WebSocket on port 8000 (``new NanoWSD(8000)``), one JSON object per text frame, its kind in
  ``"type"`` (Gson serialises the ``Message`` subclasses' fields next to it);
* on open the server sends ``RECEIVE_CONFIG`` ``{"configRoot": …}``, ``RECEIVE_CONFIG_BASELINE``, and
  ``RECEIVE_OP_MODE_LIST`` ``{"opModeInfoList": [{"name", "group"}, …]}`` once the OpModes are registered;
* ``GET_ROBOT_STATUS`` is answered by ``RECEIVE_ROBOT_STATUS`` ``{"status": {"enabled", "available",
  "activeOpMode", "activeOpModeStatus": "INIT"|"RUNNING"|"STOPPED", "warningMessage", "errorMessage",
  "batteryVoltage"}}`` (the largest hub input voltage, −1 when unknown); the browser sends it every
  second as its heartbeat. No OpMode active is ``activeOpMode == "$Stop$Robot$"`` (``STOP_OP_MODE_TAG``);
* ``INIT_OP_MODE`` ``{"opModeName"}``, ``START_OP_MODE``, ``STOP_OP_MODE`` drive the OpMode manager
  (``opModeManager.initOpMode(name)``, ``startActiveOpMode()``, ``requestOpModeStop(active)``);
* ``RECEIVE_TELEMETRY`` ``{"telemetry": [packet, …]}`` arrives in batches every ~100 ms
  (``DEFAULT_TELEMETRY_TRANSMISSION_INTERVAL``); a packet is ``{"timestamp": ms since 1970 (robot clock),
  "data": {key: value as a string}, "log": [lines], "field", "fieldOverlay"}``; an empty list means
  "clear";
* ``GET_CONFIG`` → ``RECEIVE_CONFIG``; ``SAVE_CONFIG`` ``{"configDiff": tree}`` updates the leaves the
  diff holds (``CustomVariable.update``) and the server sends the new ``RECEIVE_CONFIG`` to every client.
  A tree node is ``{"__type": "custom", "__value": {name: node}}``, a leaf ``{"__type": "double"|"float"|
  "int"|"long"|"boolean"|"string"|"enum"|"readonly_string", "__value": v}`` (enums add ``__enumClass``,
  ``__enumValues``; a non-finite double's value is a string). The browser's diff
  (``ConfigView.tsx``, ``validAndModified``) keeps only the modified leaves and their parents.
"""

from __future__ import annotations

import contextlib
import json
import threading
import time
from collections.abc import Callable
from typing import Any

from motorlab.robot import RobotLinkError

#: ``activeOpMode`` when no OpMode is active (``STOP_OP_MODE_TAG`` in client/src/store/types/opmode.ts).
STOP_TAG = "$Stop$Robot$"
#: Largest frame accepted [bytes] (a big ``@Config`` tree plus a batch of telemetry).
MAX_FRAME = 16 * 1024 * 1024

Message = dict[str, Any]


def is_idle(status: dict[str, Any]) -> bool:
    """True when the robot status says no OpMode is initialised or running."""
    active = str(status.get("activeOpMode") or "")
    return active in ("", STOP_TAG) or status.get("activeOpModeStatus") == "STOPPED"


class Dashboard:
    """One WebSocket connection to FTC Dashboard at ``host:port``, read by a background thread.

    Parameters
    ----------
    host, port
        The robot and Dashboard's port (8000 on a robot).
    timeout
        Seconds for opening the connection and for each answer waited for.
    on_telemetry
        Called (in the reader thread) with each list of packets received.
    """

    def __init__(self, host: str, port: int, *, timeout: float = 5.0,
                 on_telemetry: Callable[[list[dict[str, Any]]], None] | None = None) -> None:
        self.host, self.port, self.timeout = host, int(port), float(timeout)
        self.address = f"{host}:{self.port}"
        self.on_telemetry = on_telemetry
        self._cond = threading.Condition()
        self._latest: dict[str, tuple[int, Message]] = {}  # type -> (sequence number, message)
        self._sequence = 0
        self.last_message = time.monotonic()
        self.closed: str | None = None
        self._conn: Any = None
        self._thread: threading.Thread | None = None

    def __enter__(self) -> Dashboard:
        self.connect()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def connect(self) -> None:
        """Open the WebSocket (no proxy, no compression: NanoWSD speaks neither) and start reading."""
        from websockets.exceptions import InvalidHandshake, InvalidURI
        from websockets.sync.client import connect

        try:
            self._conn = connect(f"ws://{self.host}:{self.port}/", proxy=None, compression=None,
                                 open_timeout=self.timeout, ping_interval=None, close_timeout=1.0,
                                 max_size=MAX_FRAME).__enter__()  # the context form (websockets ≥ 17.1 warns otherwise)
        except ConnectionRefusedError:
            raise RobotLinkError(f"no FTC Dashboard at {self.address} (connection refused): install FTC Dashboard "
                                 "in TeamCode and enable it, or check --host and --dashboard-port") from None
        except (TimeoutError, OSError) as exc:
            reason = getattr(exc, "strerror", None) or type(exc).__name__
            raise RobotLinkError(f"cannot reach FTC Dashboard at {self.address} ({reason}): connect this computer "
                                 "to the robot's Wi-Fi or give --host") from None
        except (InvalidHandshake, InvalidURI) as exc:
            raise RobotLinkError(f"{self.address} is not FTC Dashboard's WebSocket ({exc}): check --dashboard-port "
                                 "(8000 on a robot)") from None
        self._thread = threading.Thread(target=self._read, name="motorlab-dashboard", daemon=True)
        self._thread.start()

    def _read(self) -> None:
        from websockets.exceptions import ConnectionClosed

        try:
            while True:
                try:
                    frame = self._conn.recv(timeout=0.05)
                except TimeoutError:
                    if self.closed:
                        return
                    continue
                self.last_message = time.monotonic()
                try:
                    message = json.loads(frame)
                except ValueError:
                    continue  # not JSON: not a Dashboard message; ignore
                if not isinstance(message, dict) or not isinstance(message.get("type"), str):
                    continue
                if message["type"] == "RECEIVE_TELEMETRY" and self.on_telemetry is not None:
                    packets = message.get("telemetry")
                    if isinstance(packets, list):
                        self.on_telemetry(packets)
                with self._cond:
                    self._sequence += 1
                    self._latest[message["type"]] = (self._sequence, message)
                    self._cond.notify_all()
        except (ConnectionClosed, OSError) as exc:
            with self._cond:
                self.closed = self.closed or f"the connection to {self.address} closed ({type(exc).__name__})"
                self._cond.notify_all()

    def send(self, message: Message) -> None:
        """Send one message; :class:`RobotLinkError` when the connection is gone."""
        from websockets.exceptions import ConnectionClosed

        if self._conn is None or self.closed:
            raise RobotLinkError(f"FTC Dashboard at {self.address}: not connected ({self.closed or 'never opened'})")
        try:
            self._conn.send(json.dumps(message))
        except (ConnectionClosed, OSError) as exc:
            self.closed = f"the connection to {self.address} closed ({type(exc).__name__})"
            raise RobotLinkError(f"FTC Dashboard at {self.address}: {self.closed}") from None

    def _mark(self) -> int:
        with self._cond:
            return self._sequence

    def wait(self, kind: str, *, after: int = -1, timeout: float | None = None,
             accept: Callable[[Message], bool] | None = None) -> Message:
        """The first ``kind`` message newer than sequence number ``after`` (that ``accept`` takes)."""
        deadline = time.monotonic() + (self.timeout if timeout is None else timeout)
        with self._cond:
            while True:
                seq, message = self._latest.get(kind, (-1, {}))
                if seq > after and (accept is None or accept(message)):
                    return message
                left = deadline - time.monotonic()
                if self.closed:
                    raise RobotLinkError(f"FTC Dashboard at {self.address}: {self.closed}")
                if left <= 0:
                    raise RobotLinkError(f"FTC Dashboard at {self.address} did not send {kind} within "
                                         f"{self.timeout if timeout is None else timeout:g} s")
                self._cond.wait(min(left, 0.05))

    def status(self, timeout: float | None = None) -> dict[str, Any]:
        """A fresh robot status (``GET_ROBOT_STATUS`` → ``RECEIVE_ROBOT_STATUS``)."""
        mark = self._mark()
        self.send({"type": "GET_ROBOT_STATUS"})
        status = self.wait("RECEIVE_ROBOT_STATUS", after=mark, timeout=timeout).get("status")
        if not isinstance(status, dict):
            raise RobotLinkError(f"FTC Dashboard at {self.address}: a robot status without 'status'")
        return status

    def op_modes(self, timeout: float | None = None) -> list[dict[str, str]]:
        """The OpModes the robot offers (sent once registered: ``RECEIVE_OP_MODE_LIST``)."""
        try:
            message = self.wait("RECEIVE_OP_MODE_LIST", timeout=timeout)
        except RobotLinkError:
            raise RobotLinkError(f"FTC Dashboard at {self.address} sent no OpMode list: wait until the robot "
                                 "controller app has started, then try again") from None
        items = message.get("opModeInfoList") or []
        return [{"name": str(i.get("name")), "group": str(i.get("group"))} for i in items if isinstance(i, dict)]

    def config(self, timeout: float | None = None) -> dict[str, Any]:
        """The whole ``@Config`` tree, fresh (``GET_CONFIG`` → ``RECEIVE_CONFIG``)."""
        mark = self._mark()
        self.send({"type": "GET_CONFIG"})
        root = self.wait("RECEIVE_CONFIG", after=mark, timeout=timeout).get("configRoot")
        if not isinstance(root, dict) or root.get("__type") != "custom":
            raise RobotLinkError(f"FTC Dashboard at {self.address}: a config tree that is not a custom variable")
        return root

    def save_config(self, diff: dict[str, Any], timeout: float | None = None) -> dict[str, Any]:
        """Send ``SAVE_CONFIG`` with ``diff``; the tree the server sends back after applying it."""
        mark = self._mark()
        self.send({"type": "SAVE_CONFIG", "configDiff": diff})
        # FtcDashboard answers a save by sending the new tree to every client (withConfigRoot →
        # updateConfig); read it back with GET_CONFIG in any case.
        with contextlib.suppress(RobotLinkError):
            self.wait("RECEIVE_CONFIG", after=mark, timeout=min(self.timeout, 2.0) if timeout is None else timeout)
        return self.config(timeout)

    def init_op_mode(self, name: str) -> None:
        self.send({"type": "INIT_OP_MODE", "opModeName": name})

    def start_op_mode(self) -> None:
        self.send({"type": "START_OP_MODE"})

    def stop_op_mode(self) -> None:
        self.send({"type": "STOP_OP_MODE"})

    def close(self) -> None:
        """Close the connection and stop the reader (within ~0.1 s)."""
        if self.closed is None:
            self.closed = "closed by motorlab"
        if self._conn is not None:
            with contextlib.suppress(Exception):
                self._conn.close()
        if self._thread is not None:
            self._thread.join(timeout=1.0)
