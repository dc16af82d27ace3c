"""Hostile input, end to end, for every ``motorlab`` command.

The brief's rule: bad input (empty, truncated, binary, non-numeric, NaN, wrong units, impossible
options) gets exactly one line on stderr, starting with ``motorlab`` and naming the file (and the
line, when the problem is in a line), exit code 2, never a traceback; the user's files are left
byte for byte and mtime for mtime as they were. Quirky but normal files (blank lines, a header,
placeholder zeros, CRLF, a BOM, a run split over two files) are analysed as usual.

The valid inputs are written once per module by the virtual rig (:class:`motorlab.rig.VirtualRig`);
every case corrupts a copy in its own ``tmp_path``.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import re
import shutil
import subprocess
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from motorlab import cli
from motorlab.rig import VirtualRig

# ---- the valid inputs --------------------------------------------------------------------------


@dataclass(frozen=True)
class Analysis:
    """How to produce and analyse one experiment's file(s)."""

    rig: str  # VirtualRig experiment
    name: str  # file name written (spindown: the first of the split pair)
    settings: dict[str, Any]
    options: tuple[str, ...]  # analyze options giving a valid run
    target: int = 0  # which of the files the corruptions hit


ANALYSES: dict[str, Analysis] = {
    # The corruptions hit testFile2.txt: the error must name the second file of the split run.
    "spindown": Analysis("spindown", "testFile.txt", {"split": True, "on_time": 10.0, "coast_time": 20.0},
                         ("--cpr", "1120"), target=1),
    "spinup": Analysis("spinup", "spinup.txt", {"duration": 10.0}, ("--cpr", "1120", "--inertia", "12.2")),
    "free-spinup": Analysis("free-spinup", "free_spinup.csv", {}, ("--K", "0.7", "--current", "0.5 A")),
    "terminal": Analysis("terminal", "terminal.csv", {}, ("--K", "0.7",)),
    "lcr": Analysis("lcr", "lcr.csv", {}, ()),
    "torque": Analysis("torque", "torque.csv", {}, ()),
    "amplifier": Analysis("amplifier", "amplifier.csv", {}, ()),
    "tachometer": Analysis("tachometer", "tachometer.csv", {}, ()),
    "pulse": Analysis("pulse", "pulse.csv", {}, ("--Ka", "1.96", "--K", "0.7")),
    "identify": Analysis("transient", "transient.csv", {"duration": 2.0}, ("--cpr", "1120")),
    "feedforward": Analysis("sysid", "sysid.json", {"quasistatic_duration": 10.0, "dynamic_duration": 3.0}, ()),
}


@pytest.fixture(scope="module")
def rig_files(tmp_path_factory: pytest.TempPathFactory) -> dict[str, list[Path]]:
    """Every experiment's valid file(s), written once by the virtual rig (unit B, noise seed 7)."""
    folder = tmp_path_factory.mktemp("rig")
    rig = VirtualRig("neverest40", unit_seed=1, noise_seed=7)
    files = {}
    for experiment, a in ANALYSES.items():
        run = rig.run(a.rig, folder / a.name, **a.settings)
        files[experiment] = [Path(p) for p in run.paths]
    return files


@pytest.fixture(scope="module")
def params_json(rig_files: dict[str, list[Path]], tmp_path_factory: pytest.TempPathFactory) -> Path:
    """``motorlab analyze identify --json`` output of the rig's transient log (for ``tune --params``)."""
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        code = cli.main(["analyze", "identify", str(rig_files["identify"][0]), "--cpr", "1120", "--json"])
    assert code == 0
    path = tmp_path_factory.mktemp("params") / "motor.json"
    path.write_text(out.getvalue())
    return path


@pytest.fixture(scope="module")
def session_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A small simulated session (two units, three quick experiments) and its ``session.toml``."""
    from motorlab.session.simulated import write_simulated_session

    folder = tmp_path_factory.mktemp("session")
    write_simulated_session(
        "neverest40", out_dir=folder, units=2, seed=3, experiments=("lcr", "torque", "spindown")
    )
    return folder


@pytest.fixture(scope="module")
def reference(rig_files: dict[str, list[Path]]) -> Callable[[str], dict[str, Any]]:
    """The parameters each experiment's valid file(s) give (computed once, on first use)."""
    cache: dict[str, dict[str, Any]] = {}

    def get(experiment: str) -> dict[str, Any]:
        if experiment not in cache:
            out = io.StringIO()
            with contextlib.redirect_stdout(out):
                code = cli.main(_argv(experiment, rig_files[experiment], "--json"))
            assert code == 0
            cache[experiment] = {k: v["value"] for k, v in json.loads(out.getvalue())["parameters"].items()}
        return cache[experiment]

    return get


def copy_inputs(paths: list[Path], folder: Path) -> list[Path]:
    folder.mkdir(parents=True, exist_ok=True)
    return [Path(shutil.copy2(p, folder / p.name)) for p in paths]


# ---- running and checking ----------------------------------------------------------------------


def snapshot(folder: Path) -> dict[Path, tuple[bytes, int]]:
    """Bytes and mtime of every file under ``folder`` (what must not change)."""
    return {p: (p.read_bytes(), p.stat().st_mtime_ns) for p in sorted(folder.rglob("*")) if p.is_file()}


def run(capsys: pytest.CaptureFixture[str], argv: list[str]) -> tuple[int, str, str]:
    """``motorlab ARGV`` in process; argparse errors leave the parser by ``SystemExit(2)``."""
    try:
        code = cli.main(argv)
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else 1
    out, err = capsys.readouterr()
    return code, out, err


def assert_one_line(err: str, *, file: str | None = None, line: int | None = None, mentions: str | None = None) -> None:
    """Exactly one stderr line, ``motorlab...``, naming ``file`` (and ``:line``), no traceback."""
    assert "Traceback" not in err
    lines = err.splitlines()
    assert len(lines) == 1, f"expected one line on stderr, got {len(lines)}:\n{err}"
    text = lines[0]
    assert text.startswith("motorlab"), text
    if file is not None:
        assert file in text, f"{file!r} not named in: {text}"
    if line is not None:
        assert re.search(re.escape(file or "") + rf"[^\s]*:{line}\b", text), f"line {line} not named in: {text}"
    if mentions is not None:
        assert mentions.lower() in text.lower(), f"{mentions!r} not in: {text}"


