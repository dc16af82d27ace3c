"""The ``motorlab ui`` web app: the page, its static files and the HTTP API (docs/ui.md).

``POST /api/analyze/<experiment>``, ``POST /api/tune`` and ``POST /api/characterize`` take a multipart
form whose fields are named as the CLI's long options and run the CLI itself
(:mod:`motorlab.ui.runner`): 200 with exactly what ``--json`` prints, or 4xx with
``{"error": "<the CLI's one-line message>"}``.
"""

from __future__ import annotations

import asyncio
import contextlib
import hmac
import json
import logging
import secrets
import time
from collections.abc import AsyncIterator, Awaitable, Callable, Coroutine, MutableMapping
from importlib import resources
from pathlib import Path
from typing import Any

from starlette.applications import Starlette
from starlette.datastructures import UploadFile
from starlette.exceptions import HTTPException
from starlette.requests import Request
from starlette.responses import FileResponse, JSONResponse, Response, StreamingResponse
from starlette.routing import Mount, Route
from starlette.staticfiles import StaticFiles

from motorlab.ui import robot, runner, schema, uploads

#: Options the page never passes on from a client (output paths, the number of processes: the app sets them).
_REFUSED_FIELDS = {"plot", "output", "o", "json", "emit-file", "processes"}

#: CLI exit code -> HTTP status.
_STATUS = {2: 400, 124: 422}

Scope = MutableMapping[str, Any]
ASGIApp = Callable[[Scope, Callable[[], Awaitable[Any]], Callable[[Any], Awaitable[None]]], Awaitable[None]]


#: The media type of a streamed answer (``Accept: application/x-ndjson``): one JSON object a line.
NDJSON = "application/x-ndjson"


def _error(message: str, status: int = 400) -> JSONResponse:
    return JSONResponse({"error": message}, status_code=status)


def _outcome_response(outcome: runner.Outcome, *, json_body: bool = True) -> Response:
    if outcome.code != 0:
        return _error(outcome.error_line(), _STATUS.get(outcome.code, 500))
    return Response(outcome.stdout, media_type="application/json" if json_body else "text/plain")


async def _save_form(request: Request, folder: Path) -> tuple[dict[str, list[str]], dict[str, list[str]]]:
    """Text fields and uploaded files (saved under ``folder``, sanitised names) of a multipart request."""
    try:
        form = await request.form(max_files=500, max_fields=200)
    except HTTPException as exc:  # starlette's own words for a body that is no form ("Invalid multipart data.")
        raise uploads.UploadError(f"the request is not a form the app can read: {exc.detail}") from exc
    values: dict[str, list[str]] = {}
    files: dict[str, list[str]] = {}
    try:
        for key, item in form.multi_items():
            if "\x00" in key or (isinstance(item, str) and "\x00" in item):
                # No command line can carry a NUL byte (the child process could not even be started).
                raise uploads.UploadError(f"form field {key.replace(chr(0), '?')!r}: contains a NUL byte")
            if isinstance(item, UploadFile):
                target = uploads.place(folder, item.filename or "upload")
                with open(target, "wb") as out:
                    while chunk := await item.read(1 << 20):
                        out.write(chunk)
                # Paths relative to the folder (the child's working folder): the CLI's messages and its
                # JSON's "sources" then name the file as the user named it, not a temporary path.
                if target.suffix.lower() == ".zip":
                    unpacked = uploads.unpack_zip(target, folder)
                    target.unlink()
                else:
                    unpacked = [target]
                files.setdefault(key, []).extend(str(p.relative_to(folder.resolve())) for p in unpacked)
            else:
                values.setdefault(key, []).append(item)
    finally:
        await form.close()
    return values, files


def _file_options(fields: list[dict[str, Any]], values: dict[str, list[str]], files: dict[str, list[str]]) -> None:
    """Put uploaded files of file options (``--params FILE.json``) into ``values``; refuse typed paths."""
    for f in fields:
        if f["kind"] != "file" or f["positional"]:
            continue
        if f["name"] in values:
            raise uploads.UploadError(f"--{f['name']}: upload the file (a part named {f['name']!r}), not a path")
        if f["name"] in files:
            values[f["name"]] = files[f["name"]]


