"""The HTTP API answers as the CLI does, refuses hostile input with 4xx JSON and keeps serving."""

from __future__ import annotations

import concurrent.futures
import contextlib
import io
import json
import logging
import os
import shutil
import subprocess
import sys
import time
import zipfile
from pathlib import Path
from typing import Any

import httpx
import pytest

from motorlab import cli
from motorlab.ui.schema import schema
from motorlab.ui.uploads import safe_relative


def _cli(argv: list[str], cwd: Path) -> tuple[int, str, str]:
    """``motorlab argv`` in-process, in ``cwd``: exit code, stdout, stderr."""
    out, err = io.StringIO(), io.StringIO()
    previous = os.getcwd()
    os.chdir(cwd)
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                code = cli.main(argv)
            except SystemExit as exc:
                code = int(exc.code or 0)
    finally:
        os.chdir(previous)
    return code, out.getvalue(), err.getvalue()


def _alive(server: Any) -> None:
    response = httpx.get(f"{server.url}/api/schema", timeout=10)
    assert response.status_code == 200
    assert "spindown" in response.json()["analyze"]


def test_spindown_posted_gives_exactly_the_cli_json(server: Any, sim_session: Path, truth: dict[str, Any],
                                                    tmp_path: Path) -> None:
    log = sim_session / "A" / "spindown.txt"
    with open(log, "rb") as handle:
        response = httpx.post(f"{server.url}/api/analyze/spindown", files=[("file", ("spindown.txt", handle))],
                              data={"cpr": "1120"}, timeout=120)
    assert response.status_code == 200, response.text
    shutil.copy(log, tmp_path / "spindown.txt")
    code, out, _err = _cli(["analyze", "spindown", "spindown.txt", "--cpr=1120", "--json"], tmp_path)
    assert code == 0
    assert response.text == out  # byte for byte
    k = response.json()["parameters"]["K"]
    assert abs(k["value"] - truth["runs"]["spindown.txt"]["params"]["K"]) < 4 * k["stderr"]


def test_option_with_unit_and_the_cli_refusal(server: Any, sim_session: Path, tmp_path: Path) -> None:
    log = (sim_session / "A" / "spindown.txt").read_bytes()
    ok = httpx.post(f"{server.url}/api/analyze/spindown", files=[("file", ("s.txt", log))],
                    data={"cpr": "1120", "inertia": "0.0149 kg*m^2"}, timeout=120)
    assert ok.status_code == 200, ok.text
    assert ok.json()["parameters"]["J"]["value"] == pytest.approx(0.0149)
    (tmp_path / "s.txt").write_bytes(log)
    for field, value in [("cpr", "0"), ("cpr", "-1120"), ("cpr", "abc"), ("inertia", "12 A"), ("no-such", "1")]:
        bad = httpx.post(f"{server.url}/api/analyze/spindown", files=[("file", ("s.txt", log))],
                         data={"cpr": "1120", field: value}, timeout=120)
        assert bad.status_code == 400, (field, value, bad.text)
        code, _out, err = _cli(["analyze", "spindown", "s.txt", "--cpr=1120", f"--{field}={value}", "--json"], tmp_path)
        assert code == 2
        assert bad.json() == {"error": err.strip().splitlines()[-1].split(": error: ", 1)[1]}


HOSTILE = {
    "random-bytes": os.urandom(4096),
    "empty": b"",
    "nul-text": b"time,position\n0,\x00\x00\n",
    "one-line": b"time\n",
    "long-line": b"1," * 200_000,
    "html": b"<html><script>alert(1)</script></html>",
    "nan": b"time [s],position [rad],current [A]\n0,nan,1\n1,inf,1\n2,1e308,1\n",
}


@pytest.mark.parametrize("name", sorted(HOSTILE))
def test_hostile_file_gets_a_4xx_json_error(server: Any, name: str) -> None:
    response = httpx.post(f"{server.url}/api/analyze/spindown", files=[("file", (f"{name}.txt", HOSTILE[name]))],
                          data={"cpr": "1120"}, timeout=120)
    assert 400 <= response.status_code < 500, response.text
    error = response.json()["error"]
    assert "\n" not in error
    assert "Traceback" not in error
    assert "motorlab-ui-" not in error  # the temporary folder is not shown; the file is named as uploaded
    _alive(server)


