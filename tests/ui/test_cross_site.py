"""No other web page can make the app act (issue 32, item 6): every state-changing route of the app, found
from the app's own route table (a route added later is covered without touching this file), refuses a
request sent by a foreign page (``Origin`` or ``Sec-Fetch-Site``) with a 403 in words, and nothing runs:
no command, no upload folder, no message to the emulated robot. The robot routes also need the page's
token. HTTP through Starlette's TestClient; the same through a real browser in
``test_cross_site_browser`` below."""

from __future__ import annotations

import re
import tempfile
import threading
import time
import warnings
from collections.abc import Iterator
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any

import pytest
import ui_browser as browser  # tests/ui/browser.py, loaded by conftest.py

with warnings.catch_warnings():  # starlette ≥ 0.48 prefers httpx2 for its test client; httpx works the same here
    warnings.simplefilter("ignore")
    from starlette.testclient import TestClient
from starlette.routing import Route

from motorlab.robot.emulator import EmulatedRobot
from motorlab.ui import runner, uploads
from motorlab.ui.app import SAFE_METHODS, create_app

APP = "http://127.0.0.1:8765"
OPMODE = "motorlab: quasistatic ramp"

#: Foreign senders: (headers, what the refusal names).
FOREIGN = [
    ({"Origin": "https://evil.example"}, "https://evil.example"),
    ({"Origin": "null"}, "null"),  # a sandboxed frame, a file:// page
    ({"Origin": "http://127.0.0.1:9999"}, "127.0.0.1:9999"),  # another port of this machine: another origin
    ({"Origin": "http://localhost:8765"}, "localhost:8765"),  # the same app by another name: not this page
    ({"Sec-Fetch-Site": "cross-site"}, "cross-site"),  # a browser that sent no Origin
    ({"Sec-Fetch-Site": "same-site"}, "same-site"),
]


def changing_routes(app: Any) -> list[tuple[str, str]]:
    """(method, path) of every route of the app that is not GET/HEAD-only, path parameters filled in."""
    starlette = app.app  # the Guard wraps the Starlette app
    found = []
    for route in starlette.routes:
        if not isinstance(route, Route):
            continue  # the static files' Mount answers GET only
        path = re.sub(r"\{experiment\}", "feedforward", route.path)
        path = re.sub(r"\{[^}]+\}", "1", path)
        found += [(m, path) for m in sorted(route.methods or ()) if m not in SAFE_METHODS]
    return found


def robot_form(robot: EmulatedRobot) -> dict[str, str]:
    """Fields that would start, write or pull on the emulated robot, if the app accepted them."""
    return {"host": "127.0.0.1", "http-port": str(robot.http_port), "dashboard-port": str(robot.dashboard_port),
            "opmode": OPMODE, "seconds": "2", "confirm": "yes", "while-running": "yes", "target": "roadrunner",
            "cpr": "537.6", "experiment": "feedforward"}


def page_token(client: TestClient) -> str:
    match = re.search(r'<meta name="motorlab-token" content="([^"]+)">', client.get("/").text)
    assert match, "the page holds no robot token"
    return match.group(1)


@pytest.fixture
def watched(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> list[str]:
    """Every command, worker and upload folder the app would start, recorded instead of run."""
    calls: list[str] = []

    async def no_cli(argv: list[str], **_: Any) -> runner.Outcome:
        calls.append(f"cli {argv}")
        raise AssertionError("a command ran")

    async def no_module(module: str, argv: list[str], **_: Any) -> runner.Outcome:
        calls.append(f"module {module} {argv}")
        raise AssertionError("a worker ran")

    real_folder = uploads.private_folder

    def folder() -> Any:
        calls.append("upload folder")
        return real_folder()

    monkeypatch.setattr(runner, "run_cli", no_cli)
    monkeypatch.setattr(runner, "run_module", no_module)
    monkeypatch.setattr(uploads, "private_folder", folder)
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))  # every folder the app makes lands here
    return calls


@pytest.fixture
def robot() -> Iterator[EmulatedRobot]:
    with EmulatedRobot(lifetime=60.0, max_requests=2000) as emulated:
        yield emulated


def test_every_state_changing_route_refuses_a_foreign_page(watched: list[str], robot: EmulatedRobot,
                                                           tmp_path: Path) -> None:
    app = create_app(host="127.0.0.1", port=8765)
    routes = changing_routes(app)
    paths = {p for _, p in routes}
    # The route table really is read: the experiments, the tuning, the session and the robot link are in it.
    assert {"/api/analyze/feedforward", "/api/tune", "/api/characterize", "/api/detect",
            "/api/robot/record/start", "/api/robot/record/stop", "/api/robot/push/apply"} <= paths, paths
    client = TestClient(app, base_url=APP)
    token = page_token(client)
    for method, path in routes:
        for headers, named in FOREIGN:
            answer = client.request(method, path, data=robot_form(robot),
                                    headers={**headers, "X-Motorlab-Token": token},
                                    files={"file": ("run.csv", b"time_s,voltage_V\n0,1\n"),
                                           "params": ("fit.json", b"{}")})
            assert answer.status_code == 403, (method, path, headers, answer.text)
            message = answer.json()["error"]
            assert named in message
            assert "\n" not in message
            assert "only the motorlab page" in message
    assert watched == []  # no command, no worker, no upload folder
    assert robot.received == []
    assert robot.http_requests == []
    assert not any(tmp_path.iterdir())  # nothing written
    assert client.get("/api/robot/record", headers={"X-Motorlab-Token": token}).json()["state"] == "idle"


