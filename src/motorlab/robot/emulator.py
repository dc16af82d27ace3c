"""An emulated FTC robot on 127.0.0.1: Road Runner's and motorlab's HTTP routes and FTC Dashboard's WebSocket.

Built from the projects' sources (see :mod:`motorlab.robot.pull` and :mod:`motorlab.robot.dashboard`
for the routes and messages), for the tests and for ``motorlab robot emulate``:

* HTTP (the robot controller's web server, port 8080 on a robot): ``/tuning/<type>/latest.json``
  (chunked, ``X-Filename``, 404 with an empty body when the type has no file), ``/tuning/<type>/<name>``,
  ``/logs`` (Road Runner's HTML list, newest first), ``/logs/download?file=`` (Road Runner's query
  parsing and its 400/404 answers), ``/motorlab/logs`` and ``/motorlab/logs/download?file=``
  (``MotorlabLogFiles.java``); ``drop_after`` cuts every download after that many bytes (a lost Wi-Fi);
* FTC Dashboard (port 8000 on a robot) as each version teams run defines it (``dashboard_version``:
  0.4.10 … 0.4.17, 0.5.0, 0.5.1, 0.6.0; the upstream file and line of each behaviour are cited where it
  is written, as ``tag:path:line``): on open ``RECEIVE_CONFIG`` (and ``RECEIVE_CONFIG_BASELINE`` from
  v0.6.0 only), ``RECEIVE_OP_MODE_LIST`` as names (up to v0.5.0) or ``{name, group}`` (v0.5.1+);
  ``GET_ROBOT_STATUS`` (``batteryVoltage`` from v0.4.14); ``INIT_OP_MODE``/``START_OP_MODE``/
  ``STOP_OP_MODE`` with the status the OpMode manager's notifications give (INIT, RUNNING, STOPPED,
  then the default OpMode ``$Stop$Robot$``); ``GET_CONFIG``; ``SAVE_CONFIG`` applied leaf by leaf;
  telemetry packets every loop sent in batches every 100 ms; NanoHTTPD's 5 s read timeout (an idle
  client is dropped without a close frame) and the dropped connection on a message type the version
  does not know; a disabled Dashboard (``enabled=False``) that answers only ``GET_ROBOT_STATUS``.

The OpModes it offers are a table (:data:`OPMODES`: name, group, behaviour): motorlab's quasistatic
ramp (a drive motor obeying V = kS·sgn(v) + kV·v + kA·a in encoder ticks, :class:`Plant`, under a
voltage ramp; keys ``voltage`` [V], ``position`` [ticks], ``velocity`` [ticks/s] and ``state``, a
word), Road Runner's ``ForwardRampLogger`` (no Dashboard telemetry; runs until STOP, then saves its
ramp file) and ``ManualFeedforwardTuner`` (keys ``mode``, ``v0``…, ``vref`` [in/s]; runs until STOP),
``LocalizationTest`` and the Dashboard's own "Enable/Disable Dashboard".

Citations read ``tag:path:line``. ``v0.x.y:…/DashboardCore.java`` is acmerobotics/ftc-dashboard at that tag,
``DashboardCore/src/main/java/com/acmerobotics/dashboard/…`` (``FtcDashboard/src/main/java/com/acmerobotics/
dashboard/FtcDashboard.java`` for ``FtcDashboard/…``); ``NanoHTTPD.java`` and ``NanoWSD.java`` are
NanoHttpd/nanohttpd at ``nanohttpd-project-2.3.1`` (the version FtcDashboard's build.gradle pins),
``core/src/main/java/fi/iki/elonen/NanoHTTPD.java`` and ``websocket/src/main/java/fi/iki/elonen/NanoWSD.java``;
``FileServing.kt`` and ``Tuning.kt`` are acmerobotics/road-runner-ftc at 1f35428,
``RoadRunner/src/main/java/com/acmerobotics/roadrunner/ftc/``.

It listens on 127.0.0.1 only, and stops by itself after ``lifetime`` seconds or ``max_requests``
requests and messages, whichever comes first.
"""

from __future__ import annotations

import contextlib
import copy
import json
import math
import threading
import time
import urllib.parse
from dataclasses import dataclass, field
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any, ClassVar

from motorlab.robot.dashboard import STOP_TAG

LOOPBACK = "127.0.0.1"
TUNING_TYPES = ("forward-ramp", "lateral-ramp", "angular-ramp", "accel")
#: FTC Dashboard versions the emulator plays (every one teams pin; acmerobotics/ftc-dashboard tags).
DASHBOARD_VERSIONS = ("0.4.10", "0.4.11", "0.4.12", "0.4.13", "0.4.14", "0.4.15", "0.4.16", "0.4.17", "0.5.0",
                      "0.5.1", "0.6.0")