def test_file_names_stay_inside_the_private_folder(server: Any, tmp_path: Path,
                                                  monkeypatch: pytest.MonkeyPatch) -> None:
    import tempfile

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path / "tmp"))  # not /tmp: other test runs share it
    (tmp_path / "tmp").mkdir()
    before = set(os.listdir(tempfile.gettempdir()))
    names = ["../../escape.txt", "/etc/passwd", "..\\..\\win.txt", "a/../../b.txt", "..", ""]
    files = [("file", (n, b"time,position\n")) for n in names]
    response = httpx.post(f"{server.url}/api/detect", files=files, timeout=120)
    assert response.status_code == 200, response.text
    shown = [entry["file"] for entry in response.json()]
    assert all(".." not in s and "/" not in s for s in shown)
    after = set(os.listdir(tempfile.gettempdir()))
    assert not {n for n in after - before if n.startswith("motorlab-ui-")}  # removed afterwards
    assert not (Path(tempfile.gettempdir()).parent / "escape.txt").exists()
    assert safe_relative("../../x/../y.txt") == Path("x/y.txt")
    assert safe_relative("C:\\..\\a.csv") == Path("C_/a.csv")
    assert safe_relative("..") == Path("upload")


def test_upload_limit_and_unknown_experiment(server: Any) -> None:
    big = httpx.post(f"{server.url}/api/analyze/lcr", files=[("file", ("big.csv", b"0" * (3 * 2**20)))], timeout=60)
    assert big.status_code == 413  # the test servers take 2 MB
    assert "MB" in big.json()["error"]
    unknown = httpx.post(f"{server.url}/api/analyze/nope", files=[("file", ("a.csv", b"1"))], timeout=60)
    assert unknown.status_code == 404
    assert "nope" in unknown.json()["error"]
    output = httpx.post(f"{server.url}/api/analyze/lcr", files=[("file", ("a.csv", b"1"))],
                        data={"plot": "/tmp/x.png"}, timeout=60)
    assert output.status_code == 400
    assert "--plot" in output.json()["error"]
    _alive(server)


def test_host_header_guard(server: Any) -> None:
    for host in ("evil.example", f"evil.example:{server.port}", "127.0.0.1:1", f"127.0.0.1.nip.io:{server.port}"):
        response = httpx.get(f"{server.url}/api/schema", headers={"Host": host}, timeout=10)
        assert response.status_code == 403, host
        assert "Host" in response.json()["error"]
    for host in (f"127.0.0.1:{server.port}", f"localhost:{server.port}"):
        page = httpx.get(f"{server.url}/", headers={"Host": host}, timeout=10)
        assert page.status_code == 200
        assert "default-src 'self'" in page.headers["content-security-policy"]  # nothing from another host
        assert "http" not in page.text.split("<body>")[0]  # scripts and styles by relative URLs


def test_token_when_served_beyond_loopback(start_server: Any) -> None:
    served = start_server(token="s3cret-token")
    assert httpx.get(f"{served.url}/api/schema", timeout=10).status_code == 403
    assert httpx.get(f"{served.url}/api/schema?token=wrong", timeout=10).status_code == 403
    page = httpx.get(f"{served.url}/?token=s3cret-token", timeout=10)
    assert page.status_code == 200
    cookie = page.headers["set-cookie"]
    assert "HttpOnly" in cookie
    with_cookie = httpx.get(f"{served.url}/api/schema", cookies={"motorlab_token": "s3cret-token"}, timeout=10)
    assert with_cookie.status_code == 200


