"""The app's robot link (docs/robot.md, "In the app"): pull, record with a live view and Stop, send gains.

Routes (mounted by :func:`motorlab.ui.app.create_app`); fields named as the CLI's long options:

* ``POST /api/robot/pull`` (``host``, ``http-port``): :func:`motorlab.robot.pull.pull` into a folder the
  app keeps while it runs; the files with their proposed analysis and a URL to fetch each one
  (``GET /api/robot/files/<id>/<path>``), so the page adds them as if they had been dropped;
* ``GET /api/robot/opmodes`` (``host``, ``dashboard-port``): the OpModes and the robot's status;
* ``POST /api/robot/record/start`` (``host``, ``dashboard-port``, ``opmode``, ``seconds``, ``cpr``): starts
  the OpMode (this request is the person's Start); one recording at a time;
* ``GET /api/robot/record``: the recording's state, rows, keys and the latest points for the live plot;
* ``POST /api/robot/record/stop``: sends ``STOP_OP_MODE`` at once (the page's always-visible Stop): through
  the recording when one runs, else to the robot the form names (``host``, ``dashboard-port``); the one
  robot route that needs no token (a page left open across a restart of the app must still stop the robot);
* ``GET /api/robot/record/log``: the CSV, once stopped;
* a recording started with ``check`` = ``before`` or ``after`` is a verification run (Road Runner's
  ``ManualFeedforwardTuner``): the drive's gains on the robot are read first, and the run's tracking error
  (:mod:`motorlab.robot.tracking`) is kept under that label; ``GET /api/robot/checks`` gives both runs,
  their gains and a sentence comparing them;
* ``POST /api/robot/push/plan``, ``/apply``, ``/restore`` (``params`` uploaded, ``target``, ``cpr``,
  ``wheel-radius``, ``config``, ``confirm``, ``while-running``): old and new values; the write after the
  person's confirmation; the old values back. The old values are kept in the app's folder while it runs.

Errors are ``{"error": line}`` with 400 (the robot said no, or is not there: the same line as the CLI).
"""

from __future__ import annotations

import shutil
import tempfile
import threading
from datetime import UTC
from pathlib import Path
from typing import Any

from starlette.concurrency import run_in_threadpool
from starlette.datastructures import UploadFile
from starlette.requests import Request
from starlette.responses import FileResponse, JSONResponse, Response
from starlette.routing import Route

from motorlab.errors import MotorlabError
from motorlab.robot import DEFAULT_DASHBOARD_PORT, DEFAULT_HOST, DEFAULT_HTTP_PORT

#: Points of the live plot sent per request (the latest ones).
LIVE_POINTS = 500


class _Link:
    """The app's robot state: its folder, the pulls, and the one recording."""

    def __init__(self) -> None:
        self._folder: Path | None = None
        self.pulls = 0
        self.recorder: Any = None
        self.thread: threading.Thread | None = None
        self.outcome: dict[str, Any] = {}
        self.checks: dict[str, dict[str, Any]] = {}  # "before"/"after" -> a verification run
        self.lock = threading.Lock()

    @property
    def folder(self) -> Path:
        """The app's private folder for pulled files, the recorded log and push state (made at first use)."""
        if self._folder is None:
            self._folder = Path(tempfile.mkdtemp(prefix="motorlab-robot-"))
        return self._folder

    def close(self) -> None:
        if self.recorder is not None:
            self.recorder.stop("the app closed")
        if self._folder is not None:
            shutil.rmtree(self._folder, ignore_errors=True)


def _error(message: str, status: int = 400) -> JSONResponse:
    return JSONResponse({"error": " ".join(message.split())}, status_code=status)


def _port(value: Any, default: int) -> int:
    text = str(value or default).strip()
    if not text.isdigit() or not 0 < int(text) < 65536:
        raise MotorlabError(f"{text!r} is not a port number (1-65535)")
    return int(text)


def _host(value: Any) -> str:
    text = str(value or DEFAULT_HOST).strip()
    if not text or any(c in text for c in "/\\@ ?#"):
        raise MotorlabError(f"{text!r} is not a host name or address (give it like 192.168.43.1)")
    return text


