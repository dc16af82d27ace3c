"""The browser app's speed (issue 22, point 7): click → result, gains, a short analysis beside sessions.

Targets: a 30 000-row spin-down posted to ``/api/analyze/spindown`` answers in ≤ 1.0 s; gains
(``/api/tune``, and ``/api/tune/response`` as the page asks at each change) in ≤ 0.5 s; a short
analysis is not queued behind running sessions; an 8-unit session's results table (the streamed
``partial`` line) in ≤ 10 s, the report following. The app runs in this process (uvicorn in a
thread) with its warm workers, and the same requests are timed with ``MOTORLAB_UI_WARM=0`` (a fresh
``python -m`` per command, as before the warm workers). Wall time depends on the machine's load: the
load average is printed with the figures.

    python benchmarks/bench_ui.py            # all
    python benchmarks/bench_ui.py quick      # without the 8-unit session
    python benchmarks/bench_ui.py session    # only the 8-unit session
    python benchmarks/bench_ui.py page       # issue 31: the page's click → result and plots

Issue 31 (``page``): click → result with its plots for a Road Runner ramp and a team's real SysId file
(12,905 rows) as the page asks for them since (one request, ``/api/analyze/<experiment>/plots``: one
analysis) and as it asked before (``/api/analyze`` and ``/api/panels`` at once: the analysis twice);
targets ≤ 1 s; a session of three units to its table, target ≤ 2 s; the size of the plots sent.
"""

from __future__ import annotations

import os
import socket
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

import httpx
import uvicorn


def _long_spindown(folder: Path) -> Path:
    """A spin-down log of about 30 000 rows (the OpMode logging every 1.7 ms)."""
    from dataclasses import replace

    from motorlab.rig import VirtualRig
    from motorlab.rig.instruments import Instruments, LoggingLoop

    instruments = Instruments(logger=replace(LoggingLoop(), period=0.0017))
    path = folder / "spindown.txt"
    VirtualRig("neverest40", unit_seed=1, noise_seed=2, instruments=instruments).spindown(path, coast_time=60.0)
    return path


def _serve() -> tuple[uvicorn.Server, str]:
    from motorlab.ui.app import create_app

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = int(s.getsockname()[1])
    server = uvicorn.Server(uvicorn.Config(create_app(host="127.0.0.1", port=port), host="127.0.0.1", port=port,
                                           log_level="warning", lifespan="off"))
    threading.Thread(target=server.run, daemon=True).start()
    while not server.started:
        time.sleep(0.02)
    return server, f"http://127.0.0.1:{port}"


def _timed(fn: Any) -> tuple[float, Any]:
    t0 = time.perf_counter()
    out = fn()
    return time.perf_counter() - t0, out


def _wait_for_spares(seconds: float = 60.0) -> None:
    from motorlab.ui import runner

    runner.POOL.fill()
    time.sleep(min(seconds, 12.0))  # the spares import numpy, scipy, matplotlib, motorlab


def _analysis(url: str, log: Path) -> float:
    data = log.read_bytes()
    dt, r = _timed(lambda: httpx.post(f"{url}/api/analyze/spindown", files=[("file", ("spindown.txt", data))],
                                      data={"cpr": "1120"}, timeout=300))
    assert r.status_code == 200, r.text
    return dt


def _gains(url: str, path: str = "/api/tune", kv: str = "0.12") -> float:
    fields = {"loop": "velocity", "kv": kv, "ka": "0.01", "ks": "0.3", "target": "roadrunner", "cpr": "8192",
              "emit": "java"}
    dt, r = _timed(lambda: httpx.post(f"{url}{path}", data=fields, timeout=300))
    assert r.status_code == 200, r.text
    return dt


def _session_zip(units: int, folder: Path) -> bytes:
    import io
    import zipfile

    from motorlab.session.simulated import write_simulated_session

    write_simulated_session("neverest40", out_dir=folder, units=units, seed=3)
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w") as zf:
        for path in folder.rglob("*"):
            if path.is_file():
                zf.write(path, str(path.relative_to(folder)))
    return buffer.getvalue()


def _session(url: str, body: bytes) -> float:
    dt, r = _timed(lambda: httpx.post(f"{url}/api/characterize", files=[("file", ("s.zip", body))], timeout=900))
    assert r.status_code == 200, r.text
    return dt


def _session_streamed(url: str, body: bytes) -> tuple[float, float]:
    """Seconds from the click to the results table (the streamed ``partial`` line), and to the report."""
    import json

    t0 = time.perf_counter()
    table = float("nan")
    with httpx.stream("POST", f"{url}/api/characterize", files=[("file", ("s.zip", body))], timeout=900,
                      headers={"Accept": "application/x-ndjson"}) as r:
        assert r.status_code == 200
        for line in r.iter_lines():
            message = json.loads(line)
            if "partial" in message:
                table = time.perf_counter() - t0
            elif "result" in message:
                assert message["result"]["report_html"]
            elif "error" in message:
                raise AssertionError(message["error"])
    return table, time.perf_counter() - t0


def _beside_sessions(url: str, log: Path, body: bytes) -> float:
    """A short analysis while two sessions run."""
    threads = [threading.Thread(target=_session, args=(url, body)) for _ in range(2)]
    for t in threads:
        t.start()
    time.sleep(1.0)
    dt = _analysis(url, log)
    for t in threads:
        t.join()
    return dt