def test_twenty_concurrent_requests_leave_it_responsive(server: Any, sim_session: Path) -> None:
    lcr = (sim_session / "A" / "lcr.csv").read_bytes()
    bodies = [lcr if k % 2 else HOSTILE["random-bytes"] for k in range(20)]

    def post(body: bytes) -> int:
        return httpx.post(f"{server.url}/api/analyze/lcr", files=[("file", ("lcr.csv", body))], timeout=300).status_code

    with concurrent.futures.ThreadPoolExecutor(20) as pool:
        futures = [pool.submit(post, body) for body in bodies]
        # Once the app has answered one of the twenty, the others are in its hands: a blocked event loop would
        # answer this request only after them all. Not a timing: it holds on a fast machine and a loaded one.
        concurrent.futures.wait(futures, timeout=300, return_when=concurrent.futures.FIRST_COMPLETED)
        _alive(server)  # served while the others wait for their child processes
        waiting = sum(not f.done() for f in futures)
        codes = [f.result() for f in futures]
    assert waiting > 0, "the app answered only after all twenty analyses had ended"
    assert codes == [200 if k % 2 else 400 for k in range(20)]


def test_whole_session_from_a_zip(server: Any, sim_session: Path) -> None:
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w") as zf:
        for path in sim_session.rglob("*"):
            if path.is_file():
                zf.write(path, f"bench/{path.relative_to(sim_session)}")
    response = httpx.post(f"{server.url}/api/characterize", files=[("file", ("bench.zip", buffer.getvalue()))],
                          timeout=300)
    assert response.status_code == 200, response.text
    body = response.json()
    assert body["exit_code"] == 0
    assert body["results"]["units"]["A"]["status"] == "ok"
    assert body["csv"].splitlines()[0].startswith("unit")
    assert "<html" in body["report_html"].lower()
    refused = httpx.post(f"{server.url}/api/characterize", files=[("file", ("a.csv", b"1"))], timeout=60)
    assert refused.status_code == 400
    assert "session" in refused.json()["error"]


def test_tune_gives_the_cli_json_and_snippet(server: Any, tmp_path: Path) -> None:
    fields = {"loop": "velocity", "kv": "1.2", "ka": "0.1", "ks": "0.3", "target": "ftc-pidf", "cpr": "1120",
              "emit": "java"}
    response = httpx.post(f"{server.url}/api/tune", data=fields, timeout=120)
    assert response.status_code == 200, response.text
    argv = ["tune", "velocity", *[f"--{k}={v}" for k, v in fields.items() if k != "loop"], "--json"]
    code, out, _err = _cli(argv, tmp_path)
    assert code == 0
    assert response.text == out
    assert "class" in response.json()["snippet"] or "double" in response.json()["snippet"]
    bad = httpx.post(f"{server.url}/api/tune", data={"loop": "velocity"}, timeout=120)
    assert bad.status_code == 400
    assert "--kv" in bad.json()["error"]


