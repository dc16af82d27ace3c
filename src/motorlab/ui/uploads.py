"""Uploaded files on disk: a private temporary folder, sanitised names, a size limit, zips unpacked safely."""

from __future__ import annotations

import re
import shutil
import tempfile
import zipfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

#: Largest request body the app accepts [bytes] (all files of one request together).
MAX_UPLOAD = 200 * 1024 * 1024

#: Most members a zip may have, and their largest total size once unpacked [bytes].
MAX_ZIP_MEMBERS = 2000
MAX_UNZIPPED = 500 * 1024 * 1024

_UNSAFE = re.compile(r"[^A-Za-z0-9._+\- ]")


class UploadError(ValueError):
    """An upload the app refuses (too large, a zip that is not one, too many members)."""


@contextmanager
def private_folder() -> Iterator[Path]:
    """A new folder only this user can read (``mkdtemp`` makes it 0700), removed with all it holds afterwards."""
    folder = Path(tempfile.mkdtemp(prefix="motorlab-ui-"))
    try:
        yield folder
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def safe_relative(name: str) -> Path:
    """A client-given file name as a relative path that cannot leave its folder.

    Both separators split; empty, ``.`` and ``..`` parts are dropped; other characters than letters,
    digits, ``._+-`` and space become ``_``; a leading dot goes (no hidden files).
    """
    parts = []
    for part in re.split(r"[/\\]+", name or ""):
        clean = _UNSAFE.sub("_", part).strip().lstrip(".")[:120]
        if clean and clean not in (".", ".."):
            parts.append(clean)
    return Path(*parts) if parts else Path("upload")


def place(folder: Path, name: str) -> Path:
    """A fresh path for ``name`` inside ``folder`` (``-2``, ``-3`` … when taken), its parents created."""
    relative = safe_relative(name)
    target = (folder / relative).resolve()
    root = folder.resolve()
    if root not in target.parents:  # cannot happen after safe_relative; checked all the same
        raise UploadError(f"{name}: not a file name")
    stem, suffix, k = target.stem, target.suffix, 1
    while target.exists():
        k += 1
        target = target.with_name(f"{stem}-{k}{suffix}")
    target.parent.mkdir(parents=True, exist_ok=True)
    return target


def unpack_zip(archive: Path, folder: Path) -> list[Path]:
    """Unpack ``archive`` into ``folder`` with sanitised member names and bounded size; the files written."""
    try:
        with zipfile.ZipFile(archive) as zf:
            members = [m for m in zf.infolist() if not m.is_dir()]
            if len(members) > MAX_ZIP_MEMBERS:
                raise UploadError(f"{archive.name}: more than {MAX_ZIP_MEMBERS} files in the zip")
            if sum(m.file_size for m in members) > MAX_UNZIPPED:
                raise UploadError(f"{archive.name}: unpacks to more than {MAX_UNZIPPED // 2**20} MB")
            written = []
            for member in members:
                target = place(folder, member.filename)
                with zf.open(member) as src, open(target, "wb") as dst:
                    data = src.read(member.file_size + 1)  # a header that lies about the size is caught here
                    if len(data) > member.file_size:
                        raise UploadError(f"{archive.name}: {member.filename} is larger than the zip says")
                    dst.write(data)
                written.append(target)
            return written
    except (zipfile.BadZipFile, zipfile.LargeZipFile, NotImplementedError, RuntimeError) as exc:
        raise UploadError(f"{archive.name}: not a zip archive that can be read ({exc})") from None



def _named_paths(node: object) -> list[str]:
    """The file names a session description gives (``files = [...]``, ``truth = ...``), in order."""
    found: list[str] = []
    if isinstance(node, dict):
        for key, value in node.items():
            if key in ("files", "truth", "spindown") and isinstance(value, str):
                found.append(value)
            elif key in ("files", "spindown") and isinstance(value, list):
                found.extend(v for v in value if isinstance(v, str))
            else:
                found.extend(_named_paths(value))
    return found


def place_session_files(folder: Path, session: str, uploaded: list[str]) -> None:
    """Put loose uploads where the session description names them (``A/spindown.txt``).

    A browser's file picker gives loose files without their folders; a session names them with
    folders. Each named file that is missing is matched by its file name among the uploads; a name
    two named files share, or a named file not chosen, is refused in one line that says what to do.
    """
    import tomllib

    root = folder.resolve()
    toml_path = (root / session).resolve()
    try:
        doc = tomllib.loads(toml_path.read_text(encoding="utf-8-sig"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError):
        return  # the CLI reads it again and says what is wrong, in its own words
    named = [n for n in dict.fromkeys(_named_paths(doc)) if not Path(n).is_absolute()]
    by_name: dict[str, list[Path]] = {}
    for rel in uploaded:
        by_name.setdefault(Path(rel).name, []).append(root / rel)
    for name in named:
        target = (toml_path.parent / safe_relative(name)).resolve()
        if target.exists() or root not in target.parents:
            continue
        base = Path(name).name
        twins = [n for n in named if Path(n).name == base]
        if len(twins) > 1:
            raise UploadError(
                f"{Path(session).name} names {twins[0]} and {twins[1]}, files with the same name in different "
                "folders: choose the session's folder, or a zip of it, which keeps them apart"
            )
        candidates = by_name.get(base, []) or [p for n, ps in by_name.items() if _stem_twin(n, base) for p in ps]
        if not candidates:
            raise UploadError(
                f"{Path(session).name} names {name}, which is not among the chosen files: choose it too, "
                "or choose the session's folder (or a zip of it)"
            )
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(candidates[0], target)


def _stem_twin(uploaded: str, base: str) -> bool:
    """``spindown-2.txt`` is how :func:`place` renamed a second ``spindown.txt``."""
    stem, suffix = Path(base).stem, Path(base).suffix
    return bool(re.fullmatch(re.escape(stem) + r"-\d+" + re.escape(suffix), uploaded))