async def _argv(request: Request, folder: Path, head: list[str], fields: list[dict[str, Any]]) -> list[str] | Response:
    """The command line a form asks for (uploads saved in ``folder``), or the error response."""
    try:
        values, files = await _save_form(request, folder)
        refused = sorted(set(values) & _REFUSED_FIELDS)
        if refused:
            return _error(f"--{refused[0]}: the app sets this option itself")
        _file_options(fields, values, files)
    except uploads.UploadError as exc:
        return _error(str(exc))
    return runner.build_argv(head, fields, values, files.get("file", []))


async def _until_disconnect(request: Request, work: Coroutine[Any, Any, runner.Outcome]) -> runner.Outcome | None:
    """``work``'s outcome, or None when the client went away first (``work`` is cancelled: its child ends)."""
    task = asyncio.ensure_future(work)

    async def disconnected() -> None:
        while (await request.receive())["type"] != "http.disconnect":
            pass

    watcher = asyncio.ensure_future(disconnected())
    try:
        await asyncio.wait({task, watcher}, return_when=asyncio.FIRST_COMPLETED)
    finally:
        watcher.cancel()
        if not task.done():
            task.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await asyncio.gather(task, watcher, return_exceptions=True)
    return None if task.cancelled() else task.result()


Finish = Callable[[runner.Outcome], Response]


def _line(obj: Any) -> bytes:
    return (json.dumps(obj, separators=(",", ":"), allow_nan=False) + "\n").encode()


def _as_line(response: Response) -> bytes:
    """The last line of a stream from the answer the request would get without streaming."""
    body = json.loads(bytes(response.body))
    if response.status_code == 200:
        return _line({"result": body})
    return _line({"error": body["error"], "status": response.status_code})


#: Looks, while a command runs, for an early part of its answer (a session's table before its report).
Peek = Callable[[], dict[str, Any] | None]


#: How often a streamed command's early answer is looked for [s] (a session's results table: a file's existence asked
#: for, a few microseconds; at 0.25 s the table waited 0.13 s on average after it was written).
PEEK_INTERVAL = 0.04


async def _ndjson(stack: contextlib.ExitStack, argv: list[str], cwd: str, slot: str,
                  finish: Finish, peek: Peek | None = None, module: str = "motorlab") -> AsyncIterator[bytes]:
    """``{"progress": {...}}`` lines while the command runs, then ``{"result": ...}`` or ``{"error", "status"}``.

    With ``peek``, it is asked every :data:`PEEK_INTERVAL` until it gives something, which is sent as a
    line of its own (``{"partial": ...}``, once) before the command ends. The response's task is
    cancelled when the client goes away (Starlette listens for the disconnect): the command's child
    process is ended then, and the request's folder removed.
    """
    reports: asyncio.Queue[dict[str, Any]] = asyncio.Queue()
    task = asyncio.ensure_future(runner.run_module(module, argv, cwd=cwd, slot=slot, on_progress=reports.put_nowait))
    try:
        while not task.done():
            get = asyncio.ensure_future(reports.get())
            await asyncio.wait({task, get}, return_when=asyncio.FIRST_COMPLETED,
                               timeout=PEEK_INTERVAL if peek else None)
            if get.done():
                yield _line({"progress": get.result()})
            else:
                get.cancel()
            if peek is not None and not task.done() and (early := peek()) is not None:
                peek = None
                yield _line({"partial": early})
        while not reports.empty():
            yield _line({"progress": reports.get_nowait()})
        yield _as_line(finish(task.result()))
    finally:
        if not task.done():
            task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await task
        stack.close()


async def _execute(request: Request, stack: contextlib.ExitStack, argv: list[str], folder: Path, *,
                   slot: str = "short", finish: Finish | None = None, peek: Peek | None = None,
                   module: str = "motorlab") -> Response:
    """Run ``motorlab argv`` in ``folder`` and answer: the CLI's JSON, or a stream of it with progress.

    ``stack`` holds the request's folder: closed here, or by the stream when it ends.
    """
    done = finish or _outcome_response
    if NDJSON in request.headers.get("accept", ""):
        moved = stack.pop_all()
        return StreamingResponse(_ndjson(moved, argv, str(folder), slot, done, peek, module), media_type=NDJSON,
                                 headers={"cache-control": "no-store", "x-accel-buffering": "no"})
    outcome = await _until_disconnect(request, runner.run_module(module, argv, cwd=str(folder), slot=slot))
    if outcome is None:
        return _error("the client went away; the command was stopped", 499)
    return done(outcome)


