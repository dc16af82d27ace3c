"""Streamed answers (``Accept: application/x-ndjson``), cancelled requests, the fork server and the resident worker."""

from __future__ import annotations

import asyncio
import io
import json
import os
import signal
import time
import zipfile
from pathlib import Path
from typing import Any

import httpx
import pytest

from motorlab.ui import runner

STREAM = {"Accept": "application/x-ndjson"}


def _zip(folder: Path) -> bytes:
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w") as zf:
        for path in folder.rglob("*"):
            if path.is_file():
                zf.write(path, f"bench/{path.relative_to(folder)}")
    return buffer.getvalue()


@pytest.fixture
def forking() -> None:
    """The app's fork server ready: commands are forked from it, not run in a fresh Python."""
    assert runner.POOL.wait_ready(), "the fork server did not start"


def _lines(response: httpx.Response) -> list[dict[str, Any]]:
    assert response.headers["content-type"].startswith("application/x-ndjson")
    return [json.loads(line) for line in response.text.splitlines()]


def test_a_streamed_analysis_ends_with_exactly_the_plain_answer(server: Any, sim_session: Path) -> None:
    log = (sim_session / "A" / "spindown.txt").read_bytes()
    files = [("file", ("spindown.txt", log))]
    plain = httpx.post(f"{server.url}/api/analyze/spindown", files=files, data={"cpr": "1120"}, timeout=120)
    streamed = httpx.post(f"{server.url}/api/analyze/spindown", files=files, data={"cpr": "1120"}, headers=STREAM,
                          timeout=120)
    assert plain.status_code == streamed.status_code == 200
    lines = _lines(streamed)
    assert all(set(line) == {"progress"} for line in lines[:-1])
    assert lines[-1] == {"result": plain.json()}  # the CLI's --json, as one line

    bad = [("file", ("typo.txt", log.replace(b"\n1", b"\nx", 1) if b"\n1" in log else b"garbage"))]
    plain_bad = httpx.post(f"{server.url}/api/analyze/spindown", files=bad, data={"cpr": "1120"}, timeout=120)
    streamed_bad = httpx.post(f"{server.url}/api/analyze/spindown", files=bad, data={"cpr": "1120"}, headers=STREAM,
                              timeout=120)
    assert plain_bad.status_code == 400
    assert _lines(streamed_bad)[-1] == {"error": plain_bad.json()["error"], "status": 400}
    # Refused before any command runs: the plain 4xx answer, streamed or not.
    unknown = httpx.post(f"{server.url}/api/analyze/nope", files=files, headers=STREAM, timeout=60)
    assert unknown.status_code == 404
    assert "nope" in unknown.json()["error"]


def test_a_streamed_session_reports_its_units_then_its_results(server: Any, sim_session: Path) -> None:
    body = _zip(sim_session)
    plain = httpx.post(f"{server.url}/api/characterize", files=[("file", ("bench.zip", body))], timeout=300)
    streamed = httpx.post(f"{server.url}/api/characterize", files=[("file", ("bench.zip", body))], headers=STREAM,
                          timeout=300)
    assert plain.status_code == streamed.status_code == 200
    lines = _lines(streamed)
    progress = [line["progress"] for line in lines if "progress" in line]
    units = [p for p in progress if p["unit"] == "unit"]
    assert units, progress
    assert units[0]["total"] == 1
    assert set(units[0]) == {"what", "done", "total", "unit", "detail", "finished"}
    assert units[-1]["finished"]
    assert units[-1]["done"] == 1
    result = lines[-1]["result"]
    assert result["exit_code"] == 0
    assert _without_folder(result["results"]) == _without_folder(plain.json()["results"])
    assert result["csv"] == plain.json()["csv"]
    # Results first: the table came in a line of its own while the report's figures were being drawn.
    partial = [k for k, line in enumerate(lines) if "partial" in line]
    assert len(partial) == 1, [list(line) for line in lines]
    early = lines[partial[0]]["partial"]
    assert early["results"] == result["results"]
    assert early["csv"] == result["csv"]
    report = [k for k, line in enumerate(lines) if line.get("progress", {}).get("what") == "Drawing the report"]
    assert report
    assert report[-1] > partial[0]  # sections still drawn after the table was sent