def test_schema_is_the_descriptions_and_agrees_with_the_cli_parsers() -> None:
    s = schema()
    spindown = {f["name"]: f for f in s["analyze"]["spindown"]["fields"]}
    assert spindown["guard"]["unit"] == "s"
    assert spindown["guard"]["default"] == 0.1
    assert spindown["files"]["required"]
    assert spindown["cpr"]["label"] == "Encoder counts per revolution"
    assert spindown["inertia"]["label"] == "Flywheel moment of inertia"
    tune = {f["name"]: f for f in s["tune"]["fields"]}
    assert tune["target"]["choices"][:2] == ["volts", "wpilib"]
    assert tune["params"]["kind"] == "file"
    assert "json" not in tune
    assert "plot" not in spindown
    assert s["parameters"]["K"] == {"name": "Back-EMF constant", "symbol": "K", "unit": "V*s/rad"}
    assert [t["key"] for t in s["targets"]] == tune["target"]["choices"]
    json.dumps(s, allow_nan=False)
    # Words everywhere a person reads: a label on every field, no flag, seed or repeated default in the help.
    for command, fields in [*((f"analyze {n}", e["fields"]) for n, e in s["analyze"].items()),
                            ("tune", s["tune"]["fields"]), ("characterize", s["characterize"]["fields"])]:
        for f in fields:
            assert f["label"], (command, f["name"])
            assert "--" not in f["label"], (command, f["name"])
            for bad in ("--", "seed ", "(default"):
                assert bad not in f["help"], (command, f)
            assert "--" not in (f["group"] or ""), (command, f["group"])
    for e in s["analyze"].values():
        assert "seed " not in e["description"]
        assert all(key in s["parameters"] for key in e["reports"])
    # The CLI's parsers are generated from the same descriptions: the same options, defaults and choices.
    import argparse

    parser = cli.build_parser()
    commands = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction)).choices

    def options(p: argparse.ArgumentParser) -> dict[str, argparse.Action]:
        return {(a.option_strings[0] if a.option_strings else a.dest): a for a in p._actions
                if a.dest not in {"help", "json", "plot", "each", "emit", "output", "quiet", "no_report",
                                  "processes"}}

    analyze = next(a for a in commands["analyze"]._actions if isinstance(a, argparse._SubParsersAction)).choices
    pairs = [(options(analyze[n]), s["analyze"][n]["fields"]) for n in s["analyze"]]
    pairs += [(options(commands[c]), s[c]["fields"]) for c in ("tune", "characterize")]
    for actions, fields in pairs:
        assert set(actions) == {f["option"] or f["dest"] for f in fields}
        for f in fields:
            action = actions[f["option"] or f["dest"]]
            assert (list(action.choices) if action.choices else None) == f["choices"]
            if f["kind"] not in ("flag", "file"):
                assert action.default == f["default"], f["name"]