def routes(link: _Link | None = None) -> list[Route]:
    """The robot link's routes, sharing one :class:`_Link`."""
    link = link or _Link()

    async def pull(request: Request) -> Response:
        from motorlab.robot.pull import pull as do_pull

        form = await request.form()
        try:
            host, port = _host(form.get("host")), _port(form.get("http-port"), DEFAULT_HTTP_PORT)
            with link.lock:
                link.pulls += 1
                pull_id = str(link.pulls)
            out = link.folder / "pull" / pull_id
            result = await run_in_threadpool(do_pull, host, out, http_port=port)
        except MotorlabError as exc:
            return _error(str(exc))
        answer = result.to_dict()
        for entry, f in zip(answer["files"], result.files, strict=True):
            rel = f.path.relative_to(out).as_posix()
            entry["path"] = rel
            entry["url"] = f"api/robot/files/{pull_id}/{rel}"
            entry["command"] = (f.command or "").replace(str(f.path), rel)
        answer["folder"] = f"pull {pull_id}"
        return JSONResponse(answer)

    async def files(request: Request) -> Response:
        base = (link.folder / "pull" / request.path_params["pull"]).resolve()
        target = (base / request.path_params["path"]).resolve()
        if not target.is_relative_to(base) or not target.is_file():
            return _error("no such pulled file", 404)
        return FileResponse(target, filename=target.name)

    async def opmodes(request: Request) -> Response:
        from motorlab.robot.dashboard import Dashboard

        def ask(host: str, port: int) -> dict[str, Any]:
            with Dashboard(host, port) as dash:
                return {"opmodes": dash.op_modes(), "status": dash.status()}

        try:
            q = request.query_params
            answer = await run_in_threadpool(ask, _host(q.get("host")),
                                             _port(q.get("dashboard-port"), DEFAULT_DASHBOARD_PORT))
        except MotorlabError as exc:
            return _error(str(exc))
        return JSONResponse(answer)

    return [
        Route("/api/robot/pull", pull, methods=["POST"]),
        Route("/api/robot/files/{pull}/{path:path}", files),
        Route("/api/robot/opmodes", opmodes),
        *_record_routes(link),
        *_push_routes(link),
    ]


def _send_stop(host: str, port: int) -> None:
    """``STOP_OP_MODE`` to the robot, confirmed by the status answer that follows it (the robot has read it)."""
    from motorlab.robot.dashboard import Dashboard

    with Dashboard(host, port) as dash:
        dash.stop_op_mode()
        dash.status()