def _without_folder(results: dict[str, Any]) -> str:
    """The results with the request's private folder (a new one per request) left out of its paths."""
    import re

    return re.sub(r"[^\"]*motorlab-ui-[^/\"]*/", "", json.dumps(results, sort_keys=True))


def _wait_until(condition: Any, seconds: float) -> bool:
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        if condition():
            return True
        time.sleep(0.02)
    return bool(condition())


@pytest.mark.parametrize("streamed", [True, False])
def test_a_client_that_goes_away_ends_its_command(server: Any, sim_session: Path, streamed: bool,
                                                  forking: None) -> None:
    import socket

    assert _wait_until(lambda: not runner.RUNNING, 120)
    request = httpx.Request("POST", f"{server.url}/api/characterize",
                            files=[("file", ("bench.zip", _zip(sim_session)))], headers=STREAM if streamed else {})
    head = "POST /api/characterize HTTP/1.1\r\n" + "".join(f"{k}: {v}\r\n" for k, v in request.headers.items())
    with socket.create_connection((server.host, server.port)) as sock:  # the page's fetch, then aborted
        sock.sendall(head.encode("latin-1") + b"\r\n" + request.read())
        assert _wait_until(lambda: bool(runner.RUNNING), 60), "the command did not start"
        children = set(runner.RUNNING)
    assert _wait_until(lambda: not runner.RUNNING, 5), "the command kept running after the client went away"
    assert all(child.wait(timeout=5) < 0 for child in children)  # ended by a signal, not finished


def test_the_time_limit_ends_a_forked_command(server: Any, sim_session: Path, monkeypatch: pytest.MonkeyPatch,
                                              forking: None) -> None:
    monkeypatch.setattr(runner, "SESSION_TIME_LIMIT", 0.5)  # a session takes seconds
    response = httpx.post(f"{server.url}/api/characterize", files=[("file", ("bench.zip", _zip(sim_session)))],
                          timeout=120)
    assert response.status_code == 422
    assert "0.5 s" in response.json()["error"]


def test_a_forked_command_answers_as_a_fresh_process(sim_session: Path, tmp_path: Path,
                                                     monkeypatch: pytest.MonkeyPatch, forking: None) -> None:
    (tmp_path / "lcr.csv").write_bytes((sim_session / "A" / "lcr.csv").read_bytes())
    argv = ["analyze", "lcr", "lcr.csv", "--json"]

    async def both() -> tuple[runner.Outcome, runner.Outcome]:
        forks = runner.POOL.forks
        warm = await runner.run_cli(argv, cwd=str(tmp_path))
        assert runner.POOL.forks == forks + 1  # forked, not a fresh Python
        monkeypatch.setenv("MOTORLAB_UI_WARM", "0")
        cold = await runner.run_cli(argv, cwd=str(tmp_path))
        assert runner.POOL.forks == forks + 1
        return warm, cold

    warm, cold = asyncio.run(both())
    assert warm.code == cold.code == 0
    assert warm.stdout == cold.stdout  # byte for byte
    assert warm.stderr == cold.stderr
    # An uploaded file named like a module is never imported (python -P: the folder is not on sys.path).
    (tmp_path / "json.py").write_text("raise SystemExit('imported an upload')\n")
    monkeypatch.delenv("MOTORLAB_UI_WARM")
    forks = runner.POOL.forks
    again = asyncio.run(runner.run_cli(argv, cwd=str(tmp_path)))
    assert runner.POOL.forks == forks + 1
    assert again.stdout == cold.stdout
    # A command that fails (a file that is not there) ends as the CLI does; the next one is forked as before.
    missing = asyncio.run(runner.run_cli(["analyze", "lcr", "nothing.csv", "--json"], cwd=str(tmp_path)))
    assert missing.code == 2
    assert "nothing.csv" in missing.error_line()
    assert asyncio.run(runner.run_cli(argv, cwd=str(tmp_path))).stdout == cold.stdout
    assert runner.POOL.forks == forks + 3


