"""A client for FTC Dashboard's WebSocket: robot status, OpModes, telemetry and the ``@Config`` tree.

The protocol, as acmerobotics/ftc-dashboard defines it at every version teams run (v0.4.10 … v0.4.17,
v0.5.0, v0.5.1, v0.6.0; ``DashboardCore/src/main/java/com/acmerobotics/dashboard/``:
``message/MessageType.java``, ``message/redux/*.java``, ``DashboardCore.java``; the server
``FtcDashboard/src/main/java/com/acmerobotics/dashboard/FtcDashboard.java``; the browser client
``client/src/store/middleware/socketMiddleware.ts``):

* a plain WebSocket on port 8000 (``new NanoWSD(8000)``, NanoHTTPD 2.3.1), one JSON object per text
  frame, its kind in ``"type"`` (Gson serialises the ``Message`` subclasses' fields next to it);
* NanoHTTPD gives every socket a 5 s read timeout (``SOCKET_READ_TIMEOUT = 5000``, NanoHTTPD.java:1836,
  ``setSoTimeout`` at :1771): a client that sends nothing for 5 s is dropped (NanoWSD.java:245-260
  closes the socket without a close frame). The browser client sends ``GET_ROBOT_STATUS`` every second
  (socketMiddleware.ts:21-47); so does :class:`Dashboard`, for as long as the connection is open;
* a message whose type this version does not know deserialises to ``null`` (MessageDeserializer.java:22)
  and the server drops the connection the same way: this client sends only the types every version has;
* on open the server sends ``RECEIVE_CONFIG`` ``{"configRoot": …}`` (and, from v0.6.0 only,
  ``RECEIVE_CONFIG_BASELINE``), then ``RECEIVE_OP_MODE_LIST`` once the OpModes are registered: up to
  v0.5.0 ``{"opModeList": [name, …]}``, from v0.5.1 ``{"opModeInfoList": [{"name", "group"}, …]}``
  (``message/redux/ReceiveOpModeList.java``); both are read;
* ``GET_ROBOT_STATUS`` is answered by ``RECEIVE_ROBOT_STATUS`` ``{"status": {"enabled", "available",
  "activeOpMode", "activeOpModeStatus": "INIT"|"RUNNING"|"STOPPED", "warningMessage", "errorMessage",
  "batteryVoltage"}}`` (``batteryVoltage`` from v0.4.14 on: the largest hub input voltage, −1 when
  unknown). Answers come in the order asked (one reader thread per socket, NanoWSD.java:245-250), which
  :meth:`Dashboard.status` uses to know the answer to its own request. No OpMode active is
  ``activeOpMode == "$Stop$Robot$"`` (the SDK's default OpMode);
* a disabled Dashboard (the robot controller's menu "Disable Dashboard", or the OpMode
  "Enable/Disable Dashboard") answers ``GET_ROBOT_STATUS`` with ``"enabled": false`` and swallows every
  other message (DashboardCore.java:123-126 at v0.4.16): :meth:`Dashboard.connect` asks for the status
  first and names it;
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
import math
import threading
import time
from collections.abc import Callable
from typing import Any

from motorlab.robot import RobotLinkError

#: ``activeOpMode`` when no OpMode is active (``STOP_OP_MODE_TAG`` in client/src/store/types/opmode.ts).
STOP_TAG = "$Stop$Robot$"
#: Largest frame accepted [bytes] (a big ``@Config`` tree plus a batch of telemetry).
MAX_FRAME = 16 * 1024 * 1024
#: Seconds between two status requests when nothing else asks: the browser client's heartbeat
#: (``setInterval(…, 1000)`` in client/src/store/middleware/socketMiddleware.ts), well inside NanoHTTPD's
#: 5 s read timeout.
HEARTBEAT = 1.0
#: What to do about a disabled Dashboard, in the words of its own page (client/src/components/Dashboard/
#: Dashboard.tsx: "To re-enable, run the "Enable/Disable Dashboard" op mode or select "Enable Dashboard"
#: from the RC menu").
DISABLED = ("FTC Dashboard is disabled on the robot: enable it from the Driver Station (run the OpMode "
            "\"Enable/Disable Dashboard\") or the robot controller's menu (\"Enable Dashboard\"), then try again")

Message = dict[str, Any]


def is_idle(status: dict[str, Any]) -> bool:
    """True when the robot status says no OpMode is initialised or running."""
    active = str(status.get("activeOpMode") or "")
    return active in ("", STOP_TAG) or status.get("activeOpModeStatus") == "STOPPED"


def battery_volts(status: dict[str, Any]) -> float:
    """The status's battery voltage [V]; NaN when the robot does not know it (−1: no hub read yet) or the
    Dashboard is older than v0.4.14 (no ``batteryVoltage`` in ``RobotStatus.java``)."""
    value = status.get("batteryVoltage")
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value) or value <= 0:
        return math.nan
    return float(value)


def op_mode_list(message: Message) -> list[dict[str, str]]:
    """The OpModes of a ``RECEIVE_OP_MODE_LIST``, as ``{"name", "group"}``: v0.5.1+ sends
    ``opModeInfoList`` (``OpModeInfo``: name, group), v0.4.x and v0.5.0 ``opModeList`` (names only; the
    group is then "")."""
    items = message.get("opModeInfoList")
    if isinstance(items, list):
        return [{"name": str(i.get("name")), "group": str(i.get("group") or "")} for i in items
                if isinstance(i, dict) and i.get("name") is not None]
    names = message.get("opModeList")
    if isinstance(names, list):
        return [{"name": str(n), "group": ""} for n in names if isinstance(n, str)]
    return []


class Dashboard:
    """One WebSocket connection to FTC Dashboard at ``host:port``, read by a background thread and kept
    alive by another (a status request every :data:`HEARTBEAT` s, as the browser client does).

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
        self._send_lock = threading.Lock()
        self._latest: dict[str, tuple[int, Message]] = {}  # type -> (sequence number, message)
        self._sequence = 0
        self._status_asked = 0  # GET_ROBOT_STATUS sent
        self._status_answered = 0  # RECEIVE_ROBOT_STATUS received (in the order asked)
        self._status_sent_at = 0.0
        self.last_message = time.monotonic()
        self.closed: str | None = None
        self._conn: Any = None
        self._threads: list[threading.Thread] = []
        self.first_status: dict[str, Any] = {}

    def __enter__(self) -> Dashboard:
        self.connect()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def connect(self) -> None:
        """Open the WebSocket (no proxy, no compression: NanoWSD speaks neither), start reading and the
        heartbeat, and read the robot status: :class:`RobotLinkError` naming a disabled Dashboard."""
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
        for target, name in ((self._read, "motorlab-dashboard"), (self._heartbeat, "motorlab-dashboard-heartbeat")):
            thread = threading.Thread(target=target, name=name, daemon=True)
            thread.start()
            self._threads.append(thread)
        try:
            self.first_status = self.status()
        except RobotLinkError:
            self.close()
            raise
        if self.first_status.get("enabled") is False:
            self.close()
            raise RobotLinkError(DISABLED)

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
                    if message["type"] == "RECEIVE_ROBOT_STATUS":
                        self._status_answered += 1
                    self._cond.notify_all()
        except (ConnectionClosed, OSError) as exc:
            with self._cond:
                self.closed = self.closed or (f"the connection to {self.address} closed ({type(exc).__name__}; "
                                              "FTC Dashboard drops a client after 5 s without a message, or on "
                                              "a message it does not know)")
                self._cond.notify_all()

    def _heartbeat(self) -> None:
        """``GET_ROBOT_STATUS`` whenever none was sent for :data:`HEARTBEAT` s, until closed."""
        while not self.closed:
            time.sleep(0.05)
            if self.closed:
                return
            if time.monotonic() - self._status_sent_at >= HEARTBEAT:
                with contextlib.suppress(RobotLinkError):
                    self.request_status()

    def send(self, message: Message) -> None:
        """Send one message; :class:`RobotLinkError` when the connection is gone."""
        with self._send_lock:
            self._send(message)

    def _send(self, message: Message) -> None:
        from websockets.exceptions import ConnectionClosed

        if self._conn is None or self.closed:
            raise RobotLinkError(f"FTC Dashboard at {self.address}: not connected ({self.closed or 'never opened'})")
        try:
            self._conn.send(json.dumps(message))
        except (ConnectionClosed, OSError) as exc:
            self.closed = self.closed or f"the connection to {self.address} closed ({type(exc).__name__})"
            raise RobotLinkError(f"FTC Dashboard at {self.address}: {self.closed}") from None

    def request_status(self) -> int:
        """Send ``GET_ROBOT_STATUS``; the number of its answer (see :meth:`status`)."""
        with self._send_lock:
            self._send({"type": "GET_ROBOT_STATUS"})
            self._status_sent_at = time.monotonic()
            with self._cond:
                self._status_asked += 1
                return self._status_asked

    def latest_status(self) -> dict[str, Any]:
        """The last robot status received (``{}`` before any)."""
        with self._cond:
            status = self._latest.get("RECEIVE_ROBOT_STATUS", (0, {}))[1].get("status")
        return status if isinstance(status, dict) else {}

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
        """The robot status answering this very request (``GET_ROBOT_STATUS`` → ``RECEIVE_ROBOT_STATUS``):
        answers come in the order asked, so the n-th answer is the n-th request's."""
        number = self.request_status()
        deadline = time.monotonic() + (self.timeout if timeout is None else timeout)
        with self._cond:
            while self._status_answered < number:
                if self.closed:
                    raise RobotLinkError(f"FTC Dashboard at {self.address}: {self.closed}")
                left = deadline - time.monotonic()
                if left <= 0:
                    waited = self.timeout if timeout is None else timeout
                    raise RobotLinkError(f"FTC Dashboard at {self.address} did not answer a status request "
                                         f"(RECEIVE_ROBOT_STATUS) within {waited:g} s")
                self._cond.wait(min(left, 0.05))
        status = self.latest_status()
        if not status:
            raise RobotLinkError(f"FTC Dashboard at {self.address}: a robot status without 'status'")
        return status

    def op_modes(self, timeout: float | None = None) -> list[dict[str, str]]:
        """The OpModes the robot offers (sent once registered: ``RECEIVE_OP_MODE_LIST``, either shape)."""
        try:
            message = self.wait("RECEIVE_OP_MODE_LIST", timeout=timeout)
        except RobotLinkError:
            if self.closed:
                raise
            raise RobotLinkError(f"FTC Dashboard at {self.address} sent no OpMode list: wait until the robot "
                                 "controller app has started, then try again") from None
        return op_mode_list(message)

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
        """Close the connection and stop the reader and the heartbeat (within ~0.1 s)."""
        if self.closed is None:
            self.closed = "closed by motorlab"
        if self._conn is not None:
            with contextlib.suppress(Exception):
                self._conn.close()
        for thread in self._threads:
            if thread is not threading.current_thread():
                thread.join(timeout=1.0)
