"""``motorlab robot pull`` against the emulated robot: byte for byte, proposals, and bad networks."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from motorlab.cli import main
from motorlab.robot.emulator import EmulatedRobot, RobotFiles

#: The emulated robot runs on the wall clock: make test runs these beside the others (the Makefile).
pytestmark = pytest.mark.realtime


def _pull(robot: EmulatedRobot, out: Path, *extra: str) -> int:
    return main(["robot", "pull", "--host", "127.0.0.1", "--http-port", str(robot.http_port), "-o", str(out), *extra])


def test_pull_brings_back_every_reachable_file_byte_for_byte(
        robot: EmulatedRobot, robot_files: RobotFiles, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "pulled"
    assert _pull(robot, out, "--json") == 0
    result = json.loads(capsys.readouterr().out)
    newest_forward = max(robot_files.tuning["forward-ramp"], key=lambda p: p.stat().st_mtime)
    lateral = robot_files.tuning["lateral-ramp"][0]
    expected = {
        out / "tuning" / "forward-ramp" / newest_forward.name: newest_forward,
        out / "tuning" / "lateral-ramp" / lateral.name: lateral,
        out / "logs" / robot_files.logs[0].name: robot_files.logs[0],
        out / "motorlab" / robot_files.motorlab[0].name: robot_files.motorlab[0],
    }
    for pulled, original in expected.items():
        assert pulled.read_bytes() == original.read_bytes(), pulled
    written = sorted(p for p in out.rglob("*") if p.is_file())
    assert written == sorted(expected)  # nothing else (no temporary file left), the older ramp unreachable
    by_name = {Path(f["path"]).name: f for f in result["files"]}
    assert by_name[newest_forward.name]["format"] == "roadrunner-ramp"
    assert by_name[newest_forward.name]["experiment"] == "feedforward"
    assert "--cpr" in by_name[newest_forward.name]["command"]
    assert by_name[robot_files.logs[0].name]["format"] == "roadrunner-log"
    assert by_name[robot_files.motorlab[0].name]["experiment"] == "spindown"
    assert result["missing"] == []
    assert {host for host, _ in robot.http_requests} == {"127.0.0.1"}

    # A second pull keeps what is there and says so.
    assert _pull(robot, out) == 0
    assert capsys.readouterr().out.count("already there") == 4


def test_no_robot_is_one_line_and_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    with EmulatedRobot(lifetime=5) as gone:
        port = gone.http_port
    assert main(["robot", "pull", "--host", "127.0.0.1", "--http-port", str(port), "-o", str(tmp_path / "x")]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err
    assert "connection refused" in err
    assert "--host" in err
    assert not (tmp_path / "x").exists()


def test_robot_without_road_runner_or_motorlab(robot_files: RobotFiles, tmp_path: Path,
                                                capsys: pytest.CaptureFixture[str]) -> None:
    with EmulatedRobot(robot_files, road_runner=False, motorlab_handler=False, dashboard=False, lifetime=20) as bare:
        assert _pull(bare, tmp_path / "a") == 2
    err = capsys.readouterr().err.strip()
    assert "neither Road Runner's files nor motorlab's logs" in err
    assert "\n" not in err
    with EmulatedRobot(robot_files, road_runner=False, dashboard=False, lifetime=20) as ours_only:
        assert _pull(ours_only, tmp_path / "b") == 0
    out = capsys.readouterr().out
    assert "no Road Runner tuning files" in out
    assert "no FlightRecorder log list" in out
    ours = robot_files.motorlab[0]
    assert (tmp_path / "b" / "motorlab" / ours.name).read_bytes() == ours.read_bytes()


@pytest.mark.parametrize("cut", [0, 1000, 70000])
def test_wifi_dropped_mid_download_leaves_nothing_half_written(robot_files: RobotFiles, tmp_path: Path,
                                                               capsys: pytest.CaptureFixture[str], cut: int) -> None:
    """Every download cut after ``cut`` bytes: what is shorter arrives whole, what is longer is named (one line
    each, "pull again") and leaves nothing behind; exit 3 (partial), or 2 when nothing arrived."""
    out = tmp_path / "pulled"
    with EmulatedRobot(robot_files, drop_after=cut, dashboard=False, lifetime=20) as flaky:
        code = _pull(flaky, out)
    served = [*robot_files.logs, *robot_files.motorlab,
              *(max(f, key=lambda p: p.stat().st_mtime) for f in robot_files.tuning.values())]
    whole = [f for f in served if f.stat().st_size <= cut]
    assert code == (3 if whole else 2)
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == len(served) - len(whole) if whole else len(err) == 1
    assert all("pull again" in line for line in err)
    kept = sorted(p.name for p in out.rglob("*") if p.is_file()) if out.exists() else []
    assert kept == sorted(f.name for f in whole)
    for f in whole:
        assert next(out.rglob(f.name)).read_bytes() == f.read_bytes()


def test_output_that_is_a_file_is_refused(robot: EmulatedRobot, tmp_path: Path,
                                          capsys: pytest.CaptureFixture[str]) -> None:
    target = tmp_path / "file.txt"
    target.write_text("keep me")
    assert _pull(robot, target) == 2
    assert "not a folder" in capsys.readouterr().err
    assert target.read_text() == "keep me"


def test_a_half_written_file_on_the_robot_comes_back_as_it_is(tmp_path: Path,
                                                              capsys: pytest.CaptureFixture[str]) -> None:
    """A ramp file cut short on the robot (the OpMode killed while saving) is pulled byte for byte and named as
    not readable, with the reader's reason; nothing is repaired or dropped."""
    folder = tmp_path / "sdcard"
    folder.mkdir()
    cut = folder / "1732521600000.json"
    cut.write_bytes(b'{\n  "type" : "MECANUM",\n  "forwardEncPositions" : [ {\n    "times" : [ 0.01, 0.02')
    with EmulatedRobot(RobotFiles({"forward-ramp": [cut]}), dashboard=False, lifetime=20) as robot:
        assert _pull(robot, tmp_path / "out", "--json") == 0
    entry = json.loads(capsys.readouterr().out)["files"][0]
    assert (tmp_path / "out" / "tuning" / "forward-ramp" / cut.name).read_bytes() == cut.read_bytes()
    assert entry["command"] is None
    assert "not" in entry["note"]