def test_where_commands_are_not_forked_a_spare_answers_as_a_fresh_process(sim_session: Path, tmp_path: Path,
                                                                         monkeypatch: pytest.MonkeyPatch) -> None:
    """Not Linux (``runner.FORKING`` false): spare Pythons started ahead, one taken per command (one spare here:
    each does the imports of a fork server, seconds of CPU)."""
    monkeypatch.setattr(runner, "FORKING", False)
    monkeypatch.setattr(runner, "SPARES", 1)
    (tmp_path / "lcr.csv").write_bytes((sim_session / "A" / "lcr.csv").read_bytes())
    argv = ["analyze", "lcr", "lcr.csv", "--json"]
    runner.POOL.fill()
    spares = list(runner.POOL._spares)
    try:
        assert len(spares) == runner.SPARES
        forks = runner.POOL.forks
        warm = asyncio.run(runner.run_cli(argv, cwd=str(tmp_path)))
        assert runner.POOL.forks == forks
        assert spares[0].poll() is not None  # taken, and ended after its one command
        assert spares[0] not in runner.POOL._spares  # (the test server's loop may have started the next one)
        monkeypatch.setenv("MOTORLAB_UI_WARM", "0")
        cold = asyncio.run(runner.run_cli(argv, cwd=str(tmp_path)))
        assert warm.code == cold.code == 0
        assert warm.stdout == cold.stdout
    finally:
        monkeypatch.setattr(runner, "SPARES", 0)  # no more started, by this thread or the test server's
        for proc in {*spares, *runner.POOL._spares}:
            runner.end(proc)
            proc.wait()
            for pipe in (proc.stdin, proc.stdout, proc.stderr):
                if pipe is not None:
                    pipe.close()
        runner.POOL._spares = []


def test_a_fork_server_that_has_gone_is_started_again(sim_session: Path, tmp_path: Path, forking: None) -> None:
    """Killed (as by the kernel's out-of-memory killer), the server is started again: meanwhile a command runs in
    a fresh Python, with the same answer."""
    (tmp_path / "lcr.csv").write_bytes((sim_session / "A" / "lcr.csv").read_bytes())
    argv = ["analyze", "lcr", "lcr.csv", "--json"]
    before = asyncio.run(runner.run_cli(argv, cwd=str(tmp_path)))
    server = runner.POOL.server
    assert server is not None
    os.kill(server.pid, signal.SIGKILL)
    assert _wait_until(lambda: not runner.POOL.ready, 10)
    forks = runner.POOL.forks
    meanwhile = asyncio.run(runner.run_cli(argv, cwd=str(tmp_path)))
    assert runner.POOL.forks == forks  # a fresh Python
    assert meanwhile.stdout == before.stdout
    assert runner.POOL.wait_ready()
    assert runner.POOL.server is not server
    again = asyncio.run(runner.run_cli(argv, cwd=str(tmp_path)))
    assert runner.POOL.forks == forks + 1
    assert again.stdout == before.stdout


def _group(pgid: int) -> list[int]:
    """The processes of a process group (Linux's /proc; zombies not counted)."""
    found = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except (OSError, IndexError):
            continue
        if int(fields[2]) == pgid and fields[0] != "Z":
            found.append(int(stat.parent.name))
    return found


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="reads the process table from /proc")
def test_ending_a_session_ends_the_processes_analysing_its_units(tmp_path: Path, forking: None) -> None:
    from motorlab.session.simulated import write_simulated_session

    toml = write_simulated_session("neverest40", out_dir=tmp_path, units=2, seed=4,
                                   experiments=("identify", "feedforward"))
    started: list[Any] = []
    start = runner._start

    def keep(*args: Any) -> Any:
        started.append(start(*args))
        return started[-1]

    async def run_then_cancel() -> list[int]:
        task = asyncio.ensure_future(runner.run_cli(["characterize", str(toml), "--quiet", "--processes=2"],
                                                    cwd=str(tmp_path), slot="session"))
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and not (started and len(_group(started[0].pid)) >= 3):
            await asyncio.sleep(0.05)
        members = _group(started[0].pid)
        task.cancel()  # as when the client goes away
        with pytest.raises(asyncio.CancelledError):
            await task
        return members

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(runner, "_start", keep)
        members = asyncio.run(run_then_cancel())
    assert len(members) >= 3, "the session's units were not analysed in processes of their own"
    # At once: without ending the group, each would finish the unit it is analysing (seconds) first.
    assert _wait_until(lambda: not _group(started[0].pid), 1.0), "processes of the session outlived it"