async def _run_command(request: Request, head: list[str], fields: list[dict[str, Any]], extra: list[str]) -> Response:
    with contextlib.ExitStack() as stack:
        folder = stack.enter_context(uploads.private_folder())
        argv = await _argv(request, folder, head, fields)
        if isinstance(argv, Response):
            return argv
        return await _execute(request, stack, [*argv, *extra], folder)


def _experiment_fields(request: Request) -> list[dict[str, Any]] | Response:
    experiment = request.path_params["experiment"]
    if experiment not in schema.schema()["analyze"]:
        return _error(f"unknown experiment {experiment!r}", 404)
    return schema.command_fields("analyze", experiment)


async def analyze(request: Request) -> Response:
    fields = _experiment_fields(request)
    if isinstance(fields, Response):
        return fields
    return await _run_command(request, ["analyze", request.path_params["experiment"]], fields, ["--json"])


async def analyze_with_plots(request: Request) -> Response:
    """``analyze`` and its panels in one run: ``{"result": <analyze --json>, "panels": [...]}`` (the page's fit)."""
    fields = _experiment_fields(request)
    if isinstance(fields, Response):
        return fields
    with contextlib.ExitStack() as stack:
        folder = stack.enter_context(uploads.private_folder())
        started = time.perf_counter()
        argv = await _argv(request, folder, [request.path_params["experiment"]], fields)
        if isinstance(argv, Response):
            return argv
        saved = time.perf_counter()
        response = await _execute(request, stack, ["fit", *argv], folder, module="motorlab.ui.worker")
        if not isinstance(response, StreamingResponse):  # where the time went (benchmarks/bench_ui.py reads it)
            response.headers["server-timing"] = (f"upload;dur={1e3 * (saved - started):.1f}, "
                                                 f"run;dur={1e3 * (time.perf_counter() - saved):.1f}")
        return response


async def tune(request: Request) -> Response:
    return await _run_command(request, ["tune"], schema.command_fields("tune"), ["--json"])


async def tune_figure(request: Request) -> Response:
    """The step and profile responses as the CLI's own ``--plot`` figure (SVG)."""
    with uploads.private_folder() as folder:
        argv = await _argv(request, folder, ["tune"], schema.command_fields("tune"))
        if isinstance(argv, Response):
            return argv
        outcome = await runner.run_cli([*argv, "--plot=step.svg"], cwd=str(folder))
        if outcome.code != 0:
            return _outcome_response(outcome)
        return Response((folder / "step.svg").read_bytes(), media_type="image/svg+xml")


async def tune_response(request: Request) -> Response:
    """The step and profile responses of ``tune`` as curves (the page's interactive plot)."""
    with uploads.private_folder() as folder:
        argv = await _argv(request, folder, ["tune"], schema.command_fields("tune"))
        if isinstance(argv, Response):
            return argv
        outcome = await runner.run_module("motorlab.ui.worker", ["response", *argv[1:]], cwd=str(folder))
        return _outcome_response(outcome)


async def panels(request: Request) -> Response:
    """Data against model of one analysis (the curves of ``--plot``), for the interactive plot."""
    fields = _experiment_fields(request)
    if isinstance(fields, Response):
        return fields
    with uploads.private_folder() as folder:
        argv = await _argv(request, folder, [request.path_params["experiment"]], fields)
        if isinstance(argv, Response):
            return argv
        return _outcome_response(await runner.run_module("motorlab.ui.worker", ["panels", *argv], cwd=str(folder)))


async def detect(request: Request) -> Response:
    """Format, proposed experiment and raw signals of each uploaded file."""
    with uploads.private_folder() as folder:
        try:
            values, files = await _save_form(request, folder)
        except uploads.UploadError as exc:
            return _error(str(exc))
        paths = [p for key in files for p in files[key]]
        rules = [f"--column={rule}" for rule in values.get("column", [])]  # the column picker's answers
        outcome = await runner.run_module("motorlab.ui.worker", ["detect", *rules, "--", *paths], cwd=str(folder))
        return _outcome_response(outcome)