#: NanoHTTPD's read timeout [s]: ``SOCKET_READ_TIMEOUT = 5000`` (NanoHttpd/nanohttpd
#: nanohttpd-project-2.3.1:core/src/main/java/fi/iki/elonen/NanoHTTPD.java:1836), set on every accepted
#: socket (:1771) by ``start()`` (:2297), which FtcDashboard calls (v0.4.16:FtcDashboard/src/main/java/com/
#: acmerobotics/dashboard/FtcDashboard.java:659, ``server.start()``).
SOCKET_READ_TIMEOUT = 5.0
#: Message types each version knows (DashboardCore/src/main/java/com/acmerobotics/dashboard/message/
#: MessageType.java at each tag); any other type deserialises to null and drops the connection.
_TYPES_04 = ("GET_ROBOT_STATUS", "RECEIVE_ROBOT_STATUS", "INIT_OP_MODE", "START_OP_MODE", "STOP_OP_MODE",
             "RECEIVE_OP_MODE_LIST", "GET_CONFIG", "SAVE_CONFIG", "RECEIVE_CONFIG", "RECEIVE_TELEMETRY",
             "RECEIVE_IMAGE", "RECEIVE_GAMEPAD_STATE")  # v0.4.16:…/MessageType.java:21-42
# v0.4.17 and v0.5.0:…/MessageType.java:23-48
_TYPES_05 = (*_TYPES_04, "RECEIVE_HARDWARE_CONFIG_LIST", "SET_HARDWARE_CONFIG")
_TYPES_06 = (*_TYPES_05, "GET_CONFIG_BASELINE", "RECEIVE_CONFIG_BASELINE", "WRITE_HARDWARE_CONFIG",
             "DELETE_HARDWARE_CONFIG", "RECEIVE_LOGCAT_ERRORS")  # v0.6.0:…/MessageType.java:28-60


def version_tuple(version: str) -> tuple[int, ...]:
    """``"0.5.1"`` → ``(0, 5, 1)``; :class:`ValueError` for a version the emulator does not play."""
    if version not in DASHBOARD_VERSIONS:
        raise ValueError(f"FTC Dashboard {version!r} is not emulated (versions: {', '.join(DASHBOARD_VERSIONS)})")
    return tuple(int(part) for part in version.split("."))


@dataclass(frozen=True)
class OpModeSpec:
    """One OpMode of the emulated robot: its name and group as registered, and what it does when started
    (``behaviour``: a key of :attr:`EmulatedRobot.BEHAVIOURS`)."""

    name: str
    group: str
    behaviour: str


#: The OpModes the emulated robot offers, one row each (add a row, and a behaviour, to add one).
OPMODES: tuple[OpModeSpec, ...] = (
    OpModeSpec("motorlab: quasistatic ramp", "motorlab", "quasistatic_ramp"),
    # road-runner-quickstart TeamCode/…/tuning/TuningOpModes.java:58-68 (group "quickstart", simple class names)
    OpModeSpec("ForwardRampLogger", "quickstart", "forward_ramp_logger"),
    OpModeSpec("ManualFeedforwardTuner", "quickstart", "manual_feedforward_tuner"),
    OpModeSpec("LocalizationTest", "quickstart", "until_stop"),
    # v0.4.16:FtcDashboard/…/FtcDashboard.java:942-948 (internalRegisterOpMode, group "dash")
    OpModeSpec("Enable/Disable Dashboard", "dash", "toggle_dashboard"),
)


def _var(kind: str, value: Any) -> dict[str, Any]:
    return {"__type": kind, "__value": value}


def _enum(value: str, cls: str, values: list[str]) -> dict[str, Any]:
    return {"__type": "enum", "__value": value, "__enumClass": cls, "__enumValues": values}


def default_config_tree() -> dict[str, Any]:
    """A robot's ``@Config`` tree: road-runner-quickstart ``MecanumDrive.PARAMS`` (every field, its defaults),
    a Pedro ``Constants`` class made ``@Config``, and an arm's ``PIDFCoefficients``."""
    facing = "com.qualcomm.hardware.rev.RevHubOrientationOnRobot$LogoFacingDirection"
    usb = "com.qualcomm.hardware.rev.RevHubOrientationOnRobot$UsbFacingDirection"
    directions = ["UP", "DOWN", "FORWARD", "BACKWARD", "LEFT", "RIGHT"]
    params = {
        "logoFacingDirection": _enum("UP", facing, directions),
        "usbFacingDirection": _enum("FORWARD", usb, directions),
        "inPerTick": _var("double", 1.0), "lateralInPerTick": _var("double", 1.0),
        "trackWidthTicks": _var("double", 0.0),
        "kS": _var("double", 0.0), "kV": _var("double", 0.0), "kA": _var("double", 0.0),
        "maxWheelVel": _var("double", 50.0), "minProfileAccel": _var("double", -30.0),
        "maxProfileAccel": _var("double", 50.0), "maxAngVel": _var("double", math.pi),
        "maxAngAccel": _var("double", math.pi),
        "axialGain": _var("double", 0.0), "lateralGain": _var("double", 0.0), "headingGain": _var("double", 0.0),
        "axialVelGain": _var("double", 0.0), "lateralVelGain": _var("double", 0.0),
        "headingVelGain": _var("double", 0.0),
    }
    drive_constants = {"xVelocity": _var("double", 81.34056), "yVelocity": _var("double", 65.43028),
                       "maxPower": _var("double", 1.0), "nominalVoltage": _var("double", 12.0),
                       "staticFrictionCoefficient": _var("double", 0.1),
                       "leftFrontMotorName": _var("string", "leftFront")}
    follower = {"mass": _var("double", 10.65), "forwardZeroPowerAcceleration": _var("double", -34.62719),
                "lateralZeroPowerAcceleration": _var("double", -78.15554)}
    pidf = {"p": _var("double", 10.0), "i": _var("double", 3.0), "d": _var("double", 0.0), "f": _var("double", 0.0),
            "algorithm": _enum("PIDF", "com.qualcomm.robotcore.hardware.MotorControlAlgorithm",
                               ["LegacyPID", "PIDF"])}
    root = {
        "MecanumDrive": _var("custom", {"PARAMS": _var("custom", params)}),
        "Constants": _var("custom", {"driveConstants": _var("custom", drive_constants),
                                     "followerConstants": _var("custom", follower)}),
        "ArmConfig": _var("custom", {"VELOCITY_PIDF": _var("custom", pidf), "TARGET": _var("int", 300)}),
    }
    return _var("custom", root)