def test_gains_are_recomputed_in_one_resident_worker(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    argv = ["tune", "velocity", "--kv=0.12", "--ka=0.01", "--ks=0.3", "--target=roadrunner", "--cpr=8192",
            "--emit=java", "--json"]

    async def changes() -> tuple[list[runner.Outcome], int, runner.Outcome, runner.Outcome]:
        worker = runner.resident()
        await worker.start()
        assert worker.ready
        started = runner.POOL.started
        before = worker.jobs  # the one resident worker of this process may have served other tests already
        answers = [await runner.run_cli([*argv[:2], f"--kv={kv}", *argv[3:]], cwd=str(tmp_path))
                   for kv in (0.12, 0.13, 0.14)]
        assert runner.POOL.started == started  # no new process for a change of the gains
        jobs = worker.jobs - before
        refused = await runner.run_cli([*argv, "--cpr=-3"], cwd=str(tmp_path))  # the CLI's refusal, as text
        monkeypatch.setenv("MOTORLAB_UI_WARM", "0")  # a fresh `python -m motorlab`, the resident left alone
        fresh = await runner.run_cli([*argv[:2], "--kv=0.14", *argv[3:]], cwd=str(tmp_path))
        assert worker.jobs == before + jobs + 1  # the refusal only
        worker.close()
        return answers, jobs, refused, fresh

    answers, jobs, refused, fresh = asyncio.run(changes())
    assert jobs == 3
    assert all(a.code == 0 for a in answers)
    kv = [json.loads(a.stdout)["feedforward"]["kV"] for a in answers]
    assert kv == sorted(set(kv))  # each change answered with its own gains
    assert answers[-1].stdout == fresh.stdout  # byte for byte what a fresh `motorlab tune` prints
    assert refused.code == 2
    assert "cpr" in refused.error_line()


def test_a_resident_job_past_its_time_limit_ends_the_worker(tmp_path: Path) -> None:
    """The worker is paused (SIGSTOP) so that its job cannot answer within the limit, whatever the load: a
    0.1 ms limit on a job that answers in milliseconds lost the race when the event loop itself was held up
    (CI, 2 cores busy)."""

    async def late() -> tuple[runner.Outcome, bool]:
        worker = runner.resident()
        await worker.start()
        assert worker.ready
        proc = worker.proc
        assert proc is not None
        os.kill(proc.pid, signal.SIGSTOP)
        try:
            outcome = await runner.run_cli(["tune", "velocity", "--kv=0.12", "--json"], cwd=str(tmp_path),
                                           time_limit=0.5)
            ended = proc.poll() is not None
        finally:
            worker.close()  # SIGKILL: ends a stopped process too
        return outcome, ended

    outcome, ended = asyncio.run(late())
    assert outcome.code == 124
    assert ended


def test_one_resident_worker_whatever_the_event_loops() -> None:
    async def ready() -> Any:
        await runner.resident().start()
        return runner.resident().proc

    first, second = asyncio.run(ready()), asyncio.run(ready())  # a harness may make an event loop per request
    assert first is second
    assert first is not None
    assert first.poll() is None
    runner.resident().close()
    assert first.poll() is not None


@pytest.mark.skipif(not runner.FORKING, reason="commands are forked on Linux only")
def test_the_resident_worker_is_forked_by_the_fork_server(tmp_path: Path, forking: None) -> None:
    """Its imports are the fork server's (a Python of its own imported everything again: seconds of CPU at every
    start of the app); it is no command (the commands forked are counted apart) and answers as a fresh command."""
    runner.resident().close()
    forks, started = runner.POOL.forks, runner.POOL.started

    async def answer() -> tuple[Any, runner.Outcome]:
        await runner.resident().start()
        proc = runner.resident().proc
        return proc, await runner.run_cli(["tune", "velocity", "--kv=0.12", "--ka=0.01", "--json"], cwd=str(tmp_path))

    jobs = runner.resident().jobs
    proc, outcome = asyncio.run(answer())
    assert isinstance(proc, runner.Forked)
    assert (runner.POOL.forks, runner.POOL.started) == (forks, started + 1)
    assert runner.resident().jobs == jobs + 1
    assert outcome.code == 0
    assert json.loads(outcome.stdout)["feedforward"]["kV"] == pytest.approx(0.12)
    runner.resident().close()
    assert proc.poll() is not None  # ended, and its end reported by the fork server