def assert_refused(
    capsys: pytest.CaptureFixture[str],
    argv: list[str],
    inputs: Path,
    *,
    file: str | None = None,
    line: int | None = None,
    mentions: str | None = None,
) -> str:
    """Run ``argv``: exit 2, one line on stderr, the files under ``inputs`` untouched."""
    before = snapshot(inputs)
    code, _, err = run(capsys, argv)
    assert code == 2, f"exit code {code}, stderr:\n{err}"
    assert_one_line(err, file=file, line=line, mentions=mentions)
    assert snapshot(inputs) == before, "an input file was modified, removed or added"
    return err


# ---- corruptions of a data file ----------------------------------------------------------------

_FIELD = re.compile(r"[^,\s]+")


def _is_number(token: str) -> bool:
    try:
        float(token)
    except ValueError:
        return False
    return True


def data_lines(text: str) -> list[int]:
    """1-based numbers of the lines made only of numbers (the data rows of the text formats)."""
    out = []
    for n, line in enumerate(text.splitlines(), start=1):
        stripped = line.strip()
        if stripped and not stripped.startswith("#"):
            fields = _FIELD.findall(stripped)
            if fields and all(_is_number(f) for f in fields):
                out.append(n)
    return out


def _replace_field(line: str, value: str | None) -> str:
    """``line`` with its second field (its only one, for one-column files) replaced, or removed (None)."""
    matches = list(_FIELD.finditer(line))
    m = matches[min(1, len(matches) - 1)]
    if value is not None:
        return line[: m.start()] + value + line[m.end() :]
    last = matches[-1]  # drop the last field with the separator before it
    return line[: matches[-2].end()] + line[last.end() :]