def _session_file(files: list[str], values: dict[str, list[str]]) -> str | None:
    """The uploaded session description: the one named by the ``session`` field, else the only ``.toml``."""
    wanted = values.pop("session", [""])[0]
    tomls = [p for p in files if p.lower().endswith(".toml")]
    named = [p for p in tomls if Path(p).name == uploads.safe_relative(wanted).name] if wanted else []
    found = named or (tomls if len(tomls) == 1 else [])
    return found[0] if found else None


async def characterize(request: Request) -> Response:
    """A whole session (its TOML and logs, or one zip) → results.json, results.csv and report.html.

    Streamed (NDJSON), the results table comes first, as ``{"partial": {"results", "csv"}}``, as soon
    as the CLI has written it; the report's figures follow in the last line.
    """
    with contextlib.ExitStack() as stack:
        folder = stack.enter_context(uploads.private_folder())
        try:
            values, files = await _save_form(request, folder)
        except uploads.UploadError as exc:
            return _error(str(exc))
        all_files = [p for key in files for p in files[key]]
        session = _session_file(all_files, values)
        if session is None:
            return _error("choose the session's .toml file with its logs, or one .zip of the session's folder")
        try:
            uploads.place_session_files(folder, session, all_files)  # loose files go where the TOML names them
        except uploads.UploadError as exc:
            return _error(str(exc))
        fields = schema.command_fields("characterize")
        refused = sorted(set(values) & _REFUSED_FIELDS)
        if refused:
            return _error(f"--{refused[0]}: the app sets this option itself")
        out = folder / "_results"
        argv = [*runner.build_argv(["characterize"], fields, values, [session]), "--quiet", f"--output={out}",
                f"--processes={runner.SESSION_PROCESSES}"]

        def finish(outcome: runner.Outcome) -> Response:
            if outcome.code not in (0, 3):
                return _outcome_response(outcome)
            body = {
                "exit_code": outcome.code,
                "message": outcome.error_line() if outcome.code else "",
                "results": json.loads((out / "results.json").read_text(encoding="utf-8")),
                "csv": (out / "results.csv").read_text(encoding="utf-8"),
                "report_html": (out / "report.html").read_text(encoding="utf-8"),
            }
            return JSONResponse(body)

        def table() -> dict[str, Any] | None:
            """results.json and results.csv once written (atomically, the csv first), the report still drawing."""
            try:
                return {"results": json.loads((out / "results.json").read_text(encoding="utf-8")),
                        "csv": (out / "results.csv").read_text(encoding="utf-8")}
            except (OSError, ValueError):
                return None

        return await _execute(request, stack, argv, folder, slot="session", finish=finish, peek=table)


async def api_schema(request: Request) -> Response:
    return JSONResponse(schema.schema())


async def motors(request: Request) -> Response:
    from motorlab.catalog import list_motors

    return JSONResponse(
        [{"key": m.key, "name": m.name, "cpr": m.cpr, "gear_ratio": m.gear_ratio} for m in list_motors()]
    )


def _static_dir() -> Path:
    return Path(str(resources.files("motorlab.ui") / "static"))


def _plotly_js() -> Path:
    import plotly

    return Path(plotly.__file__).parent / "package_data" / "plotly.min.js"


async def plotly_js(request: Request) -> Response:
    return FileResponse(_plotly_js(), media_type="text/javascript")


async def index(request: Request) -> Response:
    """The page, holding this launch's robot token (a page elsewhere cannot read it: no CORS header)."""
    page = (_static_dir() / "index.html").read_text(encoding="utf-8")
    meta = f'<meta name="motorlab-token" content="{request.app.state.robot_token}">'
    return Response(page.replace("<head>", f"<head>\n{meta}", 1), media_type="text/html",
                    headers={"cache-control": "no-store"})


#: Content-Security-Policy of every response: the page may load nothing from another host.
CSP = (
    "default-src 'self'; script-src 'self'; style-src 'self' 'unsafe-inline'; img-src 'self' data: blob:; "
    "font-src 'self' data:; connect-src 'self'; frame-src 'self' blob: data:; object-src 'none'; base-uri 'none'"
)


#: Methods that change nothing (RFC 9110, 9.2.1): any other one must come from the app's own page.
SAFE_METHODS = ("GET", "HEAD", "OPTIONS")
#: The header in which the page sends the robot token (``<meta name="motorlab-token">`` of the page).
ROBOT_TOKEN_HEADER = "x-motorlab-token"
#: The one robot route without the token (still only from the app's page): Stop, which must work from a page
#: left open while the app restarted.
ROBOT_STOP = "/api/robot/record/stop"