@dataclass
class Plant:
    """The emulated OpMode's motor, in encoder ticks: kS [V], kV [V·s/tick], kA [V·s²/tick]."""

    kS: float = 0.25
    kV: float = 0.6 * 2 * math.pi / 537.6
    kA: float = 0.04 * 2 * math.pi / 537.6
    ramp: float = 2.0  # V/s
    offset: float = 1.5  # V at the start
    period: float = 0.01  # loop period [s]
    cpr: float = 537.6
    duration: float = 8.0  # the OpMode ends by itself after this [s]

    def run(self, duration: float) -> list[tuple[float, float, float, float]]:
        """(t [s], V, position [ticks, whole], velocity [ticks/s]) every loop, 1 ms Euler steps."""
        v = x = 0.0
        out = []
        steps_per_loop = max(1, round(self.period / 1e-3))
        dt = self.period / steps_per_loop
        for k in range(int(duration / self.period) + 1):
            t = k * self.period
            volts = min(12.0, self.offset + self.ramp * t)
            out.append((t, volts, float(math.floor(x)), v))
            for _ in range(steps_per_loop):
                drive = volts - self.kV * v - (self.kS if v > 0 else 0.0)
                if v <= 0 and volts <= self.kS:
                    drive = 0.0
                v = max(0.0, v + drive / self.kA * dt)
                x += v * dt
        return out


@dataclass
class RobotFiles:
    """What the emulated robot serves: tuning files by type, FlightRecorder logs, motorlab logs."""

    tuning: dict[str, list[Path]] = field(default_factory=dict)
    logs: list[Path] = field(default_factory=list)
    motorlab: list[Path] = field(default_factory=list)


