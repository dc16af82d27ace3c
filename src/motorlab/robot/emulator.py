"""An emulated FTC robot on 127.0.0.1: Road Runner's and motorlab's HTTP routes and FTC Dashboard's WebSocket.

Built from the projects' sources (see :mod:`motorlab.robot.pull` and :mod:`motorlab.robot.dashboard`
for the routes and messages), for the tests and for ``motorlab robot emulate``:

* HTTP (the robot controller's web server, port 8080 on a robot): ``/tuning/<type>/latest.json``
  (chunked, ``X-Filename``, 404 with an empty body when the type has no file), ``/tuning/<type>/<name>``,
  ``/logs`` (Road Runner's HTML list, newest first), ``/logs/download?file=`` (Road Runner's query
  parsing and its 400/404 answers), ``/motorlab/logs`` and ``/motorlab/logs/download?file=``
  (``MotorlabLogFiles.java``); ``drop_after`` cuts every download after that many bytes (a lost Wi-Fi);
* the Dashboard (port 8000 on a robot): on open ``RECEIVE_CONFIG``, ``RECEIVE_CONFIG_BASELINE``,
  ``RECEIVE_OP_MODE_LIST``; ``GET_ROBOT_STATUS``; ``INIT_OP_MODE``/``START_OP_MODE``/``STOP_OP_MODE``
  with the status the OpMode manager's notifications give (INIT, RUNNING, STOPPED, then the default
  OpMode ``$Stop$Robot$``); ``GET_CONFIG``; ``SAVE_CONFIG`` applied leaf by leaf; while an OpMode runs,
  telemetry packets every loop (10 ms) sent in batches every 100 ms.

The running OpMode is a drive motor obeying the feedforward model in encoder ticks,
V = kS·sgn(v) + kV·v + kA·a (:class:`Plant`), under a voltage ramp with an offset; its telemetry keys are
``voltage`` [V], ``position`` [ticks], ``velocity`` [ticks/s] and ``state`` (a word, not a number).

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
from typing import Any

from motorlab.robot.dashboard import STOP_TAG

LOOPBACK = "127.0.0.1"
TUNING_TYPES = ("forward-ramp", "lateral-ramp", "angular-ramp", "accel")


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
    drop_after
        Cut every download after this many bytes (a dropped Wi-Fi), or None.
    lifetime, max_requests
        The emulator stops by itself after this many seconds, or HTTP requests + WebSocket messages.
    """

    def __init__(self, files: RobotFiles | None = None, *, http_port: int = 0, dashboard_port: int = 0,
                 road_runner: bool = True, motorlab_handler: bool = True, dashboard: bool = True,
                 drop_after: int | None = None, lifetime: float = 120.0, max_requests: int = 20000,
                 plant: Plant | None = None, opmodes: list[dict[str, str]] | None = None,
                 config_tree: dict[str, Any] | None = None) -> None:
        self.files = files or RobotFiles()
        self.road_runner, self.motorlab_handler, self.has_dashboard = road_runner, motorlab_handler, dashboard
        self.drop_after, self.lifetime, self.max_requests = drop_after, lifetime, max_requests
        self.plant = plant or Plant()
        self.opmodes = opmodes or [{"name": "motorlab: quasistatic ramp", "group": "motorlab"},
                                   {"name": "ForwardRampLogger", "group": "RoadRunner"},
                                   {"name": "LocalizationTest", "group": "RoadRunner"},
                                   {"name": "ManualFeedforwardTuner", "group": "RoadRunner"}]
        self.config = config_tree or default_config_tree()
        self.baseline = copy.deepcopy(self.config)
        self.received: list[dict[str, Any]] = []  # every Dashboard message, in order
        self.http_requests: list[tuple[str, str]] = []  # (client address, path)
        self.active, self.status = STOP_TAG, "INIT"
        self.battery = 12.8
        self.errors: list[str] = []
        self._lock = threading.RLock()
        self._clients: list[Any] = []
        self._count = 0
        self._stopped = threading.Event()
        self._run_id = 0
        self._http_port, self._dash_port = http_port, dashboard_port
        self._threads: list[threading.Thread] = []
        self._http: ThreadingHTTPServer | None = None
        self._ws: Any = None

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

    def __enter__(self) -> EmulatedRobot:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    # ---- Dashboard --------------------------------------------------------------------------------
    def robot_status(self) -> dict[str, Any]:
        with self._lock:
            return {"enabled": True, "available": True, "activeOpMode": self.active,
                    "activeOpModeStatus": self.status, "warningMessage": "", "errorMessage": "",
                    "batteryVoltage": self.battery}

    def _send(self, conn: Any, message: dict[str, Any]) -> None:
        with contextlib.suppress(Exception):
            conn.send(json.dumps(message))

    def broadcast(self, message: dict[str, Any]) -> None:
        with self._lock:
            clients = list(self._clients)
        for conn in clients:
            self._send(conn, message)

    def _ws_client(self, conn: Any) -> None:
        with self._lock:
            self._send(conn, {"type": "RECEIVE_CONFIG", "configRoot": self.config})
            self._send(conn, {"type": "RECEIVE_CONFIG_BASELINE", "configBaseline": self.baseline})
            self._send(conn, {"type": "RECEIVE_OP_MODE_LIST", "opModeInfoList": self.opmodes})
            self._clients.append(conn)
        try:
            while not self._stopped.is_set():
                try:
                    frame = conn.recv(timeout=0.05)
                except TimeoutError:
                    continue
                if not self.count():
                    return
                self._on_message(conn, json.loads(frame))
        except Exception:
            return
        finally:
            with self._lock:
                if conn in self._clients:
                    self._clients.remove(conn)

    def _on_message(self, conn: Any, message: dict[str, Any]) -> None:
        kind = message.get("type")
        with self._lock:
            self.received.append(message)
        if kind == "GET_ROBOT_STATUS":
            self._send(conn, {"type": "RECEIVE_ROBOT_STATUS", "status": self.robot_status()})
        elif kind == "GET_CONFIG":
            with self._lock:
                self._send(conn, {"type": "RECEIVE_CONFIG", "configRoot": self.config})
        elif kind == "SAVE_CONFIG":
            with self._lock:
                self._update(self.config, message.get("configDiff") or {}, "")
                tree = copy.deepcopy(self.config)
            self.broadcast({"type": "RECEIVE_CONFIG", "configRoot": tree})
        elif kind == "INIT_OP_MODE":
            with self._lock:
                names = [m["name"] for m in self.opmodes]
                if message.get("opModeName") in names:
                    self._run_id += 1
                    self.active, self.status = message["opModeName"], "INIT"
            self.broadcast({"type": "RECEIVE_TELEMETRY", "telemetry": []})  # clearTelemetry on init
        elif kind == "START_OP_MODE":
            with self._lock:
                if self.active != STOP_TAG and self.status == "INIT":
                    self.status = "RUNNING"
                    self._run_id += 1
                    run = self._run_id
                    threading.Thread(target=self._telemetry, args=(run,), daemon=True).start()
        elif kind == "STOP_OP_MODE":
            with self._lock:
                self._run_id += 1
                self.active, self.status = STOP_TAG, "INIT"

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

    def _telemetry(self, run: int) -> None:
        """The running OpMode: a packet per loop, sent in batches every 100 ms, until stopped."""
        from motorlab.robot import emulator_drive  # the drive under ManualFeedforwardTuner (issue 32, item 7)

        samples = emulator_drive.packets(self, self.active) or [
            (t, {"voltage": f"{volts:.4f}", "position": f"{x:.0f}", "velocity": f"{v:.3f}", "state": "ramping"})
            for t, volts, x, v in self.plant.run(min(self.lifetime, self.plant.duration))]
        epoch = int(time.time() * 1000)
        start = time.monotonic()
        sent = 0
        while sent < len(samples):
            time.sleep(0.1)
            with self._lock:
                if self._run_id != run or self._stopped.is_set():
                    return
            now = time.monotonic() - start
            batch = []
            while sent < len(samples) and samples[sent][0] <= now:
                t, data = samples[sent]
                batch.append({"timestamp": epoch + round(t * 1000), "data": data,
                              "log": [], "field": {"ops": []}, "fieldOverlay": {"ops": []}})
                sent += 1
            self.broadcast({"type": "RECEIVE_TELEMETRY", "telemetry": batch})
        with self._lock:  # the OpMode ends by itself
            if self._run_id == run:
                self.active, self.status = STOP_TAG, "INIT"

    # ---- HTTP -------------------------------------------------------------------------------------
    def listing_html(self) -> str:
        """Road Runner's ``/logs`` page (FileServing.kt, LogFiles)."""
        parts = ["<!doctype html><html><head><title>Logs</title></head><body><ul>"]
        for f in sorted(self.files.logs, key=lambda p: p.stat().st_mtime, reverse=True):
            parts.append(f'<li><a href="/logs/download?file={f.name}" download="{f.name}">{f.name}</a> '
                         f"({f.stat().st_size} bytes)</li>")
        parts.append("</ul></body></html>")
        return "".join(parts)