class Guard:
    """ASGI middleware: the Host header must be the served address; the token when one is set; a body limit;
    a state-changing request only from the app's own page; the robot routes only with the page's robot token.

    A foreign Host means a page elsewhere reached this app through DNS rebinding (Jupyter and Vite
    refuse such requests too). With a token (``--host`` other than loopback), a request carries it as
    ``?token=`` or in the cookie the page gets with it. A POST (any method but GET, HEAD, OPTIONS) whose
    ``Origin`` is not ``scheme://Host`` of this request (the Host checked above), or without Origin whose
    ``Sec-Fetch-Site`` is not ``same-origin`` or ``none``, is refused: another web page sent it (a
    cross-site form or ``fetch``). Neither header (curl, a script) passes. ``/api/robot/*`` but Stop also
    needs ``X-Motorlab-Token``, random at each launch and held only by the served page.
    """

    def __init__(self, app: ASGIApp, *, hosts: set[str] | None, token: str | None, max_body: int,
                 robot_token: str = "") -> None:
        self.app, self.hosts, self.token, self.max_body = app, hosts, token, max_body
        self.robot_token = robot_token

    @staticmethod
    def _foreign(scope: Scope, headers: dict[bytes, bytes]) -> str | None:
        """Who sent a state-changing request when it was not the app's own page, else None."""
        if scope["method"] in SAFE_METHODS:
            return None
        origin = headers.get(b"origin")
        if origin is not None:
            own = f"{scope.get('scheme', 'http')}://{headers.get(b'host', b'').decode('latin-1')}".lower()
            given = origin.decode("latin-1").lower()
            return None if given == own else f"a page at {given}"
        site = headers.get(b"sec-fetch-site", b"none").decode("latin-1").lower()
        return None if site in ("same-origin", "none") else f"a {site} page"

    async def _refuse(self, send: Callable[[Any], Awaitable[None]], status: int, message: str) -> None:
        body = json.dumps({"error": message}).encode()
        headers = [(b"content-type", b"application/json"), (b"content-length", str(len(body)).encode())]
        await send({"type": "http.response.start", "status": status, "headers": headers})
        await send({"type": "http.response.body", "body": body})

    def _token_ok(self, scope: Scope, headers: dict[bytes, bytes]) -> bool:
        if self.token is None:
            return True
        from urllib.parse import parse_qs

        given = parse_qs(scope.get("query_string", b"").decode("latin-1")).get("token", [""])[0]
        cookies = headers.get(b"cookie", b"").decode("latin-1")
        cookie = next((c.split("=", 1)[1] for c in cookies.split("; ") if c.startswith("motorlab_token=")), "")
        return any(secrets.compare_digest(t.encode(), self.token.encode()) for t in (given, cookie) if t)

    async def __call__(
        self, scope: Scope, receive: Callable[[], Awaitable[Any]], send: Callable[[Any], Awaitable[None]]
    ) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        headers = dict(scope.get("headers", []))
        host = headers.get(b"host", b"").decode("latin-1").lower()
        if self.hosts is not None and host not in self.hosts:
            await self._refuse(send, 403, f"Host {host!r} is not this app's address (DNS rebinding guard)")
            return
        if not self._token_ok(scope, headers):
            await self._refuse(send, 403, "this app needs its token: open the URL it printed")
            return
        if (sender := self._foreign(scope, headers)) is not None:
            await self._refuse(send, 403, f"refused: {sender} asked this app to act; only the motorlab page "
                                          "itself can, so use the app in its own tab")
            return
        if scope["path"].startswith("/api/robot/") and scope["path"] != ROBOT_STOP and not (
                self.robot_token and hmac.compare_digest(headers.get(ROBOT_TOKEN_HEADER.encode(), b""),
                                                         self.robot_token.encode())):
            await self._refuse(send, 403, "the robot link answers only the page this app served: reload the page "
                                          "(its robot token changes each time the app starts)")
            return
        if scope["method"] == "POST":
            length = headers.get(b"content-length", b"")
            if not length.isdigit():
                await self._refuse(send, 411, "the request must state its length")
                return
            if int(length) > self.max_body:
                await self._refuse(send, 413, f"the upload is larger than {self.max_body // 2**20} MB")
                return

        async def send_with_headers(message: Any) -> None:
            if message["type"] == "http.response.start":
                extra = [(b"content-security-policy", CSP.encode()), (b"x-content-type-options", b"nosniff"),
                         (b"referrer-policy", b"no-referrer")]
                if self.token is not None and scope["path"] == "/":
                    cookie = f"motorlab_token={self.token}; HttpOnly; SameSite=Strict; Path=/"
                    extra.append((b"set-cookie", cookie.encode()))
                message = {**message, "headers": [*message.get("headers", []), *extra]}
            await send(message)

        await self.app(scope, receive, send_with_headers)