def corrupt_line(path: Path, value: str | None) -> int:
    """Replace a field of a middle data row of a text file by ``value`` (None: drop a column); its line."""
    text = path.read_bytes().decode()
    lines = text.split("\n")
    rows = data_lines(text)
    n = rows[len(rows) // 2]
    lines[n - 1] = _replace_field(lines[n - 1], value)
    path.write_bytes("\n".join(lines).encode())
    return n


_ROW = re.compile(r"\[[^\[\]]*\]")


def corrupt_json_row(path: Path, value: str | None) -> int:
    """Same for a SysId JSON file: a middle row ``[t, V, x, v]`` gets ``value`` (None: loses a column)."""
    text = path.read_text()
    rows = list(_ROW.finditer(text))
    m = rows[len(rows) // 2]
    items = m.group(0)[1:-1].split(",")
    if value is None:
        items = items[:-1]
    else:
        items[1] = f" {value}"
    path.write_text(text[: m.start()] + "[" + ",".join(items) + "]" + text[m.end() :])
    return text.count("\n", 0, m.start()) + 1


def keep_single_row(path: Path) -> None:
    """Keep the comments, header and the first data row only."""
    if path.suffix == ".json":
        doc = json.loads(path.read_text())
        path.write_text(json.dumps({k: (v[:1] if isinstance(v, list) else v) for k, v in doc.items()}))
        return
    text = path.read_text()
    first = data_lines(text)[0]
    path.write_text("\n".join(text.split("\n")[:first]) + "\n")


def truncate_last_line(path: Path) -> int:
    """Cut the writer off in the middle of the last data row (no line ending after it); that line."""
    text = path.read_text().rstrip("\n")
    lines = text.split("\n")
    last = lines[-1]
    m = list(_FIELD.finditer(last))
    lines[-1] = last[: m[0].end() + 1]  # the first field and the separator after it
    path.write_text("\n".join(lines))
    return len(lines)


# Case: (corruption, expected line?) — corruptions in a line must name it.
LINE_CORRUPTIONS = {
    "non-numeric": "abc",
    "nan": "nan",
    "inf": "inf",
    "missing-column": None,
}
JSON_VALUES = {"abc": '"abc"', "nan": "NaN", "inf": "Infinity"}

FILE_CORRUPTIONS = ("empty", "binary", "directory", "missing", "single-row", "truncated")

# Not refused but analysed: one operating point gives b with Coulomb friction folded in and its
# uncertainty unknown (see test_terminal_single_row_reports_an_unknown_uncertainty).
NOT_REFUSED = {("terminal", "single-row")}


def _params(experiments: list[str], kinds: tuple[str, ...]) -> list[Any]:
    out = []
    for e in experiments:
        for k in kinds:
            if (e, k) in NOT_REFUSED:
                continue
            out.append(pytest.param(e, k, id=f"{e}-{k}"))
    return out


def _argv(experiment: str, files: list[Path], *extra: str) -> list[str]:
    return ["analyze", experiment, *map(str, files), *ANALYSES[experiment].options, *extra]


@pytest.mark.parametrize(("experiment", "kind"), _params(list(ANALYSES), tuple(LINE_CORRUPTIONS)))
def test_analyze_bad_row(experiment: str, kind: str, rig_files, tmp_path: Path, capsys) -> None:
    """A bad field or a short row in the middle of the data: refused, naming the file and the line."""
    files = copy_inputs(rig_files[experiment], tmp_path / "in")
    target = files[ANALYSES[experiment].target]
    value = LINE_CORRUPTIONS[kind]
    if target.suffix == ".json":
        line = corrupt_json_row(target, None if value is None else JSON_VALUES[value])
    elif value is None and len(_FIELD.findall(target.read_text().splitlines()[-1])) < 2:
        pytest.skip("a one-column file cannot lose a column")
    else:
        line = corrupt_line(target, value)
    assert_refused(capsys, _argv(experiment, files), tmp_path / "in", file=target.name, line=line)


def _header_line(text: str) -> int | None:
    """1-based line of a CSV header (the first line that is not blank, a comment or numbers)."""
    for n, line in enumerate(text.splitlines(), start=1):
        stripped = line.strip()
        if stripped and not stripped.startswith("#"):
            return None if n in data_lines(text) else n
    return None


def _swap_middle_rows(path: Path) -> int:
    """Swap two consecutive middle data rows (time runs backwards); the line of the later one."""
    text = path.read_text()
    lines = text.split("\n")
    rows = data_lines(text)
    n = rows[len(rows) // 2]
    lines[n - 1], lines[n] = lines[n], lines[n - 1]
    path.write_text("\n".join(lines))
    return n + 1


def _flatten(path: Path) -> None:
    """Every column but the first reads zero: a log of a rig whose sensors were unplugged."""
    if path.suffix == ".json":
        doc = json.loads(path.read_text())
        for key, rows in doc.items():
            if isinstance(rows, list):
                doc[key] = [[row[0], 0.0, 0.0, 0.0] for row in rows]
        path.write_text(json.dumps(doc))
        return
    text = path.read_text()
    lines = text.split("\n")
    for n in data_lines(text):
        fields = list(_FIELD.finditer(lines[n - 1]))
        line = lines[n - 1]
        for m in reversed(fields[1:]):
            line = line[: m.start()] + "0" + line[m.end() :]
        lines[n - 1] = line
    path.write_text("\n".join(lines))


@pytest.mark.parametrize(("experiment", "kind"), _params([e for e in ANALYSES if e != "free-spinup"], ("flat",)))
def test_analyze_flat_signals(experiment: str, kind: str, rig_files, tmp_path: Path, capsys) -> None:
    """Readable numbers that carry nothing (unplugged sensors): refused, naming the file."""
    files = copy_inputs(rig_files[experiment], tmp_path / "in")
    target = files[ANALYSES[experiment].target]
    _flatten(target)
    assert_refused(capsys, _argv(experiment, files), tmp_path / "in", file=target.name)


CONTENT_CORRUPTIONS = ("unknown-unit-in-header", "no-header", "time-backwards")
TIME_FIRST = {"spindown", "spinup", "free-spinup", "pulse", "identify"}


@pytest.mark.parametrize(("experiment", "kind"), _params(list(ANALYSES), CONTENT_CORRUPTIONS))
def test_analyze_bad_content(experiment: str, kind: str, rig_files, reference, tmp_path: Path, capsys) -> None:
    """A column in an unknown unit, no header, time going backwards: file and line."""
    files = copy_inputs(rig_files[experiment], tmp_path / "in")
    target = files[ANALYSES[experiment].target]
    text = target.read_text()
    header = _header_line(text)
    line: int | None = None
    if target.suffix == ".json":
        pytest.skip("JSON has no header and is read as a whole (its own cases are above)")
    if kind in ("unknown-unit-in-header", "no-header"):
        if target.suffix != ".csv" or header is None:
            pytest.skip("FTC logs need no header (their column order is fixed)")
        lines = text.split("\n")
        if kind == "no-header":
            del lines[header - 1]
        else:
            names = lines[header - 1].split(",")
            names[-1] = names[-1].rsplit("_", 1)[0] + "_furlongs"
            lines[header - 1] = ",".join(names)
            line = header
        target.write_text("\n".join(lines))
        if kind == "no-header" and experiment == "free-spinup":
            # Documented (io.read_scope_times): a bare column of cursor times is read as milliseconds.
            assert _result(capsys, experiment, files) == reference(experiment)
            return
    elif kind == "time-backwards":
        if experiment not in TIME_FIRST:
            pytest.skip("rows of a table without time may come in any order")
        line = _swap_middle_rows(target)
    assert_refused(capsys, _argv(experiment, files), tmp_path / "in", file=target.name, line=line)


@pytest.mark.parametrize(("experiment", "kind"), _params(list(ANALYSES), FILE_CORRUPTIONS))
def test_analyze_bad_file(experiment: str, kind: str, rig_files, tmp_path: Path, capsys) -> None:
    """Empty, binary, a directory, missing, a single row, a truncated JSON: refused, naming the file."""
    files = copy_inputs(rig_files[experiment], tmp_path / "in")
    target = files[ANALYSES[experiment].target]
    line = None
    if kind == "empty":
        target.write_bytes(b"")
    elif kind == "binary":
        target.write_bytes(np.random.default_rng(5).integers(0, 256, 3000, dtype=np.uint8).tobytes() + b"\0")
    elif kind == "directory":
        target.unlink()
        target.mkdir()
    elif kind == "missing":
        target.unlink()
    elif kind == "single-row":
        keep_single_row(target)
    elif kind == "truncated":
        if len(_FIELD.findall(target.read_text().splitlines()[-1])) < 2:
            pytest.skip("a cut-off value in a one-column file is still a number: nothing can tell")
        line = truncate_last_line(target)
        if target.suffix != ".json":
            # A text log whose writer was cut off: the partial row is dropped, the rest analysed, and
            # the user told which line went (FTC and CSV readers).
            before = snapshot(tmp_path / "in")
            code, out, err = run(capsys, _argv(experiment, files, "--json"))
            assert code == 0, err
            assert "Traceback" not in err
            warnings = " ".join(json.loads(out)["warnings"])
            assert f"{target.name}:{line}" in warnings
            assert "truncated" in warnings
            assert snapshot(tmp_path / "in") == before
            return
        line = 1
    assert_refused(capsys, _argv(experiment, files), tmp_path / "in", file=target.name, line=line)


def test_terminal_single_row_reports_an_unknown_uncertainty(rig_files, tmp_path: Path, capsys) -> None:
    """One operating point: b with Coulomb friction folded in, its uncertainty unknown (not '± 0')."""
    files = copy_inputs(rig_files["terminal"], tmp_path / "in")
    keep_single_row(files[0])
    before = snapshot(tmp_path / "in")
    code, out, err = run(capsys, _argv("terminal", files, "--json"))
    assert code == 0, err
    assert err == ""
    doc = json.loads(out)
    assert doc["parameters"]["b"]["value"] > 0
    assert doc["parameters"]["b"]["stderr"] is None  # NaN: unknown, not 0
    assert "Tf" not in doc["parameters"]
    warnings = " ".join(doc["warnings"])
    assert "folded into b" in warnings
    assert "--current-stderr" in warnings
    # With the readings' uncertainties given they are propagated.
    code, out, err = run(capsys, _argv("terminal", files, "--json", "--current-stderr", "1 mA",
                                       "--frequency-stderr", "0.01 Hz", "--K-stderr", "0.01"))
    assert code == 0, err
    b = json.loads(out)["parameters"]["b"]
    assert 0 < b["stderr"] < 0.1 * b["value"]
    assert snapshot(tmp_path / "in") == before


# A file of another experiment: readable, but not what the analysis needs.
WRONG_FILE = {e: "torque" if e != "torque" else "lcr" for e in ANALYSES}


@pytest.mark.parametrize(("experiment", "kind"), _params(list(ANALYSES), ("wrong-file",)))
def test_analyze_wrong_kind_of_file(experiment: str, kind: str, rig_files, tmp_path: Path, capsys) -> None:
    files = copy_inputs(rig_files[WRONG_FILE[experiment]], tmp_path / "in")
    assert_refused(capsys, _argv(experiment, files), tmp_path / "in", file=files[0].name)


# Impossible option values, per experiment: (options, text the error must mention).
BAD_OPTIONS: dict[str, list[tuple[tuple[str, ...], str]]] = {
    "spindown": [(("--cpr", "0"), "--cpr"), (("--cpr", "-1120"), "--cpr"), (("--cpr", "abc"), "--cpr"),
                 (("--inertia", "3 V"), "--inertia"), (("--inertia", "nan"), "--inertia"),
                 (("--cutoff", "-1 s"), "--cutoff"), (("--cutoff", "900 s"), "cut-off"),
                 (("--material", "cheese"), "--material"), (("--disc-radius", "0.1 m"), "disc"),
                 (("--cpr", "1e-300"), "--cpr")],
    "spinup": [(("--cpr", "0"), "--cpr"), (("--inertia", "3 V"), "--inertia"), (("--start", "8", "--end", "2"), "end"),
               (("--b", "inf"), "--b")],
    "free-spinup": [(("--current", "0.5 V"), "--current"), (("--current", "0"), "--current"),
                    (("--K", "-0.7"), "--K"), (("--edges-per-rev", "0"), "--edges-per-rev"),
                    (("--K", "1e300", "--current", "1e300"), "--K")],
    "terminal": [(("--K", "0.7 A"), "--K"), (("--K", "0"), "--K"), (("--cpr", "-3"), "--cpr")],
    "lcr": [(("--frequency", "1 kg"), "--frequency"), (("--frequency", "0"), "--frequency"),
            (("--circuit", "star"), "--circuit"), (("--outlier-z", "-1"), "--outlier-z"),
            (("--frequency", "1e300"), "--frequency")],
    "torque": [(("--arm", "15 V"), "--arm"), (("--arm", "0"), "--arm"), (("--arm", "-0.1"), "--arm")],
    "amplifier": [(("--nominal", "2 V"), "--nominal"), (("--nominal", "abc"), "--nominal")],
    "tachometer": [(("--nominal", "3 A"), "--nominal")],
    "pulse": [(("--Ka", "2 V"), "--Ka"), (("--Ka", "0"), "--Ka"), (("--skip", "-1"), "--skip"),
              (("--friction", "sticky"), "--friction"), (("--tach-gain", "-1"), "--tach-gain"),
              (("--Ka", "1e-300"), "--Ka")],
    "identify": [(("--cpr", "0"), "--cpr"), (("--R", "1 V"), "--R"), (("--R", "-1"), "--R")],
    "feedforward": [(("--cpr", "0"), "--cpr"), (("--mechanism", "rocket"), "--mechanism"), (("--R", "1 A"), "--R")],
}
def _option_params() -> list[Any]:
    out = []
    for e, cases in BAD_OPTIONS.items():
        for opts, mention in cases:
            out.append(pytest.param(e, opts, mention, id=f"{e}-{'='.join(opts)}"))
    return out


@pytest.mark.parametrize(("experiment", "options", "mention"), _option_params())
def test_analyze_bad_option(experiment: str, options: tuple[str, ...], mention: str, rig_files, tmp_path, capsys):
    files = copy_inputs(rig_files[experiment], tmp_path / "in")
    assert_refused(capsys, _argv(experiment, files, *options), tmp_path / "in", mentions=mention)


def test_empty_file_name(capsys, tmp_path: Path) -> None:
    assert_refused(capsys, ["analyze", "torque", ""], tmp_path, mentions="file name is empty")


def test_each_names_the_bad_file(rig_files, tmp_path: Path, capsys) -> None:
    """``--each`` over a good and a bad file: the bad one is named (not the first one given)."""
    good = copy_inputs(rig_files["torque"], tmp_path / "in")[0]
    bad = _binary(tmp_path / "in" / "unitB.csv")
    assert_refused(capsys, ["analyze", "torque", str(good), str(bad), "--each"], tmp_path / "in", file="unitB.csv")


def test_spindown_without_coast(rig_files, tmp_path: Path, capsys) -> None:
    """The powered part alone (testFile.txt without testFile2.txt): no coast to fit."""
    files = copy_inputs(rig_files["spindown"], tmp_path / "in")
    assert_refused(capsys, _argv("spindown", files[:1]), tmp_path / "in", file=files[0].name, mentions="coast")


def test_split_files_in_the_wrong_order(rig_files, tmp_path: Path, capsys) -> None:
    files = copy_inputs(rig_files["spindown"], tmp_path / "in")
    assert_refused(capsys, _argv("spindown", files[::-1]), tmp_path / "in", file=files[0].name, mentions="backwards")


@pytest.mark.parametrize(
    "argv",
    [
        pytest.param(["analyze", "nonsense", "x.csv"], id="unknown-experiment"),
        pytest.param(["analyze", "torque"], id="no-file"),
        pytest.param(["analyze", "torque", "x.csv", "--frobnicate"], id="unknown-option"),
        pytest.param(["analyze"], id="no-experiment"),
        pytest.param(["nonsense"], id="unknown-command"),
        pytest.param([], id="no-command"),
    ],
)
def test_argparse_errors_are_one_line(argv: list[str], capsys) -> None:
    with pytest.raises(SystemExit) as exc:
        cli.main(argv)
    assert exc.value.code == 2
    assert_one_line(capsys.readouterr().err)


def _every_parser(parser: Any, path: tuple[str, ...] = ()) -> list[tuple[tuple[str, ...], Any]]:
    import argparse

    out = [(path, parser)]
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                out += _every_parser(sub, (*path, name))
    return out


def test_every_sub_parser_gives_one_line_errors(capsys) -> None:
    """Every parser, nested ones included (``analyze spindown``, ``simulate session``), is a ``Parser``."""
    from motorlab.cli.common import Parser

    parsers = _every_parser(cli.build_parser())
    assert len(parsers) > 25
    for path, parser in parsers:
        assert isinstance(parser, Parser), " ".join(path)
        with pytest.raises(SystemExit) as exc:
            parser.parse_args(["--no-such-option-anywhere"])
        assert exc.value.code == 2
        assert_one_line(capsys.readouterr().err)


@pytest.mark.parametrize(
    ("plot", "mention"),
    [("missing-dir/fit.png", "does not exist"), ("fit.exe", ".png"), ("a-file.txt/fit.png", "a-file.txt")],
)
def test_analyze_plot_path_refused_before_fitting(plot, mention, rig_files, tmp_path: Path, capsys) -> None:
    files = copy_inputs(rig_files["torque"], tmp_path / "in")
    (tmp_path / "a-file.txt").write_text("not a folder\n")
    argv = _argv("torque", files, "--plot", str(tmp_path / plot))
    assert_refused(capsys, argv, tmp_path, mentions=mention)


# ---- quirky but normal files -------------------------------------------------------------------


def _result(capsys, experiment: str, files: list[Path]) -> dict[str, Any]:
    code, out, err = run(capsys, _argv(experiment, files, "--json"))
    assert code == 0, err
    assert err == ""
    return {k: v["value"] for k, v in json.loads(out)["parameters"].items()}


QUIRKS = ("crlf", "blank-lines", "bom", "no-final-newline", "latin-1")


@pytest.mark.parametrize(("experiment", "kind"), _params([e for e in ANALYSES if e != "feedforward"], QUIRKS))
def test_quirky_files_give_the_same_result(experiment: str, kind: str, rig_files, reference, tmp_path, capsys) -> None:
    expected = reference(experiment)
    files = copy_inputs(rig_files[experiment], tmp_path / "in")
    for path in files:
        text = path.read_text()
        if kind == "crlf":
            text = text.replace("\n", "\r\n")
        elif kind == "blank-lines":
            lines = text.split("\n")
            middle = data_lines(text)[len(data_lines(text)) // 2]
            text = "\n\n" + "\n".join([*lines[:middle], "", "   ", *lines[middle:]]) + "\n\n"
        elif kind == "bom":
            text = "\ufeff" + text
        elif kind == "no-final-newline":
            text = text.rstrip("\n")
        elif kind == "latin-1":  # a Windows editor's "µ" in a comment (CSV) or the header (FTC log): Latin-1
            lines = text.split("\n")
            first = next(n for n, line in enumerate(lines) if line.strip())
            if path.suffix == ".csv":
                lines.insert(first, "# probe 5 @MU@H")
            elif not _is_number(lines[first].split()[0]):
                lines[first] += " (@MU@s)"
            path.write_bytes("\n".join(lines).encode().replace(b"@MU@", b"\xb5"))
            continue
        path.write_bytes(text.encode())
    assert _result(capsys, experiment, files) == expected


@pytest.mark.parametrize("experiment", ["spindown", "spinup"])
def test_ftc_log_header_and_placeholders_are_optional(experiment: str, rig_files, reference, tmp_path, capsys) -> None:
    """No header, no blank lines, more placeholder zeros: the same run."""
    expected = reference(experiment)
    files = copy_inputs(rig_files[experiment], tmp_path / "in")
    for path in files:
        rows = [line for line in path.read_text().splitlines() if line.strip() and _is_number(line.split()[0])]
        path.write_text("\n".join(rows + ["0.0 0 0.0 0.0"] * 7) + "\n")
    assert _result(capsys, experiment, files) == expected


def test_split_run_is_one_run(rig_files, reference, tmp_path: Path, capsys) -> None:
    """testFile.txt + testFile2.txt analysed together equal the two files joined by hand."""
    expected = reference("spindown")
    joined = tmp_path / "joined.txt"
    rows = [
        line
        for path in rig_files["spindown"]
        for line in path.read_text().splitlines()
        if line.strip() and _is_number(line.split()[0]) and line.split()[0] != "0.0"
    ]
    joined.write_text("\n".join(rows) + "\n")
    assert _result(capsys, "spindown", [joined]) == expected


# ---- simulate, tune, plan, motors, demo --------------------------------------------------------


@dataclass(frozen=True)
class Case:
    """A command line built in ``tmp_path`` and what its one error line must name."""

    argv: Callable[[Path], list[str]]
    file: str | None = None
    mentions: str | None = None


def _cases(cases: dict[str, Case]) -> list[Any]:
    return [
        pytest.param(c, id=name)
        for name, c in cases.items()
    ]


def _binary(path: Path) -> Path:
    path.write_bytes(b"\x89PNG\0\0\xff\xfe" * 64)
    return path


def _text(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


def _sim(*extra: str, experiment: str = "lcr") -> Callable[[Path], list[str]]:
    return lambda d: ["simulate", experiment, "--motor", "neverest40", "-o", str(d / "out.csv"), *extra]


SIMULATE = {
    "unknown-motor": Case(lambda d: ["simulate", "lcr", "--motor", "neverest41", "-o", str(d / "x.csv")],
                          mentions="neverest41"),
    "unknown-experiment": Case(lambda d: ["simulate", "wobble", "--motor", "neverest40", "-o", str(d / "x")],
                               mentions="wobble"),
    "output-in-missing-dir": Case(lambda d: ["simulate", "lcr", "--motor", "neverest40",
                                             "-o", str(d / "nowhere" / "x.csv")], file="nowhere"),
    "output-is-a-directory": Case(lambda d: ["simulate", "lcr", "--motor", "neverest40", "-o", str(d)],
                                  file=None, mentions="director"),
    "output-under-a-file": Case(lambda d: ["simulate", "lcr", "--motor", "neverest40",
                                           "-o", str(_text(d / "f.txt", "x\n") / "x.csv")], file="f.txt"),
    "voltage-wrong-unit": Case(_sim("--voltage", "12 A", experiment="spindown"), mentions="--voltage"),
    "voltage-above-ina219": Case(_sim("--voltage", "20", experiment="spindown"), mentions="16"),
    "current-limit-zero": Case(_sim("--current-limit", "0", experiment="spindown"), mentions="--current-limit"),
    "negative-unit-seed": Case(_sim("--unit-seed", "-1"), mentions="--unit-seed"),
    "duty-above-one": Case(_sim("--duty", "1.5", experiment="pulse"), mentions="duty"),
    "duty-nan": Case(_sim("--duty", "nan", experiment="pulse"), mentions="duty"),
    "currents-not-numbers": Case(_sim("--currents", "a,b", experiment="terminal"), mentions="--currents"),
    "currents-negative": Case(_sim("--currents", "-1,2", experiment="torque"), mentions="current"),
    "positions-zero": Case(_sim("--positions", "0"), mentions="--positions"),
    "rate-wrong-unit": Case(_sim("--rate", "5 V", experiment="transient"), mentions="--rate"),
    # Settings whose output would be absurdly large: refused before anything is allocated (these
    # asked for 7 TiB, raised MemoryError or hung).
    "on-time-1e9": Case(_sim("--on-time", "1e9", experiment="spindown"), mentions="--on-time"),
    "duration-1e8": Case(_sim("--duration", "1e8", experiment="spinup"), mentions="--duration"),
    "sample-interval-1ps": Case(_sim("--sample-interval", "1e-12", experiment="pulse"), mentions="--sample-interval"),
    "rate-1e12": Case(_sim("--rate", "1e12", experiment="transient"), mentions="--rate"),
    "edges-1e8": Case(_sim("--edges", "100000000", experiment="free-spinup"), mentions="--edges"),
    "positions-1e8": Case(_sim("--positions", "100000000"), mentions="--positions"),
    "quasistatic-1e9": Case(_sim("--quasistatic-duration", "1e9", experiment="sysid"),
                            mentions="--quasistatic-duration"),
    # Values that overflowed the simulation or an instrument (warnings, then a traceback or a NaN column).
    "max-voltage-1e300": Case(_sim("--max-voltage", "1e300", experiment="transient"), mentions="--max-voltage"),
    "step-voltage-1e300": Case(_sim("--step-voltage", "1e300", experiment="sysid"), mentions="--step-voltage"),
    "hand-speed-1e300": Case(_sim("--hand-speed", "1e300", experiment="free-spinup"), mentions="--hand-speed"),
    "timebase-1e300": Case(_sim("--timebase", "1e300", experiment="free-spinup"), mentions="--timebase"),
    "session-zero-units": Case(lambda d: ["simulate", "session", "--motor", "neverest40", "--units", "0",
                                          "-o", str(d / "s")], mentions="--units"),
    "session-too-many-units": Case(lambda d: ["simulate", "session", "--motor", "neverest40", "--units", "27",
                                              "-o", str(d / "s")], mentions="units"),
    "session-output-under-a-file": Case(lambda d: ["simulate", "session", "--motor", "neverest40", "--units", "1",
                                                   "-o", str(_text(d / "f.txt", "x\n") / "s")], file="f.txt"),
}


@pytest.mark.parametrize("case", _cases(SIMULATE))
def test_simulate_refuses(case: Case, tmp_path: Path, capsys) -> None:
    assert_refused(capsys, case.argv(tmp_path), tmp_path, file=case.file, mentions=case.mentions)


def _tune(*extra: str) -> Callable[[Path], list[str]]:
    return lambda d: ["tune", "velocity", *extra]


TUNE = {
    "kv-not-a-number": Case(_tune("--kv", "abc", "--ka", "0.1"), mentions="--kv"),
    "kv-nan": Case(_tune("--kv", "nan", "--ka", "0.1"), mentions="--kv"),
    "kv-negative": Case(_tune("--kv", "-1", "--ka", "0.1"), mentions="kv"),
    "ka-zero": Case(_tune("--kv", "1", "--ka", "0"), mentions="ka"),
    "no-plant": Case(_tune(), mentions="--kv"),
    "cpr-zero": Case(_tune("--kv", "1", "--ka", "0.1", "--units", "ticks", "--cpr", "0"), mentions="--cpr"),
    "ticks-without-cpr": Case(_tune("--kv", "1", "--ka", "0.1", "--units", "ticks"), mentions="--cpr"),
    "wheel-radius-wrong-unit": Case(_tune("--kv", "1", "--ka", "0.1", "--units", "m", "--wheel-radius", "2 V"),
                                    mentions="--wheel-radius"),
    "period-zero": Case(_tune("--kv", "1", "--ka", "0.1", "--period", "0"), mentions="--period"),
    "period-nanosecond": Case(_tune("--kv", "1", "--ka", "0.1", "--period", "1 ns"), mentions="period"),
    "overshoot-150": Case(_tune("--kv", "1", "--ka", "0.1", "--method", "poles", "--rise-time", "0.1",
                                "--overshoot", "150"), mentions="--overshoot"),
    "unknown-target": Case(_tune("--kv", "1", "--ka", "0.1", "--target", "toaster"), mentions="--target"),
    "params-missing": Case(lambda d: ["tune", "velocity", "--params", str(d / "none.json")], file="none.json"),
    "params-directory": Case(lambda d: ["tune", "velocity", "--params", str(d)], file=None, mentions="director"),
    "params-empty": Case(lambda d: ["tune", "velocity", "--params", str(_text(d / "e.json", ""))], file="e.json"),
    "params-binary": Case(lambda d: ["tune", "velocity", "--params", str(_binary(d / "b.json"))], file="b.json"),
    "params-bad-json": Case(lambda d: ["tune", "velocity", "--params", str(_text(d / "j.json", '{"a":\n[1,\n'))],
                            file="j.json"),
    "params-no-parameters": Case(lambda d: ["tune", "velocity", "--params", str(_text(d / "n.json", '{"a": 1}'))],
                                 file="n.json"),
    "params-nan": Case(lambda d: ["tune", "velocity", "--params",
                                  str(_text(d / "nan.json", '{"parameters": {"kV": NaN, "kA": 0.1}}'))],
                       file="nan.json"),
    "params-negative-resistance": Case(
        lambda d: ["tune", "velocity", "--params", str(_text(
            d / "neg.json", '{"parameters": {"K": 0.7, "R": -1.0, "J": 0.01, "b": 0.001, "Tf": 0.01}}'))],
        file="neg.json"),
    "qv-underflows": Case(_tune("--kv", "1", "--ka", "0.1", "--qv", "1e-300"), mentions="qv"),
    "params-time-constant-zero": Case(
        lambda d: ["tune", "velocity", "--params",
                   str(_text(d / "tau.json", '{"parameters": {"kV": 1e308, "kA": 1e-308}}'))],
        file="tau.json"),
    "plot-in-missing-dir": Case(_tune("--kv", "1", "--ka", "0.1", "--plot", "/nonexistent-motorlab/x.png"),
                                file="nonexistent-motorlab"),
    "plot-bad-extension": Case(lambda d: ["tune", "velocity", "--kv", "1", "--ka", "0.1", "--plot", str(d / "x.exe")],
                               file="x.exe"),
}


@pytest.mark.parametrize("case", _cases(TUNE))
def test_tune_refuses(case: Case, tmp_path: Path, capsys) -> None:
    assert_refused(capsys, case.argv(tmp_path), tmp_path, file=case.file, mentions=case.mentions)


def test_tune_params_from_analyze_json(params_json: Path, capsys) -> None:
    """The valid baseline of the ``--params`` cases: analyze --json output tunes a loop."""
    code, out, err = run(capsys, ["tune", "velocity", "--params", str(params_json)])
    assert code == 0, err
    assert "gains:" in out


def _plan(*extra: str) -> Callable[[Path], list[str]]:
    return lambda d: ["plan", "--motor", "neverest40", *extra]


PLAN = {
    "unknown-motor": Case(lambda d: ["plan", "--motor", "warp-drive"], mentions="warp-drive"),
    "current-wrong-unit": Case(_plan("--current", "2 V"), mentions="--current"),
    "fraction-zero": Case(_plan("--fraction", "0"), mentions="fraction"),
    "fraction-above-one": Case(_plan("--fraction", "1.5"), mentions="fraction"),
    "fraction-nan": Case(_plan("--fraction", "nan"), mentions="fraction"),
    "time-zero": Case(_plan("--time", "0"), mentions="--time"),
    "radius-negative": Case(_plan("--radius", "-1 cm"), mentions="--radius"),
    "material": Case(_plan("--material", "unobtainium"), mentions="--material"),
    "ratio-zero": Case(_plan("--ratio", "0"), mentions="--ratio"),
    "ratio-1e300": Case(_plan("--ratio", "1e300"), mentions="ratio"),
    "voltage-inf": Case(_plan("--voltage", "inf"), mentions="--voltage"),
}


@pytest.mark.parametrize("case", _cases(PLAN))
def test_plan_refuses(case: Case, tmp_path: Path, capsys) -> None:
    assert_refused(capsys, case.argv(tmp_path), tmp_path, file=case.file, mentions=case.mentions)


MOTORS = {
    "unknown-motor": Case(lambda d: ["motors", "neverest41"], mentions="neverest41"),
    "voltage-wrong-unit": Case(lambda d: ["motors", "neverest40", "--voltage", "12 A"], mentions="--voltage"),
    "voltage-zero": Case(lambda d: ["motors", "neverest40", "--voltage", "0"], mentions="--voltage"),
    "voltage-nan": Case(lambda d: ["motors", "neverest40", "--voltage", "nan"], mentions="--voltage"),
    "voltage-1e300": Case(lambda d: ["motors", "neverest40", "--voltage", "1e300"], mentions="--voltage"),
}


@pytest.mark.parametrize("case", _cases(MOTORS))
def test_motors_refuses(case: Case, tmp_path: Path, capsys) -> None:
    assert_refused(capsys, case.argv(tmp_path), tmp_path, file=case.file, mentions=case.mentions)


DEMO = {  # all refused before anything is simulated
    "zero-units": Case(lambda d: ["demo", "-o", str(d / "o"), "--units", "0"], mentions="--units"),
    "too-many-units": Case(lambda d: ["demo", "-o", str(d / "o"), "--units", "27"], mentions="--units"),
    "unknown-motor": Case(lambda d: ["demo", "-o", str(d / "o"), "--motor", "neverest41"], mentions="neverest41"),
    "wear-wrong-unit": Case(lambda d: ["demo", "-o", str(d / "o"), "--worn", "B", "--wear", "3 V"],
                            mentions="--wear"),
    "worn-unknown-unit": Case(lambda d: ["demo", "-o", str(d / "o"), "--units", "2", "--worn", "Z"],
                              mentions="Z"),
    "output-under-a-file": Case(lambda d: ["demo", "-o", str(_text(d / "f.txt", "x\n") / "o")], file="f.txt"),
    "output-empty": Case(lambda d: ["demo", "-o", ""], mentions="-o"),
}


@pytest.mark.parametrize("case", _cases(DEMO))
def test_demo_refuses(case: Case, tmp_path: Path, capsys) -> None:
    assert_refused(capsys, case.argv(tmp_path), tmp_path, file=case.file, mentions=case.mentions)


# ---- characterize: session files ---------------------------------------------------------------


def _session_copy(session_dir: Path, tmp_path: Path) -> Path:
    folder = tmp_path / "session"
    shutil.copytree(session_dir, folder)
    return folder / "session.toml"


def _edit(toml: Path, old: str, new: str) -> int:
    """Replace ``old`` by ``new`` in the session text; the line where ``new`` starts."""
    text = toml.read_text()
    assert old in text, old
    start = text.index(old)
    toml.write_text(text.replace(old, new, 1))
    return text.count("\n", 0, start) + 1


# (old text, new text, key named in the error, offset of the offending line from the edit's first line)
SESSION_EDITS = {
    "syntax-error": ('lever_arm = "0.15 m"', 'lever_arm = "0.15 m', "lever_arm", 0),
    "unknown-key": ('lever_arm = "0.15 m"', 'lever_arm = "0.15 m"\nlevr_arm2 = 3', "levr_arm2", 1),
    "unknown-table-key": ("[units.A.lcr]", "[units.A.lcr]\nfrequncy = \"1 kHz\"", "frequncy", 1),
    "missing-data-file": ('files = ["A/lcr.csv"]', 'files = ["A/lcr_missing.csv"]', "lcr_missing.csv", 0),
    "data-file-is-a-dir": ('files = ["A/lcr.csv"]', 'files = ["A"]', "files", 0),
    "wrong-unit": ('lever_arm = "0.15 m"', 'lever_arm = "0.15 V"', "lever_arm", 0),
    "not-a-number": ('lever_arm = "0.15 m"', 'lever_arm = "fifteen cm"', "lever_arm", 0),
    "negative": ('lever_arm = "0.15 m"', 'lever_arm = "-0.15 m"', "lever_arm", 0),
    "nan": ('lever_arm = "0.15 m"', "lever_arm = nan", "lever_arm", 0),
    "unknown-motor": ('catalog = "neverest40"', 'catalog = "neverest41"', "neverest41", 0),
    "unknown-experiment": ("[units.A.lcr]", "[units.A.lcrr]", "lcrr", 0),
    "inertia-and-disc": ("ratio = 25", 'ratio = 25\ndisc = {radius = "75 mm", thickness = "50 mm", material = "steel"}',
                         "disc", 1),
    "cpr-contradicts-catalog": ('catalog = "neverest40"', 'catalog = "neverest40"\ncounts_per_revolution = 28',
                                "counts_per_revolution", 1),
    "cutoff-wrong-unit": ('files = ["A/spindown.txt"]', 'files = ["A/spindown.txt"]\ncutoff = "5 A"', "cutoff", 1),
    "current-above-supply": ("[units.A.lcr]", '[units.A.free-spinup]\nfiles = ["A/lcr.csv"]\ncurrent = "5 A"\n\n'
                             "[units.A.lcr]", "current", 2),
    "radius-and-diameter": ('inertia = "0.019527634 kg*m^2"', 'disc = {radius = "75 mm", diameter = "150 mm", '
                            'thickness = "50 mm", material = "steel"}', "diameter", 0),
    "ratio-overflows": ("ratio = 25", "ratio = 1e300", "ratio", 0),
    "duplicate-key": ('lever_arm = "0.15 m"', 'lever_arm = "0.15 m"\nlever_arm = "0.2 m"', "lever_arm", 1),
    "truth-missing": ('truth = "A/truth.json"', 'truth = "A/truth_missing.json"', "truth", 0),
}


@pytest.mark.parametrize("kind", list(SESSION_EDITS))
def test_characterize_refuses_a_bad_session(kind: str, session_dir: Path, tmp_path: Path, capsys) -> None:
    """Refused before any analysis: one line naming the session file, the line and the key; nothing written."""
    toml = _session_copy(session_dir, tmp_path)
    old, new, key, offset = SESSION_EDITS[kind]
    line = _edit(toml, old, new) + offset
    out_dir = tmp_path / "results"
    assert_refused(capsys, ["characterize", str(toml), "-o", str(out_dir)], tmp_path / "session",
                   file=toml.name, line=line, mentions=key)
    assert not out_dir.exists()


@pytest.mark.parametrize("kind", ["empty", "binary", "directory", "missing", "no-units"])
def test_characterize_refuses_a_bad_session_file(kind: str, tmp_path: Path, capsys) -> None:
    toml = tmp_path / "session.toml"
    if kind == "empty":
        toml.write_text("")
    elif kind == "binary":
        _binary(toml)
    elif kind == "directory":
        toml.mkdir()
    elif kind == "no-units":
        toml.write_text('[motor]\ncatalog = "neverest40"\n')
    assert_refused(capsys, ["characterize", str(toml), "-o", str(tmp_path / "r")], tmp_path, file=toml.name)


def test_characterize_output_under_a_file(session_dir: Path, tmp_path: Path, capsys) -> None:
    toml = _session_copy(session_dir, tmp_path)
    blocker = _text(tmp_path / "f.txt", "x\n")
    assert_refused(capsys, ["characterize", str(toml), "-o", str(blocker / "r"), "--quiet", "--no-report"],
                   tmp_path, file="f.txt")


def test_one_bad_unit_does_not_stop_the_others(session_dir: Path, tmp_path: Path, capsys) -> None:
    """Unit B's spin-down log is garbage: A is characterised, B's row says why, exit code 3."""
    toml = _session_copy(session_dir, tmp_path)
    bad = toml.parent / "B" / "spindown.txt"
    _binary(bad)
    before = snapshot(toml.parent)
    out_dir = tmp_path / "results"
    code, _out, err = run(capsys, ["characterize", str(toml), "-o", str(out_dir), "--quiet", "--no-report"])
    assert code == 3, err
    assert "Traceback" not in err
    assert snapshot(toml.parent) == before
    doc = json.loads((out_dir / "results.json").read_text())
    assert doc["units"]["A"]["status"] == "ok"
    assert set(doc["units"]["A"]["parameters"]) >= {"K", "R", "L"}
    status = doc["units"]["B"]["status"]
    assert "spindown" in status
    assert "spindown.txt" in status
    assert "binary" in status
    assert "K" in doc["units"]["B"]["parameters"]  # from the torque and LCR experiments
    csv_rows = (out_dir / "results.csv").read_text().splitlines()
    assert any(row.startswith("B,") and "binary" in row for row in csv_rows)
    # One line on stderr says that some analyses failed and where the details are.
    assert_one_line(err, mentions="failed")


# ---- the last-resort handler -------------------------------------------------------------------


def _built_afresh(monkeypatch: pytest.MonkeyPatch) -> None:
    """``main``'s parsers built for this test (a parser built before holds the command's ``run`` it was built with,
    not the one the test put in its place)."""
    monkeypatch.setattr(cli, "build_parser", cli.build_parser.__wrapped__)


def test_unexpected_exception_is_one_line_exit_1(monkeypatch: pytest.MonkeyPatch, capsys) -> None:
    """A genuine bug prints one line asking for a report and exits 1, not a traceback."""
    import motorlab.cli.motors as motors

    def broken(args: Any) -> int:
        raise ZeroDivisionError("float division by zero")

    monkeypatch.setattr(motors, "run", broken)
    _built_afresh(monkeypatch)
    code, _, err = run(capsys, ["motors"])
    assert code == 1
    assert_one_line(err, mentions="internal error")
    assert "ZeroDivisionError" in err
    assert "please report" in err


def test_python_warnings_are_one_line_each(monkeypatch: pytest.MonkeyPatch, capsys) -> None:
    """A numerical warning (numpy's overflow …) is one ``motorlab: warning:`` line, not two with source code."""
    import warnings

    import motorlab.cli.motors as motors

    def noisy(args: Any) -> int:
        warnings.warn("overflow encountered\nin scalar divide", RuntimeWarning, stacklevel=1)
        return 0

    monkeypatch.setattr(motors, "run", noisy)
    _built_afresh(monkeypatch)
    with warnings.catch_warnings():
        warnings.simplefilter("always")  # the suite turns warnings into errors; a user's Python does not
        code, _, err = run(capsys, ["motors"])
    assert code == 0
    assert_one_line(err, mentions="warning: RuntimeWarning: overflow encountered in scalar divide")


# ---- for real: a separate process --------------------------------------------------------------


def _subprocess(argv: list[str], cwd: Path) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "MPLBACKEND": "Agg", "COLUMNS": "120"}
    return subprocess.run([sys.executable, "-m", "motorlab", *argv], capture_output=True, text=True,
                          cwd=cwd, env=env, timeout=120, check=False)


def test_no_traceback_reaches_stderr_for_real(rig_files, session_dir: Path, tmp_path: Path) -> None:
    files = copy_inputs(rig_files["spindown"], tmp_path / "in")
    _binary(files[1])
    toml = _session_copy(session_dir, tmp_path)
    _edit(toml, 'lever_arm = "0.15 m"', 'lever_arm = "0.15 V"')
    before = snapshot(tmp_path)
    commands = [
        ["analyze", "spindown", *map(str, files), "--cpr", "1120"],
        ["analyze", "spindown", str(files[0]), "--cpr", "-3"],
        ["characterize", str(toml), "-o", str(tmp_path / "r")],
    ]
    for argv in commands:
        done = _subprocess(argv, tmp_path)
        assert done.returncode == 2, (argv, done.stderr)
        assert_one_line(done.stderr)
    assert snapshot(tmp_path) == before


def test_a_refusal_is_one_line_even_after_numpy_warned(monkeypatch: pytest.MonkeyPatch, capsys) -> None:
    """numpy's overflow on the way to a refusal is a symptom of the same bad input: only the refusal prints."""
    import warnings

    import motorlab.cli.motors as motors
    from motorlab.errors import OptionError

    def overflow_then_refuse(args: Any) -> int:
        warnings.warn("overflow encountered in multiply", RuntimeWarning, stacklevel=1)
        raise OptionError("the lever arm (--arm) must lie between 0.0001 and 100 [m], got 1e+308")

    monkeypatch.setattr(motors, "run", overflow_then_refuse)
    _built_afresh(monkeypatch)
    with warnings.catch_warnings():
        warnings.simplefilter("always")
        code, _, err = run(capsys, ["motors"])
    assert code == 2
    assert_one_line(err, mentions="lever arm")
