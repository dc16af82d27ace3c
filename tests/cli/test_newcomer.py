"""What a newcomer meets first: the example session runs as written, help texts read as plain text."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import pytest

from motorlab import cli
from motorlab.cli import build_parser

ROOT = Path(__file__).resolve().parents[2]


def test_the_example_session_runs_as_written(tmp_path: Path, capsys) -> None:
    code = cli.main(["characterize", str(ROOT / "examples" / "session.toml"), "-o", str(tmp_path),
                     "--quiet", "--no-report"])
    _, err = capsys.readouterr()
    assert code == 0, err
    doc = json.loads((tmp_path / "results.json").read_text())
    assert set(doc["units"]) == {"A", "B", "C"}
    assert all(unit["status"] == "ok" for unit in doc["units"].values())


def test_readme_says_how_to_run_the_command() -> None:
    readme = (ROOT / "README.md").read_text()
    assert ".venv/bin/motorlab" in readme


def _parsers(parser: argparse.ArgumentParser, path: tuple[str, ...] = ("motorlab",)):
    yield path, parser
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield from _parsers(sub, (*path, name))


def test_help_texts_show_no_restructuredtext_markup() -> None:
    for path, parser in _parsers(build_parser()):
        text = parser.format_help()
        for markup in ("``", ":func:", ":class:", ":mod:", ":data:"):
            assert markup not in text, (" ".join(path), markup)


def test_a_command_builds_only_its_own_parser_and_a_misspelt_one_lists_them_all(capsys):
    """`motorlab analyze …` imports only its own sub-command (tune's controller design costs tenths of a
    second); an unknown command still gets every choice in its one-line refusal."""
    only = build_parser("analyze")
    assert set(only._subparsers._group_actions[0].choices) == {"analyze"}  # type: ignore[union-attr]
    with pytest.raises(SystemExit) as exit_info:
        cli.main(["anlyze", "x.csv"])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert "invalid choice: 'anlyze'" in err
    assert all(f"'{name}'" in err for name in cli.COMMANDS)