#: Addresses that mean "every interface": clients name the machine by any of its addresses or names.
WILDCARDS = ("0.0.0.0", "::", "")


def allowed_hosts(host: str, port: int) -> set[str] | None:
    """Host header values that name this app: ``host:port`` (and ``localhost:port`` on loopback).

    None (any Host) when bound to every interface: other machines reach it by whatever name or
    address they know, so the Host header cannot be checked; the token (always required off
    loopback) is the guard then, as in Jupyter.
    """
    if host in WILDCARDS:
        return None
    names = {host.lower()}
    if host in ("127.0.0.1", "localhost", "::1"):
        names |= {"127.0.0.1", "localhost", "[::1]"}
    names = {f"[{n}]" if ":" in n and not n.startswith("[") else n for n in names}
    return {f"{n}:{port}" for n in names} | ({*names} if port == 80 else set())


def create_app(*, host: str = "127.0.0.1", port: int = 8765, token: str | None = None,
               max_body: int = uploads.MAX_UPLOAD) -> ASGIApp:
    """The app, guarded for ``host:port`` (and ``token`` when given)."""
    routes = [
        Route("/", index),
        Route("/static/plotly.min.js", plotly_js),
        Mount("/static", app=StaticFiles(directory=_static_dir()), name="static"),
        Route("/api/schema", api_schema),
        Route("/api/motors", motors),
        Route("/api/detect", detect, methods=["POST"]),
        Route("/api/analyze/{experiment}", analyze, methods=["POST"]),
        Route("/api/panels/{experiment}", panels, methods=["POST"]),
        Route("/api/analyze/{experiment}/plots", analyze_with_plots, methods=["POST"]),
        Route("/api/tune", tune, methods=["POST"]),
        Route("/api/tune/figure", tune_figure, methods=["POST"]),
        Route("/api/tune/response", tune_response, methods=["POST"]),
        Route("/api/characterize", characterize, methods=["POST"]),
        *robot.routes(),  # the robot link (issue 24): motorlab.ui.robot
    ]
    runner.POOL.fill()  # warm child processes, ready before the first click
    # python-multipart logs a warning ("Expected boundary character ...") for every body that is no
    # multipart form before raising; the app answers that request with a 400 naming the problem, so
    # the warning is noise in the server's log (its errors still show).
    logging.getLogger("python_multipart.multipart").setLevel(logging.ERROR)
    app = Starlette(routes=routes)
    app.state.robot_token = secrets.token_urlsafe(32)  # a new one at each launch: the page holds it
    return Guard(app, hosts=allowed_hosts(host, port), token=token, max_body=max_body,
                 robot_token=app.state.robot_token)


def is_loopback(host: str) -> bool:
    return host in ("127.0.0.1", "localhost", "::1") or host.startswith("127.")


def serve(*, host: str = "127.0.0.1", port: int = 8765, open_browser: bool = True) -> None:
    """Run the app until interrupted: print its URL, open the browser (unless told not to)."""
    import sys
    import webbrowser

    import uvicorn

    token = None if is_loopback(host) else secrets.token_urlsafe(24)
    shown = f"[{host}]" if ":" in host else host
    url = f"http://{shown}:{port}/" + (f"?token={token}" if token else "")
    if token:
        print(
            f"motorlab: warning: serving on {host}, reachable from other machines; anyone with the URL "
            "(it carries the token) can run analyses here", file=sys.stderr,
        )
    print(f"motorlab ui: {url}  (Ctrl+C stops it)", flush=True)
    if open_browser:
        webbrowser.open(url)
    uvicorn.run(create_app(host=host, port=port, token=token), host=host, port=port, log_level="warning")
