"""A live ``motorlab ui`` server (uvicorn in a thread) on a free loopback port, simulated logs, and a browser.

The browser tests' helpers (``browser.py``: a headless Chromium driven by visible words) are loaded
once here and importable by the test modules as ``ui_browser``; the ``page`` fixture gives each
browser test module a tab on the test server, in a Chromium each test process starts once (``chromium``).
"""

from __future__ import annotations

import importlib.util
import json
import socket
import sys
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
import uvicorn

from motorlab.ui.app import create_app


def _browser_helpers() -> Any:
    """tests/ui/browser.py, loaded once as the module ``ui_browser`` (the tests are no package)."""
    if "ui_browser" in sys.modules:
        return sys.modules["ui_browser"]
    spec = importlib.util.spec_from_file_location("ui_browser", Path(__file__).with_name("browser.py"))
    assert spec is not None
    assert spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules["ui_browser"] = module
    spec.loader.exec_module(module)
    return module


browser = _browser_helpers()

#: Upload limit of the test servers (small, so the 413 test is quick).
TEST_MAX_BODY = 2 * 1024 * 1024


@dataclass
class Served:
    url: str
    host: str
    port: int


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@pytest.fixture(scope="session")
def start_server() -> Iterator[Any]:
    """A factory of live servers; all stopped at the end of the session."""
    servers: list[tuple[uvicorn.Server, threading.Thread]] = []

    def start(token: str | None = None) -> Served:
        port = _free_port()
        app = create_app(host="127.0.0.1", port=port, token=token, max_body=TEST_MAX_BODY)
        server = uvicorn.Server(uvicorn.Config(app, host="127.0.0.1", port=port, log_level="warning", lifespan="off"))
        thread = threading.Thread(target=server.run, daemon=True)
        thread.start()
        deadline = time.monotonic() + 20
        while not server.started:
            assert time.monotonic() < deadline, "the server did not start"
            time.sleep(0.02)
        servers.append((server, thread))
        return Served(f"http://127.0.0.1:{port}", "127.0.0.1", port)

    yield start
    for server, thread in servers:
        server.should_exit = True
        thread.join(timeout=10)


@pytest.fixture(scope="session")
def server(start_server: Any) -> Served:
    return start_server()


@pytest.fixture(scope="session")
def sim_session(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """One simulated unit (spin-down and LCR logs, truth.json) and its session.toml."""
    from motorlab.session.simulated import write_simulated_session

    folder = tmp_path_factory.mktemp("ui-session")
    write_simulated_session("neverest40", out_dir=folder, units=1, seed=5, experiments=("lcr", "spindown"))
    return folder


@pytest.fixture(scope="session")
def truth(sim_session: Path) -> dict[str, Any]:
    return dict(json.loads((sim_session / "A" / "truth.json").read_text()))


@pytest.fixture(scope="session")
def ramp(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, float]:
    """A simulated Road Runner forward ramp (8192-count dead wheels) and its true kV per tick [V·s/tick]."""
    import math

    from motorlab.cli import main

    folder = tmp_path_factory.mktemp("ramp")
    assert main(["simulate", "roadrunner-ramp", "-o", str(folder / "ramp.json")]) == 0  # in this process
    expected = json.loads((folder / "truth.json").read_text())["runs"]["ramp.json"]["expected"]
    return folder / "ramp.json", expected["kV"] * 2 * math.pi / expected["cpr"]


@pytest.fixture(scope="session")
def simulated_sysid(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, Any]]:
    """A simulated WPILib SysId file of a NeveRest 40 (``motorlab simulate sysid``, in this process, once) and its
    expected gains (per radian)."""
    from motorlab.cli import main

    folder = tmp_path_factory.mktemp("sysid")
    assert main(["simulate", "sysid", "--motor", "neverest40", "-o", str(folder / "sysid.json")]) == 0
    expected = next(iter(json.loads((folder / "truth.json").read_text())["runs"].values()))["expected"]
    return folder / "sysid.json", dict(expected)


@pytest.fixture(scope="session")
def shooter(real_dir: Path) -> Path:
    """A team's real SysId file of a shooter (12,905 rows, units: rotations), read in place from
    ../shared/data/real/sysid."""
    return real_dir / "sysid" / "stma7028_shooter_0309.json"


@pytest.fixture(scope="session")
def chromium() -> Iterator[browser.Chromium]:
    """One headless Chromium per test process (each xdist worker), lent to one test module at a time: starting
    one and loading the page's scripts into a new profile cost seconds a module."""
    lender = browser.Chromium()
    yield lender
    lender.quit()


@pytest.fixture(scope="module")
def page(chromium: browser.Chromium, server: Served, tmp_path_factory: pytest.TempPathFactory,
         request: pytest.FixtureRequest) -> Iterator[Any]:
    """A browser tab on the test server for one test module, driven by visible words (``browser.Page``); the module
    starts as on a new profile (one tab, nothing the page stored, the window's first size)."""
    tmp = tmp_path_factory.mktemp(request.module.__name__.rsplit(".", 1)[-1])
    yield browser.Page(chromium.lend(server.url), server.url, browser.shots_folder(tmp))
    chromium.give_back()