def _handler_class(robot: EmulatedRobot) -> type[BaseHTTPRequestHandler]:
    class Handler(BaseHTTPRequestHandler):
        protocol_version = "HTTP/1.1"
        server_version = "NanoHTTPD-emulated"

        def log_message(self, format: str, *args: Any) -> None:
            return

        def do_GET(self) -> None:
            if not robot.count():
                self.close_connection = True
                return
            robot.http_requests.append((self.client_address[0], self.path))
            path, _, query = self.path.partition("?")
            if robot.road_runner and path.startswith("/tuning/"):
                self._tuning(path)
            elif robot.road_runner and path == "/logs":
                self._fixed(200, "text/html", robot.listing_html().encode())
            elif robot.road_runner and path == "/logs/download":
                self._rr_download(query)
            elif robot.motorlab_handler and path == "/motorlab/logs":
                files = [{"name": f.name, "bytes": f.stat().st_size, "modified_ms": int(f.stat().st_mtime * 1000)}
                         for f in sorted(robot.files.motorlab, key=lambda p: p.stat().st_mtime, reverse=True)]
                body = json.dumps({"folder": "/sdcard/FIRST/motorlab", "files": files}).encode()
                self._fixed(200, "application/json", body)
            elif robot.motorlab_handler and path == "/motorlab/logs/download":
                name = urllib.parse.parse_qs(query).get("file", [""])[0]
                match = [f for f in robot.files.motorlab if f.name == name]
                if not match:
                    self._fixed(404, "text/plain", f"no log named {name}".encode())
                else:
                    self._fixed(200, "text/plain", match[0].read_bytes(), drop=True)
            else:
                self._fixed(404, "text/plain", b"")

        def _tuning(self, path: str) -> None:
            parts = path.split("/")
            if len(parts) != 4 or parts[2] not in TUNING_TYPES:
                self._fixed(404, "text/plain", b"")
                return
            files = robot.files.tuning.get(parts[2], [])
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
            pairs = [p for p in query.split("&") if p]
            if len(pairs) != 1:
                self._fixed(400, "text/plain", f"expected one query parameter, got {len(pairs)}".encode())
                return
            key, _, name = pairs[0].partition("=")
            if key != "file":
                self._fixed(400, "text/plain", f"expected file query parameter, got {key}".encode())
                return
            match = [f for f in robot.files.logs if f.name == name]
            if not match:
                self._fixed(404, "text/plain", f"file /sdcard/RoadRunner/logs/{name} doesn't exist".encode())
                return
            self._chunked("application/json", match[0].read_bytes(), {})

        def _fixed(self, status: int, mime: str, body: bytes, *, drop: bool = False) -> None:
            self.send_response(status)
            self.send_header("Content-Type", mime)
            self.send_header("Content-Length", str(len(body)))
            self.send_header("Connection", "close")
            self.end_headers()
            cut = robot.drop_after if drop and robot.drop_after is not None else None
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
            cut = robot.drop_after
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

    return Handler
