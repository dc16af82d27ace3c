"""Loose files of a session go where its TOML names them; what cannot be placed is refused in one line."""

from __future__ import annotations

from pathlib import Path

import pytest

from motorlab.ui.uploads import UploadError, place_session_files

SESSION = """
[motor]
catalog = "neverest40"
[units.A]
truth = "A/truth.json"
[units.A.spindown]
files = ["A/spindown.txt"]
[units.A.lcr]
files = ["A/lcr.csv"]
"""


def _upload(folder: Path, names: list[str]) -> list[str]:
    for name in names:
        (folder / name).parent.mkdir(parents=True, exist_ok=True)
        (folder / name).write_text(f"content of {name}\n")
    return names


def test_loose_files_are_placed_where_the_session_names_them(tmp_path: Path) -> None:
    (tmp_path / "session.toml").write_text(SESSION)
    uploaded = _upload(tmp_path, ["spindown.txt", "lcr.csv", "truth.json"])
    place_session_files(tmp_path, "session.toml", ["session.toml", *uploaded])
    assert (tmp_path / "A" / "spindown.txt").read_text() == "content of spindown.txt\n"
    assert (tmp_path / "A" / "lcr.csv").is_file()
    assert (tmp_path / "A" / "truth.json").is_file()


def test_files_already_in_their_folders_are_left_alone(tmp_path: Path) -> None:
    (tmp_path / "s" / "session.toml").parent.mkdir()
    (tmp_path / "s" / "session.toml").write_text(SESSION)
    uploaded = _upload(tmp_path, ["s/A/spindown.txt", "s/A/lcr.csv", "s/A/truth.json"])
    place_session_files(tmp_path, "s/session.toml", uploaded)
    assert sorted(p.name for p in (tmp_path / "s" / "A").iterdir()) == ["lcr.csv", "spindown.txt", "truth.json"]


def test_a_missing_file_and_twin_names_are_refused_saying_what_to_do(tmp_path: Path) -> None:
    (tmp_path / "session.toml").write_text(SESSION)
    uploaded = _upload(tmp_path, ["spindown.txt", "truth.json"])
    with pytest.raises(UploadError, match=r"names A/lcr\.csv, which is not among the chosen files: choose it too"):
        place_session_files(tmp_path, "session.toml", ["session.toml", *uploaded])
    fresh = tmp_path / "fresh"
    fresh.mkdir()
    (fresh / "session.toml").write_text(SESSION + '[units.B.spindown]\nfiles = ["B/spindown.txt"]\n')
    uploaded = _upload(fresh, ["spindown.txt", "spindown-2.txt", "lcr.csv", "truth.json"])
    with pytest.raises(UploadError, match="same name in different folders: choose the session's folder"):
        place_session_files(fresh, "session.toml", ["session.toml", *uploaded])