class EmulatedRobot:
    """HTTP routes and the Dashboard WebSocket of a robot, on 127.0.0.1 (ports 0: any free port).

    Parameters
    ----------
    files
        The files served.
    http_port, dashboard_port
        Ports (0 picks free ones; see :attr:`http_port`, :attr:`dashboard_port` after :meth:`start`).
    road_runner, motorlab_handler, dashboard
        Which services the robot has.
    dashboard_version
        The FTC Dashboard version played (one of :data:`DASHBOARD_VERSIONS`; 0.6.0 by default).
    enabled
        False: the Dashboard is disabled on the robot (its menu's "Disable Dashboard").
    read_timeout
        NanoHTTPD's socket read timeout [s] (5 s, :data:`SOCKET_READ_TIMEOUT`; shorter only in tests).
    stop_ignored
        True: an OpMode that does not stop when asked (a loop that never checks ``isStopRequested``).
    log_folder
        False: the robot has no ``/sdcard/RoadRunner/logs`` folder (``/logs`` then fails, see below);
        ``logs_failure`` says how the failure reaches the client ("closed": NanoHTTPD drops the
        connection, "500": a server error answer).
    drop_after
        Cut every download after this many bytes (a dropped Wi-Fi), or None.
    lifetime, max_requests
        The emulator stops by itself after this many seconds, or HTTP requests + WebSocket messages.
    """

    def __init__(self, files: RobotFiles | None = None, *, http_port: int = 0, dashboard_port: int = 0,
                 road_runner: bool = True, motorlab_handler: bool = True, dashboard: bool = True,
                 dashboard_version: str = "0.6.0", enabled: bool = True,
                 read_timeout: float = SOCKET_READ_TIMEOUT, stop_ignored: bool = False,
                 log_folder: bool = True, logs_failure: str = "closed",
                 drop_after: int | None = None, lifetime: float = 120.0, max_requests: int = 20000,
                 plant: Plant | None = None, opmodes: list[OpModeSpec] | None = None,
                 config_tree: dict[str, Any] | None = None) -> None:
        self.files = files or RobotFiles()
        self.road_runner, self.motorlab_handler, self.has_dashboard = road_runner, motorlab_handler, dashboard
        self.version, self._v = dashboard_version, version_tuple(dashboard_version)
        self.enabled, self.read_timeout, self.stop_ignored = enabled, float(read_timeout), stop_ignored
        self.log_folder, self.logs_failure = log_folder, logs_failure
        self.drop_after, self.lifetime, self.max_requests = drop_after, lifetime, max_requests
        self.plant = plant or Plant()
        self.opmodes = list(opmodes or OPMODES)
        self.config = config_tree or default_config_tree()
        self.baseline = copy.deepcopy(self.config)
        self.received: list[dict[str, Any]] = []  # every Dashboard message, in order
        self.http_requests: list[tuple[str, str]] = []  # (client address, path)
        self.dropped: list[str] = []  # why each dropped Dashboard client was dropped
        self.active, self.status = STOP_TAG, "INIT"
        self.battery = 12.8
        self.errors: list[str] = []
        self._lock = threading.RLock()
        self._clients: list[Any] = []
        self._count = 0
        self._stopped = threading.Event()
        self._run_id = 0
        self._run_started = 0.0
        self._http_port, self._dash_port = http_port, dashboard_port
        self._threads: list[threading.Thread] = []
        self._http: ThreadingHTTPServer | None = None
        self._ws: Any = None
        self._scratch: Path | None = None
        self.external_opmode: Any = None  # an OpMode process instead of the plant: motorlab.robot.emulator_jvm

    # ---- life cycle -------------------------------------------------------------------------------
    @property
    def http_port(self) -> int:
        return self._http.server_address[1] if self._http else self._http_port

    @property
    def dashboard_port(self) -> int:
        return self._ws.socket.getsockname()[1] if self._ws else self._dash_port

    def start(self) -> EmulatedRobot:
        self._http = ThreadingHTTPServer((LOOPBACK, self._http_port), _handler_class(self))
        self._http.daemon_threads = True
        self._spawn(self._http.serve_forever, "emulator-http")
        if self.has_dashboard:
            from websockets.sync.server import serve

            self._ws = serve(self._ws_client, LOOPBACK, self._dash_port, compression=None, ping_interval=None)
            self._spawn(self._ws.serve_forever, "emulator-dashboard")
        self._spawn(self._watchdog, "emulator-watchdog")
        return self

    def _spawn(self, target: Any, name: str) -> None:
        thread = threading.Thread(target=target, name=name, daemon=True)
        thread.start()
        self._threads.append(thread)

    def _watchdog(self) -> None:
        self._stopped.wait(self.lifetime)
        self.stop()

    def count(self) -> bool:
        """Count one request or message; False (and stop) past the limit."""
        with self._lock:
            self._count += 1
            over = self._count > self.max_requests
        if over:
            threading.Thread(target=self.stop, daemon=True).start()
        return not over

    def stop(self) -> None:
        """Stop every server and the running OpMode; idempotent, from any thread."""
        self._stopped.set()
        with self._lock:
            self._run_id += 1
            ws, http_server = self._ws, self._http
            self._ws = self._http = None
        if ws is not None:
            ws.shutdown()
        if http_server is not None:
            http_server.shutdown()
            http_server.server_close()
        for thread in self._threads:
            if thread is not threading.current_thread():
                thread.join(timeout=2.0)
        if self._scratch is not None:
            import shutil

            shutil.rmtree(self._scratch, ignore_errors=True)

    def __enter__(self) -> EmulatedRobot:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    # ---- Dashboard --------------------------------------------------------------------------------
    def robot_status(self) -> dict[str, Any]:
        """``RobotStatus`` as Gson writes it (DashboardCore/…/RobotStatus.java at the tag): ``batteryVoltage``
        exists from v0.4.14 (v0.4.14:…/RobotStatus.java:23; absent at v0.4.13), the largest hub input voltage
        (v0.4.16:FtcDashboard/…/FtcDashboard.java:1192-1212); ``enabled`` is ``core.enabled``."""
        with self._lock:
            status: dict[str, Any] = {"enabled": self.enabled, "available": True, "activeOpMode": self.active,
                                      "activeOpModeStatus": self.status, "warningMessage": "", "errorMessage": ""}
            if self._v >= (0, 4, 14):
                status["batteryVoltage"] = self.battery
            return status

    def op_mode_list_message(self) -> dict[str, Any]:
        """``RECEIVE_OP_MODE_LIST`` at this version: names sorted (``List<String> opModeList``,
        v0.5.0:DashboardCore/…/message/redux/ReceiveOpModeList.java:8; sorted at v0.5.0:FtcDashboard/…/
        FtcDashboard.java:275), or ``OpModeInfo`` {name, group} sorted by group then name, ignoring case
        (v0.5.1:…/ReceiveOpModeList.java:9, v0.6.0:FtcDashboard/…/FtcDashboard.java:295-301)."""
        if self._v < (0, 5, 1):
            return {"type": "RECEIVE_OP_MODE_LIST", "opModeList": sorted(m.name for m in self.opmodes)}
        infos = sorted(self.opmodes, key=lambda m: (m.group.lower(), m.name.lower()))
        return {"type": "RECEIVE_OP_MODE_LIST", "opModeInfoList": [{"name": m.name, "group": m.group} for m in infos]}

    def _send(self, conn: Any, message: dict[str, Any]) -> None:
        with contextlib.suppress(Exception):
            conn.send(json.dumps(message))

    def broadcast(self, message: dict[str, Any]) -> None:
        with self._lock:
            clients = list(self._clients)
        for conn in clients:
            self._send(conn, message)

    def _on_open(self, conn: Any) -> None:
        """What a new client receives (v0.6.0:DashboardCore/…/DashboardCore.java:114-127, FtcDashboard.java:
        1013-1043): the config tree; the baseline from v0.6.0 only (v0.6.0:…/DashboardCore.java:120-122,
        absent at v0.5.1); the OpMode list; the hardware configurations from v0.5.0 (v0.5.0:FtcDashboard/…/
        FtcDashboard.java:781-787). Sent whether the Dashboard is enabled or not (``onOpen`` has no check)."""
        with self._lock:
            self._send(conn, {"type": "RECEIVE_CONFIG", "configRoot": self.config})
            if self._v >= (0, 6, 0):
                self._send(conn, {"type": "RECEIVE_CONFIG_BASELINE", "configBaseline": self.baseline})
            self._send(conn, self.op_mode_list_message())
            if self._v >= (0, 6, 0):  # v0.6.0:…/message/redux/ReceiveHardwareConfigList.java:10-11, HardwareConfig.java
                self._send(conn, {"type": "RECEIVE_HARDWARE_CONFIG_LIST", "currentHardwareConfig": "robot",
                                  "hardwareConfigs": [{"name": "robot", "xmlContent": "<Robot/>", "readOnly": False}]})
            elif self._v >= (0, 4, 17):  # v0.4.17, v0.5.0:…/message/redux/ReceiveHardwareConfigList.java:9-10
                self._send(conn, {"type": "RECEIVE_HARDWARE_CONFIG_LIST", "hardwareConfigList": ["robot"],
                                  "currentHardwareConfig": "robot"})
            self._clients.append(conn)

    def _ws_client(self, conn: Any) -> None:
        self._on_open(conn)
        last_frame = time.monotonic()
        try:
            while not self._stopped.is_set():
                try:
                    frame = conn.recv(timeout=0.02)
                except TimeoutError:
                    if time.monotonic() - last_frame > self.read_timeout:
                        # NanoHTTPD's socket timeout (NanoHTTPD.java:1771) throws in WebSocketFrame.read;
                        # readWebsocket's catch and finally close the streams: no close frame
                        # (nanohttpd-project-2.3.1:websocket/src/main/java/fi/iki/elonen/NanoWSD.java:245-260, 143-160).
                        self._drop(conn, f"no frame for {self.read_timeout:g} s (NanoHTTPD's read timeout)")
                        return
                    continue
                last_frame = time.monotonic()
                if not self.count():
                    return
                if not self._on_message(conn, frame):
                    return
        except Exception:
            return
        finally:
            with self._lock:
                if conn in self._clients:
                    self._clients.remove(conn)

    def _drop(self, conn: Any, why: str) -> None:
        """Close the TCP connection without a WebSocket close frame, as NanoWSD's ``doClose`` does
        (it closes the socket's streams only: NanoWSD.java:143-160)."""
        import socket

        with self._lock:
            self.dropped.append(why)
            if conn in self._clients:
                self._clients.remove(conn)
        with contextlib.suppress(OSError):
            conn.socket.shutdown(socket.SHUT_RDWR)
        with contextlib.suppress(OSError):
            conn.socket.close()

    def _on_message(self, conn: Any, frame: str | bytes) -> bool:
        """One frame, as ``DashWebSocket.onMessage`` then ``DashboardCore``'s handler treat it; False when
        the connection was dropped."""
        try:
            message = json.loads(frame)
        except ValueError:
            # Gson's JsonSyntaxException is unchecked: NanoWSD's readWebsocket does not catch it, its
            # finally closes the socket (v0.4.16:FtcDashboard/…/FtcDashboard.java:602; NanoWSD.java:245-260).
            self._drop(conn, "a frame that is not JSON")
            return False
        kind = message.get("type") if isinstance(message, dict) else None
        known = _TYPES_06 if self._v >= (0, 6, 0) else _TYPES_05 if self._v >= (0, 4, 17) else _TYPES_04
        if kind not in known:
            # MessageDeserializer returns null for a type the enum lacks (v0.4.16:DashboardCore/…/message/
            # MessageDeserializer.java:20-24); DashboardCore's handler then throws a NullPointerException on
            # message.getType() (v0.4.16:…/DashboardCore.java:124 when disabled, :128 when enabled), which
            # NanoWSD does not catch: the socket is closed (NanoWSD.java:245-260).
            self._drop(conn, f"an unknown message type {kind!r} (Dashboard {self.version})")
            return False
        with self._lock:
            self.received.append(message)
        if not self.enabled and kind != "GET_ROBOT_STATUS":
            return True  # "Swallow any messages when the server is disabled" (v0.4.16:…/DashboardCore.java:123-126)
        if kind == "GET_ROBOT_STATUS":  # v0.4.16:FtcDashboard/…/FtcDashboard.java:609-611
            self._send(conn, {"type": "RECEIVE_ROBOT_STATUS", "status": self.robot_status()})
        elif kind == "GET_CONFIG":  # v0.4.16:…/DashboardCore.java:129-134
            with self._lock:
                self._send(conn, {"type": "RECEIVE_CONFIG", "configRoot": self.config})
        elif kind == "GET_CONFIG_BASELINE":  # v0.6.0:…/DashboardCore.java:150-155
            with self._lock:
                self._send(conn, {"type": "RECEIVE_CONFIG_BASELINE", "configBaseline": self.baseline})
        elif kind == "SAVE_CONFIG":  # v0.4.16:…/DashboardCore.java:135-144, then updateConfig to all (:211-215)
            with self._lock:
                self._update(self.config, message.get("configDiff") or {}, "")
                tree = copy.deepcopy(self.config)
            self.broadcast({"type": "RECEIVE_CONFIG", "configRoot": tree})
        elif kind == "INIT_OP_MODE":  # v0.4.16:FtcDashboard/…/FtcDashboard.java:613-617 → onOpModePreInit (:1233-1242)
            self._init(str(message.get("opModeName")))
        elif kind == "START_OP_MODE":  # :618-621 → onOpModePreStart (:1245-1250)
            self._start()
        elif kind == "STOP_OP_MODE":  # :622-625, eventLoop.requestOpModeStop → onOpModePostStop (:1253-1257)
            self._request_stop()
        return True

    def _spec(self, name: str) -> OpModeSpec | None:
        return next((m for m in self.opmodes if m.name == name), None)

    def _init(self, name: str) -> None:
        with self._lock:
            if self._spec(name) is None:
                return
            self._run_id += 1
            self.active, self.status = name, "INIT"
        self.broadcast({"type": "RECEIVE_TELEMETRY", "telemetry": []})  # clearTelemetry (DashboardCore.java:184-190)

    def _start(self) -> None:
        with self._lock:
            spec = self._spec(self.active)
            if spec is None or self.status != "INIT":
                return
            self.status = "RUNNING"
            self._run_id += 1
            self._run_started = time.monotonic()
            behaviour = getattr(self, self.BEHAVIOURS[spec.behaviour])
            threading.Thread(target=behaviour, args=(self._run_id,), daemon=True).start()

    def _request_stop(self) -> None:
        """The OpMode's loop ends on the event loop's next turn; when ``runOpMode`` returns (ForwardRampLogger
        first saves its file: Tuning.kt:399-403), ``onOpModePostStop`` (status STOPPED), then the SDK inits
        its default OpMode (``onOpModePreInit``: ``$Stop$Robot$``, INIT)."""
        with self._lock:
            if self.stop_ignored and self.active != STOP_TAG and self.status == "RUNNING":
                return
            spec = self._spec(self.active)
            saves = spec is not None and self.status == "RUNNING" and spec.behaviour == "forward_ramp_logger"
            self._run_id += 1
            run = self._run_id
            seconds = time.monotonic() - self._run_started

        def finish() -> None:
            if saves:
                self._save_ramp(seconds)
            with self._lock:
                if self._run_id == run and self.active != STOP_TAG:
                    self.status = "STOPPED"
            time.sleep(0.005)
            with self._lock:
                if self._run_id == run:
                    self.active, self.status = STOP_TAG, "INIT"

        threading.Thread(target=finish, daemon=True).start()

    def _ended(self, run: int) -> None:
        """The OpMode returned by itself: STOPPED, then the default OpMode."""
        with self._lock:
            if self._run_id == run:
                self._run_id += 1
                self.active, self.status = STOP_TAG, "INIT"

    def _running(self, run: int) -> bool:
        with self._lock:
            return self._run_id == run and not self._stopped.is_set()

    def _packets(self, packets: list[dict[str, Any]]) -> None:
        """Send a batch of telemetry, unless disabled (``sendTelemetryPacket`` returns at once:
        v0.4.16:…/DashboardCore.java:161-163)."""
        if self.enabled and packets:
            self.broadcast({"type": "RECEIVE_TELEMETRY", "telemetry": packets})

    @staticmethod
    def packet(stamp_ms: int, data: dict[str, str], log: list[str] | None = None) -> dict[str, Any]:
        """A ``TelemetryPacket`` as Gson writes it (v0.4.16:DashboardCore/…/telemetry/TelemetryPacket.java:
        15-19; ``data`` a SortedMap of strings, :54-56)."""
        return {"timestamp": stamp_ms, "data": dict(sorted(data.items())), "log": log or [],
                "field": {"ops": []}, "fieldOverlay": {"ops": []}}

    # ---- OpMode behaviours (one method per OPMODES behaviour) ------------------------------------
    BEHAVIOURS: ClassVar[dict[str, str]] = {
        "quasistatic_ramp": "_run_quasistatic_ramp",
        "forward_ramp_logger": "_run_until_stop",
        "manual_feedforward_tuner": "_run_manual_feedforward_tuner",
        "until_stop": "_run_until_stop",
        "toggle_dashboard": "_run_toggle_dashboard",
    }

    def _run_quasistatic_ramp(self, run: int) -> None:
        """motorlab's ramp: a packet per loop, sent in batches every 100 ms, until stopped or done."""
        external = self.external_opmode  # motorlab.robot.emulator_jvm: forwards the process's packets until STOP
        if external is not None:
            external(self.broadcast, lambda: self._running(run))
            self._ended(run)
            return
        samples = self.plant.run(min(self.lifetime, self.plant.duration))
        epoch = int(time.time() * 1000)
        start = time.monotonic()
        sent = 0
        while sent < len(samples):
            time.sleep(0.1)  # DEFAULT_TELEMETRY_TRANSMISSION_INTERVAL (v0.4.16:…/DashboardCore.java:30)
            if not self._running(run):
                return
            now = time.monotonic() - start
            batch = []
            while sent < len(samples) and samples[sent][0] <= now:
                t, volts, x, v = samples[sent]
                batch.append(self.packet(epoch + round(t * 1000), {
                    "voltage": f"{volts:.4f}", "position": f"{x:.0f}", "velocity": f"{v:.3f}", "state": "ramping"}))
                sent += 1
            self._packets(batch)
        self._ended(run)

    def _run_until_stop(self, run: int) -> None:
        """An OpMode that sends nothing to the Dashboard and runs until STOP (Road Runner's
        ForwardRampLogger: ``while (opModeIsActive())``, Tuning.kt:370, and no telemetry)."""
        while self._running(run):
            time.sleep(0.02)

    def _run_manual_feedforward_tuner(self, run: int) -> None:
        """Road Runner's ManualFeedforwardTuner (road-runner-ftc Tuning.kt:519-618): until STOP
        (``while (!isStopRequested)``, :553), every loop ``mode``, ``v0``… (each forward encoder's velocity,
        :580) and ``vref`` (the profile's velocity, :594), through MultipleTelemetry; the profile goes
        DISTANCE = 64 in forward and back. The emulated drive is driven by the feedforward of the ``@Config``
        gains it has (:mod:`motorlab.robot.emulator_drive`): wrong gains track worse."""
        from motorlab.robot import emulator_drive

        rows = emulator_drive.packets(self, emulator_drive.NAME)
        assert rows is not None
        epoch = int(time.time() * 1000)
        start = time.monotonic()
        sent = 0
        while self._running(run):
            time.sleep(0.1)  # DEFAULT_TELEMETRY_TRANSMISSION_INTERVAL (v0.4.16:…/DashboardCore.java:30)
            now = time.monotonic() - start
            batch = []
            while sent < len(rows) and rows[sent][0] <= now:
                t, data = rows[sent]
                batch.append(self.packet(epoch + round(t * 1000), data))
                sent += 1
            self._packets(batch)

    def _run_toggle_dashboard(self, run: int) -> None:
        """"Enable/Disable Dashboard": on start, toggles (v0.4.16:FtcDashboard/…/FtcDashboard.java:958-968)."""
        with self._lock:
            self.enabled = not self.enabled
        self._ended(run)

    def _save_ramp(self, seconds: float) -> None:
        """ForwardRampLogger's file, written when it stops: ``<millis>.json`` (FileServing.kt:99-113)."""
        import tempfile

        from motorlab.rig.ftc import RampSettings, simulate_ramp

        with self._lock:
            if self._scratch is None:
                self._scratch = Path(tempfile.mkdtemp(prefix="motorlab-emulated-sdcard-"))
            folder = self._scratch / "forward-ramp"
            folder.mkdir(exist_ok=True)
            path = folder / f"{int(time.time() * 1000)}.json"
        simulate_ramp(path, kind="forward", settings=RampSettings(duration=max(0.5, min(seconds, 20.0))), seed=1)
        with self._lock:
            self.files.tuning.setdefault("forward-ramp", []).append(path)

    def _update(self, node: dict[str, Any], diff: dict[str, Any], path: str) -> None:
        """``CustomVariable.update``: every leaf the diff names takes the diff's value."""
        if diff.get("__type") == "custom":
            for name, child in (diff.get("__value") or {}).items():
                mine = (node.get("__value") or {}).get(name)
                if mine is None:  # the real server throws a NullPointerException here
                    self.errors.append(f"SAVE_CONFIG names {path}{name}, which the tree does not have")
                    continue
                self._update(mine, child, f"{path}{name}.")
        else:
            node["__value"] = diff.get("__value")

    # ---- HTTP -------------------------------------------------------------------------------------
    def listing_html(self) -> str:
        """Road Runner's ``/logs`` page, names written as they are, not escaped (road-runner-ftc 1f35428:
        RoadRunner/src/main/java/com/acmerobotics/roadrunner/ftc/FileServing.kt:150-168)."""
        parts = ["<!doctype html><html><head><title>Logs</title></head><body><ul>"]
        for f in sorted(self.files.logs, key=lambda p: p.stat().st_mtime, reverse=True):
            parts.append(f'<li><a href="/logs/download?file={f.name}" download="{f.name}">{f.name}</a> '
                         f"({f.stat().st_size} bytes)</li>")
        parts.append("</ul></body></html>")
        return "".join(parts)