def _record_routes(link: _Link) -> list[Route]:
    from motorlab.robot.record import Recorder, write_log

    async def start(request: Request) -> Response:
        form = await request.form()
        with link.lock:
            if link.thread is not None and link.thread.is_alive():
                return _error("a recording is running: stop it first", 409)
            check = str(form.get("check") or "")
            if check not in ("", *CHECKS):
                return _error(f"check must be {' or '.join(CHECKS)}, not {check!r}")
            try:
                seconds = float(str(form.get("seconds") or 30))
                cpr = float(str(form["cpr"])) if form.get("cpr") else None
                recorder = Recorder(_host(form.get("host")), _port(form.get("dashboard-port"), DEFAULT_DASHBOARD_PORT),
                                    str(form.get("opmode") or ""), seconds=seconds)
            except (MotorlabError, ValueError) as exc:
                return _error(str(exc))
            outcome: dict[str, Any] = {"cpr": cpr, "host": f"{recorder.host}:{recorder.port}", "check": check}

            def work() -> None:
                gains: dict[str, float] = {}
                try:
                    if check:  # the gains the check runs with, read before anything moves
                        gains = _drive_gains(recorder.host, recorder.port)
                    recorder.run()
                except MotorlabError as exc:
                    outcome["error"] = " ".join(str(exc).split())
                except Exception as exc:  # a link that broke in a way of its own: say so, keep what was recorded
                    outcome["error"] = f"the link to the robot ended with {type(exc).__name__}: {exc}"
                try:  # what was recorded is kept even when the link ended badly
                    log = link.folder / "record" / (f"check-{check}.csv" if check else "run.csv")
                    log.parent.mkdir(parents=True, exist_ok=True)
                    outcome["summary"] = write_log(recorder.data, log, host=outcome["host"], cpr=cpr)
                    outcome["log"] = log
                    if check and "error" not in outcome:
                        link.checks[check] = _check(recorder.data, gains, seconds)
                except (MotorlabError, OSError) as exc:
                    outcome.setdefault("error", " ".join(str(exc).split()))

            link.recorder, link.outcome = recorder, outcome
            link.thread = threading.Thread(target=work, name="motorlab-app-record", daemon=True)
            link.thread.start()
        return JSONResponse({"started": True})

    async def state(request: Request) -> Response:
        recorder = link.recorder
        if recorder is None:
            return JSONResponse({"state": "idle"})
        data = recorder.data
        with recorder._lock:
            rows = data.rows[-LIVE_POINTS:]
            keys = data.numeric_keys()
            count = len(data.rows)
        t0 = data.rows[0][0] if data.rows else 0
        series = {k: [_number(v.get(k)) for _, _, v in rows] for k in keys}
        running = link.thread is not None and link.thread.is_alive()
        # The recorder says "stopped" before its thread has written the log: until then the page keeps asking
        now = ("saving the log" if recorder.state == "stopped" else recorder.state) if running else "stopped"
        answer: dict[str, Any] = {"state": now, "opmode": data.opmode,
                                  "rows": count, "keys": keys, "time": [(s - t0) / 1000 for s, _, _ in rows],
                                  "series": series, "stop_reason": data.stop_reason,
                                  "still_running": data.still_running}
        if not running:
            answer.update({k: v for k, v in link.outcome.items() if k in ("summary", "error", "check")})
            answer["log"] = "api/robot/record/log" if "log" in link.outcome else None
        return JSONResponse(answer)

    async def stop(request: Request) -> Response:
        """Stop the app's recording at once; with none running, send STOP_OP_MODE to the robot named in the form
        (an OpMode started elsewhere, or left running by a link that broke: Stop works whatever started it)."""
        if link.thread is not None and link.thread.is_alive():
            link.recorder.stop("stopped from the app")
            return JSONResponse({"stopped": True})
        form = await request.form()
        if not form.get("host"):
            return JSONResponse({"stopped": True})
        try:
            await run_in_threadpool(_send_stop, _host(form.get("host")),
                                    _port(form.get("dashboard-port"), DEFAULT_DASHBOARD_PORT))
        except MotorlabError as exc:
            return _error(f"{exc}: press STOP on the Driver Station")
        return JSONResponse({"stopped": True, "sent": "STOP_OP_MODE"})

    async def log(request: Request) -> Response:
        path = link.outcome.get("log")
        if path is None or not Path(path).is_file():
            return _error("no recorded log yet", 404)
        return FileResponse(path, filename="run.csv", media_type="text/csv")

    async def checks(request: Request) -> Response:
        return JSONResponse({**{k: link.checks.get(k) for k in CHECKS}, "words": check_words(link.checks)})

    return [Route("/api/robot/record/start", start, methods=["POST"]), Route("/api/robot/record", state),
            Route("/api/robot/record/stop", stop, methods=["POST"]), Route("/api/robot/record/log", log),
            Route("/api/robot/checks", checks)]


#: The labels of the verification runs, in the order they are made.
CHECKS = ("before", "after")


def _drive_gains(host: str, port: int) -> dict[str, float]:
    """The drive's kS [V], kV [V·s/tick], kA [V·s²/tick] and inPerTick on the robot now (Road Runner's PARAMS)."""
    from motorlab.robot.config import leaves, target_paths
    from motorlab.robot.dashboard import Dashboard

    with Dashboard(host, port) as dash:
        tree = dash.config()
    paths = target_paths(tree, "roadrunner", {"kS": 0.0, "kV": 0.0, "kA": 0.0})
    flat = leaves(tree)
    paths["inPerTick"] = paths["kS"].rsplit(".", 1)[0] + ".inPerTick"
    return {g: float(flat[p][1]) for g, p in paths.items() if p in flat}


def _check(data: Any, gains: dict[str, float], seconds: float) -> dict[str, Any]:
    """A verification run as the page shows it: the curves, the errors, and the gains it ran with."""
    from datetime import datetime

    from motorlab.robot.tracking import tracking

    unit = "ticks/s" if gains.get("inPerTick", 1.0) == 1.0 else "in/s"  # Road Runner's distance unit per second
    return {**tracking(data, unit=unit).to_dict(), "gains": gains, "opmode": data.opmode, "seconds": seconds,
            "stop_reason": data.stop_reason, "recorded": datetime.now(UTC).isoformat(timespec="seconds")}


def _gain_words(gains: dict[str, float]) -> str:
    units = {"kS": "V", "kV": "V·s/tick", "kA": "V·s²/tick"}
    return ", ".join(f"{g} {gains[g]:.4g} {u}" for g, u in units.items() if g in gains)