def _session_only() -> None:
    """Only the 8-unit session (``python benchmarks/bench_ui.py session``)."""
    with tempfile.TemporaryDirectory() as tmp:
        body = _session_zip(8, Path(tmp) / "eight")
        print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs")
        _server, url = _serve()
        _wait_for_spares()
        table, report = _session_streamed(url, body)
        print(f"8-unit session: results table {table:.1f} s (target ≤ 10 s), report with its figures {report:.1f} s")
        print(f"load average {os.getloadavg()[0]:.1f} at the end")


#: A team's real SysId file of a shooter (12,905 rows), read in place (../shared/data/real beside the clone).
_ROOT = Path(__file__).resolve().parents[1]
_PLACES = [b / "shared/data/real/sysid/stma7028_shooter_0309.json" for b in (_ROOT.parent, _ROOT.parent.parent)]
SHOOTER = next((p for p in _PLACES if p.is_file()), None)


def _fit_with_plots(url: str, experiment: str, path: Path, fields: dict[str, str]) -> tuple[float, int]:
    """Seconds from the click to the result with its plots (one request), and the largest trace sent."""
    import json

    data = path.read_bytes()
    dt, r = _timed(lambda: httpx.post(f"{url}/api/analyze/{experiment}/plots", files=[("file", (path.name, data))],
                                      data=fields, timeout=300))
    assert r.status_code == 200, r.text
    body = json.loads(r.text)
    largest = max(len(t["x"]) for p in body["panels"] for t in [p["data"], p["model"], *p["extra"]] if t)
    return dt, largest


def _fit_before(url: str, experiment: str, path: Path, fields: dict[str, str]) -> float:
    """The same as the page asked before: the analysis and its panels as two requests at once."""
    data = path.read_bytes()

    def both() -> None:
        out: list[Any] = []
        jobs = [threading.Thread(target=lambda e=e: out.append(httpx.post(
            f"{url}/api/{e}/{experiment}", files=[("file", (path.name, data))], data=fields, timeout=300)))
            for e in ("analyze", "panels")]
        for j in jobs:
            j.start()
        for j in jobs:
            j.join()
        assert all(r.status_code == 200 for r in out)

    return _timed(both)[0]


def _page() -> None:
    """Issue 31: what the page waits for after a click, as it asks now and as it asked before."""
    import subprocess

    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        subprocess.run([sys.executable, "-m", "motorlab", "simulate", "roadrunner-ramp", "-o",
                        str(folder / "ramp.json")], check=True, capture_output=True)
        three = _session_zip(3, folder / "three")
        print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs")
        _server, url = _serve()
        _wait_for_spares()
        cases = [("Road Runner ramp", "feedforward", folder / "ramp.json", {"cpr": "8192"})]
        if SHOOTER is not None:
            rows = sum(len(v) for v in __import__("json").loads(SHOOTER.read_text()).values() if isinstance(v, list))
            cases.append((f"SysId shooter file ({rows} rows)", "feedforward", SHOOTER, {}))
        for name, experiment, path, fields in cases:
            now, before = [], []
            for _ in range(3):
                dt, largest = _fit_with_plots(url, experiment, path, fields)
                now.append(dt)
                _wait_for_spares(3.0)
                before.append(_fit_before(url, experiment, path, fields))
                _wait_for_spares(3.0)
            print(f"{name}: click → result with plots {min(now):.2f} s (best of 3; target ≤ 1 s), "
                  f"{min(before):.2f} s as two requests before; largest trace sent {largest} points")
        table, report = _session_streamed(url, three)
        print(f"3-unit session: results table {table:.1f} s (target ≤ 2 s), report with its figures {report:.1f} s")
        print(f"load average {os.getloadavg()[0]:.1f} at the end")


def main() -> None:
    if "session" in sys.argv[1:]:
        _session_only()
        return
    if "page" in sys.argv[1:]:
        _page()
        return
    quick = "quick" in sys.argv[1:]
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        log = _long_spindown(folder)
        rows = sum(1 for _ in log.open())
        small = _session_zip(1, folder / "small")
        print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs; spin-down log of {rows} rows")
        _server, url = _serve()
        for mode in ("warm", "cold"):
            os.environ["MOTORLAB_UI_WARM"] = "1" if mode == "warm" else "0"
            if mode == "warm":
                _wait_for_spares()
            analysis = []
            for _ in range(3):
                analysis.append(_analysis(url, log))
                if mode == "warm":
                    _wait_for_spares(3.0)
            gains = []
            for _ in range(3):
                gains.append(_gains(url))
                if mode == "warm":
                    _wait_for_spares(3.0)
            # A change of an option on the gains step: the page asks for the gains with their curves, at once.
            changes = [_gains(url, "/api/tune/response", kv) for kv in ("0.121", "0.122", "0.123", "0.124", "0.125")]
            print(f"{mode}: 30k-row spin-down click → result {min(analysis):.2f} s (best of 3; target ≤ 1.0 s); "
                  f"gains {min(gains):.2f} s (target ≤ 0.5 s); five changes one after another (the page's "
                  f"gains with curves) {max(changes):.2f} s the slowest, {sorted(changes)[2]:.2f} s the median")
        os.environ["MOTORLAB_UI_WARM"] = "1"
        _wait_for_spares()
        print(f"a short analysis beside two running sessions: {_beside_sessions(url, log, small):.2f} s")
        if not quick:
            body = _session_zip(8, folder / "eight")
            _wait_for_spares()
            table, report = _session_streamed(url, body)
            print(f"8-unit session: results table {table:.1f} s (target ≤ 10 s), "
                  f"report with its figures {report:.1f} s")
        print(f"load average {os.getloadavg()[0]:.1f} at the end")


if __name__ == "__main__":
    main()