class _Handler(BaseHTTPRequestHandler):
    """Road Runner's and motorlab's HTTP routes of the emulated robot (its robot set by :func:`_handler_class`)."""

    robot: EmulatedRobot
    protocol_version = "HTTP/1.1"
    server_version = "NanoHTTPD-emulated"

    def log_message(self, format: str, *args: Any) -> None:
        return

    def do_GET(self) -> None:
        if not self.robot.count():
            self.close_connection = True
            return
        # NanoHTTPD reads the request line with the platform's charset (new InputStreamReader without
        # one: NanoHTTPD.java:917), UTF-8 on Android; http.server decodes it as Latin-1.
        raw = self.path.encode("iso-8859-1").decode("utf-8", "replace")
        self.robot.http_requests.append((self.client_address[0], raw))
        path, _, query = raw.partition("?")  # the query after the first "?" (NanoHTTPD.java:681-684)
        path = urllib.parse.unquote(path)  # decodePercent(uri) (NanoHTTPD.java:684)
        if self.robot.road_runner and path.startswith("/tuning/"):
            self._tuning(path)
        elif self.robot.road_runner and path == "/logs":
            if not self.robot.log_folder:
                self._handler_threw()  # LOG_ROOT.listFiles()!! on a self.robot without the folder (FileServing.kt:153)
                return
            page = self.robot.listing_html()
            ascii_only = page.isascii()  # NanoHTTPD switches to UTF-8 when ASCII cannot encode it (:2199-2203)
            self._fixed(200, "text/html" if ascii_only else "text/html; charset=UTF-8", page.encode())
        elif self.robot.road_runner and path == "/logs/download":
            self._rr_download(query)
        elif self.robot.motorlab_handler and path == "/motorlab/logs":
            files = [{"name": f.name, "bytes": f.stat().st_size, "modified_ms": int(f.stat().st_mtime * 1000)}
                     for f in sorted(self.robot.files.motorlab, key=lambda p: p.stat().st_mtime, reverse=True)]
            body = json.dumps({"folder": "/sdcard/FIRST/motorlab", "files": files}).encode()
            self._fixed(200, "application/json", body)
        elif self.robot.motorlab_handler and path == "/motorlab/logs/download":
            name = urllib.parse.parse_qs(query).get("file", [""])[0]  # getParameters(): decoded (:839-850)
            match = [f for f in self.robot.files.motorlab if f.name == name]
            if not match:
                self._fixed(404, "text/plain", f"no log named {name}".encode())
            else:
                self._fixed(200, "text/plain", match[0].read_bytes(), drop=True)
        else:
            self._fixed(404, "text/plain", b"")

    def _handler_threw(self) -> None:
        """A handler that throws: NanoHTTPD catches no RuntimeException in ``HTTPSession.execute``
        (NanoHTTPD.java:953-985); ``ClientHandler.run`` logs it and closes the socket (:184-200), so the
        client gets no answer. ``logs_failure="500"`` plays a server that answers 500 instead."""
        if self.robot.logs_failure == "500":
            self._fixed(500, "text/plain", b"SERVER INTERNAL ERROR: java.lang.NullPointerException")
            return
        self.close_connection = True
        with contextlib.suppress(OSError):
            self.connection.shutdown(2)

    def _tuning(self, path: str) -> None:
        parts = path.split("/")
        if len(parts) != 4 or parts[2] not in TUNING_TYPES:
            self._fixed(404, "text/plain", b"")
            return
        files = self.robot.files.tuning.get(parts[2], [])
        if parts[3] == "latest.json":
            if not files:
                self._fixed(404, "text/plain", b"")
                return
            newest = max(files, key=lambda p: p.stat().st_mtime)
            self._chunked("application/json", newest.read_bytes(), {"X-Filename": newest.name})
            return
        match = [f for f in files if f.name == parts[3]]
        if match:
            self._chunked("application/json", match[0].read_bytes(), {})
        else:
            self._fixed(404, "text/plain", b"")

    def _rr_download(self, query: str) -> None:
        """Road Runner's download route (FileServing.kt:171-189): the raw query (``queryParameterString``,
        not URL-decoded: NanoHTTPD.java:839) split on "&" then "=" (Kotlin's split, trailing empty parts
        dropped), ``File(LOG_ROOT, parts[1])``."""
        pairs = query.split("&")
        while pairs and not pairs[-1]:
            pairs.pop()
        if len(pairs) != 1:
            self._fixed(400, "text/plain", f"expected one query parameter, got {len(pairs)}".encode())
            return
        parts = pairs[0].split("=")
        while parts and not parts[-1]:
            parts.pop()
        if not parts or parts[0] != "file":
            got = parts[0] if parts else ""
            self._fixed(400, "text/plain", f"expected file query parameter, got {got}".encode())
            return
        if len(parts) < 2:
            self._handler_threw()  # parts[1]: ArrayIndexOutOfBoundsException
            return
        match = [f for f in self.robot.files.logs if f.name == parts[1]]
        if not match:
            self._fixed(404, "text/plain", f"file /sdcard/RoadRunner/logs/{parts[1]} doesn't exist".encode())
            return
        self._chunked("application/json", match[0].read_bytes(), {})

    def _fixed(self, status: int, mime: str, body: bytes, *, drop: bool = False) -> None:
        self.send_response(status)
        self.send_header("Content-Type", mime)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Connection", "close")
        self.end_headers()
        cut = self.robot.drop_after if drop and self.robot.drop_after is not None else None
        self.wfile.write(body if cut is None else body[:cut])
        self.close_connection = True

    def _chunked(self, mime: str, body: bytes, headers: dict[str, str]) -> None:
        self.send_response(200)
        self.send_header("Content-Type", mime)
        self.send_header("Transfer-Encoding", "chunked")
        self.send_header("Connection", "close")
        for k, v in headers.items():
            self.send_header(k, v)
        self.end_headers()
        cut = self.robot.drop_after
        for start in range(0, len(body), 16384):
            chunk = body[start:start + 16384]
            if cut is not None and start + len(chunk) > cut:
                self.wfile.write(f"{len(chunk):x}\r\n".encode() + chunk[: max(0, cut - start)])
                self.wfile.flush()
                self.close_connection = True
                return  # connection closed mid-chunk
            self.wfile.write(f"{len(chunk):x}\r\n".encode() + chunk + b"\r\n")
        self.wfile.write(b"0\r\n\r\n")
        self.close_connection = True



def _handler_class(robot: EmulatedRobot) -> type[BaseHTTPRequestHandler]:
    return type("Handler", (_Handler,), {"robot": robot})