def test_time_limit_ends_the_command(server: Any, sim_session: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from motorlab.ui import runner

    # Shorter than any command's run (a forked LCR analysis answered within 0.05 s): the command is started, then
    # ended by the limit.
    monkeypatch.setattr(runner, "TIME_LIMIT", 1e-6)
    with open(sim_session / "A" / "lcr.csv", "rb") as handle:
        response = httpx.post(f"{server.url}/api/analyze/lcr", files=[("file", ("lcr.csv", handle))], timeout=60)
    assert response.status_code == 422
    assert "1e-06 s" in response.json()["error"]
    monkeypatch.undo()
    _alive(server)


def _start_ui(*args: str) -> tuple[subprocess.Popen[str], str]:
    """``motorlab ui --no-browser ARGS`` in a child process: the process and the line with its URL."""
    port = socket_port()
    proc = subprocess.Popen(  # no fork server (3 s of CPU importing): these tests run no command
        [sys.executable, "-m", "motorlab", "ui", "--no-browser", "--port", str(port), *args],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env={**os.environ, "MOTORLAB_UI_WARM": "0"},
    )
    assert proc.stdout is not None
    line = proc.stdout.readline()
    return proc, line


def socket_port() -> int:
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def test_ui_command_prints_its_url_and_serves() -> None:
    proc, line = _start_ui()
    try:
        url = line.split()[2]
        assert url.startswith("http://127.0.0.1:")
        deadline = time.monotonic() + 30
        while True:
            try:
                page = httpx.get(url, timeout=5)
                break
            except httpx.ConnectError:
                assert time.monotonic() < deadline
                time.sleep(0.1)
        assert page.status_code == 200
        assert 'static/js/main.js' in page.text  # the page's entry module
    finally:
        proc.terminate()
        proc.communicate(timeout=20)  # closes the pipes too


def test_ui_beyond_loopback_warns_and_wants_the_token() -> None:
    proc, line = _start_ui("--host", "0.0.0.0")
    try:
        url = line.split()[2]
        assert "?token=" in url
        assert proc.stderr is not None
        assert "warning" in proc.stderr.readline()
        port = url.split(":")[2].split("/")[0]
        deadline = time.monotonic() + 30
        while True:
            try:
                refused = httpx.get(f"http://127.0.0.1:{port}/", headers={"Host": f"0.0.0.0:{port}"}, timeout=5)
                break
            except httpx.ConnectError:
                assert time.monotonic() < deadline
                time.sleep(0.1)
        assert refused.status_code == 403
        token = url.split("?token=")[1]
        ok = httpx.get(f"http://127.0.0.1:{port}/?token={token}", headers={"Host": f"0.0.0.0:{port}"}, timeout=5)
        assert ok.status_code == 200
        # Bound to every interface, other machines name it by an address of theirs: the token guards.
        lan_host = {"Host": f"192.0.2.7:{port}"}
        lan = httpx.get(f"http://127.0.0.1:{port}/?token={token}", headers=lan_host, timeout=5)
        assert lan.status_code == 200
        assert httpx.get(f"http://127.0.0.1:{port}/", headers=lan_host, timeout=5).status_code == 403
    finally:
        proc.terminate()
        proc.communicate(timeout=20)  # closes the pipes too


def test_the_cli_hostile_cases_through_the_api(server: Any) -> None:
    """Cases of tests/cli/test_hostile_input.py, posted: the CLI's refusal comes back as 400 JSON."""
    deep = b"[" * 100_000 + b"]" * 100_000
    nested = httpx.post(f"{server.url}/api/analyze/feedforward", files=[("file", ("deep.json", deep))], timeout=120)
    assert nested.status_code == 400
    assert "nested too deeply" in nested.json()["error"]
    params = httpx.post(f"{server.url}/api/tune", data={"loop": "velocity"},
                        files=[("params", ("deep.json", deep))], timeout=120)
    assert params.status_code == 400
    assert "nested too deeply" in params.json()["error"]
    typed_path = httpx.post(f"{server.url}/api/tune", data={"loop": "velocity", "params": "/etc/passwd"}, timeout=60)
    assert typed_path.status_code == 400  # file options take uploads, never a path on the server
    assert "upload" in typed_path.json()["error"]
    for kv, ka in [("1", "1e308"), ("1e-300", "1"), ("1e300", "1e300")]:
        absurd = httpx.post(f"{server.url}/api/tune", data={"loop": "velocity", "kv": kv, "ka": ka}, timeout=120)
        assert absurd.status_code == 400, absurd.text
    _alive(server)


def test_forms_no_command_line_can_carry_get_4xx_json(server: Any, caplog: pytest.LogCaptureFixture) -> None:
    """A NUL byte in a field or its name, a body that is no form, a multipart body that is no multipart.

    The server's log stays quiet about the bodies that are no form (the 400 says it to the client).
    """
    caplog.set_level(logging.WARNING)
    url = f"{server.url}/api/analyze/spindown"
    urlencoded = {"Content-Type": "application/x-www-form-urlencoded"}
    cases = [
        httpx.post(url, content=b"cpr=1%002", headers=urlencoded, timeout=60),
        httpx.post(url, content=b"c%00pr=1", headers=urlencoded, timeout=60),
        httpx.post(f"{server.url}/api/tune", data={"loop": "velocity", "kv": "1\x00"}, timeout=60),
        httpx.post(url, content=bytes(range(256)) * 4, headers={"Content-Type": "multipart/form-data; boundary=xyz"},
                   timeout=60),
        httpx.post(url, content=b"--xyz\r\n", headers={"Content-Type": "multipart/form-data"}, timeout=60),
    ]
    for response in cases:
        assert 400 <= response.status_code < 500, response.text
        assert response.headers["content-type"].startswith("application/json")
        assert "\n" not in response.json()["error"]
    assert "NUL" in cases[0].json()["error"]
    noise = [r.getMessage() for r in caplog.records if r.name.startswith("python_multipart")]
    assert noise == [], noise
    _alive(server)


def test_detect_proposes_the_experiment_a_header_declares(server: Any, tmp_path: Path) -> None:
    """The rig's transient log (position and current) is identify's, as its header says, not a spin-down."""
    from motorlab.rig import VirtualRig

    run = VirtualRig("neverest20", unit_seed=0, noise_seed=1).transient(tmp_path / "transient.csv", duration=0.5)
    with open(run.paths[0], "rb") as handle:
        response = httpx.post(f"{server.url}/api/detect", files=[("file", ("transient.csv", handle))], timeout=120)
    assert response.status_code == 200, response.text
    assert response.json()[0]["experiment"] == "identify"