def test_the_robot_routes_need_the_page_token(robot: EmulatedRobot) -> None:
    client = TestClient(create_app(host="127.0.0.1", port=8765), base_url=APP)
    token = page_token(client)
    for headers in ({}, {"X-Motorlab-Token": "guessed"}, {"X-Motorlab-Token": token[:-1]}):
        answer = client.post("/api/robot/record/start", data=robot_form(robot), headers={"Origin": APP, **headers})
        assert answer.status_code == 403
        assert "reload the page" in answer.json()["error"]
        assert client.get("/api/robot/record", headers=headers).status_code == 403
    assert robot.received == []
    # Another launch has another token: a page of the previous one cannot drive this one.
    assert page_token(TestClient(create_app(host="127.0.0.1", port=8765), base_url=APP)) != token


def test_the_page_itself_and_local_scripts_still_act(robot: EmulatedRobot) -> None:
    """The control: the same request from the app's own page, or from a script that sends neither header,
    starts the OpMode (so the refusals above are the guard's, not a broken form); Stop works from the page."""
    client = TestClient(create_app(host="127.0.0.1", port=8765), base_url=APP)
    token = page_token(client)
    own = {"Origin": APP, "Sec-Fetch-Site": "same-origin", "X-Motorlab-Token": token}
    for headers in (own, {"X-Motorlab-Token": token}):  # the page; curl with the token
        start = client.post("/api/robot/record/start", data=robot_form(robot), headers=headers)
        assert start.status_code == 200, start.text
        deadline = time.monotonic() + 10
        while robot.status != "RUNNING" and time.monotonic() < deadline:
            time.sleep(0.02)
        assert robot.status == "RUNNING"
        assert client.post("/api/robot/record/stop", headers=own).status_code == 200
        while client.get("/api/robot/record", headers=own).json()["state"] != "stopped":
            assert time.monotonic() < deadline
            time.sleep(0.05)
    assert [m["type"] for m in robot.received].count("START_OP_MODE") == 2
    # A foreign page may still read nothing and change nothing; a GET it sends is answered (it cannot read it).
    assert client.get("/api/schema", headers={"Origin": "https://evil.example"}).status_code == 200


def test_every_interface_compares_the_origin_with_the_host() -> None:
    """Bound to 0.0.0.0 the Host is not checked (other machines name it as they like), yet the Origin must
    still be the Host the request was sent to."""
    client = TestClient(create_app(host="0.0.0.0", port=8765, token="t"), base_url="http://192.168.1.5:8765")
    refused = client.post("/api/tune?token=t", headers={"Origin": "http://192.168.1.9:8765"})
    assert refused.status_code == 403
    assert "192.168.1.9" in refused.json()["error"]


# ---- the same in a real browser ---------------------------------------------------------------------------

FOREIGN_PAGE = """<!doctype html><html><body><h1>A page elsewhere</h1>
<form id="f" method="post" enctype="multipart/form-data" action="{app}/api/robot/record/start">
<input name="host" value="127.0.0.1"><input name="dashboard-port" value="{port}">
<input name="opmode" value="{opmode}"><input name="seconds" value="2"></form>
<script>
const f = new FormData(document.getElementById("f"));
fetch("{app}/api/robot/record/start", {{method: "POST", mode: "no-cors", body: f}})
  .finally(() => fetch("{app}/api/tune", {{method: "POST", mode: "no-cors", body: f}}))
  .finally(() => {{ document.title = "sent"; document.getElementById("f").submit(); }});
</script></body></html>"""


@pytest.fixture
def foreign_site(server: Any, robot: EmulatedRobot) -> Iterator[str]:
    """A page on another loopback port that, once opened, POSTs to the app by fetch() and by a form."""
    body = FOREIGN_PAGE.format(app=server.url, port=robot.dashboard_port, opmode=OPMODE).encode()

    class Handler(BaseHTTPRequestHandler):
        def log_message(self, format: str, *args: Any) -> None:
            return

        def do_GET(self) -> None:
            self.send_response(200)
            self.send_header("Content-Type", "text/html")
            self.send_header("Content-Length", str(len(body)))
            self.end_headers()
            self.wfile.write(body)

    site = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
    threading.Thread(target=site.serve_forever, daemon=True).start()
    yield f"http://127.0.0.1:{site.server_address[1]}/"
    site.shutdown()
    site.server_close()


@browser.needs_browser
def test_cross_site_browser(page: Any, foreign_site: str, robot: EmulatedRobot, server: Any) -> None:
    page.d.get(foreign_site)
    # The form's answer replaces the foreign page: the app's refusal, in words.
    page.wait(lambda: "only the motorlab page" in page.words_of("body"), "the refusal")
    assert "127.0.0.1:" in page.words_of("body")
    time.sleep(0.5)  # anything the app had started would have reached the robot by now
    assert robot.received == [], robot.received  # the emulated robot heard nothing: no INIT, no START
    assert robot.status == "INIT"
    assert robot.active == "$Stop$Robot$"
    # The app's own page still works: it lists the OpModes through the same guard.
    page.open(browser.LAPTOP)
    page.click("Connect to the robot")
    page.click("Record a run")
    page.type("FTC Dashboard port", str(robot.dashboard_port))
    page.type("Robot address", "127.0.0.1")
    page.click("List the robot's OpModes")
    page.wait_text("OpModes; battery")