@pytest.fixture
def odd_sdcard(tmp_path: Path, robot_files: RobotFiles) -> RobotFiles:
    """The robot's files plus FlightRecorder logs with names Road Runner serves as they are ($, é, a literal
    %41) and names its /logs/download cannot be asked for (a space, an &)."""
    folder = tmp_path / "logs"
    folder.mkdir()
    names = ["2026_11_25__10_31_07_123__Auto$Blue.log", "2026_11_25__10_40_00_000__Départ.log",
             "2026_11_25__10_41_00_000__Odd%41.log", "2026_11_25__10_42_00_000__Two Words.log",
             "2026_11_25__10_43_00_000__A&B.log"]
    logs = []
    for k, name in enumerate(names):
        (folder / name).write_bytes(bytes(range(256)) * (k + 3))
        logs.append(folder / name)
    return RobotFiles(robot_files.tuning, [*robot_files.logs, *logs], robot_files.motorlab)


def test_odd_log_names_come_byte_for_byte_and_the_unaskable_are_named(
        odd_sdcard: RobotFiles, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "pulled"
    with EmulatedRobot(odd_sdcard, dashboard=False, lifetime=20) as robot:
        assert _pull(robot, out) == 3
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 2
    assert "Two Words.log" in err[0] + err[1]
    assert "A&B.log" in err[0] + err[1]
    assert all("copy it by USB" in line for line in err)
    unaskable = {"2026_11_25__10_42_00_000__Two Words.log", "2026_11_25__10_43_00_000__A&B.log"}
    for f in odd_sdcard.logs:
        pulled = out / "logs" / f.name
        assert pulled.exists() == (f.name not in unaskable), f.name
        if f.name not in unaskable:
            assert pulled.read_bytes() == f.read_bytes(), f.name
    assert (out / "motorlab" / odd_sdcard.motorlab[0].name).read_bytes() == odd_sdcard.motorlab[0].read_bytes()
    # Asked for as Road Runner reads them: the raw name, never percent-encoded (it would look for "%24").
    asked = [path for _, path in robot.http_requests if path.startswith("/logs/download")]
    assert "/logs/download?file=2026_11_25__10_31_07_123__Auto$Blue.log" in asked
    assert "/logs/download?file=2026_11_25__10_40_00_000__Départ.log" in asked


@pytest.mark.parametrize("failure", ["closed", "500"])
def test_a_robot_without_a_log_folder_still_gives_every_other_file(
        robot_files: RobotFiles, tmp_path: Path, capsys: pytest.CaptureFixture[str], failure: str) -> None:
    """Road Runner's /logs throws on a robot without /sdcard/RoadRunner/logs (``LOG_ROOT.listFiles()!!``): the
    connection closes without an answer (or a server answers 500); one line, exit 3, the rest byte for byte."""
    out = tmp_path / "pulled"
    with EmulatedRobot(robot_files, log_folder=False, logs_failure=failure, dashboard=False, lifetime=20) as robot:
        assert _pull(robot, out, "--json") == 3
    captured = capsys.readouterr()
    err = captured.err.strip().splitlines()
    assert len(err) == 1
    assert "/logs" in err[0]
    assert ("without an answer" if failure == "closed" else "HTTP 500") in err[0]
    result = json.loads(captured.out)
    assert result["failed"] == [err[0].removeprefix("motorlab: not pulled: ")]
    expected = [*robot_files.motorlab, *(max(f, key=lambda p: p.stat().st_mtime) for f in robot_files.tuning.values())]
    assert sorted(p.name for p in out.rglob("*") if p.is_file()) == sorted(f.name for f in expected)
    for f in expected:
        assert next(out.rglob(f.name)).read_bytes() == f.read_bytes()


@pytest.mark.parametrize("name", ["plain.log", 'quote".log', "angle<b>.log", 'x" download="y">z.log', "é$%#?.log"])
def test_the_logs_page_is_read_exactly_whatever_the_name(name: str) -> None:
    """Road Runner writes each name three times, not escaped (FileServing.kt:155-164): solved exactly."""
    from motorlab.robot.pull import log_entries

    entry = f'<li><a href="/logs/download?file={name}" download="{name}">{name}</a> (123 bytes)</li>'
    page = f"<!doctype html><html><head><title>Logs</title></head><body><ul>{entry}{entry}</ul></body></html>"
    assert log_entries(page) == [(name, 123), (name, 123)]


def test_each_file_not_pulled_is_named_with_its_reason_and_what_to_do(robot_files: RobotFiles, tmp_path: Path) -> None:
    """What the app lists (``not_pulled``): the file's name, why in words (no route, no address) and what to do;
    the CLI's line for it unchanged (``failed``). The Wi-Fi drops after the smallest file's size."""
    from motorlab.robot.pull import pull

    served = [*robot_files.logs, *robot_files.motorlab,
              *(max(f, key=lambda p: p.stat().st_mtime) for f in robot_files.tuning.values())]
    cut = min(f.stat().st_size for f in served)
    with EmulatedRobot(robot_files, drop_after=cut, dashboard=False, lifetime=20) as flaky:
        result = pull("127.0.0.1", tmp_path / "pulled", http_port=flaky.http_port).to_dict()
    named = {f.name for f in [*robot_files.logs, *robot_files.motorlab] if f.stat().st_size > cut}
    assert named <= {n["file"] for n in result["not_pulled"]}
    assert len(result["not_pulled"]) == sum(f.stat().st_size > cut for f in served)
    for n in result["not_pulled"]:
        assert n["todo"] == "pull again", n
        assert "127.0.0.1" not in n["reason"], n
        assert not n["reason"].startswith("/"), n
        assert "nothing of it was kept" in n["reason"], n
    assert [n["line"] for n in result["not_pulled"]] == result["failed"]
    assert len(result["files"]) == sum(f.stat().st_size <= cut for f in served) > 0