def check_words(checks: dict[str, dict[str, Any]]) -> str:
    """One sentence per verification run, and how the second compares with the first."""
    said = [f"{label.capitalize()}: RMS tracking error {c['rms']:.3g} {c['unit']} (largest {c['worst']:.3g} "
            f"{c['unit']}) with {_gain_words(c['gains'])}." for label in CHECKS if (c := checks.get(label))]
    before, after = checks.get("before"), checks.get("after")
    if before and after and before["unit"] == after["unit"] and after["rms"] > 0:
        ratio = before["rms"] / after["rms"]
        said.append(f"The new gains track {ratio:.3g} times better." if ratio >= 1 else
                    f"The new gains track {1 / ratio:.3g} times worse: put the old values back and check the fit.")
    return " ".join(said)


def _number(text: str | None) -> float | None:
    try:
        return float(text) if text is not None else None
    except ValueError:
        return None


def _push_routes(link: _Link) -> list[Route]:
    from motorlab.robot.dashboard import Dashboard
    from motorlab.robot.push import LIFETIME, apply, prepare, restore, target_values

    async def _read(request: Request) -> tuple[dict[str, Any], Path | None]:
        form = await request.form()
        fields: dict[str, Any] = {}
        params = None
        for key, item in form.multi_items():
            if isinstance(item, UploadFile):
                params = link.folder / "push" / "fit.json"
                params.parent.mkdir(parents=True, exist_ok=True)
                params.write_bytes(await item.read())
            else:
                fields.setdefault(key, []).append(item)
        await form.close()
        return {k: v[0] if k != "config" else v for k, v in fields.items()}, params

    def _plan(fields: dict[str, Any], params: Path | None, write: bool) -> dict[str, Any]:
        from motorlab.units import parse_quantity

        if params is None:
            raise MotorlabError("give the fit (a motorlab analyze --json file) as 'params'")
        target = str(fields.get("target") or "roadrunner")
        cpr = float(fields["cpr"]) if fields.get("cpr") else None
        radius = (parse_quantity(fields["wheel-radius"], "m", name="wheel radius") if fields.get("wheel-radius")
                  else None)
        gains = target_values([str(params)], target, cpr=cpr, wheel_radius=radius)
        host, port = _host(fields.get("host")), _port(fields.get("dashboard-port"), DEFAULT_DASHBOARD_PORT)
        with Dashboard(host, port) as dash:
            plan = prepare(dash, target, gains, fields.get("config") or None)
            answer = {**plan.to_dict(), "notes": plan.notes + gains.notes, "lifetime": LIFETIME}
            if write:
                if fields.get("confirm") != "yes":
                    raise MotorlabError("nothing written: the page did not confirm")
                running_ok = fields.get("while-running") == "yes"
                if plan.running and not running_ok:
                    raise MotorlabError(f"an OpMode is active on the robot ({plan.running}): stop it first, or "
                                        "confirm writing while it runs")
                apply(dash, plan, link.folder / "push" / "state.json", while_running=running_ok)
                answer["verified"] = True
        return answer

    async def plan(request: Request) -> Response:
        fields, params = await _read(request)
        try:
            return JSONResponse(await run_in_threadpool(_plan, fields, params, False))
        except (MotorlabError, OSError, ValueError) as exc:
            return _error(str(exc))

    async def write(request: Request) -> Response:
        fields, params = await _read(request)
        try:
            return JSONResponse(await run_in_threadpool(_plan, fields, params, True))
        except (MotorlabError, OSError, ValueError) as exc:
            return _error(str(exc))

    async def undo(request: Request) -> Response:
        fields, _ = await _read(request)

        def work() -> list[dict[str, Any]]:
            host, port = _host(fields.get("host")), _port(fields.get("dashboard-port"), DEFAULT_DASHBOARD_PORT)
            with Dashboard(host, port) as dash:
                changes = restore(dash, link.folder / "push" / "state.json",
                                  while_running=fields.get("while-running") == "yes")
            return [c.to_dict() for c in changes]

        try:
            return JSONResponse({"restored": await run_in_threadpool(work)})
        except (MotorlabError, OSError) as exc:
            return _error(str(exc))

    return [Route("/api/robot/push/plan", plan, methods=["POST"]),
            Route("/api/robot/push/apply", write, methods=["POST"]),
            Route("/api/robot/push/restore", undo, methods=["POST"])]
